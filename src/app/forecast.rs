//! `forecast`: how long the model can follow tracked data. Fit on a window, then an ensemble
//! drawn from the fit's uncertainty past it to the end of the data; bands, horizons (data and
//! spread), the FTLE along the fitted orbit and the horizon in Lyapunov times.

use std::path::PathBuf;

use serde_json::json;

use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::fit::forecast::{self, Forecast, QUANTILES};
use crate::fit::forecast_plot::{self, Marks};
use crate::fit::outcome::{ForecastSettings, fit_and_forecast, fit_json};
use crate::fit::read_frames;
use crate::fit::verdict::Verdict;
use crate::fit::window::TrackRows;
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::render::Outputs;
use crate::spec::Precision;

#[derive(Clone, Debug, PartialEq)]
pub struct ForecastJob {
    /// CSV of tracked positions: header with t, x1, y1, x2, y2 (s, m; y up); # comments.
    pub file: PathBuf,
    /// Directory for forecast.png, bands.csv and summary.json.
    pub output: PathBuf,
    /// How the file's numbers become seconds and metres.
    pub units: crate::fit::data::Units,
    /// The fit window, the ensemble and the horizon.
    pub settings: ForecastSettings,
    /// The model: the lab preset unless a preset or file is given, arm lengths from the data
    /// unless given.
    pub params: ParamSources,
    pub backend: Backend,
    pub precision: Precision,
    /// The film the track came from: the forecast is drawn on it, into overlay.mp4.
    pub video: Option<PathBuf>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ForecastSummary {
    pub window: (f64, f64),
    /// The lower bob's spread (m) that ends the horizon.
    pub tolerance: f64,
    pub members: usize,
    pub tracking_error: f64,
    /// Horizons (s): absolute, after the window's end, and in Lyapunov times.
    pub spread_horizon: Option<f64>,
    pub spread_horizon_lyapunov_times: Option<f64>,
    pub data_horizon: Option<f64>,
    pub data_horizon_lyapunov_times: Option<f64>,
    pub lyapunov_exponent: f64,
    pub data_coverage: Option<f64>,
    pub scores: forecast::Scores,
    pub verdict: Verdict,
    pub output: PathBuf,
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

/// Runs the forecast; `command` reproduces it and goes into summary.json.
pub fn run(
    job: &ForecastJob,
    engine: &Engine,
    command: String,
    monitor: &Monitor,
) -> Result<ForecastSummary> {
    job.settings.validate()?;
    super::checks::check_damping_not_given(&job.params)?;
    let mut inputs = super::checks::tracked_inputs(&job.file, &job.params);
    if let Some(video) = &job.video {
        if !video.exists() {
            return Err(Error::Missing {
                field: "video",
                path: video.clone(),
            });
        }
        inputs.push(("video", video.as_path()));
        crate::video::require("ffmpeg", "drawing on a film")?;
    }
    // A film FFmpeg cannot read (or no ffprobe to read it) is refused before the work.
    let film = match &job.video {
        Some(video) => Some(crate::video::probe(video).map_err(|e| e.as_input("video"))?),
        None => None,
    };
    super::checks::check_directory(
        "output",
        &job.output,
        &["forecast.png", "bands.csv", "summary.json", OVERLAY],
        &[],
        &inputs,
    )?;
    super::checks::check_units(&job.units)?;
    let read = read_frames(&job.file, &job.units)?;
    // Where the track lies in the film, and that the film is the one it was tracked from,
    // before any work: only a CSV `track` wrote says.
    let mut film_notice = None;
    let geometry = match &film {
        Some(probe) => {
            let header = crate::track::file::header_of(&job.file, "video")?;
            match header.film {
                Some(tracked) => tracked.check(&crate::track::file::Film::of(probe), "video")?,
                None => {
                    film_notice = Some(
                        "the tracked file does not record its film (tracked by an earlier version): that the film is the one it was tracked from is not checked".to_string(),
                    )
                }
            }
            Some(header.placement)
        }
        None => None,
    };
    // The pivot, arm lengths and model as `fit` finds them.
    let tracked = crate::fit::pendulum::tracked_model(&read, &job.params, &job.units)?;
    let mut notices = engine.notices();
    notices.push(tracked.source.describe_model(&tracked.params));
    notices.extend(film_notice);
    notices.extend(tracked.notices.iter().cloned());
    let crate::fit::pendulum::Tracked {
        frames,
        t,
        pivot,
        angles: angle,
        measured: data,
        params,
        ..
    } = tracked;
    let (settings, end) = (job.settings, t[t.len() - 1]);
    let track = TrackRows {
        t: &t,
        data: &data,
        angles: &angle,
    };
    let o = fit_and_forecast(&track, &params, &settings, end, engine, monitor)?;
    notices.push(o.verdict.describe());
    let f = &o.forecast;
    let (spread_after, spread_lt) = o.after_window(f.spread_horizon);
    let (data_after, data_lt) = o.after_window(o.data_horizon);

    let out = &job.output;
    let mut files = Outputs::new();
    // Long enough to see the bands open and the data part, short enough to read.
    let last_horizon = f
        .spread_horizon
        .into_iter()
        .chain(o.data_horizon)
        .fold(f.window_end, f64::max);
    let until = (last_horizon + 3.0).max(f.window_end + 3.0).min(end);
    forecast_plot::forecast(
        &mut files,
        &out.join("forecast.png"),
        f,
        &Marks {
            measured: (&t, &data),
            truth: None,
            data_horizon: o.data_horizon,
            tolerance: o.tolerance,
            until,
            title: format!(
                "{}: fit {:.3}..{:.3} s, {} members; spread > {:.3} m {}; data leave the 90 % band {}",
                job.file
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                o.window.0,
                o.window.1,
                settings.members,
                o.tolerance,
                short_time(f.spread_horizon),
                short_time(o.data_horizon),
            ),
        },
    )?;
    write_bands(&mut files, &out.join("bands.csv"), f, &command)?;
    // Which error ends the forecast first: the state's uncertainty spread by chaos (the
    // ensemble), or the model's own (its departure on held-out windows).
    let model_horizon = f.model_horizon;
    let dominated_by = match (f.spread_horizon, model_horizon) {
        (_, None) => "the state's uncertainty (the ensemble's spread)",
        (None, Some(_)) => "the model's own error (its departure on held-out windows)",
        (Some(s), Some(m)) if m < s => "the model's own error (its departure on held-out windows)",
        _ => "the state's uncertainty (the ensemble's spread)",
    };
    let summary = json!({
        "command": command,
        "file": job.file.display().to_string(),
        "pivot": [pivot.x, pivot.y],
        "parameters": crate::params::to_json(&o.fit.params),
        "fit": fit_json(&o.fit),
        "verdict": o.verdict,
        "scores": o.scores,
        "model_error": f.model_error,
        "ensemble": {
            "members": settings.members, "seed": settings.seed, "clamped_negative_damping": f.clamped,
            "tracking_error": o.tracking_error,
            "tracking_error_from": if settings.tracking_error.is_some() { "the tracking error given" } else { "the fit's residuals" },
            "backend": o.fit.backend, "precision": job.precision.name(),
            "step": f.dt, "end": end,
        },
        "horizon": {
            "tolerance": o.tolerance,
            "spread": f.spread_horizon, "spread_after_window": spread_after,
            "spread_lyapunov_times": spread_lt,
            "data": o.data_horizon, "data_after_window": data_after, "data_lyapunov_times": data_lt,
            "data_run": o.run,
            "data_rule": "the first row after the window from which a measured coordinate lies outside its 90 % band (model and tracking error) for `data_run` rows in a row",
            "data_coverage_before_spread_horizon": o.data_coverage,
            "model_error": model_horizon,
            "dominated_by": dominated_by,
        },
        "lyapunov": {
            "exponent": f.lyapunov, "time": (f.lyapunov > 0.0).then(|| 1.0 / f.lyapunov),
            "over": [f.window_end, end],
            "along": "the fitted orbit: ln of the tangent propagator's largest singular value over the time",
        },
        // The lab report's comparison, for the lab's apparatus only.
        "report": (job.params.preset == Some(crate::params::Preset::Lab)).then_some(
            "the lab report's simulation, started at 0.8 s, agreed with the measurement until about 2 s"
        ),
    });
    files.write_json(&out.join("summary.json"), &summary)?;
    if let (Some(video), Some(geometry)) = (&job.video, geometry) {
        let overlay = crate::track::overlay::Overlay {
            rows: &frames,
            geometry,
            pivot: (pivot.x, pivot.y),
            outcome: &o,
            tolerance: o.tolerance,
        };
        crate::track::overlay::write(
            &mut files,
            &out.join(OVERLAY),
            video,
            &overlay,
            &command,
            monitor,
        )?;
    }
    files.commit(monitor)?;
    Ok(ForecastSummary {
        window: o.window,
        tolerance: o.tolerance,
        members: settings.members,
        tracking_error: o.tracking_error,
        spread_horizon: f.spread_horizon,
        spread_horizon_lyapunov_times: spread_lt,
        data_horizon: o.data_horizon,
        data_horizon_lyapunov_times: data_lt,
        lyapunov_exponent: f.lyapunov,
        data_coverage: o.data_coverage,
        scores: o.scores,
        verdict: o.verdict,
        output: out.clone(),
        files: ["forecast.png", "bands.csv", "summary.json"]
            .iter()
            .map(|n| out.join(n))
            .chain(job.video.as_ref().map(|_| out.join(OVERLAY)))
            .collect(),
        notices,
    })
}

/// The forecast drawn on the film (`--video`), in the output folder.
pub const OVERLAY: &str = "overlay.mp4";

/// "at 2.31 s", or "beyond the data": short enough for a title.
fn short_time(t: Option<f64>) -> String {
    t.map_or("beyond the data".into(), |t| format!("at {t:.2} s"))
}

/// "at 2.31 s", or "never (to the data's end)".
pub fn fmt_time(t: Option<f64>) -> String {
    t.map_or("never (to the data's end)".into(), |t| {
        format!("at {t:.2} s")
    })
}

/// The bands as CSV: per coordinate the model's quantiles and a measurement's, the lower
/// bob's spread and the FTLE.
fn write_bands(
    files: &mut Outputs,
    path: &std::path::Path,
    f: &Forecast,
    command: &str,
) -> Result<()> {
    files.write(path, |w| {
        use std::io::Write;
        writeln!(w, "# {command}")?;
        writeln!(
            w,
            "# quantiles {QUANTILES:?} of the members' positions (m) and of a measurement's (obs: with the tracking error); spread_lower (m): RMS distance of the lower bob from the members' mean; ftle (1/s) along the fitted orbit from the window's end"
        )?;
        let mut header = vec!["t".to_string()];
        for c in ["x1", "y1", "x2", "y2"] {
            for kind in ["", "obs_"] {
                for q in ["p05", "p25", "median", "p75", "p95"] {
                    header.push(format!("{c}_{kind}{q}"));
                }
            }
        }
        header.extend(["spread_lower".into(), "ftle".into()]);
        writeln!(w, "{}", header.join(","))?;
        for (j, &t) in f.times.iter().enumerate() {
            let mut row = vec![format!("{t}")];
            for c in 0..4 {
                for band in [&f.model[j][c], &f.observed[j][c]] {
                    row.extend(band.iter().map(|v| format!("{v}")));
                }
            }
            row.push(format!("{}", f.spread[j]));
            row.push(format!("{}", f.ftle[j]));
            writeln!(w, "{}", row.join(","))?;
        }
        Ok(())
    })
}
