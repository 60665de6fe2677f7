//! `chaoscope.track`: a film of the pendulum to the positions of both masses
//! (`chaoscope track`'s job); the CSV written to `output`, the summary returned as JSON.

use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use chaoscope::app::track::TrackJob;
use chaoscope::engine::Backend;
use chaoscope::params::ParamSources;
use chaoscope::spec::Precision;
use chaoscope::track::{Markers, Scale};

use super::keywords::Keywords;
use super::run::{engine_in, watched};

#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
pub fn track<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<String> {
    let k = Keywords { dict: keywords };
    let markers = match k.get::<String>("markers")? {
        None => Markers::Bright,
        Some(s) => {
            Markers::parse(&s).map_err(|e| PyValueError::new_err(format!("markers: {e}")))?
        }
    };
    let scale =
        Scale::asked(k.get::<f64>("l1")?, k.units()?.pixels_per_metre).map_err(crate::py_err)?;
    let job = TrackJob {
        video: k
            .get("video")?
            .ok_or_else(|| PyTypeError::new_err("video: the film to track is needed"))?,
        output: k.or("output", std::path::PathBuf::from("out/track.csv"))?,
        markers,
        scale,
        region: k.get::<(u32, u32, u32, u32)>("region")?,
        bridge: match k.or("bridge", false)? {
            // The bridging model's masses and losses; its arms are the track's (l1 here
            // is the scale).
            true => {
                let given = k.sources()?;
                Some(ParamSources {
                    preset: given.preset,
                    params: given.params,
                    ..ParamSources::default()
                })
            }
            false => {
                // A model is only for bridging: given without it, it would do nothing.
                for key in ["preset", "params_file"] {
                    if k.dict.get_item(key)?.is_some_and(|v| !v.is_none()) {
                        return Err(PyValueError::new_err(format!(
                            "{key}: the model is only for bridging gaps: give bridge=True, or leave it out"
                        )));
                    }
                }
                None
            }
        },
    };
    let command = chaoscope::cli::command_line::track(&job);
    // Only bridging integrates the model.
    let engine = match job.bridge {
        Some(_) => Some(engine_in(Backend::Auto, Precision::F32)?),
        None => None,
    };
    let summary = watched(py, progress, move |monitor| {
        chaoscope::app::track::run(&job, engine.as_deref(), &command, monitor)
    })?;
    serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}
