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

/// Mirror of WGSL `AdaptiveSlot` (shaders/flip_adaptive.wgsl), one per pixel of an adaptive
/// map: the pendulum and its clock, (t, the next step's size, attempts so far, unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuAdaptiveSlot {
    pub y: [f32; 4],
    pub u: [f32; 4],
    pub clock: [f32; 4],
}

/// Mirror of WGSL `AdaptiveSlot` in the f64 kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuAdaptiveSlot64 {
    pub y: [f64; 4],
    pub u: [f64; 4],
    pub clock: [f64; 4],
}

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
    /// Adaptive steps: relative and absolute tolerance, the run's end time (s).
    pub rtol: f32,
    pub atol: f32,
    pub t_max: f32,
    pub _pad0: u32,
    pub _pad1: u32,
}

// A uniform buffer's size must be a multiple of 16 bytes.
const _: () = assert!(std::mem::size_of::<GpuParams>() == 160);

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
            let s = (-i.a.log2().round()).exp2();
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
                ..Default::default()
            }
        }

        pub fn with_grid(mut self, g: &Grid) -> Self {
            self.theta1_mid = g.theta1.mid() as $float;
            self.theta1_half_step = (0.5 * g.theta1_step()) as $float;
            self.theta2_mid = g.theta2.mid() as $float;
            self.theta2_half_step = (0.5 * g.theta2_step()) as $float;
            self.omega1 = g.omega1 as $float;
            self.omega2 = g.omega2 as $float;
            self.width = g.width;
            self.height = g.height;
            self
        }
    };
}

impl GpuParams {
    params_constructors!(f32, f32::EPSILON as f64);
}

/// Mirror of WGSL `Params` in the f64 kernels ([`shader_source_f64`]): the same members
/// with f64 in place of f32, laid out by WGSL's rules (f64 aligned to 8 bytes; the padding
/// made explicit for Pod).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuParams64 {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub p: f64,
    pub q: f64,
    pub l1: f64,
    pub l2: f64,
    pub dt: f64,
    pub theta1_mid: f64,
    pub theta1_half_step: f64,
    pub theta2_mid: f64,
    pub theta2_half_step: f64,
    pub omega1: f64,
    pub omega2: f64,
    pub no_flip_energy: f64,
    pub joint1: f64,
    pub joint2: f64,
    pub drag_bob1: f64,
    pub drag_bob2: f64,
    pub drag_rod1: f64,
    pub drag_rod2: f64,
    pub g: f64,
    pub mass_total: f64,
    pub mass_lower: f64,
    pub bearing: f64,
    pub width: u32,
    pub height: u32,
    pub rows: u32,
    pub row0: u32,
    pub step0: u32,
    pub steps: u32,
    pub count: u32,
    pub interval: u32,
    pub total_steps: u32,
    pub _pad_a: u32,
    pub twin_eps: f64,
    pub rtol: f64,
    pub atol: f64,
    pub t_max: f64,
    pub _pad0: u32,
    pub _pad1: u32,
}

// WGSL's size of the struct (its alignment, 8); the buffer is rounded up to 16 bytes.
const _: () = assert!(std::mem::size_of::<GpuParams64>() == 280);

impl GpuParams64 {
    params_constructors!(f64, f64::EPSILON);
}

/// Mirror of WGSL `Pendulum` in the f64 kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPendulum64 {
    pub y: [f64; 4],
    pub u: [f64; 4],
}

/// The tile counters of a kernel's params, whichever its precision.
pub trait TileParams: Pod {
    fn set_tile(&mut self, row0: u32, rows: u32, count: u32);
    fn set_steps(&mut self, step0: u32, steps: u32, count: u32);
    fn set_total(&mut self, total_steps: u32);
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
            fn count(&self) -> u32 {
                self.count
            }
        }
    };
}
tile_params!(GpuParams);
tile_params!(GpuParams64);

/// Full WGSL source of a kernel: Rust constants, then `common.wgsl`, then the kernel file.
pub fn shader_source(kernel: &str) -> String {
    format!(
        "const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\nconst NEVER: f32 = {NEVER:?};\nconst NONFINITE: f32 = {NONFINITE:?};\n{}\n{}",
        include_str!("../../shaders/common.wgsl"),
        kernel
    )
}

pub const FLIP_TIME_WGSL: &str = include_str!("../../shaders/flip_time.wgsl");
const FLIP_KIND_WGSL: &str = include_str!("../../shaders/flip_kind.wgsl");

/// The flip-kind kernel: the flip-time kernel's loop and flip location, and its own entry.
pub fn flip_kind_wgsl() -> String {
    format!("{FLIP_TIME_WGSL}\n{FLIP_KIND_WGSL}")
}
pub const TRAJECTORY_WGSL: &str = include_str!("../../shaders/trajectory.wgsl");
const LYAPUNOV_KERNEL_WGSL: &str = include_str!("../../shaders/lyapunov.wgsl");

/// The divergence kernels, with DP54's coefficients for the adaptive tangent.
pub fn lyapunov_wgsl() -> String {
    format!("{DP54_WGSL}\n{LYAPUNOV_KERNEL_WGSL}")
}
const ADAPTIVE_COMMON_WGSL: &str = include_str!("../../shaders/adaptive_common.wgsl");
const FLIP_DP54_WGSL: &str = include_str!("../../shaders/flip_adaptive.wgsl");
const DP54_WGSL: &str = include_str!("../../shaders/dp54.wgsl");
const FLIP_DOP853_WGSL: &str = include_str!("../../shaders/flip_dop853.wgsl");

/// The DP54 flip kernel: the adaptive kernels' shared part and the method's.
pub fn flip_adaptive_wgsl() -> String {
    format!("{ADAPTIVE_COMMON_WGSL}\n{DP54_WGSL}\n{FLIP_DP54_WGSL}")
}

/// The DOP853 flip kernel: its template with the stages written out from the tableau
/// (src/tableau.rs, which the CPU twin loops over), only the nonzero weights, as literals
/// that WGSL takes at full precision in either float type.
pub fn flip_dop853_wgsl() -> String {
    let t = &crate::tableau::DOP853;
    // "w1 * k1.dy + w2 * k2.dy ..." over the nonzero weights (stage j is k{j + 1}).
    let sum = |weights: &[f64], part: &str| -> String {
        let terms: Vec<String> = weights
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != 0.0)
            .map(|(j, w)| format!("{w:e} * k{}.{part}", j + 1))
            .collect();
        terms.join(" + ")
    };
    let stage = |s: usize| {
        let a = &t.a[s][..s];
        format!(
            "let k{} = rate(c, Pendulum(p.y + step * ({}), p.u + step * ({})));",
            s + 1,
            sum(a, "dy"),
            sum(a, "du")
        )
    };
    let indent = "\n        ";
    let mut stages: Vec<String> = (1..12).map(stage).collect();
    stages.push(format!(
        "let next = Pendulum(p.y + step * ({}), p.u + step * ({}));",
        sum(&t.b, "dy"),
        sum(&t.b, "du")
    ));
    stages.push(format!("let e5 = {};", sum(&t.e5, "dy")));
    stages.push(format!("let e3 = {};", sum(&t.e3, "dy")));
    let mut dense: Vec<String> = (13..16).map(stage).collect();
    for (m, d) in t.d.iter().enumerate() {
        dense.push(format!("let hd{m} = step * ({});", sum(d, "dy")));
    }
    let body = FLIP_DOP853_WGSL
        .replace("//{{STAGES}}", &stages.join(indent))
        .replace("//{{DENSE_STAGES}}", &dense.join("\n                "));
    assert!(
        !body.contains("{{"),
        "a placeholder left in flip_dop853.wgsl"
    );
    format!("{ADAPTIVE_COMMON_WGSL}\n{body}")
}

/// The f64 twin of `shader_source(kernel)`: the same WGSL with f64 for f32, and the few
/// pieces that f32 writes for its own precision written again: (sin, cos) by a longer
/// polynomial (SPIR-V's built-in trigonometry is f32 only: on lavapipe it returns garbage for
/// f64), the energy from that (sin, cos), the finiteness test, pi and the Gauss nodes to f64
/// precision, and the Hermite bisection to f64's 53 bits. Needs `Features::SHADER_F64`.
pub fn shader_source_f64(kernel: &str) -> String {
    let mut s = shader_source(kernel);
    for (name, body) in [
        ("sincos", SINCOS_F64),
        ("energy", ENERGY_F64),
        ("is_finite4", IS_FINITE4_F64),
    ] {
        s = replace_fn(&s, name, body);
    }
    // The divergence kernel's log stretches: SPIR-V's log is f32 only as well.
    if s.contains("+= log(") {
        s = s.replace("+= log(", "+= ln64(");
        s.push_str(LN_F64);
    }
    for (from, to) in [
        (
            "const PI: f32 = 3.14159265358979;",
            "const PI: f32 = 3.141592653589793;",
        ),
        (
            "vec3<f32>(0.1127016654, 0.5, 0.8872983346)",
            "vec3<f32>(0.1127016653792583, 0.5, 0.8872983346207417)",
        ),
        (
            "vec3<f32>(0.2777777778, 0.4444444444, 0.2777777778)",
            "vec3<f32>(0.2777777777777778, 0.4444444444444444, 0.2777777777777778)",
        ),
        (
            "for (var i = 0; i < 24; i++) {",
            "for (var i = 0; i < 53; i++) {",
        ),
    ] {
        assert!(s.contains(from), "f64 source: `{from}` not found");
        s = s.replace(from, to);
    }
    replace_word(&s, "f32", "f64")
}

/// `source` with the function `name` (from `fn name(` to its closing brace at the start of a
/// line) replaced by `body`.
fn replace_fn(source: &str, name: &str, body: &str) -> String {
    let start = source
        .find(&format!("fn {name}("))
        .unwrap_or_else(|| panic!("no fn {name} in the shader"));
    let end = start + source[start..].find("\n}\n").expect("a closing brace") + 3;
    format!(
        "{}{}{}",
        &source[..start],
        body.trim_end(),
        &source[end - 1..]
    )
}

/// `source` with the whole word `from` replaced by `to`.
fn replace_word(source: &str, from: &str, to: &str) -> String {
    let word = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = String::with_capacity(source.len());
    let mut rest = source;
    while let Some(i) = rest.find(from) {
        let before = rest[..i].chars().next_back();
        let after = rest[i + from.len()..].chars().next();
        out.push_str(&rest[..i]);
        if before.is_some_and(word) || after.is_some_and(word) {
            out.push_str(from);
        } else {
            out.push_str(to);
        }
        rest = &rest[i + from.len()..];
    }
    out.push_str(rest);
    out
}

/// (sin x, cos x) in f64: x = q pi/2 + r with pi/2 in three parts (Cody-Waite, fdlibm's
/// constants), Taylor polynomials to r^17 and r^18 on |r| <= pi/4 (the next terms are below
/// 1e-19), the quadrant q mod 4. tests/precision.rs measures it against Rust's sin and cos.
const SINCOS_F64: &str = "fn sincos(x: f32) -> vec2<f32> {
    let q = round(x * 0.6366197723675814);
    let r = fma(-q, 2.0222662487111665e-21, fma(-q, 6.077100506303966e-11, fma(-q, 1.5707963267341256, x)));
    let r2 = r * r;
    var s: f32 = 2.8114572543455206e-15;
    s = fma(s, r2, -7.647163731819816e-13);
    s = fma(s, r2, 1.6059043836821613e-10);
    s = fma(s, r2, -2.505210838544172e-8);
    s = fma(s, r2, 2.7557319223985893e-6);
    s = fma(s, r2, -1.984126984126984e-4);
    s = fma(s, r2, 8.333333333333333e-3);
    s = fma(s, r2, -1.6666666666666666e-1);
    s = fma(s * r2, r, r);
    var c: f32 = -1.5619206968586225e-16;
    c = fma(c, r2, 4.779477332387385e-14);
    c = fma(c, r2, -1.1470745597729725e-11);
    c = fma(c, r2, 2.08767569878681e-9);
    c = fma(c, r2, -2.755731922398589e-7);
    c = fma(c, r2, 2.48015873015873e-5);
    c = fma(c, r2, -1.388888888888889e-3);
    c = fma(c, r2, 4.1666666666666664e-2);
    c = fma(c * r2, r2, fma(-0.5, r2, 1.0));
    let quadrant = i32(q) & 3;
    let sc = select(vec2<f32>(s, c), vec2<f32>(c, -s), (quadrant & 1) != 0);
    return select(sc, -sc, (quadrant & 2) != 0);
}";

const ENERGY_F64: &str = "fn energy(c: Coeffs, y: vec4<f32>) -> f32 {
    let a = sincos(y.x);
    let b = sincos(y.z);
    let cd = a.y * b.y + a.x * b.x;
    let kinetic = 0.5 * c.a * y.y * y.y + 0.5 * c.b * y.w * y.w + c.c * y.y * y.w * cd;
    return kinetic - c.p * a.y - c.q * b.y;
}";

/// ln x in f64: x = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(s) with
/// s = (m - 1) / (m + 1), |s| <= 0.1716, by its series to s^23 (the next term is below
/// 1e-21), plus e ln 2 in two parts (fdlibm's). tests/precision.rs measures it.
const LN_F64: &str = "
fn ln64(x: f32) -> f32 {
    // x = m 2^e with m in [1, 2), by exact powers of two 2^512, 2^256, ... 2^1 (naga's f64
    // frexp returns an i64, which would need SHADER_INT64, and its bitcast of f64 to a pair
    // of u32 is not available). Positive, normal x.
    var m = x;
    var e: f32 = 0.0;
    var power: f32 = 1.3407807929942597e154;
    var k: f32 = 512.0;
    for (var i = 0; i < 10; i++) {
        if m >= power {
            m = m / power;
            e = e + k;
        }
        if m * power < 2.0 {
            m = m * power;
            e = e - k;
        }
        power = sqrt(power);
        k = 0.5 * k;
    }
    if m > 1.4142135623730951 {
        m = 0.5 * m;
        e = e + 1.0;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    var p: f32 = 0.043478260869565216;
    p = fma(p, s2, 0.047619047619047616);
    p = fma(p, s2, 0.05263157894736842);
    p = fma(p, s2, 0.058823529411764705);
    p = fma(p, s2, 0.06666666666666667);
    p = fma(p, s2, 0.07692307692307693);
    p = fma(p, s2, 0.09090909090909091);
    p = fma(p, s2, 0.1111111111111111);
    p = fma(p, s2, 0.14285714285714285);
    p = fma(p, s2, 0.2);
    p = fma(p, s2, 0.3333333333333333);
    let ln_m = 2.0 * s + 2.0 * s * s2 * p;
    return fma(e, 0.6931471803691238, fma(e, 1.9082149292705877e-10, ln_m));
}
";

/// NaN fails every comparison, infinities fail this one.
const IS_FINITE4_F64: &str = "fn is_finite4(v: vec4<f32>) -> bool {
    return all(abs(v) <= vec4<f32>(1.7976931348623157e308));
}";

/// Every kernel's full source, named, for validation.
pub fn all_shaders() -> Vec<(&'static str, String)> {
    vec![
        ("flip_time", shader_source(FLIP_TIME_WGSL)),
        ("flip_time_f64", shader_source_f64(FLIP_TIME_WGSL)),
        ("flip_adaptive", shader_source(&flip_adaptive_wgsl())),
        (
            "flip_adaptive_f64",
            shader_source_f64(&flip_adaptive_wgsl()),
        ),
        ("flip_adaptive_dop853", shader_source(&flip_dop853_wgsl())),
        (
            "flip_adaptive_dop853_f64",
            shader_source_f64(&flip_dop853_wgsl()),
        ),
        ("trajectory_f64", shader_source_f64(TRAJECTORY_WGSL)),
        ("lyapunov_f64", shader_source_f64(&lyapunov_wgsl())),
        ("trajectory", shader_source(TRAJECTORY_WGSL)),
        ("lyapunov", shader_source(&lyapunov_wgsl())),
    ]
}
