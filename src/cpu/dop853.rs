//! Dormand-Prince 8(5,3) per pendulum (Hairer's DOP853), with its seventh-order dense
//! output, in f64: the higher-order pair for tight tolerances, CPU twin of
//! `shaders/flip_dop853.wgsl` (whose stages src/gpu/layout.rs writes out from the same
//! tableau, src/tableau.rs). Loops over the tableau as data, with the mass-matrix
//! accelerations, where the shader unrolls the stages with its closed form.

use std::cell::OnceCell;

use super::adaptive::{Clock, DenseStep, Span, Stall, Stepper};
use super::rate_of;
use crate::model::{Params, State};
pub use crate::tableau::{DOP853, Dop853Tableau};

/// The step-size controller: the next step is h (SAFETY err^(-1/8)) within [SHRINK, GROW]
/// times the last (err^(-1/8) by three square roots, which the GPU's f64 has).
pub const SAFETY: f64 = 0.9;
pub const SHRINK: f64 = 1.0 / 3.0;
pub const GROW: f64 = 6.0;

/// The factor the step is scaled by after an attempt with scaled error `err`.
pub fn step_factor(err: f64) -> f64 {
    if err.is_nan() {
        return SHRINK;
    }
    (SAFETY / err.sqrt().sqrt().sqrt()).clamp(SHRINK, GROW)
}

/// The scaled error of a step (Hairer's: the fifth-order estimate, damped where the third
/// order one is much larger): |h| E5^2 / sqrt((E5^2 + 0.01 E3^2) n), E the RMS-free sums of
/// squares of the estimates over `scale`.
pub fn scaled_error(h: f64, err5: &[f64; 4], err3: &[f64; 4], scale: &[f64; 4]) -> f64 {
    let (mut e5, mut e3) = (0.0, 0.0);
    for i in 0..4 {
        e5 += (err5[i] / scale[i]).powi(2);
        e3 += (err3[i] / scale[i]).powi(2);
    }
    if e5 == 0.0 && e3 == 0.0 {
        return 0.0;
    }
    h.abs() * e5 / ((e5 + 0.01 * e3) * 4.0).sqrt()
}

/// One accepted step and the dense output's coefficients, made when first needed (three
/// more stages).
pub struct Step853<'a> {
    p: &'a Params,
    pub span: Span,
    k: [[f64; 4]; 13],
    dense: OnceCell<[[f64; 4]; 7]>,
}

impl Step853<'_> {
    /// F0..F6 of the dense output y0 + x (F0 + (1 - x) (F1 + x (F2 + (1 - x) (F3 + ...)))).
    fn coefficients(&self) -> &[[f64; 4]; 7] {
        self.dense.get_or_init(|| {
            let t = &DOP853;
            let h = self.span.h;
            let mut k = [[0.0; 4]; 16];
            k[..13].copy_from_slice(&self.k);
            for s in 13..16 {
                let stage: [f64; 4] = std::array::from_fn(|i| {
                    self.span.y0[i] + h * (0..s).map(|j| t.a[s][j] * k[j][i]).sum::<f64>()
                });
                k[s] = rate_of(self.p, &stage);
            }
            let mut f = [[0.0; 4]; 7];
            for i in 0..4 {
                let dy = self.span.y1[i] - self.span.y0[i];
                f[0][i] = dy;
                f[1][i] = h * k[0][i] - dy;
                f[2][i] = 2.0 * dy - h * (k[12][i] + k[0][i]);
                for m in 0..4 {
                    f[3 + m][i] = h * (0..16).map(|j| t.d[m][j] * k[j][i]).sum::<f64>();
                }
            }
            f
        })
    }

    /// The dense output of component `i` and its x-derivative at the fraction `x`.
    fn value_and_slope(&self, i: usize, x: f64) -> (f64, f64) {
        let f = self.coefficients();
        let (mut v, mut d) = (0.0, 0.0);
        for (m, fm) in f.iter().enumerate().rev() {
            v += fm[i];
            // Factors alternate x, 1 - x, ... from F0 outwards: x for even m.
            (v, d) = if m % 2 == 0 {
                (v * x, d * x + v)
            } else {
                (v * (1.0 - x), d * (1.0 - x) - v)
            };
        }
        (self.span.y0[i] + v, d)
    }
}

impl DenseStep for Step853<'_> {
    fn span(&self) -> &Span {
        &self.span
    }

    fn angle_rates(&self, i: usize) -> (f64, f64) {
        (self.k[0][i], self.k[12][i])
    }

    /// The dense output (seventh order).
    fn dense(&self, s: f64) -> [f64; 4] {
        std::array::from_fn(|i| self.value_and_slope(i, s).0)
    }

    fn slope(&self, i: usize, s: f64) -> f64 {
        self.value_and_slope(i, s).1
    }
}

/// One pendulum stepped by DOP853 from t = 0.
pub struct Dop853<'a> {
    p: &'a Params,
    rtol: f64,
    atol: f64,
    pub clock: Clock,
    pub y: [f64; 4],
    k1: [f64; 4],
}

impl<'a> Dop853<'a> {
    /// Starts at `start` with the first step `h` (also the largest).
    pub fn new(p: &'a Params, start: State, h: f64, rtol: f64, atol: f64) -> Self {
        let y = start.to_array();
        Dop853 {
            p,
            rtol,
            atol,
            clock: Clock::new(h),
            y,
            k1: rate_of(p, &y),
        }
    }
}

impl<'a> Stepper for Dop853<'a> {
    type Step = Step853<'a>;

    fn clock(&self) -> &Clock {
        &self.clock
    }

    /// The next accepted step, ending at `t_end` at the latest.
    fn step(&mut self, t_end: f64) -> Result<Step853<'a>, Stall> {
        let t = &DOP853;
        loop {
            let (h, last) = self.clock.attempt(t_end)?;
            let mut k = [[0.0; 4]; 13];
            k[0] = self.k1;
            for s in 1..12 {
                let stage: [f64; 4] = std::array::from_fn(|i| {
                    self.y[i] + h * (0..s).map(|j| t.a[s][j] * k[j][i]).sum::<f64>()
                });
                k[s] = rate_of(self.p, &stage);
            }
            let y1: [f64; 4] = std::array::from_fn(|i| {
                self.y[i] + h * (0..12).map(|j| t.b[j] * k[j][i]).sum::<f64>()
            });
            let weighted = |w: &[f64; 16]| -> [f64; 4] {
                std::array::from_fn(|i| (0..12).map(|j| w[j] * k[j][i]).sum())
            };
            let scale: [f64; 4] =
                std::array::from_fn(|i| self.atol + self.rtol * self.y[i].abs().max(y1[i].abs()));
            let err = scaled_error(h, &weighted(&t.e[0]), &weighted(&t.e[1]), &scale);
            let t = self.clock.t;
            self.clock
                .settle(h, last, t_end, step_factor(err), err <= 1.0);
            if err <= 1.0 {
                // The next step's first stage, at the propagated solution.
                k[12] = rate_of(self.p, &y1);
                let step = Step853 {
                    p: self.p,
                    span: Span {
                        t,
                        h,
                        y0: self.y,
                        y1,
                    },
                    k,
                    dense: OnceCell::new(),
                };
                self.y = y1;
                self.k1 = k[12];
                return Ok(step);
            }
        }
    }
}
