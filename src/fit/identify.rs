//! The pendulum's model found from its own motion. Two rigid arms on pin joints move by five
//! moments (src/model.rs): A and B (each arm's inertia about its joint, A with the lower
//! arm's mass at the middle joint), C (the coupling), P and Q (gravity's), and none of them
//! is where the markers sit. The motion cannot see their common scale, so they are found as
//! ratios to P: a = A/P, b = B/P, c = C/P (s^2), q = Q/P, and the joints' damping over P,
//! k1 = c1/P and k2 = c2/P (s). Scaling every mass scales P with them and changes nothing.
//!
//! The equations of motion are linear in these six, so they are solved by least squares on
//! the equations' weak form: each equation multiplied by a smooth bump phi(t) that vanishes
//! with its first three derivatives at the ends of a stretch of data, and integrated over it.
//! Integrating by parts moves the time derivatives of the angular momenta onto phi, so no
//! acceleration is ever differentiated out of noisy positions; only the centripetal terms need
//! the angular velocities (from a local polynomial fit). With phi vanishing so smoothly at both
//! ends the trapezoid rule integrates to many digits even at 30 frames a second. Stretches
//! do not overlap, so their residuals are independent and the least-squares covariance
//! holds. The velocities the centripetal terms need still bias the moments where the film is
//! coarse, so this answer is the start of a run of the model on the angles themselves
//! ([`super::refine`]), whose moments and errors are the ones given.
//!
//! A rigid lower arm has C/Q = l1/g: with the measured l1 this is the time-scale check
//! ([`TimeScale`]): the frame rate, the metre scale and g must agree with it.

use nalgebra::{DMatrix, DVector};

pub use super::refine::Refinement;
use super::refine::{Motion, refine};
use super::window::{DampingPrior, TrackRows};
use crate::error::{Error, Result};
use crate::model::{Losses, Params};
use crate::monitor::Monitor;

/// The identified quantities, in [`Identified::values`]' order.
pub const MOMENTS: [&str; 6] = ["a", "b", "c", "q", "k1", "k2"];

/// What the motion says of the pendulum, with standard errors.
#[derive(Clone, Debug)]
pub struct Identified {
    /// a, b, c (s^2), q (1), k1, k2 (s): the moments and damping over P ([`MOMENTS`]).
    pub values: [f64; 6],
    pub errors: [f64; 6],
    pub covariance: DMatrix<f64>,
    /// The weak form's moments (the refinement's start), and how the refinement on the
    /// angles went (None: it did not hold, and the weak form's moments stand).
    pub weak: [f64; 6],
    pub refinement: Option<Refinement>,
    /// Stretches of data used (two equations each) and their length (s), and those left out
    /// as outliers (their residual beyond [`REJECT`] robust deviations).
    pub stretches: usize,
    pub rejected: usize,
    pub stretch: f64,
    /// The weak form's weighted residuals' RMS in each equation (over their typical size): how
    /// well the rigid-arm model with joint damping explains the motion.
    pub misfit: [f64; 2],
    /// The markers' radii: the upper marker from the pivot (the middle joint, l1) and the
    /// lower marker from the middle joint (m), medians over the data.
    pub l1: f64,
    pub l2: f64,
    pub time_scale: TimeScale,
}

/// Whether the frame rate, the metre scale and g agree with the motion: a rigid lower arm
/// swings with C/Q = l1/g, so the data's l1 and times imply the gravity
/// g_implied = l1 q / c under which the model follows them.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct TimeScale {
    /// The gravity the motion implies at the data's metres and seconds, and its error.
    pub g_implied: f64,
    pub g_implied_error: f64,
    /// The gravity stated (m/s^2).
    pub g: f64,
    /// (g_implied - g) / its error.
    pub z: f64,
    /// The upper arm's length the motion implies at the data's frame rate (m), and the
    /// factor on the data's frame rate that would make the stated arm length agree.
    pub l1_implied: f64,
    pub rate_factor: f64,
}

impl TimeScale {
    /// Whether g, the scale and the frame rate disagree beyond three standard errors.
    pub fn disagrees(&self) -> bool {
        self.z.abs() > 3.0
    }
}

/// The fewest rows a stretch integrates over: the bump and its second derivative need
/// some 30 points for the trapezoid rule to hold them to parts in a thousand against the
/// motion's fastest swings (at 100 frames a second, 12 points biased a by 25 standard
/// errors).
const ROWS: usize = 32;

/// A stretch whose residual in either equation lies beyond this many robust standard
/// deviations (1.4826 times the median absolute residual) is an outlier: for normal
/// residuals one stretch in 1.7 million lies so far out.
const REJECT: f64 = 5.0;

/// A smooth bump on [-1, 1]: (1 - s^2)^4 and its first two derivatives in s.
fn bump(s: f64) -> [f64; 3] {
    let u = 1.0 - s * s;
    [
        u.powi(4),
        -8.0 * s * u.powi(3),
        -8.0 * u.powi(3) + 48.0 * s * s * u.powi(2),
    ]
}

/// The angular velocities at every row by a local polynomial over `half` rows either side
/// (fewer at the ends), at the data's own times: of degree up to 10, so that a swing
/// sampled coarsely (30 frames a second: half a radian a frame) is still differentiated
/// to its truncation error rather than a quartic's. On 50 seeded compound pendulums the
/// quartic over five rows at 30 and 60 frames a second left a's 95 % interval missing the
/// truth in 17 of 20 cases, degree 10 over eleven rows in 5 (examples/identify_coverage).
/// Solved by singular values: the powers' columns are nearly parallel.
/// Rows in parallel, a block at a time between the monitor's checks (a million rows take
/// some ten seconds of singular values on one core).
fn velocities(t: &[f64], theta: &[f64], half: usize, monitor: &Monitor) -> Result<Vec<f64>> {
    use rayon::prelude::*;
    const BLOCK: usize = 8192;
    let n = t.len();
    let at = |i: usize| {
        let (lo, hi) = (i.saturating_sub(half), (i + half + 1).min(n));
        let degree = (hi - lo - 1).min(10);
        let scale = (t[hi - 1] - t[lo]).max(1e-12);
        let x = DMatrix::from_fn(hi - lo, degree + 1, |r, k| {
            ((t[lo + r] - t[i]) / scale).powi(k as i32)
        });
        let y = DVector::from_iterator(hi - lo, theta[lo..hi].iter().copied());
        match x.svd(true, true).solve(&y, 1e-13).ok() {
            Some(beta) if degree >= 1 => beta[1] / scale,
            _ => f64::NAN,
        }
    };
    let mut out = Vec::with_capacity(n);
    for first in (0..n).step_by(BLOCK) {
        monitor.check()?;
        let block: Vec<f64> = (first..(first + BLOCK).min(n))
            .into_par_iter()
            .map(at)
            .collect();
        out.extend(block);
    }
    Ok(out)
}

/// Identifies the pendulum from a track's rows (times, positions relative to the pivot and
/// the arms' unwrapped angles, [`crate::fit::data::angles`]): the upper marker at the middle
/// joint, the lower one anywhere along the lower arm. `g` is the stated gravity.
pub fn identify(track: &TrackRows, g: f64, monitor: &Monitor) -> Result<Identified> {
    let (t, data) = (track.t, track.data);
    let n = t.len();
    let finite = |d: &[f64; 4]| d.iter().all(|x| x.is_finite());
    let radii = |f: &dyn Fn(&[f64; 4]) -> f64| {
        let mut r: Vec<f64> = data.iter().filter(|d| finite(d)).map(f).collect();
        r.sort_by(f64::total_cmp);
        r.get(r.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let l1 = radii(&|d| d[0].hypot(d[1]));
    let l2 = radii(&|d| (d[2] - d[0]).hypot(d[3] - d[1]));
    let th1: Vec<f64> = track.angles.iter().map(|a| a.0).collect();
    let th2: Vec<f64> = track.angles.iter().map(|a| a.1).collect();
    // The motion's own time, 1 / RMS(omega1) from differences (whatever units the file's
    // lengths are in), sets each stretch's length where it starts: long enough to average
    // the tracking noise and keep the quadrature accurate, at least [`ROWS`]. One length for
    // the whole recording is too short once the swing has slowed: the bump's second
    // derivative then weighs the noise in the angles against a small acceleration, and noise
    // in a regressor biases its moment towards zero (on the shared recording, 0.08 s
    // stretches over its first 20 s gave a 20 % low). The velocities' fits span a tenth of
    // the whole recording's time.
    let span = t[n - 1] - t[0];
    let rate = (n - 1) as f64 / span.max(1e-12);
    let steps: Vec<f64> = (1..n)
        .map(|i| (th1[i] - th1[i - 1]) / (t[i] - t[i - 1]))
        .filter(|w| w.is_finite())
        .collect();
    let rms_omega = (steps.iter().map(|w| w * w).sum::<f64>() / steps.len().max(1) as f64).sqrt();
    let natural = 1.0 / rms_omega.max(1e-12);
    // The rows of the stretch starting at `start`: its own motion's time, grown until it
    // holds it.
    let stretch_rows = |start: usize| {
        let mut rows = ROWS;
        for _ in 0..6 {
            let end = (start + rows).min(n);
            let part = &steps[start.min(steps.len())..(end - 1).min(steps.len())];
            let rms = (part.iter().map(|w| w * w).sum::<f64>() / part.len().max(1) as f64).sqrt();
            let want = ((rate / rms.max(1e-12)).round() as usize).clamp(ROWS, 16 * ROWS);
            if want <= rows {
                break;
            }
            rows = want;
        }
        rows
    };
    let half = ((0.1 * natural * rate).round() as usize).clamp(5, 8);
    let (w1, w2) = (
        velocities(t, &th1, half, monitor)?,
        velocities(t, &th2, half, monitor)?,
    );
    // Two equations a stretch: the regressors of (a, b, c, q, k1, k2), and the first's right
    // side (the second's is 0: gravity's moment P, the unit, acts on the upper arm alone).
    let mut rows1: Vec<([f64; 6], f64)> = Vec::new();
    let mut rows2: Vec<[f64; 6]> = Vec::new();
    let mut start = 0;
    let mut durations = Vec::new();
    let mut ranges = Vec::new();
    loop {
        monitor.check()?;
        let rows = stretch_rows(start);
        if start + rows > n {
            break;
        }
        let range = start..start + rows;
        start += rows;
        if range
            .clone()
            .any(|i| !(th1[i].is_finite() && th2[i].is_finite()))
        {
            continue;
        }
        let (ta, tb) = (t[range.start], t[range.end - 1]);
        let h = 0.5 * (tb - ta);
        let (mut e1, mut e2) = ([0.0; 6], [0.0; 6]);
        let mut rhs1 = 0.0;
        for i in range.clone() {
            // Trapezoid weights at the data's own times.
            let dt =
                0.5 * (t[(i + 1).min(range.end - 1)] - t[i.saturating_sub(1).max(range.start)]);
            let s = (t[i] - ta) / h - 1.0;
            let [f, fs, fss] = bump(s);
            let (f1, f2) = (fs / h, fss / (h * h));
            let d = th1[i] - th2[i];
            let (sd, cd) = d.sin_cos();
            let (o1, o2) = (w1[i], w2[i]);
            let rel = th2[i] - th1[i];
            // d/dt(a w1 + c w2 cos D) + c w1 w2 sin D + sin th1 + k1 w1 - k2 (w2 - w1) = 0.
            e1[0] += dt * f2 * th1[i];
            e1[2] += dt * (-f1 * o2 * cd + f * o1 * o2 * sd);
            e1[4] += dt * (-f1 * th1[i]);
            e1[5] += dt * (f1 * rel);
            rhs1 -= dt * f * th1[i].sin();
            // d/dt(b w2 + c w1 cos D) - c w1 w2 sin D + q sin th2 + k2 (w2 - w1) = 0.
            e2[1] += dt * f2 * th2[i];
            e2[2] += dt * (-f1 * o1 * cd - f * o1 * o2 * sd);
            e2[3] += dt * f * th2[i].sin();
            e2[5] += dt * (-f1 * rel);
        }
        rows1.push((e1, rhs1));
        rows2.push(e2);
        durations.push(tb - ta);
        ranges.push(range);
    }
    if rows1.len() < 8 {
        return Err(Error::invalid(
            "file",
            format!(
                "{} s of data make {} stretches of at least {ROWS} rows (each about the motion's own time 1/RMS(omega1), here {:.3} s over the whole); identifying its model takes at least 8: a longer or denser recording, or the model given as a preset or a parameter file",
                span,
                rows1.len(),
                natural
            ),
        ));
    }
    // Weighted least squares: each equation over its residuals' spread (a first unweighted
    // pass finds them), so that neither equation's units decide. A stretch whose residual
    // lies beyond REJECT robust deviations (the median's) in either equation is left out and
    // the rest solved again, until the set holds: a hand in the frame, a marker lost for a
    // few frames or a knock on the stand breaks the model for a stretch, and least squares
    // would spread that one stretch over every moment (on the shared recording one such
    // stretch in its first 20 s moved a by 20 %).
    let m1 = rows1.len();
    let solve = |w: [f64; 2], keep: &[bool]| {
        let kept: Vec<usize> = (0..m1).filter(|&k| keep[k]).collect();
        let m = 2 * kept.len();
        let x = DMatrix::from_fn(m, 6, |r, k| match r < kept.len() {
            true => rows1[kept[r]].0[k] * w[0],
            false => rows2[kept[r - kept.len()]][k] * w[1],
        });
        let y = DVector::from_fn(m, |r, _| match r < kept.len() {
            true => rows1[kept[r]].1 * w[0],
            false => 0.0,
        });
        let xtx = x.transpose() * &x;
        let beta = xtx.clone().lu().solve(&(x.transpose() * &y));
        (x, y, xtx, beta)
    };
    let singular = || {
        Error::invalid(
            "file",
            "the motion does not determine the pendulum's moments (both arms must swing, each against the other): give the model as a preset or a parameter file",
        )
    };
    // Each stretch's residuals in both equations (unweighted), for the moments `beta`.
    let residuals = |beta: &DVector<f64>| -> Vec<[f64; 2]> {
        (0..m1)
            .map(|k| {
                let dot = |e: &[f64; 6]| (0..6).map(|j| e[j] * beta[j]).sum::<f64>();
                [rows1[k].1 - dot(&rows1[k].0), -dot(&rows2[k])]
            })
            .collect()
    };
    let robust = |r: &[[f64; 2]], keep: &[bool], e: usize| {
        let mut a: Vec<f64> = (0..m1)
            .filter(|&k| keep[k])
            .map(|k| r[k][e].abs())
            .collect();
        let mid = a.len() / 2;
        1.4826 * *a.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let mut keep = vec![true; m1];
    let mut weights = [1.0, 1.0];
    let mut rounds = 0;
    loop {
        monitor.check()?;
        let beta = solve(weights, &keep).3.ok_or_else(singular)?;
        let r = residuals(&beta);
        let spread = [robust(&r, &keep, 0), robust(&r, &keep, 1)];
        let next: Vec<bool> = r
            .iter()
            .map(|r| (0..2).all(|e| r[e].abs() <= REJECT * spread[e]))
            .collect();
        let new_weights = spread.map(|s| 1.0 / s.max(1e-300));
        rounds += 1;
        let settled = next == keep && rounds > 1;
        if settled || rounds > 8 || next.iter().filter(|&&k| k).count() < 8 {
            break;
        }
        keep = next;
        weights = new_weights;
    }
    let rejected = keep.iter().filter(|&&k| !k).count();
    let (x, y, xtx, beta) = match solve(weights, &keep) {
        (x, y, xtx, Some(b)) => (x, y, xtx, b),
        _ => return Err(singular()),
    };
    let r = &y - &x * &beta;
    let kept = m1 - rejected;
    let weak: [f64; 6] = std::array::from_fn(|k| beta[k]);
    let rms = |part: std::ops::Range<usize>| {
        (part.clone().map(|k| r[k] * r[k]).sum::<f64>() / part.len().max(1) as f64).sqrt()
    };
    let dof = (x.nrows() - 6).max(1);
    let s2 = r.norm_squared() / dof as f64;
    let weak_covariance = xtx.try_inverse().ok_or_else(singular)? * s2;
    // The weak form's moments are the start; run on the angles themselves they lose the
    // velocities' bias (super::refine).
    let motion = Motion {
        t,
        theta: [&th1, &th2],
        omega: [&w1, &w2],
        radii: [l1, l2],
        natural,
    };
    let stretches: Vec<_> = ranges
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(r, _)| r.clone())
        .collect();
    let (values, covariance, refinement) = match refine(&motion, &stretches, weak, monitor)? {
        Some(r) => (r.values, r.covariance, Some(r.refinement)),
        None => (weak, weak_covariance, None),
    };
    let errors: [f64; 6] = std::array::from_fn(|k| covariance[(k, k)].sqrt());
    // The equations' typical sizes: the gravity term's.
    let size1 = (rows1.iter().map(|r| r.1 * r.1).sum::<f64>() / m1 as f64).sqrt();
    let size2 = (rows2.iter().map(|r| (weak[3] * r[3]).powi(2)).sum::<f64>() / m1 as f64).sqrt();
    let misfit = [
        rms(0..kept) / weights[0] / size1.max(1e-300),
        rms(kept..2 * kept) / weights[1] / size2.max(1e-300),
    ];
    // g_implied = l1 q / c, its relative variance from q's and c's.
    let (c, q) = (values[2], values[3]);
    let g_implied = l1 * q / c;
    let rel = (covariance[(3, 3)] / (q * q) + covariance[(2, 2)] / (c * c)
        - 2.0 * covariance[(2, 3)] / (q * c))
        .max(0.0)
        .sqrt();
    let g_implied_error = g_implied.abs() * rel;
    let time_scale = TimeScale {
        g_implied,
        g_implied_error,
        g,
        z: (g_implied - g) / g_implied_error.max(1e-300),
        l1_implied: l1 * g / g_implied,
        rate_factor: (g / g_implied).sqrt(),
    };
    Ok(Identified {
        values,
        errors,
        covariance,
        weak,
        refinement,
        stretches: kept,
        rejected,
        stretch: durations.iter().sum::<f64>() / durations.len().max(1) as f64,
        misfit,
        l1,
        l2,
        time_scale,
    })
}

impl Identified {
    /// Whether the moments are those of a real pendulum: positive inertias and gravity
    /// moments, and a positive-definite inertia (a b > c^2).
    pub fn physical(&self) -> bool {
        let [a, b, c, q, ..] = self.values;
        a > 0.0 && b > 0.0 && q > 0.0 && a * b > c * c
    }

    /// The model as [`Params`] whose motion is the identified one: the arms' lengths the
    /// markers' radii (so that its positions are the markers'), gravity the one the motion
    /// implies (the time-scale check's g_implied), and masses that give the moments, P set
    /// by a 1 kg mass at the middle joint (the motion cannot see the scale). A bar's mass
    /// sits nearer its joint than a bob's, so a bob or a rod may come out negative: an
    /// equivalent pendulum, exact in its moments ([`Params::from_moments`]).
    pub fn params(&self) -> Result<Params> {
        let g = self.time_scale.g_implied;
        let p = g * self.l1;
        let [a, b, c, _, k1, k2] = self.values;
        let params = Params::from_moments(
            [a * p, b * p, c * p, p],
            (self.l1, self.l2, g),
            // A negative damping (the data gaining energy: a drive, or the tracking's
            // errors) cannot be run as a loss: none, as the summary says.
            Losses {
                joint1: (k1 * p).max(0.0),
                joint2: (k2 * p).max(0.0),
                ..Losses::default()
            },
        );
        crate::params::validate(&params)?;
        Ok(params)
    }

    /// The joint damping the motion shows, with its standard errors, in [`Self::params`]'
    /// units (N m s on the model's scale; a negative value kept as found): what each
    /// window's fit is held to.
    pub fn damping_prior(&self) -> DampingPrior {
        let p = self.time_scale.g_implied * self.l1;
        DampingPrior {
            damping: [self.values[4] * p, self.values[5] * p],
            error: [self.errors[4] * p.abs(), self.errors[5] * p.abs()],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::State;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A compound pendulum: a heavy upper bar (0.2 kg, 0.1 m, a 10 g bob at the joint) and a
    /// light lower one (30 g, 0.08 m, the marker at its tip), about 7 : 1, released high
    /// and filmed at `fps` with `noise` (m) on each coordinate for `seconds`.
    fn filmed(
        p: &Params,
        start: State,
        fps: f64,
        seconds: f64,
        noise: f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<[f64; 4]>) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let normal = Normal::new(0.0, noise).unwrap();
        let frames = (seconds * fps) as usize;
        let sub = 20;
        let h = 1.0 / (fps * sub as f64);
        let mut y = start;
        let (mut t, mut data) = (Vec::new(), Vec::new());
        for k in 0..frames {
            if k > 0 {
                for _ in 0..sub {
                    y = crate::cpu::rk4_step(p, &y, h);
                }
            }
            let q = p.positions(&y);
            t.push(k as f64 / fps);
            data.push([q.x1, q.y1, q.x2, q.y2].map(|x| x + normal.sample(&mut rng)));
        }
        (t, data)
    }

    /// A track's angles as `fit` reads them.
    fn angles(t: &[f64], data: &[[f64; 4]]) -> Vec<(f64, f64)> {
        let frames: Vec<crate::fit::TrackedRow> = t
            .iter()
            .zip(data)
            .map(|(&t, d)| crate::fit::TrackedRow {
                t,
                x1: d[0],
                y1: d[1],
                x2: d[2],
                y2: d[3],
            })
            .collect();
        crate::fit::angles(&frames, (0.0, 0.0))
    }

    fn bars(scale: f64) -> Params {
        Params {
            m1: 0.01 * scale,
            m2: 1e-3 * scale,
            l1: 0.1,
            l2: 0.08,
            g: 9.81,
            rod1: 0.2 * scale,
            rod2: 0.03 * scale,
            losses: Losses {
                joint1: 2e-5 * scale,
                joint2: 2e-6 * scale,
                ..Losses::default()
            },
        }
    }

    /// The truth's a, b, c, q, k1, k2.
    fn truth(p: &Params) -> [f64; 6] {
        let k = p.inertia();
        [
            k.a / k.p,
            k.b / k.p,
            k.c / k.p,
            k.q / k.p,
            p.losses.joint1 / k.p,
            p.losses.joint2 / k.p,
        ]
    }

    /// Filmed at 30 to 400 frames a second with 0.1 mm of noise on each coordinate (a
    /// high-speed film's fifth of a pixel), 20 s, the whole pendulum weighing 48 g to 4.8 kg:
    /// every moment within four of its standard errors of the truth (a 1-in-16,000 miss for
    /// a Gaussian estimate), the time scale agreeing with g, and the equivalent model's
    /// moments the identified ones.
    #[test]
    fn a_compound_pendulums_moments_are_found_from_its_motion() {
        let start = State::at_rest(1.9, 2.4);
        for (scale, fps, seed) in [(0.2, 400.0, 3), (20.0, 100.0, 4), (1.0, 30.0, 5)] {
            let p = bars(scale);
            let (t, data) = filmed(&p, start, fps, 20.0, 1e-4, seed);
            let angles = angles(&t, &data);
            let rows = TrackRows {
                t: &t,
                data: &data,
                angles: &angles,
            };
            let id = identify(&rows, 9.81, &Monitor::hidden()).unwrap();
            let want = truth(&p);
            assert!(id.refinement.is_some(), "{scale} {fps}: not refined");
            eprintln!(
                "{scale} kg, {fps} fps: {:?}\n{:?}\n{want:?}\n{:?}",
                id.values, id.errors, id.time_scale
            );
            for k in 0..6 {
                let z = (id.values[k] - want[k]) / id.errors[k];
                assert!(
                    z.abs() < 4.0,
                    "{scale} {fps}: {}: {} against {} (z {z:.1})",
                    MOMENTS[k],
                    id.values[k],
                    want[k]
                );
            }
            assert!(!id.time_scale.disagrees(), "{:?}", id.time_scale);
            let q = id.params().unwrap();
            let k = q.inertia();
            let got = [k.a / k.p, k.b / k.p, k.c / k.p, k.q / k.p];
            for j in 0..4 {
                // Exact but for rounding, and q through the implied g (equal by construction).
                assert!(
                    (got[j] / id.values[j] - 1.0).abs() < 1e-9,
                    "{j}: {got:?} {:?}",
                    id.values
                );
            }
        }
    }
}
