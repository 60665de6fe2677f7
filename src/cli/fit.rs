//! `chaoscope fit`.

use std::path::PathBuf;

use clap::Args;

use super::args::{LentEngineArgs, PhysicalArgs, TrackedUnitsArgs};
use super::parse::{parse_length, parse_number, parse_usize};
use super::{command_line, json, say};
use crate::app::fit::{self, FitJob};
use crate::error::Result;
use crate::monitor::Monitor;

#[derive(Args, Debug, Clone)]
#[command(mut_args(super::args::tracked_model_help))]
pub struct FitArgs {
    /// CSV of tracked positions: header with t (or frame), x1, y1, x2, y2 (s, m; y up; or
    /// pixels, see --pixels-per-metre), optionally a moving pivot x0, y0; # comments; `,`,
    /// `;` or tab separated (decimal commas with `;` or tabs); Tracker's export of two
    /// point masses (`t x y x y`, the upper mass first).
    pub file: PathBuf,
    /// Directory for the plots, derived.csv, summary.json and model.toml.
    #[arg(long, default_value = "out/fit")]
    pub output: PathBuf,
    #[command(flatten)]
    pub units: TrackedUnitsArgs,
    /// Time (s) to start the model fit; the nearest data row is used. Within the data's
    /// times, a row either side [default: the second row]
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub start: Option<f64>,
    /// Read the rows up to this time only (s): a calibration stretch of a longer recording,
    /// whose later rows a calibrated forecast then never learns from [default: every row]
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub until: Option<f64>,
    /// Length of data (s) the model is fitted to [default: four of the motion's own times,
    /// 1/RMS of the upper arm's angular velocity; at least five rows]
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub window: Option<f64>,
    /// Position tolerance for "the model agrees with the measurement" (m, or with a unit:
    /// 3cm) [default: 6 % of the reach l1 + l2]
    #[arg(long, value_parser = parse_length, allow_hyphen_values = true)]
    pub tolerance: Option<f64>,
    /// Size of the candidate ensemble of the model fit.
    #[arg(long, default_value = "65536", value_parser = parse_usize, allow_hyphen_values = true)]
    pub candidates: usize,
    /// Stretches of the recording held out to calibrate forecasts (0 to 64): the model
    /// fitted on each (as long as --window), how far the data depart from it by the lead
    /// since its end, written with the tracking error into model.toml's [calibration] for
    /// `forecast --params`. 0: no calibration.
    #[arg(long, default_value_t = crate::app::fit::CALIBRATION_WINDOWS, value_parser = parse_usize, allow_hyphen_values = true)]
    pub held_out: usize,
    /// How far past each held-out stretch its departure is measured (s, 0.05 to 60): the
    /// longest lead a calibrated forecast's bands are measured for.
    #[arg(long, default_value_t = crate::app::fit::CALIBRATION_LEAD, value_parser = parse_number, allow_hyphen_values = true)]
    pub lead: f64,
    /// Velocity error (m/s) of each mass, for the energy error bars (the report: 0.1).
    #[arg(long, default_value = "0.1", value_parser = parse_number, allow_hyphen_values = true)]
    pub velocity_error: f64,
    /// The pendulum's weighed mass (kg, 1e-6 to 1e6): all that swings, both arms with
    /// their bobs. Sets the scale of moments found from the motion, so that they and the
    /// energies come in kg m^2 and joules (exact for bobs on uniform rods) [default: over
    /// P, the upper arm's gravity moment]
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub mass: Option<f64>,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[command(flatten)]
    pub engine: LentEngineArgs,
}

impl FitArgs {
    pub fn job(&self) -> FitJob {
        FitJob {
            file: self.file.clone(),
            output: self.output.clone(),
            units: self.units.units(),
            start: self.start,
            until: self.until,
            window: self.window,
            tolerance: self.tolerance,
            candidates: self.candidates,
            held_out: self.held_out,
            lead: self.lead,
            velocity_error: self.velocity_error,
            mass: self.mass,
            params: self.physical.sources(),
            backend: self.engine.backend,
            precision: self.engine.precision.unwrap_or_default(),
        }
    }
}

pub fn run(args: &FitArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job();
    let s = args
        .engine
        .run(&job, command_line::fit, monitor, fit::run)?;
    say("fit", &s.notices);
    let agrees = match s.verdict.follows {
        true => format!(
            "model from t = {} s agrees within {:.4} m until {} s ({:.2} s)",
            s.t0,
            s.tolerance,
            s.agrees_until,
            s.agrees_until - s.t0
        ),
        false => "the model does not follow the data: no agreement to report".to_string(),
    };
    eprintln!(
        "pivot ({:.4}, {:.4}) m, l1 {:.4} ± {:.4} m, l2 {:.4} ± {:.4} m; energy a exp(b t): a {:.3} {}, b {:.4} 1/s (chi2/dof {:.2}); inverse square chi2/dof {:.2}: {} fits better; {agrees} -> {}",
        s.pivot.0,
        s.pivot.1,
        s.l1.0,
        s.l1.1,
        s.l2.0,
        s.l2.1,
        s.exponential.0,
        s.energy_unit,
        s.exponential.1,
        s.exponential.2,
        s.inverse_square_chi2,
        s.better,
        s.output.display()
    );
    json(&s)
}
