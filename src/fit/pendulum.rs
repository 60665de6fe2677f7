//! Which pendulum a track is fitted with. A model the user states (a preset, a parameter
//! file) is used as given; with none, the pendulum's own moments are found from its motion
//! ([`super::identify`]), never the lab's apparatus in silence. Whether a fit with it
//! follows the data is [`super::verdict`]'s.

use super::data::{Estimate, Pivot, TrackedRow, angles, arm_lengths, fit_pivot};
use super::identify::{Identified, identify};
use super::joint::{Joint, Offsets};
use super::level::Roll;
use super::placed::{Placed, on_axes};
use super::weighed::Weighed;
use super::window::TrackRows;
use crate::error::{Error, Result};
use crate::model::Params;
use crate::monitor::Monitor;
use crate::params::ParamSources;

/// Where the fitted model came from.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelSource {
    /// A preset or a parameter file (with any single values on top).
    Given,
    /// The pendulum's own moments, found from the track's motion.
    Identified,
}

impl ModelSource {
    pub fn describe(&self) -> &'static str {
        match self {
            ModelSource::Given => "the model given",
            ModelSource::Identified => "the pendulum's own moments, found from its motion",
        }
    }

    /// One line on the model fitted: where it came from and what it is; a model found from
    /// the motion and weighed (`p` on the weighed scale) in kg m^2 and J.
    pub fn describe_model(&self, p: &Params, weighed: Option<&Weighed>) -> String {
        let k = p.inertia();
        match self {
            ModelSource::Given => format!(
                "the model fitted: {}: bobs {:.4} and {:.4} kg, rods {:.4} and {:.4} kg, arms {:.4} and {:.4} m, g {:.4} m/s^2",
                self.describe(),
                p.m1,
                p.m2,
                p.rod1,
                p.rod2,
                p.l1,
                p.l2,
                p.g
            ),
            ModelSource::Identified => {
                let masses = [p.m1, p.m2, p.rod1, p.rod2];
                let scale = match weighed {
                    Some(w) => format!("scaled to the weighed {} kg", w.mass),
                    None => "on a 1 kg scale: the motion cannot see the masses'".into(),
                };
                // Bobs and uniform rods hold the moments only where no mass comes out negative
                // (a marker at a bar's centre of mass puts the moments where none does).
                let equivalent = match masses.iter().all(|&m| m >= 0.0) {
                    true => format!(
                        "an equivalent pendulum of bobs {:.4} and {:.4} kg, rods {:.4} and {:.4} kg ({scale})",
                        p.m1, p.m2, p.rod1, p.rod2
                    ),
                    false => "no pendulum of point bobs on uniform rods with masses >= 0 has these moments (the arms' masses lie otherwise: the moments are the model)".into(),
                };
                let moments = match weighed {
                    Some(_) => format!(
                        "A {:.4e}, B {:.4e}, C {:.4e} kg m^2, P {:.4e}, Q {:.4e} J",
                        k.a, k.b, k.c, k.p, k.q
                    ),
                    None => format!(
                        "A/P {:.4e}, B/P {:.4e}, C/P {:.4e} s^2, Q/P {:.4}",
                        k.a / k.p,
                        k.b / k.p,
                        k.c / k.p,
                        k.q / k.p
                    ),
                };
                format!(
                    "the model fitted: {} (no preset or params given): {moments}, markers at {:.4} and {:.4} m, g {:.4} m/s^2 (the motion's); {equivalent}",
                    self.describe(),
                    p.l1,
                    p.l2,
                    p.g,
                )
            }
        }
    }

    /// Short, for summary.json.
    pub fn key(&self) -> &'static str {
        match self {
            ModelSource::Given => "given",
            ModelSource::Identified => "identified",
        }
    }
}

/// What tracked data say about the apparatus, and the model to fit to them.
pub struct Tracked {
    /// How many of the rows (the first) taught the pivot, arm lengths, scale and moments.
    pub learned: usize,
    /// The rows in seconds and metres (y up; a scale from the motion applied).
    pub frames: Vec<TrackedRow>,
    /// The metre scale found from the motion (pixels per metre and its error), where asked.
    pub scale_from_motion: Option<(f64, f64)>,
    pub pivot: Pivot,
    pub l1: Estimate,
    pub l2: Estimate,
    /// The rows' times (s), the arms' angles (rad, unwrapped) and the positions relative to
    /// the pivot (x1, y1, x2, y2; m).
    pub t: Vec<f64>,
    pub angles: Vec<(f64, f64)>,
    pub measured: Vec<[f64; 4]>,
    pub params: Params,
    pub source: ModelSource,
    /// What the motion says of the pendulum (the model itself where none was given), or
    /// why it could not say.
    pub identified: std::result::Result<Identified, String>,
    /// Notices on the model (a negative damping, a time scale that disagrees).
    pub notices: Vec<String>,
    /// Where the markers sit on the arms and gravity's down (taken out of `frames`).
    pub placed: Placed,
}

impl Tracked {
    /// The joint damping the rows' motion shows, with its errors, where the model came from
    /// the motion: what a window's fit is held to ([`super::window::DampingPrior`]).
    pub fn damping_prior(&self) -> Option<super::window::DampingPrior> {
        match (&self.source, &self.identified) {
            (ModelSource::Identified, Ok(id)) => Some(id.damping_prior()).filter(|d| d.is_valid()),
            _ => None,
        }
    }

    pub fn rows(&self) -> TrackRows<'_> {
        TrackRows {
            t: &self.t,
            data: &self.measured,
            angles: &self.angles,
        }
    }

    /// The tolerance unless given ([`TrackRows::default_tolerance`]).
    pub fn default_tolerance(&self) -> f64 {
        TrackRows::default_tolerance(&self.params)
    }

    /// The window's length (s) unless given ([`TrackRows::default_window`]).
    pub fn default_window(&self) -> f64 {
        self.rows().default_window()
    }

    /// The window's start (s) unless given: the first row with a row before it (the
    /// velocities' central differences need one).
    pub fn default_start(&self) -> f64 {
        self.t[1]
    }
}

/// Values that state a part of a pendulum, which only a stated model can hold: with none,
/// the motion fixes them.
fn stated_parts(given: &ParamSources) -> Option<&'static str> {
    let parts = [
        ("m1", given.m1.is_some()),
        ("m2", given.m2.is_some()),
        ("rod_mass", given.rod_mass.is_some()),
        ("l1", given.l1.is_some()),
        ("l2", given.l2.is_some()),
        (
            "air_drag",
            given.air_drag
                || given.rho.is_some()
                || given.cw.is_some()
                || given.drag_area.is_some()
                || given.rod_drag_area.is_some(),
        ),
        (
            "bearing_friction",
            given.bearing_friction.is_some() || given.bearing_radius.is_some(),
        ),
    ];
    parts.into_iter().find(|p| p.1).map(|p| p.0)
}

/// Arms longer than this (m) are no pendulum on a bench: positions in pixels read as metres.
const LONGEST_ARM: f64 = 10.0;

/// A motion slower than this (s, 1/RMS of the upper arm's angular velocity) is no swinging
/// pendulum: frame numbers read as seconds (a 1 m pendulum's is about 0.3 s).
const SLOWEST_MOTION: f64 = 60.0;

/// A time scale off by more than this factor in g (the frame rate by 5, the metre by 25) is
/// a unit mistake, not a camera's rate or scale a little off (the shared recording's usual
/// rate and usual arm length disagree by 1.5).
const UNIT_MISTAKE: f64 = 25.0;

/// The metre scale of `frames` (in pixels, y up) that their motion implies under gravity
/// `g` at their times: pixels per metre and its error.
pub fn scale_from_motion(frames: &[TrackedRow], g: f64, monitor: &Monitor) -> Result<(f64, f64)> {
    let (frames, _) = on_axes(frames, frames.len(), &Placed::default(), 1.0)?;
    fit_pivot(&frames)?;
    motion_scale(&frames, g, monitor)
}

/// Refuses moments that say the file's y axis is turned over. The moments are over the upper
/// arm's gravity moment P: with gravity turned over, P is negative, and both inertias over it
/// are, each by three of its standard errors (a stated model's fit is not refused on a noisy
/// file's chance).
fn turned_over(id: &Identified) -> Result<()> {
    let negative = |k: usize| id.values[k] + 3.0 * id.errors[k] < 0.0;
    if negative(0) && negative(1) {
        return Err(Error::invalid(
            "y_up",
            format!(
                "the inertias the motion implies are negative (a {:.3e}, b {:.3e} s^2 over the upper arm's gravity moment): the signature of a y axis turned over, the masses falling upwards; pixels are read y down unless [[y_up]] is given (Tracker's own frame), metres y up",
                id.values[0], id.values[1]
            ),
        ));
    }
    Ok(())
}

/// [`scale_from_motion`] of `frames` whose upper marker is on the middle joint.
fn motion_scale(frames: &[TrackedRow], g: f64, monitor: &Monitor) -> Result<(f64, f64)> {
    let pivot = fit_pivot(frames)?;
    let measured = super::measured(frames, (pivot.x, pivot.y));
    let angles = angles(frames, (pivot.x, pivot.y));
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let rows = TrackRows {
        t: &t,
        data: &measured,
        angles: &angles,
    };
    let id = identify(&rows, g, monitor).map_err(|e| match e {
        Error::InvalidSpec { reason, .. } => Error::invalid(
            "pixels_per_metre",
            format!("the scale cannot be found from this file's motion: {reason}; give it"),
        ),
        e => e,
    })?;
    let ts = id.time_scale;
    // Upside down, gravity pulls the masses up: the swing implies a negative scale.
    if ts.g_implied <= 0.0 {
        return Err(Error::invalid(
            "y_up",
            format!(
                "the motion implies a scale of {:.4} pixels per metre, negative: in this file's frame the masses fall upwards, so its y runs up (as Tracker exports it); give [[y_up]]",
                ts.g_implied / g
            ),
        ));
    }
    Ok((ts.g_implied / g, ts.g_implied_error / g))
}

/// The pivot (a least-squares circle through the upper mass), the arm lengths and angles of
/// `frames`, and the model: `given`'s where it names a preset or a file (the arm lengths
/// from the data unless given), else the one the motion implies. With `units` asking for
/// the scale from the motion, `frames` are in pixels (y up) and are scaled first.
pub fn tracked_model(
    frames: &[TrackedRow],
    given: &ParamSources,
    units: &super::data::Units,
    monitor: &Monitor,
) -> Result<Tracked> {
    tracked_model_from(
        frames,
        frames.len(),
        given,
        units,
        Known::default(),
        monitor,
    )
}

/// What a calibration knows of the camera's view of the pendulum, for a recording too short
/// to show it: the metre scale (pixels per metre and its error) where it came from the
/// motion, and the pivot (m, in the rows' frame: relative to a pivot marker where the file
/// has one, else the camera's, which must then stand where it stood).
#[derive(Clone, Copy, Debug, Default)]
pub struct Known {
    pub scale: Option<(f64, f64)>,
    pub pivot: Option<(f64, f64)>,
    /// The picture's roll (rad) and its error, and the markers' offsets from the axes (m),
    /// as the calibration's recording showed them: where the learned rows show either less
    /// precisely, the calibration's stands.
    pub roll: Option<(f64, f64)>,
    pub offsets: Option<Offsets>,
    /// The upper marker's distance from the pivot (m) in the calibration's model: a circle
    /// through a few rows that disagrees with it places no pivot.
    pub l1: Option<f64>,
}

/// A pivot the learned rows place worse than this share of the upper arm (its standard
/// error) is taken from a calibration where there is one: four frames of a high-speed film
/// span a sliver of the arc, a quarter of a second of it a clear arc.
const PIVOT_SHARE: f64 = 0.01;

/// A circle through the learned rows whose radius is off the calibration's upper arm by
/// more than this share is no pivot (a few frames fit a small circle exactly).
const ARM_SHARE: f64 = 0.05;

/// [`tracked_model`] that learns from the first `learn` rows alone: the pivot, the arm
/// lengths, the middle joint, the metre scale and the motion's moments come from them
/// (the scale, and the pivot where they cannot place it, from `known`); every row is then
/// measured against what they taught. A forecast learns only from the rows up to its
/// window's end, and the rows after it are only scored.
pub fn tracked_model_from(
    frames: &[TrackedRow],
    learn: usize,
    given: &ParamSources,
    units: &super::data::Units,
    known: Known,
    monitor: &Monitor,
) -> Result<Tracked> {
    let scale = known.scale;
    let g = given.g.unwrap_or(Params::default().g);
    let learn = learn.clamp(1, frames.len());
    // The frames' units per metre: pixels where the scale comes from the motion (the
    // calibration's, where it gives one; a recording's own is found only after this).
    let unit = match units.pixels_per_metre {
        Some(super::data::PixelScale::FromMotion) => scale.map_or(f64::NAN, |(ppm, _)| ppm),
        _ => 1.0,
    };
    let theirs = Placed {
        joint: None,
        offsets: known.offsets,
        roll: known.roll.map(|(r, e)| Roll::calibrated(r, e)),
    };
    let (frames, mut placed) = on_axes(frames, learn, &theirs, unit)?;
    let frames = &frames[..];
    let (frames, scale_from_motion) = match units.pixels_per_metre {
        Some(super::data::PixelScale::FromMotion) => {
            let (ppm, error) = match scale {
                Some(s) => s,
                None => motion_scale(&frames[..learn], g, monitor)?,
            };
            if let Some(j) = &mut placed.joint {
                *j = Joint {
                    marker: j.marker / ppm,
                    joint: j.joint / ppm,
                    error: j.error / ppm,
                };
            }
            placed.offsets = placed.offsets.map(|o| o.scaled(1.0 / ppm));
            let scaled = frames
                .iter()
                .map(|f| TrackedRow {
                    t: f.t,
                    x1: f.x1 / ppm,
                    y1: f.y1 / ppm,
                    x2: f.x2 / ppm,
                    y2: f.y2 / ppm,
                })
                .collect();
            (scaled, Some((ppm, error)))
        }
        _ => (frames.to_vec(), None),
    };
    let frames = &frames[..];
    let own = fit_pivot(&frames[..learn]);
    let well_placed = |p: &Pivot| {
        p.errors[0].hypot(p.errors[1]) <= PIVOT_SHARE * p.radius
            && known
                .l1
                .is_none_or(|l1| (p.radius - l1).abs() <= ARM_SHARE * l1)
    };
    let mut pivot_notice = None;
    let pivot = match (own, known.pivot) {
        (Ok(p), _) if well_placed(&p) => p,
        (Ok(p), None) => p,
        (own, Some((x, y))) => {
            pivot_notice = Some(format!(
                "the pivot from the calibration, ({x:.5}, {y:.5}) m: the {learn} rows learned from {}",
                match own {
                    Ok(p) => format!(
                        "place it only to {:.2} mm, on a circle of {:.4} m",
                        1e3 * p.errors[0].hypot(p.errors[1]),
                        p.radius
                    ),
                    Err(_) => "span too little of the arc to place it".into(),
                }
            ));
            Pivot {
                x,
                y,
                radius: f64::NAN,
                errors: [0.0; 3],
                rms_residual: f64::NAN,
            }
        }
        (Err(e), None) => return Err(e),
    };
    let (l1, l2) = arm_lengths(&frames[..learn], (pivot.x, pivot.y));
    let angles = angles(frames, (pivot.x, pivot.y));
    let measured = super::measured(frames, (pivot.x, pivot.y));
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    // What the motion teaches (its own time, its moments) from the learned rows alone.
    let (lt, lm, la) = (&t[..learn], &measured[..learn], &angles[..learn]);
    if l1.value > LONGEST_ARM {
        return Err(Error::invalid(
            "pixels_per_metre",
            format!(
                "the upper arm comes out {:.4} m long (the pivot to the upper marker): are the positions in pixels? Give the camera's pixels per metre, or `motion` for the scale the swing implies",
                l1.value
            ),
        ));
    }
    let natural = TrackRows {
        t: lt,
        data: lm,
        angles: la,
    }
    .motion_time();
    if natural > SLOWEST_MOTION {
        let slow = format!(
            "the upper arm turns by 1 rad in {natural:.0} s (1/RMS of its angular velocity; a swinging pendulum's is under a second or so)"
        );
        // Blame what the user gave: the frame rate that made the times, or the times' column.
        return Err(match units.frame_rate {
            Some(rate) => Error::invalid(
                "frame_rate",
                format!("{slow}: is the film's frame rate {rate} frames a second?"),
            ),
            None => Error::invalid(
                "file",
                format!(
                    "{slow}: the rows barely move (a pendulum at rest?), or their `t` column is not in seconds (frame numbers: name the column `frame` and give the frame rate)"
                ),
            ),
        });
    }
    let stated = given.preset.is_some() || given.params.is_some();
    let rows = TrackRows {
        t: lt,
        data: lm,
        angles: la,
    };
    let mut notices = Vec::new();
    let (params, source, identified) = if stated {
        let sources = ParamSources {
            l1: given.l1.or(Some(l1.value)),
            l2: given.l2.or(Some(l2.value)),
            ..given.clone()
        };
        let params = sources.resolve()?;
        if params.losses.joint1 != 0.0 || params.losses.joint2 != 0.0 {
            notices.push(format!(
                "the joint damping the model states ({:.3e} and {:.3e} N m s) is one of the fit's starts: the fit finds its own",
                params.losses.joint1, params.losses.joint2
            ));
        }
        let identified = identify(&rows, params.g, monitor).map_err(|e| match e {
            Error::InvalidSpec { reason, .. } => reason,
            e => e.to_string(),
        });
        if let Ok(id) = &identified {
            turned_over(id)?;
        }
        (params, ModelSource::Given, identified)
    } else {
        if let Some(field) = stated_parts(given) {
            return Err(Error::invalid(
                field,
                "states a part of a pendulum, but no model was given for it to be part of: with no preset or params the model is found from the motion, which fixes it; give a preset or params to state a model, or leave it out",
            ));
        }
        let id = identify(&rows, g, monitor).map_err(|e| match e {
            Error::InvalidSpec { reason, .. } => Error::invalid(
                "params",
                format!(
                    "no model was given (a preset or params), and the file's motion does not give one: {reason}"
                ),
            ),
            e => e,
        })?;
        turned_over(&id)?;
        if !id.physical() {
            return Err(Error::invalid(
                "params",
                format!(
                    "no model was given (a preset or params), and the moments the motion implies are no real pendulum's (a {:.3e}, b {:.3e}, c {:.3e} s^2, q {:.3e}: inertias and gravity's moments must be > 0 and a b > c^2): the track may not follow two rigid arms; state the model",
                    id.values[0], id.values[1], id.values[2], id.values[3]
                ),
            ));
        }
        let params = id.params()?;
        (params, ModelSource::Identified, Ok(id))
    };
    if let Ok(id) = &identified {
        let ts = id.time_scale;
        let factor = ts.g_implied / ts.g;
        if !(1.0 / UNIT_MISTAKE..=UNIT_MISTAKE).contains(&factor) {
            let (field, what) = match factor < 1.0 {
                true => (
                    "frame_rate",
                    "the times run slow: are they frame numbers? Name the column `frame` and give the frame rate",
                ),
                false => (
                    "pixels_per_metre",
                    "the lengths run long: are the positions in pixels? Give the camera's pixels per metre, or `motion`",
                ),
            };
            return Err(Error::invalid(
                field,
                format!(
                    "the motion implies gravity {:.3e} m/s^2 at the file's metres and seconds, {factor:.2e} times g ({} m/s^2): {what}",
                    ts.g_implied, ts.g
                ),
            ));
        }
        for (k, joint) in [(4, "pivot"), (5, "middle joint")] {
            if id.values[k] < 0.0 {
                notices.push(format!(
                    "the motion implies a negative damping at the {joint} ({:.2e} ± {:.1e} s over P): the data gain energy there, from a drive, a hand, or tracking errors that lean one way{}",
                    id.values[k],
                    id.errors[k],
                    match source {
                        ModelSource::Identified => "; the model starts from none and the fit finds the damping",
                        ModelSource::Given => "",
                    }
                ));
            }
        }
    }
    notices.extend(pivot_notice);
    if let Some(j) = &placed.joint {
        notices.push(format!(
            "the upper marker is not on the middle joint: it sits {:.4} m from the pivot, the joint (where the lower arm turns) {:.4} ± {:.4} m; the joint's positions along the upper arm stand in for the marker's",
            j.marker, j.joint, j.error
        ));
    }
    if let Some(o) = &placed.offsets {
        notices.push(format!(
            "the markers sit off the arms' axes, as the lower rod's length shows it: the upper marker {:.2} mm along and {:.2} mm across the upper arm from the middle joint, the lower marker seen ({:.2}, {:.2}) mm off (errors {:.2}, {:.2}, {:.2}, {:.2} mm); taken out",
            1e3 * o.along,
            1e3 * o.across,
            1e3 * o.lower.0,
            1e3 * o.lower.1,
            1e3 * o.errors[0],
            1e3 * o.errors[1],
            1e3 * o.errors[2],
            1e3 * o.errors[3]
        ));
    }
    if let Some(r) = placed.roll.filter(|r| r.applied != 0.0) {
        notices.push(format!(
            "the picture is rolled against gravity by {:.3} ± {:.3} degrees, as the motion shows it; levelled by {:.3} degrees",
            r.roll.to_degrees(),
            r.error.to_degrees(),
            r.applied.to_degrees()
        ));
    }
    if let Some((ppm, error)) = scale_from_motion {
        notices.push(format!(
            "the metre scale {}: {ppm:.2} ± {error:.2} pixels per metre at the file's frame rate and g {g} m/s^2 (arms {:.4} and {:.4} m)",
            match scale {
                Some(_) => "from the calibration",
                None => "from the motion",
            },
            l1.value,
            l2.value
        ));
    }
    Ok(Tracked {
        learned: learn,
        frames: frames.to_vec(),
        scale_from_motion,
        placed,
        pivot,
        l1,
        l2,
        t,
        angles,
        measured,
        params,
        source,
        identified,
        notices,
    })
}
