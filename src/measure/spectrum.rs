//! The Lyapunov spectrum: four tangent vectors kept orthonormal by modified Gram-Schmidt, one
//! exponent of it (in Gram-Schmidt order) or their sum; RK4 or DP54 steps.

use super::MapKindEntry;
use super::RangeRule;
use super::{CpuRun, GpuEntry, Indicator, IndicatorAsked, Look, Measure, Opt, Runs, TANGENT_COST};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::field::Precision;
use crate::quantity::{FTLE, FTLE_ABSOLUTE, Quantity, Tolerance};

pub struct Spectrum;

/// One exponent of the Lyapunov spectrum (1/s): the FTLE's rules, the first exponent being
/// the FTLE.
pub const EXPONENT: Quantity = Quantity {
    name: "Lyapunov exponent",
    counted_rule: "exponent > 0.5 /s",
    ..FTLE
};

/// The sum of the four exponents (1/s): 0 without losses, the mean phase-space contraction
/// rate with them.
pub const EXPONENT_SUM: Quantity = Quantity {
    name: "sum of the Lyapunov exponents",
    unit: "1/s",
    // Its scale is the volume change over t (ln 2 / t at most for equal masses), not the
    // exponents': 0.005 /s absolute.
    value: "a sum",
    agree: Tolerance::new(0.05, 0.005, " /s"),
    vouch: Tolerance::new(0.01, 0.001, " /s"),
    classes: false,
    counted: |x| x < -FTLE_ABSOLUTE as f32,
    counted_as: "contracting",
    counted_rule: "sum < -0.02 /s",
};

/// Which exponent of the spectrum.
const WHICH: Opt = Opt {
    field: "exponent",
    help: "Which exponent {indicator} exponent maps, 1..4, in Gram-Schmidt order: the k-th orthonormalised tangent vector's growth. The first is the largest; at a finite time the others are not sorted per pixel (exponents 3 and 4 cross where both are near 0).",
    whole: Some((1, 4)),
    offered: &[],
};

static KINDS: [MapKindEntry; 2] = [
    MapKindEntry {
        quantity: &EXPONENT,
        name: "exponent",
        short: "exponent",
        label: "Lyapunov exponent λ2",
        legend: "Colour: the second of the four Lyapunov exponents (four tangent vectors kept orthonormal); about 0 where the motion is regular or the chaos has one unstable direction.",
        low: "",
        high: "",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::Exponent(2)),
    },
    MapKindEntry {
        quantity: &EXPONENT_SUM,
        name: "exponent-sum",
        short: "exponent-sum",
        label: "sum of the exponents",
        legend: "Colour: λ1 + λ2 + λ3 + λ4: 0 without losses (the flow keeps phase-space volume), the mean contraction rate with them.",
        low: "",
        high: "",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::ExponentSum),
    },
];

/// Which exponent `i` maps (None: their sum).
fn which(i: Indicator) -> Option<u8> {
    match i {
        Indicator::Exponent(k) => Some(k),
        _ => None,
    }
}

/// The map's value from the four log sums over `t_end`.
fn value(i: Indicator, sums: &[f64], t_end: f64) -> f64 {
    match which(i) {
        Some(k) => sums[k as usize - 1] / t_end,
        None => sums.iter().sum::<f64>() / t_end,
    }
}

impl Measure for Spectrum {
    fn names(&self) -> &'static [&'static str] {
        &["exponent", "exponent-sum"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[
            ("exponent", "one of the four, {exponent}"),
            ("exponent-sum", ""),
        ]
    }
    fn options(&self, name: &str) -> &'static [Opt] {
        match name {
            "exponent" => &[WHICH],
            _ => &[],
        }
    }
    fn asked(&self, name: &str, asked: &IndicatorAsked) -> Indicator {
        match name {
            "exponent" => Indicator::Exponent(asked.get(WHICH).map_or(1, |k| k as u8)),
            _ => Indicator::ExponentSum,
        }
    }
    fn spelled(&self, i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        match which(i) {
            Some(k) => ("exponent", vec![(WHICH, k.to_string())]),
            None => ("exponent-sum", Vec::new()),
        }
    }
    fn quantity(&self, i: Indicator) -> &'static Quantity {
        match which(i) {
            Some(_) => &EXPONENT,
            None => &EXPONENT_SUM,
        }
    }
    fn vectors(&self, _i: Indicator) -> u32 {
        4
    }
    fn title(&self, i: Indicator) -> String {
        match which(i) {
            Some(k) => format!("Lyapunov exponent {k} of 4"),
            None => "sum of the Lyapunov exponents".into(),
        }
    }
    fn validate(&self, i: Indicator, _precision: Precision) -> Result<()> {
        match which(i) {
            Some(k) if !(1..=4).contains(&k) => Err(Error::invalid(
                "exponent",
                format!("{k} must be 1, 2, 3 or 4 (in Gram-Schmidt order)"),
            )),
            _ => Ok(()),
        }
    }
    fn adaptive(&self) -> bool {
        true
    }
    fn runs(&self, i: Indicator) -> Runs {
        Runs::Indicators(GpuEntry {
            entry: "spectrum_advance",
            adaptive: Some("spectrum_adaptive"),
            // 0..3: exponent 1..4; 4: their sum.
            measure: which(i).map_or(4, |k| k as u32 - 1),
            setting: 0.0,
            cost: TANGENT_COST * 4,
        })
    }
    /// The kernel keeps log sums: an exponent is one over the run's time.
    fn finish(&self, _i: Indicator, raw: f64, t_end: f64) -> f32 {
        (raw / t_end) as f32
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["lambda1", "lambda2", "lambda3", "lambda4", "sum"]
    }
    fn cpu(&self, i: Indicator, run: &mut CpuRun) -> Result<f64> {
        let t_end = run.stepping.steps() as f64 * run.stepping.dt;
        let sums = match run.integrator.tolerances() {
            Some(_) => crate::cpu::spectrum_adaptive(run)?.to_vec(),
            None => crate::cpu::tangent_sums(run, 4)?,
        };
        Ok(value(i, &sums, t_end))
    }
    fn of_spectrum(&self, i: Indicator, layers: &[Field; 4]) -> Option<Field> {
        Some(match which(i) {
            Some(k) => layers[k as usize - 1].clone(),
            None => Field {
                data: (0..layers[0].data.len())
                    .map(|p| layers.iter().map(|l| l.data[p]).sum())
                    .collect(),
                ..layers[0].clone()
            },
        })
    }
    fn look(&self, i: Indicator, t_max: f64) -> Look {
        let (title, label) = match which(i) {
            Some(k) => (format!("Lyapunov exponent {k} of 4"), format!("λ{k} (1/s)")),
            None => (
                "Sum of the four Lyapunov exponents".into(),
                "Σλ (1/s)".into(),
            ),
        };
        Look {
            title: format!("{title} over {t_max} s"),
            label,
            unit: "1/s",
            reversed: false,
        }
    }
    /// The first exponent as the FTLE; the others and the sum from their 0.5th to 99.5th
    /// percentile (they take either sign).
    fn range_rule(&self, i: Indicator, _t_max: f64) -> RangeRule {
        match which(i) {
            Some(1) => super::FTLE_RANGE,
            _ => RangeRule::percentiles(0.005, 0.995),
        }
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    /// The four-vector kernel (any exponent costs the same).
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        vec![("spectrum", Indicator::Exponent(1))]
    }
}
