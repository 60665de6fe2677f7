//! The f64 reference path: accelerations by solving the 2x2 mass-matrix system with nalgebra
//! (not the shader's closed form, so agreement checks the physics as well as the port),
//! classic RK4, rayon over pixels. Also the backend for machines without a GPU.

pub mod adaptive;
pub mod dop853;
mod flip_adaptive;
mod flip_kind;
mod flip_time;
mod indicators;
mod lyapunov;

pub use adaptive::{Adaptive, DP54, Stall, Step, step_factor};
pub use flip_adaptive::{flip_map_adaptive, flip_time_adaptive};
pub use flip_kind::flip_kind_map;
pub use flip_time::{FirstFlip, first_flip, flip_map, flip_time};
pub use indicators::{
    FRAME, alignment_index, alignment_run, descriptor_run, gram_schmidt, growth_run, indicator_map,
    indicator_run, spectrum_adaptive, spectrum_map, tangent_sums,
};
pub use lyapunov::{
    TANGENT_START, ftle, ftle_map, ftle_monitored, lyapunov_spectrum, norm, tangent_step,
};

use nalgebra::{Matrix2, Matrix4, RealField, Vector2, Vector4};
use num_dual::DualSVec64;

use rayon::prelude::*;

use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, Positions, State};
use crate::monitor::Monitor;
use crate::spec::MapSpec;

/// Angular accelerations (rad/s^2) from the Lagrange equations M(q) q'' = f(q, q') + tau:
///
/// ```text
/// [ A      C c ] [a1]   [ -C s omega2^2 - P sin theta1 ]   [tau1]
/// [ C c    B   ] [a2] = [  C s omega1^2 - Q sin theta2 ] + [tau2]
/// ```
/// with s, c = sin, cos (theta1 - theta2), A, B, C, P, Q from [`Params::inertia`] and tau the
/// loss torques ([`loss_torques`]). The matrix is positive definite (det = A B - C^2 c^2 > 0),
/// so the solve never fails. Generic over the scalar so that dual numbers (num-dual)
/// differentiate this very solve for the Jacobian.
pub fn accelerations_of<T: RealField + Copy>(p: &Params, y: &[T; 4]) -> [T; 2] {
    let k = |x: f64| -> T { nalgebra::convert(x) };
    let i = p.inertia();
    let [theta1, omega1, theta2, omega2] = *y;
    let d = theta1 - theta2;
    let (sd, cd) = (d.sin(), d.cos());
    let coupling = k(i.c);
    let mass = Matrix2::new(k(i.a), coupling * cd, coupling * cd, k(i.b));
    let [tau1, tau2] = loss_torques(p, y, cd);
    let force = Vector2::new(
        -coupling * sd * omega2 * omega2 - k(i.p) * theta1.sin() + tau1,
        coupling * sd * omega1 * omega1 - k(i.q) * theta2.sin() + tau2,
    );
    // Positive definite for every finite state; a non-finite state (a blown-up run) gives
    // non-finite accelerations rather than a panic.
    let Some(solver) = mass.cholesky() else {
        return [k(f64::NAN), k(f64::NAN)];
    };
    let a = solver.solve(&force);
    if !p.losses.has_bearings() {
        return [a[0], a[1]];
    }
    // Bearing friction needs the bearings' loads, which need the accelerations: take them
    // from the solve without it (the friction changes them by O(c_R) ~ 1e-3, so the loads by
    // O(c_R) and the torques by O(c_R^2)), then solve again with the friction torques.
    let [b1, b2] = bearing_torques(p, y, [a[0], a[1]]);
    let a = solver.solve(&(force + Vector2::new(b1, b2)));
    [a[0], a[1]]
}

/// Friction torques of the pivot and middle bearings for angular accelerations `alpha`:
/// loads F = sum(m a) - (total mass) g over the whole pendulum (pivot) and over the lower
/// arm (middle joint), torque c_R r |F| sgn(w_rel) against the rotation, the sign smoothed
/// as w / sqrt(w^2 + BEARING_SMOOTH^2).
/// With e_i = (cos t_i, sin t_i) and n_i = (sin t_i, -cos t_i), a point at s along arm 1
/// accelerates by s (alpha1 e1 - w1^2 n1), so sum(m a) = S1 (...)_1 + S2 (...)_2 with
/// S1 = P / g and S2 = Q / g.
pub fn bearing_torques<T: RealField + Copy>(p: &Params, y: &[T; 4], alpha: [T; 2]) -> [T; 2] {
    let k = |x: f64| -> T { nalgebra::convert(x) };
    let i = p.inertia();
    let (total, lower) = p.moving_mass();
    let [theta1, w1, theta2, w2] = *y;
    let (s1, c1, s2, c2) = (theta1.sin(), theta1.cos(), theta2.sin(), theta2.cos());
    // (alpha e - w^2 n) of each arm, as (x, y).
    let arm = |alpha: T, w: T, s: T, c: T| (alpha * c - w * w * s, alpha * s + w * w * c);
    let (a1x, a1y) = arm(alpha[0], w1, s1, c1);
    let (a2x, a2y) = arm(alpha[1], w2, s2, c2);
    let (s_1, s_2, low) = (k(i.p / p.g), k(i.q / p.g), k(lower * p.l1));
    let load = |fx: T, fy: T| (fx * fx + fy * fy + k(1e-18)).sqrt();
    let pivot = load(
        s_1 * a1x + s_2 * a2x,
        s_1 * a1y + s_2 * a2y + k(total * p.g),
    );
    let joint = load(
        low * a1x + s_2 * a2x,
        low * a1y + s_2 * a2y + k(lower * p.g),
    );
    let f = k(p.losses.bearing * p.losses.bearing_radius);
    let smooth2 = k(crate::model::BEARING_SMOOTH.powi(2));
    let sign = |w: T| w / (w * w + smooth2).sqrt();
    let t_pivot = f * pivot * sign(w1);
    let t_joint = f * joint * sign(w2 - w1);
    [-t_pivot + t_joint, -t_joint]
}

/// Speeds below this (m/s) are smoothed in the drag law, |v| -> sqrt(v^2 + V_SMOOTH^2), so
/// that the force -k |v| v stays differentiable at rest (for the tangent equations); the
/// force changes by less than 1e-6 relative above 1 mm/s.
pub const V_SMOOTH: f64 = 1e-6;

/// 3-point Gauss-Legendre nodes and weights on [0, 1], for the drag along the lower rod.
const GAUSS3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// Generalised forces (N m) of the losses, `cd` = cos(theta1 - theta2):
/// - joint damping: tau1 = -c1 w1 + c2 (w2 - w1), tau2 = -c2 (w2 - w1);
/// - drag on a bob at r with velocity v: F = -k |v| v, tau_j += F . dr/dtheta_j, with
///   v1 = l1 w1 e1, v2 = l1 w1 e1 + l2 w2 e2 (e_i the unit vector along dr_i/dtheta_i, and
///   e1 . e2 = cos D);
/// - drag along a rod, per unit length k/l: upper rod exactly, -k l1^3 |w1| w1 / 4; lower rod
///   by 3-point Gauss quadrature over its length.
///
/// Each term's power tau . omega is -k |u| u.u <= 0, so energy never increases.
pub fn loss_torques<T: RealField + Copy>(p: &Params, y: &[T; 4], cd: T) -> [T; 2] {
    let losses = &p.losses;
    let zero = T::zero();
    if !losses.any() {
        return [zero, zero];
    }
    let k = |x: f64| -> T { nalgebra::convert(x) };
    let (w1, w2) = (y[1], y[3]);
    let (l1, l2) = (k(p.l1), k(p.l2));
    let relative = w2 - w1;
    let mut tau1 = -k(losses.joint1) * w1 + k(losses.joint2) * relative;
    let mut tau2 = -k(losses.joint2) * relative;
    if losses.has_drag() {
        let [bob1, bob2, rod1, rod2] = losses.drag_factors();
        let smooth = k(V_SMOOTH * V_SMOOTH);
        let speed = |v2: T| (v2 + smooth).sqrt();
        // Upper bob and rod: velocity l w1 along e1 at distance l.
        let v1 = l1 * w1;
        let s1 = speed(v1 * v1);
        tau1 -= k(bob1) * s1 * v1 * l1 + k(rod1 / 4.0) * s1 * v1 * l1;
        // A point at distance s along the lower arm: u = l1 w1 e1 + s w2 e2.
        let at = |s: T| {
            let u_e1 = l1 * w1 + s * w2 * cd;
            let u_e2 = l1 * w1 * cd + s * w2;
            // |u|^2 >= 0, but rounding can take it below 0 when u ~ 0.
            let u2 = (l1 * l1 * w1 * w1 + s * s * w2 * w2 + k(2.0) * l1 * s * w1 * w2 * cd)
                .max(T::zero());
            let sp = speed(u2);
            // (force . dr/dtheta1, force . dr/dtheta2) per unit drag factor.
            (-sp * u_e1 * l1, -sp * u_e2 * s)
        };
        let (f1, f2) = at(l2);
        tau1 += k(bob2) * f1;
        tau2 += k(bob2) * f2;
        if rod2 != 0.0 {
            for (x, w) in GAUSS3 {
                let (f1, f2) = at(k(x) * l2);
                tau1 += k(rod2 * w) * f1;
                tau2 += k(rod2 * w) * f2;
            }
        }
    }
    [tau1, tau2]
}

/// Power (W) the losses take out of the pendulum at `s`: -(tau1 omega1 + tau2 omega2) >= 0,
/// bearing friction included (with the loads of the accelerations without it, as in
/// [`accelerations_of`]).
pub fn dissipated_power(p: &Params, s: &State) -> f64 {
    let y = s.to_array();
    let [mut t1, mut t2] = loss_torques(p, &y, (s.theta1 - s.theta2).cos());
    if p.losses.has_bearings() {
        let mut q = *p;
        q.losses.bearing = 0.0;
        let [b1, b2] = bearing_torques(p, &y, accelerations_of(&q, &y));
        t1 += b1;
        t2 += b2;
    }
    -(t1 * s.omega1 + t2 * s.omega2)
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

/// One classic fourth-order Runge-Kutta step of size `dt` (s): the next state and the
/// stage states y2, y3, y4 at which the rate was evaluated (besides y).
fn rk4_stages(p: &Params, y: &State, dt: f64) -> (State, [State; 3]) {
    let k1 = derivative(p, y);
    let y2 = axpy(y, 0.5 * dt, &k1);
    let k2 = derivative(p, &y2);
    let y3 = axpy(y, 0.5 * dt, &k2);
    let k3 = derivative(p, &y3);
    let y4 = axpy(y, dt, &k3);
    let k4 = derivative(p, &y4);
    let w = dt / 6.0;
    let next = State {
        theta1: y.theta1 + w * (k1.theta1 + 2.0 * k2.theta1 + 2.0 * k3.theta1 + k4.theta1),
        omega1: y.omega1 + w * (k1.omega1 + 2.0 * k2.omega1 + 2.0 * k3.omega1 + k4.omega1),
        theta2: y.theta2 + w * (k1.theta2 + 2.0 * k2.theta2 + 2.0 * k3.theta2 + k4.theta2),
        omega2: y.omega2 + w * (k1.omega2 + 2.0 * k2.omega2 + 2.0 * k3.omega2 + k4.omega2),
    };
    (next, [y2, y3, y4])
}

/// One classic fourth-order Runge-Kutta step of size `dt` (s).
pub fn rk4_step(p: &Params, y: &State, dt: f64) -> State {
    rk4_stages(p, y, dt).0
}

/// The state after `t` (s) by 4000 RK4 steps: a reference for the dense outputs' tests
/// inside one step (t <= 0.12 s: error ~ (3e-5)^4, far below theirs).
#[cfg(test)]
pub(crate) fn fine_rk4(p: &Params, start: State, t: f64) -> State {
    let n = 4000;
    (0..n).fold(start, |y, _| rk4_step(p, &y, t / n as f64))
}

/// One RK4 step and the work (J) the losses do over it, integrated with the same stages (the
/// work is a fifth ODE variable, W' = loss power, that does not feed back).
pub fn rk4_step_with_work(p: &Params, y: &State, dt: f64) -> (State, f64) {
    let (next, [y2, y3, y4]) = rk4_stages(p, y, dt);
    let power = |s: &State| dissipated_power(p, s);
    let work = dt / 6.0 * (power(y) + 2.0 * power(&y2) + 2.0 * power(&y3) + power(&y4));
    (next, work)
}

/// Work done by the losses up to each state of a trajectory (J), step by step from the
/// states themselves (so it also serves the GPU's trajectories).
pub fn dissipated_along(p: &Params, states: &[State], dt: f64) -> Vec<f64> {
    let mut total = 0.0;
    let mut out = Vec::with_capacity(states.len());
    out.push(0.0);
    for s in &states[..states.len().saturating_sub(1)] {
        total += rk4_step_with_work(p, s, dt).1;
        out.push(total);
    }
    out
}

/// `trajectory` and the losses' work up to each state, in one pass.
pub fn trajectory_with_work(
    p: &Params,
    start: State,
    dt: f64,
    steps: u32,
    monitor: &Monitor,
) -> Result<(Vec<State>, Vec<f64>)> {
    let (mut states, mut work) = (vec![start], vec![0.0]);
    monitor.start("steps", steps as u64);
    for k in 0..steps {
        // Progress and Ctrl-C every 2^16 steps (about 10 ms).
        if k % (1 << 16) == 0 {
            monitor.check()?;
            monitor.advance((steps - k).min(1 << 16) as u64);
        }
        let (next, w) = rk4_step_with_work(p, states.last().expect("start"), dt);
        states.push(next);
        work.push(work.last().expect("start") + w);
    }
    monitor.finish();
    Ok((states, work))
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

/// The bobs' positions at `times` (s from the start, ascending, within `steps` steps of `dt`)
/// along the RK4 run from `start`: between the states around a time, each angle is the
/// cubic through both states with their rates as slopes, evaluated in Bezier form by de
/// Casteljau's construction (the shader `positions` interpolates the carried cos and sin
/// instead, by the Hermite basis; both err by O(dt^4)).
pub fn positions(p: &Params, start: State, dt: f64, steps: u32, times: &[f64]) -> Vec<Positions> {
    let mut out = Vec::with_capacity(times.len());
    let mut pending = times.iter().peekable();
    let mut y = start;
    for k in 0..steps {
        let next = rk4_step(p, &y, dt);
        let last = k + 1 == steps;
        while let Some(&&t) = pending.peek() {
            if t > (k + 1) as f64 * dt && !last {
                break;
            }
            let s = ((t - k as f64 * dt) / dt).clamp(0.0, 1.0);
            let bezier = |a: f64, wa: f64, b: f64, wb: f64| {
                let c = [a, a + wa * dt / 3.0, b - wb * dt / 3.0, b];
                let lerp = |u: f64, v: f64| u + s * (v - u);
                let d = [lerp(c[0], c[1]), lerp(c[1], c[2]), lerp(c[2], c[3])];
                let e = [lerp(d[0], d[1]), lerp(d[1], d[2])];
                lerp(e[0], e[1])
            };
            out.push(p.positions(&State {
                theta1: bezier(y.theta1, y.omega1, next.theta1, next.omega1),
                omega1: 0.0,
                theta2: bezier(y.theta2, y.omega2, next.theta2, next.omega2),
                omega2: 0.0,
            }));
            pending.next();
        }
        y = next;
    }
    out
}

/// `spec`'s map over the rows it integrates: `value(parameters, start)` for every pixel of
/// them, each with its own parameters where an axis varies one (the spec's elsewhere), the
/// rest mirrored from them when its span is the whole grid; rows in parallel on all cores,
/// with progress and interruption.
pub fn map_pixels(
    spec: &impl MapSpec,
    monitor: &Monitor,
    value: impl Fn(&Params, State) -> f32 + Sync,
) -> Result<Field> {
    let (grid, params, span) = (spec.grid(), &spec.params(), spec.row_span());
    let mut field = Field::new(grid.width, span.field_rows(grid), 0.0);
    monitor.start("cpu", span.count as u64);
    let computed = span.count as usize * grid.width as usize;
    field.data[..computed]
        .par_chunks_mut(grid.width as usize)
        .enumerate()
        .try_for_each(|(row, out)| {
            monitor.check()?;
            for (col, v) in out.iter_mut().enumerate() {
                let (p, start) = grid.pixel(params, col as u32, span.first + row as u32);
                *v = value(&p, start);
            }
            monitor.advance(1);
            Ok::<(), crate::error::Error>(())
        })?;
    monitor.finish();
    if span.whole {
        field.mirror_below(span.count);
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use adaptive::Stepper;

    /// How much a method's dense output errs inside its first step of `h` against one of `h/2`
    /// (component `i`, at 0.3 of the step, against [`fine_rk4`]): 2^(q+1) for local error
    /// O(h^(q+1)). Each step's dense output must meet the step's ends (the start exactly, the
    /// end to rounding) and its slope must be its value's derivative (to a central difference's
    /// error over 1e-6 of the step).
    fn dense_error_ratio<'p, S: super::adaptive::DenseStep>(
        p: &'p Params,
        start: State,
        h: f64,
        i: usize,
        step_of: impl Fn(&'p Params, State, f64) -> S,
    ) -> f64 {
        let error_at = |h: f64| {
            let step = step_of(p, start, h);
            let y = fine_rk4(p, start, 0.3 * h).to_array();
            assert_eq!(step.dense(0.0), step.span().y0);
            assert!((step.dense(1.0)[i] - step.span().y1[i]).abs() < 1e-15);
            let d = step.slope(i, 0.3);
            let fd = (step.dense(0.3 + 1e-6)[i] - step.dense(0.3 - 1e-6)[i]) / 2e-6;
            assert!(
                (d - fd).abs() < 1e-7 * d.abs().max(1.0),
                "slope {d} vs {fd}"
            );
            (step.dense(0.3)[i] - y[i]).abs()
        };
        error_at(h) / error_at(h / 2.0)
    }

    /// DP54's dense output is (at least) fourth order: its error inside a step falls by at
    /// least 2^5 = 32 per halved step (local error O(h^5)); DOP853's is seventh order, by
    /// about 2^8 = 256.
    #[test]
    fn dense_outputs_have_their_order() {
        let p = Params::default();
        let dp54 = dense_error_ratio(&p, State::at_rest(0.3, -0.2), 0.2, 0, |p, start, h| {
            adaptive::Adaptive::new(p, start, h, 1.0, 1.0)
                .step(1.0)
                .unwrap()
        });
        // >= 32 for an O(h^5) error (less than 28: lower order); 64 if the h^5 term vanishes.
        assert!((28.0..80.0).contains(&dp54), "DP54's ratio {dp54}");
        let dop853 = dense_error_ratio(&p, State::at_rest(1.3, -0.9), 0.4, 2, |p, start, h| {
            dop853::Dop853::new(p, start, h, 1.0, 1.0)
                .step(1.0)
                .unwrap()
        });
        // 256 for an O(h^8) error; below 180 would be a lower order.
        assert!((180.0..700.0).contains(&dop853), "DOP853's ratio {dop853}");
    }
}
