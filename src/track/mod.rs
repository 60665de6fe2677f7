//! From a film of the pendulum to the positions of both masses in every frame: markers found
//! in each frame ([`detect`]), the pivot and arms read from the markers themselves and each
//! blob named by that geometry ([`geometry`]), in metres from the pivot, y up. A mass that
//! is not seen in a frame is reported as not seen, never placed. [`synth`] renders test
//! films with a known truth.

pub mod colours;
pub mod detect;
mod errors;
pub mod file;
pub mod geometry;
pub mod pivot;
pub mod reader;
pub mod release;
pub mod synth;

pub use detect::{Blob, Markers, Role};
pub use file::{CsvRow, Measured, read_rows};
pub use geometry::Geometry;
pub use pivot::PivotMarker;

use crate::error::{Error, Result};
use crate::stats::median;
use file::TrackedRow;

/// How pixels become metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    /// The upper arm's length (m): its circle's radius in pixels is that many metres.
    UpperArm(f64),
    PixelsPerMetre(f64),
    /// The scale the swing implies under gravity g (m/s^2) at the film's own frame times: a
    /// rigid pendulum's motion fixes l1/g in seconds. Finding it is the fit's work (the
    /// command hands [`track`] a [`MotionScale`]): a film's track knows no model.
    FromMotion(f64),
}

impl Scale {
    /// The scale as a door asks for it: by the upper arm's length (`l1`) or by
    /// `pixels_per_metre` (a number, or the swing's), one of the two.
    pub fn asked(
        l1: Option<f64>,
        pixels_per_metre: Option<crate::track::file::PixelScale>,
    ) -> Result<Scale> {
        use crate::track::file::PixelScale;
        match (l1, pixels_per_metre) {
            (Some(l1), None) => Ok(Scale::UpperArm(l1)),
            (None, Some(PixelScale::PerMetre(p))) => Ok(Scale::PixelsPerMetre(p)),
            (None, Some(PixelScale::FromMotion)) => {
                Ok(Scale::FromMotion(crate::model::Params::default().g))
            }
            (Some(_), Some(_)) => Err(Error::invalid(
                "pixels_per_metre",
                "give the scale once, by [[l1]] or by [[pixels_per_metre]]",
            )),
            (None, None) => Err(Error::invalid(
                "l1",
                "the scale is needed: the upper arm's length (m), or [[pixels_per_metre]]",
            )),
        }
    }
}

/// One mass in one frame, measured: its mean position over the exposure (m, origin at the
/// pivot, y up), the standard errors of that position from the sensor's noise (m), and the
/// streak's length (m: the distance moved during the exposure, 0 for a sharp marker).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mark {
    pub x: f64,
    pub y: f64,
    pub sx: f64,
    pub sy: f64,
    pub streak: f64,
    /// Where in the picture (px, x right, y down).
    pub px: (f64, f64),
    /// Not measured: placed by the model fitted to the measured rows around a gap
    /// (`--bridge`); its errors are the model's, its streak NaN.
    pub bridged: bool,
}

/// One frame's row: its time from the film's first (s) and each mass, if seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackRow {
    pub t: f64,
    pub m1: Option<Mark>,
    pub m2: Option<Mark>,
}

/// What the tracker found: every frame's row, the geometry (px), the scale (px per metre),
/// the up direction and the still blobs it set aside.
#[derive(Clone, Debug)]
pub struct Tracked {
    pub rows: Vec<TrackRow>,
    pub geometry: Geometry,
    pub pixels_per_metre: f64,
    pub up: Up,
    pub still: Vec<(f64, f64)>,
    /// The time (s) of the last frame before free motion, where the film shows the
    /// pendulum held still and then let go ([`release::release`]).
    pub release: Option<f64>,
    /// The marker at the pivot the masses were measured from, where the film shows one.
    pub pivot_marker: Option<PivotMarker>,
}

impl Tracked {
    /// When the pendulum was lifted by hand: from the end of its rest to the release, where
    /// the film shows both.
    pub fn lift(&self) -> Option<(f64, f64)> {
        let (_, end) = self.up.rest?;
        self.release.filter(|&t| t > end).map(|t| (end, t))
    }
}

/// Which way is up: from the pendulum hanging at rest (the pivot straight above both
/// markers), or, where the film never shows it at rest, the picture's.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Up {
    /// The world's up in the picture (a unit vector, px axes: x right, y down).
    pub direction: (f64, f64),
    /// How far it is turned from the picture's up (degrees, counter-clockwise as seen).
    pub tilt_degrees: f64,
    /// The stretch of the film (s) in which the pendulum hung at rest, where it did.
    pub rest: Option<(f64, f64)>,
}

impl Up {
    pub const PICTURE: Up = Up {
        direction: (0.0, -1.0),
        tilt_degrees: 0.0,
        rest: None,
    };

    /// Pixels from the pivot to metres (x along the world's right, y up).
    fn metres(&self, d: (f64, f64), ppm: f64) -> (f64, f64) {
        let (ux, uy) = self.direction;
        // The world's right in the picture: up turned a quarter clockwise as seen.
        let (rx, ry) = (-uy, ux);
        ((d.0 * rx + d.1 * ry) / ppm, (d.0 * ux + d.1 * uy) / ppm)
    }
}

/// The least a rest lasts (s): a swing's turning point stands still for a frame or two.
const REST: f64 = 1.0;
/// How far (px) a marker at rest may move from one frame to the next: the centroid's noise
/// (a sticker's on a textured board, H.264 encoded twice when a phone's film is turned:
/// up to 0.3 px on the test films).
const STILL_STEP: f64 = 0.5;
/// The most a hanging pendulum's arms may bend from one line (rad), and the most its line
/// may lean from the picture's down (a camera held near level): a pendulum held still for
/// its release bends at the middle joint, or leans further.
const HANGING_BEND: f64 = 0.03;
const LEVEL: f64 = 0.5;

/// Whether markers at `m1` and `m2` (px) hang from `pivot`: both arms in one line, leaning
/// from the picture's down by less than [`LEVEL`].
fn hangs(pivot: (f64, f64), m1: (f64, f64), m2: (f64, f64)) -> bool {
    let (a, b) = ((m1.0 - pivot.0, m1.1 - pivot.1), (m2.0 - m1.0, m2.1 - m1.1));
    let bend = (a.0 * b.1 - a.1 * b.0).atan2(a.0 * b.0 + a.1 * b.1).abs();
    let lean = a.0.atan2(a.1).abs();
    bend < HANGING_BEND && lean < LEVEL
}

/// The `still` places where the pendulum may hang at rest: on the upper marker's circle, or
/// both arms' length from the pivot, below it within [`LEVEL`] of the picture's down. A rest
/// of a fifth of the film looks like a lamp in one place or both; the rest itself is told by
/// both markers standing in line below the pivot ([`up_from_rest`]).
fn hanging_places(still: &[(f64, f64)], g: &Geometry) -> Vec<(f64, f64)> {
    still
        .iter()
        .copied()
        .filter(|&(x, y)| {
            let (dx, dy) = (x - g.pivot.0, y - g.pivot.1);
            let r = dx.hypot(dy);
            let on_arm = (r - g.r1).abs() < OFF_GEOMETRY || (r - g.r1 - g.r2).abs() < OFF_GEOMETRY;
            on_arm && dx.atan2(dy).abs() < LEVEL
        })
        .collect()
}

/// The up direction from the longest stretch of the `named` markers (px places, at `times`)
/// in which both stand still, hanging in one line below the `pivot` (None: no stretch of
/// [`REST`] or more).
fn up_from_rest(
    named: &[(geometry::Named, geometry::Named)],
    times: &[f64],
    pivot: (f64, f64),
) -> Option<Up> {
    let step = |a: Option<Blob>, b: Option<Blob>| match (a, b) {
        (Some(a), Some(b)) => (a.x - b.x).hypot(a.y - b.y) < STILL_STEP,
        _ => false,
    };
    let hanging = |m1: Blob, m2: Blob| hangs(pivot, (m1.x, m1.y), (m2.x, m2.y));
    let mut best: Option<(usize, usize)> = None;
    let mut k = 1;
    while k < named.len() {
        let still = |k: usize| {
            step(named[k].0, named[k - 1].0)
                && step(named[k].1, named[k - 1].1)
                && hanging(named[k].0.unwrap(), named[k].1.unwrap())
        };
        if !still(k) {
            k += 1;
            continue;
        }
        let first = k - 1;
        while k < named.len() && still(k) {
            k += 1;
        }
        if best.is_none_or(|(a, b)| times[k - 1] - times[first] > times[b] - times[a]) {
            best = Some((first, k - 1));
        }
    }
    let (a, b) = best.filter(|&(a, b)| times[b] - times[a] >= REST - 1e-9)?;
    // Down: from the pivot to the lower marker's mean place at rest (the longer lever).
    let n = (b - a + 1) as f64;
    let (mut dx, mut dy) = (0.0, 0.0);
    for (_, m2) in &named[a..=b] {
        let m2 = m2.expect("named at rest");
        dx += (m2.x - pivot.0) / n;
        dy += (m2.y - pivot.1) / n;
    }
    let norm = dx.hypot(dy);
    let direction = (-dx / norm, -dy / norm);
    Some(Up {
        direction,
        // Picture's up (0, -1) to `direction`, counter-clockwise as seen (y down).
        tilt_degrees: (-direction.0).atan2(-direction.1).to_degrees(),
        rest: Some((times[a], times[b])),
    })
}

/// `frames` without the blobs of less than half a marker's light: a reflection that moves
/// with the pendulum (a glossy board, a window's second pane) is a dimmer copy of both
/// markers at a fixed offset, and the upper one's copy keeps a fixed distance from the
/// upper marker, which would pass for the lower arm. A marker's light is each frame's
/// brightest blob of its colour (of one look for both: the second brightest), the median
/// over the film.
fn dim_ones_out(frames: Vec<Vec<Blob>>) -> Vec<Vec<Blob>> {
    let reference = |role: Role| {
        let rank = if role == Role::Either { 1 } else { 0 };
        let mut lights: Vec<f64> = frames
            .iter()
            .filter_map(|f| {
                let mut v: Vec<f64> = f
                    .iter()
                    .filter(|b| b.role == role)
                    .map(|b| b.flux)
                    .collect();
                v.sort_by(|a, b| b.total_cmp(a));
                v.get(rank).copied()
            })
            .collect();
        median(&mut lights)
    };
    let least = Role::ALL.map(reference);
    frames
        .into_iter()
        .map(|f| {
            f.into_iter()
                .filter(|b| least[b.role as usize].is_none_or(|l| b.flux >= 0.5 * l))
                .collect()
        })
        .collect()
}

/// How far (px) a blob may lie off the geometry and still be named by it: two pixels, a
/// blurred upper marker's sag inside its circle (its mean over an arc lies r theta^2 / 24
/// inside: 1 px at r = 300 px and 0.35 rad swept in one exposure) and its noise.
const OFF_GEOMETRY: f64 = 3.0;

/// The metre scale (pixels per metre, and its error) that rows in pixels (y up) imply
/// under gravity g (m/s^2) by their motion: the fit's `scale_from_motion`, handed in by the
/// command, so that the track room imports nothing of the rooms above it.
pub type MotionScale<'a> = &'a dyn Fn(&[TrackedRow], f64) -> Result<(f64, f64)>;

/// Names every frame's blobs (found as `markers` say) and turns them into rows (times from
/// `times`). Where a marker stays at the pivot, the blobs are measured from it frame by
/// frame ([`pivot`]) and named again. `motion` finds a scale from the motion where `scale`
/// asks for one.
pub fn track(
    frames: &[Vec<Blob>],
    times: &[f64],
    scale: Scale,
    markers: Markers,
    motion: MotionScale,
) -> Result<Tracked> {
    check_colours_seen(markers, frames)?;
    let tracked = track_steady(frames, times, scale, motion)?;
    let coloured = matches!(markers, Markers::Colours { pivot: Some(_), .. });
    match pivot::find(frames, &tracked.geometry, coloured) {
        Some((marker, shifts)) => {
            let steady = pivot::steadied(frames, &shifts);
            let mut tracked = track_steady(&steady, times, scale, motion)?;
            // The pivot's marker is no distractor set aside.
            tracked
                .still
                .retain(|s| (s.0 - marker.place.0).hypot(s.1 - marker.place.1) > pivot::WANDER);
            tracked.pivot_marker = Some(marker);
            Ok(tracked)
        }
        None if coloured => Err(Error::invalid(
            "markers",
            format!(
                "no marker of the pivot's colour stays at the pivot ({:.0}, {:.0}) px in half the frames or more: give the pivot's colour as the film shows it, or two colours only",
                tracked.geometry.pivot.0, tracked.geometry.pivot.1
            ),
        )),
        None => Ok(tracked),
    }
}

/// The blobs of each frame that look like markers (None where no blob is named one).
/// Markers of one look are as bright as each other, give or take: a blob with much less
/// light than the named ones is a reflection or a marker partly hidden (its centroid
/// off), and one with much more is two blobs merged or a lamp. Markers of two colours
/// are compared each with its own.
fn plausible_blobs(moving: &[Vec<Blob>], g: &Geometry) -> Option<Vec<Vec<Blob>>> {
    let named = geometry::name(moving, g, OFF_GEOMETRY);
    let typical = |role: Role, of: fn(&Blob) -> f64| {
        let mut v: Vec<f64> = named
            .iter()
            .flat_map(|(a, b)| [a, b])
            .filter_map(|m| m.filter(|b| b.role == role).map(|b| of(&b)))
            .collect();
        median(&mut v)
    };
    let flux = Role::ALL.map(|r| typical(r, |b| b.flux));
    let core = Role::ALL.map(|r| typical(r, |b| b.core.2));
    if flux.iter().all(Option::is_none) {
        return None;
    }
    // A sticker's colour smears further than a lamp's light under blur and the chroma's
    // subsampling (1/120 s streaks kept 74 % of a still sticker's flux on the test film):
    // a coloured marker may lose more before it is taken for a reflection (a quarter as
    // bright, or less).
    let least = |role: Role| if role == Role::Either { 0.75 } else { 0.6 };
    let marker_like = |flux: f64, typical: f64, role: Role| {
        (least(role) * typical..1.3 * typical).contains(&flux)
    };
    let plausible: Vec<Vec<Blob>> = moving
        .iter()
        .map(|f| {
            f.iter()
                .filter_map(|b| {
                    let k = b.role as usize;
                    let (typical, typical_core) = (flux[k]?, core[k]?);
                    // A dim blob run into a marker pulls its centroid off its core.
                    let pulled = (b.x - b.core.0).hypot(b.y - b.core.1) > 1.0;
                    if marker_like(b.flux, typical, b.role) && !(pulled && b.flux > 1.1 * typical) {
                        Some(*b)
                    } else if b.flux > typical && marker_like(b.core.2, typical_core, b.role) {
                        // A marker with a dimmer blob run into it: its core is the marker.
                        Some(Blob {
                            x: b.core.0,
                            y: b.core.1,
                            flux: typical,
                            ..*b
                        })
                    } else {
                        None
                    }
                })
                .collect()
        })
        .collect();
    Some(plausible)
}

/// [`track`] in a picture that stands still (or has been steadied on the pivot's marker).
fn track_steady(
    frames: &[Vec<Blob>],
    times: &[f64],
    scale: Scale,
    motion: MotionScale,
) -> Result<Tracked> {
    let mut still = geometry::still(frames);
    let without = |still: &[(f64, f64)]| -> Vec<Vec<Blob>> {
        let is_still = |b: &Blob| still.iter().any(|s| (s.0 - b.x).hypot(s.1 - b.y) < 3.0);
        dim_ones_out(
            frames
                .iter()
                .map(|f| f.iter().filter(|b| !is_still(b)).copied().collect())
                .collect(),
        )
    };
    let mut moving = without(&still);
    let not_found = || {
        Error::invalid(
            "video",
            "no pendulum found: no circle of blobs that one marker keeps to (are the markers bright on a dark background, or [[markers]] of their colour?)",
        )
    };
    let g = geometry::find(&moving, OFF_GEOMETRY, 1).ok_or_else(not_found)?;
    // A pendulum hanging still through much of the film looks like lamps where it hangs.
    let hanging = hanging_places(&still, &g);
    if !hanging.is_empty() {
        still.retain(|s| !hanging.contains(s));
        moving = without(&still);
    }
    let plausible = plausible_blobs(&moving, &g).ok_or_else(not_found)?;
    let named = geometry::name(&plausible, &g, OFF_GEOMETRY);
    check_upper_on_its_circle(frames, &named)?;
    let g = geometry::refined(&named, g);
    let up = up_from_rest(&named, times, g.pivot).unwrap_or(Up::PICTURE);
    let moved = errors::in_motion(&named);
    let floors = errors::error_floors(&named, &moved, &g);
    // A marker's own elongation (a sticker not quite round, lit from one side) is no
    // motion: the median over the frames it stood still is taken out of its streaks.
    let own = [0, 1].map(|k| {
        let mut still: Vec<f64> = named
            .iter()
            .zip(&moved)
            .filter(|(_, m)| m[k].is_none())
            .filter_map(|(n, _)| if k == 0 { n.0 } else { n.1 })
            .map(|b| b.streak().powi(2))
            .collect();
        median(&mut still).unwrap_or(0.0)
    });
    // The mass `k`'s place `b` in metres at `ppm`, moving as `motion` says.
    let mark_at = |b: Blob, ppm: f64, k: usize, motion: Option<(f64, f64)>| {
        let (x, y) = up.metres((b.x - g.pivot.0, b.y - g.pivot.1), ppm);
        let floor = floors[usize::from(motion.is_some())][k].max(errors::LEAST_ERROR);
        let (sx, sy) = up.errors(b.sx, b.sy, floor, motion, b.streak());
        Mark {
            x,
            y,
            sx: sx / ppm,
            sy: sy / ppm,
            // Still (under half a pixel a frame): no streak, whatever the shape.
            streak: match motion {
                Some(_) => (b.streak().powi(2) - own[k]).max(0.0).sqrt() / ppm,
                None => 0.0,
            },
            px: (b.x, b.y),
            bridged: false,
        }
    };
    let ppm = match scale {
        Scale::UpperArm(l1) => g.r1 / l1,
        Scale::PixelsPerMetre(p) => p,
        Scale::FromMotion(gravity) => {
            // The rows with both marks, in pixels (y up), are what the motion is read from.
            let rows: Vec<TrackedRow> = named
                .iter()
                .zip(times)
                .filter_map(|(&(a, b), &t)| {
                    let (a, b) = (mark_at(a?, 1.0, 0, None), mark_at(b?, 1.0, 1, None));
                    Some(TrackedRow {
                        t,
                        x1: a.x,
                        y1: a.y,
                        x2: b.x,
                        y2: b.y,
                    })
                })
                .collect();
            if rows.len() < 5 {
                return Err(Error::invalid(
                    "pixels_per_metre",
                    "the scale cannot be found from the motion: both markers are seen in fewer than 5 frames; give it",
                ));
            }
            motion(&rows, gravity)?.0
        }
    };
    let rows = named
        .iter()
        .zip(times)
        .zip(&moved)
        .map(|((&(a, b), &t), m)| TrackRow {
            t,
            m1: a.map(|a| mark_at(a, ppm, 0, m[0])),
            m2: b.map(|b| mark_at(b, ppm, 1, m[1])),
        })
        .collect();
    Ok(Tracked {
        rows,
        geometry: g,
        pixels_per_metre: ppm,
        up,
        still,
        release: release::release(&named, times),
        pivot_marker: None,
    })
}

/// The frames in which a blob of `role` stands out.
fn frames_with(frames: &[Vec<Blob>], role: Role) -> usize {
    frames
        .iter()
        .filter(|f| f.iter().any(|b| b.role == role))
        .count()
}

/// With a colour for each marker, each must be found in the film: a colour the camera never
/// saw is named, not left to make a geometry of whatever else there is.
fn check_colours_seen(markers: Markers, frames: &[Vec<Blob>]) -> Result<()> {
    let Markers::Colours {
        upper,
        lower,
        pivot,
    } = markers
    else {
        return Ok(());
    };
    let mut given = vec![(upper, Role::Upper, "upper"), (lower, Role::Lower, "lower")];
    given.extend(pivot.map(|p| (p, Role::Pivot, "pivot")));
    for (colour, role, which) in given {
        let seen = frames_with(frames, role);
        // A marker hidden most of the film is still a marker; one seen in fewer than one
        // frame in twenty is not there.
        if seen * 20 < frames.len() {
            let [r, g, b] = colour;
            return Err(Error::invalid(
                "markers",
                format!(
                    "no marker of colour {r:02x}{g:02x}{b:02x} (the {which} one) found: it stands out in {seen} of the {} frames; give its colour as the film shows it",
                    frames.len()
                ),
            ));
        }
    }
    Ok(())
}

/// With a colour for each marker, the upper one's blobs must run on the circle the
/// geometry found: where they mostly do not, the colours were given the other way round
/// (the lower marker runs on no circle) and the geometry is noise.
fn check_upper_on_its_circle(
    frames: &[Vec<Blob>],
    named: &[(geometry::Named, geometry::Named)],
) -> Result<()> {
    let with_upper = frames_with(frames, Role::Upper);
    let named = named.iter().filter(|(a, _)| a.is_some()).count();
    if with_upper > 0 && 2 * named < with_upper {
        return Err(Error::invalid(
            "markers",
            format!(
                "the upper marker's colour does not run on a circle about a pivot (named in {named} of the {with_upper} frames it stands out in): are the colours in order, the upper mass's first?"
            ),
        ));
    }
    Ok(())
}
