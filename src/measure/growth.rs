//! The growth of one tangent vector renormalised every step: MEGNO, the mean exponential
//! growth of nearby orbits (Cincotta and Simó 2000), and the fast Lyapunov indicator, the
//! largest log10 |v| so far (Froeschlé, Lega, Gonczi 1997).

use super::MapKindEntry;
use super::{CpuRun, GpuEntry, Indicator, IndicatorAsked, Look, Measure, Opt, Runs, TANGENT_COST};
use super::{End, RangeRule};
use crate::error::Result;
use crate::quantity::{Quantity, Tolerance};

pub struct Growth;

/// <Y> above this calls a start chaotic in the summary (regular orbits tend to 2 or 0).
pub const CHAOTIC_MEGNO: f32 = 4.0;

/// MEGNO <Y> at t-max (1).
pub const MEGNO: Quantity = Quantity {
    name: "MEGNO",
    unit: "1",
    value: "<Y>",
    agree: Tolerance::new(0.1, 0.2, ""),
    vouch: Tolerance::new(0.02, 0.04, ""),
    classes: false,
    counted: |x| x > CHAOTIC_MEGNO,
    counted_as: "chaotic",
    counted_rule: "<Y> > 4",
};

/// FLI above this (log10 |v|) calls a start chaotic in the summary: a regular orbit's tangent
/// vector grows like t, to about 10^2.5 in a few minutes of simulated time.
pub const CHAOTIC_FLI: f32 = 5.0;

/// The fast Lyapunov indicator: the largest log10 |v| so far (1).
pub const FLI: Quantity = Quantity {
    name: "fast Lyapunov indicator",
    unit: "1 (log10)",
    value: "an FLI",
    agree: Tolerance::new(0.05, 0.1, ""),
    vouch: Tolerance::new(0.01, 0.02, ""),
    classes: false,
    counted: |x| x > CHAOTIC_FLI,
    counted_as: "chaotic",
    counted_rule: "FLI > 5",
};

static KINDS: [MapKindEntry; 2] = [
    MapKindEntry {
        quantity: &MEGNO,
        name: "megno",
        short: "megno",
        label: "MEGNO <Y>",
        legend: "Colour: MEGNO <Y> ({ends}).",
        low: "regular, tends to 2, or 0 for isochronous motion",
        high: "chaotic, grows like λ t / 2",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::Megno),
    },
    MapKindEntry {
        quantity: &FLI,
        name: "fli",
        short: "fli",
        label: "fast Lyapunov indicator",
        legend: "Colour: FLI, the largest log10 |v| of a tangent vector so far ({ends}).",
        low: "regular, grows like log t",
        high: "chaotic, like λ t",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::Fli),
    },
];

fn is_megno(i: Indicator) -> bool {
    i == Indicator::Megno
}

impl Measure for Growth {
    fn names(&self) -> &'static [&'static str] {
        &["megno", "fli"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[("megno", "<Y>"), ("fli", "the fast Lyapunov indicator")]
    }
    fn options(&self, _name: &str) -> &'static [Opt] {
        &[]
    }
    fn asked(&self, name: &str, _asked: &IndicatorAsked) -> Indicator {
        match name {
            "megno" => Indicator::Megno,
            _ => Indicator::Fli,
        }
    }
    fn spelled(&self, i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        (if is_megno(i) { "megno" } else { "fli" }, Vec::new())
    }
    fn quantity(&self, i: Indicator) -> &'static Quantity {
        if is_megno(i) { &MEGNO } else { &FLI }
    }
    fn vectors(&self, _i: Indicator) -> u32 {
        1
    }
    fn title(&self, i: Indicator) -> String {
        match is_megno(i) {
            true => "MEGNO <Y>".into(),
            false => "FLI (log10 |v|)".into(),
        }
    }
    fn runs(&self, i: Indicator) -> Runs {
        Runs::Indicators(GpuEntry {
            entry: "growth_advance",
            adaptive: None,
            // 0: <Y>, 1: the FLI.
            measure: !is_megno(i) as u32,
            setting: 0.0,
            cost: TANGENT_COST,
        })
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["megno", "y", "fli"]
    }
    fn cpu(&self, i: Indicator, run: &mut CpuRun) -> Result<f64> {
        let (megno, fli) = crate::cpu::growth_run(run)?;
        Ok(if is_megno(i) { megno } else { fli })
    }
    fn look(&self, i: Indicator, t_max: f64) -> Look {
        match is_megno(i) {
            true => Look {
                title: format!("MEGNO over {t_max} s (2: regular; chaotic: grows like λt/2)"),
                label: "<Y>".into(),
                unit: "",
                reversed: false,
            },
            false => Look {
                title: format!("Fast Lyapunov indicator over {t_max} s: the largest log10 |v|"),
                label: "FLI".into(),
                unit: "",
                reversed: false,
            },
        }
    }
    /// 0 to the 99.5th percentile, at least to 4 (MEGNO) or 1 (the FLI): a regular map is
    /// then drawn dark, not stretched over its small spread.
    /// From 0 to the 99.5th percentile, at least to 4 (MEGNO: regular motion's 2, doubled)
    /// or 1 (the FLI).
    fn range_rule(&self, i: Indicator, _t_max: f64) -> RangeRule {
        let floor = if is_megno(i) { 4.0 } else { 1.0 };
        RangeRule {
            low: End::Fixed(0.0),
            high: End::Quantile { bound: Some(floor) },
            ..RangeRule::percentiles(0.0, 0.995)
        }
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        vec![("megno", Indicator::Megno), ("fli", Indicator::Fli)]
    }
}
