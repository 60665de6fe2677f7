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
    /// The moments' covariance over P (a, b, c, q, k1, k2; identify's order), where the
    /// model came from the motion.
    #[serde(default)]
    pub moment_covariance: Option<Vec<Vec<f64>>>,
    pub model_error: ModelError,
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
        if let Some(c) = &self.moment_covariance {
            let rows: Vec<String> = c.iter().map(|r| list(r)).collect();
            out.push_str(&format!(
                "moment_covariance = [{}]  # a, b, c, q, k1, k2 over P\n",
                rows.join(", ")
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
        out
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
