//! `fit`: from a camera's tracked positions to the model (src/fit), with plots, the derived
//! quantities as CSV and a summary as JSON.

use std::path::PathBuf;

use serde_json::json;

use super::{check_count, check_within};
use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::fit::data::Units;
use crate::fit::model_toml::model_file;
use crate::fit::pendulum::{ModelSource, Tracked, tracked_model};
use crate::fit::report::{self, EnergyReport};
use crate::fit::verdict::Verdict;
use crate::fit::weighed::Weighed;
use crate::fit::{ModelFit, ModelFitSpec, fit_model, grid_pivot, read_frames};
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::render::Outputs;
use crate::spec::Precision;

#[derive(Clone, Debug, PartialEq)]
pub struct FitJob {
    /// CSV of tracked positions: header with t, x1, y1, x2, y2 (s, m; y up); # comments.
    pub file: PathBuf,
    /// Directory for the plots, derived.csv and summary.json.
    pub output: PathBuf,
    /// How the file's numbers become seconds and metres.
    pub units: Units,
    /// Time (s) to start the model fit; the nearest data row is used. None: the first row
    /// with one before it.
    pub start: Option<f64>,
    /// The rows up to this time (s) only: a calibration stretch. None: every row.
    pub until: Option<f64>,
    /// Length of data (s) the model is fitted to. None: four of the motion's own times.
    pub window: Option<f64>,
    /// Position tolerance (m) for "the model agrees with the measurement". None: 6 % of
    /// the reach (l1 + l2).
    pub tolerance: Option<f64>,
    /// Size of the candidate ensemble of the model fit.
    pub candidates: usize,
    /// Stretches held out to calibrate forecasts ([`crate::forecast::calibration`]; 0: none),
    /// and how far past each its departure is measured (s).
    pub held_out: usize,
    pub lead: f64,
    /// Velocity error (m/s) of each mass, for the energy error bars.
    pub velocity_error: f64,
    /// The pendulum's weighed mass (kg, all that swings), which sets the scale of moments
    /// found from the motion ([`Weighed`]). None: they stay over P.
    pub mass: Option<f64>,
    /// The model's parameters: the lab preset unless a preset or file is given, the arm
    /// lengths from the data unless given.
    pub params: ParamSources,
    pub backend: Backend,
    /// The GPU's precision for the ensemble search (the refinement is f64 on the CPU).
    pub precision: Precision,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct FitSummary {
    pub pivot: (f64, f64),
    /// (value, error) of each arm length (m).
    pub l1: (f64, f64),
    pub l2: (f64, f64),
    /// The exponential decay a exp(b t): a (J), b (1/s), chi^2/dof; and the inverse square's.
    pub exponential: (f64, f64, f64),
    pub inverse_square_chi2: f64,
    pub better: &'static str,
    pub t0: f64,
    pub agrees_until: f64,
    pub tolerance: f64,
    /// Whether the fitted model follows the data in the window.
    pub verdict: Verdict,
    /// The energy's unit: J, or P (the upper arm's gravity moment) for a model found from
    /// the motion.
    pub energy_unit: &'static str,
    pub output: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

/// Held-out stretches of a calibration unless given, half for the model error and half for
/// the bands' factors: split conformal prediction's quantile 0.9 (1 + 1/n) over n = 20
/// windows is 0.945, where eight asked for the largest score (97 % bands on the shared
/// runs; twenty held 0.89 pooled, 0.87-0.93 by lead). Each stretch is a window fit and, for
/// the factors, a forecast: about a second each.
pub const CALIBRATION_WINDOWS: usize = 40;

/// How far past each held-out stretch a calibration measures the model's departure (s).
pub const CALIBRATION_LEAD: f64 = 1.0;

/// The fitted model as a parameter file, in the output folder.
pub const MODEL_FILE: &str = "model.toml";

/// The files a fit writes into its folder.
const FILES: [&str; 6] = [
    "positions.png",
    "energy.png",
    "phase.png",
    "derived.csv",
    "summary.json",
    MODEL_FILE,
];

/// Runs the fit; `command` reproduces it and goes into summary.json.
pub fn run(job: &FitJob, at: &super::Running) -> Result<FitSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    check_job(job)?;
    let read = read_rows(job)?;
    let t: Vec<f64> = read.iter().map(|f| f.t).collect();
    let tracked = tracked_model(&read, &job.params, &job.units, monitor)?;
    let spec = ModelFitSpec {
        params: tracked.params,
        start_time: job.start.unwrap_or_else(|| tracked.default_start()),
        window: job.window.unwrap_or_else(|| tracked.default_window()),
        tolerance: job.tolerance.unwrap_or_else(|| tracked.default_tolerance()),
        candidates: job.candidates,
    };
    let (weighed, scale_note) = weighed_of(job, &tracked);
    let energy = EnergyReport::of(&tracked, &t, job.velocity_error, weighed.as_ref());
    let mut notices = notices_of(engine, &tracked, weighed.as_ref());
    notices.extend(scale_note);
    let pivot = (tracked.pivot.x, tracked.pivot.y);
    let fit = fit_model(
        &tracked.frames,
        pivot,
        &tracked.angles,
        &spec,
        engine,
        monitor,
    )?;
    let verdict = Verdict::judge(
        fit.rms,
        &t,
        &tracked.measured,
        spec.params.l1 + spec.params.l2,
    );
    notices.push(verdict.describe());
    notices.extend(negative_damping_note(&fit));
    let calibration = calibration_of(job, &tracked, spec.window, engine, monitor, &mut notices)?;

    // Plots, derived quantities and summary, written as a set.
    let out = &job.output;
    let mut files = Outputs::new();
    report::write(&mut files, out, &t, &tracked, &fit, &energy)?;
    let summary = summary_json(
        job,
        command.clone(),
        &tracked,
        &spec,
        &fit,
        &energy,
        &verdict,
        &calibration,
        weighed.as_ref(),
    );
    files.write_json(&out.join("summary.json"), &summary)?;
    let model = Written {
        tracked: &tracked,
        fit: &fit,
        weighed: weighed.as_ref(),
    };
    write_model(&mut files, out, &model, &calibration, &command)?;
    files.commit(monitor)?;
    let (ex, inv) = (&energy.decay.exponential, &energy.decay.inverse_square);
    Ok(FitSummary {
        pivot,
        l1: (tracked.l1.value, tracked.l1.error),
        l2: (tracked.l2.value, tracked.l2.error),
        exponential: (ex.params[0], ex.params[1], ex.reduced_chi2()),
        inverse_square_chi2: inv.reduced_chi2(),
        better: energy.better,
        t0: fit.t0,
        agrees_until: fit.agrees_until,
        tolerance: spec.tolerance,
        verdict,
        energy_unit: energy.unit_symbol(),
        output: out.clone(),
        files: FILES.iter().map(|f| out.join(f)).collect(),
        notices,
    })
}

/// What the run says of its model before the fit: the engine's notices, which pendulum is
/// fitted (said, never assumed), what the motion says of it, and the tracked model's own.
fn notices_of(engine: &Engine, tracked: &Tracked, weighed: Option<&Weighed>) -> Vec<String> {
    let mut notices: Vec<String> = engine.notices();
    let params = weighed.map_or(tracked.params, |w| w.scaled(&tracked.params));
    notices.push(tracked.source.describe_model(&params, weighed));
    notices.push(match &tracked.identified {
        Ok(id) => describe_identified(id),
        Err(e) => format!("the pendulum's own moments could not be found from this file: {e}"),
    });
    notices.extend(tracked.notices.iter().cloned());
    notices
}

/// What to say where the fit put a joint's damping below zero: the value with its error,
/// and that it is written as none.
fn negative_damping_note(fit: &ModelFit) -> Option<String> {
    let (a, b) = fit.negative_damping?;
    let (ea, eb) = fit.damping_error;
    let joints = [("pivot", a, ea), ("middle joint", b, eb)];
    let below: Vec<String> = joints
        .iter()
        .filter(|j| j.1 < 0.0)
        .map(|(name, c, e)| format!("the {name}'s damping at {c:.2e} ± {e:.1e} N m s"))
        .collect();
    Some(format!(
        "the fit put {} (below zero, which no joint is: written as 0 in model.toml)",
        below.join(" and ")
    ))
}

/// What model.toml is written from: the tracked model, its fit and its scale.
struct Written<'a> {
    tracked: &'a Tracked,
    fit: &'a ModelFit,
    weighed: Option<&'a Weighed>,
}

impl Written<'_> {
    /// The model with the fit's joint damping, on the weighed scale where there is one.
    fn fitted(&self) -> crate::model::Params {
        let mut fitted = self.tracked.params;
        (fitted.losses.joint1, fitted.losses.joint2) = self.fit.damping;
        self.weighed.map_or(fitted, |w| w.scaled(&fitted))
    }
}

/// The scale of moments found from the motion, the weighed one where a mass was given and
/// one exists, and what to say of their units where there is none (a given model states
/// its masses: nothing).
fn weighed_of(job: &FitJob, tracked: &Tracked) -> (Option<Weighed>, Option<String>) {
    match (&tracked.source, job.mass) {
        (ModelSource::Identified, Some(mass)) => match Weighed::of(&tracked.params, mass) {
            Ok(w) => (Some(w), None),
            Err(why) => (None, Some(why)),
        },
        (ModelSource::Identified, None) => (None, Some("the moments and the energies are over P, the upper arm's gravity moment (the motion cannot see the masses' scale): weigh all that swings and give its mass with [[mass]] for kg m^2 and joules".into())),
        (ModelSource::Given, _) => (None, None),
    }
}

/// model.toml: the fitted pendulum with its joint damping from the fit, and the calibration.
fn write_model(
    files: &mut Outputs,
    out: &std::path::Path,
    model: &Written,
    calibration: &Option<crate::forecast::calibration::Calibration>,
    command: &str,
) -> Result<()> {
    let (tracked, fitted) = (model.tracked, model.fitted());
    let heading = format!(
        "The pendulum `chaoscope fit` fitted ({}), its joint damping from the fit:\n{command}\nRead it back with --params (trajectory, the maps, forecast).",
        tracked.source.describe()
    );
    files.write(&out.join(MODEL_FILE), |w| {
        use std::io::Write;
        let text = model_file(&fitted, &tracked.source, &heading, model.weighed);
        write!(w, "{text}")?;
        if let Some(c) = calibration {
            write!(w, "{}", c.to_toml())?;
        }
        Ok(())
    })
}

/// summary.json: the command, the file, the geometry, the energy, what the motion says, the
/// verdict, the calibration and the fitted model.
#[allow(clippy::too_many_arguments)]
fn summary_json(
    job: &FitJob,
    command: String,
    tracked: &Tracked,
    spec: &ModelFitSpec,
    fit: &ModelFit,
    energy: &EnergyReport,
    verdict: &Verdict,
    calibration: &Option<crate::forecast::calibration::Calibration>,
    weighed: Option<&Weighed>,
) -> serde_json::Value {
    let pivot = &tracked.pivot;
    // On the weighed scale where there is one (masses and damping alike).
    let factor = weighed.map_or(1.0, |w| w.factor);
    let params = weighed.map_or(tracked.params, |w| w.scaled(&tracked.params));
    // The report's grid: whole millimetres within 5 cm of the data's origin.
    let grid = grid_pivot(&tracked.frames, (0.0, 0.0), 0.05, 0.001);
    json!({
        "command": command,
        "file": job.file.display().to_string(),
        "rows": tracked.frames.len(),
        "pivot": {
            "least_squares_circle": {
                "x": pivot.x, "y": pivot.y, "x_error": pivot.errors[0], "y_error": pivot.errors[1],
                "radius": pivot.radius, "radius_error": pivot.errors[2], "rms_residual": pivot.rms_residual,
            },
            "report_grid_least_distance_variance": { "x": grid.0, "y": grid.1, "grid_step": 0.001 },
        },
        "arm_lengths": { "l1": tracked.l1, "l2": tracked.l2 },
        "middle_joint_off_marker": tracked.placed.joint,
        "markers_off_axes": tracked.placed.offsets,
        "roll": tracked.placed.roll,
        "energy": energy.to_json(),
        "identified": match &tracked.identified {
            Ok(id) => identified_json(id),
            Err(e) => json!({ "error": e.to_string() }),
        },
        "verdict": verdict,
        "calibration": calibration,
        "model": {
            "source": tracked.source.key(),
            "source_text": tracked.source.describe(),
            "parameters": crate::params::to_json(&params),
            "weighed": weighed,
            "start_row": fit.row, "t0": fit.t0,
            "state": fit.start.to_array(),
            "joint_damping": [fit.damping.0 * factor, fit.damping.1 * factor],
            "joint_damping_error": [fit.damping_error.0 * factor, fit.damping_error.1 * factor],
            "joint_damping_fitted_below_zero": fit.negative_damping.map(|(a, b)| [a * factor, b * factor]),
            "energy_unit": energy.unit_symbol(),
            "rms_position_error_in_window": fit.rms,
            "window": spec.window,
            "candidates": fit.candidates, "searched_on": fit.backend,
            "tolerance": spec.tolerance,
            "agrees_until": fit.agrees_until,
            "agrees_for": fit.agrees_until - fit.t0,
        },
    })
}

/// The job's values, its inputs and its output folder, before any work.
fn check_job(job: &FitJob) -> Result<()> {
    if let Some(window) = job.window {
        check_within("window", window, 0.01, 60.0)?;
    }
    if let Some(tolerance) = job.tolerance {
        check_within("tolerance", tolerance, 1e-6, 1e3)?;
    }
    check_within("velocity_error", job.velocity_error, 0.0, 10.0)?;
    check_count("candidates", job.candidates as u64, 64, 4_000_000)?;
    check_count(
        "held_out",
        job.held_out as u64,
        0,
        crate::forecast::outcome::MOST_HELD_OUT as u64,
    )?;
    check_within("lead", job.lead, 0.05, 60.0)?;
    if let Some(mass) = job.mass {
        check_within("mass", mass, 1e-6, 1e6)?;
        if job.params.preset.is_some() || job.params.params.is_some() {
            return Err(Error::invalid(
                "mass",
                "sets the scale of moments found from the motion; the model given (a preset or a parameter file) states its own masses",
            ));
        }
    }
    super::checks::check_damping_not_given(&job.params)?;
    super::checks::check_units(&job.units)?;
    if job.start.is_some_and(|s| !s.is_finite()) {
        return Err(Error::invalid("start", "must be a finite time (s)"));
    }
    super::checks::check_directory(
        "output",
        &job.output,
        &FILES,
        &[],
        &super::checks::tracked_inputs(&job.file, &job.params),
    )?;
    Ok(())
}

/// The file's rows (up to `until`, where given), with the start within them.
fn read_rows(job: &FitJob) -> Result<Vec<crate::fit::TrackedRow>> {
    let mut read = read_frames(&job.file, &job.units)?;
    if let Some(until) = job.until {
        let first = read[0].t;
        read.retain(|f| f.t <= until + 1e-9);
        if read.len() < 3 {
            return Err(Error::invalid(
                "until",
                format!(
                    "{until} s leaves {} row(s) of the file (its first at {first} s): a fit needs three at least",
                    read.len()
                ),
            ));
        }
    }
    let t: Vec<f64> = read.iter().map(|f| f.t).collect();
    // The fit starts at a data row with a neighbour on each side (its velocities are central
    // differences); a start outside them was moved to the nearest silently.
    let (first, last) = (t[1], t[t.len() - 2]);
    if let Some(start) = job.start
        && !(first..=last).contains(&start)
    {
        return Err(Error::invalid(
            "start",
            format!(
                "must lie within the data's times with a row either side, {first}..{last} s (got {start})"
            ),
        ));
    }

    Ok(read)
}

/// The calibration a forecast of another launch carries ([`crate::forecast::calibrate`]),
/// with its notices.
fn calibration_of(
    job: &FitJob,
    tracked: &Tracked,
    window: f64,
    engine: &Engine,
    monitor: &Monitor,
    notices: &mut Vec<String>,
) -> Result<Option<crate::forecast::calibration::Calibration>> {
    let (pivot, params, source, identified) = (
        &tracked.pivot,
        tracked.params,
        &tracked.source,
        &tracked.identified,
    );
    let (t, measured, angle) = (&tracked.t, &tracked.measured, &tracked.angles);
    let calibration = match job.held_out {
        0 => None,
        n => {
            let rows = crate::fit::window::TrackRows {
                t,
                data: measured,
                angles: angle,
            };
            let asked = crate::forecast::calibrate::Asked {
                file: job.file.display().to_string(),
                window,
                held_out: n,
                lead: job.lead,
                candidates: job.candidates,
                pixels_per_metre: tracked.scale_from_motion,
                pivot: (pivot.x, pivot.y),
                moment_covariance: match (source, identified) {
                    (ModelSource::Identified, Ok(id)) => Some(&id.covariance),
                    _ => None,
                },
                damping: tracked.damping_prior(),
                roll: tracked.placed.roll,
                offsets: tracked.placed.offsets,
            };
            let made =
                crate::forecast::calibrate::calibrate(&rows, &params, &asked, engine, monitor)?;
            if made.is_none() {
                notices.push(format!(
                    "no calibration: none of {n} held-out stretches of {window:.3} s with {:.2} s after them fitted and followed its data (a recording too short?)",
                    job.lead
                ));
            }
            made
        }
    };
    if let Some(c) = &calibration {
        let e = &c.model_error;
        let factors = match &c.band_factors {
            Some(b) => format!(
                "; the bands' factors from {} more forecast and scored: the lower mass's 90 % band x{:.2} at leads to {:.2} s, x{:.2} to {:.2} s",
                b.windows,
                b.f90[0][1],
                b.step,
                b.f90[b.f90.len() - 1][1],
                b.step * b.f90.len() as f64
            ),
            None => "; too few stretches for the bands' factors".into(),
        };
        notices.push(format!(
            "calibration for forecasts (model.toml): the model's own error on {} held-out stretches of {:.3} s ({} did not follow), tracking error {:.3} mm{factors}",
            e.windows.len(),
            window,
            e.unfollowed,
            1e3 * c.tracking_error,
        ));
    }

    Ok(calibration)
}

/// One line on what the motion says of the pendulum.
fn describe_identified(id: &crate::fit::identify::Identified) -> String {
    let v = |k: usize| format!("{:.4e} ± {:.1e}", id.values[k], id.errors[k]);
    let ts = &id.time_scale;
    let scale = match ts.disagrees() {
        true => format!(
            "the motion implies g = {:.3} ± {:.3} m/s^2 at these metres and seconds, not {}: the upper arm would be {:.4} m at this frame rate, or the frame rate {:.4} times the file's at this length",
            ts.g_implied, ts.g_implied_error, ts.g, ts.l1_implied, ts.rate_factor
        ),
        false => format!(
            "the time scale agrees with g (the motion implies {:.3} ± {:.3} m/s^2)",
            ts.g_implied, ts.g_implied_error
        ),
    };
    let damping = match id.values[4] < 0.0 || id.values[5] < 0.0 {
        true => {
            " (a negative damping: the data gain energy, from a drive or from tracking errors that lean one way)"
        }
        false => "",
    };
    let method = match &id.refinement {
        Some(r) => format!(
            "run on the angles over {} pieces of the motion ({} left out{}), the markers' arcs off it {:.3e} and {:.3e} RMS",
            r.pieces,
            r.rejected,
            match r.of > r.pieces + r.rejected {
                true => format!(
                    "; a long recording: {} of its {} pieces, evenly spread",
                    r.pieces + r.rejected,
                    r.of
                ),
                false => String::new(),
            },
            r.rms[0],
            r.rms[1]
        ),
        None => "from the equations' weak form alone (the run on the angles did not hold)".into(),
    };
    format!(
        "the pendulum's own moments from its motion, over P (the upper arm's gravity moment): a = A/P {} s^2, b = B/P {} s^2, c = C/P {} s^2, q = Q/P {}, damping k1 {} s, k2 {} s{damping}; {method}; {scale}; the weak form's misfit {:.1e} and {:.1e} of the equations' size",
        v(0),
        v(1),
        v(2),
        v(3),
        v(4),
        v(5),
        id.misfit[0],
        id.misfit[1]
    )
}

/// The identified moments as JSON: each value and error, the stretches, the misfit, the
/// time-scale check and the equivalent parameters (SI, P from a 1 kg mass at the joint).
fn identified_json(id: &crate::fit::identify::Identified) -> serde_json::Value {
    let mut moments = serde_json::Map::new();
    for (k, name) in crate::fit::identify::MOMENTS.iter().enumerate() {
        moments.insert(name.to_string(), json!(id.values[k]));
        moments.insert(format!("{name}_error"), json!(id.errors[k]));
    }
    json!({
        "over_p": moments,
        "units": "a, b, c in s^2; q none; k1, k2 in s (each moment over the upper arm's gravity moment P)",
        "physical": id.physical(),
        "stretches": id.stretches,
        "stretch_s": id.stretch,
        "misfit": id.misfit,
        "weak_form": id.weak,
        "refinement": id.refinement.map(|r| json!({
            "pieces": r.pieces,
            "pieces_in_the_recording": r.of,
            "rejected": r.rejected,
            "arc_rms": r.rms,
        })),
        "marker_radii": [id.l1, id.l2],
        "time_scale": id.time_scale,
        "equivalent_parameters": id.params().ok().map(|p| crate::params::to_json(&p)),
    })
}
