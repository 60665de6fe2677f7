//! Ensemble forecasts from a [`WindowFit`]: members drawn from the fit's covariance (state and
//! joint damping), integrated together on the engine past the window, their quantile bands
//! at every time (the model's, and a measurement's with the tracking error added), the
//! horizons, and the finite-time Lyapunov exponent along the fitted orbit.

use nalgebra::Matrix4;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64;
use rayon::prelude::*;

pub use super::members::{Members, draw_members, effective_freedom};
use crate::cpu;
use crate::engine::Engine;
use crate::error::Result;
use crate::fit::window::{STEPS_PER_SECOND, WindowFit};
use crate::model::State;
use crate::monitor::Monitor;
use crate::spec::{EnsembleSpec, Keep};
pub use crate::stats::QUANTILES;
use crate::stats::quantiles;

/// Spacing (s) of the bands' times between the data's own: smooth curves in the pictures.
pub const BAND_STEP: f64 = 0.02;

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
    /// The data's step between rows (s): past the last row the bands go on at it.
    pub cadence: f64,
    /// The model's own error (held-out windows or a calibration), which widens the
    /// measurement bands ([`Forecast::widen`]) and each member's departure ([`departed`]).
    pub model_error: Option<super::model_error::ModelError>,
    /// The bands' factors by lead from a calibration ([`Forecast::rescale`]).
    pub band_factors: Option<super::calibration::BandFactors>,
}

/// A forecast's tolerance unless given: 5 % of the reach l1 + l2 of `p`. One tolerance
/// judges everything a forecast says: the headline horizon, the ensemble's spread, and how
/// long the median followed the data.
pub fn default_tolerance(p: &crate::model::Params) -> f64 {
    TOLERANCE_SHARE * (p.l1 + p.l2)
}

/// [`default_tolerance`]'s share of the reach.
pub const TOLERANCE_SHARE: f64 = 0.05;

/// The data's step between rows (s): the median of the steps of `t` (0 for one row).
pub fn cadence(t: &[f64]) -> f64 {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    crate::stats::median(&mut steps).unwrap_or(0.0)
}

/// The headline horizon: how long the members' median is expected to stay within the
/// tolerance of the pendulum, with its uncertainty. Each member stands for a pendulum the
/// data allow; the lead at which its lower mass first lies farther than the tolerance from
/// the median is one draw of the horizon. Their quartiles are the horizon's uncertainty.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Headline {
    /// The members' median lead (s after the window's end) and its quartiles; None where
    /// more than half the members (a quarter, three quarters) never leave it before the
    /// forecast's end.
    pub lead: Option<f64>,
    pub lower_quartile: Option<f64>,
    pub upper_quartile: Option<f64>,
    /// The tolerance (m) and the forecast's last lead (s): a horizon past it is unknown.
    pub tolerance: f64,
    pub forecast_to: f64,
}

impl Headline {
    /// In words: "0.42 s (0.31-0.58 s)", with "over" where the members outlast the forecast.
    pub fn describe(&self) -> String {
        let at = |v: Option<f64>| {
            v.map_or(format!("over {:.2}", self.forecast_to), |v| {
                format!("{v:.2}")
            })
        };
        format!(
            "{} s ({}-{} s)",
            at(self.lead),
            at(self.lower_quartile),
            at(self.upper_quartile)
        )
    }
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
    /// The model's own error measured on held-out windows, by which the measurement bands
    /// were widened ([`Forecast::widen`]); None where none was measured.
    pub model_error: Option<super::model_error::ModelError>,
    /// When the model's own error alone first passes the tolerance ([`Forecast::widen`]).
    pub model_horizon: Option<f64>,
    /// Per member, the first band time at which its lower mass lies farther than the
    /// tolerance from the members' median (None: not before the end).
    pub departures: Vec<Option<f64>>,
    pub tolerance: f64,
}

impl Forecast {
    /// Widens the measurement bands after the window by `error`'s model part in quadrature,
    /// each side's distance from the members' median (its 50 % half-width for the 25-75 %
    /// band, its 90 % for the 5-95 %): where the model departs from this pendulum faster than
    /// its state's uncertainty spreads, the bands say so. No band reaches past where the
    /// masses can be: `reach` (m) from the pivot for the upper (l1) and the lower (l1 + l2).
    ///
    /// `own` is `error`'s 50 % and 90 % half-widths at every band time on the fitted orbit
    /// ([`super::model_error::ModelError::at`], its velocity carrying the model's lag); the
    /// model's own horizon is the first time the lower mass's 90 % half-width (its two
    /// coordinates' in quadrature) passes `tolerance`.
    pub fn widen(
        &mut self,
        error: super::model_error::ModelError,
        own: &[([f64; 4], [f64; 4])],
        reach: (f64, f64),
        tolerance: f64,
    ) {
        for (k, &t) in self.times.iter().enumerate() {
            let lead = t - self.window_end;
            if lead <= 1e-9 {
                continue;
            }
            let (half50, half90) = own[k];
            if self.model_horizon.is_none() && half90[2].hypot(half90[3]) > tolerance {
                self.model_horizon = Some(t);
            }
            for c in 0..4 {
                let median = self.model[k][c][2];
                let q = &mut self.observed[k][c];
                let below = |edge: f64, extra: f64| median - (median - edge).max(0.0).hypot(extra);
                let above = |edge: f64, extra: f64| median + (edge - median).max(0.0).hypot(extra);
                let most = if c < 2 { reach.0 } else { reach.1 };
                q[0] = below(q[0], half90[c]).max(-most).min(q[0]);
                q[1] = below(q[1], half50[c]).max(-most).min(q[1]);
                q[3] = above(q[3], half50[c]).min(most).max(q[3]);
                q[4] = above(q[4], half90[c]).min(most).max(q[4]);
            }
        }
        self.model_error = Some(error);
    }

    /// Scales the measurement bands after the window about the members' median by the
    /// calibration's factors at each lead (the 25-75 % band by its 50 % factor, the 5-95 %
    /// by its 90 %), each mass by its own; never past the `reach` (m) of each mass.
    pub fn rescale(&mut self, factors: &super::calibration::BandFactors, reach: (f64, f64)) {
        for (k, &t) in self.times.iter().enumerate() {
            let lead = t - self.window_end;
            if lead <= 1e-9 {
                continue;
            }
            for c in 0..4 {
                let (f50, f90) = factors.at(lead, c / 2);
                let most = if c < 2 { reach.0 } else { reach.1 };
                let q = &mut self.observed[k][c];
                let m = q[2];
                q[0] = (m - (m - q[0]) * f90).max(-most);
                q[1] = (m - (m - q[1]) * f50).max(-most);
                q[3] = (m + (q[3] - m) * f50).min(most);
                q[4] = (m + (q[4] - m) * f90).min(most);
            }
        }
    }

    /// The headline horizon ([`Headline`]) from the members' departures from the median.
    pub fn headline(&self) -> Headline {
        let end = self.times.last().copied().unwrap_or(self.window_end);
        let mut leads: Vec<f64> = self
            .departures
            .iter()
            .map(|d| d.map_or(f64::INFINITY, |t| t - self.window_end))
            .collect();
        leads.sort_by(f64::total_cmp);
        let at = |q: f64| {
            if leads.is_empty() {
                return None;
            }
            let k = ((q * leads.len() as f64).ceil() as usize).clamp(1, leads.len()) - 1;
            leads[k].is_finite().then_some(leads[k])
        };
        Headline {
            lead: at(0.5),
            lower_quartile: at(0.25),
            upper_quartile: at(0.75),
            tolerance: self.tolerance,
            forecast_to: end - self.window_end,
        }
    }

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

/// The bands' times: every [`BAND_STEP`] from `t0` to `end`, the data's times between, and
/// past the data's last row the times a row would have at the data's `cadence` (s; 0:
/// none), so that a forecast past the data has its bands where the next rows will lie.
pub fn band_times(t0: f64, end: f64, data: &[f64], cadence: f64) -> Vec<f64> {
    let n = ((end - t0) / BAND_STEP).floor() as usize;
    let mut times: Vec<f64> = (0..=n).map(|k| t0 + k as f64 * BAND_STEP).collect();
    times.push(end);
    times.extend(data.iter().filter(|&&x| x >= t0 - 1e-9 && x <= end + 1e-9));
    if let Some(&last) = data.last()
        && cadence > 0.0
        && end > last + cadence * 0.5
    {
        let past = ((end - last) / cadence + 1e-9).floor() as usize;
        times.extend((1..=past).map(|k| last + k as f64 * cadence));
    }
    times.sort_by(f64::total_cmp);
    times.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    times
}

/// The members' RK4 steps from `t0` to `end`: (dt, steps), the fit's step or just under. The
/// positions between two steps come from cubic Hermite interpolation (of the angles on the
/// CPU, of their carried cos and sin on the GPU), which errs by h^4/384 max|d^4 theta/dt^4|
/// times an arm: 0.14 um at most in the default twin release's fastest swing (11 um at
/// thrice the step, measured; tests/forecast.rs measures it on the truth).
pub fn stepping(t0: f64, end: f64) -> (f64, u32) {
    let steps = ((end - t0) * STEPS_PER_SECOND).ceil().max(1.0) as u32;
    ((end - t0) / steps as f64, steps)
}

/// Members from `fit` integrated to `spec.end` on `engine`, and their bands.
pub fn forecast(
    fit: &WindowFit,
    window_end: f64,
    spec: &ForecastSpec,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Forecast> {
    let Members {
        starts,
        damping,
        pivots,
        clamped,
    } = draw_members(fit, spec.members, spec.seed);
    let times = band_times(fit.t0, spec.end, &spec.data_times, spec.cadence);
    // The model's own error along the fitted orbit at each band time: its 50 % and 90 %
    // half-widths per coordinate (zero where none was measured, and up to the window's end).
    let velocity = match spec.model_error {
        Some(_) => fit.velocities(&times),
        None => Vec::new(),
    };
    let own: Vec<([f64; 4], [f64; 4])> = times
        .iter()
        .enumerate()
        .map(|(k, &t)| match &spec.model_error {
            Some(e) if t > window_end + 1e-9 => e.at(t - window_end, &velocity[k]),
            _ => ([0.0; 4], [0.0; 4]),
        })
        .collect();
    let m = spec.members;
    let (dt, steps) = stepping(fit.t0, spec.end);
    let since_start: Vec<f64> = times.iter().map(|t| t - fit.t0).collect();
    // Positions by time, then member (a time's values together for its quantiles): the
    // whole ensemble's bands straight from where they were read back when it came as one
    // chunk, else from the chunks gathered.
    let mut stats = Vec::new();
    let mut gathered: Option<Vec<f32>> = None;
    let mut departures = Vec::new();
    let ensemble = EnsembleSpec::new(fit.params, &starts, dt, steps)
        .damped(&damping)
        .keeping(Keep::At(&since_start));
    engine.ensemble(&ensemble, monitor, |first, chunk| {
        let v = chunk.positions();
        let n = v.len() / (4 * times.len());
        if n == m {
            stats = bands(v, &pivots, spec);
            departures = departed(v, &pivots, &stats, &times, window_end, &own, spec);
            return Ok(());
        }
        let values = gathered.get_or_insert_with(|| vec![0f32; times.len() * 4 * m]);
        for (row, chunk) in values.chunks_mut(m).zip(v.chunks(n)) {
            row[first..first + n].copy_from_slice(chunk);
        }
        Ok(())
    })?;
    monitor.check()?;
    if let Some(values) = gathered {
        stats = bands(&values, &pivots, spec);
        departures = departed(&values, &pivots, &stats, &times, window_end, &own, spec);
    }
    let model: Vec<Band> = stats.iter().map(|s| s.0).collect();
    let observed: Vec<Band> = stats.iter().map(|s| s.1).collect();
    let spread: Vec<f64> = stats.iter().map(|s| s.2).collect();
    let spread_horizon = crossing(&times, &spread, window_end, spec.tolerance);
    let (ftle, lyapunov) = ftle_along(fit, window_end, spec.end, dt, &times);
    let mut forecast = Forecast {
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
        model_error: None,
        model_horizon: None,
        departures,
        tolerance: spec.tolerance,
    };
    let p = &fit.params;
    if let Some(error) = &spec.model_error {
        forecast.widen(error.clone(), &own, (p.l1, p.l1 + p.l2), spec.tolerance);
    }
    if let Some(factors) = &spec.band_factors {
        forecast.rescale(factors, (p.l1, p.l1 + p.l2));
    }
    Ok(forecast)
}

/// Per member, the first band time after `after` at which its lower mass (moved by its
/// pivot) lies farther than the tolerance from the members' median (`stats`' model bands):
/// one draw each of when the median would leave a pendulum the data allow. The model's own
/// error (`own`: its 50 % half-widths per coordinate by band time) is added in quadrature,
/// each member with its own share of it: the model's error persists along an orbit (a lag
/// that grows), so a member draws once how far out in that error's distribution its
/// pendulum lies (|z| of a normal, whose median is 0.6745 of its standard deviation). A
/// member whose position is not finite has left.
fn departed(
    values: &[f32],
    pivots: &[(f64, f64)],
    stats: &[(Band, Band, f64)],
    times: &[f64],
    after: f64,
    own: &[([f64; 4], [f64; 4])],
    spec: &ForecastSpec,
) -> Vec<Option<f64>> {
    let m = pivots.len();
    let tolerance = spec.tolerance;
    let mut rng = Pcg64::seed_from_u64(spec.seed ^ 0x6a09_e667_f3bc_c908);
    let severity: Vec<f64> = (0..m)
        .map(|_| {
            let z: f64 = StandardNormal.sample(&mut rng);
            z.abs() / 0.6745
        })
        .collect();
    let mut out = vec![None; m];
    for (k, (&t, v)) in times.iter().zip(values.chunks(4 * m)).enumerate() {
        if t <= after + 1e-9 {
            continue;
        }
        let median = (stats[k].0[2][2], stats[k].0[3][2]);
        let model = own[k].0[2].hypot(own[k].0[3]);
        // The calibration's factor of the 50 % band: how much farther from the median the
        // pendulum lies at this lead than the members say.
        let factor = spec
            .band_factors
            .as_ref()
            .map_or(1.0, |b| b.at(t - after, 1).0);
        for (j, slot) in out.iter_mut().enumerate().filter(|(_, s)| s.is_none()) {
            let x = v[2 * m + j] as f64 + pivots[j].0;
            let y = v[3 * m + j] as f64 + pivots[j].1;
            let off = factor
                * (x - median.0)
                    .hypot(y - median.1)
                    .hypot(severity[j] * model);
            // A NaN position (a member that blew up) has left.
            if off.is_nan() || off > tolerance {
                *slot = Some(t);
            }
        }
    }
    out
}

/// The model's and a measurement's bands and the lower bob's spread at each time of
/// `values` (positions by time, coordinate, then member), each member's positions moved by
/// where it puts the pivot.
fn bands(values: &[f32], pivots: &[(f64, f64)], spec: &ForecastSpec) -> Vec<(Band, Band, f64)> {
    let m = pivots.len();
    // A measurement: the model's position and a tracking error, one a member and coordinate
    // drawn once for all times (a band at one time needs only the errors' distribution
    // there, and drawing 4 m errors a time cost more than the quantiles).
    let mut rng = Pcg64::seed_from_u64(spec.seed ^ 0x9e37_79b9_7f4a_7c15);
    let errors: Vec<f32> = (0..4 * m)
        .map(|_| {
            let z: f64 = StandardNormal.sample(&mut rng);
            (spec.tracking_error * z) as f32
        })
        .collect();
    let shifts: [Vec<f32>; 2] = [
        pivots.iter().map(|p| p.0 as f32).collect(),
        pivots.iter().map(|p| p.1 as f32).collect(),
    ];
    let variance = |a: &[f32]| {
        let mean = a.iter().map(|&x| x as f64).sum::<f64>() / m as f64;
        a.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / m as f64
    };
    values
        .par_chunks(4 * m)
        .map_init(
            || (vec![0f32; m], vec![0f32; m]),
            |(scratch, noisy), v| {
                let mut model = [[0.0; 5]; 4];
                let mut observed = [[0.0; 5]; 4];
                let mut spread = 0.0;
                for c in 0..4 {
                    let coord = &v[c * m..(c + 1) * m];
                    for (((s, o), &x), (&e, &d)) in scratch
                        .iter_mut()
                        .zip(noisy.iter_mut())
                        .zip(coord)
                        .zip(errors[c * m..].iter().zip(&shifts[c % 2]))
                    {
                        *s = x + d;
                        *o = *s + e;
                    }
                    if c >= 2 {
                        spread += variance(scratch);
                    }
                    model[c] = quantiles(scratch);
                    observed[c] = quantiles(noisy);
                }
                (model, observed, spread.sqrt())
            },
        )
        .collect()
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

/// Members the position budget allows over `times` band times.
pub fn most_members(times: usize) -> usize {
    (POSITION_BUDGET / (16 * times.max(1) as u64)) as usize
}
