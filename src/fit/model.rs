//! Fitting the model to tracked positions: the state at a start time and the joint damping,
//! by a large ensemble of candidates on the GPU (or the CPU), refined by least squares in f64.

use nalgebra::DVector;

use super::data::TrackedRow;
use super::lsq::{least_squares, numeric_jacobian};
use super::window::with_damping;
use crate::cpu;
use crate::engine::Engine;
use crate::error::Result;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{EnsembleSpec, Keep};
use crate::stats::halton;

/// Simulation steps per data interval (~1/300 s for 1/3 s frames).
const SUBSTEPS: u32 = 100;

pub struct ModelFit {
    /// The data row the fit starts at and its time (s).
    pub row: usize,
    pub t0: f64,
    pub start: State,
    /// Joint damping (N m s) at the pivot and the middle joint.
    pub damping: (f64, f64),
    /// RMS position error (m) over the fitting window.
    pub rms: f64,
    /// Candidates tried in the ensemble search, and on what.
    pub candidates: usize,
    pub backend: &'static str,
    /// Until when (s) the simulation stays within the tolerance of every tracked position.
    pub agrees_until: f64,
    /// Simulated positions (m, pivot at the origin) from t0 on, ten per data interval.
    pub simulated: Vec<(f64, [f64; 4])>,
}

/// What to fit and how.
pub struct ModelFitSpec {
    pub params: Params,
    pub start_time: f64,
    pub window: f64,
    pub tolerance: f64,
    pub candidates: usize,
}

/// Measured positions relative to the pivot.
pub fn measured(frames: &[TrackedRow], pivot: (f64, f64)) -> Vec<[f64; 4]> {
    frames
        .iter()
        .map(|f| {
            [
                f.x1 - pivot.0,
                f.y1 - pivot.1,
                f.x2 - pivot.0,
                f.y2 - pivot.1,
            ]
        })
        .collect()
}

fn positions(p: &Params, s: &State) -> [f64; 4] {
    let q = p.positions(s);
    [q.x1, q.y1, q.x2, q.y2]
}

/// Simulated (time, positions) from `start` at row0 over rows row0..row0+n, stepping each
/// data interval in SUBSTEPS equal steps (the data's times are not exactly uniform) and
/// keeping `per_interval` points an interval: 1 gives the data times.
fn simulate(
    p: &Params,
    start: State,
    t: &[f64],
    row0: usize,
    n: usize,
    per_interval: u32,
) -> Vec<(f64, [f64; 4])> {
    let keep = SUBSTEPS / per_interval;
    let mut out = Vec::with_capacity((n - 1) * per_interval as usize + 1);
    let mut y = start;
    out.push((t[row0], positions(p, &y)));
    for i in row0..row0 + n - 1 {
        let dt = (t[i + 1] - t[i]) / SUBSTEPS as f64;
        for k in 1..=SUBSTEPS {
            y = cpu::rk4_step(p, &y, dt);
            if k % keep == 0 {
                // The interval's last point sits exactly at the next data time.
                let time = if k == SUBSTEPS {
                    t[i + 1]
                } else {
                    t[i] + k as f64 * dt
                };
                out.push((time, positions(p, &y)));
            }
        }
    }
    out
}

/// Fits the model to `frames` from the row nearest `spec.start_time`, the ensemble search
/// on `engine`'s path.
pub fn fit_model(
    frames: &[TrackedRow],
    pivot: (f64, f64),
    angles: &[(f64, f64)],
    spec: &ModelFitSpec,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<ModelFit> {
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let data = measured(frames, pivot);
    // The row nearest the requested start, with a neighbour on each side.
    let row = (1..frames.len() - 1)
        .min_by(|&a, &b| {
            (t[a] - spec.start_time)
                .abs()
                .total_cmp(&(t[b] - spec.start_time).abs())
        })
        .unwrap_or(1);
    let window_rows = t[row..]
        .iter()
        .take_while(|&&x| x <= t[row] + spec.window + 1e-9)
        .count()
        .max(2);
    // The measured state at t0: angles, and angular velocities by central differences.
    let w = |k: usize, arm: usize| {
        let a = |i: usize| if arm == 0 { angles[i].0 } else { angles[i].1 };
        (a(k + 1) - a(k - 1)) / (t[k + 1] - t[k - 1])
    };
    let guess = State {
        theta1: angles[row].0,
        omega1: w(row, 0),
        theta2: angles[row].1,
        omega2: w(row, 1),
    };
    let scale = super::window::damping_scale(&spec.params);
    let window = Rows {
        t: &t,
        data: &data,
        row,
        count: window_rows,
    };
    let (best, candidates) = search(spec, &window, guess, engine, monitor)?;
    let backend = engine.info().backend();
    // Refine state and both damping constants together in f64 (damping as q^2 >= 0, smooth).
    let residuals = |q: &DVector<f64>| -> DVector<f64> {
        let p = with_damping(&spec.params, q[4] * q[4], q[5] * q[5]);
        let start = State::from_array([q[0], q[1], q[2], q[3]]);
        let sim = simulate(&p, start, &t, row, window_rows, 1);
        DVector::from_iterator(
            window_rows * 4,
            sim.iter()
                .zip(&data[row..])
                .flat_map(|((_, a), b)| (0..4).map(move |k| a[k] - b[k])),
        )
    };
    // The damping's root on the inertia's scale (the lab's 1e-5 on its 0.064 kg m^2).
    let root = (1.5e-4 * scale).sqrt();
    let steps = [1e-6, 1e-5, 1e-6, 1e-5, 3e-3 * root, 3e-3 * root];
    let c0 = (best.2 + 1.5e-2 * scale).sqrt();
    let b = best.1.to_array();
    let refined = least_squares(
        |q| (residuals(q), numeric_jacobian(&residuals, q, &steps)),
        DVector::from_vec(vec![b[0], b[1], b[2], b[3], c0, c0]),
        50,
    );
    let q = &refined.params;
    let fitted = with_damping(&spec.params, q[4] * q[4], q[5] * q[5]);
    let start = State::from_array([q[0], q[1], q[2], q[3]]);
    // Ten points per data interval for the plots; every tenth is at a data time.
    let simulated = simulate(&fitted, start, &t, row, frames.len() - row, 10);
    let all: Vec<[f64; 4]> = simulated.iter().step_by(10).map(|s| s.1).collect();
    let agrees_until = agrees_until(&all, &data[row..], &t[row..], spec.tolerance);
    Ok(ModelFit {
        row,
        t0: t[row],
        start,
        damping: (q[4] * q[4], q[5] * q[5]),
        rms: (refined.chi2 / (window_rows * 4) as f64).sqrt(),
        candidates,
        backend,
        agrees_until,
        simulated,
    })
}

/// The fitted rows: times, measured positions, and the window's first row and count.
struct Rows<'a> {
    t: &'a [f64],
    data: &'a [[f64; 4]],
    row: usize,
    count: usize,
}

/// The ensemble search over the state near `guess` and the joint damping: the best (squared
/// error, state, damping) and how many candidates it tried.
fn search(
    spec: &ModelFitSpec,
    rows: &Rows,
    guess: State,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<((f64, State, f64), usize)> {
    let (t, row, window_rows) = (rows.t, rows.row, rows.count);
    let cost = |sim: &[[f64; 4]]| -> f64 {
        sim.iter()
            .zip(&rows.data[row..])
            .map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>())
            .sum()
    };
    // Candidates: angles within +-0.15 rad (a few cm at these lengths), angular velocities
    // within +-4 rad/s (central differences over 2/3 s are crude), damping rates on the
    // upper arm's inertia (scaling every mass changes nothing).
    let spans = [0.15, 4.0, 0.15, 4.0];
    let scale = super::window::damping_scale(&spec.params);
    let dampings: Vec<f64> = super::window::DAMPING_RATES
        .iter()
        .map(|r| r * scale)
        .collect();
    let per_damping = (spec.candidates / dampings.len()).max(1);
    let starts: Vec<State> = (0..per_damping)
        .map(|k| {
            let u = halton(k, 4);
            let g = guess.to_array();
            State::from_array(std::array::from_fn(|j| {
                g[j] + spans[j] * (2.0 * u[j] - 1.0)
            }))
        })
        .collect();
    let n_sub = (window_rows as u32 - 1) * SUBSTEPS;
    // The ensemble integrates with the mean data interval; refinement uses the exact times.
    let dt = (t[row + window_rows - 1] - t[row]) / n_sub as f64;
    let mut best = (f64::INFINITY, guess, 0.0);
    for &c in &dampings {
        let p = with_damping(&spec.params, c, c);
        let ensemble = EnsembleSpec::new(p, &starts, dt, n_sub).keeping(Keep::Every(SUBSTEPS));
        let runs = engine.ensemble_all(&ensemble, monitor)?;
        for (s, run) in starts.iter().zip(&runs) {
            let sim: Vec<[f64; 4]> = run.iter().map(|y| positions(&p, y)).collect();
            let e = cost(&sim);
            if e < best.0 {
                best = (e, *s, c);
            }
        }
    }
    Ok((best, per_damping * dampings.len()))
}

/// Until when (s) `simulated` stays within `tolerance` of every measured position (both
/// masses); the first time where none does.
fn agrees_until(simulated: &[[f64; 4]], data: &[[f64; 4]], t: &[f64], tolerance: f64) -> f64 {
    let mut until = t[0];
    for (k, (a, b)) in simulated.iter().zip(data).enumerate() {
        let e1 = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        let e2 = ((a[2] - b[2]).powi(2) + (a[3] - b[3]).powi(2)).sqrt();
        if e1.max(e2) > tolerance {
            break;
        }
        until = t[k];
    }
    until
}
