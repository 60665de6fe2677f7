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
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
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
}

fn coeffs_from(p: Params) -> Coeffs {
    return Coeffs(p.m1 + p.m2, p.m2, p.l1, p.l2, p.g);
}

fn derivative(c: Coeffs, y: vec4<f32>) -> vec4<f32> {
    let d = y.x - y.z;
    let sd = sin(d);
    let cd = cos(d);
    let s1 = sin(y.x);
    let s2 = sin(y.z);
    let w1sq = y.y * y.y;
    let w2sq = y.w * y.w;
    let den = c.m - c.m2 * cd * cd;
    let a1 = (-c.m2 * c.l2 * w2sq * sd - c.g * c.m * s1 - c.m2 * c.l1 * w1sq * sd * cd + c.g * c.m2 * s2 * cd) / (c.l1 * den);
    let a2 = (c.m2 * c.l2 * w2sq * sd * cd + c.g * c.m * s1 * cd + c.m * c.l1 * w1sq * sd - c.g * c.m * s2) / (c.l2 * den);
    return vec4<f32>(y.y, a1, y.w, a2);
}

// Classic fourth-order Runge-Kutta.
fn rk4_step(c: Coeffs, y: vec4<f32>, dt: f32) -> vec4<f32> {
    let k1 = derivative(c, y);
    let k2 = derivative(c, y + (0.5 * dt) * k1);
    let k3 = derivative(c, y + (0.5 * dt) * k2);
    let k4 = derivative(c, y + dt * k3);
    return y + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4);
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

// Linear invocation index over a 2-D dispatch (more than 65535 workgroups need two dimensions).
fn linear_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP_SIZE;
}
