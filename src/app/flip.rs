//! `flip`: a flip-time (or flip-kind) map as a PNG, optionally with the raw values as .npy:
//! the one map job ([`super::map`]) over a [`FlipSpec`].

use crate::spec::FlipSpec;

pub use super::map::run;

/// A flip map to make (`colour_range` stays None: its colours span t-max).
pub type FlipJob = super::map::MapJob<FlipSpec>;
