//! The largest finite-time Lyapunov exponent: one tangent vector (or a twin), the divergence
//! kernel's map, the one measure with accurate settings.

use super::MapKindEntry;
use super::{CpuRun, Indicator, Look, Measure, Opt, Runs};
use super::{FTLE_RANGE, RangeRule};
use crate::error::Result;
use crate::quantity::{FTLE, Quantity};

pub struct Ftle;

static KINDS: [MapKindEntry; 1] = [MapKindEntry {
    quantity: &FTLE,
    name: "lyapunov",
    short: "ftle",
    label: "divergence (FTLE)",
    legend: "Colour: largest finite-time Lyapunov exponent ({ends}).",
    low: "regular",
    high: "chaotic",
    ranged: true,
    accurate: true,
    indicator: Some(Indicator::Ftle),
}];

impl Measure for Ftle {
    fn names(&self) -> &'static [&'static str] {
        &["ftle"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[("ftle", "the largest exponent")]
    }
    fn options(&self, _name: &str) -> &'static [Opt] {
        &[]
    }
    fn asked(&self, _name: &str, _asked: &super::IndicatorAsked) -> Indicator {
        Indicator::Ftle
    }
    fn spelled(&self, _i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        ("ftle", Vec::new())
    }
    fn quantity(&self, _i: Indicator) -> &'static Quantity {
        &FTLE
    }
    fn vectors(&self, _i: Indicator) -> u32 {
        1
    }
    fn title(&self, _i: Indicator) -> String {
        "largest FTLE".into()
    }
    fn short_title(&self, _i: Indicator) -> String {
        "FTLE".into()
    }
    fn accurate(&self) -> bool {
        true
    }
    fn adaptive(&self) -> bool {
        true
    }
    fn tangent_only(&self) -> bool {
        false
    }
    fn runs(&self, _i: Indicator) -> Runs {
        Runs::Divergence
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["ftle"]
    }
    fn cpu(&self, _i: Indicator, run: &mut CpuRun) -> Result<f64> {
        let t_end = run.stepping.steps() as f64 * run.stepping.dt;
        Ok(crate::cpu::tangent_sums(run, 1)?[0] / t_end)
    }
    fn look(&self, _i: Indicator, t_max: f64) -> Look {
        Look {
            title: format!("Largest finite-time Lyapunov exponent over {t_max} s"),
            label: "FTLE (1/s)".into(),
            unit: "1/s",
            reversed: false,
        }
    }
    fn range_rule(&self, _i: Indicator, _t_max: f64) -> RangeRule {
        FTLE_RANGE
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        vec![("ftle", Indicator::Ftle)]
    }
}
