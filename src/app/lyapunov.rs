//! `lyapunov`: a divergence (FTLE) map as PNG and .npy, or the convergence of one start's
//! exponent as CSV `t,ftle`.

use std::io::Write;
use std::path::PathBuf;

use super::check_output;
use crate::engine::{Backend, Engine, MapKernels};
use crate::error::Result;
use crate::model::State;
use crate::monitor::Monitor;
use crate::spec::{self, LyapunovSpec};

pub use crate::quantity::CHAOTIC_FTLE;

/// A divergence map to make: the one map job ([`super::map`]) over a [`LyapunovSpec`]; its
/// colours span `colour_range` (1/s), by default 0 to the map's 99.5th percentile
/// ([`crate::render::ftle_range`]).
pub type LyapunovMapJob = super::map::MapJob<LyapunovSpec>;

pub use super::map::run as run_map;

/// The convergence of one start's exponent. `spec.grid` is not used.
#[derive(Clone, Debug, PartialEq)]
pub struct LyapunovPointJob {
    pub spec: LyapunovSpec,
    pub start: State,
    pub backend: Backend,
    /// The CSV; None writes to the `stdout` given to [`run_point`].
    pub output: Option<PathBuf>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct LyapunovPointSummary {
    pub t_max: f64,
    /// The exponent at t-max (1/s).
    pub ftle: f64,
    pub output: Option<PathBuf>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run_point(
    job: &LyapunovPointJob,
    command: String,
    monitor: &Monitor,
    stdout: &mut dyn Write,
) -> Result<LyapunovPointSummary> {
    job.spec.validate_run()?;
    spec::validate_start(&job.start)?;
    if let Some(path) = &job.output {
        check_output("output", path, "csv")?;
    }
    let engine = Engine::new(job.backend)?;
    let mut notices: Vec<String> = engine.notices();
    let path = engine.map_info(&job.spec.grid, job.spec.precision).path;
    notices.extend(job.spec.notices(path));
    let trace = engine.ftle_convergence(&job.spec, job.start, monitor)?;
    if trace.last().is_nan() {
        notices.push(
            "warning: the exponent is NaN: the state left the numbers (a smaller time step may help)"
                .into(),
        );
    }
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(w, "# {command}")?;
        writeln!(w, "t,ftle")?;
        for (t, l) in trace.t.iter().zip(&trace.ftle) {
            writeln!(w, "{t},{l}")?;
        }
        Ok(())
    };
    super::write_text(job.output.as_deref(), stdout, monitor, write)?;
    Ok(LyapunovPointSummary {
        t_max: job.spec.stepping.t_max,
        ftle: trace.last(),
        output: job.output.clone(),
        files: job.output.iter().cloned().collect(),
        notices,
    })
}
