//! `chaoscope trajectory`.

use std::path::PathBuf;

use clap::Args;

use super::args::{PhysicalArgs, StartArgs, StepArgs, backend_parser};
use super::parse::{one_of, parse_at, parse_number};
use super::{command_line, json, say};
use crate::app::trajectory::{self, TrajectoryJob};
use crate::engine::Backend;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::Precision;

#[derive(Args, Debug, Clone)]
#[command(mut_arg("t_max", |a| a.default_value("10")))]
pub struct TrajectoryArgs {
    #[command(flatten)]
    pub start: StartArgs,
    #[command(flatten)]
    pub step: StepArgs,
    /// Output interval (s), a multiple of dt; default every step.
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub every: Option<f64>,
    /// cpu (f64, the default), gpu or auto.
    #[arg(long, default_value = "cpu", value_parser = backend_parser())]
    pub backend: Backend,
    /// The GPU's precision, f32 or f64 (an adapter with f64); the CPU is always f64.
    /// [default: f32]
    #[arg(long, value_parser = one_of(&Precision::ALL, Precision::name))]
    pub precision: Option<Precision>,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// A parameter as a map's pixel sets it, NAME=VALUE with a map axis's name (m2/m1=2.5:
    /// m2 is 2.5 m1); twice for a pixel of two parameter axes. The run of a parameter
    /// plane's pixel, as the explorer prints it.
    #[arg(long, value_parser = parse_at, action = clap::ArgAction::Append)]
    pub at: Vec<(crate::spec::Var, f64)>,
    /// CSV to write; standard output if absent.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

impl TrajectoryArgs {
    pub fn job(&self) -> Result<TrajectoryJob> {
        Ok(TrajectoryJob {
            params: crate::spec::resolve_at(&self.physical.sources(), &self.at)?,
            start: self.start.state(),
            stepping: self.step.stepping(),
            every: self.every,
            backend: self.backend,
            precision: self.precision.unwrap_or_default(),
            output: self.output.clone(),
        })
    }
}

pub fn run(args: &TrajectoryArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job()?;
    let command = command_line::trajectory(&job);
    let engine = super::args::lent_engine(args.precision, job.backend)?;
    let mut out = std::io::stdout().lock();
    let s = trajectory::run(
        &job,
        &crate::app::Running::new(&engine, command, monitor),
        &mut out,
    )?;
    say("trajectory", &s.notices);
    let to = match &s.output {
        Some(path) => path.display().to_string(),
        None => "standard output".to_string(),
    };
    eprintln!(
        "{} rows from t = 0 to {} s -> {to}",
        s.rows, job.stepping.t_max
    );
    json(&s)
}
