//! Long-exposure pictures of moving bobs, like the lab report's LED photographs: light is
//! deposited in proportion to the time the bob spends in each pixel, the sum is tone-mapped,
//! and faint drawings (pivot, arms at the start) go on top.

use plotters::prelude::*;

use crate::error::{Error, Result};

/// Bob positions (x1, y1, x2, y2) in m, pivot at the origin, y up.
pub type Bobs = (f64, f64, f64, f64);

/// Maps positions (m; pivot at the origin, y up) to pixels of a square picture that shows
/// radius `reach` (m) around the pivot.
#[derive(Clone, Copy, Debug)]
pub struct Canvas {
    pub size: u32,
    pub reach: f64,
}

impl Canvas {
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        let s = self.size as f64 / (2.0 * self.reach);
        (
            self.size as f64 / 2.0 + x * s,
            self.size as f64 / 2.0 - y * s,
        )
    }

    /// Metres per pixel.
    pub fn pixel(&self) -> f64 {
        2.0 * self.reach / self.size as f64
    }
}

/// Accumulated light (linear RGB) of a picture.
pub struct Film {
    pub canvas: Canvas,
    light: Vec<[f32; 3]>,
}

impl Film {
    pub fn new(canvas: Canvas) -> Self {
        Film {
            canvas,
            light: vec![[0.0; 3]; (canvas.size * canvas.size) as usize],
        }
    }

    /// Adds `amount` of `color` at (x, y) px, shared bilinearly by the four nearest pixels
    /// (smooth trails without aliasing).
    fn splat(&mut self, x: f64, y: f64, color: [f32; 3], amount: f32) {
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (ax, ay) = ((fx - x0) as f32, (fy - y0) as f32);
        let n = self.canvas.size as i64;
        for (dx, dy, w) in [
            (0, 0, (1.0 - ax) * (1.0 - ay)),
            (1, 0, ax * (1.0 - ay)),
            (0, 1, (1.0 - ax) * ay),
            (1, 1, ax * ay),
        ] {
            let (px, py) = (x0 as i64 + dx, y0 as i64 + dy);
            if (0..n).contains(&px) && (0..n).contains(&py) {
                let cell = &mut self.light[(py * n + px) as usize];
                for c in 0..3 {
                    cell[c] += color[c] * amount * w;
                }
            }
        }
    }

    /// The bob moving from `a` to `b` (m) in `seconds`: light proportional to the time spent,
    /// so slow stretches (turning points) come out brighter, as on the photographs.
    pub fn expose_segment(&mut self, a: (f64, f64), b: (f64, f64), seconds: f64, color: [f32; 3]) {
        let (pa, pb) = (self.canvas.to_px(a.0, a.1), self.canvas.to_px(b.0, b.1));
        let length = ((pb.0 - pa.0).powi(2) + (pb.1 - pa.1).powi(2)).sqrt();
        // Samples at most half a pixel apart.
        let n = (2.0 * length).ceil().max(1.0) as usize;
        let amount = (seconds / n as f64) as f32;
        for i in 0..n {
            let s = (i as f64 + 0.5) / n as f64;
            self.splat(
                pa.0 + s * (pb.0 - pa.0),
                pa.1 + s * (pb.1 - pa.1),
                color,
                amount,
            );
        }
    }

    /// Adds the light of `other` (a film of the same canvas).
    pub fn add(&mut self, other: &Film) {
        for (a, b) in self.light.iter_mut().zip(&other.light) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }

    /// 8-bit RGB: 1 - exp(-gain * light) per channel. `gain` is set so that a bob crossing a
    /// pixel at `speed` m/s gives half brightness.
    pub fn develop(&self, speed: f64) -> Vec<u8> {
        let seconds_per_pixel = self.canvas.pixel() / speed;
        let gain = (std::f64::consts::LN_2 / seconds_per_pixel) as f32;
        let mut rgb = Vec::with_capacity(self.light.len() * 3);
        for cell in &self.light {
            for c in cell {
                let v = 1.0 - (-gain * c).exp();
                rgb.push((v.clamp(0.0, 1.0) * 255.0).round() as u8);
            }
        }
        rgb
    }
}

fn draw_err<E: std::fmt::Debug>(e: E) -> Error {
    Error::Plot(format!("drawing: {e:?}"))
}

/// Arms drawn over a picture: pivot -> bob 1 -> bob 2 for each (x1, y1, x2, y2), in `color`
/// with `alpha`, bobs as discs of `radius` px.
pub fn draw_arms(
    rgb: &mut [u8],
    canvas: Canvas,
    arms: &[(Bobs, [u8; 3])],
    alpha: f64,
    radius: i32,
) -> Result<()> {
    let root = BitMapBackend::with_buffer(rgb, (canvas.size, canvas.size)).into_drawing_area();
    let px = |x: f64, y: f64| {
        let (a, b) = canvas.to_px(x, y);
        (a.round() as i32, b.round() as i32)
    };
    for ((x1, y1, x2, y2), c) in arms {
        let color = RGBColor(c[0], c[1], c[2]).mix(alpha);
        let (p0, p1, p2) = (px(0.0, 0.0), px(*x1, *y1), px(*x2, *y2));
        root.draw(&PathElement::new(vec![p0, p1, p2], color.stroke_width(2)))
            .map_err(draw_err)?;
        for p in [p1, p2] {
            root.draw(&Circle::new(p, radius, color.filled()))
                .map_err(draw_err)?;
        }
        root.draw(&Circle::new(p0, 3, color.filled()))
            .map_err(draw_err)?;
    }
    root.present().map_err(draw_err)?;
    Ok(())
}
