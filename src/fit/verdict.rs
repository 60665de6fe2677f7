//! Whether a fit follows the data in its window: it is judged against the tracking error the
//! rigid rods measure ([`super::window::rod_correlation`]), with what the times' rounding
//! adds; a model that strays from the data by many times that is no model of this pendulum,
//! and its horizons are no findings.

use super::window::rod_correlation;

/// How many times the tracking error a fit may stray from the data in its window and still
/// be said to follow them. A model that is right strays by the tracking error; the rods
/// measure it only along themselves, and errors along the motion (a frame's timing, blur, a
/// marker tracked by hand) are often a few times larger: the lab's hand-measured table
/// strays 6.5 times its rods' error from the lab's own apparatus, the shared high-speed
/// recording 1.3 times from its identified model. The failures this guards against stray
/// by 70-200 times (the lab's apparatus forced on another pendulum: 106 to 147).
pub const FOLLOWS_WITHIN: f64 = 8.0;

/// The tracking error a fit is judged against never goes below this share of the reach
/// (l1 + l2). The rods see only errors across the arms; positions made from an encoder's
/// angles lie on their rods exactly, while its counts (a 12-bit encoder's 1.5 mrad moves a
/// 0.2 m arm's end by 0.1 mm RMS), like a frame's timing, err along the motion. A fit that
/// strays from such a track by under FOLLOWS_WITHIN thousandths of the reach still follows
/// it; the failures this guards against stray by several hundredths.
pub const TRACKING_FLOOR: f64 = 1e-3;

/// Whether a fit follows the data in its window.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Verdict {
    pub follows: bool,
    /// The fit's RMS residual per coordinate in the window (m).
    pub rms: f64,
    /// The tracking error per coordinate (m): what the rigid rods measure over the whole
    /// track, with what the times' rounding moves a mass along its path, floored at
    /// [`TRACKING_FLOOR`] of the reach.
    pub tracking_error: f64,
    /// Its parts: along the rods (m), and the times' rounding (s, as written in the file)
    /// times the masses' RMS speed per coordinate.
    pub rods: f64,
    pub time_rounding: f64,
    /// rms / tracking_error, and the most it may be ([`FOLLOWS_WITHIN`]).
    pub ratio: f64,
    pub limit: f64,
}

/// The rounding of the times `t` (s): the step to which they are written (the largest
/// power of ten of which every time is a whole multiple, 0.001 for 0.333, 0.667, 1.0),
/// where the steps between rows show it (they differ by that much: a clock of 1/3 s written
/// to milliseconds); 0 where they do not (a clock of 1/200 s written exactly).
pub fn time_quantum(t: &[f64]) -> f64 {
    let q = (0..=9)
        .map(|d| 10f64.powi(-d))
        .find(|q| {
            t.iter()
                .all(|x| ((x / q) - (x / q).round()).abs() < 1e-6 * (1.0 + (x / q).abs() * 1e-9))
        })
        .unwrap_or(0.0);
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let Some(median) = crate::stats::median(&mut steps) else {
        return 0.0;
    };
    let rounded = steps.iter().any(|s| {
        let off = (s - median).abs();
        off > 0.5 * q && off < 1.5 * q
    });
    if rounded { q } else { 0.0 }
}

/// The RMS speed per coordinate of both masses (m/s), by central differences.
fn speed_per_coordinate(t: &[f64], data: &[[f64; 4]]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 1..t.len().saturating_sub(1) {
        let h = t[i + 1] - t[i - 1];
        for (after, before) in data[i + 1].iter().zip(&data[i - 1]) {
            let v = (after - before) / h;
            if v.is_finite() {
                sum += v * v;
                n += 1;
            }
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

impl Verdict {
    /// Judges a fit that strays from the track (`t`, `data`: positions relative to the
    /// pivot) by `rms` per coordinate in its window, for a pendulum of `reach` (m).
    pub fn judge(rms: f64, t: &[f64], data: &[[f64; 4]], reach: f64) -> Verdict {
        let rods = rod_correlation(data).rms;
        // A time written to 0.01 s is off by up to 5 ms, uniformly: sd q / sqrt 12, which
        // moves a mass along its path by that times its speed.
        let time_rounding = time_quantum(t) / 12f64.sqrt() * speed_per_coordinate(t, data);
        let tracking_error = rods.hypot(time_rounding).max(TRACKING_FLOOR * reach);
        let ratio = rms / tracking_error;
        Verdict {
            follows: ratio.is_finite() && ratio <= FOLLOWS_WITHIN,
            rms,
            tracking_error,
            rods,
            time_rounding,
            ratio,
            limit: FOLLOWS_WITHIN,
        }
    }

    /// One line for the console.
    pub fn describe(&self) -> String {
        match self.follows {
            true => format!(
                "the model follows the data in the window: RMS {:.3} mm per coordinate, {:.1} times the tracking error ({})",
                1e3 * self.rms,
                self.ratio,
                self.error_parts()
            ),
            false => format!(
                "THE MODEL DOES NOT FOLLOW THE DATA: in the window it strays by {:.3} mm RMS per coordinate, {:.1} times the tracking error ({}; at most {} times is a fit); its horizons are no findings. State the pendulum's model (a preset or params), or try another window",
                1e3 * self.rms,
                self.ratio,
                self.error_parts(),
                self.limit
            ),
        }
    }

    fn error_parts(&self) -> String {
        let mm = |x: f64| format!("{:.3} mm", 1e3 * x);
        match self.time_rounding > 0.1 * self.rods {
            true => format!(
                "{}: {} along the rigid rods, {} from the times' rounding",
                mm(self.tracking_error),
                mm(self.rods),
                mm(self.time_rounding)
            ),
            false => format!("{} along the rigid rods", mm(self.tracking_error)),
        }
    }
}
