// chaoscope: the double pendulum, written over the scalar `real` (f32 or f64, declared by
// real_f32.wgsl or real_f64.wgsl with the pieces that differ between them).
//
// State y = (theta1, omega1, theta2, omega2): rad and rad/s, angles from the downward
// vertical. Units SI. With T = A w1^2/2 + B w2^2/2 + C w1 w2 cos D, V = -P cos t1 - Q cos t2
// (src/model.rs; point masses: A = M l1^2, B = m2 l2^2, C = m2 l1 l2, P = M g l1, Q = m2 g l2)
// and loss torques tau, the closed form of the 2x2 Lagrange system is
//   f1 = -C sin D w2^2 - P sin t1 + tau1,   f2 = C sin D w1^2 - Q sin t2 + tau2
//   a1 = (B f1 - C cos D f2) / det,  a2 = (A f2 - C cos D f1) / det,  det = A B - C^2 cos^2 D.
// The CPU reference (src/cpu) solves the mass-matrix system instead, so agreement means something.
//
// Constants WORKGROUP_SIZE, NEVER and NONFINITE are prepended by src/gpu/shaders.rs.

// Mirror of src/gpu/layout.rs `GpuParams`: keep in sync (tests/layout.rs checks offsets).
struct Params {
    // Kinetic and potential energy coefficients (src/model.rs `Inertia`).
    a: real,
    b: real,
    c: real,
    p: real,
    q: real,
    l1: real,
    l2: real,
    dt: real,
    // The plane: the middle and half a pixel of each axis (x_var, y_var say what it varies);
    // for pairs (eps > 0), each range's minimum and width.
    x_mid: real,
    x_half_step: real,
    y_mid: real,
    y_half_step: real,
    // The start where no axis sets it (with theta1, theta2 below).
    omega1: real,
    omega2: real,
    // Starts below this energy (J) can never flip (src/model.rs `no_flip_threshold`).
    no_flip_energy: real,
    // Losses: joint damping (N m s), drag factors 1/2 rho c_w A of bobs and rods (N s^2/m^2).
    joint1: real,
    joint2: real,
    drag_bob1: real,
    drag_bob2: real,
    drag_rod1: real,
    drag_rod2: real,
    // Bearing friction: g, all moving mass, the mass below the middle joint, c_R r.
    g: real,
    mass_total: real,
    mass_lower: real,
    bearing: real,
    theta1: real,
    theta2: real,
    // The bobs' and rods' masses, scaled as a..q: a parameter plane forms its coefficients
    // from them per pixel.
    m1: real,
    m2: real,
    rod1: real,
    rod2: real,
    // Above 0: the pixels are pairs of starts, the second moved by eps of the plane (src/spec/
    // grid.rs `Sampling::Pairs`), drawn from `seed`.
    eps: real,
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
    setting: real,
    // Adaptive steps: relative and absolute tolerance, the run's end time (s).
    rtol: real,
    atol: real,
    t_max: real,
    measure: u32,
    // What the axes vary (src/spec/grid.rs `Var::code`).
    x_var: u32,
    y_var: u32,
    seed: u32,
    // 6, Runge-Kutta's divisor, as data rather than a literal: WGSL lets a compiler multiply
    // by 1/6 for a division by the constant 6 (Chromium's WebGPU does, one ulp off in 8 % of
    // cases), while a division by a value it cannot see stays the correctly rounded one that
    // lavapipe, real GPUs and the CPU compute. So the browser's maps equal the engine's.
    six: real,
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

// Physical constants, read once per invocation.
struct Coeffs {
    a: real,
    b: real,
    c: real,
    p: real,
    q: real,
    l1: real,
    l2: real,
    joint1: real,
    joint2: real,
    drag_bob1: real,
    drag_bob2: real,
    drag_rod1: real,
    drag_rod2: real,
    g: real,
    mass_total: real,
    mass_lower: real,
    bearing: real,
    // Params `six`.
    six: real,
}

fn coeffs_from(p: Params) -> Coeffs {
    return Coeffs(p.a, p.b, p.c, p.p, p.q, p.l1, p.l2, p.joint1, p.joint2, p.drag_bob1,
        p.drag_bob2, p.drag_rod1, p.drag_rod2, p.g, p.mass_total, p.mass_lower, p.bearing, p.six);
}

// src/model.rs BEARING_SMOOTH (rad/s).
const BEARING_SMOOTH: real = 0.01;

// sgn(w) smoothed over BEARING_SMOOTH.
fn smooth_sign(w: real) -> real {
    return w * inverseSqrt(fma(w, w, BEARING_SMOOTH * BEARING_SMOOTH));
}

// `force` plus the bearing friction torques for angular accelerations alpha (src/cpu
// `bearing_torques`): the loads on the pivot and the middle joint from the mass-weighted
// accelerations and gravity. Every product that meets a sum goes through an explicit fma:
// left to themselves, compilers may fuse or factor such sums each their own way (the plain
// form rounded apart in Mesa and in Chromium: measured), and a map of the lab's pendulum
// would depend on the GPU's compiler, not only on its arithmetic.
fn with_bearing_torques(c: Coeffs, w1: real, w2: real, c1: real, s1: real, c2: real, s2: real, alpha: vec2<real>, force: vec2<real>) -> vec2<real> {
    let ww1 = w1 * w1;
    let ww2 = w2 * w2;
    let arm1 = vec2<real>(fma(alpha.x, c1, -ww1 * s1), fma(alpha.x, s1, ww1 * c1));
    let arm2 = vec2<real>(fma(alpha.y, c2, -ww2 * s2), fma(alpha.y, s2, ww2 * c2));
    let s_1 = c.p / c.g;
    let s_2 = c.q / c.g;
    let k = c.mass_lower * c.l1;
    let pv = vec2<real>(fma(s_1, arm1.x, s_2 * arm2.x), fma(s_1, arm1.y, fma(s_2, arm2.y, c.mass_total * c.g)));
    let jv = vec2<real>(fma(k, arm1.x, s_2 * arm2.x), fma(k, arm1.y, fma(s_2, arm2.y, c.mass_lower * c.g)));
    let pivot = c.bearing * sqrt(fma(pv.x, pv.x, pv.y * pv.y));
    let joint = c.bearing * sqrt(fma(jv.x, jv.x, jv.y * jv.y));
    let sign_joint = smooth_sign(w2 - w1);
    // force + (-t_pivot + t_joint, -t_joint), t = load * sgn(relative speed).
    return vec2<real>(fma(joint, sign_joint, fma(-pivot, smooth_sign(w1), force.x)), fma(-joint, sign_joint, force.y));
}

// Speeds are smoothed in the drag law, |v| -> sqrt(v^2 + V_SMOOTH^2) (src/cpu V_SMOOTH).
const V_SMOOTH2: real = 1e-12;

// Generalised forces of the losses (src/cpu/mod.rs `loss_torques`, the same formulas).
fn loss_torques(c: Coeffs, w1: real, w2: real, cd: real) -> vec2<real> {
    let relative = w2 - w1;
    var tau = vec2<real>(-c.joint1 * w1 + c.joint2 * relative, -c.joint2 * relative);
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
fn lower_arm_drag(c: Coeffs, w1: real, w2: real, cd: real, s: real) -> vec2<real> {
    let u_e1 = c.l1 * w1 + s * w2 * cd;
    let u_e2 = c.l1 * w1 * cd + s * w2;
    // |u|^2 >= 0, but f32 rounding takes it below 0 when u ~ 0 (then sqrt gives NaN).
    let u2 = max(c.l1 * c.l1 * w1 * w1 + s * s * w2 * w2 + 2.0 * c.l1 * s * w1 * w2 * cd, 0.0);
    let sp = sqrt(u2 + V_SMOOTH2);
    return vec2<real>(-sp * u_e1 * c.l1, -sp * u_e2 * s);
}

// What the shader integrates: y = (theta1, omega1, theta2, omega2) and, carried along,
// u = (cos theta1, sin theta1, cos theta2, sin theta2) with d/dt (cos, sin) = omega (-sin, cos).
// RK4 on this extended system needs no sin or cos at any stage (they were 60 % of the work);
// u is put back on the unit circles after every step. It is the same ODE, so the result
// differs from RK4 on the angles alone by O(dt^5) per step, far below f32 round-off, and
// the angles themselves are integrated exactly as there (theta' = omega).
struct Pendulum {
    y: vec4<real>,
    u: vec4<real>,
}

struct Rate {
    dy: vec4<real>,
    du: vec4<real>,
}

fn pendulum_from(y: vec4<real>) -> Pendulum {
    let a = sincos(y.x);
    let b = sincos(y.z);
    return Pendulum(y, vec4<real>(a.y, a.x, b.y, b.x));
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
    var tau = vec2<real>();
    if has_losses() {
        tau = loss_torques(c, w1, w2, cd);
    }
    let csd = c.c * sd;
    let f1 = fma(-csd * w2, w2, fma(-c.p, s1, tau.x));
    let f2 = fma(csd * w1, w1, fma(-c.q, s2, tau.y));
    let ccd = c.c * cd;
    let inv_det = 1.0 / fma(-ccd, ccd, c.a * c.b);
    var force = vec2<real>(f1, f2);
    if has_bearings() {
        // As on the CPU: loads from the accelerations without bearing friction, then the
        // friction torques through the same (linear) solve, added to the forces before it
        // (a1 k + b1 k may be factored into (a1 + b1) k by one compiler and not another).
        let free = vec2<real>(fma(c.b, f1, -ccd * f2), fma(c.a, f2, -ccd * f1)) * inv_det;
        force = with_bearing_torques(c, w1, w2, c1, s1, c2, s2, free, force);
    }
    let a1 = fma(c.b, force.x, -ccd * force.y) * inv_det;
    let a2 = fma(c.a, force.y, -ccd * force.x) * inv_det;
    return Rate(vec4<real>(w1, a1, w2, a2), vec4<real>(-w1 * s1, w1 * c1, -w2 * s2, w2 * c2));
}

fn advanced(p: Pendulum, h: real, r: Rate) -> Pendulum {
    return Pendulum(p.y + h * r.dy, p.u + h * r.du);
}

// Classic fourth-order Runge-Kutta, the stages summed as they come (k1 + 2 k2 + 2 k3 + k4 in
// the CPU's order): fewer values stay alive at once, which lavapipe's 16 vector registers feel.
fn rk4_step(c: Coeffs, p: Pendulum, dt: real) -> Pendulum {
    return rk4_step_with(c, p, rate(c, p), dt);
}

// rk4_step with the rate at p, k1, given (a caller that needs it too).
fn rk4_step_with(c: Coeffs, p: Pendulum, k1: Rate, dt: real) -> Pendulum {
    var sum = k1;
    let k2 = rate(c, advanced(p, 0.5 * dt, k1));
    sum = Rate(fma(vec4<real>(2.0), k2.dy, sum.dy), fma(vec4<real>(2.0), k2.du, sum.du));
    let k3 = rate(c, advanced(p, 0.5 * dt, k2));
    sum = Rate(fma(vec4<real>(2.0), k3.dy, sum.dy), fma(vec4<real>(2.0), k3.du, sum.du));
    let k4 = rate(c, advanced(p, dt, k3));
    sum = Rate(sum.dy + k4.dy, sum.du + k4.du);
    let next = advanced(p, dt / c.six, sum);
    let y = next.y;
    let u = next.u;
    // Back onto the unit circles: 1/sqrt(r2) = (3 - r2) / 2 + O((r2 - 1)^2), and a step moves
    // r2 off 1 by O(dt^5), so the first-order form is exact in f32.
    let n1 = fma(u.x * u.x + u.y * u.y, -0.5, 1.5);
    let n2 = fma(u.z * u.z + u.w * u.w, -0.5, 1.5);
    return Pendulum(y, u * vec4<real>(n1, n1, n2, n2));
}

// Fraction of a step of length h at which the cubic Hermite interpolant of the step's end
// states (angle, angular velocity) reaches |angle| = pi. Needs |ta| <= pi < |tb|.
fn hermite_crossing(ta: real, wa: real, tb: real, wb: real, h: real) -> real {
    let sgn = sign(tb);
    var lo: real = 0.0;
    var hi: real = 1.0;
    for (var i = 0; i < BISECTIONS; i++) {
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

// The axes' values (x, y) at pixel i of the tile: pixel centres, row 0 at the top (y at its
// maximum). As src/spec/grid.rs `Axis::at`: the middle plus an odd number of half steps, so
// mirrored pixels of a range centred on 0 get exactly opposite values.
fn pixel_xy(p: Params, i: u32) -> vec2<real> {
    let col = i % p.width;
    let row = p.row0 + i / p.width;
    if p.eps > 0.0 {
        return pair_xy(p, col, row);
    }
    return vec2<real>(
        p.x_mid + real(i32(2u * col + 1u) - i32(p.width)) * p.x_half_step,
        p.y_mid - real(i32(2u * row + 1u) - i32(p.height)) * p.y_half_step,
    );
}

// PCG's output hash (src/spec/grid.rs `pcg`, the same u32 arithmetic).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A number in [0, 1) of 48 random bits (src/spec/grid.rs `unit`; f32 keeps 24 of them).
fn unit(a: u32, b: u32) -> real {
    return real(a >> 8u) * (1.0 / 16777216.0) + real(b >> 8u) * (1.0 / 281474976710656.0);
}

// Pixel (col, row) of a grid of pairs side by side (src/spec/grid.rs `Grid::xy`): a start
// drawn over the plane, or it moved by eps of the plane's width or height, either way, back
// inside if it would leave.
fn pair_xy(p: Params, col: u32, row: u32) -> vec2<real> {
    let h = pcg(p.seed ^ pcg(row * (p.width / 2u) + col / 2u));
    var xy = vec2<real>(p.x_mid + unit(pcg(h ^ 1u), pcg(h ^ 2u)) * p.x_half_step,
        p.y_mid + unit(pcg(h ^ 3u), pcg(h ^ 4u)) * p.y_half_step);
    if col % 2u == 1u {
        let d = pcg(h ^ 5u) & 3u;
        let along_y = d >= 2u;
        let lo = select(p.x_mid, p.y_mid, along_y);
        let width = select(p.x_half_step, p.y_half_step, along_y);
        let step = p.eps * width;
        let v = select(xy.x, xy.y, along_y);
        let down = (d & 1u) == 1u;
        var moved = select(v + step, v - step, down);
        if moved < lo || moved > lo + width {
            moved = select(v - step, v + step, down);
        }
        if along_y {
            xy.y = moved;
        } else {
            xy.x = moved;
        }
    }
    return xy;
}

// Start (theta1, omega1, theta2, omega2) of pixel i: the fixed start with the components the
// axes vary (codes 0..3, the state's order) set.
fn grid_start(p: Params, i: u32) -> vec4<real> {
    let xy = pixel_xy(p, i);
    let lanes = vec4<u32>(0u, 1u, 2u, 3u);
    var s = vec4<real>(p.theta1, p.omega1, p.theta2, p.omega2);
    s = select(s, vec4<real>(xy.x), lanes == vec4<u32>(p.x_var));
    return select(s, vec4<real>(xy.y), lanes == vec4<u32>(p.y_var));
}

// Set per pipeline (src/gpu/pipeline.rs): true when an axis varies a parameter, so each
// pixel forms its own coefficients; false keeps them uniform (the common case costs nothing).
override PER_PIXEL: bool = false;

// The parameters a plane's axis may vary (masses scaled as in Params).
struct Physical {
    m1: real,
    m2: real,
    l1: real,
    l2: real,
    g: real,
    rod1: real,
    rod2: real,
    joint1: real,
    joint2: real,
}

// `r` with parameter `code` (src/spec/grid.rs `Var::code`, 4..15) set to `v`.
fn with_var(r: Physical, code: u32, v: real) -> Physical {
    var o = r;
    switch code {
        case 4u: { o.m1 = v; }
        case 5u: { o.m2 = v; }
        case 6u: { o.m2 = v * o.m1; }
        case 7u: { o.l1 = v; }
        case 8u: { o.l2 = v; }
        case 9u: { o.l2 = v * o.l1; }
        case 10u: { o.g = v; }
        case 11u: { o.joint1 = v; o.joint2 = v; }
        case 12u: { o.joint1 = v; }
        case 13u: { o.joint2 = v; }
        case 14u: { o.rod1 = v; }
        case 15u: { o.rod2 = v; }
        default: {}
    }
    return o;
}

fn is_ratio(code: u32) -> bool {
    return code == 6u || code == 9u;
}

// The coefficients of pixel i: the uniform ones, or (PER_PIXEL) those of its parameters.
fn pixel_coeffs(p: Params, i: u32) -> Coeffs {
    if !PER_PIXEL {
        return coeffs_from(p);
    }
    return plane_coeffs(p, i);
}

// The coefficients of pixel i's own parameters (the plane's axes set in the uniform ones), as
// src/model.rs `Params::inertia` forms them (ratios set after the values they multiply).
fn plane_coeffs(p: Params, i: u32) -> Coeffs {
    let xy = pixel_xy(p, i);
    var r = Physical(p.m1, p.m2, p.l1, p.l2, p.g, p.rod1, p.rod2, p.joint1, p.joint2);
    if is_ratio(p.x_var) {
        r = with_var(with_var(r, p.y_var, xy.y), p.x_var, xy.x);
    } else {
        r = with_var(with_var(r, p.x_var, xy.x), p.y_var, xy.y);
    }
    let outer = r.m2 + 0.5 * r.rod2;
    let lower = r.m2 + r.rod2;
    return Coeffs(
        (r.m1 + lower + r.rod1 / 3.0) * r.l1 * r.l1,
        (r.m2 + r.rod2 / 3.0) * r.l2 * r.l2,
        outer * r.l1 * r.l2,
        (r.m1 + lower + 0.5 * r.rod1) * r.g * r.l1,
        outer * r.g * r.l2,
        r.l1, r.l2, r.joint1, r.joint2,
        p.drag_bob1, p.drag_bob2, p.drag_rod1, p.drag_rod2,
        r.g, r.m1 + r.rod1 + lower, lower, p.bearing, p.six,
    );
}

// Whether start y of pixel i has the energy to flip: at or above src/model.rs
// `no_flip_threshold`, the host's value or (PER_PIXEL) the same formula over the pixel's own
// coefficients, its margin of 100 epsilon covering their rounding here.
fn can_flip(p: Params, i: u32, y: vec4<real>) -> bool {
    let c = pixel_coeffs(p, i);
    var threshold = p.no_flip_energy;
    if PER_PIXEL {
        threshold = -abs(c.p - c.q) - 100.0 * EPSILON * (c.p + c.q);
    }
    return energy(c, y) >= threshold;
}

// Linear invocation index over a 2-D dispatch (more than 65535 workgroups need two dimensions).
fn linear_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP_SIZE;
}
