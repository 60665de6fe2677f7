//! `chaoscope twin`.

use std::path::PathBuf;

use clap::Args;

use super::args::{LentEngineArgs, PhysicalArgs};
use super::parse::{parse_length, parse_number, parse_u64, parse_usize, parse_window};
use super::{command_line, json, say};
use crate::app::twin::{self, TwinJob};
use crate::error::Result;
use crate::forecast::outcome::ForecastSettings;
use crate::model::State;
use crate::monitor::Monitor;
use crate::params::Preset;

/// The truth's joint damping (N m s) unless --joint-damping is given: the size `fit` finds
/// on the lab's data.
pub const TWIN_DAMPING: f64 = 1e-3;

#[derive(Args, Debug, Clone)]
#[command(mut_arg("preset", |a| a.help("A named set of parameters [default: lab, unless --params is given]")))]
#[command(mut_arg("joint_damping", |a| a.help("The truth's joint damping at the pivot and the middle joint, A or A,B (N m s) [default: 0.001]")))]
pub struct TwinArgs {
    /// Directory for twin.csv, twin.png, twin_forecast.png and summary.json.
    #[arg(long, default_value = "out/twin")]
    pub output: PathBuf,
    /// Position noise per coordinate, a list (m, or with a unit: 1mm,2mm).
    #[arg(long, default_value = "1mm,2mm,4mm,8mm", value_delimiter = ',', value_parser = parse_length)]
    pub sigma: Vec<f64>,
    /// Sampling rates (Hz), a list: 3 like the report's table, 100 like a camera.
    #[arg(long, default_value = "3,100", value_delimiter = ',', value_parser = parse_number)]
    pub rate: Vec<f64>,
    /// Noise realisations per noise and rate.
    #[arg(long, default_value = "16", value_parser = parse_usize, allow_hyphen_values = true)]
    pub replicates: usize,
    /// The fit window START:END (s from the release).
    #[arg(long, default_value = "0:1", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: (f64, f64),
    /// The track's length (s from the release).
    #[arg(long, default_value = "4", value_parser = parse_number, allow_hyphen_values = true)]
    pub duration: f64,
    /// The release's upper angle (rad from hanging; pi understood).
    #[arg(long, default_value = "2", value_parser = parse_number, allow_hyphen_values = true)]
    pub theta1: f64,
    /// The release's lower angle (rad).
    #[arg(long, default_value = "2.5", value_parser = parse_number, allow_hyphen_values = true)]
    pub theta2: f64,
    /// The release's upper angular velocity (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    /// The release's lower angular velocity (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
    /// Ensemble members of each forecast.
    #[arg(long, default_value = "4096", value_parser = parse_usize, allow_hyphen_values = true)]
    pub members: usize,
    /// Seed of the noise and the draws.
    #[arg(long, default_value = "1", value_parser = parse_u64, allow_hyphen_values = true)]
    pub seed: u64,
    /// The lower bob's spread that ends the horizon (m, or 3cm).
    #[arg(long, default_value = "3cm", value_parser = parse_length, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Candidates of each fit's ensemble search.
    #[arg(long, default_value = "4096", value_parser = parse_usize, allow_hyphen_values = true)]
    pub candidates: usize,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[command(flatten)]
    pub engine: LentEngineArgs,
}

impl TwinArgs {
    pub fn job(&self) -> TwinJob {
        let mut params = self.physical.sources();
        params.preset = params
            .preset
            .or(params.params.is_none().then_some(Preset::Lab));
        params.joint_damping = params.joint_damping.or(Some((TWIN_DAMPING, TWIN_DAMPING)));
        TwinJob {
            output: self.output.clone(),
            sigmas: self.sigma.clone(),
            rates: self.rate.clone(),
            replicates: self.replicates,
            settings: ForecastSettings {
                window: Some(self.window),
                members: self.members,
                seed: self.seed,
                tolerance: Some(self.tolerance),
                tracking_error: None,
                candidates: self.candidates,
                // The model is the truth here: no model error to measure.
                held_out: 0,
                ahead: None,
                in_sample: false,
            },
            duration: self.duration,
            start: State {
                theta1: self.theta1,
                omega1: self.omega1,
                theta2: self.theta2,
                omega2: self.omega2,
            },
            params,
            backend: self.engine.backend,
            precision: self.engine.precision.unwrap_or_default(),
        }
    }
}

pub fn run(args: &TwinArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job();
    let s = args
        .engine
        .run(&job, command_line::twin, monitor, twin::run)?;
    say("twin", &s.notices);
    for l in &s.slopes {
        eprintln!(
            "{} Hz: horizon against ln sigma: slope {:.3} ± {:.3} s, -1/lambda {:.3} s (lambda {:.2} ± {:.2} 1/s; ratio {:.2} ± {:.2})",
            l.rate,
            l.slope,
            l.slope_error,
            l.minus_one_over_lambda,
            l.lambda,
            l.lambda_error,
            l.ratio,
            l.ratio_error
        );
    }
    eprintln!(
        "{} experiments; the truth inside the 90 % band {:.1} % of the time before the horizon -> {}",
        s.rows.len(),
        100.0 * s.coverage,
        s.output.display()
    );
    json(&s)
}
