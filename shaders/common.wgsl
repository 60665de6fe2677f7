// chaoscope: the double pendulum in f32.
//
// State y = (theta1, omega1, theta2, omega2): rad and rad/s, angles from the downward
// vertical. Units SI. With T = A w1^2/2 + B w2^2/2 + C w1 w2 cos D, V = -P cos t1 - Q cos t2
// (src/model.rs; point masses: A = M l1^2, B = m2 l2^2, C = m2 l1 l2, P = M g l1, Q = m2 g l2)
// and loss torques tau, the closed form of the 2x2 Lagrange system is
//   f1 = -C sin D w2^2 - P sin t1 + tau1,   f2 = C sin D w1^2 - Q sin t2 + tau2
//   a1 = (B f1 - C cos D f2) / det,  a2 = (A f2 - C cos D f1) / det,  det = A B - C^2 cos^2 D.
// The CPU reference (src/cpu) solves the mass-matrix system instead, so agreement means something.
//
// Constants WORKGROUP_SIZE, NEVER and NONFINITE are prepended from src/gpu/layout.rs.

// Mirror of src/gpu/layout.rs `GpuParams`: keep in sync (tests/layout.rs checks offsets).
struct Params {
    // Kinetic and potential energy coefficients (src/model.rs `Inertia`).
    a: f32,
    b: f32,
    c: f32,
    p: f32,
    q: f32,
    l1: f32,
    l2: f32,
    dt: f32,
    theta1_mid: f32,
    theta1_half_step: f32,
    theta2_mid: f32,
    theta2_half_step: f32,
    omega1: f32,
    omega2: f32,
    // Starts below this energy (J) can never flip (src/model.rs `no_flip_threshold`).
    no_flip_energy: f32,
    // Losses: joint damping (N m s), drag factors 1/2 rho c_w A of bobs and rods (N s^2/m^2).
    joint1: f32,
    joint2: f32,
    drag_bob1: f32,
    drag_bob2: f32,
    drag_rod1: f32,
    drag_rod2: f32,
    // Bearing friction: g, all moving mass, the mass below the middle joint, c_R r.
    g: f32,
    mass_total: f32,
    mass_lower: f32,
    bearing: f32,
    // Grid size, and the tile: `rows` rows of `width` pixels from grid row `row0`.
    width: u32,
    height: u32,
    rows: u32,
    row0: u32,
    // This dispatch integrates steps step0 .. step0 + steps.
    step0: u32,
    steps: u32,
    // Number of invocations with work in this dispatch.
    count: u32,
    // Steps between renormalisations (divergence maps) or stored states (trajectories), steps
    // of the whole run, twin separation.
    interval: u32,
    total_steps: u32,
    twin_eps: f32,
    // Adaptive steps: relative and absolute tolerance, the run's end time (s).
    rtol: f32,
    atol: f32,
    t_max: f32,
    _pad0: u32,
    _pad1: u32,
}

// Set per pipeline (src/gpu/pipeline.rs, src/model.rs `Losses::kinds`): each kind of loss is
// compiled in only when needed. Bits: 1 joint damping, 2 air drag, 4 bearing friction.
override LOSSES: u32 = 0u;
fn has_losses() -> bool {
    return LOSSES != 0u;
}

fn has_drag() -> bool {
    return (LOSSES & 2u) != 0u;
}

fn has_bearings() -> bool {
    return (LOSSES & 4u) != 0u;
}

// Whether no component is infinite or NaN (by the exponent bits: `x != x` may be folded).
fn is_finite4(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

// f32(pi) rounds up to 3.1415927, so |theta| > PI is the f32 form of |theta| > pi.
const PI: f32 = 3.14159265358979;

// Physical constants, read once per invocation.
struct Coeffs {
    a: f32,
    b: f32,
    c: f32,
    p: f32,
    q: f32,
    l1: f32,
    l2: f32,
    joint1: f32,
    joint2: f32,
    drag_bob1: f32,
    drag_bob2: f32,
    drag_rod1: f32,
    drag_rod2: f32,
    g: f32,
    mass_total: f32,
    mass_lower: f32,
    bearing: f32,
}

fn coeffs_from(p: Params) -> Coeffs {
    return Coeffs(p.a, p.b, p.c, p.p, p.q, p.l1, p.l2, p.joint1, p.joint2, p.drag_bob1,
        p.drag_bob2, p.drag_rod1, p.drag_rod2, p.g, p.mass_total, p.mass_lower, p.bearing);
}

// src/model.rs BEARING_SMOOTH (rad/s).
const BEARING_SMOOTH: f32 = 0.01;

// sgn(w) smoothed over BEARING_SMOOTH.
fn smooth_sign(w: f32) -> f32 {
    return w * inverseSqrt(w * w + BEARING_SMOOTH * BEARING_SMOOTH);
}

// Bearing friction torques for angular accelerations alpha (src/cpu `bearing_torques`): the
// loads on the pivot and the middle joint from the mass-weighted accelerations and gravity.
fn bearing_torques(c: Coeffs, w1: f32, w2: f32, c1: f32, s1: f32, c2: f32, s2: f32, alpha: vec2<f32>) -> vec2<f32> {
    let arm1 = vec2<f32>(alpha.x * c1 - w1 * w1 * s1, alpha.x * s1 + w1 * w1 * c1);
    let arm2 = vec2<f32>(alpha.y * c2 - w2 * w2 * s2, alpha.y * s2 + w2 * w2 * c2);
    let s_1 = c.p / c.g;
    let s_2 = c.q / c.g;
    let pivot = length(s_1 * arm1 + s_2 * arm2 + vec2<f32>(0.0, c.mass_total * c.g));
    let joint = length(c.mass_lower * c.l1 * arm1 + s_2 * arm2 + vec2<f32>(0.0, c.mass_lower * c.g));
    let t_pivot = c.bearing * pivot * smooth_sign(w1);
    let t_joint = c.bearing * joint * smooth_sign(w2 - w1);
    return vec2<f32>(-t_pivot + t_joint, -t_joint);
}

// Speeds are smoothed in the drag law, |v| -> sqrt(v^2 + V_SMOOTH^2) (src/cpu V_SMOOTH).
const V_SMOOTH2: f32 = 1e-12;

// 3-point Gauss-Legendre on [0, 1] for the drag along the lower rod.
const GAUSS_X: vec3<f32> = vec3<f32>(0.1127016654, 0.5, 0.8872983346);
const GAUSS_W: vec3<f32> = vec3<f32>(0.2777777778, 0.4444444444, 0.2777777778);

// Generalised forces of the losses (src/cpu/mod.rs `loss_torques`, the same formulas).
fn loss_torques(c: Coeffs, w1: f32, w2: f32, cd: f32) -> vec2<f32> {
    let relative = w2 - w1;
    var tau = vec2<f32>(-c.joint1 * w1 + c.joint2 * relative, -c.joint2 * relative);
    if !has_drag() {
        return tau;
    }
    let v1 = c.l1 * w1;
    let s1 = sqrt(v1 * v1 + V_SMOOTH2);
    tau.x -= (c.drag_bob1 + 0.25 * c.drag_rod1) * s1 * v1 * c.l1;
    tau += c.drag_bob2 * lower_arm_drag(c, w1, w2, cd, c.l2);
    if c.drag_rod2 != 0.0 {
        for (var i = 0; i < 3; i++) {
            tau += (c.drag_rod2 * GAUSS_W[i]) * lower_arm_drag(c, w1, w2, cd, GAUSS_X[i] * c.l2);
        }
    }
    return tau;
}

// Generalised force per unit drag factor of a point at distance s along the lower arm.
fn lower_arm_drag(c: Coeffs, w1: f32, w2: f32, cd: f32, s: f32) -> vec2<f32> {
    let u_e1 = c.l1 * w1 + s * w2 * cd;
    let u_e2 = c.l1 * w1 * cd + s * w2;
    // |u|^2 >= 0, but f32 rounding takes it below 0 when u ~ 0 (then sqrt gives NaN).
    let u2 = max(c.l1 * c.l1 * w1 * w1 + s * s * w2 * w2 + 2.0 * c.l1 * s * w1 * w2 * cd, 0.0);
    let sp = sqrt(u2 + V_SMOOTH2);
    return vec2<f32>(-sp * u_e1 * c.l1, -sp * u_e2 * s);
}

// (sin x, cos x) with one shared range reduction: x = q pi/2 + r by Cody-Waite with fma (two
// parts of pi/2), then Cephes' minimax polynomials on |r| <= pi/4, then the quadrant q mod 4.
// About 2 ulp for |x| < 1e4 rad. Twice as fast on lavapipe as the built-in sin and cos, which
// reduce their argument separately.
fn sincos(x: f32) -> vec2<f32> {
    let q = round(x * 0.63661975);
    let r = fma(q, 4.371139e-8, fma(-q, 1.5707964, x));
    let r2 = r * r;
    let s = fma(r * r2, fma(r2, fma(r2, -1.9515296e-4, 8.332161e-3), -1.6666655e-1), r);
    let c = fma(r2 * r2, fma(r2, fma(r2, 2.4433157e-5, -1.3887316e-3), 4.1666646e-2), fma(-0.5, r2, 1.0));
    let quadrant = i32(q) & 3;
    let sc = select(vec2<f32>(s, c), vec2<f32>(c, -s), (quadrant & 1) != 0);
    return select(sc, -sc, (quadrant & 2) != 0);
}

// What the shader integrates: y = (theta1, omega1, theta2, omega2) and, carried along,
// u = (cos theta1, sin theta1, cos theta2, sin theta2) with d/dt (cos, sin) = omega (-sin, cos).
// RK4 on this extended system needs no sin or cos at any stage (they were 60 % of the work);
// u is put back on the unit circles after every step. It is the same ODE, so the result
// differs from RK4 on the angles alone by O(dt^5) per step, far below f32 round-off, and
// the angles themselves are integrated exactly as there (theta' = omega).
struct Pendulum {
    y: vec4<f32>,
    u: vec4<f32>,
}

struct Rate {
    dy: vec4<f32>,
    du: vec4<f32>,
}

fn pendulum_from(y: vec4<f32>) -> Pendulum {
    let a = sincos(y.x);
    let b = sincos(y.z);
    return Pendulum(y, vec4<f32>(a.y, a.x, b.y, b.x));
}

fn rate(c: Coeffs, p: Pendulum) -> Rate {
    let w1 = p.y.y;
    let w2 = p.y.w;
    let c1 = p.u.x;
    let s1 = p.u.y;
    let c2 = p.u.z;
    let s2 = p.u.w;
    // sin D and cos D from the angle-difference identities.
    let sd = s1 * c2 - c1 * s2;
    let cd = c1 * c2 + s1 * s2;
    var tau = vec2<f32>();
    if has_losses() {
        tau = loss_torques(c, w1, w2, cd);
    }
    let csd = c.c * sd;
    let f1 = fma(-csd * w2, w2, fma(-c.p, s1, tau.x));
    let f2 = fma(csd * w1, w1, fma(-c.q, s2, tau.y));
    let ccd = c.c * cd;
    let inv_det = 1.0 / fma(-ccd, ccd, c.a * c.b);
    var a1 = fma(c.b, f1, -ccd * f2) * inv_det;
    var a2 = fma(c.a, f2, -ccd * f1) * inv_det;
    if has_bearings() {
        // As on the CPU: loads from the accelerations without bearing friction, then the
        // friction torques added through the same (linear) solve.
        let b = bearing_torques(c, w1, w2, c1, s1, c2, s2, vec2<f32>(a1, a2));
        a1 += fma(c.b, b.x, -ccd * b.y) * inv_det;
        a2 += fma(c.a, b.y, -ccd * b.x) * inv_det;
    }
    return Rate(vec4<f32>(w1, a1, w2, a2), vec4<f32>(-w1 * s1, w1 * c1, -w2 * s2, w2 * c2));
}

fn advanced(p: Pendulum, h: f32, r: Rate) -> Pendulum {
    return Pendulum(p.y + h * r.dy, p.u + h * r.du);
}

// Classic fourth-order Runge-Kutta, the stages summed as they come (k1 + 2 k2 + 2 k3 + k4 in
// the CPU's order): fewer values stay alive at once, which lavapipe's 16 vector registers feel.
fn rk4_step(c: Coeffs, p: Pendulum, dt: f32) -> Pendulum {
    let k1 = rate(c, p);
    var sum = k1;
    let k2 = rate(c, advanced(p, 0.5 * dt, k1));
    sum = Rate(fma(vec4<f32>(2.0), k2.dy, sum.dy), fma(vec4<f32>(2.0), k2.du, sum.du));
    let k3 = rate(c, advanced(p, 0.5 * dt, k2));
    sum = Rate(fma(vec4<f32>(2.0), k3.dy, sum.dy), fma(vec4<f32>(2.0), k3.du, sum.du));
    let k4 = rate(c, advanced(p, dt, k3));
    sum = Rate(sum.dy + k4.dy, sum.du + k4.du);
    let next = advanced(p, dt / 6.0, sum);
    let y = next.y;
    let u = next.u;
    // Back onto the unit circles: 1/sqrt(r2) = (3 - r2) / 2 + O((r2 - 1)^2), and a step moves
    // r2 off 1 by O(dt^5), so the first-order form is exact in f32.
    let n1 = fma(u.x * u.x + u.y * u.y, -0.5, 1.5);
    let n2 = fma(u.z * u.z + u.w * u.w, -0.5, 1.5);
    return Pendulum(y, u * vec4<f32>(n1, n1, n2, n2));
}

fn energy(c: Coeffs, y: vec4<f32>) -> f32 {
    let kinetic = 0.5 * c.a * y.y * y.y + 0.5 * c.b * y.w * y.w + c.c * y.y * y.w * cos(y.x - y.z);
    return kinetic - c.p * cos(y.x) - c.q * cos(y.z);
}

// Fraction of a step of length h at which the cubic Hermite interpolant of the step's end
// states (angle, angular velocity) reaches |angle| = pi. Needs |ta| <= pi < |tb|.
fn hermite_crossing(ta: f32, wa: f32, tb: f32, wb: f32, h: f32) -> f32 {
    let sgn = sign(tb);
    var lo: f32 = 0.0;
    var hi: f32 = 1.0;
    for (var i = 0; i < 24; i++) {
        let s = 0.5 * (lo + hi);
        let s2 = s * s;
        let s3 = s2 * s;
        let v = (2.0 * s3 - 3.0 * s2 + 1.0) * ta + (s3 - 2.0 * s2 + s) * h * wa
            + (-2.0 * s3 + 3.0 * s2) * tb + (s3 - s2) * h * wb;
        if sgn * v > PI {
            hi = s;
        } else {
            lo = s;
        }
    }
    return hi;
}

// Start (theta1, omega1, theta2, omega2) of pixel i of the tile: pixel centres, row 0 at the
// top (theta2 at its maximum). As src/spec.rs `Grid::theta1_at`: the middle plus an odd number
// of half steps, so mirrored pixels of a range centred on 0 get exactly opposite angles.
fn grid_start(p: Params, i: u32) -> vec4<f32> {
    let col = i % p.width;
    let row = p.row0 + i / p.width;
    return vec4<f32>(
        p.theta1_mid + f32(i32(2u * col + 1u) - i32(p.width)) * p.theta1_half_step,
        p.omega1,
        p.theta2_mid - f32(i32(2u * row + 1u) - i32(p.height)) * p.theta2_half_step,
        p.omega2,
    );
}

// Linear invocation index over a 2-D dispatch (more than 65535 workgroups need two dimensions).
fn linear_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP_SIZE;
}
