//! The maps a front door asks for by name (`sweep --map`, the explorer's menu), one table
//! line each: a new quantity's map is one more line here, and both front doors list it.

use super::{ALIGNED_F32_FLOOR, Alignment, Indicator};
use super::{AnyMap, MapSpec};
use crate::quantity::{
    ALIGNMENT_TIME, DESCRIPTOR, EXPONENT, EXPONENT_SUM, FLI, FLIP_KIND, FLIP_TIME, FTLE, GALI,
    MEGNO, Quantity, SALI,
};

/// A map by what it measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MapKind {
    FlipTime,
    /// Which arm flips first and which way.
    FlipKind,
    /// The largest finite-time Lyapunov exponent.
    Ftle,
    /// One exponent of the Lyapunov spectrum.
    Exponent,
    /// The sum of the four exponents.
    ExponentSum,
    Sali,
    Gali,
    /// The time an alignment index fell below its threshold.
    AlignmentTime,
    Megno,
    Fli,
    /// The Lagrangian descriptor.
    Descriptor,
}

/// A map's line in [`MapKind::TABLE`].
pub struct MapKindEntry {
    pub kind: MapKind,
    pub quantity: &'static Quantity,
    /// Its name in `sweep --map`.
    pub name: &'static str,
    /// Its name in the explorer's queries (`kind=`).
    pub short: &'static str,
    /// The explorer's menu entry.
    pub label: &'static str,
    /// What its colours mean, under the explorer's colour bar; `{ends}` stands where the
    /// picture's dark and bright ends are named, with the meanings `low` and `high` of its
    /// low and high values in the order the picture draws them (`render::legend`).
    pub legend: &'static str,
    /// What its low values mean ("" where its colours have no order).
    pub low: &'static str,
    /// What its high values mean.
    pub high: &'static str,
    /// Whether its colours span a range the user may set (`--colour-range`).
    pub ranged: bool,
    /// Whether it has accurate settings (`--accurate`: f64, adaptive steps).
    pub accurate: bool,
    /// The divergence family's measure a front door asks for by this name (None: a flip map).
    pub indicator: Option<Indicator>,
}

impl MapKind {
    pub const TABLE: [MapKindEntry; 11] = [
        MapKindEntry {
            kind: MapKind::FlipTime,
            quantity: &FLIP_TIME,
            name: "flip",
            short: "flip",
            label: "flip time",
            legend: "Colour: time until an arm first flips ({ends}); black: no flip within t-max; green: NaN.",
            low: "soon",
            high: "late",
            ranged: false,
            accurate: true,
            indicator: None,
        },
        MapKindEntry {
            kind: MapKind::FlipKind,
            quantity: &FLIP_KIND,
            name: "flip-kind",
            short: "flip-kind",
            label: "which arm flips first",
            legend: "Colour: which arm flips over first, and which way (+: past +π, −: past −π); black: no flip within t-max; green: NaN.",
            low: "",
            high: "",
            ranged: false,
            // Located by the RK4 flip-time loop only.
            accurate: false,
            indicator: None,
        },
        MapKindEntry {
            kind: MapKind::Ftle,
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
        },
        MapKindEntry {
            kind: MapKind::Exponent,
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
            kind: MapKind::ExponentSum,
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
        MapKindEntry {
            kind: MapKind::Sali,
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
            kind: MapKind::Gali,
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
            kind: MapKind::AlignmentTime,
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
        MapKindEntry {
            kind: MapKind::Megno,
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
            kind: MapKind::Fli,
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
        MapKindEntry {
            kind: MapKind::Descriptor,
            quantity: &DESCRIPTOR,
            name: "descriptor",
            short: "descriptor",
            label: "Lagrangian descriptor",
            legend: "Colour: the Lagrangian descriptor M, the integral of Σ|f_i|^0.5 of the phase-space velocity over [-t-max, t-max]; its sharp ridges and valleys trace the stable and unstable manifolds.",
            low: "",
            high: "",
            ranged: true,
            accurate: false,
            indicator: Some(Indicator::Descriptor { p: 0.5 }),
        },
    ];

    /// Every kind, in the table's order.
    pub const ALL: [MapKind; 11] = [
        MapKind::FlipTime,
        MapKind::FlipKind,
        MapKind::Ftle,
        MapKind::Exponent,
        MapKind::ExponentSum,
        MapKind::Sali,
        MapKind::Gali,
        MapKind::AlignmentTime,
        MapKind::Megno,
        MapKind::Fli,
        MapKind::Descriptor,
    ];

    /// Its line in the table (the table is in the enum's order: the test below).
    pub fn entry(self) -> &'static MapKindEntry {
        &Self::TABLE[self as usize]
    }

    /// Its name in `sweep --map`.
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// Its name in the explorer's queries.
    pub fn short(self) -> &'static str {
        self.entry().short
    }

    pub fn quantity(self) -> &'static Quantity {
        self.entry().quantity
    }

    /// The kind of `map`, by the quantity it measures (names are unique; the addresses of
    /// constants are not guaranteed to be).
    pub fn of(map: &AnyMap) -> MapKind {
        let name = map.quantity().name;
        Self::TABLE
            .iter()
            .find(|e| e.quantity.name == name)
            .map(|e| e.kind)
            .expect("every quantity a map measures has its line in MapKind::TABLE")
    }

    /// The kind the explorer names `short`.
    pub fn from_short(short: &str) -> Option<MapKind> {
        Self::TABLE
            .iter()
            .find(|e| e.short == short)
            .map(|e| e.kind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_the_kinds_order_with_unique_names() {
        for (k, kind) in MapKind::ALL.into_iter().enumerate() {
            assert_eq!(MapKind::TABLE[k].kind, kind);
            for other in &MapKind::TABLE[k + 1..] {
                assert!(other.name != kind.name() && other.short != kind.short());
                assert!(other.quantity.name != kind.quantity().name);
            }
        }
    }
}
