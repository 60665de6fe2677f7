//! Ensemble forecasts from a [`WindowFit`]: members drawn from the fit's covariance (state and
//! joint damping), integrated together on the engine past the window, their quantile bands
//! at every time (the model's, and a measurement's with the tracking error added), the
//! horizons, and the finite-time Lyapunov exponent along the fitted orbit.

use nalgebra::{Matrix4, SymmetricEigen};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;
use rayon::prelude::*;

use super::window::{STEPS_PER_SECOND, WindowFit};
use crate::cpu;
use crate::engine::Engine;
use crate::error::Result;
use crate::model::{KeptRuns, Params, State};
use crate::monitor::Monitor;

/// Quantiles of every band: the 90 % band's ends, the 50 % band's ends, the median.
pub const QUANTILES: [f64; 5] = [0.05, 0.25, 0.5, 0.75, 0.95];

/// Spacing (s) of the bands' times between the data's own: smooth curves in the pictures.
pub const BAND_STEP: f64 = 0.02;

/// Kept states a member keeps per second (every third RK4 step): cubic Hermite
/// interpolation between them (angles with their rates) errs by h^4/384 max|d^4 theta/dt^4|
/// times an arm, at most 11 um midway between states in the default twin release's fastest
/// swing (79 um at half the rate; tests/forecast.rs measures it on the truth), a hundredth
/// of the smallest tracking noise a twin adds; half as many cost 8 % less on lavapipe.
const KEPT_PER_SECOND: f64 = 100.0;

/// Most bytes of the members' positions held at once (f32, four coordinates a time).
pub const POSITION_BUDGET: u64 = 4 << 30;

pub struct ForecastSpec {
    pub members: usize,
    pub seed: u64,
    /// The lower bob's spread (m) that ends the forecast's horizon.
    pub tolerance: f64,
    /// A measurement's error (m per coordinate) added to the model's band.
    pub tracking_error: f64,
    /// End of the forecast (s).
    pub end: f64,
    /// The data's times, to evaluate the bands at besides the regular ones.
    pub data_times: Vec<f64>,
}

/// The quantiles ([`QUANTILES`]) of the four coordinates x1, y1, x2, y2 at one time.
pub type Band = [[f64; 5]; 4];

pub struct Forecast {
    /// Where the members start (the window's first row) and where the window ends (s).
    pub t0: f64,
    pub window_end: f64,
    /// The bands' times, their model bands and measurement bands, the lower bob's spread (m,
    /// RMS distance from the members' mean) and the FTLE along the fitted orbit from the
    /// window's end (1/s; NaN up to it).
    pub times: Vec<f64>,
    pub model: Vec<Band>,
    pub observed: Vec<Band>,
    pub spread: Vec<f64>,
    pub ftle: Vec<f64>,
    /// Members drawn with a negative damping, which took zero instead.
    pub clamped: usize,
    /// The time the spread first exceeds the tolerance (None: not before the end).
    pub spread_horizon: Option<f64>,
    /// The FTLE over the whole forecast (window end to end) and the integration step.
    pub lyapunov: f64,
    pub dt: f64,
}

impl Forecast {
    /// Index of the band at time `t` (one of `times`).
    pub fn index(&self, t: f64) -> Option<usize> {
        let k = self.times.partition_point(|&x| x < t - 1e-9);
        (k < self.times.len() && (self.times[k] - t).abs() < 1e-9).then_some(k)
    }

    /// The fraction of the coordinates of `truth` (positions at `times`) inside the model's 90 %
    /// band after the window's end and before `until` (None: no time there).
    pub fn coverage(&self, truth: &[[f64; 4]], until: f64) -> Option<f64> {
        let (mut inside, mut all) = (0usize, 0usize);
        for (k, &t) in self.times.iter().enumerate() {
            if t <= self.window_end + 1e-9 || t >= until {
                continue;
            }
            for (q, x) in self.model[k].iter().zip(&truth[k]) {
                all += 1;
                inside += (q[0]..=q[4]).contains(x) as usize;
            }
        }
        (all > 0).then(|| inside as f64 / all as f64)
    }

    /// ln of the largest singular value of the tangent propagator along the fitted orbit from
    /// the window's end to the first band time at or after `t`: the e-foldings so far.
    pub fn stretching(&self, t: f64) -> Option<f64> {
        let k = self.times.partition_point(|&x| x < t);
        let k = k.min(self.times.len() - 1);
        let v = self.ftle[k] * (self.times[k] - self.window_end);
        v.is_finite().then_some(v)
    }
}

/// One sampling rate's test of the horizon against the noise: the horizon's slope against
/// ln sigma and the stretching rate lambda over the span where the horizons fall (both
/// within each orbit, with their standard errors); linear growth predicts slope = -1/lambda.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Slope {
    pub rate: f64,
    pub slope: f64,
    pub slope_error: f64,
    pub lambda: f64,
    pub lambda_error: f64,
    pub minus_one_over_lambda: f64,
    /// slope / (-1/lambda), and its error from both (relative errors in quadrature).
    pub ratio: f64,
    pub ratio_error: f64,
}

/// Draws `n` members (state and joint damping) from the fit's normal distribution; a damping
/// drawn below zero takes zero (no measurement allows a joint that pushes), and the members
/// that did are counted.
pub fn draw_members(fit: &WindowFit, n: usize, seed: u64) -> (Vec<State>, Vec<(f64, f64)>, usize) {
    let eigen = SymmetricEigen::new(fit.covariance.clone());
    // Sigma = V diag(l) V^T: a draw is the fit plus V sqrt(l) z (l < 0 from rounding: 0).
    let root = &eigen.eigenvectors
        * nalgebra::DMatrix::from_diagonal(&eigen.eigenvalues.map(|l| l.max(0.0).sqrt()));
    let mut rng = Pcg64::seed_from_u64(seed);
    let (mut starts, mut damping, mut clamped) = (Vec::with_capacity(n), Vec::with_capacity(n), 0);
    for _ in 0..n {
        let z = nalgebra::DVector::from_fn(6, |_, _| StandardNormal.sample(&mut rng));
        let d = &root * z;
        let v: [f64; 6] = std::array::from_fn(|k| fit.values[k] + d[k]);
        clamped += (v[4] < 0.0 || v[5] < 0.0) as usize;
        starts.push(State::from_array([v[0], v[1], v[2], v[3]]));
        damping.push((v[4].max(0.0), v[5].max(0.0)));
    }
    (starts, damping, clamped)
}

/// The bands' times: every [`BAND_STEP`] from `t0` to `end`, and the data's times between.
pub fn band_times(t0: f64, end: f64, data: &[f64]) -> Vec<f64> {
    let n = ((end - t0) / BAND_STEP).floor() as usize;
    let mut times: Vec<f64> = (0..=n).map(|k| t0 + k as f64 * BAND_STEP).collect();
    times.push(end);
    times.extend(data.iter().filter(|&&x| x >= t0 - 1e-9 && x <= end + 1e-9));
    times.sort_by(f64::total_cmp);
    times.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    times
}

/// Runs of `members` and the times each keeps: (dt, steps, stride).
pub fn stepping(t0: f64, end: f64) -> (f64, u32, u32) {
    let stride = (STEPS_PER_SECOND / KEPT_PER_SECOND).round() as u32;
    let kept = ((end - t0) * KEPT_PER_SECOND).ceil().max(1.0) as u32;
    let steps = kept * stride;
    ((end - t0) / steps as f64, steps, stride)
}

/// Where time `t` (s from the runs' start `t0`) falls among kept states `h` apart (`len` of
/// them): the state before it, and the cubic Hermite weights of the two states' angles
/// (h00, h01) and rates (h10 h, h11 h).
fn hermite(t: f64, t0: f64, h: f64, len: usize) -> (usize, [f64; 4]) {
    let x = ((t - t0) / h).max(0.0);
    let k = (x.floor() as usize).min(len - 2);
    let s = x - k as f64;
    let (h00, h10) = (
        2.0 * s.powi(3) - 3.0 * s * s + 1.0,
        s.powi(3) - 2.0 * s * s + s,
    );
    let (h01, h11) = (-2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
    (k, [h00, h10 * h, h01, h11 * h])
}

/// Band times placed by one task: a run's states for them lie together (16 kept states, a
/// few cache lines), where a task per time read every run's pair of states from afar.
const TIMES_PER_TASK: usize = 8;

/// The positions of the runs `kept` (the members from `first` on) at `times`, written into
/// `values` (time, then coordinate, then member of `m`), a few times per task, run by run.
fn place(
    p: &Params,
    kept: KeptRuns<'_>,
    first: usize,
    h: f64,
    t0: f64,
    times: &[f64],
    values: &mut [f32],
) {
    let m = values.len() / (4 * times.len());
    values
        .par_chunks_mut(4 * m * TIMES_PER_TASK)
        .zip(times.par_chunks(TIMES_PER_TASK))
        .for_each(|(v, times)| {
            let weights: Vec<_> = times
                .iter()
                .map(|&t| hermite(t, t0, h, kept.per_run))
                .collect();
            for i in 0..kept.len() {
                for (j, &(k, [h00, h10, h01, h11])) in weights.iter().enumerate() {
                    let (a, b) = (kept.state(i, k), kept.state(i, k + 1));
                    let at = |ta: f64, wa: f64, tb: f64, wb: f64| {
                        h00 * ta + h10 * wa + h01 * tb + h11 * wb
                    };
                    let q = p.positions(&State {
                        theta1: at(a.theta1, a.omega1, b.theta1, b.omega1),
                        omega1: 0.0,
                        theta2: at(a.theta2, a.omega2, b.theta2, b.omega2),
                        omega2: 0.0,
                    });
                    for (c, x) in [q.x1, q.y1, q.x2, q.y2].into_iter().enumerate() {
                        v[(4 * j + c) * m + first + i] = x as f32;
                    }
                }
            }
        });
}

/// The quantiles of `v` (its values reordered and rewritten in place), by the nearest rank.
/// The values become integers of the same total order (`f32::total_cmp`'s map, which is its
/// own inverse), and each rank is selected only between the ranks already in place, the
/// median first: about 2.5 n integer comparisons where five selections of f32 took 5 n.
fn quantiles(v: &mut [f32]) -> [f64; 5] {
    let n = v.len();
    let keys: &mut [i32] = bytemuck::cast_slice_mut(v);
    let order = |k: i32| k ^ (((k >> 31) as u32) >> 1) as i32;
    keys.iter_mut().for_each(|k| *k = order(*k));
    let rank = |q: f64| ((q * (n - 1) as f64).round() as usize).min(n - 1);
    let ranks = QUANTILES.map(rank);
    let mut placed: Vec<usize> = Vec::with_capacity(5);
    for i in [2, 1, 0, 3, 4] {
        let r = ranks[i];
        if placed.contains(&r) {
            continue;
        }
        let lo = placed.iter().filter(|&&x| x < r).max().map_or(0, |x| x + 1);
        let hi = placed
            .iter()
            .filter(|&&x| x > r)
            .min()
            .copied()
            .unwrap_or(n);
        keys[lo..hi].select_nth_unstable(r - lo);
        placed.push(r);
    }
    ranks.map(|r| f32::from_bits(order(keys[r]) as u32) as f64)
}

/// Members from `fit` integrated to `spec.end` on `engine`, and their bands.
pub fn forecast(
    fit: &WindowFit,
    window_end: f64,
    spec: &ForecastSpec,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Forecast> {
    let (starts, damping, clamped) = draw_members(fit, spec.members, spec.seed);
    let times = band_times(fit.t0, spec.end, &spec.data_times);
    let m = spec.members;
    let (dt, steps, stride) = stepping(fit.t0, spec.end);
    let h = dt * stride as f64;
    // Positions by time, then member: a time's values sit together for its quantiles.
    let mut values = vec![0f32; times.len() * 4 * m];
    engine.ensemble_kept_each(
        &fit.params,
        &starts,
        Some(&damping),
        dt,
        steps,
        stride,
        monitor,
        |first, kept| {
            place(&fit.params, kept, first, h, fit.t0, &times, &mut values);
            Ok(())
        },
    )?;
    monitor.check()?;
    let sigma = spec.tracking_error;
    let stats: Vec<(Band, Band, f64)> = values
        .par_chunks_mut(4 * m)
        .enumerate()
        .map(|(j, v)| {
            let spread = {
                let (x, y) = (&v[2 * m..3 * m], &v[3 * m..]);
                let var = |a: &[f32]| {
                    let mean = a.iter().map(|&x| x as f64).sum::<f64>() / m as f64;
                    a.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / m as f64
                };
                (var(x) + var(y)).sqrt()
            };
            // A measurement: the model's position and the tracking error, drawn per time
            // from a stream of its own so that the bands do not depend on the threads.
            let mut rng = Pcg64::seed_from_u64(
                spec.seed ^ (0x9e37_79b9_7f4a_7c15u64.wrapping_mul(j as u64 + 1)),
            );
            let mut model = [[0.0; 5]; 4];
            let mut observed = [[0.0; 5]; 4];
            let mut noisy = vec![0f32; m];
            for c in 0..4 {
                let coord = &mut v[c * m..(c + 1) * m];
                for (o, &x) in noisy.iter_mut().zip(coord.iter()) {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    *o = (x as f64 + sigma * z) as f32;
                }
                model[c] = quantiles(coord);
                observed[c] = quantiles(&mut noisy);
            }
            (model, observed, spread)
        })
        .collect();
    let model: Vec<Band> = stats.iter().map(|s| s.0).collect();
    let observed: Vec<Band> = stats.iter().map(|s| s.1).collect();
    let spread: Vec<f64> = stats.iter().map(|s| s.2).collect();
    let spread_horizon = crossing(&times, &spread, window_end, spec.tolerance);
    let (ftle, lyapunov) = ftle_along(fit, window_end, spec.end, dt, &times);
    Ok(Forecast {
        t0: fit.t0,
        window_end,
        times,
        model,
        observed,
        spread,
        ftle,
        clamped,
        spread_horizon,
        lyapunov,
        dt,
    })
}

/// The first time after `after` that `v` exceeds `limit`, interpolated linearly in ln v
/// between the bands' times (the spread grows exponentially).
pub fn crossing(times: &[f64], v: &[f64], after: f64, limit: f64) -> Option<f64> {
    let k = (1..times.len()).find(|&k| times[k] > after + 1e-9 && v[k] > limit)?;
    let (ta, tb) = (times[k - 1].max(after), times[k]);
    let (a, b) = (v[k - 1].max(1e-300).ln(), v[k].ln());
    if times[k - 1] < after || a >= limit.ln() || b <= a {
        return Some(tb);
    }
    Some(ta + (limit.ln() - a) / (b - a) * (tb - ta))
}

/// The largest singular value's logarithm of the tangent propagator along the fitted orbit
/// from `from` (RK4 of y and Phi together, Phi' = J(y) Phi, in steps near `dt`), as the FTLE
/// ln sigma_max / (t - from) at `times` after `from` (NaN before), and over all of it.
fn ftle_along(fit: &WindowFit, from: f64, end: f64, dt: f64, times: &[f64]) -> (Vec<f64>, f64) {
    let p = &fit.params;
    let mut y = fit.start;
    let n0 = ((from - fit.t0) / dt).round() as u32;
    let h0 = if n0 > 0 {
        (from - fit.t0) / n0 as f64
    } else {
        0.0
    };
    for _ in 0..n0 {
        y = cpu::rk4_step(p, &y, h0);
    }
    let n = ((end - from) / dt).ceil().max(1.0) as usize;
    let h = (end - from) / n as f64;
    let mut phi = Matrix4::<f64>::identity();
    // ln of a scale taken out of phi whenever it grows large (f64 holds e^700).
    let mut scale = 0.0;
    let mut logs = Vec::with_capacity(n + 1);
    logs.push(0.0);
    let f = |y: &State| nalgebra::Vector4::from(cpu::derivative(p, y).to_array());
    let state = |v: nalgebra::Vector4<f64>| State::from_array([v[0], v[1], v[2], v[3]]);
    for _ in 0..n {
        let y0 = nalgebra::Vector4::from(y.to_array());
        let k1 = (f(&y), cpu::jacobian(p, &y) * phi);
        let y2 = state(y0 + k1.0 * (h / 2.0));
        let k2 = (f(&y2), cpu::jacobian(p, &y2) * (phi + k1.1 * (h / 2.0)));
        let y3 = state(y0 + k2.0 * (h / 2.0));
        let k3 = (f(&y3), cpu::jacobian(p, &y3) * (phi + k2.1 * (h / 2.0)));
        let y4 = state(y0 + k3.0 * h);
        let k4 = (f(&y4), cpu::jacobian(p, &y4) * (phi + k3.1 * h));
        y = state(y0 + (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0) * (h / 6.0));
        phi += (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1) * (h / 6.0);
        let norm = phi.norm();
        if norm > 1e100 {
            phi /= norm;
            scale += norm.ln();
        }
        let top = (phi.transpose() * phi).symmetric_eigenvalues().max();
        logs.push(scale + 0.5 * top.ln());
    }
    let ftle = times
        .iter()
        .map(|&t| {
            if t <= from + 1e-9 {
                return f64::NAN;
            }
            let k = (((t - from) / h).round() as usize).min(n);
            logs[k] / (k as f64 * h)
        })
        .collect();
    (ftle, logs[n] / (end - from))
}

/// The first data row (its time) after the window from which a measured coordinate lies
/// outside its measurement band at `run` rows in a row: a single exit is what a calibrated
/// 90 % band shows one time in ten. `run` is the least for which a calibrated band would
/// show such a run by chance with probability under 5 % over the forecast's rows.
pub fn data_horizon(
    forecast: &Forecast,
    t: &[f64],
    data: &[[f64; 4]],
) -> (Option<f64>, usize, Option<f64>) {
    let rows: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > forecast.window_end + 1e-9 && forecast.index(t[i]).is_some())
        .collect();
    let chances = 4.0 * rows.len().max(1) as f64;
    let run = (1..)
        .find(|&k| chances * 0.1f64.powi(k) < 0.05)
        .unwrap_or(1) as usize;
    let out = |i: usize, c: usize| {
        let q = forecast.observed[forecast.index(t[i]).expect("a band time")][c];
        !(q[0]..=q[4]).contains(&data[i][c])
    };
    let horizon = (0..rows.len()).find_map(|r| {
        (0..4)
            .any(|c| r + run <= rows.len() && (r..r + run).all(|s| out(rows[s], c)))
            .then_some(t[rows[r]])
    });
    // How often the measurements lie inside the band before the spread's horizon.
    let until = forecast.spread_horizon.unwrap_or(f64::INFINITY);
    let (mut inside, mut all) = (0usize, 0usize);
    for &i in rows.iter().filter(|&&i| t[i] < until) {
        for c in 0..4 {
            all += 1;
            inside += !out(i, c) as usize;
        }
    }
    (horizon, run, (all > 0).then(|| inside as f64 / all as f64))
}

/// Members the position budget allows over `times` band times.
pub fn most_members(times: usize) -> usize {
    (POSITION_BUDGET / (16 * times.max(1) as u64)) as usize
}
