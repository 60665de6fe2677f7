//! What a divergence-family map measures of each start: the largest exponent (today's FTLE
//! map), one exponent of the spectrum or their sum, an alignment index (SALI, GALI_k) or the
//! time it took to fall below its threshold, MEGNO, the FLI, or a Lagrangian descriptor. All
//! but the descriptor follow tangent vectors along the orbit, renormalised every `renorm`.

use crate::error::{Error, Result};
use crate::quantity::{self, Quantity};
use crate::spec::Precision;

/// Which alignment index of normalised tangent vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Alignment {
    /// The smaller alignment index of two vectors, min(|v1 + v2|, |v1 - v2|) (Skokos 2001).
    Sali,
    /// The generalised alignment index of k = 2..4 vectors: the volume of their
    /// parallelotope (Skokos, Bountis, Antonopoulos 2007).
    Gali(u8),
}

impl Alignment {
    /// Tangent vectors it follows.
    pub fn vectors(self) -> u32 {
        match self {
            Alignment::Sali => 2,
            Alignment::Gali(k) => k as u32,
        }
    }

    pub fn name(self) -> String {
        match self {
            Alignment::Sali => "SALI".into(),
            Alignment::Gali(k) => format!("GALI_{k}"),
        }
    }
}

/// Default threshold below which an alignment index calls a start chaotic and stops it.
pub const ALIGNED: f64 = 1e-8;

/// f32 holds unit vectors to about 6e-8 a component: alignment indices below this are its
/// round-off, not the orbit's.
pub const ALIGNED_F32_FLOOR: f64 = 1e-5;

/// The exponents p a Lagrangian descriptor takes.
pub const DESCRIPTOR_POWERS: [f64; 4] = [0.25, 0.5, 1.0, 2.0];

/// A divergence-family map's measure of each start.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Indicator {
    /// The largest finite-time Lyapunov exponent, one tangent vector (1/s).
    #[default]
    Ftle,
    /// Exponent k (1..=4, in Gram-Schmidt order) of the spectrum: four tangent vectors kept
    /// orthonormal by modified Gram-Schmidt (1/s).
    Exponent(u8),
    /// The sum of the four exponents (1/s).
    ExponentSum,
    /// log10 of an alignment index at t-max, or where it fell below `threshold` (the start is
    /// then called chaotic and stops).
    Alignment { index: Alignment, threshold: f64 },
    /// The time the alignment index fell below `threshold` (s; +inf = not within t-max).
    AlignmentTime { index: Alignment, threshold: f64 },
    /// The mean exponential growth of nearby orbits, <Y> at t-max (Cincotta and Simó 2000).
    Megno,
    /// The fast Lyapunov indicator: the largest log10 |v| of one tangent vector so far
    /// (Froeschlé, Lega, Gonczi 1997).
    Fli,
    /// The Lagrangian descriptor M: the integral of sum_i |f_i|^p of the phase-space velocity
    /// f over [-t-max, t-max] (Lopesino et al. 2017).
    Descriptor { p: f64 },
}

impl Indicator {
    /// The quantity it measures.
    pub fn quantity(self) -> &'static Quantity {
        match self {
            Indicator::Ftle => &quantity::FTLE,
            Indicator::Exponent(_) => &quantity::EXPONENT,
            Indicator::ExponentSum => &quantity::EXPONENT_SUM,
            Indicator::Alignment {
                index: Alignment::Sali,
                ..
            } => &quantity::SALI,
            Indicator::Alignment { .. } => &quantity::GALI,
            Indicator::AlignmentTime { .. } => &quantity::ALIGNMENT_TIME,
            Indicator::Megno => &quantity::MEGNO,
            Indicator::Fli => &quantity::FLI,
            Indicator::Descriptor { .. } => &quantity::DESCRIPTOR,
        }
    }

    /// Tangent vectors it follows (0: none, a plain trajectory each way).
    pub fn vectors(self) -> u32 {
        match self {
            Indicator::Ftle | Indicator::Megno | Indicator::Fli => 1,
            Indicator::Exponent(_) | Indicator::ExponentSum => 4,
            Indicator::Alignment { index, .. } | Indicator::AlignmentTime { index, .. } => {
                index.vectors()
            }
            Indicator::Descriptor { .. } => 0,
        }
    }

    /// Its name in words, for the picture and the summary ("SALI (log10)").
    pub fn title(self) -> String {
        match self {
            Indicator::Ftle => "largest FTLE".into(),
            Indicator::Exponent(k) => format!("Lyapunov exponent {k} of 4"),
            Indicator::ExponentSum => "sum of the Lyapunov exponents".into(),
            Indicator::Alignment { index, .. } => format!("log10 {}", index.name()),
            Indicator::AlignmentTime { index, threshold } => {
                format!("time until {} < {threshold:e}", index.name())
            }
            Indicator::Megno => "MEGNO <Y>".into(),
            Indicator::Fli => "FLI (log10 |v|)".into(),
            Indicator::Descriptor { p } => format!("Lagrangian descriptor M (p = {p})"),
        }
    }

    /// Whether it is the threshold's early stop: the alignment indices.
    pub fn threshold(self) -> Option<f64> {
        match self {
            Indicator::Alignment { threshold, .. } | Indicator::AlignmentTime { threshold, .. } => {
                Some(threshold)
            }
            _ => None,
        }
    }

    /// Its settings in range for `precision` (the GPU's: an f32 alignment index cannot fall
    /// below its round-off).
    pub fn validate(self, precision: Precision) -> Result<()> {
        match self {
            Indicator::Exponent(k) if !(1..=4).contains(&k) => Err(Error::invalid(
                "exponent",
                format!("{k} must be 1, 2, 3 or 4 (in Gram-Schmidt order)"),
            )),
            Indicator::Alignment {
                index: Alignment::Gali(k),
                ..
            }
            | Indicator::AlignmentTime {
                index: Alignment::Gali(k),
                ..
            } if !(2..=4).contains(&k) => Err(Error::invalid(
                "gali",
                format!("{k} must be 2, 3 or 4 tangent vectors"),
            )),
            Indicator::Alignment { threshold, .. } | Indicator::AlignmentTime { threshold, .. }
                if !(threshold.is_finite() && threshold > 0.0 && threshold < 1.0) =>
            {
                Err(Error::invalid(
                    "threshold",
                    format!("{threshold:e} must be in (0, 1)"),
                ))
            }
            Indicator::Alignment { threshold, .. } | Indicator::AlignmentTime { threshold, .. }
                if precision == Precision::F32 && threshold < ALIGNED_F32_FLOOR =>
            {
                Err(Error::invalid(
                    "threshold",
                    format!(
                        "{threshold:e} is below what f32 resolves of an alignment index ({ALIGNED_F32_FLOOR:e}, its round-off): take --precision f64 or a threshold >= {ALIGNED_F32_FLOOR:e}"
                    ),
                ))
            }
            Indicator::Descriptor { p } if !DESCRIPTOR_POWERS.contains(&p) => Err(Error::invalid(
                "ld_p",
                format!(
                    "{p} must be 0.25, 0.5, 1 or 2 (the powers made of square roots and products, which every GPU has in f64)"
                ),
            )),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_out_of_range_are_refused_naming_their_flag() {
        let field = |i: Indicator, p| match i.validate(p) {
            Err(Error::InvalidSpec { field, .. }) => field,
            other => panic!("{i:?}: {other:?}"),
        };
        assert_eq!(field(Indicator::Exponent(5), Precision::F64), "exponent");
        let gali = |k, threshold| Indicator::Alignment {
            index: Alignment::Gali(k),
            threshold,
        };
        assert_eq!(field(gali(5, ALIGNED), Precision::F64), "gali");
        assert_eq!(field(gali(3, 2.0), Precision::F64), "threshold");
        assert_eq!(field(gali(3, ALIGNED), Precision::F32), "threshold");
        assert!(gali(3, ALIGNED).validate(Precision::F64).is_ok());
        assert_eq!(
            field(Indicator::Descriptor { p: 0.0 }, Precision::F64),
            "ld_p"
        );
    }
}

/// Every indicator's name, as `--indicator` and Python's `indicator=` take it.
pub const INDICATORS: [&str; 10] = [
    "ftle",
    "exponent",
    "exponent-sum",
    "sali",
    "sali-time",
    "gali",
    "gali-time",
    "megno",
    "fli",
    "descriptor",
];

/// An indicator as a user asks for it: its name and the options of some indicators.
#[derive(Clone, Copy, Debug)]
pub struct IndicatorAsked<'a> {
    pub name: &'a str,
    /// Which exponent (`exponent`), 1..4.
    pub exponent: Option<u8>,
    /// GALI's order (`gali`, `gali-time`).
    pub gali: Option<u8>,
    /// The alignment index's threshold (`sali`, `gali` and their times).
    pub threshold: Option<f64>,
    /// The Lagrangian descriptor's p (`descriptor`).
    pub ld_p: Option<f64>,
    /// The accurate settings asked (ftle only).
    pub accurate: bool,
    /// Whether it runs in f32 on a GPU (the alignment threshold's default).
    pub gpu_f32: bool,
}

impl IndicatorAsked<'_> {
    /// The indicator asked for; an option of another indicator is refused naming it.
    pub fn indicator(&self) -> Result<Indicator> {
        let name = self.name;
        if !INDICATORS.contains(&name) {
            return Err(Error::invalid(
                "indicator",
                format!("{name:?}: one of {}", INDICATORS.join(", ")),
            ));
        }
        let alignment = match name {
            "sali" | "sali-time" => Some(Alignment::Sali),
            "gali" | "gali-time" => Some(Alignment::Gali(self.gali.unwrap_or(4))),
            _ => None,
        };
        let misplaced = [
            (
                "exponent",
                self.exponent.is_some() && name != "exponent",
                "exponent",
            ),
            (
                "gali",
                self.gali.is_some() && !name.starts_with("gali"),
                "gali or gali-time",
            ),
            (
                "threshold",
                self.threshold.is_some() && alignment.is_none(),
                "sali, gali, sali-time or gali-time",
            ),
            (
                "ld_p",
                self.ld_p.is_some() && name != "descriptor",
                "descriptor",
            ),
        ];
        if let Some((flag, _, of)) = misplaced.into_iter().find(|m| m.1) {
            return Err(Error::invalid(flag, format!("is for the indicator {of}")));
        }
        if self.accurate && name != "ftle" {
            return Err(Error::invalid(
                "accurate",
                format!(
                    "is for the largest exponent (ftle); {name} steps with rk4 (set dt and precision)"
                ),
            ));
        }
        // f32 on the GPU resolves an alignment index to about 1e-5: its default there.
        let threshold = self.threshold.unwrap_or(match self.gpu_f32 {
            true => ALIGNED_F32_FLOOR,
            false => ALIGNED,
        });
        Ok(match (name, alignment) {
            ("exponent", _) => Indicator::Exponent(self.exponent.unwrap_or(1)),
            ("exponent-sum", _) => Indicator::ExponentSum,
            (n, Some(index)) if n.ends_with("-time") => {
                Indicator::AlignmentTime { index, threshold }
            }
            (_, Some(index)) => Indicator::Alignment { index, threshold },
            ("megno", _) => Indicator::Megno,
            ("fli", _) => Indicator::Fli,
            ("descriptor", _) => Indicator::Descriptor {
                p: self.ld_p.unwrap_or(0.5),
            },
            _ => Indicator::Ftle,
        })
    }
}
