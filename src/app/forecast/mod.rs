//! `forecast`: how long the model can follow tracked data. Fit on a window, then an ensemble
//! drawn from the fit's uncertainty past it to the end of the data; bands, horizons (data and
//! spread), the FTLE along the fitted orbit and the horizon in Lyapunov times.

mod learned;

use std::path::PathBuf;

use serde_json::json;

use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::fit::read_frames;
use crate::fit::verdict::Verdict;
use crate::forecast::outcome::{ForecastSettings, Learning, Outcome, fit_and_forecast, fit_json};
use crate::forecast::plot::{self, Marks};
use crate::forecast::{self, Headline, files::MODEL_FILE};
use learned::{learned, provenance};

/// The files a forecast writes (and the overlay, with a film).
const FILES: [&str; 4] = ["forecast.png", "bands.csv", "summary.json", MODEL_FILE];
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
    /// Whether the forecast learned from the rows after its window ([`IN_SAMPLE`]).
    pub in_sample: bool,
    /// The one answer to "how long does the model predict the pendulum": the lead at which
    /// the median is expected to leave it by the tolerance, with its quartiles.
    pub headline: Headline,
    /// What chaos and the tracking error alone allow (s): (1/lambda) ln(tolerance / tracking
    /// error), None where the orbit does not stretch.
    pub chaos_bound: Option<f64>,
    /// How long the median followed the data within the tolerance (s after the window's
    /// end; a lower bound where the data ended first).
    pub median_follows_for: Option<f64>,
    pub followed_to_data_end: bool,
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
pub fn run(job: &ForecastJob, at: &super::Running) -> Result<ForecastSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    let film = check_inputs(job)?;
    let read = read_frames(&job.file, &job.units)?;
    let (geometry, film_notice) = film_placement(job, film.as_ref())?;
    let learned = learned(job, &read, engine, monitor)?;
    let (tracked, calibration) = (&learned.tracked, learned.calibration.as_ref());
    let mut notices = engine.notices();
    notices.push(tracked.source.describe_model(&tracked.params, None));
    notices.extend(film_notice);
    notices.extend(tracked.notices.iter().cloned());
    notices.extend(learned.refreshed.map(|[a, b]| {
        format!("the model's own error and the bands' factors measured again on this file's rows {a:.2}-{b:.2} s, just before the window (the calibration's model kept)")
    }));
    let provenance = provenance(job, &learned);
    let settings = ForecastSettings {
        window: Some(learned.window),
        ..job.settings
    };
    let (t, data, pivot) = (&tracked.t, &tracked.measured, &tracked.pivot);
    let learning = Learning {
        calibration,
        damping: learned.damping,
    };
    let end = t[t.len() - 1];
    let (track, params) = (tracked.rows(), &tracked.params);
    let o = fit_and_forecast(&track, params, &settings, learning, end, engine, monitor)?;
    notices.push(o.verdict.describe());
    if job.settings.in_sample {
        notices.push(IN_SAMPLE.into());
    }
    notices.extend(calibration.and_then(|c| c.held_past(o.lead())));
    let f = &o.forecast;
    let headline = f.headline();
    let chaos_bound = o.chaos_bound();
    let out = &job.output;
    let mut files = Outputs::new();
    draw(
        &mut files,
        &out.join("forecast.png"),
        job,
        (&o, &headline),
        (t, data),
    )?;
    crate::forecast::files::write_bands(&mut files, &out.join("bands.csv"), f, &command)?;
    crate::forecast::files::write_model(&mut files, &out.join(MODEL_FILE), tracked, &command)?;
    let summary = summary_json(
        job,
        &command,
        &o,
        provenance,
        (pivot.x, pivot.y),
        t,
        (&headline, chaos_bound),
    );
    files.write_json(&out.join("summary.json"), &summary)?;
    if let (Some(video), Some(geometry)) = (&job.video, geometry) {
        let overlay = crate::forecast::overlay::Overlay {
            rows: &tracked.frames,
            geometry,
            pivot: (pivot.x, pivot.y),
            roll: tracked.placed.roll.map_or(0.0, |r| r.applied),
            outcome: &o,
            headline,
            tolerance: o.tolerance,
        };
        let path = out.join(OVERLAY);
        crate::forecast::overlay::write(&mut files, &path, video, &overlay, &command, monitor)?;
    }
    files.commit(monitor)?;
    Ok(summary_of(job, o, headline, settings.members, notices))
}

/// What the command reports of `o`.
fn summary_of(
    job: &ForecastJob,
    o: Outcome,
    headline: Headline,
    members: usize,
    notices: Vec<String>,
) -> ForecastSummary {
    let f = &o.forecast;
    let (_, spread_lt) = o.after_window(f.spread_horizon);
    let (_, data_lt) = o.after_window(o.data_horizon);
    let out = &job.output;
    ForecastSummary {
        in_sample: job.settings.in_sample,
        headline,
        chaos_bound: o.chaos_bound(),
        median_follows_for: o.scores.median_follows_for,
        followed_to_data_end: o.scores.followed_to_data_end,
        window: o.window,
        tolerance: o.tolerance,
        members,
        tracking_error: o.tracking_error,
        spread_horizon: f.spread_horizon,
        spread_horizon_lyapunov_times: spread_lt,
        data_horizon: o.data_horizon,
        data_horizon_lyapunov_times: data_lt,
        lyapunov_exponent: f.lyapunov,
        data_coverage: o.data_coverage,
        scores: o.scores.clone(),
        verdict: o.verdict,
        output: out.clone(),
        files: FILES
            .iter()
            .map(|n| out.join(n))
            .chain(job.video.as_ref().map(|_| out.join(OVERLAY)))
            .collect(),
        notices,
    }
}

/// The inputs' and outputs' checks before any work; the film's probe, where one is given.
fn check_inputs(job: &ForecastJob) -> Result<Option<crate::video::Probe>> {
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
        &[&FILES[..], &[OVERLAY]].concat(),
        &[],
        &inputs,
    )?;
    super::checks::check_units(&job.units)?;
    Ok(film)
}

/// Where the track lies in the film, and that the film is the one it was tracked from,
/// before any work (only a CSV `track` wrote says); a notice where it cannot be checked.
fn film_placement(
    job: &ForecastJob,
    film: Option<&crate::video::Probe>,
) -> Result<(Option<crate::track::file::Placement>, Option<String>)> {
    let Some(probe) = film else {
        return Ok((None, None));
    };
    let header = crate::track::file::header_of(&job.file, "video")?;
    let notice = match header.film {
        Some(tracked) => {
            let film = crate::track::file::Film::of(probe);
            tracked.check_film(&film, job.video.as_deref().expect("a film"), "video")?;
            None
        }
        None => Some(
            "the tracked file does not record its film (tracked by an earlier version): that the film is the one it was tracked from is not checked".to_string(),
        ),
    };
    Ok((Some(header.placement), notice))
}

/// forecast.png: the bands, the measured rows, the headline horizon and where the median
/// left the data, long enough to see the bands open and the data part, short enough to read.
fn draw(
    files: &mut Outputs,
    path: &std::path::Path,
    job: &ForecastJob,
    (o, headline): (&Outcome, &Headline),
    (t, data): (&[f64], &[[f64; 4]]),
) -> Result<()> {
    let f = &o.forecast;
    let forecast_end = f.times.last().copied().unwrap_or(f.window_end);
    let last_horizon = headline
        .lead
        .into_iter()
        .chain(o.scores.median_follows_for)
        .map(|l| f.window_end + l)
        .fold(f.window_end, f64::max);
    let until = (last_horizon + 3.0)
        .max(f.window_end + 3.0)
        .min(forecast_end);
    plot::forecast(
        files,
        path,
        f,
        &Marks {
            measured: (t, data),
            truth: None,
            horizon: (
                headline.lead.map(|l| f.window_end + l),
                "horizon: the members' median expected to leave the pendulum by the tolerance",
            ),
            on_data: (
                o.scores
                    .median_follows_for
                    .filter(|_| !o.scores.followed_to_data_end)
                    .map(|l| f.window_end + l),
                "where the median left the measurements by the tolerance",
            ),
            tolerance: o.tolerance,
            until,
            title: format!(
                "{}{}: fit {:.3}..{:.3} s, {} members; horizon {} (median within {:.1} mm){}",
                job.file
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                if job.settings.in_sample {
                    " (in sample)"
                } else {
                    ""
                },
                o.window.0,
                o.window.1,
                job.settings.members,
                headline.describe(),
                1e3 * o.tolerance,
                match (o.scores.median_follows_for, o.scores.followed_to_data_end) {
                    (Some(l), false) => format!("; on the data {l:.2} s"),
                    (Some(l), true) => format!("; on the data over {l:.2} s"),
                    (None, _) => String::new(),
                },
            ),
        },
    )?;
    Ok(())
}

/// summary.json: the command, what taught each part and what was scored, the fit, the
/// scores, the ensemble, every horizon by name and the exponent.
fn summary_json(
    job: &ForecastJob,
    command: &str,
    o: &crate::forecast::outcome::Outcome,
    provenance: serde_json::Value,
    pivot: (f64, f64),
    t: &[f64],
    (headline, chaos_bound): (&Headline, Option<f64>),
) -> serde_json::Value {
    let f = &o.forecast;
    let settings = &job.settings;
    let end = t[t.len() - 1];
    let forecast_end = f.times.last().copied().unwrap_or(end);
    let (spread_after, spread_lt) = o.after_window(f.spread_horizon);
    let (data_after, data_lt) = o.after_window(o.data_horizon);
    // Which error ends the forecast first: the state's uncertainty spread by chaos (the
    // ensemble), or the model's own (its departure on held-out windows).
    let model_horizon = f.model_horizon;
    let dominated_by = match (f.spread_horizon, model_horizon) {
        (_, None) => "the state's uncertainty (the ensemble's spread)",
        (None, Some(_)) => "the model's own error (its departure on held-out windows)",
        (Some(s), Some(m)) if m < s => "the model's own error (its departure on held-out windows)",
        _ => "the state's uncertainty (the ensemble's spread)",
    };
    json!({
        "command": command,
        "sample": if job.settings.in_sample { "in sample" } else { "out of sample" },
        "file": job.file.display().to_string(),
        "learned_from": provenance,
        "scored": {
            "rule": "only rows after the window's end, up to the forecast's end",
            "rows": o.scores.rows,
            "from": t.iter().find(|&&x| x > f.window_end + 1e-9),
            "to": o.scores.last_lead.map(|l| f.window_end + l),
        },
        "pivot": [pivot.0, pivot.1],
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
            "step": f.dt, "end": forecast_end, "data_end": end,
        },
        "horizon": {
            "headline": headline,
            "headline_rule": "the lead after the window's end at which the members' median is expected to leave the pendulum by more than the tolerance: each member is one pendulum the data allow (the model's own error added, each member its share), and the lead at which it first lies farther than the tolerance from the median is one draw; the median of the draws, with their quartiles",
            "chaos_bound": chaos_bound,
            "chaos_bound_rule": "(1/lambda) ln(tolerance / tracking error), lambda the FTLE along the fitted orbit over the forecast: how long chaos lets an error of the tracking's size stay within the tolerance, with a perfect model",
            "median_on_the_data": o.scores.median_follows_for,
            "median_on_the_data_is_lower_bound": o.scores.followed_to_data_end,
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
    })
}

/// The forecast drawn on the film (`--video`), in the output folder.
pub const OVERLAY: &str = "overlay.mp4";

/// What every output of a forecast that learned from its future says.
pub const IN_SAMPLE: &str = "in sample: the pivot, the arms, the model and its errors were learned from every row of the file, the rows this forecast is scored on included; its scores flatter it";

/// "at 2.31 s", or "never (to the data's end)".
pub fn fmt_time(t: Option<f64>) -> String {
    t.map_or("never (to the data's end)".into(), |t| {
        format!("at {t:.2} s")
    })
}
