//! A fit and forecast of one track: the window fit, the ensemble past it, the model's own
//! error from held-out windows, and how the forecast did against the data (its horizons,
//! scores and the fit's verdict). `forecast` and each of `twin`'s experiments run it.

use serde_json::json;

use super::calibration::Calibration;
use crate::engine::Engine;
use crate::error::{Error, Result, check_count, check_within};
use crate::fit::verdict::Verdict;
use crate::fit::window::{DampingPrior, FITTED, TrackRows, WindowFit, fit_window};
use crate::forecast::{self, Forecast, ForecastSpec, band_times, most_members};
use crate::model::Params;
use crate::monitor::Monitor;

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

    /// How far past its window's end (s) the forecast runs.
    pub fn lead(&self) -> f64 {
        let f = &self.forecast;
        f.times.last().copied().unwrap_or(f.window_end) - f.window_end
    }

    /// What chaos and the tracking error alone allow (s): (1/lambda) ln(tolerance / tracking
    /// error), the FTLE lambda along the fitted orbit. None where the orbit does not stretch or
    /// the data have no error.
    pub fn chaos_bound(&self) -> Option<f64> {
        let lambda = self.forecast.lyapunov;
        (lambda > 0.0 && self.tracking_error > 0.0)
            .then(|| (self.tolerance / self.tracking_error).ln() / lambda)
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
    /// the bands then hold the tracking error and the fit's uncertainty alone). Unless in
    /// sample, they lie before the forecast's window; a calibration's model error takes
    /// their place.
    pub held_out: usize,
    /// How far past the window's end to forecast (s), whether or not rows exist there.
    /// None: to the data's end.
    pub ahead: Option<f64>,
    /// Learn from every row of the file, the rows after the window included (the held-out
    /// windows spread over the whole recording): every output then says "in sample".
    pub in_sample: bool,
}

/// The most members of an ensemble: a band's 5 % quantile is good to a fraction of a percent
/// at a million; the positions' memory budget may allow fewer over a long forecast.
pub const MOST_MEMBERS: usize = 1_000_000;

/// The most held-out windows: each is a whole fit (a few seconds), and past some dozens the
/// bands' widths no longer move (Student's t at 64 windows is within 1 % of the normal).
pub const MOST_HELD_OUT: usize = 64;

/// The farthest a forecast runs past its window (s): a chaotic pendulum's forecast holds
/// for a few seconds; an ahead of minutes only fills the bands' memory.
pub const MOST_AHEAD: f64 = 600.0;

impl ForecastSettings {
    /// Checks the settings every forecast shares (the window against the data, later).
    pub fn validate(&self) -> Result<()> {
        if self.members == 0 || self.members > MOST_MEMBERS {
            return Err(Error::invalid(
                "members",
                format!("must be between 1 and {MOST_MEMBERS} (10000 draws a smooth band)"),
            ));
        }
        if let Some(tolerance) = self.tolerance {
            check_within("tolerance", tolerance, 1e-6, 1e3)?;
        }
        if let Some(e) = self.tracking_error {
            check_within("tracking_error", e, 0.0, 0.1)?;
        }
        if let Some(ahead) = self.ahead {
            check_within("ahead", ahead, 1e-3, MOST_AHEAD)?;
        }
        check_count("held_out", self.held_out as u64, 0, MOST_HELD_OUT as u64)?;
        check_count("candidates", self.candidates as u64, 64, 4_000_000)
    }
}

/// What a forecast may learn from besides the rows up to its window's end (all rows, in
/// sample): a calibration made on another recording, or another stretch of this one.
#[derive(Clone, Copy, Debug, Default)]
pub struct Learning<'a> {
    pub calibration: Option<&'a Calibration>,
    /// The joint damping the motion shows (the calibration's, or the learned rows'), which
    /// the window's fit and the held-out ones are held to.
    pub damping: Option<DampingPrior>,
}

/// The rows of `t` a forecast with `window` learns from: those up to its end (to a
/// microsecond), or all of them in sample.
pub fn learned_rows(t: &[f64], window: (f64, f64), in_sample: bool) -> usize {
    match in_sample {
        true => t.len(),
        false => t.partition_point(|&x| x <= window.1 + 1e-6),
    }
}

/// Candidates of each held-out window's search: the model's error needs each fit found, not
/// the last digit of its state.
pub const HELD_OUT_CANDIDATES: usize = 4096;

/// Fits `p` to the `track` in the settings' window and forecasts to `end` (s; the data's
/// end) or the settings' `ahead` past the window, learning only what `learning` allows.
pub fn fit_and_forecast(
    track: &TrackRows,
    p: &Params,
    settings: &ForecastSettings,
    learning: Learning,
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
        .unwrap_or_else(|| forecast::default_tolerance(p));
    let (a, b) = window;
    // With `ahead` the window may end at the last row: the forecast runs past the data.
    let before_last = settings.ahead.is_some() || b < last;
    if !(a.is_finite()
        && b.is_finite()
        && a < b
        && a >= first - 1e-6
        && b <= last + 1e-6
        && before_last)
    {
        return Err(Error::invalid(
            "window",
            format!(
                "{a}:{b} must be START:END with START < END within the data's times {first}..{last} s, END before the last row (the forecast runs past it) unless [[ahead]] says how far to forecast"
            ),
        ));
    }
    // What the fit and its errors may learn from: the rows up to the window's end.
    let learned = learned_rows(t, window, settings.in_sample).max(1);
    let learn = TrackRows {
        t: &t[..learned],
        data: &data[..learned],
        angles: &track.angles[..learned],
    };
    let end = settings.ahead.map_or(end, |ahead| b + ahead);
    let times = band_times(a, end, t, forecast::cadence(learn.t)).len();
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
    let (prior, candidates) = (learning.damping.as_ref(), settings.candidates);
    let fit = fit_window(&learn, p, window, candidates, prior, engine, monitor)?;
    // The window ends at its last row.
    let window_end = t[fit.row0 + fit.rows - 1];
    let end = settings.ahead.map_or(end, |ahead| window_end + ahead);
    let tracking_error = settings.tracking_error.unwrap_or_else(|| {
        learning
            .calibration
            .map_or(fit.tracking_error, |c| c.tracking_error)
    });
    let lead = end - window_end;
    let held = crate::forecast::model_error::HeldOut {
        length: b - a,
        avoid: Some(window),
        windows: settings.held_out,
        lead,
        candidates: settings.candidates.min(HELD_OUT_CANDIDATES),
        phase: 0.5,
        damping: learning.damping,
    };
    // The model's own error: a calibration's, else the held-out windows' (each fitted
    // orbit followed as far as this forecast's lead: a model's lag keeps growing on a
    // pendulum that is not chaotic, and a shorter reach would hold its last value on).
    let model_error = match learning.calibration {
        Some(c) => Some(c.model_error.clone()),
        None => crate::forecast::model_error::estimate(&learn, p, &held, engine, monitor)?,
    };
    let spec = ForecastSpec {
        members: settings.members,
        seed: settings.seed,
        tolerance,
        tracking_error,
        end,
        data_times: t.to_vec(),
        cadence: forecast::cadence(learn.t),
        model_error,
        band_factors: learning.calibration.and_then(|c| c.band_factors.clone()),
    };
    let forecast = forecast::forecast(&fit, window_end, &spec, engine, monitor)?;
    let (data_horizon, run, data_coverage) = forecast::data_horizon(&forecast, t, data);
    // The median within the tolerance, the measure a forecast is judged by here.
    let scores = forecast::scores(&forecast, t, data, tolerance);
    let rms = (fit.chi2 / (4 * fit.rows) as f64).sqrt();
    let verdict = Verdict::judge(rms, learn.t, learn.data, p.l1 + p.l2);
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

/// The window when none is given and no calibration says its length: from the second row,
/// four of the motion's own times (1/RMS of the upper arm's angular velocity) and at least
/// five rows, the motion measured over the window's own rows: the rows are taken one by one
/// until they span four of the motion time they show.
pub fn own_window(read: &[crate::fit::TrackedRow]) -> Result<(f64, f64)> {
    use crate::fit::window::{WINDOW_ROWS, WINDOW_TIMES};
    let n = read.len();
    let t: Vec<f64> = read.iter().map(|f| f.t).collect();
    let step = super::ensemble::cadence(&t);
    // The window's length from the first k rows, and whether those rows span it.
    let length = |k: usize| -> Option<f64> {
        let pivot = crate::fit::fit_pivot(&read[..k]).ok()?;
        let angles = crate::fit::angles(&read[..k], (pivot.x, pivot.y));
        let rows = TrackRows {
            t: &t[..k],
            data: &[],
            angles: &angles,
        };
        let w = (WINDOW_TIMES * rows.motion_time()).max(WINDOW_ROWS as f64 * step);
        w.is_finite().then_some(w)
    };
    let spans = |k: usize| length(k).is_some_and(|w| t[1] + w <= t[k - 1] + 1e-9);
    // Doubling to rows that span their window, then the fewest that do.
    let mut k = (WINDOW_ROWS + 2).min(n);
    while !spans(k) {
        if k == n {
            return Err(Error::invalid(
                "window",
                format!(
                    "the file's {n} rows do not span four of the motion's own times: give the window, or a calibration ([[params]] written by `fit`) and [[ahead]]"
                ),
            ));
        }
        k = (2 * k).min(n);
    }
    let (mut lo, mut hi) = (k / 2, k);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        match spans(mid) {
            true => hi = mid,
            false => lo = mid,
        }
    }
    let w = length(hi).expect("spans");
    Ok((t[1], t[1] + w))
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
