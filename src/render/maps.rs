//! Maps as pictures: bare (one pixel a pendulum) or annotated with axes, colour bar and
//! title; and the PNG text chunks that say how a picture was made.

use crate::error::{Error, Result};
use crate::field::Field;
use crate::field::RunInfo;
use crate::model::Params;
use crate::spec::{AnyMap, FlipMeasure, FlipSpec, Grid, LyapunovSpec, MapKind, MapSpec, on_any};

use super::{
    Annotation, Axis, ColorBar, Colormap, FlipColors, NEVER_RGB, annotate, decimal_ticks,
    flip_colors, flip_kind_bar, flip_kind_colors, ftle_colors, ftle_table,
};

/// How a map becomes a picture.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PictureSpec {
    /// Frame the map with theta axes, a colour bar with units and a title.
    pub annotate: bool,
    /// The colour map; None for the kind's default (inferno for times, magma for exponents).
    pub colormap: Option<Colormap>,
}

/// A rendered map: bare or annotated, with where the map sits.
pub struct Picture {
    pub rgb: Vec<u8>,
    pub width: u32,
    pub height: u32,
    /// (x, y, width, height) of the map inside an annotated picture.
    pub map: Option<(u32, u32, u32, u32)>,
}

impl Picture {
    /// PNG text chunks saying where the map sits (annotated pictures only).
    pub fn metadata(&self) -> Vec<(String, String)> {
        match self.map {
            Some((x, y, w, h)) => vec![(
                "chaoscope:map-region".into(),
                format!("{w}x{h} map at x {x}, y {y} (top left); the rest is annotation"),
            )],
            None => Vec::new(),
        }
    }
}

/// How a map of the measure is drawn: its title, colour bar label and unit, and whether its
/// low values are the chaotic ones (the colours then run the other way, so that chaos is
/// bright in every map).
pub struct Look {
    pub title: String,
    pub label: String,
    pub unit: &'static str,
    /// Low values chaotic (alignment indices and their times).
    pub reversed: bool,
}

/// PNG text chunks that let an image be reproduced from itself: the version, the command
/// (given by the caller, which knows how it was asked for) and the path that ran.
pub fn provenance(command: String, info: &RunInfo) -> Vec<(String, String)> {
    vec![
        (
            "Software".into(),
            format!("chaoscope {}", env!("CARGO_PKG_VERSION")),
        ),
        ("chaoscope:command".into(), command),
        ("chaoscope:backend".into(), info.backend().into()),
        (
            "chaoscope:adapter".into(),
            info.adapter
                .clone()
                .unwrap_or_else(|| "none (CPU f64)".into()),
        ),
    ]
}

fn frame(
    field: &Field,
    rgb: Vec<u8>,
    annotated: bool,
    a: impl FnOnce() -> Annotation,
) -> Result<Picture> {
    if !annotated {
        return Ok(Picture {
            rgb,
            width: field.width,
            height: field.height,
            map: None,
        });
    }
    let out = annotate(&rgb, field.width, field.height, &a())?;
    Ok(Picture {
        rgb: out.rgb,
        width: out.width,
        height: out.height,
        map: Some((out.map_x, out.map_y, field.width, field.height)),
    })
}

/// The picture's axes: what they vary and its unit (today's plane as it always was: θ1 (rad)
/// and θ2), angles ticked at multiples of pi, everything else at round decimals.
fn axes(grid: &Grid) -> (Axis, Axis) {
    let axis = |a: &crate::spec::Axis, label: String| Axis {
        label,
        min: a.range.min,
        max: a.range.max,
        decimal: !a.var.is_angle(),
    };
    let label = |a: &crate::spec::Axis| match a.var.unit() {
        "1" => a.var.symbol().to_string(),
        unit => format!("{} ({})", a.var.symbol(), unit.replace("^2", "²")),
    };
    if grid.is_angle_plane() {
        return (axis(&grid.x, "θ1 (rad)".into()), axis(&grid.y, "θ2".into()));
    }
    (axis(&grid.x, label(&grid.x)), axis(&grid.y, label(&grid.y)))
}

/// The parameters and start the picture holds fixed (today's plane: as it always said).
fn physics_line(p: &Params, grid: &Grid) -> String {
    if !grid.is_angle_plane() {
        return plane_line(p, grid);
    }
    let s = sig;
    let line = format!(
        "m1 {} kg · m2 {} kg · l1 {} m · l2 {} m · g {} m/s² · ω0 ({}, {}) rad/s",
        s(p.m1),
        s(p.m2),
        s(p.l1),
        s(p.l2),
        s(p.g),
        s(grid.fixed.omega1),
        s(grid.fixed.omega2)
    );
    line + &losses_line(p)
}

/// Any other plane: what no axis sets, the start among it.
fn plane_line(p: &Params, grid: &Grid) -> String {
    use crate::spec::Var;
    let on_axis = |v: Var| [grid.x.var, grid.y.var].iter().any(|a| a.overlaps(v));
    let s = &grid.fixed;
    let mut items: Vec<String> = [
        (Var::M1, "kg"),
        (Var::M2, "kg"),
        (Var::L1, "m"),
        (Var::L2, "m"),
        (Var::G, "m/s²"),
    ]
    .iter()
    .filter(|(v, _)| !on_axis(*v))
    .map(|(v, unit)| format!("{} {} {unit}", v.name(), sig(v.get(p, s))))
    .collect();
    let start: Vec<String> = [Var::Theta1, Var::Theta2, Var::Omega1, Var::Omega2]
        .iter()
        .filter(|v| !on_axis(**v))
        .map(|v| format!("{} {}", v.symbol(), sig(v.get(p, s))))
        .collect();
    items.push(format!("start {}", start.join(", ")));
    let mut losses = *p;
    if on_axis(Var::Damping) {
        (losses.losses.joint1, losses.losses.joint2) = (0.0, 0.0);
    }
    if on_axis(Var::Rod1) || on_axis(Var::Rod2) {
        (losses.rod1, losses.rod2) = (0.0, 0.0);
    }
    items.join(" · ") + &losses_line(&losses)
}

/// `x` to four significant figures, as short as it reads (a fitted pendulum's 16-digit
/// masses made a subtitle run off the picture): 0.414, 9.81, 1, 2.5e-5.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let magnitude = x.abs().log10().floor() as i32;
    if !(-3..5).contains(&magnitude) {
        let s = format!("{x:.3e}");
        let (mantissa, exponent) = s.split_once('e').expect("an exponent");
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}e{exponent}");
    }
    let decimals = (3 - magnitude).max(0) as usize;
    let s = format!("{x:.decimals$}");
    match s.contains('.') {
        true => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => s,
    }
}

fn losses_line(p: &Params) -> String {
    let mut line = String::new();
    if p.rod1 != 0.0 || p.rod2 != 0.0 {
        line += &format!(" · rods {}/{} kg", sig(p.rod1), sig(p.rod2));
    }
    let l = &p.losses;
    if l.joint1 != 0.0 || l.joint2 != 0.0 {
        line += &format!(" · damping {}/{} N m s", sig(l.joint1), sig(l.joint2));
    }
    if l.has_drag() {
        line += " · air drag";
    }
    if l.has_bearings() {
        line += " · bearing friction";
    }
    line
}

/// The flip map as a picture.
/// The colour of pixels the verdict could not resolve (`--show-unresolved`): mid grey, apart
/// from every colour map's ends, the "never" black and the NaN green.
pub const UNRESOLVED_RGB: [u8; 3] = [128, 128, 128];

/// Paints the pixels whose `mask` entry is 0 in [`UNRESOLVED_RGB`].
fn mark_unresolved(rgb: &mut [u8], mask: Option<&[u8]>) {
    if let Some(mask) = mask {
        for (px, &m) in rgb.chunks_exact_mut(3).zip(mask) {
            if m == 0 {
                px.copy_from_slice(&UNRESOLVED_RGB);
            }
        }
    }
}

/// The subtitle's note on unresolved pixels, when they are shown: at this step, or at these
/// tolerances (`adaptive`).
fn unresolved_note(mask: Option<&[u8]>, adaptive: bool) -> &'static str {
    match (mask.is_some(), adaptive) {
        (false, _) => "",
        (true, false) => " · grey: not resolved at this step",
        (true, true) => " · grey: not resolved",
    }
}

/// How a flip map was stepped, for its subtitle.
fn stepping_note(spec: &impl MapSpec) -> String {
    let Some((rtol, atol)) = spec.integrator().tolerances() else {
        return format!("RK4 dt {} s", spec.stepping().dt);
    };
    let method = spec.integrator().name().to_uppercase();
    match rtol == atol {
        true => format!("{method} tol {rtol:e} {}", spec.precision().name()),
        false => format!(
            "{method} rtol {rtol:e} atol {atol:e} {}",
            spec.precision().name()
        ),
    }
}

/// The flip map as a picture (times or kinds, as `spec.measure` says); with `unresolved`,
/// the pixels whose mask is 0 in grey.
pub fn flip_picture(
    field: &Field,
    spec: &FlipSpec,
    picture: &PictureSpec,
    unresolved: Option<&[u8]>,
) -> Result<Picture> {
    if spec.measure == FlipMeasure::Kind {
        return flip_kind_picture(field, spec, picture, unresolved);
    }
    let colors = FlipColors {
        t_lo: FlipColors::t_lo(&spec.params),
        t_max: spec.stepping.t_max,
        colormap: picture.colormap.unwrap_or(Colormap::Inferno),
    };
    let mut rgb = flip_colors(field, colors);
    mark_unresolved(&mut rgb, unresolved);
    frame(field, rgb, picture.annotate, || {
        let (x, y) = axes(&spec.grid);
        let (colors_, ticks) = colors.bar();
        Annotation {
            title: "Time until an arm first flips over".into(),
            subtitle: format!(
                "{} · {}{}",
                physics_line(&spec.params, &spec.grid),
                stepping_note(spec),
                unresolved_note(unresolved, spec.integrator.tolerances().is_some())
            ),
            x,
            y,
            bar: ColorBar {
                colors: colors_,
                ticks,
                label: "flip time (s)".into(),
                swatch: Some((NEVER_RGB, format!("> {} s", spec.stepping.t_max))),
            },
        }
    })
}

/// The flip-kind map as a picture: a colour a class, the legend's blocks named.
fn flip_kind_picture(
    field: &Field,
    spec: &FlipSpec,
    picture: &PictureSpec,
    unresolved: Option<&[u8]>,
) -> Result<Picture> {
    let mut rgb = flip_kind_colors(field);
    mark_unresolved(&mut rgb, unresolved);
    frame(field, rgb, picture.annotate, || {
        let (x, y) = axes(&spec.grid);
        // The upper arm's classes at the top (the bar runs from the bottom).
        let (mut colors, ticks) = flip_kind_bar();
        colors.reverse();
        let ticks = ticks.into_iter().map(|(f, l)| (1.0 - f, l)).collect();
        Annotation {
            title: format!(
                "Which arm flips over first, and which way, within {} s",
                spec.stepping.t_max
            ),
            subtitle: format!(
                "{} · {} · + past +π, − past −π{}",
                physics_line(&spec.params, &spec.grid),
                stepping_note(spec),
                unresolved_note(unresolved, false)
            ),
            x,
            y,
            bar: ColorBar {
                colors,
                ticks,
                label: "first flip".into(),
                swatch: Some((NEVER_RGB, "never".into())),
            },
        }
    })
}

/// How `spec`'s measure is drawn.
fn look(spec: &LyapunovSpec) -> Look {
    let i = spec.indicator;
    i.measure().look(i, spec.stepping.t_max)
}

/// The colour range a divergence-family map takes by default (its measure's).
pub fn default_range(spec: &LyapunovSpec, field: &Field) -> (f32, f32) {
    let i = spec.indicator;
    i.measure().default_range(i, spec.stepping.t_max, field)
}

/// The colour bar of a divergence-family map over `range`: colours from left to right,
/// ticks as (fraction, label), and its label.
pub fn lyapunov_bar(
    spec: &LyapunovSpec,
    range: (f32, f32),
    colormap: Colormap,
) -> (Vec<[u8; 3]>, Vec<(f64, String)>, String) {
    let look = look(spec);
    let (lo, hi) = (range.0 as f64, range.1 as f64);
    let ticks = decimal_ticks(lo, hi)
        .into_iter()
        .map(|(v, l)| {
            let u = (v - lo) / (hi - lo);
            (if look.reversed { 1.0 - u } else { u }, l)
        })
        .collect();
    (ftle_table(colormap), ticks, look.label)
}

/// The divergence-family map as a picture, coloured over `range` (its quantity's unit).
pub fn lyapunov_picture(
    field: &Field,
    spec: &LyapunovSpec,
    range: (f32, f32),
    picture: &PictureSpec,
    unresolved: Option<&[u8]>,
) -> Result<Picture> {
    let look = look(spec);
    let colormap = picture.colormap.unwrap_or(Colormap::Magma);
    // Reversed, the range's ends swap: its low end is then the bright one.
    let ends = match look.reversed {
        true => (range.1, range.0),
        false => range,
    };
    let mut rgb = ftle_colors(field, ends, colormap);
    mark_unresolved(&mut rgb, unresolved);
    frame(field, rgb, picture.annotate, || {
        let (x, y) = axes(&spec.grid);
        let (colors, ticks, label) = lyapunov_bar(spec, range, colormap);
        Annotation {
            title: look.title,
            subtitle: format!(
                "{} · {}{}{}",
                physics_line(&spec.params, &spec.grid),
                stepping_note(spec),
                match spec.indicator.measure().renormalised() {
                    false => String::new(),
                    true => format!(" · renormalised every {} s", spec.renorm),
                },
                unresolved_note(unresolved, false)
            ),
            x,
            y,
            bar: ColorBar {
                colors,
                ticks,
                label,
                swatch: None,
            },
        }
    })
}

/// A map drawn as its quantity draws it: the picture, the PNG text beyond the run's
/// provenance, and the colour range used where the quantity's colours span one.
pub struct Drawn {
    pub picture: Picture,
    pub text: Vec<(String, String)>,
    pub range: Option<(f32, f32)>,
}

/// How a map's quantity is drawn, the one picture entry of every map path (command, sweep,
/// store render, explorer tiles): its colours, scale, legend and how NaN, never and unresolved
/// look are its picture function's (below); a new quantity is one more impl.
pub trait MapPicture: MapSpec {
    /// Whether its colours span a range the user may set (`--colour-range`), which the
    /// summary then reports: its kind's table line.
    fn ranged(&self) -> bool {
        MapKind::of(&self.any()).entry().ranged
    }
    /// `picture` and `range` checked against what the quantity's colours allow.
    fn check_picture(&self, picture: &PictureSpec, range: Option<(f32, f32)>) -> Result<()>;
    /// `field` (this spec's map) drawn; `range` None: the quantity's default for the field.
    fn draw(
        &self,
        field: &Field,
        picture: &PictureSpec,
        range: Option<(f32, f32)>,
        unresolved: Option<&[u8]>,
    ) -> Result<Drawn>;
}

impl MapPicture for FlipSpec {
    fn check_picture(&self, picture: &PictureSpec, range: Option<(f32, f32)>) -> Result<()> {
        if self.measure == FlipMeasure::Kind && picture.colormap.is_some() {
            return Err(Error::invalid(
                "colormap",
                "the flip kind has a colour a class of its own; leave out [[colormap]]",
            ));
        }
        match range {
            Some(_) => Err(Error::invalid(
                "colour_range",
                "applies to the divergence map only",
            )),
            None => Ok(()),
        }
    }

    fn draw(
        &self,
        field: &Field,
        picture: &PictureSpec,
        _range: Option<(f32, f32)>,
        unresolved: Option<&[u8]>,
    ) -> Result<Drawn> {
        Ok(Drawn {
            picture: flip_picture(field, self, picture, unresolved)?,
            text: Vec::new(),
            range: None,
        })
    }
}

impl MapPicture for LyapunovSpec {
    fn check_picture(&self, _picture: &PictureSpec, range: Option<(f32, f32)>) -> Result<()> {
        match range {
            Some((lo, hi)) if !(lo.is_finite() && hi.is_finite() && lo < hi) => {
                Err(Error::invalid(
                    "colour_range",
                    format!(
                        "{lo}:{hi} must be LOW:HIGH with LOW < HIGH ({})",
                        self.quantity().unit
                    ),
                ))
            }
            _ => Ok(()),
        }
    }

    fn draw(
        &self,
        field: &Field,
        picture: &PictureSpec,
        range: Option<(f32, f32)>,
        unresolved: Option<&[u8]>,
    ) -> Result<Drawn> {
        let look = look(self);
        let range = range.unwrap_or_else(|| default_range(self, field));
        let name = self.indicator.measure().short_title(self.indicator);
        let text = vec![(
            "chaoscope:colour-range".into(),
            format!(
                "{name} {} .. {} {}, {}, linear ({} = regular)",
                range.0,
                range.1,
                look.unit,
                picture.colormap.unwrap_or(Colormap::Magma).name(),
                if look.reversed { "high" } else { "low" }
            )
            .replace("  ", " "),
        )];
        Ok(Drawn {
            picture: lyapunov_picture(field, self, range, picture, unresolved)?,
            text,
            range: Some(range),
        })
    }
}

impl MapPicture for AnyMap {
    fn check_picture(&self, picture: &PictureSpec, range: Option<(f32, f32)>) -> Result<()> {
        on_any!(self, s => s.check_picture(picture, range))
    }

    fn draw(
        &self,
        field: &Field,
        picture: &PictureSpec,
        range: Option<(f32, f32)>,
        unresolved: Option<&[u8]>,
    ) -> Result<Drawn> {
        on_any!(self, s => s.draw(field, picture, range, unresolved))
    }
}

#[cfg(test)]
mod tests {
    use super::sig;

    #[test]
    fn subtitles_give_four_significant_figures() {
        let cases = [
            (0.41400441153470036, "0.414"),
            (9.81, "9.81"),
            (1.0, "1"),
            (-2.0, "-2"),
            (0.2963, "0.2963"),
            (123456.0, "1.235e5"),
            (2.5e-5, "2.5e-5"),
            (0.0, "0"),
            (1234.6, "1235"),
        ];
        for (x, want) in cases {
            assert_eq!(sig(x), want, "{x}");
        }
    }
}
