//! Colours for maps: perceptual gradients from colorgrad, sampled once into a lookup table.

use colorgrad::Gradient;
use rayon::prelude::*;

use crate::field::Field;

const LUT_SIZE: usize = 1024;

/// How a flip-time map is coloured: log10 of the time in units of the natural time
/// sqrt(l1/g), from `t_lo` (brightest) to `t_max` (darkest); never flipped in black.
#[derive(Clone, Copy, Debug)]
pub struct FlipColors {
    pub t_lo: f64,
    pub t_max: f64,
}

/// The colour of never-flipped pixels: black, below the darkest gradient colour used.
pub const NEVER_RGB: [u8; 3] = [0, 0, 0];

fn lut(gradient: &dyn Gradient, from: f32, to: f32) -> Vec<[u8; 3]> {
    (0..LUT_SIZE)
        .map(|i| {
            let u = from + (to - from) * i as f32 / (LUT_SIZE - 1) as f32;
            let [r, g, b, _] = gradient.at(u).to_rgba8();
            [r, g, b]
        })
        .collect()
}

/// RGB bytes of a flip-time map: inferno from pale yellow (early flips) to dark purple (late).
pub fn flip_colors(field: &Field, colors: FlipColors) -> Vec<u8> {
    // Stop short of inferno's black end so that "never" stays distinct.
    let table = lut(&colorgrad::preset::inferno(), 1.0, 0.15);
    let (lo, hi) = (colors.t_lo.ln(), colors.t_max.ln());
    let mut rgb = vec![0u8; field.data.len() * 3];
    rgb.par_chunks_mut(3)
        .zip(field.data.par_iter())
        .for_each(|(px, &t)| {
            let c = if t.is_finite() {
                let u = ((f64::from(t).max(colors.t_lo).ln() - lo) / (hi - lo)).clamp(0.0, 1.0);
                table[(u * (LUT_SIZE - 1) as f64).round() as usize]
            } else {
                NEVER_RGB
            };
            px.copy_from_slice(&c);
        });
    rgb
}

/// Colour range (1/s) of a divergence map: 0 (regular, dark) to the 99.5th percentile of the
/// exponents, so a few extreme pixels do not wash out the chaotic sea, and at least 0.1 /s.
pub fn ftle_range(field: &Field) -> (f32, f32) {
    let mut v: Vec<f32> = field
        .data
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    if v.is_empty() {
        return (0.0, 1.0);
    }
    let k = ((v.len() - 1) as f64 * 0.995).round() as usize;
    let (_, hi, _) = v.select_nth_unstable_by(k, f32::total_cmp);
    (0.0, hi.max(0.1))
}

/// RGB bytes of a divergence map: magma, linear in the exponent from `range.0` (black:
/// regular) to `range.1` (pale yellow: strongly chaotic); values outside are clamped.
pub fn ftle_colors(field: &Field, range: (f32, f32)) -> Vec<u8> {
    let table = lut(&colorgrad::preset::magma(), 0.0, 1.0);
    let (lo, hi) = range;
    let mut rgb = vec![0u8; field.data.len() * 3];
    rgb.par_chunks_mut(3)
        .zip(field.data.par_iter())
        .for_each(|(px, &x)| {
            let u = if x.is_nan() {
                0.0
            } else {
                ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
            };
            px.copy_from_slice(&table[(u * (LUT_SIZE - 1) as f32).round() as usize]);
        });
    rgb
}
