//! The adaptive flip-time map: each start stepped by its own pair (DP54 in `adaptive.rs`,
//! DOP853 in `dop853.rs`), the CPU twin of `shaders/flip_adaptive.wgsl` and
//! `flip_dop853.wgsl`.

use super::adaptive::{Adaptive, flip_time_with};
use super::dop853::Dop853;
use super::map_pixels;
use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Integrator, Stepping};

/// The flip time of one start by `integrator` (adaptive), and the attempts it took
/// ([`flip_time_with`]); starts below the no-flip energy never flip (with `early_exit`).
pub fn flip_time_adaptive(
    p: &Params,
    start: State,
    stepping: &Stepping,
    integrator: Integrator,
    early_exit: bool,
) -> (f64, u32) {
    if early_exit && p.energy(&start) < p.no_flip_threshold(f64::EPSILON) {
        return (f64::INFINITY, 0);
    }
    match integrator {
        Integrator::Rk4 => panic!("flip_time_adaptive needs an adaptive integrator"),
        Integrator::Dp54 { rtol, atol } => flip_time_with(
            &mut Adaptive::new(p, start, stepping.dt, rtol, atol),
            stepping.t_max,
        ),
        Integrator::Dop853 { rtol, atol } => flip_time_with(
            &mut Dop853::new(p, start, stepping.dt, rtol, atol),
            stepping.t_max,
        ),
    }
}

/// The adaptive flip-time map of `spec` (its integrator must be adaptive), rows in parallel.
pub fn flip_map_adaptive(spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
    map_pixels(spec, monitor, |p, start| {
        flip_time_adaptive(p, start, &spec.stepping, spec.integrator, spec.early_exit).0 as f32
    })
}
