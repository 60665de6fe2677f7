//! The pendulum's geometry read from the markers themselves: the pivot is the centre of the
//! circle the upper marker runs on (found among every frame's blobs by RANSAC, then fitted,
//! and once the blobs are named, fitted again to the upper marker's places alone),
//! the lower arm the one distance the lower marker keeps from the upper; then each frame's
//! blobs are named by that geometry (and, where it cannot tell, by continuity), never by
//! where a blob happens to be.

use rand::{Rng, SeedableRng};

use super::detect::Blob;
use crate::stats::median;

/// The pivot (px), the upper marker's circle's radius and the lower arm (px).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    pub pivot: (f64, f64),
    pub r1: f64,
    pub r2: f64,
}

/// A circle: its centre and radius.
type Circle = ((f64, f64), f64);

/// The circle through three points, if they are not on a line.
fn circle(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> Option<Circle> {
    let d = 2.0 * (a.0 * (b.1 - c.1) + b.0 * (c.1 - a.1) + c.0 * (a.1 - b.1));
    if d.abs() < 1e-9 {
        return None;
    }
    let sq = |p: (f64, f64)| p.0 * p.0 + p.1 * p.1;
    let ux = (sq(a) * (b.1 - c.1) + sq(b) * (c.1 - a.1) + sq(c) * (a.1 - b.1)) / d;
    let uy = (sq(a) * (c.0 - b.0) + sq(b) * (a.0 - c.0) + sq(c) * (b.0 - a.0)) / d;
    let r = ((a.0 - ux).powi(2) + (a.1 - uy).powi(2)).sqrt();
    Some(((ux, uy), r))
}

fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt()
}

/// The circle (centre, radius) fitted to `points` by least squares on the distances
/// (Gauss-Newton from `start`).
fn fit_circle(points: &[(f64, f64)], start: Circle) -> Circle {
    let ((mut cx, mut cy), mut r) = start;
    for _ in 0..20 {
        // Normal equations of the residuals d_i - r in (cx, cy, r).
        let mut ata = nalgebra::Matrix3::<f64>::zeros();
        let mut atb = nalgebra::Vector3::<f64>::zeros();
        for &p in points {
            let d = dist(p, (cx, cy)).max(1e-9);
            let j = nalgebra::Vector3::new(-(p.0 - cx) / d, -(p.1 - cy) / d, -1.0);
            ata += j * j.transpose();
            atb -= j * (d - r);
        }
        let Some(step) = ata.lu().solve(&atb) else {
            break;
        };
        cx += step[0];
        cy += step[1];
        r += step[2];
        if step.norm() < 1e-9 {
            break;
        }
    }
    ((cx, cy), r)
}

/// Finds the geometry in `frames` (each frame's candidate blobs, distractors that stood
/// still already taken out): the circle with most frames' support within `tol` px, refined;
/// then the lower arm as the distance from the circle's marker that most frames share.
pub fn find(frames: &[Vec<Blob>], tol: f64, seed: u64) -> Option<Geometry> {
    let points: Vec<(usize, (f64, f64))> = frames
        .iter()
        .enumerate()
        .flat_map(|(f, b)| {
            b.iter()
                .filter(|b| b.may_be_upper())
                .map(move |b| (f, (b.x, b.y)))
        })
        .collect();
    if points.len() < 3 {
        return None;
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut best: Option<(usize, Circle)> = None;
    // Points of one frame's support counted once: a blob near the circle per frame.
    let support = |c: (f64, f64), r: f64, tol: f64| {
        let mut last = usize::MAX;
        let mut n = 0;
        for &(f, p) in &points {
            if f != last && (dist(p, c) - r).abs() < tol {
                n += 1;
                last = f;
            }
        }
        n
    };
    for _ in 0..600 {
        let pick = |rng: &mut rand_pcg::Pcg64| points[rng.random_range(0..points.len())];
        let (a, b, c) = (pick(&mut rng), pick(&mut rng), pick(&mut rng));
        if a.0 == b.0 || b.0 == c.0 || a.0 == c.0 {
            continue;
        }
        let Some((centre, r)) = circle(a.1, b.1, c.1) else {
            continue;
        };
        // A pendulum's upper arm is longer than a marker's size and shorter than a frame.
        if !(r > 8.0 && r < 1e5) {
            continue;
        }
        let n = support(centre, r, tol);
        if best.is_none_or(|(m, _)| n > m) {
            best = Some((n, (centre, r)));
        }
    }
    let (_, (mut centre, mut r)) = best?;
    // Refined on its support, twice (the second on the first's sharper circle).
    for _ in 0..2 {
        let inliers: Vec<(f64, f64)> = points
            .iter()
            .filter(|(_, p)| (dist(*p, centre) - r).abs() < tol)
            .map(|(_, p)| *p)
            .collect();
        if inliers.len() < 3 {
            return None;
        }
        (centre, r) = fit_circle(&inliers, (centre, r));
    }
    // The lower arm: distances from each frame's one marker on the circle to its others,
    // the mode of their histogram (0.5 px bins), then the median near it.
    let mut distances = Vec::new();
    for blobs in frames {
        let on: Vec<&Blob> = blobs
            .iter()
            .filter(|b| b.may_be_upper() && (dist((b.x, b.y), centre) - r).abs() < tol)
            .collect();
        if let [m1] = on[..] {
            for b in blobs {
                if b != m1 && b.may_be_lower() {
                    distances.push(dist((b.x, b.y), (m1.x, m1.y)));
                }
            }
        }
    }
    let top = distances.iter().copied().fold(0.0, f64::max);
    if distances.is_empty() || top < 1.0 {
        return None;
    }
    let bins = (top / 0.5) as usize + 2;
    let mut histogram = vec![0u32; bins];
    for &d in &distances {
        let k = (d / 0.5) as usize;
        // Each distance counts in its bin and the next, so the peak is not split by a bin edge.
        histogram[k] += 1;
        histogram[k + 1] += 1;
    }
    let peak = histogram
        .iter()
        .enumerate()
        .max_by_key(|(_, n)| **n)
        .map(|(k, _)| k as f64 * 0.5)?;
    let mut near: Vec<f64> = distances
        .into_iter()
        .filter(|d| (d - peak).abs() < tol)
        .collect();
    let r2 = median(&mut near)?;
    Some(Geometry {
        pivot: centre,
        r1: r,
        r2,
    })
}

/// `g` refined on the markers as `name` named them: the pivot and the upper arm from the
/// upper marker's own places (the first circle's support, every blob within a few pixels of
/// it, also holds the lower marker wherever it crosses that circle, which moved the centre by
/// a tenth of a pixel on the test films: more than the markers' own errors, and every
/// position is measured from it), the lower arm the median distance between the two.
pub fn refined(named: &[(Named, Named)], g: Geometry) -> Geometry {
    let upper: Vec<(f64, f64)> = named
        .iter()
        .filter_map(|(a, _)| a.map(|b| (b.x, b.y)))
        .collect();
    let mut arms: Vec<f64> = named
        .iter()
        .filter_map(|&(a, b)| Some(dist((a?.x, a?.y), (b?.x, b?.y))))
        .collect();
    if upper.len() < 3 || arms.is_empty() {
        return g;
    }
    let (pivot, r1) = fit_circle(&upper, (g.pivot, g.r1));
    // A streak's centroid lies inside its arc by r phi^2 / 24 (phi = streak / r): put back,
    // the circle is the marker's own, not one a little inside it where it moves fast (a
    // scale from the arm's length was 5e-4 off at 1/60 s without it).
    let outward: Vec<(f64, f64)> = named
        .iter()
        .filter_map(|(a, _)| *a)
        .map(|b| {
            let d = dist((b.x, b.y), pivot).max(1e-9);
            let sag = b.streak().powi(2) / (24.0 * r1);
            (
                b.x + (b.x - pivot.0) / d * sag,
                b.y + (b.y - pivot.1) / d * sag,
            )
        })
        .collect();
    let (pivot, r1) = fit_circle(&outward, (pivot, r1));
    let r2 = median(&mut arms).unwrap_or(g.r2);
    // A circle that wandered off (too few places on too short an arc) keeps the first.
    if !(dist(pivot, g.pivot) < 3.0 && (r1 - g.r1).abs() < 3.0) {
        return g;
    }
    Geometry { pivot, r1, r2 }
}

/// The blobs that stand still: a place (2 px cells) with a blob in more than a fifth of the
/// frames is a lamp, a reflection of one, a fixed mark, never a swinging marker.
pub fn still(frames: &[Vec<Blob>]) -> Vec<(f64, f64)> {
    let mut cells: std::collections::HashMap<(i64, i64), (u32, f64, f64)> =
        std::collections::HashMap::new();
    for blobs in frames {
        let mut seen = std::collections::HashSet::new();
        for b in blobs {
            let cell = ((b.x / 2.0).floor() as i64, (b.y / 2.0).floor() as i64);
            if seen.insert(cell) {
                let e = cells.entry(cell).or_insert((0, 0.0, 0.0));
                e.0 += 1;
                e.1 += b.x;
                e.2 += b.y;
            }
        }
    }
    let many = (frames.len() as u32 / 5).max(3);
    // A blob at a cell's edge falls in either cell: the two are one place.
    let mut out: Vec<(f64, f64, u32)> = Vec::new();
    for (&(cx, cy), &(n, _, _)) in &cells {
        let around: u32 = (-1..=1)
            .flat_map(|dy| (-1..=1).map(move |dx| (cx + dx, cy + dy)))
            .filter_map(|c| cells.get(&c).map(|e| e.0))
            .sum();
        if n > 0 && around > many {
            let (_, sx, sy) = cells[&(cx, cy)];
            out.push((sx / n as f64, sy / n as f64, n));
        }
    }
    // One place per still thing: cells within 5 px of a busier one are part of it (its
    // neighbours counted it, and a blob merged with it lands beside it).
    let all = out.clone();
    out.retain(|a| {
        !all.iter().any(|b| {
            (b.2, b.0.to_bits()) > (a.2, a.0.to_bits()) && (a.0 - b.0).hypot(a.1 - b.1) < 5.0
        })
    });
    out.into_iter().map(|(x, y, _)| (x, y)).collect()
}

/// A mass's place in one frame: where it was measured (px) and its blob, or not seen.
pub type Named = Option<Blob>;

/// Names each frame's blobs: the upper marker on the circle, the lower one an arm's length
/// from it; of several pairs that fit, the one nearest to where each marker was going (its
/// last two places); with the upper marker hidden, the lower one only where it continues
/// its own path. `tol` (px) is how far a blob may lie off the geometry.
pub fn name(frames: &[Vec<Blob>], g: &Geometry, tol: f64) -> Vec<(Named, Named)> {
    // Forward and backward in time: a marker coming out from behind the table has a path
    // only after it. Where the passes disagree, the mass is not named.
    let forward = name_along(frames.iter(), g, tol);
    let mut backward = name_along(frames.iter().rev(), g, tol);
    backward.reverse();
    let merge = |a: Named, b: Named| match (a, b) {
        (Some(a), Some(b)) if a == b => Some(a),
        (Some(a), None) | (None, Some(a)) => Some(a),
        _ => None,
    };
    forward
        .into_iter()
        .zip(backward)
        .map(|(f, b)| {
            // A blob one pass names the upper marker and the other the lower is neither.
            let conflict = |x: &Blob| {
                (f.0 == Some(*x) && b.1 == Some(*x)) || (f.1 == Some(*x) && b.0 == Some(*x))
            };
            (
                merge(f.0, b.0).filter(|x| !conflict(x)),
                merge(f.1, b.1).filter(|x| !conflict(x)),
            )
        })
        .collect()
}

/// [`name`] in one direction of time.
fn name_along<'a>(
    frames: impl Iterator<Item = &'a Vec<Blob>>,
    g: &Geometry,
    tol: f64,
) -> Vec<(Named, Named)> {
    let mut out: Vec<(Named, Named)> = Vec::new();
    let reach = g.r1 + g.r2 + tol;
    for (f, blobs) in frames.enumerate() {
        // Where each marker was going: its last place within three frames, moved on by its
        // last step where the place before that is known too; and how far it may land from
        // there: half the lower arm, and half the way it was going (the extrapolation misses
        // by the acceleration's a dt^2, which grows with the speed around the pivot).
        let predict = |which: usize| -> Option<((f64, f64), f64)> {
            let at = |k: usize| {
                out.get(k).and_then(|p: &(Named, Named)| {
                    match which {
                        0 => p.0,
                        _ => p.1,
                    }
                    .map(|b| (b.x, b.y))
                })
            };
            let (k, a) = (1..=3)
                .filter_map(|back| f.checked_sub(back).map(|k| (k, back)))
                .find_map(|(k, back)| at(k).map(|a| ((k, back), a)))?;
            let (k, back) = k;
            match k.checked_sub(1).and_then(at) {
                Some(b) => {
                    let step = (a.0 - b.0, a.1 - b.1);
                    let ahead = back as f64 * step.0.hypot(step.1);
                    Some((
                        (a.0 + back as f64 * step.0, a.1 + back as f64 * step.1),
                        0.5 * (g.r2 + ahead),
                    ))
                }
                None => Some((a, 0.5 * g.r2)),
            }
        };
        let ((p1, gate1), (p2, gate2)) = {
            let split = |p: Option<((f64, f64), f64)>| (p.map(|p| p.0), p.map_or(0.0, |p| p.1));
            (split(predict(0)), split(predict(1)))
        };
        let off = |p: Option<(f64, f64)>, b: &Blob| p.map_or(0.0, |p| dist(p, (b.x, b.y)));
        let on_circle = |b: &Blob| (dist((b.x, b.y), g.pivot) - g.r1).abs();
        let mut pair: Option<(f64, Blob, Blob)> = None;
        for a in blobs
            .iter()
            .filter(|b| b.may_be_upper() && on_circle(b) < tol)
        {
            for b in blobs.iter().filter(|b| b.may_be_lower()) {
                let arm = (dist((a.x, a.y), (b.x, b.y)) - g.r2).abs();
                if b == a || arm >= tol {
                    continue;
                }
                // Geometry first; continuity (in arm lengths) tells apart pairs that fit alike.
                let cost = (on_circle(a) + arm) / tol + (off(p1, a) + off(p2, b)) / g.r2;
                if pair.is_none_or(|(c, _, _)| cost < c) {
                    pair = Some((cost, *a, *b));
                }
            }
        }
        // A lone blob where the lower marker's path goes on, and nearer to it than to the
        // upper's, is the lower marker even when it passes over the upper one's circle.
        let lower_path = |b: &Blob| {
            p2.is_some_and(|p| dist(p, (b.x, b.y)) < gate2)
                && p1.is_none_or(|q| dist(p2.unwrap(), (b.x, b.y)) < dist(q, (b.x, b.y)))
        };
        let named = match pair {
            Some((_, a, b)) => (Some(a), Some(b)),
            None => {
                // One marker only: the upper one on its circle, on its path; or, the upper
                // one hidden, the lower one where its own path goes on, within reach.
                let m1 = blobs
                    .iter()
                    .filter(|b| b.may_be_upper() && on_circle(b) < tol && !lower_path(b))
                    .filter(|b| p1.is_none_or(|p| dist(p, (b.x, b.y)) < gate1))
                    .min_by(|a, b| off(p1, a).total_cmp(&off(p1, b)))
                    .copied();
                // The one blob in the frame, clear of the upper marker's circle (a partly
                // hidden upper marker lies near it), is the lower marker when the upper one
                // could be out of sight an arm's length from it: it lies in the ring the
                // lower marker sweeps (|m2 - pivot| within r1 -+ r2). Its path may be too
                // fast to follow from frame to frame where the upper arm is hidden.
                let in_ring = |b: &Blob| {
                    let r = dist((b.x, b.y), g.pivot);
                    b.may_be_lower() && r < reach && r > (g.r1 - g.r2).abs() - tol
                };
                let m2 = match (m1, blobs.as_slice()) {
                    (Some(_), _) => None,
                    (None, [lone]) if in_ring(lone) && on_circle(lone) > 2.0 * tol => Some(*lone),
                    (None, _) => blobs
                        .iter()
                        .filter(|b| in_ring(b) && lower_path(b))
                        .min_by(|a, b| off(p2, a).total_cmp(&off(p2, b)))
                        .copied(),
                };
                (m1, m2)
            }
        };
        out.push(named);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_circle_through_three_points_and_its_fit() {
        let ((cx, cy), r) = circle((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)).unwrap();
        assert!(cx.abs() < 1e-12 && cy.abs() < 1e-12 && (r - 1.0).abs() < 1e-12);
        let points: Vec<(f64, f64)> = (0..50)
            .map(|k| {
                let a = k as f64 * 0.1;
                (300.0 + 200.0 * a.cos(), 100.0 + 200.0 * a.sin())
            })
            .collect();
        let ((cx, cy), r) = fit_circle(&points, ((290.0, 110.0), 190.0));
        assert!((cx - 300.0).abs() < 1e-6 && (cy - 100.0).abs() < 1e-6 && (r - 200.0).abs() < 1e-6);
    }

    /// The pendulum's two markers through 400 frames, the lower one crossing the upper's
    /// circle in many of them: the first circle takes every blob within its tolerance, the
    /// lower marker's crossings too, and its centre moves; refined on the named upper marker
    /// alone it is the circle's own (no noise here: to rounding; the first is 0.075 px off).
    #[test]
    fn the_pivot_is_refined_on_the_upper_marker_alone() {
        let (pivot, r1, r2) = ((320.0, 160.0), 110.0, 71.0);
        let blob = |x: f64, y: f64| Blob::round(x, y, super::super::detect::Role::Either);
        let frames: Vec<Vec<Blob>> = (0..400)
            .map(|k| {
                let t = k as f64 / 30.0;
                let (a, b) = (1.4 * (2.1 * t).sin(), 3.0 * (3.3 * t).sin() + 0.5 * t);
                let m1 = (pivot.0 + r1 * a.sin(), pivot.1 + r1 * a.cos());
                vec![
                    blob(m1.0, m1.1),
                    blob(m1.0 + r2 * b.sin(), m1.1 + r2 * b.cos()),
                ]
            })
            .collect();
        let first = find(&frames, 3.0, 1).unwrap();
        let named = name(&frames, &first, 3.0);
        let g = refined(&named, first);
        let off = |g: &Geometry| dist(g.pivot, pivot);
        eprintln!(
            "first {:.4} px off, refined {:.2e} px",
            off(&first),
            off(&g)
        );
        assert!(off(&first) > 1e-3, "{first:?}");
        assert!(off(&g) < 1e-6 && (g.r1 - r1).abs() < 1e-6, "{g:?}");
        assert!((g.r2 - r2).abs() < 1e-6, "{g:?}");
    }
}
