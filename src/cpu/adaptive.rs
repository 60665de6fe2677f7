//! Dormand-Prince 5(4) per pendulum, with its dense output, in f64: the CPU twin of
//! `shaders/flip_adaptive.wgsl`. Written from the Butcher tableau as data (the shader unrolls
//! the stages by hand) over the mass-matrix accelerations, so agreement checks both.

use std::f64::consts::PI;

use super::{map_pixels, rate_of};
use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, MAX_STEPS, Stepping};

/// An explicit embedded Runge-Kutta pair with a dense output of the form of Hairer's
/// `dopri5` (`contd5`): y(t + s h) = y0 + s (dy + (1 - s) (b + s (r + (1 - s) h sum d_i k_i)))
/// with dy = y1 - y0, b = h k1 - dy, r = dy - h k7 - b.
pub struct Tableau {
    pub c: [f64; 7],
    pub a: [[f64; 6]; 7],
    /// Weights of the propagated (fifth-order) solution; the last stage is the next step's
    /// first (FSAL), so b equals the last row of a.
    pub b: [f64; 7],
    /// b minus the embedded fourth-order weights: the local error estimate's weights.
    pub e: [f64; 7],
    /// The dense output's weights.
    pub d: [f64; 7],
}

/// Dormand & Prince (1980), the coefficients of Hairer, Norsett & Wanner, Solving ODE I,
/// table 5.2, and the dense output of `dopri5.f`.
pub const DP54: Tableau = Tableau {
    c: [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0],
    a: [
        [0.0; 6],
        [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ],
    b: [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
        0.0,
    ],
    e: [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ],
    d: [
        -12715105075.0 / 11282082432.0,
        0.0,
        87487479700.0 / 32700410799.0,
        -10690763975.0 / 1880347072.0,
        701980252875.0 / 199316789632.0,
        -1453857185.0 / 822651844.0,
        69997945.0 / 29380423.0,
    ],
};

/// The step-size controller: the next step is h (SAFETY err^(-1/4)) within [SHRINK, GROW]
/// times the last (err the RMS of the error over the tolerance; a quarter, not the textbook
/// fifth, because the GPU's f64 has square roots but no pow). Shared with the shader.
pub const SAFETY: f64 = 0.9;
pub const SHRINK: f64 = 0.2;
pub const GROW: f64 = 5.0;

/// The factor the step is scaled by after an attempt with scaled error `err`.
pub fn step_factor(err: f64) -> f64 {
    if err.is_nan() {
        return SHRINK;
    }
    (SAFETY / err.sqrt().sqrt()).clamp(SHRINK, GROW)
}

/// One accepted step from `y0` at `t` to `y1` at `t + h`, with its stages.
pub struct Step {
    pub t: f64,
    pub h: f64,
    pub y0: [f64; 4],
    pub y1: [f64; 4],
    k: [[f64; 4]; 7],
}

impl Step {
    /// The dense output at the fraction `s` of the step (fourth order).
    pub fn dense(&self, s: f64) -> [f64; 4] {
        let h = self.h;
        std::array::from_fn(|i| {
            let dy = self.y1[i] - self.y0[i];
            let b = h * self.k[0][i] - dy;
            let r = dy - h * self.k[6][i] - b;
            let sum: f64 = (0..7).map(|j| DP54.d[j] * self.k[j][i]).sum();
            self.y0[i] + s * (dy + (1.0 - s) * (b + s * (r + (1.0 - s) * h * sum)))
        })
    }

    /// d/ds of the dense output's component `i` (over the step, so h times its rate).
    fn slope(&self, i: usize, s: f64) -> f64 {
        let h = self.h;
        let dy = self.y1[i] - self.y0[i];
        let b = h * self.k[0][i] - dy;
        let r = dy - h * self.k[6][i] - b;
        let sum: f64 = (0..7).map(|j| DP54.d[j] * self.k[j][i]).sum();
        dy + (1.0 - 2.0 * s) * b
            + s * (2.0 - 3.0 * s) * r
            + 2.0 * s * (1.0 - s) * (1.0 - 2.0 * s) * h * sum
    }

    /// Where in the step (a fraction) the angle `i` (0 or 2) first reaches |angle| = pi on
    /// the dense output, if it does; needs |y0[i]| <= pi. An angle that ends the step within
    /// pi can still have passed it and come back at a turning point inside the step (large
    /// adaptive steps make that likely near the top): the turn is found first.
    pub fn crossing(&self, i: usize) -> Option<f64> {
        let bisect = |mut lo: f64, mut hi: f64, above: &dyn Fn(f64) -> bool| {
            for _ in 0..53 {
                let mid = 0.5 * (lo + hi);
                if above(mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            (lo, hi)
        };
        let (w0, w1) = (self.k[0][i], self.k[6][i]);
        let (end, peak) = if self.y1[i].abs() > PI {
            (1.0, self.y1[i])
        } else if w0 * w1 <= 0.0 {
            // Where the slope leaves the sign it started with.
            let (turn, _) = bisect(0.0, 1.0, &|s| self.slope(i, s).signum() != w0.signum());
            (turn, self.dense(turn)[i])
        } else {
            return None;
        };
        if peak.abs() <= PI {
            return None;
        }
        let target = PI.copysign(peak);
        let (_, hi) = bisect(0.0, end, &|s| {
            (self.dense(s)[i] - target) * target.signum() > 0.0
        });
        Some(hi)
    }
}

/// Why an adaptive run stopped before its end: it can say nothing beyond this point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stall {
    /// The step shrank until it no longer advances the time, or the state left the numbers.
    StepUnderflow,
    /// More than MAX_STEPS attempts.
    TooManySteps,
}

/// One pendulum stepped by DP54 from t = 0.
pub struct Adaptive<'a> {
    p: &'a Params,
    rtol: f64,
    atol: f64,
    h_max: f64,
    pub t: f64,
    pub y: [f64; 4],
    h: f64,
    k1: [f64; 4],
    pub attempts: u32,
}

impl<'a> Adaptive<'a> {
    /// Starts at `start` with the first step `h` (also the largest).
    pub fn new(p: &'a Params, start: State, h: f64, rtol: f64, atol: f64) -> Self {
        let y = start.to_array();
        Adaptive {
            p,
            rtol,
            atol,
            h_max: h,
            t: 0.0,
            y,
            h,
            k1: rate_of(p, &y),
            attempts: 0,
        }
    }

    /// The next accepted step, ending at `t_end` at the latest.
    pub fn step(&mut self, t_end: f64) -> std::result::Result<Step, Stall> {
        loop {
            if self.attempts >= MAX_STEPS {
                return Err(Stall::TooManySteps);
            }
            self.attempts += 1;
            let last = self.t + self.h >= t_end;
            let h = if last { t_end - self.t } else { self.h };
            if h.is_nan() || self.t + h <= self.t {
                return Err(Stall::StepUnderflow);
            }
            let mut k = [[0.0; 4]; 7];
            k[0] = self.k1;
            for s in 1..7 {
                let stage: [f64; 4] = std::array::from_fn(|i| {
                    self.y[i] + h * (0..s).map(|j| DP54.a[s][j] * k[j][i]).sum::<f64>()
                });
                k[s] = rate_of(self.p, &stage);
            }
            // The last stage was evaluated at the propagated solution (FSAL).
            let y1: [f64; 4] = std::array::from_fn(|i| {
                self.y[i] + h * (0..7).map(|j| DP54.b[j] * k[j][i]).sum::<f64>()
            });
            let err = (0..4)
                .map(|i| {
                    let e = h * (0..7).map(|j| DP54.e[j] * k[j][i]).sum::<f64>();
                    let scale = self.atol + self.rtol * self.y[i].abs().max(y1[i].abs());
                    (e / scale).powi(2)
                })
                .sum::<f64>()
                * 0.25;
            let err = err.sqrt();
            let next_h = (self.h * step_factor(err)).min(self.h_max);
            if err <= 1.0 {
                let step = Step {
                    t: self.t,
                    h,
                    y0: self.y,
                    y1,
                    k,
                };
                self.t = if last { t_end } else { self.t + h };
                self.y = y1;
                self.k1 = k[6];
                self.h = next_h;
                return Ok(step);
            }
            self.h = next_h;
        }
    }
}

/// What the adaptive flip rule gives for one start: the flip time (s; +inf = not by
/// t_max, NaN = the run stalled before flipping) and the attempts it took.
pub fn flip_time_adaptive(
    p: &Params,
    start: State,
    stepping: &Stepping,
    rtol: f64,
    atol: f64,
    early_exit: bool,
) -> (f64, u32) {
    if early_exit && p.energy(&start) < p.no_flip_threshold(f64::EPSILON) {
        return (f64::INFINITY, 0);
    }
    let mut run = Adaptive::new(p, start, stepping.dt, rtol, atol);
    while run.t < stepping.t_max {
        let step = match run.step(stepping.t_max) {
            Ok(step) => step,
            Err(_) => return (f64::NAN, run.attempts),
        };
        let crossings = [0, 2].into_iter().filter_map(|i| step.crossing(i));
        if let Some(s) = crossings.reduce(f64::min) {
            return (step.t + s * step.h, run.attempts);
        }
    }
    (f64::INFINITY, run.attempts)
}

/// The adaptive flip-time map of `spec` (its integrator must be adaptive), rows in parallel.
pub fn flip_map_adaptive(spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
    let (rtol, atol) = spec
        .integrator
        .tolerances()
        .expect("an adaptive integrator");
    map_pixels(&spec.grid, spec.row_span(), monitor, |start| {
        flip_time_adaptive(
            &spec.params,
            start,
            &spec.stepping,
            rtol,
            atol,
            spec.early_exit,
        )
        .0 as f32
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tableau's order conditions up to order 5 (quadrature and the tall trees' simplest
    /// ones): sum b = 1, sum b c^(q-1) = 1/q, row sums of a equal c; the embedded weights
    /// b - e are fourth order.
    #[test]
    fn tableau_conditions() {
        let t = &DP54;
        for (i, row) in t.a.iter().enumerate() {
            let sum: f64 = row.iter().sum();
            assert!((sum - t.c[i]).abs() < 1e-14, "row {i}");
        }
        for q in 1..=5 {
            let s: f64 = (0..7).map(|i| t.b[i] * t.c[i].powi(q - 1)).sum();
            assert!((s - 1.0 / q as f64).abs() < 1e-14, "b order {q}");
        }
        for q in 1..=4 {
            let s: f64 = (0..7).map(|i| (t.b[i] - t.e[i]) * t.c[i].powi(q - 1)).sum();
            assert!((s - 1.0 / q as f64).abs() < 1e-14, "embedded order {q}");
        }
    }

    /// The dense output is (at least) fourth order: its error inside a step falls by at least
    /// 2^5 = 32 per halved step (local error O(h^5)), and it meets the step's ends.
    #[test]
    fn dense_output_order() {
        let p = Params::default();
        let start = State::at_rest(0.3, -0.2);
        let error_at = |h: f64| {
            let mut run = Adaptive::new(&p, start, h, 1.0, 1.0);
            let step = run.step(1.0).unwrap();
            // The reference: the same start over 0.3 h with tiny fixed RK4 steps.
            let n = 2000;
            let mut y = start;
            for _ in 0..n {
                y = super::super::rk4_step(&p, &y, 0.3 * h / n as f64);
            }
            assert_eq!(step.dense(0.0), step.y0);
            assert!((step.dense(1.0)[0] - step.y1[0]).abs() < 1e-15);
            (step.dense(0.3)[0] - y.theta1).abs()
        };
        let (e1, e2) = (error_at(0.2), error_at(0.1));
        let ratio = e1 / e2;
        // >= 32 for an O(h^5) error (less than 28: lower order); 64 if the h^5 term vanishes.
        assert!(
            (28.0..80.0).contains(&ratio),
            "ratio {ratio} ({e1:e}, {e2:e})"
        );
    }
}
