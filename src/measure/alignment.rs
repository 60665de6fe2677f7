//! Alignment indices of normalised tangent vectors: SALI (Skokos 2001) and GALI_k (Skokos,
//! Bountis, Antonopoulos 2007), as log10 of the index or the time it fell below its
//! threshold (where the start is called chaotic and stops).

use super::MapKindEntry;
use super::RangeRule;
use super::indicator::{ALIGNED, ALIGNED_F32_FLOOR, Alignment};
use super::{CpuRun, GpuEntry, Indicator, IndicatorAsked, Look, Measure, Opt, Runs, TANGENT_COST};
use crate::error::{Error, Result};
use crate::field::Precision;
use crate::gpu::layout::NEVER;
use crate::quantity::{Quantity, Tolerance};

/// An alignment threshold that nothing reaches, so that every pixel runs every step (the
/// bench's peer has no early stop): its rows time the indicator's work, not the map's.
const NEVER_ALIGNED: f64 = 1e-300;

pub struct AlignmentIndex;

/// Alignment indices (log10) agree within this many decades.
pub const ALIGNMENT_DECADES: f64 = 0.5;

/// log10 of an alignment index at or below this calls a start chaotic in the summary: SALI
/// of a regular orbit stays near 1e-1..1, GALI_k of a regular orbit decays like a power of
/// t, far slower than 1e-4 within a map's minutes of simulated time.
pub const ALIGNED_LOG10: f32 = -4.0;

/// log10 SALI at t-max, or where it fell below the threshold.
pub const SALI: Quantity = Quantity {
    name: "log10 SALI",
    unit: "1 (log10)",
    value: "log10 SALI",
    agree: Tolerance::new(0.0, ALIGNMENT_DECADES, " decades"),
    vouch: Tolerance::new(0.0, 0.1, " decades"),
    classes: false,
    // The map counts the starts below its threshold (spec::LyapunovSpec::counted).
    counted: |x| x <= ALIGNED_LOG10,
    counted_as: "chaotic",
    counted_rule: "log10 SALI <= -4",
};

/// log10 GALI_k at t-max, or where it fell below the threshold: SALI's rules.
pub const GALI: Quantity = Quantity {
    name: "log10 GALI",
    value: "log10 GALI",
    counted_rule: "log10 GALI <= -4",
    ..SALI
};

/// The time an alignment index fell below its threshold (s; +inf = not within t-max).
pub const ALIGNMENT_TIME: Quantity = Quantity {
    name: "time to alignment",
    unit: "s",
    value: "a time",
    agree: Tolerance::new(0.05, 0.1, " s").time("aligning"),
    vouch: Tolerance::new(0.01, 0.02, " s").time("aligning"),
    classes: false,
    counted: f32::is_finite,
    counted_as: "chaotic",
    counted_rule: "aligned within t-max",
};

/// GALI's order.
const ORDER: Opt = Opt {
    field: "gali",
    help: "Tangent vectors of {indicator} gali or gali-time, 2..4.",
    whole: Some((2, 4)),
    offered: &[],
};

/// The index below which a start is called chaotic.
const THRESHOLD: Opt = Opt {
    field: "threshold",
    help: "The alignment index below which a start is called chaotic and stops [default: 1e-8; f32 resolves 1e-5 at best, its default there].",
    whole: None,
    offered: &[1e-5, 1e-4, 1e-3],
};

static KINDS: [MapKindEntry; 3] = [
    MapKindEntry {
        quantity: &SALI,
        name: "sali",
        short: "sali",
        label: "alignment index SALI",
        legend: "Colour: log10 SALI of two tangent vectors ({ends}).",
        low: "chaotic, SALI falls to its threshold, 1e-5 here, and the pixel stops",
        high: "regular, SALI stays near 1",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::Alignment {
            index: Alignment::Sali,
            threshold: ALIGNED_F32_FLOOR,
        }),
    },
    MapKindEntry {
        quantity: &GALI,
        name: "gali",
        short: "gali",
        label: "alignment index GALI_4",
        legend: "Colour: log10 GALI_4, the volume spanned by four unit tangent vectors ({ends}).",
        low: "chaotic, decays exponentially to the threshold, 1e-5 here",
        high: "regular, decays like t^-4, so its colour moves with t-max too",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::Alignment {
            index: Alignment::Gali(4),
            threshold: ALIGNED_F32_FLOOR,
        }),
    },
    MapKindEntry {
        quantity: &ALIGNMENT_TIME,
        name: "alignment-time",
        short: "alignment-time",
        label: "time until SALI aligns",
        legend: "Colour: the time SALI took to fall below its threshold, 1e-5 here ({ends}); black: not within t-max (regular).",
        low: "soon, strongly chaotic",
        high: "late",
        ranged: true,
        accurate: false,
        indicator: Some(Indicator::AlignmentTime {
            index: Alignment::Sali,
            threshold: ALIGNED_F32_FLOOR,
        }),
    },
];

/// The index, its threshold and whether the map is the time it fell below it.
fn parts(i: Indicator) -> (Alignment, f64, bool) {
    match i {
        Indicator::Alignment { index, threshold } => (index, threshold, false),
        Indicator::AlignmentTime { index, threshold } => (index, threshold, true),
        other => unreachable!("{other:?} is not an alignment index"),
    }
}

impl Measure for AlignmentIndex {
    fn names(&self) -> &'static [&'static str] {
        &["sali", "sali-time", "gali", "gali-time"]
    }
    fn about(&self) -> &'static [(&'static str, &'static str)] {
        &[
            (
                "sali or gali",
                "log10 of an alignment index of 2 or {gali} tangent vectors; a start stops, called chaotic, once it falls below {threshold}",
            ),
            ("sali-time or gali-time", "the time that took"),
        ]
    }
    fn options(&self, name: &str) -> &'static [Opt] {
        match name.starts_with("gali") {
            true => &[ORDER, THRESHOLD],
            false => &[THRESHOLD],
        }
    }
    fn asked(&self, name: &str, asked: &IndicatorAsked) -> Indicator {
        let index = match name.starts_with("gali") {
            true => Alignment::Gali(asked.get(ORDER).map_or(4, |k| k as u8)),
            false => Alignment::Sali,
        };
        // f32 on the GPU resolves an alignment index to about 1e-5: its default there.
        let threshold = asked.get(THRESHOLD).unwrap_or(match asked.gpu_f32 {
            true => ALIGNED_F32_FLOOR,
            false => ALIGNED,
        });
        match name.ends_with("-time") {
            true => Indicator::AlignmentTime { index, threshold },
            false => Indicator::Alignment { index, threshold },
        }
    }
    fn spelled(&self, i: Indicator) -> (&'static str, Vec<(Opt, String)>) {
        let (index, threshold, time) = parts(i);
        let threshold = (THRESHOLD, format!("{threshold:e}"));
        match (index, time) {
            (Alignment::Sali, false) => ("sali", vec![threshold]),
            (Alignment::Sali, true) => ("sali-time", vec![threshold]),
            (Alignment::Gali(k), time) => (
                if time { "gali-time" } else { "gali" },
                vec![(ORDER, k.to_string()), threshold],
            ),
        }
    }
    fn quantity(&self, i: Indicator) -> &'static Quantity {
        match parts(i) {
            (_, _, true) => &ALIGNMENT_TIME,
            (Alignment::Sali, _, _) => &SALI,
            (Alignment::Gali(_), _, _) => &GALI,
        }
    }
    fn vectors(&self, i: Indicator) -> u32 {
        parts(i).0.vectors()
    }
    fn title(&self, i: Indicator) -> String {
        match parts(i) {
            (index, threshold, true) => format!("time until {} < {threshold:e}", index.name()),
            (index, _, false) => format!("log10 {}", index.name()),
        }
    }
    fn validate(&self, i: Indicator, precision: Precision) -> Result<()> {
        let (index, threshold, _) = parts(i);
        if let Alignment::Gali(k) = index
            && !(2..=4).contains(&k)
        {
            return Err(Error::invalid(
                "gali",
                format!("{k} must be 2, 3 or 4 tangent vectors"),
            ));
        }
        if !(threshold.is_finite() && threshold > 0.0 && threshold < 1.0) {
            return Err(Error::invalid(
                "threshold",
                format!("{threshold:e} must be in (0, 1)"),
            ));
        }
        if precision == Precision::F32 && threshold < ALIGNED_F32_FLOOR {
            return Err(Error::invalid(
                "threshold",
                format!(
                    "{threshold:e} is below what f32 resolves of an alignment index ({ALIGNED_F32_FLOOR:e}, its round-off): take [[precision=f64]] or a threshold >= {ALIGNED_F32_FLOOR:e}"
                ),
            ));
        }
        Ok(())
    }
    fn runs(&self, i: Indicator) -> Runs {
        let (index, threshold, time) = parts(i);
        Runs::Indicators(GpuEntry {
            entry: match index {
                Alignment::Sali => "sali_advance",
                Alignment::Gali(2) => "gali2_advance",
                Alignment::Gali(3) => "gali3_advance",
                Alignment::Gali(_) => "gali4_advance",
            },
            adaptive: None,
            measure: time as u32,
            setting: threshold,
            cost: TANGENT_COST * index.vectors() as u64,
        })
    }
    fn finish(&self, i: Indicator, raw: f64, _t_end: f64) -> f32 {
        match parts(i).2 && raw == NEVER as f64 {
            true => f32::INFINITY,
            false => raw as f32,
        }
    }
    fn columns(&self, _i: Indicator) -> &'static [&'static str] {
        &["log10_index"]
    }
    fn cpu(&self, i: Indicator, run: &mut CpuRun) -> Result<f64> {
        let (index, threshold, time) = parts(i);
        let (log, aligned_at) = crate::cpu::alignment_run(run, index, threshold)?;
        Ok(match (time, log.is_nan()) {
            (_, true) => f64::NAN,
            (true, false) => aligned_at,
            (false, false) => log,
        })
    }
    fn look(&self, i: Indicator, t_max: f64) -> Look {
        let (index, threshold, time) = parts(i);
        match time {
            false => Look {
                title: format!(
                    "Alignment index {} over {t_max} s (a start stops below {threshold:e})",
                    index.name()
                ),
                label: format!("log10 {}", index.name()),
                unit: "(log10)",
                reversed: true,
            },
            true => Look {
                title: format!(
                    "Time until {} < {threshold:e} within {t_max} s (black: never)",
                    index.name()
                ),
                label: "time (s)".into(),
                unit: "s",
                reversed: true,
            },
        }
    }
    /// The threshold to 1 for the index, 0 to t-max for its time.
    fn range_rule(&self, i: Indicator, t_max: f64) -> RangeRule {
        match parts(i) {
            (_, _, true) => RangeRule::fixed(0.0, t_max as f32),
            (_, threshold, false) => RangeRule::fixed(threshold.log10() as f32, 0.0),
        }
    }
    /// The map counts the starts it stopped: those below its threshold (a running pixel's
    /// last value is at or above it).
    fn counted(&self, i: Indicator, x: f32) -> bool {
        match parts(i) {
            (_, threshold, false) => (x as f64) < threshold.log10(),
            _ => (self.quantity(i).counted)(x),
        }
    }
    fn counted_rule(&self, i: Indicator) -> String {
        match parts(i) {
            (index, threshold, false) => format!("{} fell below {threshold:e}", index.name()),
            _ => self.quantity(i).counted_rule.to_string(),
        }
    }
    fn kinds(&self) -> &'static [MapKindEntry] {
        &KINDS
    }
    fn bench(&self) -> Vec<(&'static str, Indicator)> {
        let threshold = NEVER_ALIGNED;
        vec![
            (
                "sali",
                Indicator::Alignment {
                    index: Alignment::Sali,
                    threshold,
                },
            ),
            (
                "gali4",
                Indicator::Alignment {
                    index: Alignment::Gali(4),
                    threshold,
                },
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_out_of_range_are_refused_naming_their_field() {
        let field = |i: Indicator, p| match i.validate(p) {
            Err(Error::InvalidSpec { field, .. }) => field,
            other => panic!("{i:?}: {other:?}"),
        };
        let gali = |k, threshold| Indicator::Alignment {
            index: Alignment::Gali(k),
            threshold,
        };
        assert_eq!(field(gali(5, ALIGNED), Precision::F64), "gali");
        assert_eq!(field(gali(3, 2.0), Precision::F64), "threshold");
        assert_eq!(field(gali(3, ALIGNED), Precision::F32), "threshold");
        assert!(gali(3, ALIGNED).validate(Precision::F64).is_ok());
        assert_eq!(field(Indicator::Exponent(5), Precision::F64), "exponent");
        assert_eq!(
            field(Indicator::Descriptor { p: 0.0 }, Precision::F64),
            "ld_p"
        );
    }
}
