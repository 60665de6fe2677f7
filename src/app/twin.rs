//! `twin`: twin experiments that check the forecast against a hidden truth. Tracks made by
//! the model itself (a chaotic release of the lab pendulum with its losses), sampled like the
//! report's table or a camera, with Gaussian position noise, are fitted and forecast as real
//! data are; the truth then says whether the 90 % band holds it 90 % of the time (calibration)
//! and how the horizon falls with the noise (by ln 2 / lambda per doubling).

use std::path::PathBuf;

use serde_json::json;

use super::check_count;
use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::forecast::Slope;
use crate::forecast::outcome::{ForecastSettings, Outcome, fit_json};
use crate::forecast::plot::{self, Marks};
use crate::forecast::twin::{Track, experiment, make_track, release};
use crate::model::State;
use crate::monitor::Monitor;
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

/// One experiment's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TwinRow {
    pub sigma: f64,
    pub rate: f64,
    pub replicate: usize,
    /// Horizons (s after the window's end; None: beyond the track).
    pub spread_horizon: Option<f64>,
    pub data_horizon: Option<f64>,
    /// The truth inside the model's 90 % band, over the coordinates and times from the
    /// window's end to the spread horizon (None: the horizon came at once).
    pub coverage: Option<f64>,
    /// The FTLE along the fitted orbit over the forecast, and the stretching (e-foldings)
    /// from the window's end to the spread horizon.
    pub lyapunov: f64,
    pub stretching: Option<f64>,
    pub tracking_error: f64,
    pub damping: (f64, f64),
}

/// The slope of y on x within groups (each group's own means taken out, so that where the
/// groups lie does not enter: a fixed-effects regression), and its standard error. Groups of
/// fewer than two points add nothing.
pub fn within_slope(groups: &[Vec<(f64, f64)>]) -> (f64, f64) {
    let (mut sxx, mut sxy, mut n, mut used) = (0.0, 0.0, 0usize, 0usize);
    let centred: Vec<Vec<(f64, f64)>> = groups
        .iter()
        .filter(|g| g.len() >= 2)
        .map(|g| {
            let k = g.len() as f64;
            let (mx, my) = (
                g.iter().map(|p| p.0).sum::<f64>() / k,
                g.iter().map(|p| p.1).sum::<f64>() / k,
            );
            g.iter().map(|p| (p.0 - mx, p.1 - my)).collect()
        })
        .collect();
    for g in &centred {
        used += 1;
        for &(x, y) in g {
            sxx += x * x;
            sxy += x * y;
            n += 1;
        }
    }
    let b = sxy / sxx;
    let rss: f64 = centred
        .iter()
        .flatten()
        .map(|&(x, y)| (y - b * x).powi(2))
        .sum();
    let dof = n.saturating_sub(used + 1).max(1) as f64;
    (b, (rss / dof / sxx).sqrt())
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| sum / n as f64)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Per replicate (one orbit, every noise), the points `point(row)` of its rows that have one.
fn by_replicate(
    rows: &[&TwinRow],
    replicates: usize,
    point: impl Fn(&TwinRow) -> Option<(f64, f64)>,
) -> Vec<Vec<(f64, f64)>> {
    (0..replicates)
        .map(|k| {
            rows.iter()
                .filter(|r| r.replicate == k && r.sigma > 0.0)
                .filter_map(|r| point(r))
                .collect()
        })
        .collect()
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

pub fn run(
    job: &TwinJob,
    engine: &Engine,
    command: String,
    monitor: &Monitor,
) -> Result<TwinSummary> {
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
    super::checks::check_directory(
        "output",
        &job.output,
        &["twin.csv", "twin.png", "twin_forecast.png", "summary.json"],
        &[],
        &inputs,
    )?;
    let truth = job.params.resolve()?;
    let notices = engine.notices();
    let settings = job.settings;
    let mut rows = Vec::new();
    // The experiment pictured: (outcome, truth at its times, track, sigma, rate).
    type Shown = (Outcome, Vec<[f64; 4]>, Track, f64, f64);
    let mut shown: Option<Shown> = None;
    let (mut inside, mut counted) = (0.0, 0usize);
    let total = job.sigmas.len() * job.rates.len() * job.replicates;
    monitor.start("twins", total as u64);
    // Each experiment's own phases (search, ensemble) run without a bar of their own.
    let nested = monitor.quiet();
    for (ri, &rate) in job.rates.iter().enumerate() {
        for &sigma in &job.sigmas {
            for k in 0..job.replicates {
                monitor.check()?;
                // Replicate k: its own release near the given one (k > 0) and its own noise,
                // the same for every sigma, so that sigma alone differs between them.
                let seed = job.settings.seed
                    ^ ((ri as u64) << 32 | k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                let start = release(job.start, k, job.settings.seed);
                let track = make_track(&truth, start, rate, job.duration, sigma, seed);
                let settings = ForecastSettings { seed, ..settings };
                let (o, at) = experiment(
                    &truth,
                    start,
                    &track,
                    &settings,
                    job.duration,
                    engine,
                    &nested,
                )?;
                let f = &o.forecast;
                let until = f.spread_horizon.unwrap_or(f64::INFINITY);
                let coverage = f.coverage(&at, until);
                if let Some(c) = coverage {
                    inside += c;
                    counted += 1;
                }
                rows.push(TwinRow {
                    sigma,
                    rate,
                    replicate: k,
                    spread_horizon: o.after_window(f.spread_horizon).0,
                    data_horizon: o.after_window(o.data_horizon).0,
                    coverage,
                    lyapunov: f.lyapunov,
                    stretching: f.spread_horizon.and_then(|h| f.stretching(h)),
                    tracking_error: o.tracking_error,
                    damping: (o.fit.values[4], o.fit.values[5]),
                });
                monitor.advance(1);
                if k == 0
                    && shown
                        .as_ref()
                        .is_none_or(|s| s.4 < rate || (s.4 == rate && s.3 < 2e-3))
                {
                    shown = Some((o, at, track, sigma, rate));
                }
            }
        }
    }
    monitor.finish();
    // Per rate: the horizon against ln sigma, and the FTLE over the span where the horizons
    // fall (the stretching at each horizon against its time), both within each orbit.
    let slopes: Vec<Slope> = job
        .rates
        .iter()
        .map(|&rate| {
            let of: Vec<&TwinRow> = rows.iter().filter(|r| r.rate == rate).collect();
            let horizons = by_replicate(&of, job.replicates, |r| {
                r.spread_horizon.map(|h| (r.sigma.ln(), h))
            });
            let stretching = by_replicate(&of, job.replicates, |r| {
                Some((r.spread_horizon?, r.stretching?))
            });
            let (slope, slope_error) = within_slope(&horizons);
            let (lambda, lambda_error) = within_slope(&stretching);
            let ratio = -slope * lambda;
            Slope {
                rate,
                slope,
                slope_error,
                lambda,
                lambda_error,
                minus_one_over_lambda: -1.0 / lambda,
                ratio,
                ratio_error: ratio.abs() * (slope_error / slope).hypot(lambda_error / lambda),
            }
        })
        .collect();
    let coverage = inside / counted.max(1) as f64;

    let out = &job.output;
    let mut files = Outputs::new();
    files.write(&out.join("twin.csv"), |w| {
        use std::io::Write;
        writeln!(w, "# {command}")?;
        writeln!(w, "# horizons in s after the window's end (empty: beyond the track); coverage: the truth inside the model's 90 % band before the spread horizon; lyapunov (1/s) along the fitted orbit")?;
        writeln!(w, "sigma,rate,replicate,spread_horizon,data_horizon,coverage,lyapunov,stretching,tracking_error,damping1,damping2")?;
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        for r in &rows {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{}",
                r.sigma, r.rate, r.replicate, opt(r.spread_horizon), opt(r.data_horizon),
                opt(r.coverage), r.lyapunov, opt(r.stretching), r.tracking_error, r.damping.0, r.damping.1
            )?;
        }
        Ok(())
    })?;
    let series: Vec<(f64, Vec<(f64, f64)>)> = job
        .rates
        .iter()
        .map(|&rate| {
            let points = rows
                .iter()
                .filter(|r| r.rate == rate && r.sigma > 0.0)
                .filter_map(|r| r.spread_horizon.map(|h| (r.sigma, h)))
                .collect();
            (rate, points)
        })
        .collect();
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
    let table: Vec<serde_json::Value> = job
        .rates
        .iter()
        .flat_map(|&rate| job.sigmas.iter().map(move |&sigma| (rate, sigma)))
        .map(|(rate, sigma)| {
            let of: Vec<&TwinRow> = rows.iter().filter(|r| r.rate == rate && r.sigma == sigma).collect();
            let beyond = of.iter().filter(|r| r.spread_horizon.is_none()).count();
            json!({
                "sigma": sigma, "rate": rate, "replicates": of.len(),
                "spread_horizon_median": median(of.iter().filter_map(|r| r.spread_horizon).collect()),
                "beyond_the_track": beyond,
                "data_horizon_median": median(of.iter().filter_map(|r| r.data_horizon).collect()),
                "coverage_mean": mean(of.iter().filter_map(|r| r.coverage)),
                "coverage_undefined": of.iter().filter(|r| r.coverage.is_none()).count(),
                "lyapunov_median": median(of.iter().map(|r| r.lyapunov).collect()),
            })
        })
        .collect();
    let summary = json!({
        "command": command,
        "truth": { "parameters": crate::params::to_json(&truth), "start": job.start.to_array() },
        "window": shown.as_ref().map(|s| s.0.window), "duration": job.duration, "members": job.settings.members,
        "tolerance": shown.as_ref().map(|s| s.0.tolerance), "table": table,
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
        files: ["twin.csv", "twin.png", "twin_forecast.png", "summary.json"]
            .iter()
            .map(|n| out.join(n))
            .collect(),
        notices,
    })
}
