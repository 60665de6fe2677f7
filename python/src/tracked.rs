//! `chaoscope.fit` and `chaoscope.forecast`: a camera-tracked run to the model fitted to it
//! and its ensemble forecast (the commands' jobs); the outputs written, the summary as JSON.

use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use chaoscope::cli::command_line;

use super::keywords::Keywords;
use super::run::{engine_in, watched};

/// The model fitted to a camera-tracked run (`chaoscope fit`'s job): its summary as JSON (the
/// pivot, the arm lengths with errors, the energy's decay fits, how long the model from `start`
/// agrees with the data), its plots, derived.csv and summary.json written to `output`.
#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
pub fn fit<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<String> {
    let k = Keywords { dict: keywords };
    let job = chaoscope::app::fit::FitJob {
        file: k
            .get("file")?
            .ok_or_else(|| PyTypeError::new_err("file: the tracked data's CSV is needed"))?,
        output: k.or("output", std::path::PathBuf::from("out/fit"))?,
        units: k.units()?,
        start: k.get("start")?,
        until: k.get("until")?,
        window: k.get("window")?,
        tolerance: k.get("tolerance")?,
        candidates: k.whole("candidates")?.unwrap_or(65536),
        held_out: k
            .whole("held_out")?
            .unwrap_or(chaoscope::app::fit::CALIBRATION_WINDOWS),
        lead: k.or("lead", chaoscope::app::fit::CALIBRATION_LEAD)?,
        velocity_error: k.or("velocity_error", 0.1)?,
        mass: k.get("mass")?,
        params: k.sources()?,
        backend: k.backend()?,
        precision: k.precision()?,
    };
    let command = command_line::fit(&job);
    let engine = engine_in(job.backend, job.precision)?;
    let summary = watched(py, progress, move |monitor| {
        chaoscope::app::fit::run(
            &job,
            &chaoscope::app::Running::new(&engine, command, monitor),
        )
    })?;
    serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// An ensemble forecast of a camera-tracked run (`chaoscope forecast`'s job): fitted on
/// `window`, `members` drawn from the fit's uncertainty to the data's end; forecast.png,
/// bands.csv and summary.json written to `output`; the short summary as JSON.
#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
pub fn forecast<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<String> {
    let k = Keywords { dict: keywords };
    let job = chaoscope::app::forecast::ForecastJob {
        file: k
            .get("file")?
            .ok_or_else(|| PyTypeError::new_err("file: the tracked data's CSV is needed"))?,
        output: k.or("output", std::path::PathBuf::from("out/forecast"))?,
        units: k.units()?,
        settings: chaoscope::forecast::outcome::ForecastSettings {
            window: k.get("window")?,
            members: k.whole("members")?.unwrap_or(10_000),
            seed: k.whole("seed")?.unwrap_or(1),
            tolerance: k.get("tolerance")?,
            tracking_error: k.get("tracking_error")?,
            candidates: k.whole("candidates")?.unwrap_or(65536),
            held_out: k
                .whole("held_out")?
                .unwrap_or(chaoscope::forecast::model_error::HELD_OUT),
            ahead: k.get("ahead")?,
            in_sample: k.or("in_sample", false)?,
        },
        params: k.sources()?,
        backend: k.backend()?,
        precision: k.precision()?,
        video: k.get("video")?,
    };
    let command = command_line::forecast(&job);
    let engine = engine_in(job.backend, job.precision)?;
    let summary = watched(py, progress, move |monitor| {
        chaoscope::app::forecast::run(
            &job,
            &chaoscope::app::Running::new(&engine, command, monitor),
        )
    })?;
    serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}
