//! The forecast's row: an ensemble of tracked data as `chaoscope forecast` runs it (members
//! drawn from a window fit, integrated with their own joint damping, bands, spread and the
//! FTLE along the fitted orbit) over 6 s past the window, on the GPU engine.

use super::Sample;
use crate::engine::Engine;
use crate::error::Result;
use crate::forecast::outcome::ForecastSettings;
use crate::forecast::twin::{experiment, make_track};
use crate::forecast::{ForecastSpec, forecast};
use crate::model::State;
use crate::monitor::Monitor;
use crate::params::Preset;
use std::time::Instant;

/// Seconds forecast past the window (the "the data's 6 s").
const SPAN: f64 = 6.0;

/// A fitted window to forecast from: a twin track of the lab pendulum (30 Hz, 2 mm noise),
/// fitted over its first half second.
pub(super) fn prepare(engine: &Engine, monitor: &Monitor) -> Result<crate::fit::window::WindowFit> {
    let mut p = Preset::Lab.params();
    (p.losses.joint1, p.losses.joint2) = (1e-3, 1e-3);
    let start = State {
        theta1: 2.0,
        omega1: 0.0,
        theta2: 2.5,
        omega2: 0.0,
    };
    let track = make_track(&p, start, 30.0, 0.5 + SPAN, 0.002, 1);
    let settings = ForecastSettings {
        window: Some((0.0, 0.5)),
        members: 16,
        seed: 1,
        tolerance: Some(0.03),
        tracking_error: None,
        candidates: 4096,
        // The model is the truth here: no model error to measure.
        held_out: 0,
        ahead: None,
        in_sample: false,
    };
    Ok(
        experiment(&p, start, &track, &settings, 0.5 + SPAN, engine, monitor)?
            .0
            .fit,
    )
}

/// One timed forecast of `members` from `fit`.
pub(super) fn sample(
    fit: &crate::fit::window::WindowFit,
    members: usize,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Sample> {
    let window_end = fit.t0 + 0.5;
    let spec = ForecastSpec {
        members,
        seed: 1,
        tolerance: 0.03,
        tracking_error: fit.tracking_error,
        end: window_end + SPAN,
        data_times: Vec::new(),
        cadence: 0.0,
        model_error: None,
        band_factors: None,
    };
    let t0 = Instant::now();
    let f = forecast(fit, window_end, &spec, engine, monitor)?;
    let wall_s = t0.elapsed().as_secs_f64();
    let steps = (f.times.last().copied().unwrap_or(0.0) - fit.t0) / f.dt;
    Ok(Sample {
        name: format!("chaoscope {} forecast", engine.info().backend()),
        mode: "forecast",
        wall_s,
        pendulum_steps: members as f64 * steps,
        right: None,
    })
}
