//! Dormand-Prince 5(4) per pendulum, with its dense output, in f64: the CPU twin of
//! `shaders/flip_adaptive.wgsl`. Written from the Butcher tableau as data (the shader unrolls
//! the stages by hand) over the mass-matrix accelerations, so agreement checks both.

use std::f64::consts::PI;

use super::rate_of;
use crate::model::{Params, State};
use crate::spec::MAX_STEPS;
pub use crate::tableau::DP54;

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

/// One accepted DP54 step, with its stages.
pub struct Step {
    pub span: Span,
    k: [[f64; 4]; 7],
}

/// An accepted step with its dense output: what the flip rule needs of a method.
pub trait DenseStep {
    /// Where the step lies.
    fn span(&self) -> &Span;
    /// The rate of angle `i` (0 or 2) at the step's start and end.
    fn angle_rates(&self, i: usize) -> (f64, f64);
    /// The dense output at the fraction `s` of the step.
    fn dense(&self, s: f64) -> [f64; 4];
    /// d/ds of the dense output's component `i` (over the step, so h times its rate).
    fn slope(&self, i: usize, s: f64) -> f64;

    /// Where in the step (a fraction) the angle `i` (0 or 2) first reaches |angle| = pi on
    /// the dense output, if it does; needs the angle within pi at the start. An angle that
    /// ends the step within pi can still have passed pi and come back at a turning point
    /// inside the step (long adaptive steps make that likely near the top; a long step may
    /// hold two turns): the step is searched in [`PIECES`] pieces, in order, each for a
    /// crossing at its end or a turn beyond pi inside. Steps that cannot reach pi are passed
    /// over first ([`may_reach_pi`], the kernels' rule too).
    fn crossing(&self, i: usize) -> Option<f64> {
        let (w0, w1) = self.angle_rates(i);
        let span = self.span();
        if !may_reach_pi(span.y0[i], span.y1[i], w0, w1, span.h) {
            return None;
        }
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
        for k in 0..PIECES {
            let (lo, hi) = (k as f64 / PIECES as f64, (k + 1) as f64 / PIECES as f64);
            let mut top = hi;
            let mut peak = self.dense(hi)[i];
            if peak.abs() <= PI {
                let rising = self.slope(i, lo).signum();
                if self.slope(i, hi).signum() == rising {
                    continue;
                }
                // Where the slope leaves the sign it had at the piece's start.
                (top, _) = bisect(lo, hi, &|s| self.slope(i, s).signum() != rising);
                peak = self.dense(top)[i];
                if peak.abs() <= PI {
                    continue;
                }
            }
            let target = PI.copysign(peak);
            let (_, hi) = bisect(lo, top, &|s| {
                (self.dense(s)[i] - target) * target.signum() > 0.0
            });
            return Some(hi);
        }
        None
    }
}

/// The pieces a step's dense output is searched in for a crossing of pi (the kernels' too).
pub const PIECES: usize = 8;

/// Whether an angle from `a0` to `a1` over a step `h`, with rates `w0` and `w1` at its ends,
/// may reach |angle| = pi within the step: beyond its ends by at most h (|w0| + |w1|), twice
/// what a smooth angle travels at those rates (a bound of the dense output itself decides
/// in the kernels).
pub fn may_reach_pi(a0: f64, a1: f64, w0: f64, w1: f64, h: f64) -> bool {
    a0.abs().max(a1.abs()) + h * (w0.abs() + w1.abs()) > PI
}

/// A method stepping one pendulum: its next accepted step.
pub trait Stepper {
    type Step: DenseStep;
    fn clock(&self) -> &Clock;
    fn step(&mut self, t_end: f64) -> std::result::Result<Self::Step, Stall>;
}

/// An accepted step: from `y0` at `t` to `y1` at `t + h`.
#[derive(Clone, Copy, Debug)]
pub struct Span {
    pub t: f64,
    pub h: f64,
    pub y0: [f64; 4],
    pub y1: [f64; 4],
}

impl DenseStep for Step {
    fn span(&self) -> &Span {
        &self.span
    }

    fn angle_rates(&self, i: usize) -> (f64, f64) {
        (self.k[0][i], self.k[6][i])
    }

    /// The dense output (fourth order).
    fn dense(&self, s: f64) -> [f64; 4] {
        let h = self.span.h;
        std::array::from_fn(|i| {
            let dy = self.span.y1[i] - self.span.y0[i];
            let b = h * self.k[0][i] - dy;
            let r = dy - h * self.k[6][i] - b;
            let sum: f64 = (0..7).map(|j| DP54.d[0][j] * self.k[j][i]).sum();
            self.span.y0[i] + s * (dy + (1.0 - s) * (b + s * (r + (1.0 - s) * h * sum)))
        })
    }

    fn slope(&self, i: usize, s: f64) -> f64 {
        let h = self.span.h;
        let dy = self.span.y1[i] - self.span.y0[i];
        let b = h * self.k[0][i] - dy;
        let r = dy - h * self.k[6][i] - b;
        let sum: f64 = (0..7).map(|j| DP54.d[0][j] * self.k[j][i]).sum();
        dy + (1.0 - 2.0 * s) * b
            + s * (2.0 - 3.0 * s) * r
            + 2.0 * s * (1.0 - s) * (1.0 - 2.0 * s) * h * sum
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
    pub clock: Clock,
    pub y: [f64; 4],
    k1: [f64; 4],
}

/// An adaptive run's time, step and attempts, shared by the pairs.
#[derive(Clone, Copy, Debug)]
pub struct Clock {
    pub t: f64,
    /// The next step to try, and the largest.
    h: f64,
    h_max: f64,
    pub attempts: u32,
}

impl Clock {
    /// At t = 0 with the first step `h` (also the largest).
    pub fn new(h: f64) -> Self {
        Clock {
            t: 0.0,
            h,
            h_max: h,
            attempts: 0,
        }
    }

    /// The next attempt: its step (shortened to land on `t_end`) and whether it lands there;
    /// a stall when the attempts run out or the step no longer advances the time.
    pub fn attempt(&mut self, t_end: f64) -> std::result::Result<(f64, bool), Stall> {
        if self.attempts >= MAX_STEPS {
            return Err(Stall::TooManySteps);
        }
        self.attempts += 1;
        let last = self.t + self.h >= t_end;
        let h = if last { t_end - self.t } else { self.h };
        if h.is_nan() || self.t + h <= self.t {
            return Err(Stall::StepUnderflow);
        }
        Ok((h, last))
    }

    /// After an attempt of `h`: the next step is the last scaled by `factor` (at most the
    /// largest); when `accepted` the time moves on (to `t_end` exactly when `last`).
    pub fn settle(&mut self, h: f64, last: bool, t_end: f64, factor: f64, accepted: bool) {
        if accepted {
            self.t = if last { t_end } else { self.t + h };
        }
        self.h = (self.h * factor).min(self.h_max);
    }
}

/// One DP54 attempt of step `h` from the N-component state `x` whose rate is `k1` (FSAL):
/// the proposed state, the seven stages, and the error's RMS over the components scaled by
/// `atol + rtol max(|x|, |next|)`. The one stepper of every state the CPU steps adaptively:
/// the pendulum (4), the pendulum and a tangent vector (8), and four vectors (20).
pub fn dp54_attempt<const N: usize>(
    x: &[f64; N],
    k1: [f64; N],
    h: f64,
    (rtol, atol): (f64, f64),
    rate: impl Fn(&[f64; N]) -> [f64; N],
) -> ([f64; N], [[f64; N]; 7], f64) {
    let mut k = [[0.0; N]; 7];
    k[0] = k1;
    for s in 1..7 {
        let stage: [f64; N] =
            std::array::from_fn(|i| x[i] + h * (0..s).map(|j| DP54.a[s][j] * k[j][i]).sum::<f64>());
        k[s] = rate(&stage);
    }
    // The last stage was evaluated at the propagated solution (FSAL).
    let next: [f64; N] =
        std::array::from_fn(|i| x[i] + h * (0..7).map(|j| DP54.b[j] * k[j][i]).sum::<f64>());
    let err = ((0..N)
        .map(|i| {
            let e = h * (0..7).map(|j| DP54.e[0][j] * k[j][i]).sum::<f64>();
            (e / (atol + rtol * x[i].abs().max(next[i].abs()))).powi(2)
        })
        .sum::<f64>()
        / N as f64)
        .sqrt();
    (next, k, err)
}

/// DP54 steps of the N-component state `x` on `clock` until it reaches `t_end` exactly (a
/// renormalisation window), or the stall that stopped it.
pub fn dp54_to<const N: usize>(
    x: &mut [f64; N],
    clock: &mut Clock,
    t_end: f64,
    tolerances: (f64, f64),
    rate: impl Fn(&[f64; N]) -> [f64; N],
) -> std::result::Result<(), Stall> {
    let mut k1 = rate(x);
    while clock.t < t_end {
        let (h, last) = clock.attempt(t_end)?;
        let (next, k, err) = dp54_attempt(x, k1, h, tolerances, &rate);
        clock.settle(h, last, t_end, step_factor(err), err <= 1.0);
        if err <= 1.0 {
            *x = next;
            k1 = k[6];
        }
    }
    Ok(())
}

impl<'a> Adaptive<'a> {
    /// Starts at `start` with the first step `h` (also the largest).
    pub fn new(p: &'a Params, start: State, h: f64, rtol: f64, atol: f64) -> Self {
        let y = start.to_array();
        Adaptive {
            p,
            rtol,
            atol,
            clock: Clock::new(h),
            y,
            k1: rate_of(p, &y),
        }
    }

    /// The next accepted step, ending at `t_end` at the latest.
    pub fn step(&mut self, t_end: f64) -> std::result::Result<Step, Stall> {
        loop {
            let (h, last) = self.clock.attempt(t_end)?;
            let tolerances = (self.rtol, self.atol);
            let (y1, k, err) =
                dp54_attempt(&self.y, self.k1, h, tolerances, |y| rate_of(self.p, y));
            let t = self.clock.t;
            self.clock
                .settle(h, last, t_end, step_factor(err), err <= 1.0);
            if err <= 1.0 {
                let step = Step {
                    span: Span {
                        t,
                        h,
                        y0: self.y,
                        y1,
                    },
                    k,
                };
                self.y = y1;
                self.k1 = k[6];
                return Ok(step);
            }
        }
    }
}

impl Stepper for Adaptive<'_> {
    type Step = Step;

    fn clock(&self) -> &Clock {
        &self.clock
    }

    fn step(&mut self, t_end: f64) -> std::result::Result<Step, Stall> {
        Adaptive::step(self, t_end)
    }
}

/// The adaptive flip rule: the flip time (s; +inf = not by `t_max`, NaN = the run stalled
/// before flipping) and the attempts it took.
pub fn flip_time_with(run: &mut impl Stepper, t_max: f64) -> (f64, u32) {
    while run.clock().t < t_max {
        let step = match run.step(t_max) {
            Ok(step) => step,
            Err(_) => return (f64::NAN, run.clock().attempts),
        };
        let crossings = [0, 2].into_iter().filter_map(|i| step.crossing(i));
        if let Some(s) = crossings.reduce(f64::min) {
            return (step.span().t + s * step.span().h, run.clock().attempts);
        }
    }
    (f64::INFINITY, run.clock().attempts)
}
