//! `trajectory`: one run as CSV, every `stride`-th step.

use std::io::Write;
use std::path::PathBuf;

use super::check_output;
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::spec::{self, Precision, Stepping};

#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryJob {
    pub params: Params,
    pub start: State,
    pub stepping: Stepping,
    /// Output interval (s), a whole multiple of dt; None: every step.
    pub every: Option<f64>,
    pub backend: Backend,
    /// The GPU's precision (the CPU is always f64).
    pub precision: Precision,
    /// The CSV; None writes to the `stdout` given to [`run`].
    pub output: Option<PathBuf>,
}

impl TrajectoryJob {
    /// Steps between written rows.
    pub fn stride(&self) -> Result<u32> {
        let dt = self.stepping.dt;
        let Some(every) = self.every else {
            return Ok(1);
        };
        let k = every / dt;
        let n = k.round();
        if !(every.is_finite() && every > 0.0) || n < 1.0 || (k - n).abs() > 1e-9 * n {
            return Err(Error::invalid(
                "every",
                format!("{every} s must be a positive whole multiple of the time step {dt} s"),
            ));
        }
        Ok(n as u32)
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TrajectorySummary {
    pub rows: usize,
    pub output: Option<PathBuf>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

/// The CSV columns after the `#` command line.
pub const COLUMNS: &str = "t,theta1,omega1,theta2,omega2,x1,y1,x2,y2,energy,dissipated";

pub fn run(
    job: &TrajectoryJob,
    at: &super::Running,
    stdout: &mut dyn Write,
) -> Result<TrajectorySummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    spec::validate_params(&job.params)?;
    spec::validate_stepping(&job.stepping)?;
    spec::validate_stability(&job.params, &job.stepping)?;
    spec::validate_start(&job.start)?;
    spec::validate_speeds(
        &job.params,
        &job.stepping,
        job.start.omega1,
        job.start.omega2,
    )?;
    let stride = job.stride()?;
    if let Some(path) = &job.output {
        check_output("output", path, "csv")?;
    }
    let mut notices: Vec<String> = engine.notices();
    let (states, dissipated) = engine.trajectory(&job.params, job.start, job.stepping, monitor)?;
    let finite = |s: &State| s.to_array().iter().all(|v| v.is_finite());
    if let Some(k) = states.iter().position(|s| !finite(s)) {
        notices.push(format!(
            "warning: the state is NaN or infinite from t = {} s on: the integration blew up (a smaller time step may help)",
            k as f64 * job.stepping.dt
        ));
    }
    let p = &job.params;
    let dt = job.stepping.dt;
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(w, "# {command}")?;
        writeln!(w, "{COLUMNS}")?;
        for (k, s) in states.iter().enumerate().step_by(stride as usize) {
            let pos = p.positions(s);
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{}",
                k as f64 * dt,
                s.theta1,
                s.omega1,
                s.theta2,
                s.omega2,
                pos.x1,
                pos.y1,
                pos.x2,
                pos.y2,
                p.energy(s),
                dissipated[k]
            )?;
        }
        Ok(())
    };
    super::write_text(job.output.as_deref(), stdout, monitor, write)?;
    Ok(TrajectorySummary {
        rows: states.len().div_ceil(stride as usize),
        output: job.output.clone(),
        files: job.output.iter().cloned().collect(),
        notices,
    })
}
