//! Fitting the model to tracked positions for `fit`: the state at a start time and the joint
//! damping, by the one window fitter ([`fit_window`]) that the forecast, its model error and
//! the bridge use, read out as the lab report's fit (ten points a data interval for the
//! plots, how long the model stays within the tolerance).

use super::data::TrackedRow;
use super::window::{TrackRows, fit_window};
use crate::engine::Engine;
use crate::error::Result;
use crate::model::{Params, State};
use crate::monitor::Monitor;

pub struct ModelFit {
    /// The data row the fit starts at and its time (s).
    pub row: usize,
    pub t0: f64,
    pub start: State,
    /// Joint damping (N m s) at the pivot and the middle joint, never below zero, and the
    /// fit's standard errors of it.
    pub damping: (f64, f64),
    pub damping_error: (f64, f64),
    /// Where the fit found a joint's damping below zero (N m s): unphysical, written as 0.
    pub negative_damping: Option<(f64, f64)>,
    /// RMS position error (m) over the fitting window.
    pub rms: f64,
    /// Candidates tried in the ensemble search, and on what.
    pub candidates: usize,
    pub backend: &'static str,
    /// Until when (s) the simulation stays within the tolerance of every tracked position.
    pub agrees_until: f64,
    /// Simulated positions (m, from the tracked pivot, the fit's pivot offset included) from
    /// t0 on, ten per data interval.
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

/// Points the plots draw per data interval.
const PER_INTERVAL: usize = 10;

/// Fits the model to `frames` from the row nearest `spec.start_time` over `spec.window`
/// seconds, the ensemble search on `engine`'s path.
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
    // The row nearest the requested start, with a neighbour on each side for the angular
    // velocities' central differences.
    let row = (1..frames.len() - 1)
        .min_by(|&a, &b| {
            (t[a] - spec.start_time)
                .abs()
                .total_cmp(&(t[b] - spec.start_time).abs())
        })
        .unwrap_or(1);
    let rows = TrackRows {
        t: &t,
        data: &data,
        angles,
    };
    let window = (t[row], t[row] + spec.window);
    let fit = fit_window(
        &rows,
        &spec.params,
        window,
        spec.candidates,
        None,
        engine,
        monitor,
    )?;
    // Ten points per data interval for the plots; every tenth is at a data time.
    let times: Vec<f64> = std::iter::once(t[row])
        .chain((row..t.len() - 1).flat_map(|i| {
            let h = (t[i + 1] - t[i]) / PER_INTERVAL as f64;
            let t = &t;
            (1..=PER_INTERVAL).map(move |k| {
                if k == PER_INTERVAL {
                    t[i + 1]
                } else {
                    t[i] + k as f64 * h
                }
            })
        }))
        .collect();
    let simulated: Vec<(f64, [f64; 4])> =
        times.iter().copied().zip(fit.positions(&times)).collect();
    let at_rows: Vec<[f64; 4]> = simulated
        .iter()
        .step_by(PER_INTERVAL)
        .map(|s| s.1)
        .collect();
    let agrees_until = agrees_until(&at_rows, &data[row..], &t[row..], spec.tolerance);
    // The fit's own rows are the first of them.
    let in_window = &at_rows[fit.row0 - row..][..fit.rows];
    let rms = (in_window
        .iter()
        .zip(&data[fit.row0..])
        .map(|(a, b)| (0..4).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (4 * fit.rows) as f64)
        .sqrt();
    let (c1, c2) = (fit.values[4], fit.values[5]);
    Ok(ModelFit {
        row,
        t0: fit.t0,
        start: fit.start,
        damping: (c1.max(0.0), c2.max(0.0)),
        damping_error: (fit.errors[4], fit.errors[5]),
        negative_damping: (c1 < 0.0 || c2 < 0.0).then_some((c1, c2)),
        rms,
        candidates: fit.candidates,
        backend: fit.backend,
        agrees_until,
        simulated,
    })
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
