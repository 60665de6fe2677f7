//! `chaoscope forecast`.

use std::path::PathBuf;

use clap::Args;

use super::args::{LentEngineArgs, PhysicalArgs, TrackedUnitsArgs};
use super::parse::{parse_length, parse_number, parse_u64, parse_usize, parse_window};
use super::{command_line, json, say};
use crate::app::forecast::{self, ForecastJob};
use crate::error::Result;
use crate::forecast::outcome::ForecastSettings;
use crate::monitor::Monitor;

#[derive(Args, Debug, Clone)]
#[command(mut_args(super::args::tracked_model_help))]
pub struct ForecastArgs {
    /// CSV of tracked positions: header with t (or frame), x1, y1, x2, y2 (s, m; y up; or
    /// pixels, see --pixels-per-metre), optionally a moving pivot x0, y0; # comments; `,`,
    /// `;` or tab separated (decimal commas with `;` or tabs); Tracker's export of two
    /// point masses (`t x y x y`, the upper mass first).
    pub file: PathBuf,
    /// Directory for forecast.png, bands.csv and summary.json (and overlay.mp4).
    #[arg(long, default_value = "out/forecast")]
    pub output: PathBuf,
    /// The film FILE was tracked from (`chaoscope track`): the forecast drawn on its frames
    /// as OUTPUT/overlay.mp4 (the tracked markers ringed, the fitted model's arms over the
    /// window, then each mass's 90 % band and the horizon).
    #[arg(long)]
    pub video: Option<PathBuf>,
    #[command(flatten)]
    pub units: TrackedUnitsArgs,
    /// The fit window START:END (s): the state at its first row and the joint damping are
    /// fitted to the rows within it; the forecast runs from its end to the data's end (or
    /// --ahead past it). Nothing is learned from the rows after it: they are only scored
    /// [default: the calibration's length (--params written by fit), else four of the
    /// motion's own times (1/RMS of the upper arm's angular velocity, over the window's own
    /// rows), at least five rows; from the second row]
    #[arg(long, value_parser = parse_window, allow_hyphen_values = true)]
    pub window: Option<(f64, f64)>,
    /// Forecast this far past the window's end (s, at most 600), whether or not rows exist
    /// there: the bands go on at the data's cadence; rows there are scored [default: to the
    /// data's end].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub ahead: Option<f64>,
    /// Learn from every row of the file, the rows after the window included (the pivot, the
    /// arms, the model, the tracking and model errors): every output then says "in sample".
    #[arg(long)]
    pub in_sample: bool,
    /// Ensemble members drawn from the fit's uncertainty (state, damping, pivot): 1 to
    /// 1,000,000 (fewer where their positions over a long forecast pass 4 GiB).
    #[arg(long, default_value = "10000", value_parser = parse_usize, allow_hyphen_values = true)]
    pub members: usize,
    /// Seed of the draws: the same seed, the same forecast.
    #[arg(long, default_value = "1", value_parser = parse_u64, allow_hyphen_values = true)]
    pub seed: u64,
    /// How far the median may lie from the lower mass and still follow it: the horizon, the
    /// spread and the scores (m, or with a unit: 3cm) [default: 5 %
    /// of the reach l1 + l2]
    #[arg(long, value_parser = parse_length, allow_hyphen_values = true)]
    pub tolerance: Option<f64>,
    /// A measurement's error per coordinate (m, or 2mm) [default: from the fit's residuals].
    #[arg(long, value_parser = parse_length, allow_hyphen_values = true)]
    pub tracking_error: Option<f64>,
    /// Candidates of the fit's ensemble search.
    #[arg(long, default_value = "65536", value_parser = parse_usize, allow_hyphen_values = true)]
    pub candidates: usize,
    /// Windows of the same recording held out to measure the model's own error (0 to 64):
    /// the model fitted on each, how far the data depart from it by the time since its end;
    /// the bands are at least that wide. They lie before the forecast's window (over the
    /// whole file with --in-sample); a calibration (--params written by fit) takes their
    /// place. 0: the bands hold the tracking error and the fit's uncertainty alone.
    #[arg(long, default_value_t = crate::forecast::model_error::HELD_OUT, value_parser = parse_usize, allow_hyphen_values = true)]
    pub held_out: usize,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[command(flatten)]
    pub engine: LentEngineArgs,
}

impl ForecastArgs {
    pub fn job(&self) -> ForecastJob {
        ForecastJob {
            file: self.file.clone(),
            output: self.output.clone(),
            units: self.units.units(),
            settings: ForecastSettings {
                window: self.window,
                members: self.members,
                seed: self.seed,
                tolerance: self.tolerance,
                tracking_error: self.tracking_error,
                candidates: self.candidates,
                held_out: self.held_out,
                ahead: self.ahead,
                in_sample: self.in_sample,
            },
            params: self.physical.sources(),
            video: self.video.clone(),
            backend: self.engine.backend,
            precision: self.engine.precision.unwrap_or_default(),
        }
    }
}

pub fn run(args: &ForecastArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job();
    let s = args
        .engine
        .run(&job, command_line::forecast, monitor, forecast::run)?;
    say("forecast", &s.notices);
    if !s.verdict.follows {
        // The verdict (among the notices) says why; nothing here is a finding.
        eprintln!(
            "no horizons: the fitted model does not follow the data (outputs in {} for a look)",
            s.output.display()
        );
        return json(&s);
    }
    let on_data = match (s.median_follows_for, s.followed_to_data_end) {
        (Some(l), false) => format!("; on the data the median followed for {l:.2} s"),
        (Some(l), true) => format!("; on the data the median followed to the data's end, {l:.2} s"),
        (None, _) => "; no rows after the window to score".into(),
    };
    eprintln!(
        "{}fit {:.4}..{:.4} s, {} members, tracking error {:.2} mm; horizon {} after the window (the median within {:.1} mm of the pendulum; the members' quartiles){on_data}; FTLE along the orbit {:.2} 1/s{} -> {}",
        if s.in_sample { "IN SAMPLE: " } else { "" },
        s.window.0,
        s.window.1,
        s.members,
        s.tracking_error * 1e3,
        s.headline.describe(),
        s.tolerance * 1e3,
        s.lyapunov_exponent,
        s.chaos_bound.map_or(String::new(), |b| format!(
            " (chaos and the tracking error alone would allow {b:.2} s)"
        )),
        s.output.display()
    );
    json(&s)
}
