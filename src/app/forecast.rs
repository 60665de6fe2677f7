//! `forecast`: how long the model can follow tracked data. Fit on a window, then an ensemble
//! drawn from the fit's uncertainty past it to the end of the data; bands, horizons (data and
//! spread), the FTLE along the fitted orbit and the horizon in Lyapunov times.

use std::path::PathBuf;

use serde_json::json;

use super::{check_count, check_within};
use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::fit::forecast::{self, Forecast, ForecastSpec, QUANTILES, band_times, most_members};
use crate::fit::forecast_plot::{self, Marks};
use crate::fit::pendulum::Verdict;
use crate::fit::read_frames;
use crate::fit::window::{FITTED, TrackRows, WindowFit, fit_window};
use crate::model::Params;
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

/// What a fit and forecast of one track found.
pub struct Outcome {
    pub fit: WindowFit,
    pub forecast: Forecast,
    pub tracking_error: f64,
    /// The first time measurements leave their band for `run` rows in a row, and how often
    /// they lie inside it before the spread's horizon.
    pub data_horizon: Option<f64>,
    pub run: usize,
    pub data_coverage: Option<f64>,
    /// The median's and the bands' record against the data after the window.
    pub scores: forecast::Scores,
    /// Whether the fit follows the data in its window: where it does not, the horizons are
    /// no findings.
    pub verdict: Verdict,
    /// The window and the tolerance used: the settings', else the data's defaults.
    pub window: (f64, f64),
    pub tolerance: f64,
}

impl Outcome {
    /// A horizon (s) as time after the window's end, and in Lyapunov times (None where the
    /// orbit does not stretch: an exponent <= 0 has no Lyapunov time).
    pub fn after_window(&self, horizon: Option<f64>) -> (Option<f64>, Option<f64>) {
        let after = horizon.map(|t| t - self.forecast.window_end);
        let lambda = self.forecast.lyapunov;
        (after, after.filter(|_| lambda > 0.0).map(|a| a * lambda))
    }
}

/// The settings of a fit and forecast of one track (`forecast`'s, and each of `twin`'s
/// experiments').
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForecastSettings {
    /// The fit window (s): the model is fitted to the rows from its start to its end. None:
    /// four of the motion's own times from the second row ([`TrackRows::default_window`]).
    pub window: Option<(f64, f64)>,
    /// Number of ensemble members.
    pub members: usize,
    /// Seed of the members' draws and of the measurement noise in the bands.
    pub seed: u64,
    /// The lower bob's spread (m) that ends the forecast's horizon. None: 6 % of the reach.
    pub tolerance: Option<f64>,
    /// A measurement's error (m per coordinate); None: what the fit's residuals imply.
    pub tracking_error: Option<f64>,
    /// Candidates of the fit's ensemble search.
    pub candidates: usize,
    /// Windows of the same recording held out to measure the model's own error (0: none;
    /// the bands then hold the tracking error and the fit's uncertainty alone).
    pub held_out: usize,
}

impl ForecastSettings {
    /// Checks the settings every forecast shares (the window against the data, later).
    pub fn validate(&self) -> Result<()> {
        if self.members == 0 {
            return Err(Error::invalid(
                "members",
                "must be at least 1 (10000 draws a smooth band)",
            ));
        }
        if let Some(tolerance) = self.tolerance {
            check_within("tolerance", tolerance, 1e-6, 1e3)?;
        }
        if let Some(e) = self.tracking_error {
            check_within("tracking_error", e, 0.0, 0.1)?;
        }
        check_count("candidates", self.candidates as u64, 64, 4_000_000)
    }
}

/// Candidates of each held-out window's search: the model's error needs each fit found, not
/// the last digit of its state.
const HELD_OUT_CANDIDATES: usize = 4096;

/// Fits `p` to the `track` in the settings' window and forecasts to `end` (s).
pub fn fit_and_forecast(
    track: &TrackRows,
    p: &Params,
    settings: &ForecastSettings,
    end: f64,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Outcome> {
    let (t, data) = (track.t, track.data);
    let (first, last) = (t[0], t[t.len() - 1]);
    let window = settings
        .window
        .unwrap_or_else(|| (t[1], t[1] + track.default_window()));
    let tolerance = settings
        .tolerance
        .unwrap_or_else(|| TrackRows::default_tolerance(p));
    let (a, b) = window;
    if !(a.is_finite() && b.is_finite() && a < b && a >= first - 1e-6 && b < last) {
        return Err(Error::invalid(
            "window",
            format!(
                "{a}:{b} must be START:END with START < END within the data's times {first}..{last} s, END before the last row (the forecast runs past it)"
            ),
        ));
    }
    let times = band_times(a, end, t).len();
    let most = most_members(times);
    if settings.members > most {
        return Err(Error::invalid(
            "members",
            format!(
                "{} members over {times} band times need {} GiB of positions; at most {most} fit the budget of {} GiB",
                settings.members,
                (settings.members as u64 * times as u64 * 16) >> 30,
                forecast::POSITION_BUDGET >> 30
            ),
        ));
    }
    let fit = fit_window(track, p, window, settings.candidates, engine, monitor)?;
    let tracking_error = settings.tracking_error.unwrap_or(fit.tracking_error);
    let spec = ForecastSpec {
        members: settings.members,
        seed: settings.seed,
        tolerance,
        tracking_error,
        end,
        data_times: t.to_vec(),
    };
    // The window ends at its last row.
    let window_end = t[fit.row0 + fit.rows - 1];
    let mut forecast = forecast::forecast(&fit, window_end, &spec, engine, monitor)?;
    // The model's own error, from windows of the same recording held out from this one,
    // each followed as far as this forecast's lead (a model's lag keeps growing on a
    // pendulum that is not chaotic: a shorter reach would hold its last value on).
    let lead = end - window_end;
    let held = crate::fit::model_error::HeldOut {
        window,
        windows: settings.held_out,
        lead,
        candidates: settings.candidates.min(HELD_OUT_CANDIDATES),
    };
    if let Some(error) = crate::fit::model_error::estimate(track, p, &held, engine, monitor)? {
        let velocity = fit.velocities(&forecast.times);
        forecast.widen(error, &velocity, (p.l1, p.l1 + p.l2), tolerance);
    }
    let (data_horizon, run, data_coverage) = forecast::data_horizon(&forecast, t, data);
    // The median within 5 % of the reach, the measure a forecast is judged by here.
    let scores = forecast::scores(&forecast, t, data, 0.05 * (p.l1 + p.l2));
    let rms = (fit.chi2 / (4 * fit.rows) as f64).sqrt();
    let verdict = Verdict::judge(rms, t, data, p.l1 + p.l2);
    Ok(Outcome {
        scores,
        verdict,
        window,
        tolerance,
        fit,
        forecast,
        tracking_error,
        data_horizon,
        run,
        data_coverage,
    })
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
        let overlay = super::overlay::Overlay {
            rows: &frames,
            geometry,
            pivot: (pivot.x, pivot.y),
            outcome: &o,
            tolerance: o.tolerance,
        };
        let meta = crate::render::provenance(command.clone(), &engine.info());
        super::overlay::write(
            &mut files,
            &out.join(OVERLAY),
            video,
            &overlay,
            &meta,
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

/// The fit as JSON: values, errors, covariance in [`FITTED`]'s order.
pub fn fit_json(fit: &WindowFit) -> serde_json::Value {
    let cov: Vec<Vec<f64>> = (0..FITTED.len())
        .map(|i| (0..FITTED.len()).map(|j| fit.covariance[(i, j)]).collect())
        .collect();
    json!({
        "t0": fit.t0, "rows": fit.rows, "first_row": fit.row0,
        "names": FITTED, "values": fit.values, "errors": fit.errors, "covariance": cov,
        "tracking_error_correlation": fit.correlation,
        "chi2": fit.chi2, "dof": fit.dof, "rms_residual": (fit.chi2 / (4 * fit.rows) as f64).sqrt(),
        "candidates": fit.candidates, "searched_on": fit.backend,
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
