//! When classic RK4 stays stable: the linearised motion's eigenvalues and the fastest
//! reachable rotation bound the time step.

use super::Stepping;
use crate::error::{Error, Result};
use crate::model::Params;

/// Largest time step (s) at which classic RK4 is linearly stable for `p`: no eigenvalue
/// lambda of the motion linearised about rest may leave RK4's stability region,
/// |1 + z + z^2/2 + z^3/6 + z^4/24| <= 1 at z = lambda dt. The linearisation takes the
/// gravity stiffness at rest, the joint damping and the bearing friction's slope at rest
/// (c_R r F_N / BEARING_SMOOTH with the static loads) as damping, for mass matrices over the
/// whole range of the arms' relative angle (cos D from -1 to 1). Undamped, this is
/// 2 sqrt(2) / omega_max; a damping rate c / I needs dt <= 2.785 I / c.
pub fn largest_stable_dt(p: &Params) -> f64 {
    use nalgebra::{Complex, Matrix2, Matrix4};
    let i = p.inertia();
    let l = &p.losses;
    let (total, lower) = p.moving_mass();
    let slope = l.bearing * l.bearing_radius / crate::model::BEARING_SMOOTH;
    let c1 = l.joint1 + slope * total * p.g;
    let c2 = l.joint2 + slope * lower * p.g;
    // Torques -C w and -K theta (model.rs: tau1 = -c1 w1 + c2 (w2 - w1), tau2 = -c2 (w2 - w1)).
    let damping = Matrix2::new(c1 + c2, -c2, -c2, c2);
    let stiffness = Matrix2::new(i.p, 0.0, 0.0, i.q);
    let r4 = |z: Complex<f64>| 1.0 + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0;
    let mut dt = f64::INFINITY;
    for cos_d in [-1.0, -0.5, 0.0, 0.5, 1.0] {
        let mass = Matrix2::new(i.a, i.c * cos_d, i.c * cos_d, i.b);
        let Some(inverse) = mass.try_inverse() else {
            continue;
        };
        let (k, c) = (-inverse * stiffness, -inverse * damping);
        // (theta1, theta2, omega1, omega2)' = A (theta1, theta2, omega1, omega2).
        #[rustfmt::skip]
        let a = Matrix4::new(
            0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 1.0,
            k[(0, 0)], k[(0, 1)], c[(0, 0)], c[(0, 1)],
            k[(1, 0)], k[(1, 1)], c[(1, 0)], c[(1, 1)],
        );
        // A bounded Schur decomposition (nalgebra's complex_eigenvalues iterates without a
        // limit, and spun for ever on a matrix with inf or NaN); validated parameters give
        // finite matrices, which converge in a few dozen iterations.
        let Some(schur) = a.try_schur(1e-15, 1000) else {
            return f64::NAN;
        };
        for lambda in schur.complex_eigenvalues().iter() {
            let size = lambda.norm();
            if size == 0.0 {
                continue;
            }
            // The region holds |z| <= 2.83 at most: bisect the boundary along lambda's ray.
            let (mut lo, mut hi) = (0.0, 3.0 / size);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if r4(lambda * mid).norm() <= 1.0 + 1e-12 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            dt = dt.min(lo);
        }
    }
    dt
}

/// `s.dt` inside RK4's stability region for `p` ([`largest_stable_dt`]), else an error
/// naming `dt` with the largest stable step.
pub fn validate_stability(p: &Params, s: &Stepping) -> Result<()> {
    let limit = largest_stable_dt(p);
    if limit.is_nan() || limit <= 0.0 {
        return Err(Error::invalid(
            "dt",
            "no stable step can be found for these parameters (their linearised motion has no finite eigenvalues): check the masses, lengths, g and losses",
        ));
    }
    if s.dt > limit {
        return Err(Error::invalid(
            "dt",
            format!(
                "{} s is unstable for these parameters (RK4 blows up above {limit:.4e} s here, with the damping and inertias given); take a step below it, e.g. {:.2e} s",
                s.dt,
                limit / 4.0
            ),
        ));
    }
    Ok(())
}

/// Largest angular speed (rad/s) either arm can reach from a start with angular velocities
/// (`omega1`, `omega2`) at any angles: the energy never increases (losses only take it), so
/// the kinetic energy stays below the start's largest plus the potential's whole range,
/// and T >= lambda_min(M) |omega|^2 / 2.
pub fn speed_bound(p: &Params, omega1: f64, omega2: f64) -> f64 {
    let i = p.inertia();
    let kinetic =
        0.5 * i.a * omega1 * omega1 + 0.5 * i.b * omega2 * omega2 + i.c * (omega1 * omega2).abs();
    // The mass matrix's smallest eigenvalue over every relative angle (|cos D| = 1).
    let lambda_min = 0.5 * ((i.a + i.b) - ((i.a - i.b).powi(2) + 4.0 * i.c * i.c).sqrt());
    (2.0 * (kinetic + 2.0 * (i.p + i.q)) / lambda_min).sqrt()
}

/// RK4 follows the cos and sin the shaders carry (u' = omega J u) only while omega dt stays
/// inside its stability interval on the imaginary axis, |omega dt| <= 2 sqrt(2): refuse a
/// step that the fastest reachable rotation ([`speed_bound`]) would blow up, naming `dt`.
pub fn validate_speeds(p: &Params, s: &Stepping, omega1: f64, omega2: f64) -> Result<()> {
    let omega = speed_bound(p, omega1, omega2);
    if !(omega.is_finite() && omega > 0.0) {
        // The larger starting speed is the likelier cause (masses and lengths are bounded).
        return Err(Error::invalid(
            if omega2.abs() > omega1.abs() {
                "omega2"
            } else {
                "omega1"
            },
            format!(
                "the speeds these starts can reach are not finite ({omega:e} rad/s): check the starting speeds, masses and lengths"
            ),
        ));
    }
    let limit = 2.0 * std::f64::consts::SQRT_2 / omega;
    if s.dt > limit {
        return Err(Error::invalid(
            "dt",
            format!(
                "{} s is unstable here: the arms can reach {omega:.3e} rad/s (the start's energy allows it), and RK4 blows up above {limit:.3e} s at that speed",
                s.dt
            ),
        ));
    }
    Ok(())
}
