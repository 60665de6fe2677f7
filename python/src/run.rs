//! How a call runs: on the engine the module lends, on a thread of its own while Python
//! keeps its signals and progress.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use chaoscope::engine::{Backend, Engine};
use chaoscope::monitor::Monitor;
use chaoscope::spec::Precision;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::py_err;

/// The engine of `backend` for maps (each map carries its own precision).
pub fn engine(backend: Backend) -> PyResult<Arc<Engine>> {
    engine_in(backend, Precision::F32)
}

/// The engine of `backend` whose trajectories and ensembles run in `precision`, made on the
/// module's first call that asks for it and lent to every later one: a GPU device and its
/// compiled kernels are made once per process and (backend, precision), not once per call
/// (200 calls each making a device grew the process by 53 MB).
pub fn engine_in(backend: Backend, precision: Precision) -> PyResult<Arc<Engine>> {
    type Made = (Backend, Precision, Arc<Engine>);
    static ENGINES: std::sync::Mutex<Vec<Made>> = std::sync::Mutex::new(Vec::new());
    let mut engines = ENGINES
        .lock()
        .map_err(|_| PyRuntimeError::new_err("the engines' lock was poisoned"))?;
    if let Some((_, _, e)) = engines
        .iter()
        .find(|(b, p, _)| (*b, *p) == (backend, precision))
    {
        return Ok(e.clone());
    }
    let made = Arc::new(Engine::in_precision(backend, precision).map_err(py_err)?);
    engines.push((backend, precision, made.clone()));
    Ok(made)
}

/// Runs `work` on a thread of its own while this one, the GIL released between looks, checks
/// Python's signals every 0.1 s (Ctrl-C sets the work's cancel flag; the work stops at its
/// next dispatch and KeyboardInterrupt is raised) and reports progress to `progress(phase,
/// done, total)` when given.
pub fn watched<T: Send + 'static>(
    py: Python<'_>,
    progress: Option<Bound<'_, PyAny>>,
    work: impl FnOnce(&Monitor) -> chaoscope::Result<T> + Send + 'static,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let monitor = Monitor::cancelled_by(cancel.clone());
    let (tx, rx) = std::sync::mpsc::channel();
    // Waited on with the GIL released, from this thread only.
    let rx = std::sync::Mutex::new(rx);
    let watched = monitor.clone();
    std::thread::spawn(move || {
        let _ = tx.send(work(&watched));
    });
    let mut stop: Option<PyErr> = None;
    loop {
        let next = py.detach(|| match rx.lock() {
            Ok(rx) => rx.recv_timeout(Duration::from_millis(100)),
            Err(_) => Err(std::sync::mpsc::RecvTimeoutError::Disconnected),
        });
        match next {
            Ok(result) => {
                return match (stop, result) {
                    (Some(e), _) => Err(e),
                    (None, r) => r.map_err(py_err),
                };
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err("the work's thread panicked"));
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
        }
        if stop.is_some() {
            continue;
        }
        let looked = py.check_signals().and_then(|()| match &progress {
            Some(report) => {
                let (phase, done, total) = monitor.progress();
                report.call1((phase, done, total)).map(|_| ())
            }
            None => Ok(()),
        });
        if let Err(e) = looked {
            cancel.store(true, Ordering::Relaxed);
            // The work may be blocked on an FFmpeg program that stalled.
            chaoscope::video::stop_all();
            stop = Some(e);
        }
    }
}
