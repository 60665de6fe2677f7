//! The Lagrangian descriptor M (Lopesino et al. 2017): the integral of sum_i |f_i|^p of the
//! phase-space velocity f over [-t-max, t-max], one plain trajectory each way.

use super::MapKindEntry;
use super::RangeRule;
use super::{CpuRun, GpuEntry, Indicator, IndicatorAsked, Look, Measure, Opt, Runs};
use crate::error::{Error, Result};
use crate::field::Precision;
use crate::model::Params;
use crate::quantity::{Quantity, Tolerance};

/// The exponents p a Lagrangian descriptor takes.
pub const DESCRIPTOR_POWERS: [f64; 4] = [0.25, 0.5, 1.0, 2.0];

pub struct Descriptor;

/// The Lagrangian descriptor M (the unit of |f|^p times s; f mixes rad/s and rad/s^2).
pub const DESCRIPTOR: Quantity = Quantity {
    name: "Lagrangian descriptor",
    unit: "sum of |f_i|^p s",
    value: "M",
    agree: Tolerance::new(0.01, 1e-3, ""),
    vouch: Tolerance::new(0.002, 2e-4, ""),
    classes: false,
    counted: f32::is_finite,
    counted_as: "finite",
    counted_rule: "M finite",
};

/// The power p of the descriptor's sum.
const POWER: Opt = Opt {
    field: "ld_p",
    help: "The exponent p of the descriptor's sum of |f_i|^p: 0.25, 0.5, 1 or 2.",
    whole: None,
    offered: &[0.25, 0.5, 1.0, 2.0],
};

static KINDS: [MapKindEntry; 1] = [MapKindEntry {
    quantity: &DESCRIPTOR,
    name: "descriptor",
    short: "descriptor",
    label: "Lagrangian descriptor",
    legend: "Colour: the Lagrangian descriptor M, the integral of Σ|f_i|^0.5 of the phase-space velocity over [-t-max, t-max]; its sharp ridges and valleys trace the stable and unstable manifolds.",
    low: "",
    high: "",
    ranged: true,
    accurate: false,
    indicator: Some(Indicator::Descriptor { p: 0.5 }),
}];

fn power(i: Indicator) -> f64 {
    match i {
        Indicator::Descriptor { p } => p,
        other => unreachable!("{other:?} is not a descriptor"),
    }
}

impl Measure for Descriptor {
    fn names(&self) -> &'static [&'static str] {
        &["descriptor"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[(
            "descriptor",
            "the Lagrangian descriptor M over [-t-max, t-max], {ld_p}",
        )]
    }
    fn options(&self, _name: &str) -> &'static [Opt] {
        &[POWER]
    }
    fn asked(&self, _name: &str, asked: &IndicatorAsked) -> Indicator {
        Indicator::Descriptor {
            p: asked.get(POWER).unwrap_or(0.5),
        }
    }
    fn spelled(&self, i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        ("descriptor", vec![(POWER, power(i).to_string())])
    }
    fn quantity(&self, _i: Indicator) -> &'static Quantity {
        &DESCRIPTOR
    }
    fn vectors(&self, _i: Indicator) -> u32 {
        0
    }
    fn title(&self, i: Indicator) -> String {
        format!("Lagrangian descriptor M (p = {})", power(i))
    }
    fn validate(&self, i: Indicator, _precision: Precision) -> Result<()> {
        let p = power(i);
        match DESCRIPTOR_POWERS.contains(&p) {
            true => Ok(()),
            false => Err(Error::invalid(
                "ld_p",
                format!(
                    "{p} must be 0.25, 0.5, 1 or 2 (the powers made of square roots and products, which every GPU has in f64)"
                ),
            )),
        }
    }
    /// One plain trajectory each way: nothing renormalised.
    fn renormalised(&self) -> bool {
        false
    }
    fn runs(&self, i: Indicator) -> Runs {
        Runs::Indicators(GpuEntry {
            entry: "descriptor_advance",
            adaptive: None,
            measure: 0,
            setting: power(i),
            // Two plain steps, one each way.
            cost: 2,
        })
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["descriptor"]
    }
    fn cpu(&self, i: Indicator, run: &mut CpuRun) -> Result<f64> {
        crate::cpu::descriptor_run(run, power(i))
    }
    fn look(&self, i: Indicator, t_max: f64) -> Look {
        Look {
            title: format!(
                "Lagrangian descriptor M over [-{t_max}, {t_max}] s, p = {}",
                power(i)
            ),
            label: "M".into(),
            unit: "",
            reversed: false,
        }
    }
    fn range_rule(&self, _i: Indicator, _t_max: f64) -> RangeRule {
        RangeRule::percentiles(0.005, 0.995)
    }
    /// With losses the backward half runs anti-damped: say so.
    fn notices(&self, _i: Indicator, params: &Params) -> Vec<String> {
        match params.losses.kinds() {
            0 => Vec::new(),
            _ => vec![
                "note: with losses the descriptor's backward run is anti-damped (energy grows as it goes back), and a start may leave the numbers (NaN); a shorter [[t_max]] keeps more"
                    .into(),
            ],
        }
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        vec![("descriptor", Indicator::Descriptor { p: 0.5 })]
    }
}
