//! CPU twin of `shaders/flip_time.wgsl`: the same step loop and flip rule, in f64.

use std::f64::consts::PI;

use super::{hermite_crossing, map_pixels, rk4_step};
use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Stepping};

/// Time (s) until |theta1| or |theta2| first exceeds pi, located inside the step by cubic
/// Hermite interpolation; +inf if that does not happen by `t_max`, NaN if the state becomes
/// infinite or NaN first. With `early_exit`, starts
/// below the no-flip energy are not integrated at all.
pub fn flip_time(p: &Params, start: State, stepping: &Stepping, early_exit: bool) -> f64 {
    if early_exit && p.energy(&start) < p.no_flip_threshold(f64::EPSILON) {
        return f64::INFINITY;
    }
    let dt = stepping.dt;
    let mut y = start;
    let mut flip = f64::INFINITY;
    for k in 0..stepping.steps() {
        let next = rk4_step(p, &y, dt);
        if flip.is_infinite() {
            let mut s = f64::INFINITY;
            if next.theta1.abs() > PI {
                s = s.min(hermite_crossing(
                    y.theta1,
                    y.omega1,
                    next.theta1,
                    next.omega1,
                    dt,
                ));
            }
            if next.theta2.abs() > PI {
                s = s.min(hermite_crossing(
                    y.theta2,
                    y.omega2,
                    next.theta2,
                    next.omega2,
                    dt,
                ));
            }
            if s.is_finite() {
                flip = (k as f64 + s) * dt;
                if early_exit {
                    break;
                }
            }
        }
        y = next;
    }
    if flip <= stepping.t_max {
        flip
    } else if y.to_array().iter().all(|v| v.is_finite()) {
        f64::INFINITY
    } else {
        // The state left the numbers (the step blew up): no flip time, not "never".
        f64::NAN
    }
}

/// The flip-time map of `spec` (s, +inf = never flipped), rows in parallel.
pub fn flip_map(spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
    map_pixels(&spec.grid, spec.row_span(), monitor, |start| {
        flip_time(&spec.params, start, &spec.stepping, spec.early_exit) as f32
    })
}
