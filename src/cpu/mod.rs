//! The f64 reference path: accelerations by solving the 2x2 mass-matrix system with nalgebra
//! (not the shader's closed form, so agreement checks the physics as well as the port),
//! classic RK4, rayon over pixels. Also the backend for machines without a GPU.

mod flip_time;
mod lyapunov;

pub use flip_time::{flip_map, flip_time};
pub use lyapunov::{Convergence, ftle, ftle_map, lyapunov_spectrum};

use nalgebra::{Matrix2, Matrix4, RealField, Vector2, Vector4};
use num_dual::DualSVec64;

use rayon::prelude::*;

use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::Grid;

/// Angular accelerations (rad/s^2) from the Lagrange equations M(q) q'' = f(q, q'):
///
/// ```text
/// [ M l1^2        m2 l1 l2 c ] [a1]   [ -m2 l1 l2 s omega2^2 - M g l1 sin theta1 ]
/// [ m2 l1 l2 c    m2 l2^2    ] [a2] = [  m2 l1 l2 s omega1^2 - m2 g l2 sin theta2 ]
/// ```
/// with s, c = sin, cos (theta1 - theta2). The matrix is positive definite (det =
/// m2 l1^2 l2^2 (m1 + m2 sin^2 D) > 0), so the solve never fails. Generic over the scalar so
/// that dual numbers (num-dual) differentiate this very solve for the Jacobian.
pub fn accelerations_of<T: RealField + Copy>(p: &Params, y: &[T; 4]) -> [T; 2] {
    let k = |x: f64| -> T { nalgebra::convert(x) };
    let [theta1, omega1, theta2, omega2] = *y;
    let m = p.total_mass();
    let d = theta1 - theta2;
    let (sd, cd) = (d.sin(), d.cos());
    let coupling = k(p.m2 * p.l1 * p.l2);
    let mass = Matrix2::new(
        k(m * p.l1 * p.l1),
        coupling * cd,
        coupling * cd,
        k(p.m2 * p.l2 * p.l2),
    );
    let force = Vector2::new(
        -coupling * sd * omega2 * omega2 - k(m * p.g * p.l1) * theta1.sin(),
        coupling * sd * omega1 * omega1 - k(p.m2 * p.g * p.l2) * theta2.sin(),
    );
    let a = mass
        .cholesky()
        .expect("the mass matrix is positive definite")
        .solve(&force);
    [a[0], a[1]]
}

/// Angular accelerations (rad/s^2) at `s`; see [`accelerations_of`].
pub fn accelerations(p: &Params, s: &State) -> (f64, f64) {
    let [a1, a2] = accelerations_of(p, &s.to_array());
    (a1, a2)
}

/// Time derivative of the state, generic over the scalar.
pub fn rate_of<T: RealField + Copy>(p: &Params, y: &[T; 4]) -> [T; 4] {
    let [a1, a2] = accelerations_of(p, y);
    [y[1], a1, y[3], a2]
}

/// Time derivative of the state.
pub fn derivative(p: &Params, s: &State) -> State {
    State::from_array(rate_of(p, &s.to_array()))
}

/// Jacobian d(rate)/d(state) at `s`, by forward-mode differentiation of [`rate_of`].
pub fn jacobian(p: &Params, s: &State) -> Matrix4<f64> {
    let x = Vector4::from(s.to_array());
    let (_, jac) = num_dual::jacobian(
        |x: Vector4<DualSVec64<4>>| Vector4::from(rate_of(p, &[x[0], x[1], x[2], x[3]])),
        &x,
    );
    jac
}

fn axpy(y: &State, h: f64, k: &State) -> State {
    State {
        theta1: y.theta1 + h * k.theta1,
        omega1: y.omega1 + h * k.omega1,
        theta2: y.theta2 + h * k.theta2,
        omega2: y.omega2 + h * k.omega2,
    }
}

/// One classic fourth-order Runge-Kutta step of size `dt` (s).
pub fn rk4_step(p: &Params, y: &State, dt: f64) -> State {
    let k1 = derivative(p, y);
    let k2 = derivative(p, &axpy(y, 0.5 * dt, &k1));
    let k3 = derivative(p, &axpy(y, 0.5 * dt, &k2));
    let k4 = derivative(p, &axpy(y, dt, &k3));
    let w = dt / 6.0;
    State {
        theta1: y.theta1 + w * (k1.theta1 + 2.0 * k2.theta1 + 2.0 * k3.theta1 + k4.theta1),
        omega1: y.omega1 + w * (k1.omega1 + 2.0 * k2.omega1 + 2.0 * k3.omega1 + k4.omega1),
        theta2: y.theta2 + w * (k1.theta2 + 2.0 * k2.theta2 + 2.0 * k3.theta2 + k4.theta2),
        omega2: y.omega2 + w * (k1.omega2 + 2.0 * k2.omega2 + 2.0 * k3.omega2 + k4.omega2),
    }
}

/// States at t = 0, dt, 2 dt, ... n dt (n + 1 states).
pub fn trajectory(p: &Params, start: State, dt: f64, steps: u32) -> Vec<State> {
    let mut out = Vec::with_capacity(steps as usize + 1);
    let mut y = start;
    out.push(y);
    for _ in 0..steps {
        y = rk4_step(p, &y, dt);
        out.push(y);
    }
    out
}

/// A map over `grid`: `value(start)` for every pixel, rows in parallel on all cores, with
/// progress and interruption.
pub fn map_pixels(
    grid: &Grid,
    monitor: &Monitor,
    value: impl Fn(State) -> f32 + Sync,
) -> Result<Field> {
    let mut field = Field::new(grid.width, grid.height, 0.0);
    monitor.start("cpu", grid.height as u64);
    field
        .data
        .par_chunks_mut(grid.width as usize)
        .enumerate()
        .try_for_each(|(row, out)| {
            monitor.check()?;
            for (col, v) in out.iter_mut().enumerate() {
                *v = value(grid.start(col as u32, row as u32));
            }
            monitor.advance(1);
            Ok::<(), crate::error::Error>(())
        })?;
    monitor.finish();
    Ok(field)
}

/// Where inside a step of length `h` an angle following the cubic Hermite interpolant of the
/// step's end states (angle, angular velocity) first reaches |angle| = pi, as a fraction of
/// the step in [0, 1]. Needs |theta_a| <= pi < |theta_b|.
pub fn hermite_crossing(theta_a: f64, omega_a: f64, theta_b: f64, omega_b: f64, h: f64) -> f64 {
    let target = std::f64::consts::PI.copysign(theta_b);
    let at = |s: f64| {
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        (h00 * theta_a + h10 * h * omega_a + h01 * theta_b + h11 * h * omega_b - target)
            * target.signum()
    };
    // at(0) <= 0 < at(1): bisect to f64 resolution of the fraction.
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..52 {
        let mid = 0.5 * (lo + hi);
        if at(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}
