//! Where gravity's down lies in the picture. A camera rolled by a fraction of a degree turns
//! every angle the model reads by as much, and gravity's torques with it: P sin(theta1 - r)
//! where the model has P sin theta1. The arms' rigid lengths cannot show a roll; the motion
//! can. With P sin(theta1 - r) = P cos r sin theta1 - P sin r cos theta1, the upper arm's
//! equation of motion gains a term -tan r cos theta1 over P cos r, linear
//! like the moments themselves (`super::identify`), so one least squares over the rows gives
//! it. On IBM's films it came out 0.3-0.4 degrees in all three runs, and a film made by the
//! model rolled by 0.5 degrees lost a fifth of its forecasts' follow time to it.

use nalgebra::{SMatrix, SVector};

use super::TrackedRow;

/// The picture's roll against gravity (rad, counter-clockwise positive in the frames' y-up
/// frame: gravity's down lies at this angle from the frames' -y), its standard error, and
/// the roll taken out of the frames (shrunk toward zero by its error,
/// [`super::joint::shrunk`]).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Roll {
    pub roll: f64,
    pub error: f64,
    pub applied: f64,
    /// Whether it is a calibration's (`forecast --params`) rather than the rows' own.
    pub from_calibration: bool,
}

impl Roll {
    /// A calibration's roll and its error, applied shrunk as the rows' own would be.
    pub fn calibrated(roll: f64, error: f64) -> Roll {
        Roll {
            roll,
            error,
            applied: super::joint::shrunk(roll, error),
            from_calibration: true,
        }
    }
}

/// The rows a local polynomial spans on either side: 25 ms of rows, enough for the angular
/// accelerations of the motion's fastest swings (a degree-4 polynomial over 21 rows at 400
/// frames a second recovered a 0.5 degree roll to 0.02 degree on a film made by the model).
const HALF_SPAN: f64 = 0.025;

/// Rows closer together than this (s) are needed: coarser films' polynomials bend the
/// accelerations more than a roll does.
const COARSEST_ROW: f64 = 0.005;

/// The local polynomial's degree.
const DEGREE: usize = 4;

/// Unknowns of the two equations: a, b, c (s^2), tan r (the upper arm's -cos theta1 term),
/// q and the lower arm's cos theta2 term over P, k1 and k2 (s).
const UNKNOWNS: usize = 8;

/// The roll the motion of `angles` (theta1, theta2, unwrapped, at the times `t`) shows, with
/// its error; None where the rows are too coarse, too few, or do not determine it.
pub fn roll(t: &[f64], angles: &[(f64, f64)]) -> Option<Roll> {
    let n = t.len().min(angles.len());
    if n < 2 {
        return None;
    }
    let step = (t[n - 1] - t[0]) / (n - 1) as f64;
    if !(step > 0.0 && step <= COARSEST_ROW) {
        return None;
    }
    let half = ((HALF_SPAN / step).round() as usize).max(DEGREE);
    let weights = derivative_weights(half)?;
    let mut normal = SMatrix::<f64, UNKNOWNS, UNKNOWNS>::zeros();
    let mut right = SVector::<f64, UNKNOWNS>::zeros();
    let mut rows = Vec::new();
    for k in half..n.saturating_sub(half) {
        // A span with a gap (a row missing, a time off the grid) would bend the polynomial.
        let span = t[k + half] - t[k - half];
        if (span - 2.0 * half as f64 * step).abs() > 0.01 * step {
            continue;
        }
        let [(th1, w1, a1), (th2, w2, a2)] = [0, 1].map(|arm| {
            let pick = |j: usize| match arm {
                0 => angles[k - half + j].0,
                _ => angles[k - half + j].1,
            };
            let d = |w: &[f64]| w.iter().enumerate().map(|(j, c)| c * pick(j)).sum::<f64>();
            (
                d(&weights[0]),
                d(&weights[1]) / step,
                d(&weights[2]) / (step * step),
            )
        });
        let (s, c) = (th1 - th2).sin_cos();
        let relative = w2 - w1;
        let upper = SVector::<f64, UNKNOWNS>::from([
            a1,
            0.0,
            c * a2 + s * w2 * w2,
            -th1.cos(),
            0.0,
            0.0,
            w1,
            -relative,
        ]);
        let lower = SVector::<f64, UNKNOWNS>::from([
            0.0,
            a2,
            c * a1 - s * w1 * w1,
            0.0,
            th2.sin(),
            -th2.cos(),
            0.0,
            relative,
        ]);
        if !(upper.iter().chain(lower.iter()).all(|v| v.is_finite())) {
            continue;
        }
        for (x, r) in [(upper, -th1.sin()), (lower, 0.0)] {
            normal += x * x.transpose();
            right += x * r;
        }
        rows.push((upper, -th1.sin(), lower));
    }
    if rows.len() < 4 * UNKNOWNS {
        return None;
    }
    let inverse = normal.try_inverse()?;
    let solution = inverse * right;
    // Neighbouring rows' polynomials share their rows, so their residuals are correlated:
    // the covariance is widened by the upper equation's long-run variance.
    let upper: Vec<f64> = rows.iter().map(|(x, r, _)| r - x.dot(&solution)).collect();
    let lower: Vec<f64> = rows.iter().map(|(_, _, x)| -x.dot(&solution)).collect();
    let square = upper.iter().chain(&lower).map(|e| e * e).sum::<f64>();
    let s2 = square / (2 * rows.len() - UNKNOWNS) as f64;
    let (_, _, inflation) = super::correlation::long_run(&[upper]);
    let tan = solution[3];
    let error = (s2 * inflation * inverse[(3, 3)]).sqrt() / (1.0 + tan * tan);
    let roll = tan.atan();
    Some(Roll {
        roll,
        error,
        applied: super::joint::shrunk(roll, error),
        from_calibration: false,
    })
}

/// The weights that give a degree-[`DEGREE`] polynomial's value, first and second
/// derivatives (per row and per row squared) at the middle of 2 `half` + 1 equally spaced
/// rows: rows 0, 1, 2 of (V^T V)^-1 V^T, times 1, 1, 2.
fn derivative_weights(half: usize) -> Option<[Vec<f64>; 3]> {
    let m = 2 * half + 1;
    let v = nalgebra::DMatrix::from_fn(m, DEGREE + 1, |i, p| {
        (i as f64 - half as f64).powi(p as i32)
    });
    let pseudo = (v.transpose() * &v).try_inverse()? * v.transpose();
    Some([0, 1, 2].map(|p| {
        let factor = if p == 2 { 2.0 } else { 1.0 };
        (0..m).map(|j| factor * pseudo[(p, j)]).collect()
    }))
}

/// `frames` turned about `pivot` by -`angle`: gravity's down where the frames' -y is.
pub fn levelled(frames: &[TrackedRow], pivot: (f64, f64), angle: f64) -> Vec<TrackedRow> {
    let (s, c) = angle.sin_cos();
    // theta = atan2(x, -y) from the pivot; theta - angle is wanted.
    let turn = |x: f64, y: f64| {
        let (u, v) = (x - pivot.0, -(y - pivot.1));
        (pivot.0 + u * c - v * s, pivot.1 - (v * c + u * s))
    };
    frames
        .iter()
        .map(|f| {
            let (x1, y1) = turn(f.x1, f.y1);
            let (x2, y2) = turn(f.x2, f.y2);
            TrackedRow {
                t: f.t,
                x1,
                y1,
                x2,
                y2,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Params, State};

    /// A chaotic swing of a compound pendulum at 400 rows a second, its picture rolled by
    /// 0.5 degree: the roll is found within three of its standard errors, and that error is
    /// under a tenth of it; the same swing unrolled shows a roll within three errors of none.
    #[test]
    fn a_rolled_picture_shows_its_roll() {
        let p = Params {
            m1: 0.8,
            m2: 0.12,
            l1: 0.146,
            l2: 0.112,
            rod1: 0.15,
            rod2: 0.03,
            ..Params::default()
        };
        let t: Vec<f64> = (0..4000).map(|k| k as f64 / 400.0).collect();
        let track = crate::fit::window::track(&p, State::at_rest(2.0, 2.5), &t);
        let frames = |r: f64| -> Vec<TrackedRow> {
            let rows: Vec<TrackedRow> = t
                .iter()
                .zip(&track)
                .map(|(&t, q)| TrackedRow {
                    t,
                    x1: q[0],
                    y1: q[1],
                    x2: q[2],
                    y2: q[3],
                })
                .collect();
            levelled(&rows, (0.0, 0.0), -r)
        };
        for truth in [0.5f64.to_radians(), 0.0] {
            let f = frames(truth);
            let angles = crate::fit::angles(&f, (0.0, 0.0));
            let r = roll(&t, &angles).expect("a roll");
            // Without noise the error is the polynomials' own bending of the accelerations.
            assert!(
                (r.roll - truth).abs() < 3.0 * r.error + 1e-4,
                "{r:?} against {truth}"
            );
            assert!(r.error < 0.1 * 0.5f64.to_radians(), "{r:?}");
        }
    }

    /// Turning by the roll found and back gives the frames again.
    #[test]
    fn levelling_turns_about_the_pivot() {
        let f = [TrackedRow {
            t: 0.0,
            x1: 0.3,
            y1: -1.0,
            x2: 0.5,
            y2: -2.0,
        }];
        let back = levelled(&levelled(&f, (0.1, 0.2), 0.3), (0.1, 0.2), -0.3);
        assert!((back[0].x2 - 0.5).abs() < 1e-12 && (back[0].y1 + 1.0).abs() < 1e-12);
        // A point straight below the pivot, levelled by r, lies at angle -r.
        let down = levelled(
            &[TrackedRow {
                t: 0.0,
                x1: 0.0,
                y1: -1.0,
                x2: 0.0,
                y2: -2.0,
            }],
            (0.0, 0.0),
            0.1,
        );
        assert!((down[0].x1.atan2(-down[0].y1) + 0.1).abs() < 1e-12);
    }
}
