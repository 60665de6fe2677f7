//! A marker at the pivot. Where the pivot is marked (an LED or a sticker on the axle), the
//! masses are measured from it frame by frame: a camera on a tripod that creeps, a stand
//! that flexes, a high-speed camera whose picture wanders by a fraction of a pixel move the
//! pivot and the masses together, and the motion of the pivot's marker takes that out.

use super::detect::{Blob, Role};
use super::geometry::Geometry;
use crate::stats::median;

/// The pivot's marker as the film showed it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PivotMarker {
    /// Its median place (px, x right, y down).
    pub place: (f64, f64),
    /// The share of frames in which it was measured.
    pub seen: f64,
    /// How far it wandered from its median place (px, RMS over the frames it was seen).
    pub wander: f64,
}

/// A frame's shift of the pivot's marker from its median place and its standard errors
/// (dx, dy, sx, sy; px).
pub type Shift = (f64, f64, f64, f64);

/// How far from the pivot the geometry found (px) a marker may sit and be the pivot's: an
/// LED on the axle's end or a sticker on the stand beside it.
const NEAR: f64 = 8.0;

/// How far (px) the pivot's marker may wander from its median place: a fraction of a pixel
/// on a high-speed camera, a pixel or two on a tripod that creeps. Further than this the
/// markers' still places blur and the tracker's geometry would not have been found.
pub(super) const WANDER: f64 = 3.0;

/// The pivot's marker in `frames`, and each frame's shift of it from its median place (px;
/// frames where it was not measured take their neighbours' shift, linearly between them).
/// `coloured`: the pivot's marker has a colour of its own (its blobs are [`Role::Pivot`]);
/// otherwise it has the masses' look and is told by its place at the pivot. None where no
/// marker stays at the pivot in half the frames or more.
pub fn find(
    frames: &[Vec<Blob>],
    g: &Geometry,
    coloured: bool,
) -> Option<(PivotMarker, Vec<Shift>)> {
    let candidate = |b: &&Blob| {
        if coloured {
            b.role == Role::Pivot
        } else {
            b.role == Role::Either
        }
    };
    let d = |a: (f64, f64), b: &Blob| (a.0 - b.x).hypot(a.1 - b.y);
    let nearest = |f: &Vec<Blob>, at: (f64, f64), within: f64| {
        let mut near = f.iter().filter(candidate).filter(|b| d(at, b) < within);
        let first = near.next()?;
        // Two blobs at the pivot (a mass passing over it): neither is taken.
        near.next().is_none().then_some(*first)
    };
    let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = frames
        .iter()
        .filter_map(|f| nearest(f, g.pivot, NEAR))
        .map(|b| (b.x, b.y))
        .unzip();
    if 2 * xs.len() < frames.len() {
        return None;
    }
    let place = (median(&mut xs)?, median(&mut ys)?);
    let near: Vec<Option<Blob>> = frames.iter().map(|f| nearest(f, place, WANDER)).collect();
    let mut fluxes: Vec<f64> = near.iter().flatten().map(|b| b.flux).collect();
    let flux = median(&mut fluxes)?;
    // A mass crossing the marker adds its light: such a frame's centroid is not the pivot's.
    let measured: Vec<Option<Blob>> = near
        .into_iter()
        .map(|b| b.filter(|b| (0.7 * flux..1.4 * flux).contains(&b.flux)))
        .collect();
    let seen = measured.iter().flatten().count();
    if 2 * seen < frames.len() {
        return None;
    }
    let wander = (measured
        .iter()
        .flatten()
        .map(|b| d(place, b).powi(2))
        .sum::<f64>()
        / seen as f64)
        .sqrt();
    let shifts = fill_gaps(&measured, place);
    Some((
        PivotMarker {
            place,
            seen: seen as f64 / frames.len() as f64,
            wander,
        },
        shifts,
    ))
}

/// Each frame's shift from `place` and its standard errors (dx, dy, sx, sy, px): measured
/// where the marker was, linear between the nearest measured frames elsewhere (held at the
/// film's ends), with the larger of the two neighbours' errors.
fn fill_gaps(measured: &[Option<Blob>], place: (f64, f64)) -> Vec<Shift> {
    let at: Vec<(usize, Shift)> = measured
        .iter()
        .enumerate()
        .filter_map(|(k, b)| b.map(|b| (k, (b.x - place.0, b.y - place.1, b.sx, b.sy))))
        .collect();
    let mut next = 0;
    (0..measured.len())
        .map(|k| {
            while next < at.len() && at[next].0 < k {
                next += 1;
            }
            match (next.checked_sub(1).map(|p| at[p]), at.get(next)) {
                (_, Some(&(j, s))) if j == k => s,
                (Some((i, a)), Some(&(j, b))) => {
                    let u = (k - i) as f64 / (j - i) as f64;
                    (
                        a.0 + u * (b.0 - a.0),
                        a.1 + u * (b.1 - a.1),
                        a.2.max(b.2),
                        a.3.max(b.3),
                    )
                }
                (Some((_, a)), None) => a,
                (None, Some(&(_, b))) => b,
                (None, None) => (0.0, 0.0, 0.0, 0.0),
            }
        })
        .collect()
}

/// `frames` seen from the pivot's marker: every blob moved back by its frame's shift, its
/// errors widened by the marker's own.
pub fn steadied(frames: &[Vec<Blob>], shifts: &[Shift]) -> Vec<Vec<Blob>> {
    frames
        .iter()
        .zip(shifts)
        .map(|(f, &(dx, dy, sx, sy))| {
            f.iter()
                .map(|b| Blob {
                    x: b.x - dx,
                    y: b.y - dy,
                    sx: b.sx.hypot(sx),
                    sy: b.sy.hypot(sy),
                    core: (b.core.0 - dx, b.core.1 - dy, b.core.2),
                    ..*b
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A marker at the pivot wandering by half a pixel, missing in every fifth frame: its
    /// shift is found where it was seen and drawn between neighbours where not (a linear
    /// wander: exactly), and taking it out leaves a mass that moved with it where it was.
    #[test]
    fn the_pivots_wander_is_taken_out() {
        let g = Geometry {
            pivot: (100.0, 50.0),
            r1: 80.0,
            r2: 60.0,
        };
        let wander = |k: usize| (0.5 * k as f64 / 40.0, -0.25 * k as f64 / 40.0);
        let frames: Vec<Vec<Blob>> = (0..41)
            .map(|k| {
                let (dx, dy) = wander(k);
                let mut f = vec![Blob::round(130.0 + dx, 120.0 + dy, Role::Either)];
                if k % 5 != 2 {
                    f.push(Blob::round(101.0 + dx, 49.0 + dy, Role::Either));
                }
                f
            })
            .collect();
        let (marker, shifts) = find(&frames, &g, false).expect("a marker at the pivot");
        assert!((marker.seen - 33.0 / 41.0).abs() < 1e-12, "{marker:?}");
        // The median place is the middle frame's (frame 20 is seen).
        let middle = wander(20);
        assert!(
            (marker.place.0 - 101.0 - middle.0).abs() < 1e-12,
            "{marker:?}"
        );
        let steady = steadied(&frames, &shifts);
        for f in &steady {
            // The mass moved with the picture: seen from the pivot's marker it stood still
            // (to rounding; the interpolated frames too, the wander being linear).
            assert!((f[0].x - 130.0 - middle.0).abs() < 1e-9, "{:?}", f[0]);
            assert!((f[0].y - 120.0 - middle.1).abs() < 1e-9, "{:?}", f[0]);
        }
        // Without a marker of its own colour, none is found; with the masses' look only.
        assert!(find(&frames, &g, true).is_none());
    }
}
