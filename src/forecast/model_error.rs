//! The model's own error, measured on the recording itself. An ensemble drawn from one fit's
//! covariance holds the tracking error and what the window leaves uncertain, not how far the
//! model is from the pendulum: on precise data (an encoder, a high-speed film) its bands are a
//! fraction of a millimetre wide while the real pendulum leaves them within a few
//! hundredths of a second. So the model is fitted again on other windows of the same
//! recording (held out from the forecast's own), each fitted orbit is run on past its window,
//! and how far the data lie from it is gathered by the time since the window's end. That
//! departure holds every error: the state's uncertainty grown by chaos and the tracking error
//! (which the ensemble holds already) and the model's own (air drag it lacks, a bearing's
//! friction, arms that bend). A model's error shows mostly as its orbit running early or
//! late: the departure lies along the motion, as the speed times a lag. So each row's
//! departure d is split into a lag tau along the orbit's velocity v (tau = d.v / v.v) and
//! what is left across it (d - tau v); the lag's quantiles by lead are carried to the
//! forecast's own orbit as tau times its velocity there (a pendulum swinging slower or
//! faster than the held-out windows' departs less or more), the rest as it is. The model's
//! own part is what the quantiles exceed the fit's own (its covariance carried along the
//! orbit, to first order) by, in quadrature; a forecast's bands are widened by it in
//! quadrature. Once chaos has spread the state over
//! the motion, the fit's own error outgrows the departure and the model's part is zero: the
//! ensemble's bands stand (widening by the whole departure there would count the spread
//! twice: a band about the members' median as wide as the distance between two unrelated
//! states holds 98 % of the data, not 90 %).

use crate::engine::Engine;
use crate::error::Result;
use crate::fit::verdict::Verdict;
use crate::fit::window::{DampingPrior, TrackRows, WindowFit, fit_window};
use crate::model::Params;
use crate::monitor::Monitor;

/// Quantiles of the departure of fitted orbits from the data, by lead time.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelError {
    /// The width of a lead bin (s); bin k holds leads from k step to (k + 1) step.
    pub step: f64,
    /// Per bin: the 50 % and 90 % quantiles of the lag |tau| (s), and per coordinate (x1,
    /// y1, x2, y2) those of the departure across the motion, |d - tau v| (m).
    pub lag50: Vec<f64>,
    pub lag90: Vec<f64>,
    pub q50: Vec<[f64; 4]>,
    pub q90: Vec<[f64; 4]>,
    /// The model's own part of them: what they exceed the fits' own 50 % and 90 %
    /// half-widths by, in quadrature (0 where they do not); the lag's in s, the rest in m.
    pub model_lag50: Vec<f64>,
    pub model_lag90: Vec<f64>,
    pub m50: Vec<[f64; 4]>,
    pub m90: Vec<[f64; 4]>,
    /// The held-out windows fitted (s), and those whose fit did not follow its data (left
    /// out).
    pub windows: Vec<(f64, f64)>,
    pub unfollowed: usize,
    /// The tracking error (m per coordinate) the followed windows' fits showed, their median:
    /// what a forecast that learns it from a calibration takes.
    pub tracking_error: f64,
}

impl ModelError {
    /// The model's own 50 % and 90 % half-widths at `lead` (s after a window's end) on an
    /// orbit moving at `velocity` (m/s, each coordinate's): the lag times the velocity and
    /// the departure across the motion, in quadrature. Past the leads measured, the last
    /// bin's.
    pub fn at(&self, lead: f64, velocity: &[f64; 4]) -> ([f64; 4], [f64; 4]) {
        let k = ((lead / self.step).floor().max(0.0) as usize).min(self.m50.len() - 1);
        (
            std::array::from_fn(|c| (self.model_lag50[k] * velocity[c]).hypot(self.m50[k][c])),
            std::array::from_fn(|c| (self.model_lag90[k] * velocity[c]).hypot(self.m90[k][c])),
        )
    }
}

/// A row's lag is measured where the masses move faster than this share of their RMS speed
/// after the window (both masses' velocities together).
const MOVING: f64 = 0.3;

/// Student's t quantile where the normal's is `z`, at `dof` degrees of freedom, by its
/// Cornish-Fisher expansion in 1/dof (Abramowitz and Stegun 26.7.5): within 1 % from 2
/// degrees of freedom on (2.885 for 2.920 at 95 %), 12 % low at 1.
fn student_t(z: f64, dof: f64) -> f64 {
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * dof)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * dof.powi(3))
}

fn dot(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    (0..4).map(|c| a[c] * b[c]).sum()
}

/// Held-out windows fitted by default.
pub const HELD_OUT: usize = 8;

/// Which windows to hold out and how far to follow them.
#[derive(Clone, Copy, Debug)]
pub struct HeldOut {
    /// The windows' length (s): the forecast's own.
    pub length: f64,
    /// The forecast's own window (s), which the held-out ones keep clear of (a calibration
    /// has none).
    pub avoid: Option<(f64, f64)>,
    /// How many windows, spread evenly over the recording.
    pub windows: usize,
    /// How far past each window's end its fitted orbit is followed (s).
    pub lead: f64,
    /// Where in its share of the recording each window starts (0.5: the middle; 0: the
    /// start): two sets of windows with phases 0.5 and 0 interleave.
    pub phase: f64,
    /// Candidates of each window's search.
    pub candidates: usize,
    /// What each window's fit knows of the joint damping.
    pub damping: Option<DampingPrior>,
}

impl HeldOut {
    /// The windows' starts (s) in the rows' times `t`: spread evenly over the recording, each
    /// with room for a quarter of its length after it, none overlapping the window to avoid.
    pub fn starts(&self, t: &[f64]) -> Vec<f64> {
        let (first, last) = (t[1], t[t.len() - 1]);
        let latest = last - self.length - 0.25 * self.length;
        if self.windows == 0 || latest <= first {
            return Vec::new();
        }
        let n = self.windows as f64;
        (0..self.windows)
            .map(|k| first + (latest - first) * (k as f64 + self.phase) / n)
            .filter(|&s| {
                self.avoid
                    .is_none_or(|window| s + self.length <= window.0 || s >= window.1)
            })
            .collect()
    }
}

/// The departure of the model `p` fitted on the `held` windows of the track. None where no
/// window fits (a short recording) or none follows its data.
pub fn estimate(
    track: &TrackRows,
    p: &Params,
    held: &HeldOut,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Option<ModelError>> {
    let (length, lead) = (held.length, held.lead);
    let t = track.t;
    let (first, last) = (t[1], t[t.len() - 1]);
    // Each window needs some lead after it: a quarter of its own length at least.
    let latest = last - length - 0.25 * length;
    if held.windows == 0 || latest <= first {
        return Ok(None);
    }
    let step_rows = t.len() as f64 / (last - t[0]).max(1e-12);
    let step = (0.25 * length).max(2.0 / step_rows);
    let mut bins = Bins::new((lead / step).ceil().max(1.0) as usize, step);
    let (mut windows, mut unfollowed) = (Vec::new(), 0);
    // Evenly spread over the recording; one that overlaps the forecast's window is moved
    // past it (or dropped where there is no room).
    let mut tracking_errors = Vec::new();
    let reach = p.l1 + p.l2;
    for s in held.starts(t) {
        monitor.check()?;
        let w = (s, s + length);
        let Ok(fit) = fit_window(
            track,
            p,
            w,
            held.candidates,
            held.damping.as_ref(),
            engine,
            &monitor.quiet(),
        ) else {
            continue;
        };
        let rms = (fit.chi2 / (4 * fit.rows) as f64).sqrt();
        if !Verdict::judge(rms, t, track.data, reach).follows {
            unfollowed += 1;
            continue;
        }
        tracking_errors.push(fit.tracking_error);
        if bins.add(track, &fit, lead) {
            windows.push(w);
        }
    }
    if windows.is_empty() {
        return Ok(None);
    }
    let tracking_error = crate::stats::median(&mut tracking_errors).unwrap_or(f64::NAN);
    Ok(Some(bins.summary(windows, unfollowed, tracking_error)))
}

/// The held-out windows' departures by lead, a bin every `step` s.
struct Bins {
    step: f64,
    /// Per bin: each row's lag and departure across the motion, and the fit's own standard
    /// errors of them there.
    lags: Vec<Vec<f64>>,
    own_lags: Vec<Vec<f64>>,
    departures: Vec<Vec<[f64; 4]>>,
    own: Vec<Vec<[f64; 4]>>,
    /// How many windows reach each bin: each window's departures are one draw of the model's
    /// error, so the bins' quantiles stand on this many draws.
    draws: Vec<usize>,
}

impl Bins {
    fn new(bins: usize, step: f64) -> Bins {
        Bins {
            step,
            lags: vec![Vec::new(); bins],
            own_lags: vec![Vec::new(); bins],
            departures: vec![Vec::new(); bins],
            own: vec![Vec::new(); bins],
            draws: vec![0; bins],
        }
    }

    /// The departures of the rows within `lead` after `fit`'s window from its orbit; false
    /// where no row follows the window.
    fn add(&mut self, track: &TrackRows, fit: &WindowFit, lead: f64) -> bool {
        let (t, bins) = (track.t, self.draws.len());
        let end = t[fit.row0 + fit.rows - 1];
        let after: Vec<usize> = (fit.row0 + fit.rows..t.len())
            .take_while(|&i| t[i] - end <= lead)
            .collect();
        if after.is_empty() {
            return false;
        }
        let times: Vec<f64> = after.iter().map(|&i| t[i]).collect();
        let orbit = fit.positions(&times);
        let velocity = fit.velocities(&times);
        let errors = fit.position_errors(&times);
        // A lag is measured where the pendulum moves: near a standstill of both masses any
        // departure would read as a long lag.
        let speeds: Vec<f64> = velocity.iter().map(|v| dot(v, v)).collect();
        let slow = MOVING * MOVING * speeds.iter().sum::<f64>() / speeds.len() as f64;
        let mut reached = vec![false; bins];
        for (((&i, o), v), e) in after.iter().zip(&orbit).zip(&velocity).zip(&errors) {
            let k = (((t[i] - end) / self.step).floor() as usize).min(bins - 1);
            reached[k] = true;
            let d: [f64; 4] = std::array::from_fn(|c| track.data[i][c] - o[c]);
            // The fit's own error with the tracking error a measurement adds.
            let e: [f64; 4] = std::array::from_fn(|c| e[c].hypot(fit.tracking_error));
            let vv = dot(v, v);
            let lag = if vv > slow {
                let tau = dot(&d, v) / vv;
                self.lags[k].push(tau.abs());
                // The fit's own errors along the motion, as a lag (the coordinates' errors
                // taken as independent).
                self.own_lags[k]
                    .push((0..4).map(|c| (e[c] * v[c]).powi(2)).sum::<f64>().sqrt() / vv);
                tau
            } else {
                0.0
            };
            self.departures[k].push(std::array::from_fn(|c| (d[c] - lag * v[c]).abs()));
            self.own[k].push(e);
        }
        for (n, r) in self.draws.iter_mut().zip(reached) {
            *n += r as usize;
        }
        true
    }

    /// The model error: per bin the departures' quantiles widened to prediction intervals,
    /// and the model's own part of them.
    fn summary(
        self,
        windows: Vec<(f64, f64)>,
        unfollowed: usize,
        tracking_error: f64,
    ) -> ModelError {
        let bins = self.draws.len();
        let quantile_of = |v: Vec<f64>, q: f64| crate::stats::quantile(v, q).unwrap_or(0.0);
        let quantile = |values: &[[f64; 4]], c: usize, q: f64| {
            quantile_of(values.iter().map(|d| d[c]).collect(), q)
        };
        let rms = |v: &mut dyn Iterator<Item = f64>| {
            let (sum, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
            (sum / n.max(1) as f64).sqrt()
        };
        // What a quantile `q` exceeds a normal error of standard deviation `s`'s half-width
        // (z of them) by, in quadrature.
        let excess = |q: f64, z: f64, s: f64| (q * q - (z * s).powi(2)).max(0.0).sqrt();
        // A quantile of n draws speaks for the next draw (this forecast's) only as widely as
        // a prediction interval: Student's t with n - 1 degrees of freedom for the normal z,
        // and the draws' own mean's uncertainty, sqrt(1 + 1/n). Five windows widen a 90 %
        // band by 1.42, eight by 1.22.
        let predictive = |z: f64, n: usize| match n {
            0 => 1.0,
            n => student_t(z, (n.max(2) - 1) as f64) / z * (1.0 + 1.0 / n as f64).sqrt(),
        };
        // A normal error's 50 % and 90 % half-widths in standard deviations.
        const Z50: f64 = 0.6745;
        const Z90: f64 = 1.6449;
        let mut e = ModelError {
            step: self.step,
            lag50: Vec::with_capacity(bins),
            lag90: Vec::with_capacity(bins),
            q50: Vec::with_capacity(bins),
            q90: Vec::with_capacity(bins),
            model_lag50: Vec::with_capacity(bins),
            model_lag90: Vec::with_capacity(bins),
            m50: Vec::with_capacity(bins),
            m90: Vec::with_capacity(bins),
            windows,
            unfollowed,
            tracking_error,
        };
        // A bin with no rows (a gap) takes the one before it.
        let (mut lag, mut lag_model) = ([0.0; 2], [0.0; 2]);
        let (mut across, mut across_model) = (([0.0; 4], [0.0; 4]), ([0.0; 4], [0.0; 4]));
        for k in 0..bins {
            if !self.lags[k].is_empty() {
                // The fit's own standard error in this bin: the root mean square.
                let s = rms(&mut self.own_lags[k].iter().copied());
                let n = self.draws[k];
                lag = [(0.5, Z50), (0.9, Z90)]
                    .map(|(q, z)| quantile_of(self.lags[k].clone(), q) * predictive(z, n));
                lag_model = [excess(lag[0], Z50, s), excess(lag[1], Z90, s)];
            }
            if !self.departures[k].is_empty() {
                let (bin, sd) = (&self.departures[k], &self.own[k]);
                let s: [f64; 4] = std::array::from_fn(|c| rms(&mut sd.iter().map(|e| e[c])));
                let (w50, w90) = (
                    predictive(Z50, self.draws[k]),
                    predictive(Z90, self.draws[k]),
                );
                let d50: [f64; 4] = std::array::from_fn(|c| quantile(bin, c, 0.5) * w50);
                let d90: [f64; 4] = std::array::from_fn(|c| quantile(bin, c, 0.9) * w90);
                across = (d50, d90);
                across_model = (
                    std::array::from_fn(|c| excess(d50[c], Z50, s[c])),
                    std::array::from_fn(|c| excess(d90[c], Z90, s[c])),
                );
            }
            e.lag50.push(lag[0]);
            e.lag90.push(lag[1]);
            e.model_lag50.push(lag_model[0]);
            e.model_lag90.push(lag_model[1]);
            e.q50.push(across.0);
            e.q90.push(across.1);
            e.m50.push(across_model.0);
            e.m90.push(across_model.1);
        }
        e
    }
}
