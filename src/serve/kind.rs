//! The maps the explorer shows: every line of the kinds' table ([`MapKind::all`]), and the
//! verdict; the page's menu and legends are built from [`Kind::describe`].

use crate::error::{Error, Result};
use crate::spec::AnyMap;
use crate::spec::MapKind;

/// The map a tile shows: a map of the kinds' table ([`MapKind::all`]), or the verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    Map(MapKind),
    /// The verdict on the flip map: white resolved, black not.
    Resolved,
}

impl Kind {
    pub const FLIP: Kind = Kind::Map(MapKind::FLIP_TIME);
    pub const FLIP_KIND: Kind = Kind::Map(MapKind::FLIP_KIND);
    pub const FTLE: Kind = Kind::Map(MapKind::FTLE);

    const RESOLVED_LABEL: &str = "verdict (white: resolved)";
    const RESOLVED_LEGEND: &str = "White: the pixel's flip time agrees with a finer run (resolved); black: it does not, so its colour cannot be trusted.";

    /// Every kind, in the page's menu order.
    pub fn all() -> impl Iterator<Item = Kind> {
        MapKind::all()
            .iter()
            .map(|&k| Kind::Map(k))
            .chain([Kind::Resolved])
    }

    /// Its name in queries.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Map(k) => k.short(),
            Kind::Resolved => "resolved",
        }
    }

    /// The page's menu entry and what its colours mean.
    pub fn describe(self) -> serde_json::Value {
        let (label, legend) = match self {
            Kind::Map(k) => (k.entry().label, crate::render::legend(k)),
            Kind::Resolved => (Self::RESOLVED_LABEL, Self::RESOLVED_LEGEND.to_string()),
        };
        let (ranged, accurate) = match self {
            Kind::Map(k) => (k.entry().ranged, k.entry().accurate),
            Kind::Resolved => (false, true),
        };
        // The colour range's unit beside its inputs, where it has one worth writing.
        let unit = match self {
            Kind::Map(k) if matches!(k.quantity().unit, "1/s" | "s") => k.quantity().unit,
            _ => "",
        };
        serde_json::json!({
            "name": self.name(), "label": label, "legend": legend,
            "ranged": ranged, "accurate": accurate, "unit": unit,
        })
    }

    /// The kind a stored map shows.
    pub fn of(map: &AnyMap) -> Kind {
        Kind::Map(MapKind::of(map))
    }

    pub(super) fn parse(s: &str) -> Result<Kind> {
        Kind::all().find(|k| k.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Kind::all().map(Kind::name).collect();
            Error::invalid("kind", format!("{s:?}: one of {}", names.join(", ")))
        })
    }
}

impl serde::Serialize for Kind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}
