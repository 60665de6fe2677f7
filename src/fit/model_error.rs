//! The model's own error, measured on the recording itself. An ensemble drawn from one fit's
//! covariance holds the tracking error and what the window leaves uncertain, not how far the
//! model is from the pendulum: on precise data (an encoder, a high-speed film) its bands are a
//! fraction of a millimetre wide while the real pendulum leaves them within a few
//! hundredths of a second. So the model is fitted again on other windows of the same
//! recording (held out from the forecast's own), each fitted orbit is run on past its window,
//! and how far the data lie from it is gathered by the time since the window's end. That
//! departure holds every error: the state's uncertainty grown by chaos and the tracking error
//! (which the ensemble holds already) and the model's own (air drag it lacks, a bearing's
//! friction, arms that bend). The model's own part is what the departure's quantiles exceed
//! the fit's own (its covariance carried along the orbit, to first order) by, in quadrature;
//! a forecast's bands are widened by it in quadrature. Once chaos has spread the state over
//! the motion, the fit's own error outgrows the departure and the model's part is zero: the
//! ensemble's bands stand (widening by the whole departure there would count the spread
//! twice: a band about the members' median as wide as the distance between two unrelated
//! states holds 98 % of the data, not 90 %).

use super::pendulum::Verdict;
use super::window::{TrackRows, fit_window};
use crate::engine::Engine;
use crate::error::Result;
use crate::model::Params;
use crate::monitor::Monitor;

/// Quantiles of the departure of fitted orbits from the data, by lead time.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ModelError {
    /// The width of a lead bin (s); bin k holds leads from k step to (k + 1) step.
    pub step: f64,
    /// Per bin and coordinate (x1, y1, x2, y2): the 50 % and 90 % quantiles of |data - orbit|
    /// (m), the departure itself.
    pub q50: Vec<[f64; 4]>,
    pub q90: Vec<[f64; 4]>,
    /// The model's own part of them (m): what they exceed the fits' own 50 % and 90 %
    /// half-widths by, in quadrature (0 where they do not).
    pub m50: Vec<[f64; 4]>,
    pub m90: Vec<[f64; 4]>,
    /// The held-out windows fitted (s), and those whose fit did not follow its data (left
    /// out).
    pub windows: Vec<(f64, f64)>,
    pub unfollowed: usize,
}

impl ModelError {
    /// The model's own 50 % and 90 % half-widths at `lead` (s after a window's end): the
    /// last bin's past the leads measured.
    pub fn at(&self, lead: f64) -> ([f64; 4], [f64; 4]) {
        let k = ((lead / self.step).floor().max(0.0) as usize).min(self.m50.len() - 1);
        (self.m50[k], self.m90[k])
    }

    /// The lead (s) at which the lower mass's own 90 % model error (its two coordinates' in
    /// quadrature) first passes `tolerance`.
    pub fn horizon(&self, tolerance: f64) -> Option<f64> {
        self.m90
            .iter()
            .position(|q| q[2].hypot(q[3]) > tolerance)
            .map(|k| k as f64 * self.step)
    }
}

/// Held-out windows fitted by default.
pub const HELD_OUT: usize = 8;

/// Which windows to hold out and how far to follow them.
#[derive(Clone, Copy, Debug)]
pub struct HeldOut {
    /// The forecast's own window (s): the held-out ones are as long and clear of it.
    pub window: (f64, f64),
    /// How many windows, spread evenly over the recording.
    pub windows: usize,
    /// How far past each window's end its fitted orbit is followed (s).
    pub lead: f64,
    /// Candidates of each window's search.
    pub candidates: usize,
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
    let HeldOut {
        window,
        windows: held_out,
        lead,
        candidates,
    } = *held;
    let t = track.t;
    let (first, last) = (t[1], t[t.len() - 1]);
    let length = window.1 - window.0;
    // Each window needs some lead after it: a quarter of its own length at least.
    let latest = last - length - 0.25 * length;
    if held_out == 0 || latest <= first {
        return Ok(None);
    }
    let step_rows = t.len() as f64 / (last - t[0]).max(1e-12);
    let step = (0.25 * length).max(2.0 / step_rows);
    let bins = (lead / step).ceil().max(1.0) as usize;
    // Per bin: each row's departure |data - orbit| and the fit's own standard error there.
    let mut departures: Vec<Vec<[f64; 4]>> = vec![Vec::new(); bins];
    let mut own: Vec<Vec<[f64; 4]>> = vec![Vec::new(); bins];
    let (mut windows, mut unfollowed) = (Vec::new(), 0);
    // Evenly spread over the recording; one that overlaps the forecast's window is moved
    // past it (or dropped where there is no room).
    let starts: Vec<f64> = (0..held_out)
        .map(|k| first + (latest - first) * (k as f64 + 0.5) / held_out as f64)
        .filter(|&s| s + length <= window.0 || s >= window.1)
        .collect();
    let reach = p.l1 + p.l2;
    for s in starts {
        monitor.check()?;
        let w = (s, s + length);
        let Ok(fit) = fit_window(track, p, w, candidates, engine, &monitor.quiet()) else {
            continue;
        };
        let rms = (fit.chi2 / (4 * fit.rows) as f64).sqrt();
        if !Verdict::judge(rms, t, track.data, reach).follows {
            unfollowed += 1;
            continue;
        }
        let end = t[fit.row0 + fit.rows - 1];
        let after: Vec<usize> = (fit.row0 + fit.rows..t.len())
            .take_while(|&i| t[i] - end <= lead)
            .collect();
        if after.is_empty() {
            continue;
        }
        let times: Vec<f64> = after.iter().map(|&i| t[i]).collect();
        let orbit = fit.positions(&times);
        let errors = fit.position_errors(&times);
        for ((&i, o), e) in after.iter().zip(&orbit).zip(&errors) {
            let k = (((t[i] - end) / step).floor() as usize).min(bins - 1);
            departures[k].push(std::array::from_fn(|c| (track.data[i][c] - o[c]).abs()));
            // The fit's own error with the tracking error a measurement adds.
            own[k].push(std::array::from_fn(|c| e[c].hypot(fit.tracking_error)));
        }
        windows.push(w);
    }
    if windows.is_empty() {
        return Ok(None);
    }
    let quantile = |values: &[[f64; 4]], c: usize, q: f64| -> f64 {
        let mut v: Vec<f64> = values
            .iter()
            .map(|d| d[c])
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            return 0.0;
        }
        let k = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
        *v.select_nth_unstable_by(k, f64::total_cmp).1
    };
    // A normal error's 50 % and 90 % half-widths in standard deviations.
    const Z50: f64 = 0.6745;
    const Z90: f64 = 1.6449;
    let (mut q50, mut q90) = (Vec::with_capacity(bins), Vec::with_capacity(bins));
    let (mut m50, mut m90) = (Vec::with_capacity(bins), Vec::with_capacity(bins));
    // A bin with no rows (a gap) takes the one before it.
    let (mut last, mut last_model) = (([0.0; 4], [0.0; 4]), ([0.0; 4], [0.0; 4]));
    for (bin, sd) in departures.iter().zip(&own) {
        if !bin.is_empty() {
            let excess = |q: f64, z: f64, c: usize| {
                // The fit's own standard error in this bin: the root mean square.
                let s = (sd.iter().map(|e| e[c] * e[c]).sum::<f64>() / sd.len() as f64).sqrt();
                (q * q - (z * s).powi(2)).max(0.0).sqrt()
            };
            let d50: [f64; 4] = std::array::from_fn(|c| quantile(bin, c, 0.5));
            let d90: [f64; 4] = std::array::from_fn(|c| quantile(bin, c, 0.9));
            last = (d50, d90);
            last_model = (
                std::array::from_fn(|c| excess(d50[c], Z50, c)),
                std::array::from_fn(|c| excess(d90[c], Z90, c)),
            );
        }
        q50.push(last.0);
        q90.push(last.1);
        m50.push(last_model.0);
        m90.push(last_model.1);
    }
    Ok(Some(ModelError {
        step,
        q50,
        q90,
        m50,
        m90,
        windows,
        unfollowed,
    }))
}
