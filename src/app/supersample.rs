//! `--samples N`: N x N stratified starts a pixel (the centres of its N x N sub-pixels, the map
//! made at N times the size), reduced to one value a pixel by the quantity's own rule.

use crate::field::Field;
use crate::quantity::{FLIP_KIND, FLIP_TIME, Quantity};

/// Most sub-samples a side.
pub const MAX_SAMPLES: u32 = 16;

/// How a pixel's sub-samples become its value: flip times by the mean of their logs (the
/// geometric mean, as the colours are logarithmic) over those that flip, never where none
/// does; a class by the majority (the lowest code on a tie); any other quantity by the
/// mean. A sub-sample that left the numbers (NaN) makes the pixel NaN: nothing is hidden.
fn reduce(quantity: &Quantity, values: &[f32]) -> f32 {
    if values.iter().any(|v| v.is_nan()) {
        return f32::NAN;
    }
    if quantity.name == FLIP_TIME.name {
        let flipped: Vec<f64> = values
            .iter()
            .filter(|v| v.is_finite())
            .map(|&v| (v as f64).max(f64::MIN_POSITIVE).ln())
            .collect();
        return match flipped.len() {
            0 => f32::INFINITY,
            n => (flipped.iter().sum::<f64>() / n as f64).exp() as f32,
        };
    }
    if quantity.name == FLIP_KIND.name {
        let mut counts = [0u32; 8];
        for &v in values {
            counts[(v as usize).min(7)] += 1;
        }
        let best = (0..8)
            .max_by_key(|&k| (counts[k], std::cmp::Reverse(k)))
            .unwrap_or(0);
        return best as f32;
    }
    (values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64) as f32
}

/// The `n` x `n` sub-samples of every pixel of `fine` (a map `n` times the size) reduced to
/// one, and a pixel resolved only where all its sub-samples are.
pub fn reduce_map(
    quantity: &Quantity,
    fine: &Field,
    mask: Option<&[u8]>,
    n: u32,
) -> (Field, Option<Vec<u8>>) {
    let (w, h) = (fine.width / n, fine.height / n);
    let mut out = Field::new(w, h, 0.0);
    let mut resolved = mask.map(|_| vec![0u8; (w * h) as usize]);
    let mut values = Vec::with_capacity((n * n) as usize);
    for row in 0..h {
        for col in 0..w {
            values.clear();
            let mut all = 1u8;
            for r in row * n..(row + 1) * n {
                for c in col * n..(col + 1) * n {
                    values.push(fine.get(c, r));
                    if let Some(m) = mask {
                        all &= m[(r * fine.width + c) as usize];
                    }
                }
            }
            out.data[(row * w + col) as usize] = reduce(quantity, &values);
            if let Some(r) = resolved.as_mut() {
                r[(row * w + col) as usize] = all;
            }
        }
    }
    (out, resolved)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_quantity_reduces_by_its_rule() {
        let inf = f32::INFINITY;
        assert_eq!(reduce(&FLIP_TIME, &[1.0, 4.0, inf, inf]), 2.0);
        assert_eq!(reduce(&FLIP_TIME, &[inf; 4]), inf);
        assert!(reduce(&FLIP_TIME, &[1.0, f32::NAN]).is_nan());
        assert_eq!(reduce(&FLIP_KIND, &[3.0, 1.0, 3.0, 0.0]), 3.0);
        assert_eq!(reduce(&FLIP_KIND, &[2.0, 1.0, 1.0, 2.0]), 1.0);
        assert_eq!(reduce(&crate::quantity::FTLE, &[1.0, 2.0, 3.0, 4.0]), 2.5);
    }
}
