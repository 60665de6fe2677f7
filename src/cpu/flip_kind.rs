//! CPU twin of `shaders/flip_kind.wgsl`: which arm flips first and which way, from the same
//! step loop and flip rule as the flip time ([`super::flip_time::first_flip`]).

use super::flip_time::first_flip;
use super::map_pixels;
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::quantity::FlipKind;
use crate::spec::FlipSpec;

/// The flip-kind map of `spec` ([`FlipKind`]'s codes; NaN where the state left the numbers),
/// rows in parallel.
pub fn flip_kind_map(spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
    map_pixels(spec, monitor, |p, start| {
        let flip = first_flip(p, start, &spec.stepping, spec.early_exit);
        match (flip.time.is_nan(), flip.arm) {
            (true, _) => f32::NAN,
            (false, None) => FlipKind::Never.code(),
            (false, Some((arm, way))) => FlipKind::of(arm, way).code(),
        }
    })
}
