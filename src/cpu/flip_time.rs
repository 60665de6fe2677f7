//! CPU twin of `shaders/flip_time.wgsl`: the same step loop and flip rule, in f64.

use std::f64::consts::PI;

use super::{hermite_crossing, map_pixels, rk4_step};
use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Stepping};

/// The first flip of a start: when, and which arm which way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstFlip {
    /// Time (s) until |theta1| or |theta2| first exceeds pi; +inf = not by t-max, NaN = the
    /// state left the numbers first.
    pub time: f64,
    /// Which arm crossed first (1 upper, 2 lower; the upper on a tie) and which way (+1:
    /// past +pi, -1: past -pi); None when `time` is not finite.
    pub arm: Option<(u8, i8)>,
}

/// The first flip of `start`, located inside its step by cubic Hermite interpolation. With
/// `early_exit`, starts below the no-flip energy are not integrated at all.
pub fn first_flip(p: &Params, start: State, stepping: &Stepping, early_exit: bool) -> FirstFlip {
    let never = FirstFlip {
        time: f64::INFINITY,
        arm: None,
    };
    if early_exit && p.energy(&start) < p.no_flip_threshold(f64::EPSILON) {
        return never;
    }
    let dt = stepping.dt;
    let mut y = start;
    let mut flip = never;
    for k in 0..stepping.steps() {
        let next = rk4_step(p, &y, dt);
        if flip.time.is_infinite() {
            // (fraction of the step, arm, direction) of each angle past pi; the earliest wins.
            let crossings = [
                (y.theta1, y.omega1, next.theta1, next.omega1, 1),
                (y.theta2, y.omega2, next.theta2, next.omega2, 2),
            ]
            .into_iter()
            .filter(|c| c.2.abs() > PI)
            .map(|(a, w, b, wb, arm)| (hermite_crossing(a, w, b, wb, dt), arm, b.signum() as i8));
            if let Some((s, arm, way)) = crossings.reduce(|e, l| if l.0 < e.0 { l } else { e }) {
                flip = FirstFlip {
                    time: (k as f64 + s) * dt,
                    arm: Some((arm, way)),
                };
                if early_exit {
                    break;
                }
            }
        }
        y = next;
    }
    if flip.time <= stepping.t_max {
        flip
    } else if y.to_array().iter().all(|v| v.is_finite()) {
        never
    } else {
        // The state left the numbers (the step blew up): no flip time, not "never".
        FirstFlip {
            time: f64::NAN,
            arm: None,
        }
    }
}

/// Time (s) until |theta1| or |theta2| first exceeds pi ([`first_flip`]).
pub fn flip_time(p: &Params, start: State, stepping: &Stepping, early_exit: bool) -> f64 {
    first_flip(p, start, stepping, early_exit).time
}

/// The flip-time map of `spec` (s, +inf = never flipped), rows in parallel.
pub fn flip_map(spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
    map_pixels(spec, monitor, |p, start| {
        flip_time(p, start, &spec.stepping, spec.early_exit) as f32
    })
}
