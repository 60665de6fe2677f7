//! Colours for maps: perceptual gradients from colorgrad, sampled once into a lookup table.

use crate::quantity::FlipKind;
use colorgrad::Gradient;
use rayon::prelude::*;

use crate::field::Field;

/// Colours in a colour map's lookup table.
pub const LUT_SIZE: usize = 1024;

/// How a flip-time map is coloured: log10 of the time in units of the natural time
/// sqrt(l1/g), from `t_lo` (brightest) to `t_max` (darkest); never flipped in black.
#[derive(Clone, Copy, Debug)]
pub struct FlipColors {
    pub t_lo: f64,
    pub t_max: f64,
    pub colormap: Colormap,
}

impl FlipColors {
    /// The earliest time the colours tell apart for a pendulum `p` (its brightest): the
    /// natural time sqrt(l1 / g).
    pub fn t_lo(p: &crate::model::Params) -> f64 {
        (p.l1 / p.g).sqrt()
    }

    /// The colour bar: colours from late (bottom) to early (top), ticks at round times.
    pub fn bar(&self) -> (Vec<[u8; 3]>, Vec<(f64, String)>) {
        let (from, to) = self.colormap.flip_span();
        let colors = lut(&*self.colormap.gradient(), to, from);
        let (lo, hi) = (self.t_lo.ln(), self.t_max.ln());
        let mut ticks = Vec::new();
        for decade in [0.1, 1.0, 10.0, 100.0, 1000.0] {
            for m in [1.0, 2.0, 5.0] {
                let t: f64 = decade * m;
                if t >= self.t_lo * 0.999 && t <= self.t_max * 1.001 {
                    // Early (t_lo) is the top of the bar.
                    ticks.push((1.0 - (t.ln() - lo) / (hi - lo), format!("{t}")));
                }
            }
        }
        (colors, ticks)
    }
}

/// The colour of never-flipped pixels: black, below the darkest gradient colour used.
pub const NEVER_RGB: [u8; 3] = [0, 0, 0];

/// The colour of pixels whose result is NaN (the integration left the numbers): a pure
/// green that none of the colour maps' ends or the "never" black resemble.
pub const NAN_RGB: [u8; 3] = [0, 255, 0];

/// The colour maps `--colormap` offers (colorgrad presets): sequential ones for times and
/// exponents, cyclic ones (sinebow, rainbow) for angles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colormap {
    Inferno,
    Magma,
    Viridis,
    Plasma,
    Cividis,
    Turbo,
    Cubehelix,
    /// Cyclic.
    Sinebow,
    /// Cyclic.
    Rainbow,
}

impl Colormap {
    pub const ALL: [Colormap; 9] = [
        Colormap::Inferno,
        Colormap::Magma,
        Colormap::Viridis,
        Colormap::Plasma,
        Colormap::Cividis,
        Colormap::Turbo,
        Colormap::Cubehelix,
        Colormap::Sinebow,
        Colormap::Rainbow,
    ];

    pub fn gradient(self) -> Box<dyn Gradient> {
        use colorgrad::preset;
        match self {
            Colormap::Inferno => Box::new(preset::inferno()),
            Colormap::Magma => Box::new(preset::magma()),
            Colormap::Viridis => Box::new(preset::viridis()),
            Colormap::Plasma => Box::new(preset::plasma()),
            Colormap::Cividis => Box::new(preset::cividis()),
            Colormap::Turbo => Box::new(preset::turbo()),
            Colormap::Cubehelix => Box::new(preset::cubehelix_default()),
            Colormap::Sinebow => Box::new(preset::sinebow()),
            Colormap::Rainbow => Box::new(preset::rainbow()),
        }
    }

    /// (from, to) along the gradient for flip times: early flips bright, late flips dark.
    /// Dark-ended maps stop short of the black end so that "never" stays distinct.
    fn flip_span(self) -> (f32, f32) {
        match self {
            Colormap::Inferno | Colormap::Magma => (1.0, 0.15),
            _ => (1.0, 0.0),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Colormap::Inferno => "inferno",
            Colormap::Magma => "magma",
            Colormap::Viridis => "viridis",
            Colormap::Plasma => "plasma",
            Colormap::Cividis => "cividis",
            Colormap::Turbo => "turbo",
            Colormap::Cubehelix => "cubehelix",
            Colormap::Sinebow => "sinebow",
            Colormap::Rainbow => "rainbow",
        }
    }
}

fn lut(gradient: &dyn Gradient, from: f32, to: f32) -> Vec<[u8; 3]> {
    (0..LUT_SIZE)
        .map(|i| {
            let u = from + (to - from) * i as f32 / (LUT_SIZE - 1) as f32;
            let [r, g, b, _] = gradient.at(u).to_rgba8();
            [r, g, b]
        })
        .collect()
}

/// The flip-time colours of `colormap`, from the earliest flip (first) to the latest (last),
/// [`LUT_SIZE`] of them: what [`flip_colors`] picks from, and the static explorer too.
pub fn flip_table(colormap: Colormap) -> Vec<[u8; 3]> {
    let (from, to) = colormap.flip_span();
    lut(&*colormap.gradient(), from, to)
}

/// RGB bytes of a flip-time map: by default inferno from pale yellow (early flips) to dark
/// purple (late).
pub fn flip_colors(field: &Field, colors: FlipColors) -> Vec<u8> {
    let table = flip_table(colors.colormap);
    let (lo, hi) = (colors.t_lo.ln(), colors.t_max.ln());
    let mut rgb = vec![0u8; field.data.len() * 3];
    rgb.par_chunks_mut(3)
        .zip(field.data.par_iter())
        .for_each(|(px, &t)| {
            let c = if t.is_finite() {
                let u = ((f64::from(t).max(colors.t_lo).ln() - lo) / (hi - lo)).clamp(0.0, 1.0);
                table[(u * (LUT_SIZE - 1) as f64).round() as usize]
            } else if t.is_nan() {
                NAN_RGB
            } else {
                NEVER_RGB
            };
            px.copy_from_slice(&c);
        });
    rgb
}

/// The colours of the flip kinds ([`FlipKind`], Okabe and Ito's colour-blind safe set): the
/// upper arm warm (orange +, yellow -), the lower arm cool (blue +, sky blue -), never black.
pub fn flip_kind_rgb(kind: FlipKind) -> [u8; 3] {
    match kind {
        FlipKind::Never => NEVER_RGB,
        FlipKind::UpperPlus => [230, 159, 0],
        FlipKind::UpperMinus => [240, 228, 66],
        FlipKind::LowerPlus => [0, 114, 178],
        FlipKind::LowerMinus => [86, 180, 233],
    }
}

/// The flip kinds' colour bar: an equal block for each class that flips, in [`FlipKind`]'s
/// order from the start of the bar, and ticks (fraction of the bar, label) at their middles.
pub fn flip_kind_bar() -> (Vec<[u8; 3]>, Vec<(f64, String)>) {
    let flips = &FlipKind::ALL[1..];
    let colors = flips
        .iter()
        .flat_map(|&k| std::iter::repeat_n(flip_kind_rgb(k), 64))
        .collect();
    let ticks = flips
        .iter()
        .enumerate()
        .map(|(i, k)| ((i as f64 + 0.5) / flips.len() as f64, k.label().to_string()))
        .collect();
    (colors, ticks)
}

/// RGB bytes of a flip-kind map; NaN (and any value that is no class) in [`NAN_RGB`].
pub fn flip_kind_colors(field: &Field) -> Vec<u8> {
    field
        .data
        .iter()
        .flat_map(|&x| FlipKind::from_code(x).map_or(NAN_RGB, flip_kind_rgb))
        .collect()
}

/// The colour table of a divergence map, regular (low) to chaotic (high).
pub fn ftle_table(colormap: Colormap) -> Vec<[u8; 3]> {
    lut(&*colormap.gradient(), 0.0, 1.0)
}

/// RGB bytes of a divergence map: by default magma, linear in the exponent from `range.0`
/// (black: regular) to `range.1` (pale yellow: strongly chaotic); values outside are clamped.
pub fn ftle_colors(field: &Field, range: (f32, f32), colormap: Colormap) -> Vec<u8> {
    let table = ftle_table(colormap);
    let (lo, hi) = range;
    let mut rgb = vec![0u8; field.data.len() * 3];
    rgb.par_chunks_mut(3)
        .zip(field.data.par_iter())
        .for_each(|(px, &x)| {
            if x.is_nan() {
                px.copy_from_slice(&NAN_RGB);
            } else {
                let u = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
                px.copy_from_slice(&table[(u * (LUT_SIZE - 1) as f32).round() as usize]);
            }
        });
    rgb
}
