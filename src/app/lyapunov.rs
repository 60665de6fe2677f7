//! `lyapunov`: a divergence-family map (the FTLE or another chaos indicator) as PNG and
//! .npy, or the convergence of one start's indicator as CSV (`t,ftle` for the FTLE).

use std::io::Write;
use std::path::PathBuf;

use super::check_output;
use crate::cpu;
use crate::engine::{Backend, Engine, MapKernels};
use crate::error::Error;
use crate::error::Result;
use crate::model::State;
use crate::monitor::Monitor;
use crate::spec::{self, Indicator, LyapunovSpec, MapSpec};

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
    /// The indicator's quantity (its name in words).
    pub quantity: &'static str,
    /// Its value at t-max (an alignment index's where it fell below the threshold).
    pub value: f64,
    /// The exponent at t-max (1/s), for the FTLE.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ftle: Option<f64>,
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
    let indicator = job.spec.indicator;
    if indicator != Indicator::Ftle && job.backend == Backend::Gpu {
        return Err(Error::invalid(
            "backend",
            format!(
                "a single start's {} runs on the CPU (f64); leave out --backend gpu",
                indicator.title()
            ),
        ));
    }
    let engine = Engine::new(job.backend)?;
    let mut notices: Vec<String> = engine.notices();
    let path = engine.map_info(&job.spec.grid, job.spec.precision).path;
    notices.extend(job.spec.notices(path));
    // (t, the columns at t) at every renormalisation, and the map's value at t-max.
    let (header, rows, value) = match indicator {
        Indicator::Ftle => {
            let trace = engine.ftle_convergence(&job.spec, job.start, monitor)?;
            let rows = trace.t.iter().zip(&trace.ftle).map(|(&t, &l)| (t, vec![l]));
            (vec!["ftle"], rows.collect(), trace.last())
        }
        _ => {
            let mut rows = Vec::new();
            let value = cpu::indicator_run(&job.spec, job.start, Some(monitor), &mut |t, row| {
                rows.push((t, row.to_vec()))
            })?;
            (cpu::columns(indicator), rows, value)
        }
    };
    if value.is_nan() {
        notices.push(format!(
            "warning: the {} is NaN: the state left the numbers (a smaller time step may help)",
            indicator.title()
        ));
    }
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(w, "# {command}")?;
        writeln!(w, "t,{}", header.join(","))?;
        for (t, row) in &rows {
            let row: Vec<String> = row.iter().map(|x| x.to_string()).collect();
            writeln!(w, "{t},{}", row.join(","))?;
        }
        Ok(())
    };
    super::write_text(job.output.as_deref(), stdout, monitor, write)?;
    Ok(LyapunovPointSummary {
        t_max: job.spec.stepping.t_max,
        quantity: job.spec.quantity().name,
        value,
        ftle: (indicator == Indicator::Ftle).then_some(value),
        output: job.output.clone(),
        files: job.output.iter().cloned().collect(),
        notices,
    })
}
