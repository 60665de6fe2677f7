//! Pod mirrors of the WGSL structs, and the constants the shaders share with Rust.
//! Keep in sync with `shaders/common.wgsl`; `tests/layout.rs` checks sizes and offsets.

use bytemuck::{Pod, Zeroable};

use crate::model::Params;
use crate::spec::Grid;

/// Invocations per workgroup. 64 fills eight 8-lane SIMD groups on lavapipe and two warps
/// on discrete GPUs.
pub const WORKGROUP_SIZE: u32 = 64;

/// The flip-time sentinel for "has not flipped" inside the shader (times are never negative).
pub const NEVER: f32 = -1.0;

/// The flip-time sentinel for "the state became infinite or NaN before any flip".
pub const NONFINITE: f32 = -2.0;

/// Mirror of WGSL `Pendulum`: the state y = (theta1, omega1, theta2, omega2) and the cos and
/// sin of the angles carried along, u = (cos theta1, sin theta1, cos theta2, sin theta2).
/// The flip kernel stores one per pixel (`states[2 i]`, `states[2 i + 1]`), trajectories
/// store the y of each kept step.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPendulum {
    pub y: [f32; 4],
    pub u: [f32; 4],
}

/// Mirror of WGSL `LyapunovSlot`, one per pixel of a divergence map: a pendulum and its
/// tangent vector in `b.y` (tangent method), or a pendulum and its twin (twin method).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLyapunovSlot {
    pub a: GpuPendulum,
    pub b: GpuPendulum,
}

/// Bytes of a flip map's tile per pixel: its pendulum, flip time and two active-list entries.
pub const FLIP_BYTES_PER_PIXEL: u64 = (std::mem::size_of::<GpuPendulum>()
    + std::mem::size_of::<f32>()
    + 2 * std::mem::size_of::<u32>()) as u64;

/// Bytes of a divergence map's tile per pixel: its slot and log-stretch sum.
pub const LYAPUNOV_BYTES_PER_PIXEL: u64 =
    (std::mem::size_of::<GpuLyapunovSlot>() + std::mem::size_of::<f32>()) as u64;

/// Mirror of WGSL `Params`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuParams {
    pub a: f32,
    pub b: f32,
    pub c: f32,
    pub p: f32,
    pub q: f32,
    pub l1: f32,
    pub l2: f32,
    pub dt: f32,
    pub theta1_mid: f32,
    pub theta1_half_step: f32,
    pub theta2_mid: f32,
    pub theta2_half_step: f32,
    pub omega1: f32,
    pub omega2: f32,
    pub no_flip_energy: f32,
    pub joint1: f32,
    pub joint2: f32,
    pub drag_bob1: f32,
    pub drag_bob2: f32,
    pub drag_rod1: f32,
    pub drag_rod2: f32,
    /// Bearing friction: g, all moving mass, the mass below the middle joint, c_R r.
    pub g: f32,
    pub mass_total: f32,
    pub mass_lower: f32,
    pub bearing: f32,
    pub width: u32,
    pub height: u32,
    pub rows: u32,
    pub row0: u32,
    pub step0: u32,
    pub steps: u32,
    pub count: u32,
    /// Steps between renormalisations (divergence maps) or between stored states
    /// (trajectories); steps of the whole run; twin separation (Euclidean in (theta1, omega1,
    /// theta2, omega2)).
    pub interval: u32,
    pub total_steps: u32,
    pub twin_eps: f32,
    pub _pad0: u32,
}

// A uniform buffer's size must be a multiple of 16 bytes.
const _: () = assert!(std::mem::size_of::<GpuParams>() == 144);

impl GpuParams {
    /// The coefficients are formed in f64 and rounded once. Everything measured in mass
    /// (inertias, torques, energies, masses) is scaled by the power of two nearest 1 / A: the
    /// motion does not depend on the mass scale, and f32 then holds any mass without
    /// overflow or underflow. A power of two scales exactly, so results keep every bit.
    pub fn new(p: &Params, dt: f64) -> Self {
        let i = p.inertia();
        let s = (-i.a.log2().round()).exp2();
        let m = |x: f64| (x * s) as f32;
        let [drag_bob1, drag_bob2, drag_rod1, drag_rod2] = p.losses.drag_factors();
        let (mass_total, mass_lower) = p.moving_mass();
        GpuParams {
            a: m(i.a),
            b: m(i.b),
            c: m(i.c),
            p: m(i.p),
            q: m(i.q),
            l1: p.l1 as f32,
            l2: p.l2 as f32,
            dt: dt as f32,
            no_flip_energy: m(p.no_flip_threshold(f32::EPSILON as f64)),
            joint1: m(p.losses.joint1),
            joint2: m(p.losses.joint2),
            drag_bob1: m(drag_bob1),
            drag_bob2: m(drag_bob2),
            drag_rod1: m(drag_rod1),
            drag_rod2: m(drag_rod2),
            g: p.g as f32,
            mass_total: m(mass_total),
            mass_lower: m(mass_lower),
            bearing: (p.losses.bearing * p.losses.bearing_radius) as f32,
            ..Default::default()
        }
    }

    pub fn with_grid(mut self, g: &Grid) -> Self {
        self.theta1_mid = g.theta1.mid() as f32;
        self.theta1_half_step = (0.5 * g.theta1_step()) as f32;
        self.theta2_mid = g.theta2.mid() as f32;
        self.theta2_half_step = (0.5 * g.theta2_step()) as f32;
        self.omega1 = g.omega1 as f32;
        self.omega2 = g.omega2 as f32;
        self.width = g.width;
        self.height = g.height;
        self
    }
}

/// Full WGSL source of a kernel: Rust constants, then `common.wgsl`, then the kernel file.
pub fn shader_source(kernel: &str) -> String {
    format!(
        "const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\nconst NEVER: f32 = {NEVER:?};\nconst NONFINITE: f32 = {NONFINITE:?};\n{}\n{}",
        include_str!("../../shaders/common.wgsl"),
        kernel
    )
}

pub const FLIP_TIME_WGSL: &str = include_str!("../../shaders/flip_time.wgsl");
pub const TRAJECTORY_WGSL: &str = include_str!("../../shaders/trajectory.wgsl");
pub const LYAPUNOV_WGSL: &str = include_str!("../../shaders/lyapunov.wgsl");

/// Every kernel's full source, named, for validation.
pub fn all_shaders() -> Vec<(&'static str, String)> {
    vec![
        ("flip_time", shader_source(FLIP_TIME_WGSL)),
        ("trajectory", shader_source(TRAJECTORY_WGSL)),
        ("lyapunov", shader_source(LYAPUNOV_WGSL)),
    ]
}
