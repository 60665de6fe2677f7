//! What a map can measure, one table line each: a quantity's name and unit, when two values of
//! one pixel agree (the verdict's rule, as data), and which pixels its summary counts. The
//! one map path (engine, verdict, store, summary) reads a quantity from here; its kernels are
//! in `engine::MapKernels`.

/// Flip times agree within this fraction of the time ...
pub const FLIP_RELATIVE: f64 = 0.01;
/// ... or within this many seconds, whichever is larger.
pub const FLIP_ABSOLUTE: f64 = 0.02;

/// Exponents agree within this fraction ...
pub const FTLE_RELATIVE: f64 = 0.05;
/// ... or within this many 1/s, whichever is larger.
pub const FTLE_ABSOLUTE: f64 = 0.02;

/// Whether `a` and `b` lie within `relative` of the larger or `absolute`, whichever is larger
/// (NaN never does).
pub fn within(a: f32, b: f32, relative: f64, absolute: f64) -> bool {
    let (a, b) = (a as f64, b as f64);
    (a - b).abs() <= (relative * a.abs().max(b.abs())).max(absolute)
}

/// Whether two flip times (s; inf = never) agree.
pub fn flip_times_agree(a: f32, b: f32) -> bool {
    times_within(a, b, FLIP_RELATIVE, FLIP_ABSOLUTE)
}

/// Whether two exponents (1/s) agree.
pub fn exponents_agree(a: f32, b: f32) -> bool {
    within(a, b, FTLE_RELATIVE, FTLE_ABSOLUTE)
}

/// [`within`] for times where +inf is "never": two nevers agree, a never and a time do not.
fn times_within(a: f32, b: f32, relative: f64, absolute: f64) -> bool {
    match a.is_infinite() || b.is_infinite() {
        true => a == b,
        false => within(a, b, relative, absolute),
    }
}

/// One quantity a map can measure.
#[derive(Debug)]
pub struct Quantity {
    /// Its name in words (a store's `quantity` attribute).
    pub name: &'static str,
    /// Its unit (a store's `units` attribute).
    pub unit: &'static str,
    /// Whether two values of one pixel agree: the accuracy a resolved pixel is promised.
    pub agree: fn(f32, f32) -> bool,
    /// The rule in words: "the same map ... gives <agreement>".
    pub agreement: &'static str,
    /// The tolerance alone, in a few words.
    pub tolerance: &'static str,
    /// The verdict's rule: two runs at different steps must agree this closely for the map
    /// to vouch that the pixel is right within `agree`. Where chaos can make two runs of a
    /// start diverge and still land within `agree` by chance (a finite-time exponent of a
    /// diverged orbit is a draw from a spread of about 0.1 /s), this is a fifth of it.
    pub vouch: fn(f32, f32) -> bool,
    /// `vouch` in words, and its tolerance alone.
    pub vouching: &'static str,
    pub vouch_tolerance: &'static str,
    /// The pixels the summary counts (flipped, chaotic).
    pub counted: fn(f32) -> bool,
    /// The summary's key for their share.
    pub counted_as: &'static str,
    /// Which pixels those are, in words.
    pub counted_rule: &'static str,
}

/// The time until either arm first flips over (s; +inf = never within t-max).
pub const FLIP_TIME: Quantity = Quantity {
    name: "flip time",
    unit: "s",
    agree: flip_times_agree,
    agreement: "a flip time within 1 % or 0.02 s (both never flipping agrees; NaN never does)",
    tolerance: "1 % or 0.02 s",
    vouch: flip_times_agree,
    vouching: "a flip time within 1 % or 0.02 s (both never flipping agrees; NaN never does)",
    vouch_tolerance: "1 % or 0.02 s",
    counted: f32::is_finite,
    counted_as: "flipped",
    counted_rule: "a flip within t-max",
};

/// The largest finite-time Lyapunov exponent (1/s).
pub const FTLE: Quantity = Quantity {
    name: "finite-time Lyapunov exponent",
    unit: "1/s",
    agree: exponents_agree,
    agreement: "an exponent within 5 % or 0.02 /s (NaN never agrees)",
    tolerance: "5 % or 0.02 /s",
    vouch: |a, b| within(a, b, 0.01, 0.004),
    vouching: "an exponent within 1 % or 0.004 /s (NaN never agrees)",
    vouch_tolerance: "1 % or 0.004 /s",
    counted: |x| x > CHAOTIC_FTLE,
    counted_as: "chaotic",
    counted_rule: "FTLE > 0.5 /s",
};

/// One exponent of the Lyapunov spectrum (1/s).
pub const EXPONENT: Quantity = Quantity {
    name: "Lyapunov exponent",
    unit: "1/s",
    agree: exponents_agree,
    agreement: "an exponent within 5 % or 0.02 /s (NaN never agrees)",
    tolerance: "5 % or 0.02 /s",
    vouch: |a, b| within(a, b, 0.01, 0.004),
    vouching: "an exponent within 1 % or 0.004 /s (NaN never agrees)",
    vouch_tolerance: "1 % or 0.004 /s",
    counted: |x| x > CHAOTIC_FTLE,
    counted_as: "chaotic",
    counted_rule: "exponent > 0.5 /s",
};

/// The sum of the four exponents (1/s): 0 without losses, the mean phase-space contraction
/// rate with them.
pub const EXPONENT_SUM: Quantity = Quantity {
    name: "sum of the Lyapunov exponents",
    unit: "1/s",
    // Its scale is the volume change over t (ln 2 / t at most for equal masses), not the
    // exponents': 0.005 /s absolute.
    agree: |a, b| within(a, b, 0.05, 0.005),
    agreement: "a sum within 5 % or 0.005 /s (NaN never agrees)",
    tolerance: "5 % or 0.005 /s",
    vouch: |a, b| within(a, b, 0.01, 0.001),
    vouching: "a sum within 1 % or 0.001 /s (NaN never agrees)",
    vouch_tolerance: "1 % or 0.001 /s",
    counted: |x| x < -FTLE_ABSOLUTE as f32,
    counted_as: "contracting",
    counted_rule: "sum < -0.02 /s",
};

/// Alignment indices (log10) agree within this many decades.
pub const ALIGNMENT_DECADES: f64 = 0.5;

/// log10 of an alignment index at or below this calls a start chaotic in the summary: SALI
/// of a regular orbit stays near 1e-1..1, GALI_k of a regular orbit decays like a power of
/// t, far slower than 1e-4 within a map's minutes of simulated time.
pub const ALIGNED_LOG10: f32 = -4.0;

fn alignments_agree(a: f32, b: f32) -> bool {
    ((a - b) as f64).abs() <= ALIGNMENT_DECADES
}

/// log10 SALI at t-max, or where it fell below the threshold.
pub const SALI: Quantity = Quantity {
    name: "log10 SALI",
    unit: "1 (log10)",
    agree: alignments_agree,
    agreement: "log10 SALI within 0.5 (NaN never agrees)",
    tolerance: "0.5 decades",
    vouch: |a, b| ((a - b) as f64).abs() <= 0.1,
    vouching: "log10 SALI within 0.1 (NaN never agrees)",
    vouch_tolerance: "0.1 decades",
    // The map counts the starts below its threshold (spec::LyapunovSpec::counted).
    counted: |x| x <= ALIGNED_LOG10,
    counted_as: "chaotic",
    counted_rule: "log10 SALI <= -4",
};

/// log10 GALI_k at t-max, or where it fell below the threshold.
pub const GALI: Quantity = Quantity {
    name: "log10 GALI",
    unit: "1 (log10)",
    agree: alignments_agree,
    agreement: "log10 GALI within 0.5 (NaN never agrees)",
    tolerance: "0.5 decades",
    vouch: |a, b| ((a - b) as f64).abs() <= 0.1,
    vouching: "log10 GALI within 0.1 (NaN never agrees)",
    vouch_tolerance: "0.1 decades",
    // The map counts the starts below its threshold (spec::LyapunovSpec::counted).
    counted: |x| x <= ALIGNED_LOG10,
    counted_as: "chaotic",
    counted_rule: "log10 GALI <= -4",
};

/// The time an alignment index fell below its threshold (s; +inf = not within t-max).
pub const ALIGNMENT_TIME: Quantity = Quantity {
    name: "time to alignment",
    unit: "s",
    agree: |a, b| times_within(a, b, 0.05, 0.1),
    agreement: "a time within 5 % or 0.1 s (both never aligning agrees; NaN never does)",
    tolerance: "5 % or 0.1 s",
    vouch: |a, b| times_within(a, b, 0.01, 0.02),
    vouching: "a time within 1 % or 0.02 s (both never aligning agrees; NaN never does)",
    vouch_tolerance: "1 % or 0.02 s",
    counted: f32::is_finite,
    counted_as: "chaotic",
    counted_rule: "aligned within t-max",
};

/// <Y> above this calls a start chaotic in the summary (regular orbits tend to 2 or 0).
pub const CHAOTIC_MEGNO: f32 = 4.0;

/// MEGNO <Y> at t-max (1).
pub const MEGNO: Quantity = Quantity {
    name: "MEGNO",
    unit: "1",
    agree: |a, b| within(a, b, 0.1, 0.2),
    agreement: "<Y> within 10 % or 0.2 (NaN never agrees)",
    tolerance: "10 % or 0.2",
    vouch: |a, b| within(a, b, 0.02, 0.04),
    vouching: "<Y> within 2 % or 0.04 (NaN never agrees)",
    vouch_tolerance: "2 % or 0.04",
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
    agree: |a, b| within(a, b, 0.05, 0.1),
    agreement: "an FLI within 5 % or 0.1 (NaN never agrees)",
    tolerance: "5 % or 0.1",
    vouch: |a, b| within(a, b, 0.01, 0.02),
    vouching: "an FLI within 1 % or 0.02 (NaN never agrees)",
    vouch_tolerance: "1 % or 0.02",
    counted: |x| x > CHAOTIC_FLI,
    counted_as: "chaotic",
    counted_rule: "FLI > 5",
};

/// The Lagrangian descriptor M (the unit of |f|^p times s; f mixes rad/s and rad/s^2).
pub const DESCRIPTOR: Quantity = Quantity {
    name: "Lagrangian descriptor",
    unit: "sum of |f_i|^p s",
    agree: |a, b| within(a, b, 0.01, 1e-3),
    agreement: "M within 1 % (NaN never agrees)",
    tolerance: "1 %",
    vouch: |a, b| within(a, b, 0.002, 2e-4),
    vouching: "M within 0.2 % (NaN never agrees)",
    vouch_tolerance: "0.2 %",
    counted: f32::is_finite,
    counted_as: "finite",
    counted_rule: "M finite",
};

/// Which arm flips first and which way: a class per pixel (its code in the map, as f32; NaN
/// where the state left the numbers).
pub const FLIP_KIND: Quantity = Quantity {
    name: "first flip: arm and direction",
    unit: "class (0 never, 1 upper +, 2 upper -, 3 lower +, 4 lower -)",
    agree: |a, b| a == b,
    agreement: "the same arm flipping first the same way at a flip time within 1 % or 0.02 s, or neither flipping (NaN never agrees)",
    tolerance: "its class and 1 % or 0.02 s",
    vouch: |a, b| a == b,
    vouching: "the same arm flipping first the same way at a flip time within 1 % or 0.02 s, or neither flipping (NaN never agrees)",
    vouch_tolerance: "its class and 1 % or 0.02 s",
    counted: |x| x.is_finite() && x != FlipKind::Never.code(),
    counted_as: "flipped",
    counted_rule: "a flip within t-max",
};

/// The classes of [`FLIP_KIND`]: + is past +pi (the angle growing), - past -pi.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlipKind {
    Never,
    UpperPlus,
    UpperMinus,
    LowerPlus,
    LowerMinus,
}

impl FlipKind {
    pub const ALL: [FlipKind; 5] = [
        FlipKind::Never,
        FlipKind::UpperPlus,
        FlipKind::UpperMinus,
        FlipKind::LowerPlus,
        FlipKind::LowerMinus,
    ];

    /// The class of `arm` (1 upper, 2 lower) flipping `way` (+1 past +pi, -1 past -pi).
    pub fn of(arm: u8, way: i8) -> FlipKind {
        match (arm, way > 0) {
            (1, true) => FlipKind::UpperPlus,
            (1, false) => FlipKind::UpperMinus,
            (_, true) => FlipKind::LowerPlus,
            (_, false) => FlipKind::LowerMinus,
        }
    }

    /// Its code in a map (the .npy's values; the shader writes the same numbers).
    pub fn code(self) -> f32 {
        self as u8 as f32
    }

    /// The class of a map value (None for NaN or a value that is no class).
    pub fn from_code(x: f32) -> Option<FlipKind> {
        FlipKind::ALL.into_iter().find(|k| k.code() == x)
    }

    /// In words, for the legend.
    pub fn label(self) -> &'static str {
        match self {
            FlipKind::Never => "never",
            FlipKind::UpperPlus => "upper arm +",
            FlipKind::UpperMinus => "upper arm −",
            FlipKind::LowerPlus => "lower arm +",
            FlipKind::LowerMinus => "lower arm −",
        }
    }
}

/// Exponent (1/s) above which the summary counts a pixel as chaotic: regular orbits stay
/// below ln(1 + K t) / t, about 0.27 /s at 20 s (tests/lyapunov.rs).
pub const CHAOTIC_FTLE: f32 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agreement_rules() {
        let inf = f32::INFINITY;
        assert!(flip_times_agree(inf, inf));
        assert!(!flip_times_agree(29.9, inf));
        assert!(!flip_times_agree(f32::NAN, f32::NAN));
        // 0.02 s absolute below 2 s, 1 % above.
        assert!(flip_times_agree(1.0, 1.019));
        assert!(!flip_times_agree(1.0, 1.03));
        assert!(flip_times_agree(20.0, 20.19));
        assert!(!flip_times_agree(20.0, 20.25));
        assert!(exponents_agree(1.0, 1.04) && !exponents_agree(1.0, 1.1));
        assert!(exponents_agree(0.0, 0.015) && !exponents_agree(f32::NAN, 1.0));
    }
}
