//! `chaoscope phase`.

use std::path::PathBuf;

use clap::Args;

use super::args::{LentEngineArgs, PhysicalArgs, StepArgs, colormap_parser};
use super::parse::{parse_number, parse_spread, parse_u32};
use super::{command_line, json, say};
use crate::app::phase::{self, PhaseJob};
use crate::error::Result;
use crate::model::State;
use crate::monitor::Monitor;
use crate::render::Colormap;
use crate::spec::Spread;

#[derive(Args, Debug, Clone)]
#[command(mut_arg("t_max", |a| a.default_value("60")))]
#[command(mut_arg("dt", |a| a.default_value("0.005")))]
pub struct PhaseArgs {
    /// Start angle of the upper arm (rad); ignored with --single.
    #[arg(long, default_value = "2", value_parser = parse_number, allow_hyphen_values = true)]
    pub theta1: f64,
    /// Start angle of the lower arm (rad).
    #[arg(long, default_value = "2", value_parser = parse_number, allow_hyphen_values = true)]
    pub theta2: f64,
    /// Initial angular velocity of the upper arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    /// Initial angular velocity of the lower arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
    /// Number of runs (starts spread as for `traces`); their time densities add up.
    #[arg(long, default_value = "1", value_parser = parse_u32, allow_hyphen_values = true)]
    pub runs: u32,
    /// Distance between the runs' starts: rad, or a position error with a unit (5mm).
    #[arg(long, default_value = "0.01", value_parser = parse_spread, allow_hyphen_values = true)]
    pub spread: Spread,
    #[command(flatten)]
    pub step: StepArgs,
    /// Side of each panel (px).
    #[arg(long, default_value = "600", value_parser = parse_u32, allow_hyphen_values = true)]
    pub size: u32,
    /// The single pendulum (length l1): libration and rotation orbits and the separatrix
    /// that divides them, the report's figure 4.
    #[arg(long)]
    pub single: bool,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[command(flatten)]
    pub engine: LentEngineArgs,
    /// Colour map of the densities (default inferno).
    #[arg(long, value_parser = colormap_parser())]
    pub colormap: Option<Colormap>,
    /// PNG to write.
    #[arg(long, default_value = "out/phase.png")]
    pub output: PathBuf,
}

impl PhaseArgs {
    pub fn job(&self) -> Result<PhaseJob> {
        Ok(PhaseJob {
            params: self.physical.sources().resolve()?,
            start: State {
                theta1: self.theta1,
                omega1: self.omega1,
                theta2: self.theta2,
                omega2: self.omega2,
            },
            runs: self.runs,
            spread: self.spread,
            stepping: self.step.stepping(),
            size: self.size,
            single: self.single,
            backend: self.engine.backend,
            precision: self.engine.precision.unwrap_or_default(),
            colormap: self.colormap,
            output: self.output.clone(),
        })
    }
}

pub fn run(args: &PhaseArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job()?;
    let s = args
        .engine
        .run(&job, command_line::phase, monitor, phase::run)?;
    say("phase", &s.notices);
    eprintln!("phase portrait -> {}", s.output.display());
    json(&s)
}
