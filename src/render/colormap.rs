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
