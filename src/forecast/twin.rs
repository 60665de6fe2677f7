//! Twin experiments' tracks: the model itself as the truth, released where asked (or near
//! it, per replicate), sampled at a rate with Gaussian noise, then fitted and forecast as
//! real data are ([`super::outcome::fit_and_forecast`]), beside the truth at the forecast's
//! times. `twin` and the forecast benchmark run them.

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;

use super::outcome::{ForecastSettings, Learning, Outcome, fit_and_forecast};
use crate::engine::Engine;
use crate::error::Result;
use crate::fit::window::{STEPS_PER_SECOND, TrackRows, track_with};
use crate::fit::{TrackedRow, angles};
use crate::model::{Params, State};
use crate::monitor::Monitor;

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
    let frames: Vec<TrackedRow> = track
        .t
        .iter()
        .zip(&track.measured)
        .map(|(&t, m)| TrackedRow {
            t,
            x1: m[0],
            y1: m[1],
            x2: m[2],
            y2: m[3],
        })
        .collect();
    let angle = angles(&frames, (0.0, 0.0));
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
