//! Finite-time Lyapunov exponents in f64: the tangent method (the variational equations,
//! differentiated by num-dual through the same mass-matrix solve as the state) and the twin
//! method, both with periodic renormalisation (Benettin et al. 1980). The shader
//! `shaders/lyapunov.wgsl` does the same in f32 with hand-written dual numbers.

use nalgebra::{Matrix4, Vector4};
use num_dual::Dual64;

use super::adaptive::{Clock, dp54_to};
use super::{jacobian, map_pixels, rate_of, rk4_step};
use crate::error::Result;
use crate::field::{Convergence, Field};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{LyapunovSpec, Method};

/// The tangent vector every run starts from (unit length, all components equal), so the CPU
/// and the GPU follow the same vector.
pub const TANGENT_START: [f64; 4] = [0.5, 0.5, 0.5, 0.5];

/// One RK4 step of the state and of a tangent vector along it: each stage evaluates the rate
/// at dual numbers (y + eps v), whose dual part is J(y) v.
pub fn tangent_step(p: &Params, y: &[f64; 4], v: &[f64; 4], dt: f64) -> ([f64; 4], [f64; 4]) {
    let rate = |y: &[f64; 4], v: &[f64; 4]| {
        let x: [Dual64; 4] = std::array::from_fn(|i| Dual64::new(y[i], v[i]));
        let r = rate_of(p, &x);
        (r.map(|d| d.re), r.map(|d| d.eps))
    };
    let ahead = |a: &[f64; 4], h: f64, k: &[f64; 4]| -> [f64; 4] {
        std::array::from_fn(|i| a[i] + h * k[i])
    };
    let (ky1, kv1) = rate(y, v);
    let (ky2, kv2) = rate(&ahead(y, 0.5 * dt, &ky1), &ahead(v, 0.5 * dt, &kv1));
    let (ky3, kv3) = rate(&ahead(y, 0.5 * dt, &ky2), &ahead(v, 0.5 * dt, &kv2));
    let (ky4, kv4) = rate(&ahead(y, dt, &ky3), &ahead(v, dt, &kv3));
    let w = dt / 6.0;
    let combine = |a: &[f64; 4], k1: &[f64; 4], k2: &[f64; 4], k3: &[f64; 4], k4: &[f64; 4]| {
        std::array::from_fn(|i| a[i] + w * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
    };
    (
        combine(y, &ky1, &ky2, &ky3, &ky4),
        combine(v, &kv1, &kv2, &kv3, &kv4),
    )
}

/// A state-sized vector's Euclidean length (a tangent vector's, before it is renormalised).
pub fn norm(v: &[f64; 4]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The largest FTLE of one start by `spec`'s method and renormalisation interval, with its
/// running estimate at every renormalisation.
pub fn ftle(spec: &LyapunovSpec, start: State) -> Convergence {
    ftle_monitored(spec, start, &Monitor::hidden()).expect("never cancelled")
}

/// As [`ftle`], with progress (steps) and Ctrl-C at every renormalisation.
pub fn ftle_monitored(spec: &LyapunovSpec, start: State, monitor: &Monitor) -> Result<Convergence> {
    let p = &spec.params;
    let dt = spec.stepping.dt;
    let steps = spec.stepping.steps();
    let every = spec.renorm_steps();
    let mut out = Convergence::default();
    let mut log_sum = 0.0;
    let mut y = start.to_array();
    monitor.start("steps", steps as u64);
    match spec.method {
        Method::Tangent if spec.integrator.tolerances().is_some() => {
            tangent_adaptive(spec, start, monitor, &mut out)?;
        }
        Method::Tangent => {
            let mut v = TANGENT_START;
            for k in 1..=steps {
                (y, v) = tangent_step(p, &y, &v, dt);
                if k % every == 0 || k == steps {
                    monitor.check()?;
                    monitor.advance(every.min(k) as u64);
                    let n = norm(&v);
                    log_sum += n.ln();
                    v = v.map(|x| x / n);
                    out.t.push(k as f64 * dt);
                    out.ftle.push(log_sum / (k as f64 * dt));
                }
            }
        }
        Method::Twin { eps } => {
            let mut twin: [f64; 4] = std::array::from_fn(|i| y[i] + eps * TANGENT_START[i]);
            let mut a = start;
            for k in 1..=steps {
                a = rk4_step(p, &a, dt);
                twin = rk4_step(p, &State::from_array(twin), dt).to_array();
                if k % every == 0 || k == steps {
                    monitor.check()?;
                    monitor.advance(every.min(k) as u64);
                    let y = a.to_array();
                    let d: [f64; 4] = std::array::from_fn(|i| twin[i] - y[i]);
                    let n = norm(&d);
                    log_sum += (n / eps).ln();
                    twin = std::array::from_fn(|i| y[i] + d[i] * (eps / n));
                    out.t.push(k as f64 * dt);
                    out.ftle.push(log_sum / (k as f64 * dt));
                }
            }
        }
    }
    monitor.finish();
    Ok(out)
}

/// The tangent method with DP54 steps (`spec.integrator`'s tolerances) over the state and
/// the tangent vector together, each renormalisation interval landed on exactly; a stalled
/// run ends the estimate with NaN.
fn tangent_adaptive(
    spec: &LyapunovSpec,
    start: State,
    monitor: &Monitor,
    out: &mut Convergence,
) -> Result<()> {
    let p = &spec.params;
    let (rtol, atol) = spec.integrator.tolerances().expect("adaptive");
    let dt = spec.stepping.dt;
    let (steps, every) = (spec.stepping.steps(), spec.renorm_steps());
    // (theta1, omega1, theta2, omega2, v): the rate of y at dual numbers y + eps v.
    let rate = |x: &[f64; 8]| -> [f64; 8] {
        let d: [Dual64; 4] = std::array::from_fn(|i| Dual64::new(x[i], x[4 + i]));
        let r = rate_of(p, &d);
        std::array::from_fn(|i| if i < 4 { r[i].re } else { r[i - 4].eps })
    };
    let mut x: [f64; 8] = std::array::from_fn(|i| {
        if i < 4 {
            start.to_array()[i]
        } else {
            TANGENT_START[i - 4]
        }
    });
    let mut clock = Clock::new(dt);
    let mut log_sum = 0.0;
    let mut done = 0;
    while done < steps {
        let end = (done + every).min(steps);
        let t_end = end as f64 * dt;
        if dp54_to(&mut x, &mut clock, t_end, (rtol, atol), rate).is_err() {
            out.t.push(t_end);
            out.ftle.push(f64::NAN);
            return Ok(());
        }
        monitor.check()?;
        monitor.advance((end - done) as u64);
        let n = x[4..].iter().map(|v| v * v).sum::<f64>().sqrt();
        log_sum += n.ln();
        for v in &mut x[4..] {
            *v /= n;
        }
        out.t.push(t_end);
        out.ftle.push(log_sum / t_end);
        done = end;
    }
    Ok(())
}

/// All four Lyapunov exponents (1/s, descending) over `spec`'s time: four tangent vectors
/// through the full Jacobian, re-orthonormalised by nalgebra's (Householder) QR at every
/// renormalisation; they start from the indicators' frame (`indicators::FRAME`), so this is
/// an independent reference for the spectrum the indicator maps compute.
pub fn lyapunov_spectrum(spec: &LyapunovSpec, start: State) -> [f64; 4] {
    let p = &spec.params;
    let dt = spec.stepping.dt;
    let steps = spec.stepping.steps();
    let every = spec.renorm_steps();
    let rate = |y: &State, v: &Matrix4<f64>| (super::derivative(p, y), jacobian(p, y) * v);
    let ahead = |y: &State, v: &Matrix4<f64>, h: f64, k: &(State, Matrix4<f64>)| {
        let a = Vector4::from(y.to_array()) + h * Vector4::from(k.0.to_array());
        (State::from_array(a.into()), v + h * k.1)
    };
    let mut y = start;
    let mut v = Matrix4::from_columns(&super::FRAME.map(Vector4::from));
    let mut sums = Vector4::<f64>::zeros();
    for k in 1..=steps {
        let k1 = rate(&y, &v);
        let (y2, v2) = ahead(&y, &v, 0.5 * dt, &k1);
        let k2 = rate(&y2, &v2);
        let (y3, v3) = ahead(&y, &v, 0.5 * dt, &k2);
        let k3 = rate(&y3, &v3);
        let (y4, v4) = ahead(&y, &v, dt, &k3);
        let k4 = rate(&y4, &v4);
        y = rk4_step(p, &y, dt);
        v += (dt / 6.0) * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        if k % every == 0 || k == steps {
            let qr = v.qr();
            let r = qr.r();
            for i in 0..4 {
                sums[i] += r[(i, i)].abs().ln();
            }
            v = qr.q();
        }
    }
    let mut out: [f64; 4] = (sums / (steps as f64 * dt)).into();
    out.sort_by(|a, b| b.total_cmp(a));
    out
}

/// The FTLE map of `spec` (1/s at t-max), rows in parallel.
pub fn ftle_map(spec: &LyapunovSpec, monitor: &Monitor) -> Result<Field> {
    map_pixels(spec, monitor, |p, start| {
        let spec = LyapunovSpec {
            params: *p,
            ..*spec
        };
        ftle(&spec, start).last() as f32
    })
}
