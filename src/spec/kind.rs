//! The maps a front door asks for by name (`sweep --map`, the explorer's menu), one table
//! line each: a new quantity's map is one more line here, and both front doors list it.

use super::{AnyMap, MapSpec};
use crate::quantity::{FLIP_KIND, FLIP_TIME, FTLE, Quantity};

/// A map by what it measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MapKind {
    FlipTime,
    /// Which arm flips first and which way.
    FlipKind,
    /// The largest finite-time Lyapunov exponent.
    Ftle,
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
    /// What its colours mean, under the explorer's colour bar.
    pub legend: &'static str,
    /// Whether its colours span a range the user may set (`--colour-range`).
    pub ranged: bool,
    /// Whether it has accurate settings (`--accurate`: f64, adaptive steps).
    pub accurate: bool,
}

impl MapKind {
    pub const TABLE: [MapKindEntry; 3] = [
        MapKindEntry {
            kind: MapKind::FlipTime,
            quantity: &FLIP_TIME,
            name: "flip",
            short: "flip",
            label: "flip time",
            legend: "Colour: time until an arm first flips (dark: soon, bright: late); black: no flip within t-max; green: NaN.",
            ranged: false,
            accurate: true,
        },
        MapKindEntry {
            kind: MapKind::FlipKind,
            quantity: &FLIP_KIND,
            name: "flip-kind",
            short: "flip-kind",
            label: "which arm flips first",
            legend: "Colour: which arm flips over first, and which way (+: past +π, −: past −π); black: no flip within t-max; green: NaN.",
            ranged: false,
            // Located by the RK4 flip-time loop only.
            accurate: false,
        },
        MapKindEntry {
            kind: MapKind::Ftle,
            quantity: &FTLE,
            name: "lyapunov",
            short: "ftle",
            label: "divergence (FTLE)",
            legend: "Colour: largest finite-time Lyapunov exponent (black: regular, bright: chaotic).",
            ranged: true,
            accurate: true,
        },
    ];

    /// Every kind, in the table's order.
    pub const ALL: [MapKind; 3] = [MapKind::FlipTime, MapKind::FlipKind, MapKind::Ftle];

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
