// chaoscope: the point-mass double pendulum in f32.
//
// State y = (theta1, omega1, theta2, omega2): rad and rad/s, angles from the downward
// vertical. Units SI. With D = theta1 - theta2 and M = m1 + m2 (the lab report's equations):
//   a1 = (-m2 l2 w2^2 sin D - g M sin t1 - m2 l1 w1^2 sin D cos D + g m2 sin t2 cos D) / (l1 (M - m2 cos^2 D))
//   a2 = ( m2 l2 w2^2 sin D cos D + g M sin t1 cos D + M l1 w1^2 sin D - g M sin t2) / (l2 (M - m2 cos^2 D))
// The CPU reference (src/cpu) solves the mass-matrix system instead, so agreement means something.
//
// Constants WORKGROUP_SIZE and NEVER are prepended from src/gpu/layout.rs.

// Mirror of src/gpu/layout.rs `GpuParams`: keep in sync (tests/layout.rs checks offsets).
struct Params {
    m1: f32,
    m2: f32,
    l1: f32,
    l2: f32,
    g: f32,
    dt: f32,
    theta1_min: f32,
    theta1_step: f32,
    theta2_max: f32,
    theta2_step: f32,
    omega1: f32,
    omega2: f32,
    // Starts below this energy (J) can never flip (src/model.rs `no_flip_threshold`).
    no_flip_energy: f32,
    // Tile of the grid: `rows` rows of `width` pixels from grid row `row0`.
    width: u32,
    rows: u32,
    row0: u32,
    // This dispatch integrates steps step0 .. step0 + steps.
    step0: u32,
    steps: u32,
    // 1: stop a pixel when it flips and integrate only the listed active pixels.
    early_exit: u32,
    // Number of invocations with work in this dispatch.
    count: u32,
    // Divergence maps: steps between renormalisations, steps of the whole run, twin separation.
    renorm_steps: u32,
    total_steps: u32,
    twin_eps: f32,
    _pad0: u32,
}

// f32(pi) rounds up to 3.1415927, so |theta| > PI is the f32 form of |theta| > pi.
const PI: f32 = 3.14159265358979;

// Physical constants folded once per invocation rather than per stage.
struct Coeffs {
    m: f32,      // M = m1 + m2
    m2: f32,
    l1: f32,
    l2: f32,
    g: f32,
    inv_l1: f32,
    inv_l2: f32,
}

fn coeffs_from(p: Params) -> Coeffs {
    return Coeffs(p.m1 + p.m2, p.m2, p.l1, p.l2, p.g, 1.0 / p.l1, 1.0 / p.l2);
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
    let w1sq = w1 * w1;
    let w2sq = w2 * w2;
    let inv_den = 1.0 / (c.m - c.m2 * cd * cd);
    let a1 = (-c.m2 * c.l2 * w2sq * sd - c.g * c.m * s1 - c.m2 * c.l1 * w1sq * sd * cd + c.g * c.m2 * s2 * cd) * (c.inv_l1 * inv_den);
    let a2 = (c.m2 * c.l2 * w2sq * sd * cd + c.g * c.m * s1 * cd + c.m * c.l1 * w1sq * sd - c.g * c.m * s2) * (c.inv_l2 * inv_den);
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
    let kinetic = 0.5 * c.m * c.l1 * c.l1 * y.y * y.y + 0.5 * c.m2 * c.l2 * c.l2 * y.w * y.w
        + c.m2 * c.l1 * c.l2 * y.y * y.w * cos(y.x - y.z);
    return kinetic - c.m * c.g * c.l1 * cos(y.x) - c.m2 * c.g * c.l2 * cos(y.z);
}

// Fraction of a step of length h at which the cubic Hermite interpolant of the step's end
// states (angle, angular velocity) reaches |angle| = pi. Needs |ta| <= pi < |tb|.
fn hermite_crossing(ta: f32, wa: f32, tb: f32, wb: f32, h: f32) -> f32 {
    let sgn = sign(tb);
    var lo = 0.0;
    var hi = 1.0;
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
// top (theta2 at its maximum).
fn grid_start(p: Params, i: u32) -> vec4<f32> {
    let col = i % p.width;
    let row = p.row0 + i / p.width;
    return vec4<f32>(
        p.theta1_min + (f32(col) + 0.5) * p.theta1_step,
        p.omega1,
        p.theta2_max - (f32(row) + 0.5) * p.theta2_step,
        p.omega2,
    );
}

// Linear invocation index over a 2-D dispatch (more than 65535 workgroups need two dimensions).
fn linear_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP_SIZE;
}
