//! Twin experiments' tracks: the model itself as the truth, released where asked (or near
//! it, per replicate), sampled at a rate with Gaussian noise, then fitted and forecast as
//! real data are ([`super::outcome::fit_and_forecast`]), beside the truth at the forecast's
//! times. `twin` and the forecast benchmark run them.

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;

use std::path::Path;

use serde_json::json;

use super::Slope;
use super::outcome::{ForecastSettings, Learning, Outcome, fit_and_forecast};
use crate::engine::Engine;
use crate::error::Result;
use crate::fit::window::{STEPS_PER_SECOND, TrackRows, track_with};
use crate::fit::{TrackedRow, angles};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::render::Outputs;

/// The truth's steps per second: ten times the model's, so that its own error is negligible
/// beside the model's.
const TRUTH_STEPS_PER_SECOND: f64 = 10.0 * STEPS_PER_SECOND;

/// Replicate k's release: the given one (k = 0), or within 0.5 rad of it in each angle
/// (seeded): other orbits of the same character, so that the horizons average over where
/// along an orbit its stretching happens.
pub fn release(start: State, k: usize, seed: u64) -> State {
    if k == 0 {
        return start;
    }
    let mut rng = Pcg64::seed_from_u64(
        seed.wrapping_add(k as u64)
            .wrapping_mul(0x2545_f491_4f6c_dd1d),
    );
    let mut u = || {
        rand_distr::Uniform::new(-0.5, 0.5)
            .expect("a range")
            .sample(&mut rng)
    };
    State {
        theta1: start.theta1 + u(),
        theta2: start.theta2 + u(),
        ..start
    }
}

/// A track of the truth: times every 1/`rate` s over `duration`, positions with noise.
pub struct Track {
    pub t: Vec<f64>,
    pub truth: Vec<[f64; 4]>,
    pub measured: Vec<[f64; 4]>,
}

impl Track {
    /// The arms' angles of the measured positions (the pivot at the origin), as a tracked
    /// file's are found.
    pub fn angles(&self) -> Vec<(f64, f64)> {
        let frames: Vec<TrackedRow> = self
            .t
            .iter()
            .zip(&self.measured)
            .map(|(&t, m)| TrackedRow {
                t,
                x1: m[0],
                y1: m[1],
                x2: m[2],
                y2: m[3],
            })
            .collect();
        angles(&frames, (0.0, 0.0))
    }
}

pub fn make_track(
    p: &Params,
    start: State,
    rate: f64,
    duration: f64,
    sigma: f64,
    seed: u64,
) -> Track {
    let n = (duration * rate).round() as usize;
    let t: Vec<f64> = (0..=n).map(|i| i as f64 / rate).collect();
    let truth = track_with(p, start, &t, TRUTH_STEPS_PER_SECOND);
    let mut rng = Pcg64::seed_from_u64(seed);
    let measured = truth
        .iter()
        .map(|q| {
            q.map(|x| {
                let z: f64 = StandardNormal.sample(&mut rng);
                x + sigma * z
            })
        })
        .collect();
    Track { t, truth, measured }
}

/// Fits and forecasts a track as `forecast` does real data (the pivot known: the origin),
/// and the truth at the forecast's times.
pub fn experiment(
    truth: &Params,
    start: State,
    track: &Track,
    settings: &ForecastSettings,
    end: f64,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<(Outcome, Vec<[f64; 4]>)> {
    let angle = track.angles();
    let rows = TrackRows {
        t: &track.t,
        data: &track.measured,
        angles: &angle,
    };
    let o = fit_and_forecast(
        &rows,
        truth,
        settings,
        Learning::default(),
        end,
        engine,
        monitor,
    )?;
    // The truth at the bands' times, from the release.
    let mut times = vec![0.0];
    times.extend(o.forecast.times.iter().filter(|&&x| x > 0.0));
    let mut at = track_with(truth, start, &times, TRUTH_STEPS_PER_SECOND);
    if o.forecast.times[0] > 0.0 {
        at.remove(0);
    }
    Ok((o, at))
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

/// What a set of twin experiments varies: every rate, noise and replicate, with the same
/// fit window, ensemble and horizon (the settings' seed the replicates' base seed).
pub struct Design<'a> {
    pub sigmas: &'a [f64],
    pub rates: &'a [f64],
    pub replicates: usize,
    pub settings: ForecastSettings,
    pub duration: f64,
    pub start: State,
}

/// The experiment a picture shows: its outcome, the truth at its times, its track, its noise
/// and rate.
pub type Shown = (Outcome, Vec<[f64; 4]>, Track, f64, f64);

/// Every experiment of `design` on `truth`: their rows, the truth inside the 90 % band over
/// all of them, and the one to picture (the highest rate's first replicate, at the noise
/// nearest 2 mm from below).
pub fn experiments(
    design: &Design,
    truth: &Params,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<(Vec<TwinRow>, f64, Option<Shown>)> {
    let mut rows = Vec::new();
    let mut shown: Option<Shown> = None;
    let (mut inside, mut counted) = (0.0, 0usize);
    let total = design.sigmas.len() * design.rates.len() * design.replicates;
    monitor.start("twins", total as u64);
    // Each experiment's own phases (search, ensemble) run without a bar of their own.
    let nested = monitor.quiet();
    for (ri, &rate) in design.rates.iter().enumerate() {
        for &sigma in design.sigmas {
            for k in 0..design.replicates {
                monitor.check()?;
                // Replicate k: its own release near the given one (k > 0) and its own noise,
                // the same for every sigma, so that sigma alone differs between them.
                let seed = design.settings.seed
                    ^ ((ri as u64) << 32 | k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                let start = release(design.start, k, design.settings.seed);
                let track = make_track(truth, start, rate, design.duration, sigma, seed);
                let settings = ForecastSettings {
                    seed,
                    ..design.settings
                };
                let (o, at) = experiment(
                    truth,
                    start,
                    &track,
                    &settings,
                    design.duration,
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
    Ok((rows, inside / counted.max(1) as f64, shown))
}

/// Per rate: the horizon against ln sigma, and the FTLE over the span where the horizons
/// fall (the stretching at each horizon against its time), both within each orbit.
pub fn slopes(rows: &[TwinRow], rates: &[f64], replicates: usize) -> Vec<Slope> {
    rates
        .iter()
        .map(|&rate| {
            let of: Vec<&TwinRow> = rows.iter().filter(|r| r.rate == rate).collect();
            let horizons = by_replicate(&of, replicates, |r| {
                r.spread_horizon.map(|h| (r.sigma.ln(), h))
            });
            let stretching = by_replicate(&of, replicates, |r| {
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
        .collect()
}

/// summary.json's table: per rate and noise, the horizons' medians, the coverage's mean.
pub fn table(rows: &[TwinRow], rates: &[f64], sigmas: &[f64]) -> Vec<serde_json::Value> {
    rates
        .iter()
        .flat_map(|&rate| sigmas.iter().map(move |&sigma| (rate, sigma)))
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
        .collect()
}

/// twin.csv: one line per experiment, `command` in its header.
pub fn write_csv(files: &mut Outputs, path: &Path, command: &str, rows: &[TwinRow]) -> Result<()> {
    files.write(path, |w| {
        use std::io::Write;
        writeln!(w, "# {command}")?;
        writeln!(w, "# horizons in s after the window's end (empty: beyond the track); coverage: the truth inside the model's 90 % band before the spread horizon; lyapunov (1/s) along the fitted orbit")?;
        writeln!(w, "sigma,rate,replicate,spread_horizon,data_horizon,coverage,lyapunov,stretching,tracking_error,damping1,damping2")?;
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        for r in rows {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{}",
                r.sigma, r.rate, r.replicate, opt(r.spread_horizon), opt(r.data_horizon),
                opt(r.coverage), r.lyapunov, opt(r.stretching), r.tracking_error, r.damping.0, r.damping.1
            )?;
        }
        Ok(())
    })
}

/// The horizons of every rate's experiments against their noise, for the picture.
pub fn horizon_series(rows: &[TwinRow], rates: &[f64]) -> Vec<(f64, Vec<(f64, f64)>)> {
    rates
        .iter()
        .map(|&rate| {
            let points = rows
                .iter()
                .filter(|r| r.rate == rate && r.sigma > 0.0)
                .filter_map(|r| r.spread_horizon.map(|h| (r.sigma, h)))
                .collect();
            (rate, points)
        })
        .collect()
}
