//! What a forecast learns and from where: its calibration (measured again on the rows just
//! before its window where there are enough), its window, what the rows up to the window's
//! end teach, and summary.json's `learned_from`, which names the rows or the calibration
//! behind each part.

use serde_json::json;

use super::ForecastJob;
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::forecast::calibration::Calibration;
use crate::forecast::outcome::learned_rows;
use crate::monitor::Monitor;

/// What a forecast may learn, decided before it learns anything: its calibration, its
/// window (which says which rows may teach) and what those rows taught.
pub(super) struct Learned {
    pub(super) calibration: Option<Calibration>,
    /// The span (s) of this file's rows the calibration's errors and bands were measured
    /// again on ([`crate::forecast::calibrate::refreshed`]).
    pub(super) refreshed: Option<[f64; 2]>,
    pub(super) window: (f64, f64),
    pub(super) window_from: &'static str,
    pub(super) rows: usize,
    pub(super) tracked: crate::fit::pendulum::Tracked,
    /// The joint damping each window's fit is held to: the calibration's, or the learned
    /// rows' motion's.
    pub(super) damping: Option<crate::fit::window::DampingPrior>,
}

pub(super) fn learned(
    job: &ForecastJob,
    read: &[crate::fit::TrackedRow],
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Learned> {
    // A calibration that `fit` wrote beside the model, unless in sample (where the file
    // itself teaches everything).
    let calibration = match &job.params.params {
        Some(path) if !job.settings.in_sample => Calibration::read("params", path)?,
        _ => None,
    };
    // The window, before anything is learned: it says which rows may teach.
    let (window, window_from) = match (job.settings.window, &calibration) {
        (Some(w), _) => (w, "given"),
        (None, Some(c)) => (
            (read[1].t, read[1].t + c.window),
            "the calibration's length",
        ),
        (None, None) => (
            crate::forecast::outcome::own_window(read)?,
            "four of the motion's own times, over the window's own rows",
        ),
    };
    let learn = learned_rows(
        &read.iter().map(|f| f.t).collect::<Vec<_>>(),
        window,
        job.settings.in_sample,
    )
    .max(1);
    // The pivot, arm lengths and model as `fit` finds them, from the rows that may teach.
    let pair = |key: fn(&Calibration) -> Option<[f64; 2]>| {
        calibration.as_ref().and_then(key).map(|[a, b]| (a, b))
    };
    let known = crate::fit::pendulum::Known {
        scale: pair(|c| c.pixels_per_metre),
        pivot: pair(|c| c.pivot),
        l1: match &calibration {
            Some(_) => Some(job.params.resolve()?.l1),
            None => None,
        },
        roll: pair(|c| c.roll),
        offsets: calibration
            .as_ref()
            .and_then(|c| c.marker_offsets)
            .map(|[o, errors]| crate::fit::joint::Offsets {
                along: o[0],
                across: o[1],
                lower: (o[2], o[3]),
                errors,
                from_calibration: true,
            }),
    };
    let tracked = crate::fit::pendulum::tracked_model_from(
        read,
        learn,
        &job.params,
        &job.units,
        known,
        monitor,
    )
    .map_err(|e| match e {
        Error::InvalidSpec { field: "params", reason } if !job.settings.in_sample => Error::invalid(
            "params",
            format!(
                "{reason} (a forecast learns only from the rows up to its window's end: calibrate once with `fit` on a longer recording of this pendulum and give its model.toml as [[params]])"
            ),
        ),
        e => e,
    })?;
    let damping = match &calibration {
        Some(c) => c.damping,
        None => tracked.damping_prior(),
    };
    let (rows, p) = (tracked.rows(), &tracked.params);
    let refreshed = match &calibration {
        Some(c) => crate::forecast::calibrate::refreshed(c, &rows, p, window, engine, monitor)?,
        None => None,
    };
    Ok(Learned {
        refreshed: refreshed.as_ref().map(|(_, span)| *span),
        calibration: refreshed.map(|(c, _)| c).or(calibration),
        window,
        window_from,
        rows: learn,
        tracked,
        damping,
    })
}

/// Which rows of which file, or which calibration, taught each part of the forecast.
pub(super) fn provenance(job: &ForecastJob, learned: &Learned) -> serde_json::Value {
    let (tracked, learn) = (&learned.tracked, learned.rows);
    let (window_from, calibration) = (learned.window_from, learned.calibration.as_ref());
    let file = job.file.display().to_string();
    let rows = json!({
        "file": file, "from": tracked.t[0], "to": tracked.t[learn - 1], "count": learn,
    });
    let calibrated = |what: &str| {
        calibration.map(|c| {
            json!({ "from": format!("the calibration in {}", job.params.params.as_ref().map(|p| p.display().to_string()).unwrap_or_default()),
                    "recording": c.file, "span": c.span, "what": what })
        })
    };
    let from_rows = match job.settings.in_sample {
        true => "this file's rows, all of them (in sample)",
        false => "this file's rows up to the window's end (`rows`)",
    };
    let these_rows = |what: &str| json!({ "from": from_rows, "what": what });
    let model = match tracked.source {
        crate::fit::pendulum::ModelSource::Given => json!({
            "from": match (&job.params.params, job.params.preset) {
                (Some(p), _) => format!("the parameter file {}", p.display()),
                (None, Some(p)) => format!("the preset {}", p.name()),
                (None, None) => "the values given".into(),
            },
            "what": "the model (its joint damping fitted in the window)",
        }),
        crate::fit::pendulum::ModelSource::Identified => {
            these_rows("the moments, found from the motion")
        }
    };
    let scale = match (
        job.units.pixels_per_metre,
        calibration.and_then(|c| c.pixels_per_metre),
    ) {
        (Some(crate::fit::data::PixelScale::FromMotion), Some(_)) => {
            calibrated("the metre scale (from the recording's motion)")
        }
        (Some(crate::fit::data::PixelScale::FromMotion), None) => {
            Some(these_rows("the metre scale, from the motion"))
        }
        _ => None,
    };
    let again = |what: &str| {
        learned.refreshed.map(|span| {
            json!({ "from": "this file's rows just before the window, with the calibration's model", "span": span, "what": what })
        })
    };
    let calibrated_or_again = |what: &str| again(what).or_else(|| calibrated(what));
    let tracking = match (job.settings.tracking_error, calibration) {
        (Some(e), _) => json!({ "from": "given", "value": e }),
        (None, Some(_)) => {
            calibrated_or_again("the tracking error (the held-out fits' residuals)").into()
        }
        (None, None) => json!({ "from": "the window fit's residuals" }),
    };
    let model_error = match calibration {
        Some(_) => calibrated_or_again(
            "the model's own error by lead and the bands' factors (held-out stretches)",
        )
        .into(),
        None if job.settings.held_out == 0 => json!({ "from": "none measured (held_out 0)" }),
        None => these_rows(match job.settings.in_sample {
            true => "held-out windows spread over the whole file",
            false => "held-out windows before the forecast's window",
        }),
    };
    let damping = damping_source(learned, calibrated, these_rows);
    let placed = |found: Option<(bool, serde_json::Value)>, what: &str| match found {
        None => {
            json!({ "from": "none: the rows show none and no calibration gives one", "what": what })
        }
        Some((true, v)) => {
            let mut c = calibrated(what).unwrap_or_default();
            c["value"] = v;
            c
        }
        Some((false, v)) => {
            let mut c = these_rows(what);
            c["value"] = v;
            c
        }
    };
    json!({
        "sample": if job.settings.in_sample { "in sample" } else { "out of sample" },
        "rows": rows,
        "window": window_from,
        "geometry": these_rows("the pivot, the arm lengths and the middle joint"),
        "markers": placed(
            tracked.placed.offsets.map(|o| (o.from_calibration, json!(o))),
            "the markers' offsets from the arms' axes (m), taken out of every row",
        ),
        "roll": placed(
            tracked.placed.roll.map(|r| (r.from_calibration, json!(r))),
            "the picture's roll against gravity (rad), levelled out of every row",
        ),
        "scale": scale,
        "model": model,
        "fit": these_rows("the state, joint damping, pivot offset, scale and lower arm in the window"),
        "tracking_error": tracking,
        "model_error": model_error,
        "damping": damping,
    })
}

/// Where the joint damping each window's fit was held to came from, with its value.
fn damping_source(
    learned: &Learned,
    calibrated: impl Fn(&str) -> Option<serde_json::Value>,
    these_rows: impl Fn(&str) -> serde_json::Value,
) -> serde_json::Value {
    match learned.damping {
        None => {
            json!({ "from": "none: the window's fit finds the joint damping alone (a stated model)" })
        }
        Some(d) => {
            let mut v = match learned.calibration {
                Some(_) => calibrated(
                    "the joint damping each window's fit is held to (the recording's motion)",
                )
                .unwrap_or_default(),
                None => these_rows(
                    "the joint damping the motion shows, which the window's fit is held to",
                ),
            };
            v["damping"] = json!(d.damping);
            v["error"] = json!(d.error);
            v
        }
    }
}
