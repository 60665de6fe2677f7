//! `chaoscope forecast`.

use std::path::PathBuf;

use clap::Args;

use super::args::{PhysicalArgs, backend_parser};
use super::parse::{one_of, parse_length, parse_u64, parse_usize, parse_window};
use super::{command_line, json, say};
use crate::app::forecast::{self, ForecastJob, ForecastSettings, fmt_time};
use crate::engine::Backend;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::Precision;

#[derive(Args, Debug, Clone)]
#[command(mut_arg("m1", |a| a.help("Upper bob mass (kg) [default: the lab preset's]")))]
#[command(mut_arg("m2", |a| a.help("Lower bob mass (kg) [default: the lab preset's]")))]
#[command(mut_arg("l1", |a| a.help("Upper arm length (m) [default: fitted to the data]")))]
#[command(mut_arg("l2", |a| a.help("Lower arm length (m) [default: fitted to the data]")))]
#[command(mut_arg("preset", |a| a.help("A named set of parameters [default: lab, unless --params is given]")))]
pub struct ForecastArgs {
    /// CSV of tracked positions: header with t, x1, y1, x2, y2 (s, m; y up); # comments.
    pub file: PathBuf,
    /// Directory for forecast.png, bands.csv and summary.json (and overlay.mp4).
    #[arg(long, default_value = "out/forecast")]
    pub output: PathBuf,
    /// The film FILE was tracked from (`chaoscope track`): the forecast drawn on its frames
    /// as OUTPUT/overlay.mp4 (the tracked markers ringed, the fitted model's arms over the
    /// window, then each mass's 90 % band and the horizon).
    #[arg(long)]
    pub video: Option<PathBuf>,
    /// The fit window START:END (s): the state at its first row and the joint damping are
    /// fitted to the rows within it (the default: the lab data's rows 0.667 to 2.002 s, near
    /// the report's start at 0.8 s); the forecast runs from its end to the data's end.
    #[arg(long, default_value = "0.6:2.1", value_parser = parse_window, allow_hyphen_values = true)]
    pub window: (f64, f64),
    /// Ensemble members drawn from the fit's uncertainty (state, damping, pivot).
    #[arg(long, default_value = "10000", value_parser = parse_usize, allow_hyphen_values = true)]
    pub members: usize,
    /// Seed of the draws: the same seed, the same forecast.
    #[arg(long, default_value = "1", value_parser = parse_u64, allow_hyphen_values = true)]
    pub seed: u64,
    /// The lower bob's spread that ends the horizon (m, or with a unit: 3cm).
    #[arg(long, default_value = "3cm", value_parser = parse_length, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// A measurement's error per coordinate (m, or 2mm) [default: from the fit's residuals].
    #[arg(long, value_parser = parse_length, allow_hyphen_values = true)]
    pub tracking_error: Option<f64>,
    /// Candidates of the fit's ensemble search.
    #[arg(long, default_value = "65536", value_parser = parse_usize, allow_hyphen_values = true)]
    pub candidates: usize,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// auto, gpu or cpu (f64).
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    /// The GPU's precision, f32 or f64 (an adapter with f64); the CPU is always f64.
    /// [default: f32]
    #[arg(long, value_parser = one_of(&Precision::ALL, Precision::name))]
    pub precision: Option<Precision>,
}

impl ForecastArgs {
    pub fn job(&self) -> ForecastJob {
        ForecastJob {
            file: self.file.clone(),
            output: self.output.clone(),
            settings: ForecastSettings {
                window: self.window,
                members: self.members,
                seed: self.seed,
                tolerance: self.tolerance,
                tracking_error: self.tracking_error,
                candidates: self.candidates,
            },
            params: self.physical.sources(),
            video: self.video.clone(),
            backend: self.backend,
            precision: self.precision.unwrap_or_default(),
        }
    }
}

pub fn run(args: &ForecastArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job();
    let engine = super::args::lent_engine(args.precision, job.backend)?;
    let s = forecast::run(&job, &engine, command_line::forecast(&job), monitor)?;
    say("forecast", &s.notices);
    if !s.verdict.follows {
        // The verdict (among the notices) says why; nothing here is a finding.
        eprintln!(
            "no horizons: the fitted model does not follow the data (outputs in {} for a look)",
            s.output.display()
        );
        return json(&s);
    }
    let lt = |v: Option<f64>| v.map_or(String::new(), |v| format!(" ({v:.1} Lyapunov times)"));
    eprintln!(
        "fit {}..{} s, {} members, tracking error {:.1} mm; horizon: spread > {} m {}{}, data out of the 90 % band {}{}; FTLE along the orbit {:.2} 1/s -> {}",
        s.window.0,
        s.window.1,
        s.members,
        s.tracking_error * 1e3,
        job.settings.tolerance,
        fmt_time(s.spread_horizon),
        lt(s.spread_horizon_lyapunov_times),
        fmt_time(s.data_horizon),
        lt(s.data_horizon_lyapunov_times),
        s.lyapunov_exponent,
        s.output.display()
    );
    json(&s)
}
