//! The maps a front door asks for by name (`sweep --map`, the explorer's menu), one table
//! line each: a new quantity's map is one more line here, and both front doors list it.

use super::{AnyMap, MapSpec};
use crate::measure::MEASURES;
pub use crate::measure::MapKindEntry;
use crate::quantity::{FLIP_KIND, FLIP_TIME, Quantity};

/// A map by what it measures: its place in the kinds' table ([`MapKind::all`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MapKind(u16);

/// The flip family's maps; the divergence family's come from its measures
/// ([`crate::measure::Measure::kinds`]).
static FLIP_KINDS: [MapKindEntry; 2] = [
    MapKindEntry {
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
];

/// The kinds' table: the flip maps, then each measure's in the measures' order.
static TABLE: std::sync::LazyLock<Vec<&'static MapKindEntry>> = std::sync::LazyLock::new(|| {
    FLIP_KINDS
        .iter()
        .chain(MEASURES.iter().flat_map(|m| m.kinds()))
        .collect()
});

static ALL: std::sync::LazyLock<Vec<MapKind>> =
    std::sync::LazyLock::new(|| (0..TABLE.len() as u16).map(MapKind).collect());

impl MapKind {
    pub const FLIP_TIME: MapKind = MapKind(0);
    pub const FLIP_KIND: MapKind = MapKind(1);
    /// The first measure's first map (the test below).
    pub const FTLE: MapKind = MapKind(2);

    /// Every kind: the flip maps, then each measure's.
    pub fn all() -> &'static [MapKind] {
        &ALL
    }

    /// Its line in the table.
    pub fn entry(self) -> &'static MapKindEntry {
        TABLE[self.0 as usize]
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
        Self::all()
            .iter()
            .find(|k| k.quantity().name == name)
            .copied()
            .expect("every quantity a map measures has its line in the kinds' table")
    }

    /// The kind the explorer names `short`.
    pub fn from_short(short: &str) -> Option<MapKind> {
        Self::all().iter().find(|k| k.short() == short).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kinds_have_unique_names_and_quantities() {
        let all = MapKind::all();
        for (k, kind) in all.iter().enumerate() {
            for other in &all[k + 1..] {
                assert!(other.name() != kind.name() && other.short() != kind.short());
                assert!(other.quantity().name != kind.quantity().name);
            }
        }
        assert_eq!(MapKind::FLIP_TIME.name(), "flip");
        assert_eq!(MapKind::FLIP_KIND.name(), "flip-kind");
        assert_eq!(MapKind::FTLE.name(), "lyapunov");
    }
}
