//! The names of what a divergence-family map measures: data only, so that the spec can name
//! an indicator without reaching the measures' rules ([`super::Measure`]), which consult the spec's numbers.

/// What a divergence-family map measures of each start (its family says how:
/// [`Indicator::measure`]). Stores keep it in their identity, so variants keep their names.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Indicator {
    /// The largest finite-time Lyapunov exponent, one tangent vector (1/s).
    #[default]
    Ftle,
    /// Exponent k (1..=4, in Gram-Schmidt order) of the spectrum (1/s).
    Exponent(u8),
    /// The sum of the four exponents (1/s).
    ExponentSum,
    /// log10 of an alignment index at t-max, or where it fell below `threshold`.
    Alignment { index: Alignment, threshold: f64 },
    /// The time the alignment index fell below `threshold` (s; +inf = not within t-max).
    AlignmentTime { index: Alignment, threshold: f64 },
    /// The mean exponential growth of nearby orbits, <Y> at t-max.
    Megno,
    /// The fast Lyapunov indicator: the largest log10 |v| of one tangent vector so far.
    Fli,
    /// The Lagrangian descriptor M with the power `p`.
    Descriptor { p: f64 },
    /// The orthogonal FLI: the largest log10 of the tangent vector's part across the flow.
    Ofli,
    /// log10 of the relative Lyapunov indicator, the neighbour `delta` away.
    Rli { delta: f64 },
}

/// Which alignment index of normalised tangent vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Alignment {
    /// The smaller alignment index of two vectors, min(|v1 + v2|, |v1 - v2|).
    Sali,
    /// The generalised alignment index of k = 2..4 vectors: the volume of their
    /// parallelotope.
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
