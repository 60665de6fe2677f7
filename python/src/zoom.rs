//! `chaoscope.zoom`: a map's keywords plus the zoom's own (`zoom=`), run as `chaoscope zoom`
//! runs it; the summary returned as JSON, the frames read back by the wrapper.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use chaoscope::app::film::FilmSpec;
use chaoscope::app::map::MapJob;
use chaoscope::app::zoom::{self, Target, ZoomJob};
use chaoscope::engine::MapKernels;
use chaoscope::render::MapPicture;
use chaoscope::spec::ZOOM;

use super::keywords::Keywords;
use super::py_err;
use super::run::{engine, watched};

/// The zoom of `map` (the first frame's job) that the `zoom` keywords describe.
pub fn run<'py, S: MapKernels + MapPicture + Copy + Send + Sync + 'static>(
    py: Python<'py>,
    zoom: Bound<'py, PyDict>,
    map: MapJob<S>,
    command_of: fn(&MapJob<S>) -> String,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<String> {
    let k = Keywords { dict: zoom };
    let to: Vec<(f64, f64, f64)> = k.get("to")?.unwrap_or_default();
    let output: std::path::PathBuf = k.or("output", ZOOM.output.into())?;
    let tile = k.tile()?;
    let job = ZoomJob {
        map,
        to: to
            .into_iter()
            .map(|(x, y, width)| Target { x, y, width })
            .collect(),
        frames: k.whole("frames")?.unwrap_or(ZOOM.frames),
        film: FilmSpec {
            path: k.get("film")?.unwrap_or_else(|| output.join(zoom::FILM)),
            fps: k.or("fps", ZOOM.fps)?,
            crf: k.whole("crf")?.unwrap_or(ZOOM.crf),
        },
        output,
        tile,
        verdict: k.or("verdict", false)?,
    };
    let command = chaoscope::cli::command_line::zoom(&job, &command_of(&job.map));
    let engine = engine(job.map.backend)?;
    let summary = watched(py, progress, move |monitor| {
        zoom::run(
            &job,
            &chaoscope::app::Running::new(&engine, command, monitor),
            &command_of,
        )
    })?;
    serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// A frame's PNG: (width, height, its RGB bytes), read as every PNG chaoscope reads is
/// (bounded, a regular file).
#[pyfunction]
pub fn png_rgb<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<(u32, u32, Bound<'py, PyBytes>)> {
    let png = chaoscope::render::read_png(&path).map_err(py_err)?;
    Ok((png.width, png.height, PyBytes::new(py, &png.rgb)))
}
