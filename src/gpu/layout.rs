//! Pod mirrors of the WGSL structs, and the constants the shaders share with Rust.
//! Keep in sync with `shaders/common.wgsl`; `tests/layout.rs` checks sizes and offsets.

use bytemuck::{Pod, Zeroable};

use crate::model::Params;
use crate::spec::Grid;

/// Invocations per workgroup. 64 fills eight 8-lane SIMD groups on lavapipe and two warps
/// on discrete GPUs.
pub const WORKGROUP_SIZE: u32 = 64;

/// The most workgroups a dispatch takes along one dimension (WebGPU's and wgpu's default
/// limit).
pub const MAX_WORKGROUPS: u32 = 65535;

/// The flip-time sentinel for "has not flipped" inside the shader (times are never negative).
pub const NEVER: f32 = -1.0;

/// The flip-time sentinel for "the state became infinite or NaN before any flip".
pub const NONFINITE: f32 = -2.0;

/// The host's mirrors of the WGSL structs, each from one definition made in both scalars:
/// `real` fields become f32 in the first name and f64 in the second, `[real; N]` likewise,
/// `pendulum` the mirror of `Pendulum` in that scalar, `pad64` a u32 of padding that only
/// f64's alignment needs (nothing in f32); other fields stay as written.
macro_rules! mirrors {
    ($($(#[$m:meta])* struct $f32:ident / $f64:ident {
        $($(#[$fm:meta])* $field:ident: $ty:tt,)*
    })*) => {
        $(
            $(#[$m])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
            pub struct $f32 {
                $($(#[$fm])* pub $field: scalar!(f32, $ty),)*
            }

            $(#[$m])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
            pub struct $f64 {
                $($(#[$fm])* pub $field: scalar!(f64, $ty),)*
            }
        )*
    };
}

/// A field's type in a mirror of scalar `$r` (see [`mirrors`]).
macro_rules! scalar {
    (f32, pad64) => {
        [u32; 0]
    };
    (f64, pad64) => {
        u32
    };
    (f32, pendulum) => {
        GpuPendulum
    };
    (f64, pendulum) => {
        GpuPendulum64
    };
    ($r:ident, real) => {
        $r
    };
    ($r:ident, [real; $n:literal]) => {
        [$r; $n]
    };
    ($r:ident, $t:ty) => {
        $t
    };
}

mirrors! {
    /// Mirror of WGSL `Pendulum`: the state y = (theta1, omega1, theta2, omega2) and the cos
    /// and sin of the angles carried along, u = (cos theta1, sin theta1, cos theta2, sin
    /// theta2). The flip kernel stores one per pixel (`states[2 i]`, `states[2 i + 1]`),
    /// trajectories store the y of each kept step.
    struct GpuPendulum / GpuPendulum64 {
        y: [real; 4],
        u: [real; 4],
    }

    /// Mirror of WGSL `LyapunovSlot`, one per pixel of a divergence map: a pendulum (`y`,
    /// `u`) and its tangent vector in `v` and adaptive clock in `w` (tangent method), or its
    /// twin's `y` and `u` there (twin method).
    struct GpuLyapunovSlot / GpuLyapunovSlot64 {
        y: [real; 4],
        u: [real; 4],
        v: [real; 4],
        w: [real; 4],
    }

    /// Mirror of WGSL `AdaptiveSlot` (shaders/adaptive_common.wgsl), one per pixel of an
    /// adaptive map: the pendulum and its clock, (t, the next step's size, attempts so far,
    /// unused).
    struct GpuAdaptiveSlot / GpuAdaptiveSlot64 {
        y: [real; 4],
        u: [real; 4],
        clock: [real; 4],
    }

    /// Mirror of WGSL `IndicatorSlot` (shaders/indicators.wgsl), one per pixel of an
    /// indicator map: the pendulum, four tangent vectors, the running sums, and the adaptive
    /// spectrum's clock (the next step, attempts so far (-1: stalled), windows done, the time
    /// into the next).
    struct GpuIndicatorSlot / GpuIndicatorSlot64 {
        y: [real; 4],
        u: [real; 4],
        v: [real; 16],
        sums: [real; 4],
        clock: [real; 4],
    }

    /// Mirror of WGSL `Params`, laid out by WGSL's rules (f64 aligned to 8 bytes; the padding
    /// made explicit for Pod).
    struct GpuParams / GpuParams64 {
        a: real,
        b: real,
        c: real,
        p: real,
        q: real,
        l1: real,
        l2: real,
        dt: real,
        x_mid: real,
        x_half_step: real,
        y_mid: real,
        y_half_step: real,
        omega1: real,
        omega2: real,
        no_flip_energy: real,
        joint1: real,
        joint2: real,
        drag_bob1: real,
        drag_bob2: real,
        drag_rod1: real,
        drag_rod2: real,
        /// Bearing friction: g, all moving mass, the mass below the middle joint, c_R r.
        g: real,
        mass_total: real,
        mass_lower: real,
        bearing: real,
        /// The start's angles where no axis sets them; the masses (scaled) a parameter
        /// plane forms its coefficients from.
        theta1: real,
        theta2: real,
        m1: real,
        m2: real,
        rod1: real,
        rod2: real,
        /// Above 0: the pixels are pairs of starts (`Sampling::Pairs`), the plane's fields
        /// each range's minimum and width.
        eps: real,
        width: u32,
        height: u32,
        rows: u32,
        row0: u32,
        step0: u32,
        steps: u32,
        count: u32,
        /// Steps between renormalisations (divergence maps) or between stored states
        /// (trajectories); steps of the whole run; the method's setting: the twin's
        /// separation (Euclidean in (theta1, omega1, theta2, omega2)), an alignment index's
        /// threshold, a Lagrangian descriptor's exponent p.
        interval: u32,
        total_steps: u32,
        _pad_a: pad64,
        setting: real,
        /// Adaptive steps: relative and absolute tolerance, the run's end time (s).
        rtol: real,
        atol: real,
        t_max: real,
        /// Which value an indicator kernel writes (shaders/indicators.wgsl).
        measure: u32,
        /// What the axes vary (`Var::code`).
        x_var: u32,
        y_var: u32,
        seed: u32,
        /// 6, Runge-Kutta's divisor, as data: a division by a literal may be compiled as a
        /// multiplication by its reciprocal (Chromium's WebGPU does), one by data stays exact.
        six: real,
    }
}

// A uniform buffer's size must be a multiple of 16 bytes; f64's is WGSL's size of the struct
// (its alignment, 8), the buffer rounded up to 16 bytes.
const _: () = assert!(std::mem::size_of::<GpuParams>() == 200);
const _: () = assert!(std::mem::size_of::<GpuParams64>() == 352);

/// `new` (physics and step) and `with_grid` (the grid) of a params mirror whose floats are
/// `$float`, `$eps` its machine epsilon (the margin of the no-flip energy).
macro_rules! params_constructors {
    ($float:ty, $eps:expr) => {
        /// The coefficients are formed in f64 and rounded once. Everything measured in mass
        /// (inertias, torques, energies, masses) is scaled by the power of two nearest 1 / A:
        /// the motion does not depend on the mass scale, and f32 then holds any mass without
        /// overflow or underflow. A power of two scales exactly, so results keep every bit.
        pub fn new(p: &Params, dt: f64) -> Self {
            let i = p.inertia();
            let s = mass_scale(p);
            let m = |x: f64| (x * s) as $float;
            let [drag_bob1, drag_bob2, drag_rod1, drag_rod2] = p.losses.drag_factors();
            let (mass_total, mass_lower) = p.moving_mass();
            Self {
                a: m(i.a),
                b: m(i.b),
                c: m(i.c),
                p: m(i.p),
                q: m(i.q),
                l1: p.l1 as $float,
                l2: p.l2 as $float,
                dt: dt as $float,
                no_flip_energy: m(p.no_flip_threshold($eps)),
                joint1: m(p.losses.joint1),
                joint2: m(p.losses.joint2),
                drag_bob1: m(drag_bob1),
                drag_bob2: m(drag_bob2),
                drag_rod1: m(drag_rod1),
                drag_rod2: m(drag_rod2),
                g: p.g as $float,
                mass_total: m(mass_total),
                mass_lower: m(mass_lower),
                bearing: (p.losses.bearing * p.losses.bearing_radius) as $float,
                m1: m(p.m1),
                m2: m(p.m2),
                rod1: m(p.rod1),
                rod2: m(p.rod2),
                six: 6.0,
                ..Default::default()
            }
        }

        /// The plane of `g`; an axis measured in mass in the mass scale of `new`.
        pub fn with_grid(mut self, g: &Grid, p: &Params) -> Self {
            let s = mass_scale(p);
            let scale = |a: &crate::spec::Axis| if a.var.is_mass() { s } else { 1.0 };
            let (sx, sy) = (scale(&g.x), scale(&g.y));
            match g.sampling {
                crate::spec::Sampling::Centres => {
                    self.x_mid = (g.x.range.mid() * sx) as $float;
                    self.x_half_step = (0.5 * g.x_step() * sx) as $float;
                    self.y_mid = (g.y.range.mid() * sy) as $float;
                    self.y_half_step = (0.5 * g.y_step() * sy) as $float;
                }
                crate::spec::Sampling::Pairs { seed, eps } => {
                    let (x, y) = (g.x.range, g.y.range);
                    self.x_mid = (x.min * sx) as $float;
                    self.x_half_step = ((x.max - x.min) * sx) as $float;
                    self.y_mid = (y.min * sy) as $float;
                    self.y_half_step = ((y.max - y.min) * sy) as $float;
                    self.eps = eps as $float;
                    self.seed = seed;
                }
            }
            self.x_var = g.x.var.code();
            self.y_var = g.y.var.code();
            self.theta1 = g.fixed.theta1 as $float;
            self.theta2 = g.fixed.theta2 as $float;
            self.omega1 = g.fixed.omega1 as $float;
            self.omega2 = g.fixed.omega2 as $float;
            self.width = g.width;
            self.height = g.height;
            self
        }
    };
}

/// The power of two nearest 1 / A that the GPU's mass-measured values are scaled by.
pub fn mass_scale(p: &Params) -> f64 {
    (-p.inertia().a.log2().round()).exp2()
}

impl GpuParams {
    params_constructors!(f32, f32::EPSILON as f64);
}

impl GpuParams64 {
    params_constructors!(f64, f64::EPSILON);
}

/// A scalar the GPU kernels run in, as a type: its precision, its mirrors of the WGSL structs,
/// and the conversions. Kernels are written once over it; `with_real!` turns a run's
/// [`Precision`](crate::spec::Precision) into it, the one place where a precision is matched on the host.
pub trait Real: Pod + Copy + Default + PartialEq + std::fmt::Debug + Send + Sync + 'static {
    /// Its WGSL file: `alias real = ...` and the functions whose form differs by precision.
    const WGSL: &'static str;
    type Params: TileParams + RunParams;
    type Pendulum: Pod + Default;
    type LyapunovSlot: Pod + Default;
    type AdaptiveSlot: Pod + Default;
    type IndicatorSlot: Pod + Default;
    /// An indicator slot's running sums (the spectrum's four log sums).
    fn slot_sums(slot: &Self::IndicatorSlot) -> [f64; 4];
    /// An indicator slot's adaptive clock ([`super::tiled::catch_up`]).
    fn slot_clock(slot: &Self::IndicatorSlot) -> [f64; 4];
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
}

macro_rules! real {
    ($r:ident, $wgsl:literal, $params:ident, $pendulum:ident, $slot:ident, $adaptive:ident, $indicator:ident) => {
        impl Real for $r {
            const WGSL: &'static str = include_str!($wgsl);
            type Params = $params;
            type Pendulum = $pendulum;
            type LyapunovSlot = $slot;
            type AdaptiveSlot = $adaptive;
            type IndicatorSlot = $indicator;
            fn slot_sums(slot: &$indicator) -> [f64; 4] {
                slot.sums.map(|x| x as f64)
            }
            fn slot_clock(slot: &$indicator) -> [f64; 4] {
                slot.clock.map(|x| x as f64)
            }
            fn from_f64(x: f64) -> Self {
                x as $r
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
        }

        impl RunParams for $params {
            fn of(p: &Params, dt: f64) -> Self {
                $params::new(p, dt)
            }
            fn over(self, g: &Grid, p: &Params) -> Self {
                self.with_grid(g, p)
            }
            fn with_run(mut self, run: Run) -> Self {
                self.interval = run.interval;
                self.total_steps = run.total_steps;
                self.steps = run.steps;
                self.count = run.count;
                self.setting = run.setting as $r;
                self.measure = run.measure;
                self.rtol = run.rtol as $r;
                self.atol = run.atol as $r;
                self.t_max = run.t_max as $r;
                self
            }
        }
    };
}
real!(
    f32,
    "../../shaders/real_f32.wgsl",
    GpuParams,
    GpuPendulum,
    GpuLyapunovSlot,
    GpuAdaptiveSlot,
    GpuIndicatorSlot
);
real!(
    f64,
    "../../shaders/real_f64.wgsl",
    GpuParams64,
    GpuPendulum64,
    GpuLyapunovSlot64,
    GpuAdaptiveSlot64,
    GpuIndicatorSlot64
);

/// `$body` with the type `$r` the [`Real`] of `$precision`.
macro_rules! with_real {
    ($precision:expr, $r:ident => $body:expr) => {
        match $precision {
            $crate::spec::Precision::F32 => {
                type $r = f32;
                $body
            }
            $crate::spec::Precision::F64 => {
                type $r = f64;
                $body
            }
        }
    };
}
pub(crate) use with_real;

/// The values of a buffer of `R`s, as f64.
pub fn read_reals<R: Real>(bytes: &[u8]) -> Vec<f64> {
    bytemuck::pod_collect_to_vec::<u8, R>(bytes)
        .into_iter()
        .map(R::to_f64)
        .collect()
}

/// A time of an ensemble's positions (`shaders/positions.wgsl`): the step it falls in (from
/// the state after `step` steps to the next) and the fraction of that step.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBandTime {
    pub step: u32,
    pub fraction: f32,
}

impl GpuBandTime {
    /// Time `t` (s from the runs' start) among `steps` (at least one) steps of `dt`, computed
    /// in f64: the fraction in f32 errs by 6e-8 of a step.
    pub fn at(t: f64, dt: f64, steps: u32) -> Self {
        let x = (t / dt).max(0.0);
        let step = (x.floor() as u32).min(steps - 1);
        GpuBandTime {
            step,
            fraction: (x - step as f64).clamp(0.0, 1.0) as f32,
        }
    }
}

/// What a run sets in its params beyond the physics and the grid (0 where unused).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Run {
    pub interval: u32,
    pub total_steps: u32,
    pub steps: u32,
    pub count: u32,
    pub setting: f64,
    pub measure: u32,
    pub rtol: f64,
    pub atol: f64,
    pub t_max: f64,
}

/// A params mirror built from the run's physics, grid and settings, whichever its scalar.
pub trait RunParams: Sized {
    fn of(p: &Params, dt: f64) -> Self;
    /// The plane of `g` over the map's parameters `p` (those `of` was made from).
    fn over(self, g: &Grid, p: &Params) -> Self;
    fn with_run(self, run: Run) -> Self;
}

/// The tile counters of a kernel's params, whichever its precision.
pub trait TileParams: Pod {
    fn set_tile(&mut self, row0: u32, rows: u32, count: u32);
    fn set_steps(&mut self, step0: u32, steps: u32, count: u32);
    fn set_total(&mut self, total_steps: u32);
    fn set_interval(&mut self, interval: u32);
    fn count(&self) -> u32;
}

macro_rules! tile_params {
    ($t:ty) => {
        impl TileParams for $t {
            fn set_tile(&mut self, row0: u32, rows: u32, count: u32) {
                (self.row0, self.rows, self.count) = (row0, rows, count);
            }
            fn set_steps(&mut self, step0: u32, steps: u32, count: u32) {
                (self.step0, self.steps, self.count) = (step0, steps, count);
            }
            fn set_total(&mut self, total_steps: u32) {
                self.total_steps = total_steps;
            }
            fn set_interval(&mut self, interval: u32) {
                self.interval = interval;
            }
            fn count(&self) -> u32 {
                self.count
            }
        }
    };
}
tile_params!(GpuParams);
tile_params!(GpuParams64);
