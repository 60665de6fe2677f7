//! The relative Lyapunov indicator (Sándor, Érdi, Széll, Funk 2004): the time average of
//! |L(x + Δx, t) - L(x, t)|, L(x, t) = ln |v(t)| / t the finite-time exponent of one tangent
//! vector along the orbit from x, for a neighbour Δx = `rli_delta` away (along
//! +-(1, 1, 1, 1): the sign of x's first non-zero coordinate, so that the mirrored start
//! -x gets the mirrored pair and the map keeps the pendulum's point symmetry). Two orbits that
//! start that close on one torus keep nearly the same L, so the RLI stays near the
//! separation's size; in chaos they part and so do their L, and the RLI is of the order of
//! the exponent itself. Its kernel is `shaders/rli.wgsl`; its CPU twin, below, steps with
//! the FTLE's dual numbers.

use super::MapKindEntry;
use super::RangeRule;
use super::{CpuRun, GpuEntry, Indicator, IndicatorAsked, Look, Measure, Opt, Runs, TANGENT_COST};
use crate::cpu::{TANGENT_START, norm, tangent_step};
use crate::error::{Error, Result};
use crate::field::Precision;
use crate::quantity::{Quantity, Tolerance};

pub struct Rli;

/// The neighbour's distance.
const DELTA: Opt = Opt {
    field: "rli_delta",
    help: "How far the relative Lyapunov indicator's neighbour starts (along +-(1, 1, 1, 1) in (theta1, omega1, theta2, omega2), the sign of the start's first non-zero one), 1e-12..1e-2 [default: 1e-8; in f32 at least 1e-4, its default there].",
    whole: None,
    offered: &[1e-4, 1e-3, 1e-2],
};

/// The default separation in f64, and in f32: f32 carries an angle of 3 rad to 2e-7, so a
/// neighbour closer than 1e-4 would start on the same float or a few ulps off.
const DELTA_F64: f64 = 1e-8;
const DELTA_F32: f64 = 1e-4;

/// log10 RLI above this calls a start chaotic: a neighbour 1e-8 away on one torus keeps
/// its L within some 1e-6 /s over a minute; chaos parts them by the exponent itself (0.1
/// to 5 /s).
pub const CHAOTIC_RLI: f32 = -3.0;

/// log10 of the RLI at t-max.
pub const RLI: Quantity = Quantity {
    name: "relative Lyapunov indicator",
    unit: "1 (log10)",
    // In chaos the two orbits part after ln(1/delta)/λ and their L differ by O(λ) as they
    // go: round-off moves the mean by tens of percent (0.2 in log10) where that happens.
    value: "log10 RLI",
    agree: Tolerance::new(0.0, 0.3, ""),
    vouch: Tolerance::new(0.0, 0.1, ""),
    classes: false,
    counted: |x| x > CHAOTIC_RLI,
    counted_as: "chaotic",
    counted_rule: "log10 RLI > -3",
};

static KINDS: [MapKindEntry; 1] = [MapKindEntry {
    quantity: &RLI,
    name: "rli",
    short: "rli",
    label: "relative Lyapunov indicator",
    legend: "Colour: log10 RLI, the mean difference of the finite-time exponents of two orbits 1e-8 apart ({ends}).",
    low: "regular, near the separation",
    high: "chaotic, of the order of the exponent",
    ranged: true,
    accurate: false,
    indicator: Some(Indicator::Rli { delta: DELTA_F64 }),
}];

fn separation(i: Indicator) -> f64 {
    match i {
        Indicator::Rli { delta } => delta,
        other => unreachable!("{other:?} is not the RLI"),
    }
}

impl Measure for Rli {
    fn names(&self) -> &'static [&'static str] {
        &["rli"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[(
            "rli",
            "log10 of the relative Lyapunov indicator, a neighbour {rli_delta} away",
        )]
    }
    fn options(&self, _name: &str) -> &'static [Opt] {
        &[DELTA]
    }
    fn asked(&self, _name: &str, asked: &IndicatorAsked) -> Indicator {
        let delta = asked.get(DELTA).unwrap_or(match asked.gpu_f32 {
            true => DELTA_F32,
            false => DELTA_F64,
        });
        Indicator::Rli { delta }
    }
    fn spelled(&self, i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        ("rli", vec![(DELTA, format!("{:e}", separation(i)))])
    }
    fn quantity(&self, _i: Indicator) -> &'static Quantity {
        &RLI
    }
    fn vectors(&self, _i: Indicator) -> u32 {
        2
    }
    fn title(&self, i: Indicator) -> String {
        format!("log10 RLI (neighbour {:e} away)", separation(i))
    }
    fn validate(&self, i: Indicator, precision: Precision) -> Result<()> {
        let delta = separation(i);
        let least = match precision {
            Precision::F32 => DELTA_F32,
            _ => 1e-12,
        };
        match (least..=1e-2).contains(&delta) {
            true => Ok(()),
            false => Err(Error::invalid(
                "rli_delta",
                format!(
                    "{delta:e} must be within {least:e}..1e-2 in {} (closer, the neighbour starts on the same numbers; further, it is no neighbour)",
                    precision.name()
                ),
            )),
        }
    }
    fn runs(&self, i: Indicator) -> Runs {
        Runs::Indicators(GpuEntry {
            entry: "rli_advance",
            adaptive: None,
            measure: 0,
            setting: separation(i),
            // A tangent step for each of the two orbits.
            cost: 2 * TANGENT_COST,
        })
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["rli", "delta_l"]
    }
    /// Both orbits stepped with a tangent vector each, renormalised every step, their
    /// lengths kept as logs; the running log10 RLI and |L_b - L_a| (1/s) sampled every
    /// `renorm`; NaN where either left the numbers.
    fn cpu(&self, i: Indicator, run: &mut CpuRun) -> Result<f64> {
        let (p, dt) = (&run.params, run.stepping.dt);
        let delta = separation(i);
        let mut a = run.start.to_array();
        let side = a.iter().find(|x| **x != 0.0).map_or(1.0, |x| x.signum());
        let mut b: [f64; 4] = std::array::from_fn(|k| a[k] + side * delta * TANGENT_START[k]);
        let (mut va, mut vb) = (TANGENT_START, TANGENT_START);
        let (mut ln_a, mut ln_b, mut sum) = (0.0f64, 0.0f64, 0.0f64);
        let steps = run.stepping.steps();
        for k in 1..=steps {
            let (next_a, wa) = tangent_step(p, &a, &va, dt);
            let (next_b, wb) = tangent_step(p, &b, &vb, dt);
            let (na, nb) = (norm(&wa), norm(&wb));
            (a, va, b, vb) = (next_a, wa.map(|x| x / na), next_b, wb.map(|x| x / nb));
            ln_a += na.ln();
            ln_b += nb.ln();
            let t = k as f64 * dt;
            let apart = (ln_a - ln_b).abs() / t;
            sum += apart;
            if !apart.is_finite() {
                return Ok(f64::NAN);
            }
            if run.renormalise(k) {
                (run.sample)(t, &[(sum / k as f64).log10(), apart]);
                (run.tick)(k)?;
            }
        }
        Ok((sum / steps as f64).log10())
    }
    fn look(&self, i: Indicator, t_max: f64) -> Look {
        Look {
            title: format!(
                "Relative Lyapunov indicator over {t_max} s, neighbours {:e} apart",
                separation(i)
            ),
            label: "log10 RLI".into(),
            unit: "",
            reversed: false,
        }
    }
    fn range_rule(&self, _i: Indicator, _t_max: f64) -> RangeRule {
        RangeRule::percentiles(0.005, 0.995)
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        vec![("rli", Indicator::Rli { delta: DELTA_F64 })]
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../shaders/rli.wgsl")
    }
}
