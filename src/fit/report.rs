//! The lab report's analysis of a fit: the energy with its error bars and its decay laws, the
//! pictures (positions, energy, phase portraits) and the derived quantities as CSV.

use serde_json::{Value, json};

use super::pendulum::{ModelSource, Tracked};
use super::plots::{self, EnergyUnit};
use super::weighed::Weighed;
use super::{DecayFits, Energies, Fit, ModelFit, data, energies, fit_decay};
use crate::error::Result;
use crate::model::{Params, State};
use crate::render::Outputs;

/// The energy row by row and the decay laws fitted to it.
pub struct EnergyReport {
    pub energies: Energies,
    pub unit: EnergyUnit,
    pub decay: DecayFits,
    /// The decay law with the smaller reduced chi^2.
    pub better: &'static str,
    pub velocity_error: f64,
}

impl EnergyReport {
    /// The tracked rows' energy and its decay. A model found from the motion cannot see the
    /// masses' scale: its energy is in units of its gravity moment P (in joules where the
    /// pendulum was `weighed`), and counts the arms' own inertia as the model does.
    pub fn of(
        tracked: &Tracked,
        t: &[f64],
        velocity_error: f64,
        weighed: Option<&Weighed>,
    ) -> EnergyReport {
        let params = &tracked.params;
        let (en, unit) = match tracked.source {
            ModelSource::Given => (
                energies(
                    &tracked.frames,
                    (tracked.pivot.x, tracked.pivot.y),
                    (params.m1, params.m2),
                    (tracked.l1.value, tracked.l2.value),
                    params.g,
                    velocity_error,
                ),
                EnergyUnit::Joule,
            ),
            ModelSource::Identified => {
                let over_p = model_energies(t, &tracked.angles, params, velocity_error);
                match weighed {
                    // E/P does not see the scale: times the weighed P, joules.
                    Some(w) => (
                        Energies {
                            t: over_p.t,
                            e: over_p.e.iter().map(|e| e * w.p).collect(),
                            de: over_p.de.iter().map(|e| e * w.p).collect(),
                        },
                        EnergyUnit::Joule,
                    ),
                    None => (over_p, EnergyUnit::GravityMoment),
                }
            }
        };
        let decay = fit_decay(&en);
        let better = if decay.exponential.reduced_chi2() <= decay.inverse_square.reduced_chi2() {
            "exponential"
        } else {
            "inverse_square"
        };
        EnergyReport {
            energies: en,
            unit,
            decay,
            better,
            velocity_error,
        }
    }

    /// The energy's unit as summaries write it: J, or P.
    pub fn unit_symbol(&self) -> &'static str {
        match self.unit {
            EnergyUnit::Joule => "J",
            EnergyUnit::GravityMoment => "P",
        }
    }

    /// summary.json's `energy`.
    pub fn to_json(&self) -> Value {
        let fitted = |f: &Fit, names: [&str; 2]| {
            json!({
                names[0]: f.params[0], format!("{}_error", names[0]): f.errors[0],
                names[1]: f.params[1], format!("{}_error", names[1]): f.errors[1],
                "chi2": f.chi2, "dof": f.dof, "reduced_chi2": f.reduced_chi2(),
            })
        };
        json!({
            "velocity_error": self.velocity_error,
            "exponential": fitted(&self.decay.exponential, ["a", "b"]),
            "inverse_square": fitted(&self.decay.inverse_square, ["a", "b"]),
            "inverse_square_note": "E = a (b t + d)^-2 with d = 1: a, b, d are degenerate (only a/d^2 and b/d matter)",
            "better_fit": self.better,
        })
    }
}

/// positions.png, energy.png, phase.png and derived.csv into `out`, among `files`.
pub fn write(
    files: &mut Outputs,
    out: &std::path::Path,
    t: &[f64],
    tracked: &Tracked,
    fit: &ModelFit,
    report: &EnergyReport,
) -> Result<()> {
    let (ex, inv) = (&report.decay.exponential, &report.decay.inverse_square);
    // Long enough to see the model agree and then part (chaos), short enough to read.
    let t_end = (fit.agrees_until + 4.0).max(fit.t0 + 4.0);
    plots::positions(
        files,
        &out.join("positions.png"),
        t,
        &tracked.measured,
        &fit.simulated,
        fit.t0,
        t_end,
    )?;
    plots::energy(
        files,
        &out.join("energy.png"),
        &report.energies,
        (ex.params[0], ex.params[1]),
        (inv.params[0], inv.params[1]),
        report.unit,
    )?;
    let angle = &tracked.angles;
    // Angular velocities at the interior rows (central differences), once for both uses.
    let arm = |k: usize| -> Vec<f64> {
        angle
            .iter()
            .map(|a| if k == 0 { a.0 } else { a.1 })
            .collect()
    };
    let (wa, wb) = (
        data::central_differences(t, &arm(0)),
        data::central_differences(t, &arm(1)),
    );
    let wrap = |x: f64| {
        (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    let portrait = |k: usize, w: &[f64]| -> Vec<(f64, f64)> {
        let a = arm(k);
        w.iter()
            .enumerate()
            .filter(|(_, w)| w.is_finite())
            .map(|(i, &w)| (wrap(a[i + 1]), w))
            .collect()
    };
    let (w1, w2) = (portrait(0, &wa), portrait(1, &wb));
    plots::phase(
        files,
        &out.join("phase.png"),
        [&w1, &w2],
        &plots::cadence(t),
    )?;
    let en = &report.energies;
    // The derived quantities row by row (interior rows: central differences need neighbours).
    files.write(&out.join("derived.csv"), |f| {
        use std::io::Write;
        writeln!(
            f,
            "# chaoscope fit: angles (rad, unwrapped), angular velocities (rad/s, central differences), energy and its error ({})",
            match report.unit {
                EnergyUnit::Joule => "J",
                EnergyUnit::GravityMoment => "over the upper arm's gravity moment P",
            }
        )?;
        writeln!(f, "t,theta1,theta2,omega1,omega2,energy,energy_error")?;
        for i in 1..tracked.frames.len() - 1 {
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
    })
}

/// Energies at the interior rows in units of the upper arm's gravity moment P (E/P, zero
/// hanging at rest) by the model `p` itself (rods and bars included), angular velocities by
/// central differences, and their errors: a mass's velocity error `dv` (m/s) moves omega1
/// by dv / l1 and omega2 by sqrt 2 dv / l2 (both its ends' errors), dE = |M omega| d omega.
pub fn model_energies(t: &[f64], angles: &[(f64, f64)], p: &Params, dv: f64) -> Energies {
    let k = p.inertia();
    let floor = p.potential_energy(0.0, 0.0);
    let mut out = Energies {
        t: Vec::new(),
        e: Vec::new(),
        de: Vec::new(),
    };
    let gap = super::data::gaps(t);
    for i in 1..t.len() - 1 {
        if gap(i) {
            // No velocity across a gap in the rows, so no energy.
            out.t.push(t[i]);
            out.e.push(f64::NAN);
            out.de.push(f64::NAN);
            continue;
        }
        let h = t[i + 1] - t[i - 1];
        let s = State {
            theta1: angles[i].0,
            omega1: (angles[i + 1].0 - angles[i - 1].0) / h,
            theta2: angles[i].1,
            omega2: (angles[i + 1].1 - angles[i - 1].1) / h,
        };
        let cd = (s.theta1 - s.theta2).cos();
        let m_omega = [
            k.a * s.omega1 + k.c * cd * s.omega2,
            k.c * cd * s.omega1 + k.b * s.omega2,
        ];
        let (d1, d2) = (dv / p.l1, std::f64::consts::SQRT_2 * dv / p.l2);
        out.t.push(t[i]);
        out.e.push((p.energy(&s) - floor) / k.p);
        out.de.push((m_omega[0] * d1).hypot(m_omega[1] * d2) / k.p);
    }
    out
}
