//! The model fitted to a window of tracked positions with its uncertainty: the state at the
//! window's first row and both joints' damping, searched by an ensemble on the engine and
//! refined by least squares in f64, whose covariance a forecast draws its members from.

use nalgebra::{DMatrix, DVector};

use super::lsq::{least_squares, numeric_jacobian};
use super::model::halton;
use crate::cpu;
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{EnsembleSpec, Keep};

/// Fitted parameters: the state (theta1, omega1, theta2, omega2) and the joint damping at
/// the pivot and the middle joint (N m s).
pub const FITTED: [&str; 6] = [
    "theta1", "omega1", "theta2", "omega2", "damping1", "damping2",
];

/// Integration steps per second of simulated time (RK4): a step of 1/300 s moves these
/// pendulums (|omega| up to ~20 rad/s) by 0.07 rad at most, where RK4's error per second
/// stays below 1e-5 rad (tests/forecast.rs measures it against a step ten times finer).
pub const STEPS_PER_SECOND: f64 = 300.0;

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
    /// The six parameters in [`FITTED`]'s order, their covariance (s^2 (J^T J)^-1) and
    /// standard errors.
    pub values: [f64; 6],
    pub covariance: DMatrix<f64>,
    pub errors: [f64; 6],
    /// Residual sum of squares (m^2) and its degrees of freedom (4 rows - 6).
    pub chi2: f64,
    pub dof: usize,
    /// The tracking error the residuals imply (m per coordinate): sqrt(chi^2 / dof).
    pub tracking_error: f64,
    /// Candidates of the ensemble search, and on what.
    pub candidates: usize,
    pub backend: &'static str,
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

fn with_damping(p: &Params, c1: f64, c2: f64) -> Params {
    let mut q = *p;
    (q.losses.joint1, q.losses.joint2) = (c1, c2);
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

/// Fits `p`'s state and joint damping to the `track`'s measured positions within `window`;
/// `candidates` states and dampings are searched on `engine` first.
pub fn fit_window(
    rows: &TrackRows,
    p: &Params,
    window: (f64, f64),
    candidates: usize,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<WindowFit> {
    let (t, data, angles) = (rows.t, rows.data, rows.angles);
    let (row0, rows) = window_rows(t, window);
    // Four coordinates a row against six parameters, and one degree of freedom to estimate
    // the tracking error from.
    if 4 * rows < FITTED.len() + 1 {
        return Err(Error::invalid(
            "window",
            format!(
                "{}:{} s holds {rows} tracked row(s) ({} coordinates), fewer than the {} fitted parameters and one more to estimate the tracking error: widen it",
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
    // velocities +-4 rad/s (differences over 2/3 s are crude), damping 0 .. 0.01 N m s.
    let spans = [0.15, 4.0, 0.15, 4.0];
    let dampings: Vec<f64> = (0..4).map(|k| 0.01 * k as f64 / 3.0).collect();
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
    // The search integrates the mean data interval in equal steps, a row every `stride`.
    let stride = ((times[rows - 1] - times[0]) / (rows - 1) as f64 * STEPS_PER_SECOND)
        .round()
        .max(1.0) as u32;
    let steps = (rows as u32 - 1) * stride;
    let dt = (times[rows - 1] - times[0]) / steps as f64;
    // The best few candidates (cost, index), each refined below: in a chaotic window the
    // least-squares valley of the best one need not hold the least minimum.
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(REFINED + 1);
    let ensemble = EnsembleSpec::new(*p, &starts, dt, steps)
        .damped(&pairs)
        .keeping(Keep::Every(stride));
    engine.ensemble(&ensemble, monitor, |first, runs| {
        for (k, run) in runs.into_states().iter().enumerate() {
            let q = with_damping(p, pairs[first + k].0, pairs[first + k].1);
            let cost: f64 = run
                .iter()
                .zip(data)
                .map(|(y, d)| {
                    let s = q.positions(y);
                    let e = [s.x1 - d[0], s.y1 - d[1], s.x2 - d[2], s.y2 - d[3]];
                    e.iter().map(|e| e * e).sum::<f64>()
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
    // Refine the state and both dampings together in f64, at the data's own times. The
    // damping is fitted as it is (not squared to keep it positive) so that its covariance is
    // that of the quantity itself; a forecast keeps members' damping >= 0.
    let residuals = |q: &DVector<f64>| -> DVector<f64> {
        let model = with_damping(p, q[4], q[5]);
        let sim = track(&model, State::from_array([q[0], q[1], q[2], q[3]]), times);
        DVector::from_iterator(
            rows * 4,
            sim.iter()
                .zip(data)
                .flat_map(|(a, b)| (0..4).map(move |k| a[k] - b[k])),
        )
    };
    let steps = [1e-6, 1e-5, 1e-6, 1e-5, 1e-5, 1e-5];
    let mut refined: Option<crate::fit::Fit> = None;
    for &(_, i) in &best {
        monitor.check()?;
        let b = starts[i].to_array();
        let c = pairs[i].0;
        let fit = least_squares(
            |q| (residuals(q), numeric_jacobian(&residuals, q, &steps)),
            DVector::from_vec(vec![b[0], b[1], b[2], b[3], c, c]),
            100,
        );
        if refined.as_ref().is_none_or(|r| fit.chi2 < r.chi2) {
            refined = Some(fit);
        }
    }
    let refined = refined.expect("at least one candidate");
    let values: [f64; 6] = std::array::from_fn(|k| refined.params[k]);
    let covariance = refined.covariance.clone().ok_or_else(|| {
        Error::invalid(
            "window",
            "the data in it do not determine all six parameters (the fit's normal matrix is singular): widen it",
        )
    })?;
    Ok(WindowFit {
        row0,
        rows,
        t0: times[0],
        params: with_damping(p, values[4], values[5]),
        start: State::from_array([values[0], values[1], values[2], values[3]]),
        values,
        errors: std::array::from_fn(|k| refined.errors[k]),
        covariance,
        chi2: refined.chi2,
        dof: refined.dof,
        tracking_error: (refined.chi2 / refined.dof.max(1) as f64).sqrt(),
        candidates: starts.len(),
        backend: engine.info().backend(),
    })
}
