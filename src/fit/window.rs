//! The model fitted to a window of tracked positions with its uncertainty: the state at the
//! window's first row and both joints' damping, searched by an ensemble on the engine and
//! refined by least squares in f64, whose covariance a forecast draws its members from.

use nalgebra::{DMatrix, DVector};

pub use super::correlation::{Correlation, rod_correlation};
use super::lsq::{least_squares, numeric_jacobian};
use crate::cpu;
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{EnsembleSpec, Keep};
use crate::stats::halton;

/// Fitted parameters: the state (theta1, omega1, theta2, omega2), the joint damping at the
/// pivot and the middle joint (N m s), where the pivot lies in the data's frame (m), the
/// data's scale against gravity and the lower arm's length against the data's. The data's
/// origin is the pivot a circle through the whole track puts there, off by a fraction of a
/// pixel where the tracker's errors lean one way (its prior: a coordinate's tracking error).
/// A camera's metres are the rod length the user gave over the arm's length in pixels, off
/// by parts in ten thousand or more, and a pendulum whose every length is (1 + s) times as
/// long swings as it would under gravity g (1 + s): the model's g takes (1 + s) so that its
/// angles follow the data's (a scale off by 4e-4 moved a forecast by more than its band).
/// The arms' lengths come from the whole track's mean distances, which the same leaning
/// errors move by parts in ten thousand, and the scale corrects only their common factor:
/// the lower arm takes (1 + r) l2 (on the test films r came out -2e-4 to +4e-5, and the
/// band's coverage rose from 69 % to 84 %).
pub const FITTED: [&str; 10] = [
    "theta1",
    "omega1",
    "theta2",
    "omega2",
    "damping1",
    "damping2",
    "pivot_x",
    "pivot_y",
    "scale",
    "lower_arm",
];

/// The scale's prior standard deviation, and the lower arm's: a rod measured to half a
/// millimetre in 0.3 m, a pixel scale to a part in a thousand. Data that say more (a film's hundreds of frames fix
/// it to 1e-4) override it; a sparse table's few rows leave it near zero.
pub const SCALE_PRIOR: f64 = 2e-3;

/// Fitted parameters, the length of [`FITTED`].
pub const PARAMETERS: usize = FITTED.len();

/// Fitted parameters with a prior (the pivot's two, the scale, the lower arm): one
/// residual each.
const PRIORS: usize = 4;

/// Integration steps per second of simulated time (RK4): a step of 1/300 s moves these
/// pendulums (|omega| up to ~20 rad/s) by 0.07 rad at most, where RK4's error per second
/// stays below 1e-5 rad (tests/forecast.rs measures it against a step ten times finer).
pub const STEPS_PER_SECOND: f64 = 300.0;

/// The parameters' steps (FITTED's order) of the central differences for the Jacobian:
/// near the square root of f64's rounding times each parameter's size; the damping's on
/// the scale of `p`'s upper arm's inertia ([`damping_scale`]).
fn difference_steps(p: &Params) -> [f64; PARAMETERS] {
    let c = 1e-4 * damping_scale(p);
    [1e-6, 1e-5, 1e-6, 1e-5, c, c, 1e-6, 1e-6, 1e-6, 1e-6]
}

/// The joint damping the search tries, as rates on the upper arm's inertia (c / A, 1/s):
/// none up to the lab pendulum's 0.01 N m s on its 0.064 kg m^2 upper arm. A pendulum of ten
/// times the mass damped alike has ten times the damping: the search scales with it, so
/// that scaling every mass changes nothing.
pub const DAMPING_RATES: [f64; 4] = [0.0, 0.16 / 3.0, 0.32 / 3.0, 0.16];

/// A damping (N m s) over this is a rate (1/s): the upper arm's inertia A (kg m^2).
pub fn damping_scale(p: &Params) -> f64 {
    p.inertia().a.abs().max(1e-300)
}

/// Candidates of the search refined by least squares, the least result kept.
const REFINED: usize = 4;

/// A fit of the model to rows `row0 .. row0 + rows` of the data.
#[derive(Clone, Debug)]
pub struct WindowFit {
    pub row0: usize,
    pub rows: usize,
    /// The time of the first row (s): the fitted state is the state then.
    pub t0: f64,
    /// The model with the fitted damping.
    pub params: Params,
    pub start: State,
    /// Where the pivot lies in the data's frame (m): the model's positions plus this are the
    /// data's.
    pub pivot: (f64, f64),
    /// The parameters in [`FITTED`]'s order, their covariance (s^2 (J^T J)^-1 widened by the
    /// tracking errors' correlation, see [`rod_correlation`]) and standard errors.
    pub values: [f64; PARAMETERS],
    pub covariance: DMatrix<f64>,
    pub errors: [f64; PARAMETERS],
    /// How the tracking errors are correlated from row to row, by which the covariance is
    /// widened.
    pub correlation: Correlation,
    /// Residual sum of squares (m^2, the priors' terms included) and its degrees of
    /// freedom (4 rows + 4 - 10).
    pub chi2: f64,
    pub dof: usize,
    /// The tracking error the residuals imply (m per coordinate): sqrt(chi^2 / dof).
    pub tracking_error: f64,
    /// Candidates of the ensemble search, and on what.
    pub candidates: usize,
    pub backend: &'static str,
}

impl WindowFit {
    /// The model's positions in the data's frame (the fitted pivot added) at `times` (s,
    /// ascending, none before the fit's first row) for the parameters `v` ([`FITTED`]'s order).
    fn positions_for(&self, v: &[f64], times: &[f64]) -> Vec<[f64; 4]> {
        // The unfitted model: the fitted gravity and lower arm undone.
        let mut base = self.params;
        base.g /= 1.0 + self.values[8];
        base.l2 /= 1.0 + self.values[9];
        let q = fitted_params(&base, v[4], v[5], v[8], v[9]);
        let t: Vec<f64> = std::iter::once(self.t0)
            .chain(times.iter().copied())
            .collect();
        track(&q, State::from_array([v[0], v[1], v[2], v[3]]), &t)[1..]
            .iter()
            .map(|p| [p[0] + v[6], p[1] + v[7], p[2] + v[6], p[3] + v[7]])
            .collect()
    }

    /// The fitted model's positions in the data's frame at `times` (s, from the fit's first
    /// row on).
    pub fn positions(&self, times: &[f64]) -> Vec<[f64; 4]> {
        self.positions_for(&self.values, times)
    }

    /// The fitted model's velocities in the data's frame at `times` (m/s; as
    /// [`WindowFit::positions`]), by a forward difference over 1e-6 s (RK4's error and
    /// rounding leave some 1e-7 of it).
    pub fn velocities(&self, times: &[f64]) -> Vec<[f64; 4]> {
        const H: f64 = 1e-6;
        let pairs: Vec<f64> = times.iter().flat_map(|&t| [t, t + H]).collect();
        self.positions(&pairs)
            .chunks(2)
            .map(|p| std::array::from_fn(|c| (p[1][c] - p[0][c]) / H))
            .collect()
    }

    /// The standard errors of [`WindowFit::positions`] from the fit's covariance, to first
    /// order (the Jacobian J of the positions in the parameters: the diagonal of J Sigma J^T).
    /// Where the parameters' spread stretches along an unstable direction faster than
    /// linearly (past a forecast's horizon) this understates it; between measured rows it
    /// holds.
    pub fn position_errors(&self, times: &[f64]) -> Vec<[f64; 4]> {
        let flat = |v: &DVector<f64>| {
            let rows = self.positions_for(v.as_slice(), times);
            DVector::from_iterator(4 * rows.len(), rows.into_iter().flatten())
        };
        let values = DVector::from_row_slice(&self.values);
        let j = numeric_jacobian(&flat, &values, &difference_steps(&self.params));
        let spread = &j * &self.covariance;
        (0..times.len())
            .map(|k| {
                std::array::from_fn(|c| {
                    let r = 4 * k + c;
                    spread.row(r).dot(&j.row(r)).max(0.0).sqrt()
                })
            })
            .collect()
    }
}

/// Positions (x1, y1, x2, y2; m, pivot at the origin) of `p` from `start` at the data times
/// `t` (the first is the start's), each interval in equal RK4 steps near 1/300 s: the data's
/// times need not be uniform.
pub fn track(p: &Params, start: State, t: &[f64]) -> Vec<[f64; 4]> {
    track_with(p, start, t, STEPS_PER_SECOND)
}

/// As [`track`] with steps near 1/`steps_per_second` s.
pub fn track_with(p: &Params, start: State, t: &[f64], steps_per_second: f64) -> Vec<[f64; 4]> {
    let at = |y: &State| {
        let q = p.positions(y);
        [q.x1, q.y1, q.x2, q.y2]
    };
    let mut y = start;
    let mut out = vec![at(&y)];
    for w in t.windows(2) {
        let h = w[1] - w[0];
        let n = (h * steps_per_second).round().max(1.0) as u32;
        for _ in 0..n {
            y = cpu::rk4_step(p, &y, h / n as f64);
        }
        out.push(at(&y));
    }
    out
}

/// `p` with the joint damping `c1`, `c2` (N m s).
fn with_damping(p: &Params, c1: f64, c2: f64) -> Params {
    let mut q = *p;
    (q.losses.joint1, q.losses.joint2) = (c1, c2);
    q
}

/// `p` with the joint damping `c1`, `c2`, gravity scaled by 1 + `scale` and the lower arm
/// by 1 + `lower_arm`.
fn fitted_params(p: &Params, c1: f64, c2: f64, scale: f64, lower_arm: f64) -> Params {
    let mut q = with_damping(p, c1, c2);
    q.g *= 1.0 + scale;
    q.l2 *= 1.0 + lower_arm;
    q
}

/// The rows of `t` within `window` (s; ends included to a microsecond).
pub fn window_rows(t: &[f64], window: (f64, f64)) -> (usize, usize) {
    let inside = |x: f64| x >= window.0 - 1e-6 && x <= window.1 + 1e-6;
    let row0 = t.iter().position(|&x| inside(x)).unwrap_or(t.len());
    let rows = t[row0..].iter().take_while(|&&x| inside(x)).count();
    (row0, rows)
}

/// A track's rows: times (s), the measured positions (x1, y1, x2, y2, m, relative to the
/// pivot, y up) and the arms' angles from them (rad).
#[derive(Clone, Copy, Debug)]
pub struct TrackRows<'a> {
    pub t: &'a [f64],
    pub data: &'a [[f64; 4]],
    pub angles: &'a [(f64, f64)],
}

/// The default tolerance, as a share of the reach (l1 + l2): 3 cm on the lab's pendulum.
pub const TOLERANCE_SHARE: f64 = 0.06;

/// A default window holds this many of the motion's own times ([`TrackRows::motion_time`]):
/// long enough to pin the state and damping, short enough that chaos has not yet parted
/// the model from the data (0.4 s on the shared high-speed run, 1.8 s on the lab's table).
pub const WINDOW_TIMES: f64 = 4.0;

/// The fewest row intervals in a default window.
pub const WINDOW_ROWS: usize = 5;

impl TrackRows<'_> {
    /// The motion's own time (s): 1 / RMS of the upper arm's angular velocity, by
    /// differences between rows.
    pub fn motion_time(&self) -> f64 {
        let steps: Vec<f64> = self
            .angles
            .windows(2)
            .zip(self.t.windows(2))
            .map(|(a, t)| (a[1].0 - a[0].0) / (t[1] - t[0]))
            .filter(|w| w.is_finite())
            .collect();
        1.0 / (steps.iter().map(|w| w * w).sum::<f64>() / steps.len().max(1) as f64).sqrt()
    }

    /// A window's length (s) unless given: [`WINDOW_TIMES`] of the motion's own times, at
    /// least [`WINDOW_ROWS`] row intervals, at most half the data.
    pub fn default_window(&self) -> f64 {
        let n = self.t.len();
        let span = self.t[n - 1] - self.t[0];
        let step = span / (n - 1).max(1) as f64;
        (WINDOW_TIMES * self.motion_time())
            .max(WINDOW_ROWS as f64 * step)
            .min(0.5 * span)
    }

    /// A tolerance unless given: [`TOLERANCE_SHARE`] of the reach of `p`.
    pub fn default_tolerance(p: &Params) -> f64 {
        TOLERANCE_SHARE * (p.l1 + p.l2)
    }
}

/// What a window's fit knows of the joint damping before it looks: the damping (N m s) at
/// the pivot and the middle joint with its standard errors, as the motion of a longer stretch
/// shows it (a calibration's recording, or the rows a forecast learns from). A window of a
/// few motion times hardly sees the damping: fitted alone, the pivot's (over the gravity
/// moment) ranged from -0.0019 to +0.0016 s between a shared recording's windows, where its
/// first 10 s of motion say 0.00013 +- 0.00009 s; the members' spread followed it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DampingPrior {
    pub damping: [f64; 2],
    pub error: [f64; 2],
}

impl DampingPrior {
    /// Finite values with errors > 0.
    pub fn is_valid(&self) -> bool {
        self.damping.iter().all(|d| d.is_finite())
            && self.error.iter().all(|e| e.is_finite() && *e > 0.0)
    }
}

/// Fits `p`'s state, joint damping, pivot and scale to the `track`'s measured positions
/// within `window`, the damping held to `prior` where one is known; `candidates` states and
/// dampings are searched on `engine` first.
pub fn fit_window(
    rows: &TrackRows,
    p: &Params,
    window: (f64, f64),
    candidates: usize,
    prior: Option<&DampingPrior>,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<WindowFit> {
    let (t, data, angles) = (rows.t, rows.data, rows.angles);
    // A camera's errors are correlated from frame to frame (the marker's pixels, the
    // encoder's blocks), and s^2 (J^T J)^-1 counts every row as new evidence. The fit's own
    // residuals cannot say by how much (the orbit bends to follow slow errors), the rigid
    // rods can: over the whole track, how far each mass lies from its rod's length is
    // tracking error alone.
    let correlation = rod_correlation(data);
    let (row0, rows) = window_rows(t, window);
    // Four coordinates a row and the priors against the parameters, and one degree
    // of freedom to estimate the tracking error from.
    if 4 * rows + PRIORS < FITTED.len() + 1 {
        return Err(Error::invalid(
            "window",
            format!(
                "{}:{} s holds {rows} tracked row(s) ({} coordinates), fewer than the {} fitted parameters less the {PRIORS} with priors, and one more to estimate the tracking error: widen it",
                window.0,
                window.1,
                4 * rows,
                FITTED.len()
            ),
        ));
    }
    let times = &t[row0..row0 + rows];
    let data = &data[row0..row0 + rows];
    // The measured state at the first row: angles, and angular velocities by central
    // differences (one-sided at the data's ends).
    let (before, after) = (row0.saturating_sub(1), (row0 + 1).min(t.len() - 1));
    let w = |arm: fn(&(f64, f64)) -> f64| {
        (arm(&angles[after]) - arm(&angles[before])) / (t[after] - t[before])
    };
    let guess = State {
        theta1: angles[row0].0,
        omega1: w(|a| a.0),
        theta2: angles[row0].1,
        omega2: w(|a| a.1),
    };
    // Candidates around the guess as `fit` searches them: angles +-0.15 rad, angular
    // velocities +-4 rad/s (differences over 2/3 s are crude), damping rates on the upper
    // arm's inertia, and the model's own damping where it states one.
    let spans = [0.15, 4.0, 0.15, 4.0];
    let own = (p.losses.joint1 + p.losses.joint2) / 2.0;
    let dampings: Vec<f64> = DAMPING_RATES
        .iter()
        .map(|r| r * damping_scale(p))
        .chain((own > 0.0).then_some(own))
        .collect();
    let per_damping = (candidates / dampings.len()).max(1);
    let mut starts = Vec::with_capacity(per_damping * dampings.len());
    let mut pairs = Vec::with_capacity(starts.capacity());
    for &c in &dampings {
        for k in 0..per_damping {
            let u = halton(k, 4);
            let g = guess.to_array();
            starts.push(State::from_array(std::array::from_fn(|j| {
                g[j] + spans[j] * (2.0 * u[j] - 1.0)
            })));
            pairs.push((c, c));
        }
    }
    // The search integrates the window in equal steps near the fit's and reads each run's
    // positions at the rows' own times (a track with gaps, as `track --bridge` fits, has
    // rows at uneven times).
    let since: Vec<f64> = times.iter().map(|x| x - times[0]).collect();
    let steps = (since[rows - 1] * STEPS_PER_SECOND).ceil().max(1.0) as u32;
    let dt = since[rows - 1] / steps as f64;
    // The best few candidates (cost, index), each refined below: in a chaotic window the
    // least-squares valley of the best one need not hold the least minimum.
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(REFINED + 1);
    let ensemble = EnsembleSpec::new(*p, &starts, dt, steps)
        .damped(&pairs)
        .keeping(Keep::At(&since));
    engine.ensemble(&ensemble, monitor, |first, chunk| {
        // Positions by row, coordinate, then run.
        let v = chunk.positions();
        let n = v.len() / (4 * rows);
        for k in 0..n {
            let cost: f64 = data
                .iter()
                .enumerate()
                .map(|(r, d)| {
                    (0..4)
                        .map(|c| (v[(4 * r + c) * n + k] as f64 - d[c]).powi(2))
                        .sum::<f64>()
                })
                .sum();
            if best.len() < REFINED || cost < best[REFINED - 1].0 {
                best.push((cost, first + k));
                best.sort_by(|a, b| a.0.total_cmp(&b.0));
                best.truncate(REFINED);
            }
        }
        Ok(())
    })?;
    // Refine the state, both dampings, the pivot and the scale together in f64, at the
    // data's own times. The damping is fitted as it is (not squared to keep it positive) so
    // that its covariance is that of the quantity itself; a forecast keeps members' damping
    // >= 0. The priors are four more residuals, in metres as a coordinate's: each parameter
    // over its prior deviation, times the tracking error (first the rods', then the fit's).
    let pivot_prior = correlation.rms.max(1e-9);
    let residuals = |q: &DVector<f64>, error: f64| -> DVector<f64> {
        let model = fitted_params(p, q[4], q[5], q[8], q[9]);
        let sim = track(&model, State::from_array([q[0], q[1], q[2], q[3]]), times);
        let pivot = [q[6], q[7], q[6], q[7]];
        let priors: [f64; PRIORS] = [
            q[6] / pivot_prior,
            q[7] / pivot_prior,
            q[8] / SCALE_PRIOR,
            q[9] / SCALE_PRIOR,
        ];
        // The damping's prior, where known: two more residuals of the same kind.
        let damping = prior.map(|d| [0, 1].map(|k| (q[4 + k] - d.damping[k]) / d.error[k]));
        DVector::from_iterator(
            rows * 4 + priors.len() + damping.map_or(0, |d| d.len()),
            sim.iter()
                .zip(data)
                .flat_map(|(a, b)| (0..4).map(move |k| a[k] + pivot[k] - b[k]))
                .chain(priors.map(|z| z * error))
                .chain(damping.into_iter().flatten().map(|z| z * error)),
        )
    };
    let solve = |q0: DVector<f64>, error: f64| {
        let r = |q: &DVector<f64>| residuals(q, error);
        least_squares(
            |q| (r(q), numeric_jacobian(&r, q, &difference_steps(p))),
            q0,
            100,
        )
    };
    let mut refined: Option<crate::fit::Fit> = None;
    for &(_, i) in &best {
        monitor.check()?;
        let b = starts[i].to_array();
        let c = pairs[i].0;
        let start = DVector::from_vec(vec![b[0], b[1], b[2], b[3], c, c, 0.0, 0.0, 0.0, 0.0]);
        let fit = solve(start, correlation.rms);
        if refined.as_ref().is_none_or(|r| fit.chi2 < r.chi2) {
            refined = Some(fit);
        }
    }
    // Again from the best, the priors weighed against the fit's own tracking error (a
    // table tracked by hand strays from the model by more than from its rods).
    let first = refined.expect("at least one candidate");
    let error = (first.chi2 / first.dof.max(1) as f64).sqrt();
    let refined = solve(DVector::from_vec(first.params), error);
    let values: [f64; PARAMETERS] = std::array::from_fn(|k| refined.params[k]);
    let covariance = refined.covariance.clone().ok_or_else(|| {
        Error::invalid(
            "window",
            "the data in it do not determine all the fitted parameters (the fit's normal matrix is singular): widen it",
        )
    })? * correlation.inflation;
    Ok(WindowFit {
        row0,
        rows,
        t0: times[0],
        params: fitted_params(p, values[4], values[5], values[8], values[9]),
        start: State::from_array([values[0], values[1], values[2], values[3]]),
        pivot: (values[6], values[7]),
        values,
        errors: std::array::from_fn(|k| covariance[(k, k)].sqrt()),
        covariance,
        correlation,
        chi2: refined.chi2,
        dof: refined.dof,
        tracking_error: (refined.chi2 / refined.dof.max(1) as f64).sqrt(),
        candidates: starts.len(),
        backend: engine.info().backend(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Both masses on their rods at angles that wander, each rod's length read with errors
    /// following x_i = rho x_(i-1) + e_i (rho = 0.6): the inflation is Bartlett's sum at the
    /// lags chosen, 1 + 2 sum (1 - l/(L+1)) rho^l (3.6 at L near 21; (1 + rho)/(1 - rho) = 4
    /// untruncated), to three of its estimate's standard deviations, sqrt(4 L / 3 n) of it
    /// for n = 4000 pooled rows; and 1 for independent errors (at most 1.15: the sum's
    /// scatter over a few lags).
    #[test]
    fn the_rods_measure_the_tracking_errors_correlation() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut errors = |rho: f64, n: usize| -> Vec<f64> {
            let mut x = 0.0;
            (0..n)
                .map(|_| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    x = rho * x + (1.0 - rho * rho).sqrt() * 1e-4 * e;
                    x
                })
                .collect()
        };
        let rods = |r1: &[f64], r2: &[f64]| -> Vec<[f64; 4]> {
            r1.iter()
                .zip(r2)
                .enumerate()
                .map(|(i, (a, b))| {
                    let (t1, t2) = (0.01 * i as f64, 0.023 * i as f64);
                    let (l1, l2) = (0.3 + a, 0.2 + b);
                    let (x1, y1) = (l1 * t1.sin(), -l1 * t1.cos());
                    [x1, y1, x1 + l2 * t2.sin(), y1 - l2 * t2.cos()]
                })
                .collect()
        };
        let (a, b) = (errors(0.6, 2000), errors(0.6, 2000));
        let correlated = rod_correlation(&rods(&a, &b));
        let (a, b) = (errors(0.0, 2000), errors(0.0, 2000));
        let independent = rod_correlation(&rods(&a, &b));
        eprintln!("{correlated:?} {independent:?}");
        let lags = correlated.lags;
        let expected = 1.0
            + 2.0
                * (1..=lags)
                    .map(|l| (1.0 - l as f64 / (lags + 1) as f64) * 0.6f64.powi(l as i32))
                    .sum::<f64>();
        let scatter = (4.0 * lags as f64 / (3.0 * 4000.0)).sqrt() * expected;
        assert!(
            (correlated.inflation - expected).abs() < 3.0 * scatter,
            "{correlated:?} against {expected:.2} +- {scatter:.2}"
        );
        assert!(independent.inflation <= 1.15, "{independent:?}");
        // The RMS: 1e-4 m along each rod, the lower's counted at 1/sqrt 2 (a track's errors
        // at both its ends add; here one error moves the lower mass): sqrt(3/4) 1e-4, to
        // the scatter of 2000 rows' correlated errors.
        assert!(
            (correlated.rms / (0.75f64.sqrt() * 1e-4) - 1.0).abs() < 0.1,
            "{correlated:?}"
        );
    }
}
