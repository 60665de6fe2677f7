//! `chaoscope fit`: from a camera's tracked positions to the model, as the lab report did by
//! hand: pivot and arm lengths, angles, velocities and energies with error bars, the energy
//! decay laws, and the model's state and damping fitted to the positions.

mod data;
mod lsq;
mod model;
mod plots;

use std::path::PathBuf;

use clap::Args;
use serde_json::json;

pub use data::{
    Energies, Frame, angles, arm_lengths, energies, fit_decay, fit_pivot, grid_pivot, read_frames,
};
pub use lsq::{Fit, least_squares};
pub use model::{ModelFit, ModelFitSpec, fit_model};

use crate::cli::{PhysicalArgs, parse_number};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::physics_args::Preset;

#[derive(Args, Debug, Clone)]
pub struct FitArgs {
    /// CSV of tracked positions: header with t, x1, y1, x2, y2 (s, m; y up); # comments.
    pub file: PathBuf,
    /// Directory for the plots and summary.json.
    #[arg(long, default_value = "out/fit")]
    pub output: PathBuf,
    /// Time (s) to start the model fit (the report: 0.8 s, where dx2/dt ~ 0); the nearest
    /// data row is used.
    #[arg(long, default_value = "0.8", value_parser = parse_number)]
    pub start: f64,
    /// Length of data (s) the model is fitted to.
    #[arg(long, default_value = "1.5", value_parser = parse_number)]
    pub window: f64,
    /// Position tolerance (m) for "the model agrees with the measurement".
    #[arg(long, default_value = "0.03", value_parser = parse_number)]
    pub tolerance: f64,
    /// Size of the candidate ensemble of the model fit.
    #[arg(long, default_value = "65536")]
    pub candidates: usize,
    /// Velocity error (m/s) of each mass, for the energy error bars (the report: 0.1).
    #[arg(long, default_value = "0.1", value_parser = parse_number)]
    pub velocity_error: f64,
    /// The model's parameters; by default the lab preset, with the arm lengths from the data.
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
}

pub fn run(args: &FitArgs) -> Result<()> {
    for (flag, v, lo, hi) in [
        ("--window", args.window, 0.3, 60.0),
        ("--tolerance", args.tolerance, 1e-4, 1.0),
        ("--velocity-error", args.velocity_error, 0.0, 10.0),
    ] {
        if !(v.is_finite() && v >= lo && v <= hi) {
            return Err(Error::invalid(flag, format!("{v} must be in [{lo}, {hi}]")));
        }
    }
    if !(64..=4_000_000).contains(&args.candidates) {
        return Err(Error::invalid(
            "--candidates",
            "must be between 64 and 4000000",
        ));
    }
    let frames = read_frames(&args.file)?;
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();

    // Pivot: least-squares circle, and the report's grid search beside it.
    let pivot = fit_pivot(&frames)?;
    // The report's grid: whole millimetres within 5 cm of the data's origin.
    let grid = grid_pivot(&frames, (0.0, 0.0), 0.05, 0.001);
    let (l1, l2) = arm_lengths(&frames, (pivot.x, pivot.y));
    let angle = angles(&frames, (pivot.x, pivot.y));

    // The model: preset lab unless told otherwise, arm lengths from the data unless given.
    let mut physical = args.physical.clone();
    if physical.preset.is_none() && physical.params.is_none() {
        physical.preset = Some(Preset::Lab);
    }
    physical.l1 = physical.l1.or(Some(l1.value));
    physical.l2 = physical.l2.or(Some(l2.value));
    let params = physical.params()?;

    let en = energies(
        &frames,
        (pivot.x, pivot.y),
        (params.m1, params.m2),
        (l1.value, l2.value),
        params.g,
        args.velocity_error,
    );
    let decay = fit_decay(&en);
    let (ex, inv) = (&decay.exponential, &decay.inverse_square);
    let better = if ex.reduced_chi2() <= inv.reduced_chi2() {
        "exponential"
    } else {
        "inverse_square"
    };

    let spec = ModelFitSpec {
        params,
        start_time: args.start,
        window: args.window,
        tolerance: args.tolerance,
        candidates: args.candidates,
        backend: args.backend,
    };
    let fit = fit_model(&frames, (pivot.x, pivot.y), &angle, &spec)?;

    // Plots and summary.
    let out = &args.output;
    std::fs::create_dir_all(out)?;
    let measured: Vec<[f64; 4]> = frames
        .iter()
        .map(|f| {
            [
                f.x1 - pivot.x,
                f.y1 - pivot.y,
                f.x2 - pivot.x,
                f.y2 - pivot.y,
            ]
        })
        .collect();
    // Long enough to see the model agree and then part (chaos), short enough to read.
    let t_end = (fit.agrees_until + 4.0).max(fit.t0 + 4.0);
    plots::positions(
        &out.join("positions.png"),
        &t,
        &measured,
        &fit.simulated,
        fit.t0,
        t_end,
    )?;
    plots::energy(
        &out.join("energy.png"),
        &en.t,
        &en.e,
        &en.de,
        (ex.params[0], ex.params[1]),
        (inv.params[0], inv.params[1]),
    )?;
    // Angular velocities at the interior rows (central differences), once for both uses.
    let arm = |k: usize| -> Vec<f64> {
        angle
            .iter()
            .map(|a| if k == 0 { a.0 } else { a.1 })
            .collect()
    };
    let (wa, wb) = (
        data::central_differences(&t, &arm(0)),
        data::central_differences(&t, &arm(1)),
    );
    let wrap = |x: f64| {
        (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    let portrait = |k: usize, w: &[f64]| -> Vec<(f64, f64)> {
        let a = arm(k);
        w.iter()
            .enumerate()
            .map(|(i, &w)| (wrap(a[i + 1]), w))
            .collect()
    };
    let (w1, w2) = (portrait(0, &wa), portrait(1, &wb));
    plots::phase(&out.join("phase.png"), [&w1, &w2])?;
    // The derived quantities row by row (interior rows: central differences need neighbours).
    crate::render::write_atomic(&out.join("derived.csv"), |f| {
        use std::io::Write;
        writeln!(
            f,
            "# chaoscope fit: angles (rad, unwrapped), angular velocities (rad/s, central differences), energy and its error (J)"
        )?;
        writeln!(f, "t,theta1,theta2,omega1,omega2,energy,energy_error")?;
        for i in 1..frames.len() - 1 {
            writeln!(
                f,
                "{},{},{},{},{},{},{}",
                t[i],
                angle[i].0,
                angle[i].1,
                wa[i - 1],
                wb[i - 1],
                en.e[i - 1],
                en.de[i - 1]
            )?;
        }
        Ok(())
    })?;
    let fitted = |f: &Fit, names: [&str; 2]| {
        json!({
            names[0]: f.params[0], format!("{}_error", names[0]): f.errors[0],
            names[1]: f.params[1], format!("{}_error", names[1]): f.errors[1],
            "chi2": f.chi2, "dof": f.dof, "reduced_chi2": f.reduced_chi2(),
        })
    };
    let summary = json!({
        "file": args.file.display().to_string(),
        "rows": frames.len(),
        "pivot": {
            "least_squares_circle": {
                "x": pivot.x, "y": pivot.y, "x_error": pivot.errors[0], "y_error": pivot.errors[1],
                "radius": pivot.radius, "radius_error": pivot.errors[2], "rms_residual": pivot.rms_residual,
            },
            "report_grid_least_distance_variance": { "x": grid.0, "y": grid.1, "grid_step": 0.001 },
        },
        "arm_lengths": { "l1": l1, "l2": l2 },
        "energy": {
            "velocity_error": args.velocity_error,
            "exponential": fitted(ex, ["a", "b"]),
            "inverse_square": fitted(inv, ["a", "b"]),
            "inverse_square_note": "E = a (b t + d)^-2 with d = 1: a, b, d are degenerate (only a/d^2 and b/d matter)",
            "better_fit": better,
        },
        "model": {
            "parameters": crate::physics_args::flags(&params),
            "start_row": fit.row, "t0": fit.t0,
            "state": fit.start.to_array(),
            "joint_damping": [fit.damping.0, fit.damping.1],
            "rms_position_error_in_window": fit.rms,
            "window": args.window,
            "candidates": fit.candidates, "searched_on": fit.backend,
            "tolerance": args.tolerance,
            "agrees_until": fit.agrees_until,
            "agrees_for": fit.agrees_until - fit.t0,
        },
    });
    let text =
        serde_json::to_string_pretty(&summary).map_err(|e| Error::Io(std::io::Error::other(e)))?;
    crate::render::write_atomic(&out.join("summary.json"), |w| {
        use std::io::Write;
        writeln!(w, "{text}")?;
        Ok(())
    })?;
    eprintln!(
        "pivot ({:.4}, {:.4}) m, l1 {:.4} ± {:.4} m, l2 {:.4} ± {:.4} m; energy a exp(b t): a {:.3} J, b {:.4} 1/s (chi2/dof {:.2}); inverse square chi2/dof {:.2}: {better} fits better; model from t = {} s agrees within {} m until {} s ({:.2} s) -> {}",
        pivot.x,
        pivot.y,
        l1.value,
        l1.error,
        l2.value,
        l2.error,
        ex.params[0],
        ex.params[1],
        ex.reduced_chi2(),
        inv.reduced_chi2(),
        fit.t0,
        args.tolerance,
        fit.agrees_until,
        fit.agrees_until - fit.t0,
        out.display()
    );
    Ok(())
}
