//! A calibration made on one recording ([`calibrate`], which `fit` runs): the model's own
//! error on held-out stretches of it, and the bands' factors by lead ([`BandFactors`]) from
//! forecasts of other held-out stretches, each forecast as a new launch would be and scored
//! on the rows after it.

use super::calibration::{BandFactors, Calibration, MOST_FACTOR};
use super::model_error::{HeldOut, ModelError, estimate};
use crate::engine::Engine;
use crate::error::Result;
use crate::fit::window::{DampingPrior, TrackRows};
use crate::model::Params;
use crate::monitor::Monitor;

/// What a calibration is asked for, and what the recording's fit already knows.
pub struct Asked<'a> {
    /// The recording (as given), and the forecast window's length (s).
    pub file: String,
    pub window: f64,
    /// Held-out stretches (half measure the model error, half the bands' factors), how far
    /// past each they are followed (s), and the candidates of each stretch's fit.
    pub held_out: usize,
    pub lead: f64,
    pub candidates: usize,
    /// Pixels per metre and its error where the scale came from the motion; the pivot (m).
    pub pixels_per_metre: Option<(f64, f64)>,
    pub pivot: (f64, f64),
    /// The moments' covariance, where the model came from the motion.
    pub moment_covariance: Option<&'a nalgebra::DMatrix<f64>>,
    /// The joint damping the recording's motion shows, which each stretch's fit is held to
    /// (and a forecast's, after).
    pub damping: Option<DampingPrior>,
    /// The picture's roll and the markers' offsets from the axes (m) the recording shows.
    pub roll: Option<crate::fit::level::Roll>,
    pub offsets: Option<crate::fit::joint::Offsets>,
}

/// The calibration of `p` on the recording `rows`: the model's own error on half the
/// held-out stretches and the bands' factors from forecasts of the other half, interleaved
/// with the first. None where no stretch fits and follows its data.
pub fn calibrate(
    rows: &TrackRows,
    p: &Params,
    asked: &Asked,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Option<Calibration>> {
    let n = asked.held_out;
    let held = HeldOut {
        length: asked.window,
        avoid: None,
        windows: n.div_ceil(2),
        lead: asked.lead,
        candidates: asked.candidates.min(super::outcome::HELD_OUT_CANDIDATES),
        phase: 0.5,
        damping: asked.damping,
    };
    let Some(model_error) =
        estimate(rows, p, &held, engine, monitor)?.filter(|e| e.tracking_error.is_finite())
    else {
        return Ok(None);
    };
    let band_factors = match n >= 2 {
        true => {
            let run = FactorRun {
                held: HeldOut {
                    windows: n / 2,
                    phase: 0.0,
                    ..held
                },
                model_error: &model_error,
                members: FACTOR_MEMBERS,
                seed: 1,
                tolerance: super::ensemble::default_tolerance(p),
            };
            band_factors(rows, p, &run, engine, monitor)?
        }
        false => None,
    };
    let t = rows.t;
    Ok(Some(Calibration {
        file: asked.file.clone(),
        span: [t[0], t[t.len() - 1]],
        window: asked.window,
        tracking_error: model_error.tracking_error,
        pixels_per_metre: asked.pixels_per_metre.map(|(v, e)| [v, e]),
        pivot: Some([asked.pivot.0, asked.pivot.1]),
        moment_covariance: asked.moment_covariance.map(|c| {
            (0..c.nrows())
                .map(|i| c.row(i).iter().copied().collect())
                .collect()
        }),
        damping: asked.damping,
        roll: asked.roll.map(|r| [r.roll, r.error]),
        marker_offsets: asked
            .offsets
            .map(|o| [[o.along, o.across, o.lower.0, o.lower.1], o.errors]),
        model_error,
        band_factors,
    }))
}

/// A calibration's model error, tracking error and bands' factors measured again on the
/// rows just before a forecast's `window` (as long a stretch as the calibration's span,
/// with as many held-out stretches and the same lead), the model and the rest kept: the
/// pendulum loses energy, and a model's error where it whirled (a recording's early
/// stretch, where a calibration is usually made) is not its error where it swings. On IBM's
/// runs 0, 3 and 4, each calibrated on its first 10 s, the 90 % band held 0.98 of the data
/// after it; with its error measured again on the 10 s before each window, 0.95
/// (`scripts/forecast-bench`). Returns the calibration
/// so refreshed and the span (s) it was measured on; None where the rows before the window
/// are fewer than that, or no stretch of them fits and follows.
pub fn refreshed(
    c: &Calibration,
    rows: &TrackRows,
    p: &Params,
    window: (f64, f64),
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Option<(Calibration, [f64; 2])>> {
    let span = c.span[1] - c.span[0];
    let t = rows.t;
    let from = window.0 - span;
    if !span.is_finite() || span <= 0.0 || t.first().is_none_or(|&t0| t0 > from) {
        return Ok(None);
    }
    let first = t.partition_point(|&x| x < from);
    let last = t.partition_point(|&x| x < window.0);
    let recent = TrackRows {
        t: &t[first..last],
        data: &rows.data[first..last],
        angles: &rows.angles[first..last],
    };
    let e = &c.model_error;
    let asked = Asked {
        file: String::new(),
        window: c.window,
        held_out: e.windows.len() + c.band_factors.as_ref().map_or(0, |b| b.windows),
        lead: e.step * e.m50.len() as f64,
        candidates: super::outcome::HELD_OUT_CANDIDATES,
        pixels_per_metre: None,
        pivot: (0.0, 0.0),
        moment_covariance: None,
        damping: c.damping,
        roll: None,
        offsets: None,
    };
    let quiet = monitor.quiet();
    Ok(calibrate(&recent, p, &asked, engine, &quiet)?.map(|new| {
        let again = Calibration {
            tracking_error: new.tracking_error,
            model_error: new.model_error,
            band_factors: new.band_factors,
            ..c.clone()
        };
        (again, new.span)
    }))
}

/// What [`band_factors`] forecasts each held-out window with.
pub struct FactorRun<'a> {
    pub held: HeldOut,
    pub model_error: &'a ModelError,
    pub members: usize,
    pub seed: u64,
    pub tolerance: f64,
}

/// Members of each held-out window's forecast: a 90 % band's edges to a few percent.
pub const FACTOR_MEMBERS: usize = 1000;

/// Measures [`BandFactors`] on `track` (the calibration recording) with the model `p`.
pub fn band_factors(
    track: &TrackRows,
    p: &Params,
    run: &FactorRun,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Option<BandFactors>> {
    use super::ensemble::{ForecastSpec, cadence, forecast};
    use crate::fit::window::fit_window;
    let t = track.t;
    let e = run.model_error;
    let step = e.step;
    let bins = e.m50.len();
    let quiet = monitor.quiet();
    let mut z50: Vec<[Vec<f64>; 2]> = vec![[Vec::new(), Vec::new()]; bins];
    let mut z90: Vec<[Vec<f64>; 2]> = vec![[Vec::new(), Vec::new()]; bins];
    let mut windows = 0;
    for s in run.held.starts(t) {
        monitor.check()?;
        let w = (s, s + run.held.length);
        let Ok(fit) = fit_window(
            track,
            p,
            w,
            run.held.candidates,
            run.held.damping.as_ref(),
            engine,
            &quiet,
        ) else {
            continue;
        };
        let rms = (fit.chi2 / (4 * fit.rows) as f64).sqrt();
        if !crate::fit::verdict::Verdict::judge(rms, t, track.data, p.l1 + p.l2).follows {
            continue;
        }
        let window_end = t[fit.row0 + fit.rows - 1];
        let end = (window_end + run.held.lead).min(t[t.len() - 1]);
        if end <= window_end {
            continue;
        }
        let spec = ForecastSpec {
            members: run.members,
            seed: run.seed,
            tolerance: run.tolerance,
            tracking_error: e.tracking_error,
            end,
            data_times: t.to_vec(),
            cadence: cadence(t),
            model_error: Some(e.clone()),
            band_factors: None,
        };
        let f = forecast(&fit, window_end, &spec, engine, &quiet)?;
        windows += 1;
        for (i, &ti) in t.iter().enumerate() {
            if ti <= window_end + 1e-9 || ti > end + 1e-9 {
                continue;
            }
            let Some(k) = f.index(ti) else { continue };
            let bin = (((ti - window_end) / step).floor() as usize).min(bins - 1);
            for c in 0..4 {
                let q = &f.observed[k][c];
                let (m, d) = (q[2], track.data[i][c]);
                let (h50, h90) = match d >= m {
                    true => (q[3] - m, q[4] - m),
                    false => (m - q[1], m - q[0]),
                };
                let off = (d - m).abs();
                if h50 > 0.0 {
                    z50[bin][c / 2].push(off / h50);
                }
                if h90 > 0.0 {
                    z90[bin][c / 2].push(off / h90);
                }
            }
        }
    }
    if windows == 0 {
        return Ok(None);
    }
    let quantile = |v: &[f64], q: f64| {
        crate::stats::quantile(v.to_vec(), q).map(|f| f.clamp(1.0 / MOST_FACTOR, MOST_FACTOR))
    };
    // The windows are the draws: a quantile of n of them holds a new one with the
    // conformal correction (1 + 1/n).
    let q90 = (0.9 * (1.0 + 1.0 / windows as f64)).min(1.0);
    let q50 = (0.5 * (1.0 + 1.0 / windows as f64)).min(1.0);
    let (mut f50, mut f90, mut scored) = (Vec::new(), Vec::new(), Vec::new());
    // A bin with no rows (a gap) takes the one before it (the first: no change).
    let (mut last50, mut last90) = ([1.0; 2], [1.0; 2]);
    for k in 0..bins {
        for mass in 0..2 {
            if let Some(v) = quantile(&z50[k][mass], q50) {
                last50[mass] = v;
            }
            if let Some(v) = quantile(&z90[k][mass], q90) {
                last90[mass] = v;
            }
        }
        f50.push(last50);
        f90.push(last90);
        scored.push(z90[k][0].len() + z90[k][1].len());
    }
    Ok(Some(BandFactors {
        step,
        f50,
        f90,
        windows,
        scored,
    }))
}
