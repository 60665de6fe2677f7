//! What a run is: the grid of starts, the physics, the time stepping. Validated before any
//! work starts, so a bad value fails fast; errors name the field (`t_max`, `size`...), which
//! the command line turns into its flag.

use crate::error::{Error, Result};
use crate::model::{Params, State};

/// A closed interval `min:max` of angles (rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub min: f64,
    pub max: f64,
}

impl Range {
    pub fn mid(&self) -> f64 {
        0.5 * (self.min + self.max)
    }

    pub const FULL_TURN: Range = Range {
        min: -std::f64::consts::PI,
        max: std::f64::consts::PI,
    };
}

/// The initial-condition grid: theta1 along x (left to right), theta2 along y (top = max),
/// every start with the same angular velocities. Pixel centres, not edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub width: u32,
    pub height: u32,
    pub theta1: Range,
    pub theta2: Range,
    /// Initial angular velocities (rad/s), the same for every pixel.
    pub omega1: f64,
    pub omega2: f64,
}

impl Grid {
    pub fn square(n: u32) -> Self {
        Grid {
            width: n,
            height: n,
            theta1: Range::FULL_TURN,
            theta2: Range::FULL_TURN,
            omega1: 0.0,
            omega2: 0.0,
        }
    }

    pub fn theta1_step(&self) -> f64 {
        (self.theta1.max - self.theta1.min) / self.width as f64
    }

    pub fn theta2_step(&self) -> f64 {
        (self.theta2.max - self.theta2.min) / self.height as f64
    }

    /// theta1 at the centre of column `col`: the range's middle plus an odd whole number of
    /// half steps, so columns mirrored about the middle get exactly opposite angles (the map's
    /// symmetry, see `point_symmetric`, then holds bit for bit).
    pub fn theta1_at(&self, col: u32) -> f64 {
        let half_steps = 2.0 * col as f64 + 1.0 - self.width as f64;
        self.theta1.mid() + half_steps * (0.5 * self.theta1_step())
    }

    /// theta2 at the centre of row `row` (row 0 is the top, theta2 near its maximum).
    pub fn theta2_at(&self, row: u32) -> f64 {
        let half_steps = 2.0 * row as f64 + 1.0 - self.height as f64;
        self.theta2.mid() - half_steps * (0.5 * self.theta2_step())
    }

    /// Whether the starts come in opposite pairs (theta1, theta2) <-> (-theta1, -theta2), i.e.
    /// pixel (col, row) <-> (width-1-col, height-1-row): both ranges centred on 0 and released
    /// from rest. The equations of motion are odd under y -> -y (losses included), so mirrored
    /// starts follow mirrored trajectories and flip at the same time: half the map is enough.
    pub fn point_symmetric(&self) -> bool {
        self.theta1.mid() == 0.0
            && self.theta2.mid() == 0.0
            && self.omega1 == 0.0
            && self.omega2 == 0.0
    }

    pub fn start(&self, col: u32, row: u32) -> State {
        State {
            theta1: self.theta1_at(col),
            omega1: self.omega1,
            theta2: self.theta2_at(row),
            omega2: self.omega2,
        }
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Whether neighbouring pixels are closer than f32 resolves near |theta| = pi
    /// ([`F32_MIN_PIXEL_STEP`]): such a grid must be integrated in f64.
    pub fn needs_f64(&self) -> bool {
        self.theta1_step().min(self.theta2_step()) < F32_MIN_PIXEL_STEP
    }

    /// Whether neighbouring pixels are closer than even f64 resolves near |theta| = pi
    /// ([`F64_MIN_PIXEL_STEP`]): the map is computed, but no pixel of it is resolved.
    pub fn beyond_f64(&self) -> bool {
        self.theta1_step().min(self.theta2_step()) < F64_MIN_PIXEL_STEP
    }
}

/// Smallest angle step between pixels that f32 still resolves near |theta| = pi: 16 ulp of
/// pi (ulp = 2.4e-7), so neighbouring pixels start from distinct f32 angles with room for
/// the arithmetic that forms them.
pub const F32_MIN_PIXEL_STEP: f64 = 16.0 * 2.384185791015625e-7;

/// The same for f64: 16 ulp of pi (ulp = 4.4e-16).
pub const F64_MIN_PIXEL_STEP: f64 = 16.0 * 4.440892098500626e-16;

/// Fixed-step time integration from t = 0 to `t_max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stepping {
    /// Time step (s).
    pub dt: f64,
    /// End time (s).
    pub t_max: f64,
}

impl Stepping {
    /// Number of steps to cover `t_max`; a final partial step is taken whole, and events
    /// after `t_max` are not reported.
    pub fn steps(&self) -> u32 {
        let n = self.t_max / self.dt;
        // t_max = 20, dt = 0.01 gives 2000.0000000000002: round when within round-off.
        let rounded = n.round();
        if (n - rounded).abs() < 1e-9 * n.max(1.0) {
            rounded as u32
        } else {
            n.ceil() as u32
        }
    }
}

/// How far apart the releases of an ensemble start: an angle (rad) or a position error of
/// the bobs (m), as the lab report quotes its release accuracy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spread {
    Radians(f64),
    Metres(f64),
}

impl Spread {
    /// Between 0 and 1 (rad or m), else an error naming `spread`.
    pub fn validate(&self) -> Result<()> {
        let (Spread::Radians(r) | Spread::Metres(r)) = *self;
        if r.is_finite() && (0.0..=1.0).contains(&r) {
            Ok(())
        } else {
            Err(Error::invalid(
                "spread",
                "must be between 0 and 1 (rad, or m with a unit)",
            ))
        }
    }
}

/// The releases: `runs` starts around `start`, evenly on a circle of radius `spread` in the
/// (theta1, theta2) plane (a position error e moves arm i by e / l_i). Deterministic, so a
/// picture can be made again; with spread 0 all starts are identical.
pub fn releases(p: &Params, start: State, runs: u32, spread: Spread) -> Vec<State> {
    let (d1, d2) = match spread {
        Spread::Radians(r) => (r, r),
        Spread::Metres(e) => (e / p.l1, e / p.l2),
    };
    (0..runs)
        .map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / runs as f64;
            State {
                theta1: start.theta1 + d1 * phi.cos(),
                theta2: start.theta2 + d2 * phi.sin(),
                ..start
            }
        })
        .collect()
}

/// The floating-point precision a GPU kernel integrates in (the CPU path is always f64).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Precision {
    /// The default: every GPU, fastest.
    #[default]
    F32,
    /// Needs an adapter with f64 (`Features::SHADER_F64`; lavapipe has it).
    F64,
}

impl Precision {
    pub const ALL: [Precision; 2] = [Precision::F32, Precision::F64];

    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }
}

/// How each pendulum is stepped in time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
                return Err(Error::invalid(
                    field,
                    format!(
                        "{v:e} must be between {least:e} and 1e-2 in {} (use --precision f64 for tighter tolerances)",
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

/// `ACCURATE_FTLE`'s largest step for renormalisations every `renorm` s: the longest whole
/// fraction of `renorm` that is at most its 0.1 s.
pub fn accurate_ftle_dt(renorm: f64) -> f64 {
    renorm / (renorm / ACCURATE_FTLE.2).ceil().max(1.0)
}

/// Tightest tolerances an adaptive run may ask for in each precision: ~100 epsilon, so the
/// error estimate is not round-off.
pub const MIN_TOLERANCE_F32: f64 = 1e-5;
pub const MIN_TOLERANCE_F64: f64 = 1e-13;

/// A flip-time map: for every start, the time until either arm first flips over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlipSpec {
    pub params: Params,
    pub grid: Grid,
    pub stepping: Stepping,
    /// Stop integrating a pixel once it has flipped, and skip the starts that cannot flip.
    /// Off only for benchmarks (every pixel runs every step).
    pub early_exit: bool,
    /// Integrate only the top half of a point-symmetric grid and mirror it (same map, half
    /// the work). Off for benchmarks of raw throughput and for checking the symmetry.
    pub use_symmetry: bool,
    /// The GPU's precision (the CPU is always f64); grids finer than f32 resolves run in
    /// f64 whatever is asked.
    pub precision: Precision,
    pub integrator: Integrator,
    /// Only these rows of the grid (first, count): a unit of a store's work. The map then
    /// holds just them (nothing mirrored).
    pub band: Option<(u32, u32)>,
}

/// The rows a map run integrates and the field it gives: rows `first..first + count` of
/// the grid; `whole`: the field is the whole grid, the rows below `count` mirrored from them
/// (`first` is 0), else the field is just those rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowSpan {
    pub first: u32,
    pub count: u32,
    pub whole: bool,
}

impl RowSpan {
    /// The whole grid, `count` top rows integrated.
    pub fn top(count: u32) -> Self {
        RowSpan {
            first: 0,
            count,
            whole: true,
        }
    }

    /// Rows of the field this span gives on `grid`.
    pub fn field_rows(&self, grid: &Grid) -> u32 {
        if self.whole { grid.height } else { self.count }
    }
}

/// Largest number of steps one run may take (the step counter is a u32 on the GPU, and f32
/// counts steps exactly only up to 2^24).
pub const MAX_STEPS: u32 = 1 << 24;

impl FlipSpec {
    pub fn new(params: Params, grid: Grid, stepping: Stepping) -> Self {
        FlipSpec {
            params,
            grid,
            stepping,
            early_exit: true,
            use_symmetry: true,
            precision: Precision::F32,
            integrator: Integrator::Rk4,
            band: None,
        }
    }

    /// Rows to integrate: the band's, or all from the top, or the top half when the other
    /// half mirrors it.
    pub fn rows_to_integrate(&self) -> u32 {
        self.row_span().count
    }

    pub fn row_span(&self) -> RowSpan {
        match self.band {
            Some((first, count)) => RowSpan {
                first,
                count,
                whole: false,
            },
            None if self.use_symmetry && self.grid.point_symmetric() => {
                RowSpan::top(self.grid.height.div_ceil(2))
            }
            None => RowSpan::top(self.grid.height),
        }
    }

    pub fn validate(&self) -> Result<()> {
        validate_params(&self.params)?;
        validate_grid(&self.grid)?;
        validate_stepping(&self.stepping)?;
        // The f64 range here; the f32 GPU's own is checked where the engine has picked it.
        self.integrator.validate(Precision::F64)?;
        if let Some((first, count)) = self.band
            && (count == 0 || first as u64 + count as u64 > self.grid.height as u64)
        {
            return Err(Error::invalid(
                "tile",
                format!(
                    "rows {first}..{} lie outside the grid's {} rows",
                    first as u64 + count as u64,
                    self.grid.height
                ),
            ));
        }
        validate_stability(&self.params, &self.stepping)?;
        validate_speeds(
            &self.params,
            &self.stepping,
            self.grid.omega1,
            self.grid.omega2,
        )
    }
}

/// How the divergence of nearby starts is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Tangent (variational) equations alongside the state (Benettin et al.).
    Tangent,
    /// A second trajectory started `eps` away (Euclidean in (theta1, omega1, theta2, omega2)),
    /// pulled back to `eps` at every renormalisation.
    Twin { eps: f64 },
}

/// A divergence map: the largest finite-time Lyapunov exponent (1/s) of every start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LyapunovSpec {
    pub params: Params,
    pub grid: Grid,
    pub stepping: Stepping,
    pub method: Method,
    /// Renormalisation interval (s), a whole number of steps.
    pub renorm: f64,
    /// With the tangent method, integrate only the top half of a point-symmetric grid and
    /// mirror it: the tangent equations are even under y -> -y (the Jacobian of an odd field
    /// is even), so mirrored starts get the same exponent bit for bit. Twins are not mirrored
    /// (the twin of -y sits at -y + eps, the mirror of y - eps, not of y + eps).
    pub use_symmetry: bool,
    /// The GPU's precision (the CPU is always f64); grids finer than f32 resolves run in f64.
    pub precision: Precision,
    /// Only these rows of the grid (first, count), as for [`FlipSpec::band`].
    pub band: Option<(u32, u32)>,
    /// How the state and the tangent vector are stepped: RK4 at `dt`, or DP54 with every
    /// pendulum's own steps (of at most `dt`) between renormalisations, which it lands on
    /// exactly; the error is controlled over the state and the tangent vector. Tangent method
    /// only.
    pub integrator: Integrator,
}

impl LyapunovSpec {
    /// Rows to integrate: the band's, or all from the top, or the top half when the other
    /// half mirrors it.
    pub fn rows_to_integrate(&self) -> u32 {
        self.row_span().count
    }

    /// Whether the tangent map's point symmetry applies (see `use_symmetry`).
    pub fn mirrors(&self) -> bool {
        self.use_symmetry && self.method == Method::Tangent
    }

    pub fn row_span(&self) -> RowSpan {
        match self.band {
            Some((first, count)) => RowSpan {
                first,
                count,
                whole: false,
            },
            None if self.mirrors() && self.grid.point_symmetric() => {
                RowSpan::top(self.grid.height.div_ceil(2))
            }
            None => RowSpan::top(self.grid.height),
        }
    }

    /// Steps between renormalisations (the last interval may be shorter).
    pub fn renorm_steps(&self) -> u32 {
        ((self.renorm / self.stepping.dt).round() as u32).max(1)
    }

    pub fn validate(&self) -> Result<()> {
        validate_params(&self.params)?;
        validate_grid(&self.grid)?;
        self.validate_run()
    }

    /// Everything but the grid (a single-point run has none).
    pub fn validate_run(&self) -> Result<()> {
        validate_params(&self.params)?;
        validate_stepping(&self.stepping)?;
        validate_stability(&self.params, &self.stepping)?;
        let g = &self.grid;
        validate_speeds(&self.params, &self.stepping, g.omega1, g.omega2)?;
        let k = self.renorm / self.stepping.dt;
        if !(self.renorm.is_finite() && self.renorm > 0.0)
            || k.round() < 1.0
            || (k - k.round()).abs() > 1e-9 * k
            || self.renorm > self.stepping.t_max
        {
            return Err(Error::invalid(
                "renorm",
                format!(
                    "{} s must be a whole multiple of the time step {} s and at most the run's {} s",
                    self.renorm, self.stepping.dt, self.stepping.t_max
                ),
            ));
        }
        self.integrator.validate(Precision::F64)?;
        match (self.method, self.integrator) {
            (_, Integrator::Rk4) | (Method::Tangent, Integrator::Dp54 { .. }) => {}
            (Method::Twin { .. }, _) | (_, Integrator::Dop853 { .. }) => {
                return Err(Error::invalid(
                    "integrator",
                    "divergence maps step adaptively with dp54 and the tangent method only",
                ));
            }
        }
        if let Method::Twin { eps } = self.method
            && !(eps.is_finite() && eps > 0.0 && eps <= 0.1)
        {
            return Err(Error::invalid(
                "eps",
                format!("{eps} must be in (0, 0.1]: the twin must stay in the linear regime"),
            ));
        }
        Ok(())
    }
}

/// `v` finite and > 0, else an error naming `field`.
pub(crate) fn finite_positive(field: &'static str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!("{v} is not allowed; it must be a finite number > 0"),
        ))
    }
}

pub fn validate_params(p: &Params) -> Result<()> {
    crate::params::validate(p)
}

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
        for lambda in a.complex_eigenvalues().iter() {
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

pub fn validate_stepping(s: &Stepping) -> Result<()> {
    finite_positive("dt", s.dt)?;
    finite_positive("t_max", s.t_max)?;
    let n = s.t_max / s.dt;
    if n > MAX_STEPS as f64 {
        return Err(Error::invalid(
            "dt",
            format!(
                "t-max / dt = {n:.0} steps; at most {MAX_STEPS} are allowed (raise the step or shorten the run)"
            ),
        ));
    }
    Ok(())
}

/// A single start (trajectory, convergence run): every component finite.
pub fn validate_start(s: &State) -> Result<()> {
    for (field, v) in [
        ("theta1", s.theta1),
        ("theta2", s.theta2),
        ("omega1", s.omega1),
        ("omega2", s.omega2),
    ] {
        if !v.is_finite() {
            return Err(Error::invalid(field, "must be a finite number"));
        }
    }
    Ok(())
}

/// Angles must stay strictly inside (-pi, pi): a start outside has already flipped.
fn validate_range(field: &'static str, r: &Range) -> Result<()> {
    use std::f64::consts::PI;
    // Allow the user's "-pi:pi" written with a rounded pi.
    let limit = PI + 1e-9;
    if !(r.min.is_finite() && r.max.is_finite()) || r.min >= r.max {
        return Err(Error::invalid(
            field,
            format!("{}:{} must be MIN:MAX with MIN < MAX", r.min, r.max),
        ));
    }
    if r.min < -limit || r.max > limit {
        return Err(Error::invalid(
            field,
            format!("{}:{} must lie within -pi:pi", r.min, r.max),
        ));
    }
    Ok(())
}

pub fn validate_grid(g: &Grid) -> Result<()> {
    const MAX_SIDE: u32 = 1 << 16;
    if g.width == 0 || g.height == 0 || g.width > MAX_SIDE || g.height > MAX_SIDE {
        return Err(Error::invalid(
            "size",
            format!(
                "{}x{} must be between 1 and {MAX_SIDE} on each side",
                g.width, g.height
            ),
        ));
    }
    // The map (4 B), its colours (3 B) and the PNG encoder's copy (3 B) live in memory at once.
    check_memory(
        "size",
        g.pixels() * 10,
        &format!("a {}x{} map", g.width, g.height),
    )?;
    validate_range("theta1", &g.theta1)?;
    validate_range("theta2", &g.theta2)?;
    if !g.omega1.is_finite() {
        return Err(Error::invalid("omega1", "must be a finite number"));
    }
    if !g.omega2.is_finite() {
        return Err(Error::invalid("omega2", "must be a finite number"));
    }
    Ok(())
}

/// Memory this process can still take (bytes): the least of what the system has available
/// (MemAvailable), what its cgroup allows beyond its use (v2 memory.max, v1
/// memory.limit_in_bytes), and what its address-space limit (RLIMIT_AS, as `ulimit -v`
/// sets) leaves beyond its current size; 16 GiB where none can be read.
pub fn available_memory() -> u64 {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let number = |s: Option<String>| s.and_then(|s| s.trim().parse::<u64>().ok());
    let field_kb = |text: &Option<String>, key: &str| {
        text.as_ref().and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
                .map(|kb| kb * 1024)
        })
    };
    let mut limits = vec![field_kb(&read("/proc/meminfo"), "MemAvailable:")];
    // The cgroup: its own directory (v2 "0::/path", v1 "N:memory:/path"), or the mounted
    // root when the container shows its cgroup there.
    let cgroup = read("/proc/self/cgroup").unwrap_or_default();
    let own = |prefix: &str| {
        cgroup
            .lines()
            .find_map(|l| l.split_once(prefix).map(|(_, p)| p.to_string()))
            .unwrap_or_default()
    };
    for (dir, max, used) in [
        (
            format!("/sys/fs/cgroup{}", own("::")),
            "memory.max",
            "memory.current",
        ),
        ("/sys/fs/cgroup".to_string(), "memory.max", "memory.current"),
        (
            format!("/sys/fs/cgroup/memory{}", own(":memory:")),
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
        ),
        (
            "/sys/fs/cgroup/memory".to_string(),
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
        ),
    ] {
        // "max" (v2) or a huge number (v1) means no limit: it does not parse or never binds.
        if let (Some(max), Some(used)) = (
            number(read(&format!("{dir}/{max}"))),
            number(read(&format!("{dir}/{used}"))),
        ) {
            limits.push(Some(max.saturating_sub(used)));
        }
    }
    let address_space = read("/proc/self/limits").and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("Max address space"))
            .and_then(|l| l.split_whitespace().nth(3))
            .and_then(|soft| soft.parse::<u64>().ok())
    });
    if let Some(limit) = address_space {
        let size = field_kb(&read("/proc/self/status"), "VmSize:").unwrap_or(0);
        limits.push(Some(limit.saturating_sub(size)));
    }
    limits.into_iter().flatten().min().unwrap_or(16 << 30)
}

/// `need` bytes for `what` fit in [`available_memory`], else an error naming `field`.
pub fn check_memory(field: &'static str, need: u64, what: &str) -> Result<()> {
    let have = available_memory();
    if need > have {
        return Err(Error::invalid(
            field,
            format!(
                "{what} needs about {} MiB but only {} MiB of memory are available to this process",
                need >> 20,
                have >> 20
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_round_off() {
        let s = Stepping {
            dt: 0.01,
            t_max: 20.0,
        };
        assert_eq!(s.steps(), 2000);
        let s = Stepping {
            dt: 0.3,
            t_max: 1.0,
        };
        assert_eq!(s.steps(), 4);
    }

    #[test]
    fn pixel_centres() {
        let g = Grid::square(4);
        let h = std::f64::consts::PI / 4.0;
        assert!((g.theta1_at(0) - (-3.0 * h)).abs() < 1e-15);
        assert!((g.theta2_at(0) - 3.0 * h).abs() < 1e-15);
        assert!((g.theta2_at(3) + 3.0 * h).abs() < 1e-15);
    }
}
