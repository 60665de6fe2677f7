//! From a film of the pendulum to the positions of both masses in every frame: markers found
//! in each frame ([`detect`]), the pivot and arms read from the markers themselves and each
//! blob named by that geometry ([`geometry`]), in metres from the pivot, y up. A mass that
//! is not seen in a frame is reported as not seen, never placed. [`synth`] renders test
//! films with a known truth.

pub mod detect;
pub mod geometry;
pub mod synth;

pub use detect::{Blob, Markers};
pub use geometry::Geometry;

use crate::error::{Error, Result};

/// How pixels become metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    /// The upper arm's length (m): its circle's radius in pixels is that many metres.
    UpperArm(f64),
    PixelsPerMetre(f64),
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
}

/// One frame's row: its time from the film's first (s) and each mass, if seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackRow {
    pub t: f64,
    pub m1: Option<Mark>,
    pub m2: Option<Mark>,
}

/// What the tracker found: every frame's row, the geometry (px), the scale (px per metre)
/// and the still blobs it set aside.
#[derive(Clone, Debug)]
pub struct Tracked {
    pub rows: Vec<TrackRow>,
    pub geometry: Geometry,
    pub pixels_per_metre: f64,
    pub still: Vec<(f64, f64)>,
}

/// How far (px) a blob may lie off the geometry and still be named by it: two pixels, a
/// blurred upper marker's sag inside its circle (its mean over an arc lies r theta^2 / 24
/// inside: 1 px at r = 300 px and 0.35 rad swept in one exposure) and its noise.
const OFF_GEOMETRY: f64 = 3.0;

/// Names every frame's blobs and turns them into rows (times from `times`).
pub fn track(frames: &[Vec<Blob>], times: &[f64], scale: Scale) -> Result<Tracked> {
    let still = geometry::still(frames);
    let is_still = |b: &Blob| still.iter().any(|s| (s.0 - b.x).hypot(s.1 - b.y) < 3.0);
    let moving: Vec<Vec<Blob>> = frames
        .iter()
        .map(|f| f.iter().filter(|b| !is_still(b)).copied().collect())
        .collect();
    let not_found = || {
        Error::invalid(
            "video",
            "no pendulum found: no circle of blobs that one marker keeps to (are the markers bright on a dark background, or [[markers]] of their colour?)",
        )
    };
    let g = geometry::find(&moving, OFF_GEOMETRY, 1).ok_or_else(not_found)?;
    // Markers are as bright as each other, give or take: a blob with much less light than
    // the named ones is a reflection or a marker partly hidden (its centroid off), and one
    // with much more is two blobs merged or a lamp.
    let named = geometry::name(&moving, &g, OFF_GEOMETRY);
    let mut fluxes: Vec<f64> = named
        .iter()
        .flat_map(|(a, b)| [a, b])
        .filter_map(|m| m.map(|b| b.flux))
        .collect();
    if fluxes.is_empty() {
        return Err(not_found());
    }
    let median = |v: &mut Vec<f64>| {
        let mid = v.len() / 2;
        *v.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let typical = median(&mut fluxes);
    let mut cores: Vec<f64> = named
        .iter()
        .flat_map(|(a, b)| [a, b])
        .filter_map(|m| m.map(|b| b.core.2))
        .collect();
    let typical_core = median(&mut cores);
    let marker_like = |flux: f64, typical: f64| (0.75 * typical..1.3 * typical).contains(&flux);
    let plausible: Vec<Vec<Blob>> = moving
        .iter()
        .map(|f| {
            f.iter()
                .filter_map(|b| {
                    if marker_like(b.flux, typical) {
                        Some(*b)
                    } else if b.flux > typical && marker_like(b.core.2, typical_core) {
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
    let named = geometry::name(&plausible, &g, OFF_GEOMETRY);
    let ppm = match scale {
        Scale::UpperArm(l1) => g.r1 / l1,
        Scale::PixelsPerMetre(p) => p,
    };
    let mark = |b: Blob| Mark {
        x: (b.x - g.pivot.0) / ppm,
        y: -(b.y - g.pivot.1) / ppm,
        sx: b.sx / ppm,
        sy: b.sy / ppm,
        streak: b.streak() / ppm,
        px: (b.x, b.y),
    };
    let rows = named
        .iter()
        .zip(times)
        .map(|(&(a, b), &t)| TrackRow {
            t,
            m1: a.map(mark),
            m2: b.map(mark),
        })
        .collect();
    Ok(Tracked {
        rows,
        geometry: g,
        pixels_per_metre: ppm,
        still,
    })
}

/// A row of a CSV that `track` wrote: its time (s) and the upper and lower mass's position
/// (m), None where it was not measured.
pub type CsvRow = (f64, Option<(f64, f64)>, Option<(f64, f64)>);

/// Reads back the positions of a CSV that `track` wrote (its header and `seen` columns).
pub fn read_rows(path: &std::path::Path) -> Result<Vec<CsvRow>> {
    let text = crate::input::read_text("file", path, crate::input::CSV_CAP)?;
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let bad = |what: &str| Error::format(path, format!("not a CSV that track wrote: {what}"));
    if lines.next() != Some("t,x1,y1,x2,y2,seen1,seen2,sx1,sy1,sx2,sy2,streak1,streak2") {
        return Err(bad("its header"));
    }
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            if c.len() != 13 {
                return Err(bad("a row of other than 13 fields"));
            }
            let at = |k: usize, seen: &str| -> Result<Option<(f64, f64)>> {
                match seen {
                    "measured" => {
                        let v = |s: &str| s.parse::<f64>().map_err(|_| bad("a position"));
                        Ok(Some((v(c[k])?, v(c[k + 1])?)))
                    }
                    // Not seen: no position, not even a guessed one.
                    "hidden" if c[k].is_empty() && c[k + 1].is_empty() => Ok(None),
                    _ => Err(bad("a seen cell, or a hidden mass's position")),
                }
            };
            let t = c[0].parse::<f64>().map_err(|_| bad("a time"))?;
            Ok((t, at(1, c[5])?, at(3, c[6])?))
        })
        .collect()
}
