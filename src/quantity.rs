//! What a map can measure, one table line each: a quantity's name and unit, when two values of
//! one pixel agree (the verdict's rule, as data), and which pixels its summary counts. The
//! one map path (engine, verdict, store, summary) reads a map's quantity through its spec;
//! its kernels are in `engine::MapKernels`. Here: the flip family's quantities, the FTLE
//! (the divergence kernel's, which the verdict's tests and --samples lean on) and the rules
//! they share; every other indicator's quantity lives with its measure (src/measure/).

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
    FLIP_TIME.agree.agrees(a, b)
}

/// Whether two exponents (1/s) agree.
pub fn exponents_agree(a: f32, b: f32) -> bool {
    FTLE.agree.agrees(a, b)
}

/// How closely two values of one pixel must lie to agree: within `relative` of the larger
/// or `absolute`, whichever is larger ([`within`]; NaN never agrees). Where the value is a
/// time, +inf is "never" (`never` says what never happens) and two nevers agree. Its words
/// are made from its numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub relative: f64,
    pub absolute: f64,
    /// The absolute tolerance's unit in words, with its space (" s", " /s"; "" for none).
    pub unit: &'static str,
    /// What never happens where a time is +inf ("flipping"); None: not a time.
    pub never: Option<&'static str>,
}

impl Tolerance {
    pub const fn new(relative: f64, absolute: f64, unit: &'static str) -> Self {
        Tolerance {
            relative,
            absolute,
            unit,
            never: None,
        }
    }

    /// The same for a time, +inf meaning that `what` never happens.
    pub const fn time(self, what: &'static str) -> Self {
        Tolerance {
            never: Some(what),
            ..self
        }
    }

    pub fn agrees(&self, a: f32, b: f32) -> bool {
        match self.never.is_some() && (a.is_infinite() || b.is_infinite()) {
            true => a == b,
            false => within(a, b, self.relative, self.absolute),
        }
    }

    /// The tolerance alone: "1 % or 0.02 s", "0.5 decades".
    pub fn words(&self) -> String {
        let absolute = format!("{}{}", self.absolute, self.unit);
        match self.relative {
            0.0 => absolute,
            // In whole hundredths of a percent, so 0.1 reads 10, not 10.000000000000002.
            r => format!("{} % or {absolute}", (r * 1e4).round() / 100.0),
        }
    }

    /// The rule for `value` ("a flip time"): "a flip time within 1 % or 0.02 s (both never
    /// flipping agrees; NaN never does)".
    pub fn rule(&self, value: &str) -> String {
        let nan = match self.never {
            Some(what) => format!("both never {what} agrees; NaN never does"),
            None => "NaN never agrees".into(),
        };
        format!("{value} within {} ({nan})", self.words())
    }
}

/// One quantity a map can measure.
#[derive(Debug)]
pub struct Quantity {
    /// Its name in words (a store's `quantity` attribute).
    pub name: &'static str,
    /// Its unit (a store's `units` attribute).
    pub unit: &'static str,
    /// One value of it in words, for its rules ("a flip time", "log10 SALI").
    pub value: &'static str,
    /// When two values of one pixel agree: the accuracy a resolved pixel is promised.
    pub agree: Tolerance,
    /// The verdict's rule: two runs at different steps must agree this closely for the map
    /// to vouch that the pixel is right within `agree`. Where chaos can make two runs of a
    /// start diverge and still land within `agree` by chance (a finite-time exponent of a
    /// diverged orbit is a draw from a spread of about 0.1 /s), this is a fifth of it.
    pub vouch: Tolerance,
    /// A class per pixel (its code): two values agree when they are equal, and the rules
    /// say so in the flip kind's words.
    pub classes: bool,
    /// The pixels the summary counts (flipped, chaotic).
    pub counted: fn(f32) -> bool,
    /// The summary's key for their share.
    pub counted_as: &'static str,
    /// Which pixels those are, in words.
    pub counted_rule: &'static str,
}

impl Quantity {
    /// Its accuracy rule in words: "the same map ... gives <agreement>".
    pub fn agreement(&self) -> String {
        self.rule(&self.agree)
    }

    /// The verdict's rule in words.
    pub fn vouching(&self) -> String {
        self.rule(&self.vouch)
    }

    /// The verdict's tolerance alone, in a few words.
    pub fn vouch_tolerance(&self) -> String {
        match self.classes {
            true => format!("its class and {}", FLIP_TOLERANCE.words()),
            false => self.vouch.words(),
        }
    }

    fn rule(&self, tolerance: &Tolerance) -> String {
        match self.classes {
            true => format!(
                "{} at a flip time within {}, or neither flipping (NaN never agrees)",
                self.value,
                FLIP_TOLERANCE.words()
            ),
            false => tolerance.rule(self.value),
        }
    }
}

/// Flip times agree within 1 % or 0.02 s, two nevers too.
const FLIP_TOLERANCE: Tolerance =
    Tolerance::new(FLIP_RELATIVE, FLIP_ABSOLUTE, " s").time("flipping");

/// Classes agree when equal (a tolerance of nothing; two nevers too).
const CLASS: Tolerance = Tolerance::new(0.0, 0.0, "").time("flipping");

/// The time until either arm first flips over (s; +inf = never within t-max).
pub const FLIP_TIME: Quantity = Quantity {
    name: "flip time",
    unit: "s",
    value: "a flip time",
    agree: FLIP_TOLERANCE,
    vouch: FLIP_TOLERANCE,
    classes: false,
    counted: f32::is_finite,
    counted_as: "flipped",
    counted_rule: "a flip within t-max",
};

/// The largest finite-time Lyapunov exponent (1/s).
pub const FTLE: Quantity = Quantity {
    name: "finite-time Lyapunov exponent",
    unit: "1/s",
    value: "an exponent",
    agree: Tolerance::new(FTLE_RELATIVE, FTLE_ABSOLUTE, " /s"),
    vouch: Tolerance::new(0.01, 0.004, " /s"),
    classes: false,
    counted: |x| x > CHAOTIC_FTLE,
    counted_as: "chaotic",
    counted_rule: "FTLE > 0.5 /s",
};

/// Which arm flips first and which way: a class per pixel (its code in the map, as f32; NaN
/// where the state left the numbers).
pub const FLIP_KIND: Quantity = Quantity {
    name: "first flip: arm and direction",
    unit: "class (0 never, 1 upper +, 2 upper -, 3 lower +, 4 lower -)",
    value: "the same arm flipping first the same way",
    agree: CLASS,
    vouch: CLASS,
    classes: true,
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

    /// The rules' words are made from their numbers, as the maps' files state them.
    #[test]
    fn the_rules_words_are_made_from_their_numbers() {
        assert_eq!(
            FLIP_TIME.vouching(),
            "a flip time within 1 % or 0.02 s (both never flipping agrees; NaN never does)"
        );
        assert_eq!(FTLE.vouch_tolerance(), "1 % or 0.004 /s");
        assert_eq!(
            FTLE.agreement(),
            "an exponent within 5 % or 0.02 /s (NaN never agrees)"
        );
        assert_eq!(
            FLIP_KIND.vouching(),
            "the same arm flipping first the same way at a flip time within 1 % or 0.02 s, or neither flipping (NaN never agrees)"
        );
    }
}
