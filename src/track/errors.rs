//! How far each tracked place may be from the truth: the centroid's noise, and the floor
//! beyond it that the film's own rigid arms measure, wider along a marker's motion.

use super::geometry::{self, Geometry};
use super::{Blob, Up};
use crate::stats::robust_spread;

/// Which way each mass moved in each frame (a unit vector in the picture), where its mean
/// step from the neighbouring frames it was seen in (the one before to the one after) is
/// more than [`MOVED`] px; None where it stood still or was seen in neither neighbour.
pub(super) fn in_motion(
    named: &[(geometry::Named, geometry::Named)],
) -> Vec<[Option<(f64, f64)>; 2]> {
    let at = |i: Option<usize>, k: usize| {
        named
            .get(i?)
            .and_then(|m| if k == 0 { m.0 } else { m.1 })
            .map(|b| (b.x, b.y))
    };
    (0..named.len())
        .map(|i| {
            [0, 1].map(|k| {
                let (before, here, after) =
                    (at(i.checked_sub(1), k), at(Some(i), k)?, at(Some(i + 1), k));
                let (a, b) = (before.unwrap_or(here), after.unwrap_or(here));
                let steps = usize::from(before.is_some()) + usize::from(after.is_some());
                let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                let length = dx.hypot(dy);
                (steps > 0 && length > MOVED * steps as f64).then(|| (dx / length, dy / length))
            })
        })
        .collect()
}

/// A step (px) from one frame to the next beyond a still marker's noise.
const MOVED: f64 = 0.5;

/// How much further a moving marker's place errs along its motion than across it, and how
/// that grows with its streak: along the motion the error is ALONG_MOTION times the floor
/// and STREAK_SHARE of the streak's length in quadrature. Measured on the test films (H.264
/// smears a moving marker along its path, the more the longer its streak): stickers at
/// 1/120 s erred 1.3 times further along than across; LEDs at 1/60 s, whose streaks run to
/// 60 px, by a further 0.45 % of the streak (0.05 px across, 0.25 px along at 50 px; 0.5 %
/// put the 1/60 s films a tenth of a point over 98 % within 1.96 sigma).
/// Across the motion the film's own rigid arms measure it ([`error_floors`]).
const ALONG_MOTION: f64 = 1.3;
const STREAK_SHARE: f64 = 0.0045;

/// The least error (px) a place is stated with: a still sticker's centroid was 0.06 px
/// from the truth on the test film, an LED's 0.06 px a coordinate (the chroma's subsampling and the board's texture
/// under it, a bias that the arms' spread cannot see as it does not change while the
/// marker stands still).
pub(super) const LEAST_ERROR: f64 = 0.05;

/// The error each mass's measured place carries beyond its centroid's noise (px, a
/// coordinate's standard deviation), still and moving: compression (far worse where the
/// picture moves), the board's texture, a sticker's uneven light. A rigid arm measures it
/// on the film itself: the upper marker's distance from the pivot, and the lower's from
/// the upper, vary by the tracking errors along the arm alone, once the streak's own sag
/// is put back (the mean of an arc of angle phi lies r phi^2 / 24 inside it: the truth's
/// too). Their spread (robust: 1.4826 median absolute deviations, the stray frame a
/// distractor caught left out) less the centroids' own noise is the floor; the lower
/// arm's spread holds both markers' errors, so the upper's is taken out. Along the arm is
/// across a marker's motion; along the motion the test films erred more.
pub(super) fn error_floors(
    named: &[(geometry::Named, geometry::Named)],
    moved: &[[Option<(f64, f64)>; 2]],
    g: &Geometry,
) -> [[f64; 2]; 2] {
    let dist = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1);
    let noise = |b: &Blob| (b.sx * b.sx + b.sy * b.sy) / 2.0;
    // A streak as a vector along the motion (px).
    let streak = |b: &Blob, m: Option<(f64, f64)>| {
        m.map_or((0.0, 0.0), |u| (b.streak() * u.0, b.streak() * u.1))
    };
    // Each frame's arm lengths less the arms, where measured, the sag put back.
    let arms: Vec<[Option<f64>; 2]> = named
        .iter()
        .zip(moved)
        .map(|(&(a, b), m)| {
            let upper = a.map(|a| {
                let s = streak(&a, m[0]);
                dist((a.x, a.y), g.pivot) - g.r1 + (s.0 * s.0 + s.1 * s.1) / (24.0 * g.r1)
            });
            let lower = a.zip(b).map(|(a, b)| {
                let (s1, s2) = (streak(&a, m[0]), streak(&b, m[1]));
                let relative = (s2.0 - s1.0).hypot(s2.1 - s1.1);
                dist((b.x, b.y), (a.x, a.y)) - g.r2 + relative * relative / (24.0 * g.r2)
            });
            [upper, lower]
        })
        .collect();
    let spread = |k: usize, motion: bool| -> Option<f64> {
        let mut e: Vec<f64> = arms
            .iter()
            .zip(moved)
            .filter(|(_, m)| m[k].is_some() == motion)
            .filter_map(|(a, _)| a[k])
            .collect();
        if e.len() < 8 {
            return None;
        }
        robust_spread(&mut e)
    };
    [false, true].map(|motion| {
        let mean_noise = |k: usize| {
            let v: Vec<f64> = named
                .iter()
                .zip(moved)
                .filter(|(_, m)| m[k].is_some() == motion)
                .filter_map(|(n, _)| if k == 0 { n.0 } else { n.1 })
                .map(|b| noise(&b))
                .collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let (noise1, noise2) = (mean_noise(0), mean_noise(1));
        let floor1 = spread(0, motion).map_or(0.0, |s| (s * s - noise1).max(0.0).sqrt());
        let floor2 = spread(1, motion).map_or(0.0, |s| {
            (s * s - noise1 - floor1 * floor1 - noise2).max(0.0).sqrt()
        });
        [floor1, floor2]
    })
}

impl Up {
    /// A place's standard errors along the world's axes (px): its centroid's noise along
    /// the picture's (`sx`, `sy`, independent), and `floor` (px) across its motion and
    /// more along the motion's direction (a unit vector in the picture; None: alike every
    /// way) by [`ALONG_MOTION`] and [`STREAK_SHARE`] of the `streak` (px).
    pub(super) fn errors(
        &self,
        sx: f64,
        sy: f64,
        floor: f64,
        motion: Option<(f64, f64)>,
        streak: f64,
    ) -> (f64, f64) {
        // The covariance in the picture's axes, then read along the world's right and up.
        let (mx, my) = motion.unwrap_or((1.0, 0.0));
        let excess = match motion {
            Some(_) => {
                (ALONG_MOTION * ALONG_MOTION - 1.0) * floor * floor
                    + (STREAK_SHARE * streak).powi(2)
            }
            None => 0.0,
        };
        let f2 = floor * floor;
        let cxx = sx * sx + f2 + excess * mx * mx;
        let cyy = sy * sy + f2 + excess * my * my;
        let cxy = excess * mx * my;
        let (ux, uy) = self.direction;
        let along =
            |(vx, vy): (f64, f64)| (vx * vx * cxx + 2.0 * vx * vy * cxy + vy * vy * cyy).sqrt();
        (along((-uy, ux)), along((ux, uy)))
    }
}
