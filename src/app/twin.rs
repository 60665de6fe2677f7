//! `twin`: twin experiments that check the forecast against a hidden truth. Tracks made by
//! the model itself (a chaotic release of the lab pendulum with its losses), sampled like the
//! report's table or a camera, with Gaussian position noise, are fitted and forecast as real
//! data are; the truth then says whether the 90 % band holds it 90 % of the time (calibration)
//! and how the horizon falls with the noise (by ln 2 / lambda per doubling).

use std::path::PathBuf;

use serde_json::json;

use super::check_count;
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::forecast::Slope;
use crate::forecast::outcome::{ForecastSettings, fit_json};
use crate::forecast::plot::{self, Marks};
use crate::forecast::twin::{self, Design, TwinRow, experiments};
use crate::model::State;
use crate::params::ParamSources;
use crate::render::Outputs;
use crate::spec::Precision;

#[derive(Clone, Debug, PartialEq)]
pub struct TwinJob {
    /// Directory for twin.csv, twin.png, twin_forecast.png and summary.json.
    pub output: PathBuf,
    /// Position noise (m per coordinate) of each experiment.
    pub sigmas: Vec<f64>,
    /// Sampling rates (Hz): 3 like the report's table, 100 like a camera.
    pub rates: Vec<f64>,
    /// Noise realisations per noise and rate.
    pub replicates: usize,
    /// The fit window, the ensemble and the horizon of each experiment (its seed the
    /// replicates' base seed; no tracking error given: each fit's residuals give it).
    pub settings: ForecastSettings,
    /// The track's length (s) from the release.
    pub duration: f64,
    /// The release.
    pub start: State,
    /// The truth's parameters, joint damping included; the model fits the damping and takes
    /// the rest from them.
    pub params: ParamSources,
    pub backend: Backend,
    pub precision: Precision,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TwinSummary {
    pub rows: Vec<TwinRow>,
    pub slopes: Vec<Slope>,
    pub coverage: f64,
    pub output: PathBuf,
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run(job: &TwinJob, at: &super::Running) -> Result<TwinSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    check_job(job)?;
    let truth = job.params.resolve()?;
    let notices = engine.notices();
    let design = Design {
        sigmas: &job.sigmas,
        rates: &job.rates,
        replicates: job.replicates,
        settings: job.settings,
        duration: job.duration,
        start: job.start,
    };
    let (rows, coverage, shown) = experiments(&design, &truth, engine, monitor)?;
    let slopes = twin::slopes(&rows, &job.rates, job.replicates);

    let out = &job.output;
    let mut files = Outputs::new();
    twin::write_csv(&mut files, &out.join("twin.csv"), &command, &rows)?;
    let series = twin::horizon_series(&rows, &job.rates);
    plot::twin(&mut files, &out.join("twin.png"), &series, &slopes)?;
    if let Some((o, at, track, sigma, rate)) = &shown {
        plot::forecast(
            &mut files,
            &out.join("twin_forecast.png"),
            &o.forecast,
            &Marks {
                measured: (&track.t, &track.measured),
                truth: Some(at),
                horizon: (o.forecast.spread_horizon, plot::SPREAD_MARK),
                on_data: (o.data_horizon, plot::DATA_MARK),
                tolerance: o.tolerance,
                until: job.duration,
                title: format!(
                    "twin experiment: {rate} Hz, noise {} mm, fit {}..{} s, {} members; truth green",
                    sigma * 1e3,
                    o.window.0,
                    o.window.1,
                    job.settings.members
                ),
            },
        )?;
    }
    let summary = json!({
        "command": command,
        "truth": { "parameters": crate::params::to_json(&truth), "start": job.start.to_array() },
        "window": shown.as_ref().map(|s| s.0.window), "duration": job.duration, "members": job.settings.members,
        "tolerance": shown.as_ref().map(|s| s.0.tolerance),
        "table": twin::table(&rows, &job.rates, &job.sigmas),
        "coverage": coverage,
        "slopes": slopes.iter().map(|s| json!({
            "rate": s.rate, "slope": s.slope, "slope_error": s.slope_error, "lambda": s.lambda,
            "lambda_error": s.lambda_error, "minus_one_over_lambda": s.minus_one_over_lambda,
            "ratio": s.ratio, "ratio_error": s.ratio_error,
        })).collect::<Vec<_>>(),
        "example_fit": shown.as_ref().map(|s| fit_json(&s.0.fit)),
    });
    files.write_json(&out.join("summary.json"), &summary)?;
    files.commit(monitor)?;
    Ok(TwinSummary {
        rows,
        slopes,
        coverage,
        output: out.clone(),
        files: FILES.iter().map(|n| out.join(n)).collect(),
        notices,
    })
}

/// The files a twin run writes into its folder.
const FILES: [&str; 4] = ["twin.csv", "twin.png", "twin_forecast.png", "summary.json"];

/// The job's values and its output folder, before any work.
fn check_job(job: &TwinJob) -> Result<()> {
    job.settings.validate()?;
    check_count("replicates", job.replicates as u64, 1, 100)?;
    for (field, v, most) in [
        ("theta1", job.start.theta1, 100.0),
        ("theta2", job.start.theta2, 100.0),
        ("omega1", job.start.omega1, 1000.0),
        ("omega2", job.start.omega2, 1000.0),
    ] {
        super::check_within(field, v, -most, most)?;
    }
    for &s in &job.sigmas {
        // A noise-free track has nothing for the band to cover and no ln sigma to fit.
        if !(s.is_finite() && s > 0.0 && s <= 0.1) {
            return Err(Error::invalid(
                "sigma",
                format!("{s} must be in (0, 0.1] m: a twin measures how noise limits the forecast"),
            ));
        }
    }
    for &r in &job.rates {
        super::check_within("rate", r, 0.5, 10_000.0)?;
    }
    super::check_within("duration", job.duration, 0.1, 60.0)?;
    if job.sigmas.is_empty() || job.rates.is_empty() {
        return Err(Error::invalid(
            "sigma",
            "give at least one noise and one rate",
        ));
    }
    let inputs: Vec<_> = job
        .params
        .params
        .as_deref()
        .map(|p| ("params", p))
        .into_iter()
        .collect();
    super::checks::check_directory("output", &job.output, &FILES, &[], &inputs)?;
    Ok(())
}
