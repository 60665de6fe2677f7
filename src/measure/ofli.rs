//! The orthogonal fast Lyapunov indicator (Fouchard, Froeschlé, Valsecchi, Rickman 2002): the
//! largest log10 |v_perp| so far of one tangent vector's part across the flow f,
//! v_perp = v - (v . f) f / |f|^2. Among regular orbits it tells periodic ones (bounded: a
//! periodic orbit's tangent vectors shear only along the flow) from quasi-periodic ones
//! (growing like log t); chaotic orbits grow like λ t, as for the FLI. Its kernel is
//! `shaders/ofli.wgsl`; its CPU twin, below, steps with the FTLE's dual numbers.

use super::MapKindEntry;
use super::growth::CHAOTIC_FLI;
use super::{CpuRun, GpuEntry, Indicator, IndicatorAsked, Look, Measure, Opt, Runs, TANGENT_COST};
use super::{End, RangeRule};
use crate::cpu::{TANGENT_START, derivative, norm, tangent_step};
use crate::error::Result;
use crate::model::{Params, State};
use crate::quantity::{Quantity, Tolerance};

pub struct Ofli;

/// The largest log10 |v_perp| at t-max.
pub const OFLI: Quantity = Quantity {
    name: "orthogonal fast Lyapunov indicator",
    unit: "1 (log10)",
    // As the FLI's: it is the FLI less log10 of the cosine-free part, of the same scale.
    value: "an OFLI",
    agree: Tolerance::new(0.05, 0.1, ""),
    vouch: Tolerance::new(0.01, 0.02, ""),
    classes: false,
    counted: |x| x > CHAOTIC_FLI,
    counted_as: "chaotic",
    counted_rule: "OFLI > 5",
};

static KINDS: [MapKindEntry; 1] = [MapKindEntry {
    quantity: &OFLI,
    name: "ofli",
    short: "ofli",
    label: "orthogonal FLI",
    legend: "Colour: OFLI, the largest log10 of a tangent vector's part across the flow ({ends}).",
    low: "periodic, stays bounded; quasi-periodic grows like log t",
    high: "chaotic, like λ t",
    ranged: true,
    accurate: false,
    indicator: Some(Indicator::Ofli),
}];

/// log10 |v_perp| of `v` at the state `y` (|v| where the flow stops).
fn log10_across(p: &Params, y: &[f64; 4], v: &[f64; 4]) -> f64 {
    let f = derivative(p, &State::from_array(*y)).to_array();
    let ff: f64 = f.iter().map(|x| x * x).sum();
    let along = match ff > 0.0 {
        true => v.iter().zip(&f).map(|(a, b)| a * b).sum::<f64>() / ff,
        false => 0.0,
    };
    let across: f64 = (0..4).map(|i| (v[i] - along * f[i]).powi(2)).sum();
    across.sqrt().log10()
}

impl Measure for Ofli {
    fn names(&self) -> &'static [&'static str] {
        &["ofli"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[(
            "ofli",
            "the orthogonal FLI: periodic orbits bounded, quasi-periodic ones growing like log t",
        )]
    }
    fn options(&self, _name: &str) -> &'static [Opt] {
        &[]
    }
    fn asked(&self, _name: &str, _asked: &IndicatorAsked) -> Indicator {
        Indicator::Ofli
    }
    fn spelled(&self, _i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        ("ofli", Vec::new())
    }
    fn quantity(&self, _i: Indicator) -> &'static Quantity {
        &OFLI
    }
    fn vectors(&self, _i: Indicator) -> u32 {
        1
    }
    fn title(&self, _i: Indicator) -> String {
        "OFLI (log10 |v_perp|)".into()
    }
    fn runs(&self, _i: Indicator) -> Runs {
        Runs::Indicators(GpuEntry {
            entry: "ofli_advance",
            adaptive: None,
            measure: 0,
            setting: 0.0,
            // A tangent step and one rate for the flow's direction.
            cost: TANGENT_COST + 1,
        })
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["ofli", "fli"]
    }
    /// One vector renormalised every step, its length kept as a log; the OFLI and the FLI
    /// sampled every `renorm`; NaN where it left the numbers.
    fn cpu(&self, _i: Indicator, run: &mut CpuRun) -> Result<f64> {
        let (p, dt) = (&run.params, run.stepping.dt);
        let mut y = run.start.to_array();
        let mut v = TANGENT_START;
        let mut ofli = log10_across(p, &y, &v);
        let (mut log10_length, mut fli) = (0.0, 0.0f64);
        for k in 1..=run.stepping.steps() {
            let (next, w) = tangent_step(p, &y, &v, dt);
            let n = norm(&w);
            (y, v) = (next, w.map(|x| x / n));
            log10_length += n.log10();
            fli = fli.max(log10_length);
            ofli = ofli.max(log10_length + log10_across(p, &y, &v));
            if run.renormalise(k) {
                (run.sample)(k as f64 * run.stepping.dt, &[ofli, fli]);
                (run.tick)(k)?;
            }
            if !log10_length.is_finite() {
                return Ok(f64::NAN);
            }
        }
        Ok(ofli)
    }
    fn look(&self, _i: Indicator, t_max: f64) -> Look {
        Look {
            title: format!("Orthogonal FLI over {t_max} s: the largest log10 |v⊥| across the flow"),
            label: "OFLI".into(),
            unit: "",
            reversed: false,
        }
    }
    /// From its 0.5th percentile (it may start below 0: v's part across the flow is shorter
    /// than v) to its 99.5th, at least to 1: a regular map is then drawn dark.
    fn range_rule(&self, _i: Indicator, _t_max: f64) -> RangeRule {
        RangeRule {
            low: End::Quantile { bound: Some(0.0) },
            high: End::Quantile { bound: Some(1.0) },
            ..RangeRule::percentiles(0.005, 0.995)
        }
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        vec![("ofli", Indicator::Ofli)]
    }
    fn wgsl(&self) -> &'static str {
        include_str!("../../shaders/ofli.wgsl")
    }
}
