//! A map's colour range by default, as data: the engine applies it here, and the browser
//! page (manifest.json) applies the same rule to the maps it computes.

use crate::field::Field;

/// One end of a colour range.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum End {
    /// This value, whatever the map holds.
    Fixed(f32),
    /// The rule's quantile of the map's finite values at this end, kept at or below `bound`
    /// (the low end) or at or above it (the high end) where one is given.
    Quantile { bound: Option<f32> },
}

/// The colour range of a map by default: each end fixed or a quantile of its finite values.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RangeRule {
    /// The quantiles of the finite values the ends may take (the low's, the high's).
    pub quantiles: (f64, f64),
    /// Where the two quantiles meet (a flat map), they are taken as 0.5 either side of the
    /// low one, a nonzero span.
    pub widen: bool,
    pub low: End,
    pub high: End,
}

/// The largest exponent's: from 0 (regular, dark) to the 99.5th percentile of the map, at
/// least 0.1 /s (a map of regular motion is not stretched over its noise).
pub const FTLE_RANGE: RangeRule = RangeRule {
    quantiles: (0.0, 0.995),
    widen: false,
    low: End::Fixed(0.0),
    high: End::Quantile { bound: Some(0.1) },
};

impl RangeRule {
    /// The low and high quantiles (0.005 and 0.995, say), spread out where they meet.
    pub const fn percentiles(low: f64, high: f64) -> Self {
        RangeRule {
            quantiles: (low, high),
            widen: true,
            low: End::Quantile { bound: None },
            high: End::Quantile { bound: None },
        }
    }

    /// The same range whatever the map holds.
    pub const fn fixed(low: f32, high: f32) -> Self {
        RangeRule {
            quantiles: (0.0, 1.0),
            widen: false,
            low: End::Fixed(low),
            high: End::Fixed(high),
        }
    }

    /// The range of `field`: a map without finite values takes its quantiles as 0 and 1.
    pub fn apply(&self, field: &Field) -> (f32, f32) {
        let mut v: Vec<f32> = field
            .data
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        let (mut low, mut high) = (0.0, 1.0);
        if !v.is_empty() {
            v.sort_unstable_by(f32::total_cmp);
            let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
            (low, high) = (at(self.quantiles.0), at(self.quantiles.1));
            if self.widen && high <= low {
                (low, high) = (low - 0.5, low + 0.5);
            }
        }
        let end = |end: End, quantile: f32, keep: fn(f32, f32) -> f32| match end {
            End::Fixed(x) => x,
            End::Quantile { bound } => bound.map_or(quantile, |b| keep(quantile, b)),
        };
        (end(self.low, low, f32::min), end(self.high, high, f32::max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(data: Vec<f32>) -> Field {
        Field {
            width: data.len() as u32,
            height: 1,
            data,
        }
    }

    #[test]
    fn the_rule_takes_quantiles_of_finite_values_and_bounds_them() {
        let ramp = field(
            (0..=200)
                .map(|k| k as f32 / 100.0)
                .chain([f32::NAN])
                .collect(),
        );
        // 0.995 of the 201 finite values 0..2: index 199 (0.995 * 200 = 199), 1.99.
        assert_eq!(
            RangeRule::percentiles(0.005, 0.995).apply(&ramp),
            (0.01, 1.99)
        );
        let bounded = RangeRule {
            low: End::Quantile { bound: Some(-1.0) },
            high: End::Quantile { bound: Some(5.0) },
            ..RangeRule::percentiles(0.005, 0.995)
        };
        assert_eq!(bounded.apply(&ramp), (-1.0, 5.0));
        assert_eq!(RangeRule::fixed(-8.0, 0.0).apply(&ramp), (-8.0, 0.0));
        // A flat map is spread about its value; an empty one takes 0 to 1.
        let flat = field(vec![3.0; 10]);
        assert_eq!(
            RangeRule::percentiles(0.005, 0.995).apply(&flat),
            (2.5, 3.5)
        );
        assert_eq!(
            RangeRule::percentiles(0.005, 0.995).apply(&field(vec![f32::NAN])),
            (0.0, 1.0)
        );
    }
}
