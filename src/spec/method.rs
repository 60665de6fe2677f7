//! How a map is stepped: the precision of the GPU kernel, the integrator and its tolerances,
//! and what `--accurate` stands for.

use crate::error::{Error, Result};

/// The precision lives on the ground floor, beside the `Field` whose path names it.
pub use crate::field::Precision;

/// How each pendulum is stepped in time.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Integrator {
    /// Classic fourth-order Runge-Kutta at the fixed step `dt`, the flip located by cubic
    /// Hermite interpolation.
    #[default]
    Rk4,
    /// Dormand-Prince 5(4), each pendulum with its own steps: a step is kept when its
    /// error estimate is within `atol + rtol |y|` (per component, RMS over the state);
    /// `dt` is the first and the largest step. The flip is located on the method's
    /// fourth-order dense output.
    Dp54 { rtol: f64, atol: f64 },
    /// Dormand-Prince 8(5,3) (Hairer's DOP853), steps kept as for `Dp54`: the higher-order
    /// pair, fewer and longer steps at tight tolerances; the flip is located on its
    /// seventh-order dense output.
    Dop853 { rtol: f64, atol: f64 },
}

impl Integrator {
    pub const NAMES: [&'static str; 3] = ["rk4", "dp54", "dop853"];

    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Rk4 => "rk4",
            Integrator::Dp54 { .. } => "dp54",
            Integrator::Dop853 { .. } => "dop853",
        }
    }

    /// The tolerances of an adaptive method.
    pub fn tolerances(&self) -> Option<(f64, f64)> {
        match *self {
            Integrator::Rk4 => None,
            Integrator::Dp54 { rtol, atol } | Integrator::Dop853 { rtol, atol } => {
                Some((rtol, atol))
            }
        }
    }

    /// The same method at `factor` times the tolerances (RK4 unchanged).
    pub fn tightened(self, factor: f64) -> Integrator {
        match self {
            Integrator::Rk4 => Integrator::Rk4,
            Integrator::Dp54 { rtol, atol } => Integrator::Dp54 {
                rtol: factor * rtol,
                atol: factor * atol,
            },
            Integrator::Dop853 { rtol, atol } => Integrator::Dop853 {
                rtol: factor * rtol,
                atol: factor * atol,
            },
        }
    }

    /// Tolerances in range for `precision`, else an error naming `rtol` or `atol`: f32
    /// cannot follow a relative tolerance below ~100 of its epsilon, f64 below ~100 of its.
    pub fn validate(&self, precision: Precision) -> Result<()> {
        let Some((rtol, atol)) = self.tolerances() else {
            return Ok(());
        };
        let least = match precision {
            Precision::F32 => MIN_TOLERANCE_F32,
            Precision::F64 => MIN_TOLERANCE_F64,
        };
        for (field, v) in [("rtol", rtol), ("atol", atol)] {
            if !(v.is_finite() && (least..=1e-2).contains(&v)) {
                // Advice only where it helps: a tolerance too tight for f32.
                let advice = match precision == Precision::F32 && v < least {
                    true => " (use [[precision=f64]] for tighter tolerances)",
                    false => "",
                };
                return Err(Error::invalid(
                    field,
                    format!(
                        "{v:e} must be between {least:e} and 1e-2 in {}{advice}",
                        precision.name()
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// What `--accurate` stands for: the recommended settings for a flip map right on >= 99.5 %
/// of its pixels (measured on a 256 x 256, 30 s map: 99.84 % against a converged reference,
/// 8-9x the kernel time of the f32 RK4 map at dt 0.01 on lavapipe, BENCH.md): f64, DP54 at
/// rtol = atol = 1e-9, steps of at most 0.05 s.
pub const ACCURATE: (Precision, Integrator, f64) = (
    Precision::F64,
    Integrator::Dp54 {
        rtol: 1e-9,
        atol: 1e-9,
    },
    0.05,
);

/// What `lyapunov --accurate` stands for: f64, DP54 over the state and the tangent vector at
/// rtol = atol = 1e-9, steps of at most 0.1 s (measured on a 128 x 128, 10 s map: 99.93 % of
/// the exponents within 5 % or 0.02 /s of DP54 at 1e-11, where f32 RK4 at dt 0.01 has 84 %;
/// BENCH.md). The tangent method only.
pub const ACCURATE_FTLE: (Precision, Integrator, f64) = (
    Precision::F64,
    Integrator::Dp54 {
        rtol: 1e-9,
        atol: 1e-9,
    },
    0.1,
);

/// Tightest tolerances an adaptive run may ask for in each precision: ~100 epsilon, so the
/// error estimate is not round-off.
pub const MIN_TOLERANCE_F32: f64 = 1e-5;
pub const MIN_TOLERANCE_F64: f64 = 1e-13;

/// The integrator `name` with its tolerances (default: f32's least on an f32 GPU, else
/// 1e-9; atol as rtol); tolerances given without an adaptive integrator are an error.
pub fn integrator_of(
    name: &str,
    rtol: Option<f64>,
    atol: Option<f64>,
    f32_gpu: bool,
) -> Result<Integrator> {
    if name == "rk4" {
        for (field, given) in [("rtol", rtol), ("atol", atol)] {
            if given.is_some() {
                return Err(Error::invalid(
                    field,
                    "applies only to an adaptive integrator (dp54 or dop853)",
                ));
            }
        }
        return Ok(Integrator::Rk4);
    }
    let rtol = rtol.unwrap_or(if f32_gpu { MIN_TOLERANCE_F32 } else { 1e-9 });
    let atol = atol.unwrap_or(rtol);
    Ok(match name {
        "dp54" => Integrator::Dp54 { rtol, atol },
        "dop853" => Integrator::Dop853 { rtol, atol },
        _ => {
            return Err(Error::invalid(
                "integrator",
                format!("{name:?}: one of {}", Integrator::NAMES.join(", ")),
            ));
        }
    })
}

/// How a door asks for a map to be stepped: the precision, the integrator by name with any
/// tolerances given, or `accurate`'s settings; `gpu_f32` whether the door expects an f32
/// GPU path (the default tolerance's floor then). The CLI and Python both make their maps'
/// stepping from it.
#[derive(Clone, Copy, Debug)]
pub struct SteppingAsked<'a> {
    pub precision: Precision,
    pub integrator: &'a str,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub accurate: bool,
    pub gpu_f32: bool,
}

impl SteppingAsked<'_> {
    /// The integrator asked for (`accurate` sets its own).
    fn integrator(&self) -> Result<Integrator> {
        match self.accurate {
            true => Ok(Integrator::Rk4),
            false => integrator_of(self.integrator, self.rtol, self.atol, self.gpu_f32),
        }
    }

    /// `spec` stepped as asked (`accurate` expanded by the spec).
    pub fn flip(&self, spec: super::FlipSpec) -> Result<super::FlipSpec> {
        let spec = super::FlipSpec {
            precision: self.precision,
            integrator: self.integrator()?,
            ..spec
        };
        Ok(if self.accurate { spec.accurate() } else { spec })
    }

    /// `spec` stepped as asked (`accurate`: the tangent method's DP54, so not a twin's).
    pub fn lyapunov(&self, spec: super::LyapunovSpec) -> Result<super::LyapunovSpec> {
        if self.accurate && matches!(spec.method, super::Method::Twin { .. }) {
            return Err(Error::invalid(
                "accurate",
                "steps the tangent method with dp54; [[method=twin]] has fixed steps only",
            ));
        }
        let spec = super::LyapunovSpec {
            precision: self.precision,
            integrator: self.integrator()?,
            ..spec
        };
        Ok(if self.accurate { spec.accurate() } else { spec })
    }
}
