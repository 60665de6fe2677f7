//! `--annotate`: the bare map framed by theta axes (ticks at multiples of pi), a colour bar
//! with units and a title. The map's pixels are copied one to one, never resampled, so the
//! annotated image carries exactly the bare map's data (tests/pictures.rs checks it).

use std::f64::consts::PI;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{Error, Result};

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Makes the embedded DejaVu Sans plotters' "sans-serif" (once).
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans is a valid font"));
    });
}

/// An axis of the map: the angle range shown (rad) and its name.
#[derive(Clone, Debug)]
pub struct Axis {
    pub label: String,
    pub min: f64,
    pub max: f64,
    /// Ticks at round decimals instead of multiples of pi (for non-angles).
    pub decimal: bool,
}

impl Axis {
    fn ticks(&self) -> Vec<(f64, String)> {
        if self.decimal {
            decimal_ticks(self.min, self.max)
        } else {
            angle_ticks(self.min, self.max)
        }
    }
}

/// The colour bar: colours from bottom to top, ticks at fractions of its height.
#[derive(Clone, Debug)]
pub struct ColorBar {
    pub colors: Vec<[u8; 3]>,
    pub ticks: Vec<(f64, String)>,
    pub label: String,
    /// A separate swatch below the bar, e.g. ("never", black).
    pub swatch: Option<([u8; 3], String)>,
}

#[derive(Clone, Debug)]
pub struct Annotation {
    pub title: String,
    /// A smaller second line under the title (the parameters).
    pub subtitle: String,
    pub x: Axis,
    pub y: Axis,
    pub bar: ColorBar,
}

/// An annotated picture, and where the map sits inside it.
pub struct Annotated {
    pub rgb: Vec<u8>,
    pub width: u32,
    pub height: u32,
    pub map_x: u32,
    pub map_y: u32,
}

/// Tick positions and labels for an angle range: multiples of pi/k for the smallest k in
/// 1, 2, 4, 6, 8, 12, 16, 24 that gives 4 to 9 ticks; plain decimals for ranges too small for that.
pub fn angle_ticks(min: f64, max: f64) -> Vec<(f64, String)> {
    for k in [1u32, 2, 4, 6, 8, 12, 16, 24] {
        let step = PI / k as f64;
        let first = (min / step - 1e-9).ceil() as i64;
        let last = (max / step + 1e-9).floor() as i64;
        let n = last - first + 1;
        if (4..=9).contains(&n) || (k == 24 && n >= 2) {
            return (first..=last)
                .map(|i| (i as f64 * step, pi_label(i, k as i64)))
                .collect();
        }
        if n > 9 {
            break;
        }
    }
    decimal_ticks(min, max)
}

/// "0", "π", "-π/2", "3π/4", ... for i pi / k, reduced.
fn pi_label(i: i64, k: i64) -> String {
    if i == 0 {
        return "0".into();
    }
    let g = gcd(i.unsigned_abs(), k as u64) as i64;
    let (num, den) = (i / g, k / g);
    let sign = if num < 0 { "-" } else { "" };
    let n = num.abs();
    let head = if n == 1 {
        format!("{sign}π")
    } else {
        format!("{sign}{n}π")
    };
    if den == 1 {
        head
    } else {
        format!("{head}/{den}")
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// About five round decimal ticks (1, 2 or 5 times a power of ten) within [min, max].
pub fn decimal_ticks(min: f64, max: f64) -> Vec<(f64, String)> {
    let raw = (max - min) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let first = (min / step).ceil() as i64;
    let last = (max / step).floor() as i64;
    (first..=last)
        .map(|i| {
            let v = i as f64 * step;
            (v, format!("{:.*}", decimals, v))
        })
        .collect()
}

/// `line` cut in two at the " · " nearest its middle (the whole where it has none).
fn halves(line: &str) -> Vec<String> {
    let middle = line.len() / 2;
    match line
        .match_indices(" · ")
        .min_by_key(|(i, _)| i.abs_diff(middle))
    {
        Some((i, sep)) => vec![line[..i].to_string(), line[i + sep.len()..].to_string()],
        None => vec![line.to_string()],
    }
}

const BACKGROUND: [u8; 3] = [17, 17, 20];
const INK: RGBColor = RGBColor(225, 225, 225);

fn draw_err<E: std::fmt::Debug>(e: E) -> Error {
    Error::Plot(format!("annotating the map: {e:?}"))
}

/// Frames a `w` x `h` RGB map with axes, colour bar and title.
pub fn annotate(map: &[u8], w: u32, h: u32, a: &Annotation) -> Result<Annotated> {
    register_font();
    // Text scales with the map, within readable bounds.
    let font = (h.min(w) as f64 / 28.0).clamp(12.0, 30.0);
    let f = |x: f64| (x * font).round() as u32;
    // Wide enough for the y tick labels (about 0.45 em a character at 0.8 of the font size).
    let widest =
        a.y.ticks()
            .iter()
            .map(|t| t.1.chars().count())
            .max()
            .unwrap_or(1) as f64;
    let (left, right, bottom) = (f(2.6 + 0.36 * widest).max(f(4.2)), f(7.0), f(3.4));
    let width = left + w + right;
    // The parameters' line, on two lines where one would not fit the picture (a small map
    // of a fitted pendulum ran off it), each shrunk to fit if need be: never clipped.
    let room = (width - left) as f64 - font * 0.3;
    let measure = |line: &str, size: f64| -> f64 {
        ("sans-serif", size)
            .into_font()
            .box_size(line)
            .map_or(0.0, |(w, _)| w as f64)
    };
    let sub_size = font * 0.72;
    let sub_lines: Vec<String> = match measure(&a.subtitle, sub_size) > room {
        true => halves(&a.subtitle),
        false => vec![a.subtitle.clone()],
    };
    let top = f(3.2) + f(0.9) * (sub_lines.len() as u32 - 1);
    let height = top + h + bottom;
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    for px in rgb.chunks_exact_mut(3) {
        px.copy_from_slice(&BACKGROUND);
    }
    for row in 0..h {
        let src = &map[(row * w * 3) as usize..((row + 1) * w * 3) as usize];
        let at = (((top + row) * width + left) * 3) as usize;
        rgb[at..at + src.len()].copy_from_slice(src);
    }
    // The colour bar's strip, painted directly (one row per colour sample).
    let (bar_x, bar_w, bar_h) = (left + w + f(1.0), f(1.0), h * 4 / 5);
    let bar_top = top + (h - bar_h) / 2 - if a.bar.swatch.is_some() { f(0.8) } else { 0 };
    let n = a.bar.colors.len();
    for r in 0..bar_h {
        let c = a.bar.colors[((bar_h - 1 - r) as usize * (n - 1)) / (bar_h - 1).max(1) as usize];
        for x in bar_x..bar_x + bar_w {
            let at = (((bar_top + r) * width + x) * 3) as usize;
            rgb[at..at + 3].copy_from_slice(&c);
        }
    }
    let swatch_top = bar_top + bar_h + f(0.6);
    if let Some((c, _)) = &a.bar.swatch {
        for r in swatch_top..swatch_top + f(0.8) {
            for x in bar_x..bar_x + bar_w {
                let at = ((r * width + x) * 3) as usize;
                rgb[at..at + 3].copy_from_slice(c);
            }
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        let text = |size: f64, pos: Pos| ("sans-serif", size).into_font().color(&INK).pos(pos);
        let tick_font = text(font * 0.8, Pos::new(HPos::Center, VPos::Top));
        let line = |x0: i32, y0: i32, x1: i32, y1: i32| {
            root.draw(&PathElement::new(vec![(x0, y0), (x1, y1)], INK))
        };
        // Frame.
        let (l, t, r, b) = (
            left as i32 - 1,
            top as i32 - 1,
            (left + w) as i32,
            (top + h) as i32,
        );
        line(l, t, r, t).map_err(draw_err)?;
        line(l, b, r, b).map_err(draw_err)?;
        line(l, t, l, b).map_err(draw_err)?;
        line(r, t, r, b).map_err(draw_err)?;
        let tick = f(0.35) as i32;
        // x axis: theta1 left to right at pixel edges min .. max.
        for (v, label) in a.x.ticks() {
            let x = left as f64 + (v - a.x.min) / (a.x.max - a.x.min) * w as f64;
            let x = x.round() as i32;
            line(x, b, x, b + tick).map_err(draw_err)?;
            root.draw_text(&label, &tick_font, (x, b + tick + 2))
                .map_err(draw_err)?;
        }
        root.draw_text(
            &a.x.label,
            &text(font, Pos::new(HPos::Center, VPos::Bottom)),
            ((left + w / 2) as i32, height as i32 - f(0.25) as i32),
        )
        .map_err(draw_err)?;
        // y axis: theta2 with its maximum at the top.
        let right_font = text(font * 0.8, Pos::new(HPos::Right, VPos::Center));
        for (v, label) in a.y.ticks() {
            let y = top as f64 + (a.y.max - v) / (a.y.max - a.y.min) * h as f64;
            let y = y.round() as i32;
            line(l - tick, y, l, y).map_err(draw_err)?;
            root.draw_text(&label, &right_font, (l - tick - 3, y))
                .map_err(draw_err)?;
        }
        // A short label (today's θ2) stands upright; a longer one runs up the side.
        let y_label = text(font, Pos::new(HPos::Center, VPos::Center));
        let y_label = match a.y.label.chars().count() > 3 {
            true => y_label.transform(FontTransform::Rotate270),
            false => y_label,
        };
        root.draw_text(&a.y.label, &y_label, (f(0.8) as i32, (top + h / 2) as i32))
            .map_err(draw_err)?;
        // Colour bar ticks, label and swatch.
        let left_font = text(font * 0.8, Pos::new(HPos::Left, VPos::Center));
        let bx = (bar_x + bar_w) as i32;
        for (frac, label) in &a.bar.ticks {
            let y = (bar_top + bar_h) as f64 - frac.clamp(0.0, 1.0) * (bar_h - 1) as f64;
            let y = y.round() as i32;
            line(bx, y, bx + tick, y).map_err(draw_err)?;
            root.draw_text(label, &left_font, (bx + tick + 3, y))
                .map_err(draw_err)?;
        }
        if let Some((_, label)) = &a.bar.swatch {
            let y = (swatch_top + f(0.4)) as i32;
            root.draw_text(label, &left_font, (bx + tick + 3, y))
                .map_err(draw_err)?;
        }
        root.draw_text(
            &a.bar.label,
            &text(font * 0.8, Pos::new(HPos::Left, VPos::Bottom)),
            (bar_x as i32 - f(0.2) as i32, bar_top as i32 - f(0.3) as i32),
        )
        .map_err(draw_err)?;
        // The title and the parameters' lines shrink to the picture's width if need be.
        let fitted = |line: &str, size: f64| -> f64 {
            let w = measure(line, size);
            if w > room { size * room / w } else { size }
        };
        root.draw_text(
            &a.title,
            &text(fitted(&a.title, font), Pos::new(HPos::Left, VPos::Center)),
            (left as i32, f(0.9) as i32),
        )
        .map_err(draw_err)?;
        for (k, line) in sub_lines.iter().enumerate() {
            root.draw_text(
                line,
                &text(fitted(line, sub_size), Pos::new(HPos::Left, VPos::Center)),
                (left as i32, (f(2.15) + f(0.9) * k as u32) as i32),
            )
            .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Annotated {
        rgb,
        width,
        height,
        map_x: left,
        map_y: top,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_multiples_of_pi() {
        let labels: Vec<String> = angle_ticks(-PI, PI).into_iter().map(|t| t.1).collect();
        assert_eq!(labels, ["-π", "-π/2", "0", "π/2", "π"]);
        let labels: Vec<String> = angle_ticks(0.0, 3.0).into_iter().map(|t| t.1).collect();
        assert_eq!(labels, ["0", "π/4", "π/2", "3π/4"]);
        // Too narrow for pi fractions: decimals.
        let ticks = angle_ticks(1.0, 1.01);
        assert!(
            ticks.len() >= 3 && ticks[0].1.starts_with("1.00"),
            "{ticks:?}"
        );
    }
}
