//! A calibration: what `fit` learns of one pendulum from one recording that a forecast of any
//! other launch of it carries, so that the forecast learns nothing from the rows it is scored
//! on. It is written into `model.toml` beside the model (table `[calibration]`, which the
//! parameter reader leaves to this module) and read back by `forecast --params`:
//! - the recording and the span of rows it was learned from;
//! - the forecast window's length its model error was measured with;
//! - the tracking error a window fit's residuals showed (the held-out fits' median);
//! - the metre scale, where it came from the motion (a short recording cannot give one);
//! - the moments' covariance, where the model came from the motion;
//! - the model's own error ([`ModelError`]): how far the data departed from fits on held-out
//!   stretches of the recording, by the lead since each window's end.

use std::path::Path;

use serde::Deserialize;

use super::model_error::ModelError;
use crate::error::{Error, Result};
use crate::fit::window::DampingPrior;

#[derive(Clone, Debug, serde::Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The recording it was learned from (as given to `fit`), and the times (s) of the first
    /// and last rows it read.
    pub file: String,
    pub span: [f64; 2],
    /// The forecast window's length (s) the model error was measured with: a forecast with
    /// no `--window` takes it.
    pub window: f64,
    /// A measurement's error (m per coordinate) as the held-out window fits' residuals show
    /// it (their median).
    pub tracking_error: f64,
    /// Pixels per metre and its error, where the recording's scale came from its motion.
    #[serde(default)]
    pub pixels_per_metre: Option<[f64; 2]>,
    /// The pivot (m) in the recording's frame (relative to its pivot marker where it has
    /// one): a recording too short to place it takes this one.
    #[serde(default)]
    pub pivot: Option<[f64; 2]>,
    /// The moments' covariance over P (a, b, c, q, k1, k2; identify's order), where the
    /// model came from the motion.
    #[serde(default)]
    pub moment_covariance: Option<Vec<Vec<f64>>>,
    /// The joint damping the recording's motion shows (N m s on the model's scale) and its
    /// standard errors, where the model came from the motion: each window's fit is held to it.
    #[serde(default)]
    pub damping: Option<DampingPrior>,
    /// The picture's roll against gravity (rad) and its error, as the recording's motion
    /// shows it: a recording too short to show it takes this one.
    #[serde(default)]
    pub roll: Option<[f64; 2]>,
    /// The markers' offsets from the arms' axes (m: the upper marker along and across its
    /// arm, the lower marker's lean in x and y), then their errors: likewise.
    #[serde(default)]
    pub marker_offsets: Option<[[f64; 4]; 2]>,
    pub model_error: ModelError,
    /// By how much the bands are widened at each lead to hold the data (measured on held-out
    /// windows of the recording other than the model error's).
    #[serde(default)]
    pub band_factors: Option<BandFactors>,
}

/// The table's name in model.toml.
pub const TABLE: &str = "calibration";

impl Calibration {
    /// The table as TOML text, appended to a model file (every number finite: TOML has no
    /// words for NaN in the model's sense, and none arises from a fit that followed).
    pub fn to_toml(&self) -> String {
        let list = |v: &[f64]| format!("{v:?}");
        let quads = |v: &[[f64; 4]]| format!("{v:?}");
        let mut out = format!(
            "\n# What `forecast --params` carries of this pendulum beyond its model: the recording and\n\
             # span it was learned from, the tracking error, and the model's own error by the lead\n\
             # since a window's end (measured on held-out stretches of the recording).\n\
             [{TABLE}]\n\
             file = {}\n\
             span = {}  # s\n\
             window = {}  # s: the forecast window's length the model error was measured with\n\
             tracking_error = {}  # m per coordinate\n",
            toml_string(&self.file),
            list(&self.span),
            self.window,
            self.tracking_error,
        );
        if let Some(ppm) = self.pixels_per_metre {
            out.push_str(&format!(
                "pixels_per_metre = {}  # and its error, from the motion\n",
                list(&ppm)
            ));
        }
        if let Some(p) = self.pivot {
            out.push_str(&format!(
                "pivot = {}  # m, in the recording's frame (relative to its pivot marker where it has one)\n",
                list(&p)
            ));
        }
        if let Some(r) = self.roll {
            out.push_str(&format!(
                "roll = {}  # rad and its error: the picture's down against gravity's, from the motion\n",
                list(&r)
            ));
        }
        if let Some([o, e]) = self.marker_offsets {
            out.push_str(&format!(
                "marker_offsets = [{}, {}]  # m, then their errors: the upper marker along and across its arm from the joint, the lower marker's lean (x, y)\n",
                list(&o),
                list(&e)
            ));
        }
        if let Some(c) = &self.moment_covariance {
            let rows: Vec<String> = c.iter().map(|r| list(r)).collect();
            out.push_str(&format!(
                "moment_covariance = [{}]  # a, b, c, q, k1, k2 over P\n",
                rows.join(", ")
            ));
        }
        if let Some(d) = &self.damping {
            out.push_str(&format!(
                "\n[{TABLE}.damping]  # N m s on the model's scale, as the motion shows it: each window's fit is held to it\n\
                 damping = {}  # at the pivot and the middle joint\n\
                 error = {}  # their standard errors\n",
                list(&d.damping),
                list(&d.error),
            ));
        }
        let e = &self.model_error;
        let windows: Vec<[f64; 2]> = e.windows.iter().map(|w| [w.0, w.1]).collect();
        out.push_str(&format!(
            "\n[{TABLE}.model_error]  # bins of `step` s of lead; lags in s, the rest in m (x1, y1, x2, y2)\n\
             step = {}\n\
             tracking_error = {}\n\
             lag50 = {}\n\
             lag90 = {}\n\
             q50 = {}\n\
             q90 = {}\n\
             model_lag50 = {}\n\
             model_lag90 = {}\n\
             m50 = {}\n\
             m90 = {}\n\
             windows = {windows:?}\n\
             unfollowed = {}\n",
            e.step,
            e.tracking_error,
            list(&e.lag50),
            list(&e.lag90),
            quads(&e.q50),
            quads(&e.q90),
            list(&e.model_lag50),
            list(&e.model_lag90),
            quads(&e.m50),
            quads(&e.m90),
            e.unfollowed,
        ));
        if let Some(b) = &self.band_factors {
            let pairs = |v: &[[f64; 2]]| format!("{v:?}");
            out.push_str(&format!(
                "\n[{TABLE}.band_factors]  # per bin of `step` s of lead: [upper mass, lower mass]\n\
                 step = {}\n\
                 f50 = {}\n\
                 f90 = {}\n\
                 windows = {}\n\
                 scored = {:?}\n",
                b.step,
                pairs(&b.f50),
                pairs(&b.f90),
                b.windows,
                b.scored,
            ));
        }
        out
    }

    /// Where a forecast runs `lead` s past its window, beyond the lead to which this
    /// calibration measured the model's own error: a notice saying its bands there are not
    /// calibrated.
    pub fn held_past(&self, lead: f64) -> Option<String> {
        let measured = self.model_error.step * self.model_error.m50.len() as f64;
        (lead > measured + 1e-9).then(|| format!(
            "the calibration measured the model's own error to {measured:.2} s after a window; past that its last value is held, so the bands there are not calibrated (calibrate with a longer [[lead]])"
        ))
    }

    /// The calibration in the parameter file `path`, if it holds one (`field` names the
    /// option that gave the file).
    pub fn read(field: &'static str, path: &Path) -> Result<Option<Calibration>> {
        #[derive(Deserialize)]
        struct File {
            calibration: Option<toml::Value>,
        }
        let text = crate::input::read_text(field, path, crate::input::TOML_CAP)?;
        let file: File = toml::from_str(&text)
            .map_err(|e| Error::invalid(field, format!("{}: {e}", path.display())))?;
        let Some(table) = file.calibration else {
            return Ok(None);
        };
        let c: Calibration = table.try_into().map_err(|e| {
            Error::invalid(field, format!("{}: table [{TABLE}]: {e}", path.display()))
        })?;
        c.check()
            .map_err(|reason| {
                Error::invalid(
                    field,
                    format!("{}: table [{TABLE}]: {reason}", path.display()),
                )
            })
            .map(|()| Some(c))
    }

    /// What a forecast relies on: finite, positive sizes and bins that agree in number.
    fn check(&self) -> std::result::Result<(), String> {
        let e = &self.model_error;
        let bins = e.m50.len();
        if bins == 0
            || [
                e.lag50.len(),
                e.lag90.len(),
                e.model_lag50.len(),
                e.model_lag90.len(),
            ]
            .iter()
            .chain([e.q50.len(), e.q90.len(), e.m90.len()].iter())
            .any(|&n| n != bins)
        {
            return Err("model_error's bins differ in number (or are none)".into());
        }
        let positive = [
            ("window", self.window),
            ("model_error.step", e.step),
            ("tracking_error", self.tracking_error),
        ];
        if let Some((key, v)) = positive.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
            return Err(format!("key {key}: {v} must be a finite number > 0"));
        }
        if self.damping.is_some_and(|d| !d.is_valid()) {
            return Err("damping: finite values and errors > 0".into());
        }
        // A roll is a camera's few degrees at most; an offset a fraction of the arm.
        if self
            .roll
            .is_some_and(|[r, e]| !(r.abs() < 0.2 && e.is_finite() && e >= 0.0))
        {
            return Err("key roll: [radians under 0.2 in size, error >= 0]".into());
        }
        if self.marker_offsets.is_some_and(|[o, e]| {
            !(o.iter().all(|v| v.is_finite()) && e.iter().all(|v| v.is_finite() && *v >= 0.0))
        }) {
            return Err("key marker_offsets: [four finite offsets (m), four errors >= 0]".into());
        }
        if let Some(b) = &self.band_factors {
            let ok = b.step.is_finite()
                && b.step > 0.0
                && !b.f50.is_empty()
                && b.f50.len() == b.f90.len()
                && b.f50
                    .iter()
                    .chain(&b.f90)
                    .flatten()
                    .all(|f| f.is_finite() && *f > 0.0);
            if !ok {
                return Err(
                    "band_factors: a step > 0 and as many finite factors > 0 in f50 as in f90"
                        .into(),
                );
            }
        }
        let widths = e
            .model_lag50
            .iter()
            .chain(&e.model_lag90)
            .chain(e.m50.iter().flatten())
            .chain(e.m90.iter().flatten());
        if widths.clone().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err("model_error: every width must be a finite number >= 0".into());
        }
        Ok(())
    }
}

/// `s` as a TOML basic string: quotes, backslashes and control characters escaped.
fn toml_string(s: &str) -> String {
    let mut out = String::from('"');
    for ch in s.chars() {
        match ch {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// By how much a forecast's bands must be widened (or narrowed) at each lead to hold the
/// data they were meant to hold: measured on the calibration recording by forecasting its
/// held-out windows exactly as a forecast of a new launch would (the model error measured
/// on other windows, the same members and tracking error) and scoring each forecast on the
/// rows after its window. For each row and coordinate, z is its distance from the median
/// over the band's half-width on its side; the factor of the 90 % band is the quantile of z
/// that holds 90 % of them (split conformal prediction, with the windows' count as the
/// draws: the quantile 0.9 (1 + 1/n)), the 50 % band's the median. The lag of a model's
/// orbit, grown by chaos, is what such factors catch that the model error's quadrature
/// misses.
#[derive(Clone, Debug, PartialEq, serde::Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BandFactors {
    /// The width of a lead bin (s), as the model error's.
    pub step: f64,
    /// Per bin, the upper mass's and the lower mass's factors for the 50 % and 90 % bands.
    pub f50: Vec<[f64; 2]>,
    pub f90: Vec<[f64; 2]>,
    /// The windows forecast, and the coordinates scored in each bin.
    pub windows: usize,
    pub scored: Vec<usize>,
}

/// The most a band factor may be: past it the bands hold nothing but the reach.
pub const MOST_FACTOR: f64 = 100.0;

impl BandFactors {
    /// The 50 % and 90 % factors of mass `mass` (0 upper, 1 lower) at `lead` (s): the last
    /// bin's past the leads measured.
    pub fn at(&self, lead: f64, mass: usize) -> (f64, f64) {
        let k = ((lead / self.step).floor().max(0.0) as usize).min(self.f50.len() - 1);
        (self.f50[k][mass], self.f90[k][mass])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Calibration {
        let quads = |k: f64| vec![[k, 2.0 * k, 3.0 * k, 4.5e-4 * k]; 3];
        Calibration {
            file: "runs/a \"quoted\" name\\with\tcontrols.csv".into(),
            span: [0.0, 9.9975],
            window: 0.249_014_479_855_328_35,
            tracking_error: 2.153_251_594_031_466_2e-4,
            pixels_per_metre: Some([823.794_208_122_597_5, 3.74]),
            pivot: Some([4.5e-4, -1.9e-4]),
            moment_covariance: Some(vec![vec![1.48e-9, -9.08e-11], vec![-9.08e-11, 1.02e-9]]),
            damping: Some(DampingPrior {
                damping: [-2.2e-5, 1.4e-4],
                error: [9.4e-5, 1.46e-5],
            }),
            roll: Some([5.45e-3, 1.85e-3]),
            marker_offsets: Some([[3.8e-4, -1.8e-4, -6.0e-5, -2.6e-4], [1.0e-5; 4]]),
            model_error: ModelError {
                step: 0.062_253_619_963_832_09,
                lag50: vec![1.3e-4, 5.6e-4, 1.2e-3],
                lag90: vec![4.5e-4, 1.4e-3, 3.0e-3],
                q50: quads(1e-4),
                q90: quads(3e-4),
                model_lag50: vec![4.4e-5, 0.0, 1.0e-3],
                model_lag90: vec![3.3e-4, 1.2e-3, 2.6e-3],
                m50: quads(0.0),
                m90: quads(2e-4),
                windows: vec![(0.305, 0.554), (0.91, 1.159)],
                unfollowed: 1,
                tracking_error: 2.153_251_594_031_466_2e-4,
            },
            band_factors: Some(BandFactors {
                step: 0.062_253_619_963_832_09,
                f50: vec![[0.6, 0.7], [0.79, 1.2], [0.38, 2.4]],
                f90: vec![[1.36, 3.01], [1.74, 4.67], [0.56, 3.99]],
                windows: 8,
                scored: vec![704, 704, 736],
            }),
        }
    }

    /// What `fit` writes is what `forecast` reads, to the last bit (Rust prints the shortest
    /// decimal that reads back as the same f64), and the parameter reader takes the file
    /// with its [calibration] table.
    #[test]
    fn a_calibration_reads_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.toml");
        let c = sample();
        let text = format!("m1 = 1.0\nm2 = 0.5\nl1 = 0.3\nl2 = 0.2\n{}", c.to_toml());
        std::fs::write(&path, &text).unwrap();
        assert_eq!(
            Calibration::read("params", &path).unwrap(),
            Some(c),
            "{text}"
        );
        let sources = crate::params::ParamSources {
            params: Some(path.clone()),
            ..Default::default()
        };
        assert_eq!(sources.resolve().unwrap().l2, 0.2);
    }

    /// A calibration whose bins disagree, or whose widths are negative, is refused naming the
    /// file's table; a file without one has none.
    #[test]
    fn a_damaged_calibration_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.toml");
        let mut c = sample();
        c.model_error.m90.pop();
        std::fs::write(&path, c.to_toml()).unwrap();
        let err = Calibration::read("params", &path).unwrap_err().to_string();
        assert!(
            err.contains("[calibration]") && err.contains("bins"),
            "{err}"
        );
        let mut c = sample();
        c.model_error.model_lag90[1] = -1.0;
        std::fs::write(&path, c.to_toml()).unwrap();
        let err = Calibration::read("params", &path).unwrap_err().to_string();
        assert!(err.contains("width"), "{err}");
        std::fs::write(&path, "m1 = 1.0\n").unwrap();
        assert_eq!(Calibration::read("params", &path).unwrap(), None);
    }
}
