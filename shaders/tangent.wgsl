// The tangent vector's arithmetic both divergence kernels share: dual numbers, the tangent
// rate and RK4 step, the unit start vector, when to renormalise. No bindings of its own: each
// kernel declares `params` and its per-pixel storage (lyapunov.wgsl, indicators.wgsl).

// The unit tangent vector every run starts from (src/cpu/lyapunov.rs TANGENT_START).
const TANGENT_START: vec4<real> = vec4<real>(0.5, 0.5, 0.5, 0.5);

// Dual numbers as vec2: .x the value, .y the derivative along the tangent vector. Sums and
// products with plain numbers are the vector operations; these are the rest.
fn dmul(a: vec2<real>, b: vec2<real>) -> vec2<real> {
    return vec2<real>(a.x * b.x, fma(a.x, b.y, a.y * b.x));
}

// a b + c, each part rounded once where the plain numbers' fma is.
fn dfma(a: vec2<real>, b: vec2<real>, c: vec2<real>) -> vec2<real> {
    return vec2<real>(fma(a.x, b.x, c.x), fma(a.x, b.y, fma(a.y, b.x, c.y)));
}

fn drecip(a: vec2<real>) -> vec2<real> {
    let r = 1.0 / a.x;
    return vec2<real>(r, -a.y * r * r);
}

fn dconst(x: real) -> vec2<real> {
    return vec2<real>(x, 0.0);
}

fn dsqrt(a: vec2<real>) -> vec2<real> {
    let r = sqrt(a.x);
    return vec2<real>(r, 0.5 * a.y / r);
}

// `loss_torques` of common.wgsl in dual numbers (value, derivative along v) per torque.
fn dual_loss_torques(c: Coeffs, w1: vec2<real>, w2: vec2<real>, cd: vec2<real>) -> array<vec2<real>, 2> {
    let relative = w2 - w1;
    var tau1 = -c.joint1 * w1 + c.joint2 * relative;
    var tau2 = -c.joint2 * relative;
    if !has_drag() {
        return array<vec2<real>, 2>(tau1, tau2);
    }
    let v1 = c.l1 * w1;
    let s1 = dsqrt(dmul(v1, v1) + dconst(V_SMOOTH2));
    tau1 -= (c.drag_bob1 + 0.25 * c.drag_rod1) * c.l1 * dmul(s1, v1);
    var f = dual_lower_arm_drag(c, w1, w2, cd, c.l2);
    tau1 += c.drag_bob2 * f[0];
    tau2 += c.drag_bob2 * f[1];
    if c.drag_rod2 != 0.0 {
        for (var i = 0; i < 3; i++) {
            f = dual_lower_arm_drag(c, w1, w2, cd, GAUSS_X[i] * c.l2);
            tau1 += (c.drag_rod2 * GAUSS_W[i]) * f[0];
            tau2 += (c.drag_rod2 * GAUSS_W[i]) * f[1];
        }
    }
    return array<vec2<real>, 2>(tau1, tau2);
}

// smooth_sign of common.wgsl: w / sqrt(w^2 + s^2), derivative s^2 / (w^2 + s^2)^(3/2).
fn dsmooth_sign(w: vec2<real>) -> vec2<real> {
    let s2 = BEARING_SMOOTH * BEARING_SMOOTH;
    let r = inverseSqrt(fma(w.x, w.x, s2));
    return vec2<real>(w.x * r, s2 * r * r * r * w.y);
}

// |(x, y)| of dual components.
fn dlength(x: vec2<real>, y: vec2<real>) -> vec2<real> {
    return dsqrt(dfma(x, x, dmul(y, y)));
}

// `with_bearing_torques` of common.wgsl in dual numbers: the forces plus the bearing
// friction torques for accelerations (a1, a2), each product that meets a sum an explicit
// fma, as there.
fn dual_with_bearing_torques(c: Coeffs, w1: vec2<real>, w2: vec2<real>, c1: vec2<real>, s1: vec2<real>, c2: vec2<real>, s2: vec2<real>, a1: vec2<real>, a2: vec2<real>, force1: vec2<real>, force2: vec2<real>) -> array<vec2<real>, 2> {
    let w1sq = dmul(w1, w1);
    let w2sq = dmul(w2, w2);
    let arm1x = dfma(a1, c1, -dmul(w1sq, s1));
    let arm1y = dfma(a1, s1, dmul(w1sq, c1));
    let arm2x = dfma(a2, c2, -dmul(w2sq, s2));
    let arm2y = dfma(a2, s2, dmul(w2sq, c2));
    let s_1 = vec2<real>(c.p / c.g);
    let s_2 = vec2<real>(c.q / c.g);
    let low = vec2<real>(c.mass_lower * c.l1);
    let pivot = dlength(fma(s_1, arm1x, s_2 * arm2x), fma(s_1, arm1y, fma(s_2, arm2y, dconst(c.mass_total * c.g))));
    let joint = dlength(fma(low, arm1x, s_2 * arm2x), fma(low, arm1y, fma(s_2, arm2y, dconst(c.mass_lower * c.g))));
    let sign_joint = dsmooth_sign(w2 - w1);
    let t_joint = c.bearing * joint;
    // force + (-t_pivot + t_joint, -t_joint), t = load * sgn(relative speed).
    return array<vec2<real>, 2>(
        dfma(t_joint, sign_joint, dfma(-c.bearing * pivot, dsmooth_sign(w1), force1)),
        dfma(-t_joint, sign_joint, force2),
    );
}

fn dual_lower_arm_drag(c: Coeffs, w1: vec2<real>, w2: vec2<real>, cd: vec2<real>, s: real) -> array<vec2<real>, 2> {
    let u_e1 = c.l1 * w1 + s * dmul(w2, cd);
    let u_e2 = c.l1 * dmul(w1, cd) + s * w2;
    let u2 = c.l1 * c.l1 * dmul(w1, w1) + s * s * dmul(w2, w2) + 2.0 * c.l1 * s * dmul(dmul(w1, w2), cd);
    // As in common.wgsl: keep |u|^2 >= 0 against rounding.
    let sp = dsqrt(select(u2, vec2<real>(0.0), u2.x < 0.0) + dconst(V_SMOOTH2));
    return array<vec2<real>, 2>(-c.l1 * dmul(sp, u_e1), -s * dmul(sp, u_e2));
}

// The state of Pendulum (y, u) and a tangent vector v = (d theta1, d omega1, d theta2,
// d omega2) of the four-dimensional system. The tangents of the carried cos and sin follow
// from v (d cos = -sin d theta, d sin = cos d theta), so they are not integrated.
struct Tangent {
    y: vec4<real>,
    u: vec4<real>,
    v: vec4<real>,
}

// `rate` of common.wgsl evaluated at dual numbers: the value parts are the rate, the
// derivative parts are J v (the variational equations), exact up to round-off.
fn tangent_rate(c: Coeffs, t: Tangent) -> Tangent {
    let w1 = vec2<real>(t.y.y, t.v.y);
    let w2 = vec2<real>(t.y.w, t.v.w);
    let c1 = vec2<real>(t.u.x, -t.u.y * t.v.x);
    let s1 = vec2<real>(t.u.y, t.u.x * t.v.x);
    let c2 = vec2<real>(t.u.z, -t.u.w * t.v.z);
    let s2 = vec2<real>(t.u.w, t.u.z * t.v.z);
    let sd = dmul(s1, c2) - dmul(c1, s2);
    let cd = dmul(c1, c2) + dmul(s1, s2);
    var tau1 = vec2<real>();
    var tau2 = vec2<real>();
    if has_losses() {
        let tau = dual_loss_torques(c, w1, w2, cd);
        tau1 = tau[0];
        tau2 = tau[1];
    }
    let csd = c.c * sd;
    // As in `rate`, each product that meets a sum an explicit fma.
    let f1 = dfma(-dmul(csd, w2), w2, fma(vec2<real>(-c.p), s1, tau1));
    let f2 = dfma(dmul(csd, w1), w1, fma(vec2<real>(-c.q), s2, tau2));
    let ccd = c.c * cd;
    let inv_det = drecip(dconst(c.a * c.b) - dmul(ccd, ccd));
    var force1 = f1;
    var force2 = f2;
    if has_bearings() {
        // As in `rate`: the torques added to the forces before the solve.
        let free1 = dmul(c.b * f1 - dmul(ccd, f2), inv_det);
        let free2 = dmul(c.a * f2 - dmul(ccd, f1), inv_det);
        let f = dual_with_bearing_torques(c, w1, w2, c1, s1, c2, s2, free1, free2, f1, f2);
        force1 = f[0];
        force2 = f[1];
    }
    let a1 = dmul(c.b * force1 - dmul(ccd, force2), inv_det);
    let a2 = dmul(c.a * force2 - dmul(ccd, force1), inv_det);
    return Tangent(
        vec4<real>(w1.x, a1.x, w2.x, a2.x),
        // d/dt (cos, sin) = omega (-sin, cos)
        vec4<real>(-w1.x * s1.x, w1.x * c1.x, -w2.x * s2.x, w2.x * c2.x),
        vec4<real>(w1.y, a1.y, w2.y, a2.y),
    );
}

fn tangent_ahead(t: Tangent, h: real, k: Tangent) -> Tangent {
    return Tangent(t.y + h * k.y, t.u + h * k.u, t.v + h * k.v);
}

// RK4 with the stages summed as they come (k1 + 2 k2 + 2 k3 + k4, in the CPU's order), which
// keeps fewer values alive at once than summing at the end.
fn tangent_step(c: Coeffs, t: Tangent, dt: real) -> Tangent {
    let k1 = tangent_rate(c, t);
    var sum = k1;
    let k2 = tangent_rate(c, tangent_ahead(t, 0.5 * dt, k1));
    sum = tangent_ahead(sum, 2.0, k2);
    let k3 = tangent_rate(c, tangent_ahead(t, 0.5 * dt, k2));
    sum = tangent_ahead(sum, 2.0, k3);
    let k4 = tangent_rate(c, tangent_ahead(t, dt, k3));
    sum = tangent_ahead(sum, 1.0, k4);
    return tangent_on_circles(tangent_ahead(t, dt / c.six, sum));
}

// Back onto the unit circles after a step, as in rk4_step; the tangent vector as it is.
fn tangent_on_circles(next: Tangent) -> Tangent {
    let u = next.u;
    let n1 = fma(u.x * u.x + u.y * u.y, -0.5, 1.5);
    let n2 = fma(u.z * u.z + u.w * u.w, -0.5, 1.5);
    return Tangent(next.y, u * vec4<real>(n1, n1, n2, n2), next.v);
}

// The renormalisation: the tangent vector scaled to unit length; its length before.
fn unit_tangent(t: ptr<function, Tangent>) -> real {
    let n = length((*t).v);
    (*t).v = (*t).v / n;
    return n;
}

// Renormalise after step k (1-based)?
fn renormalise_after(k: u32) -> bool {
    return k % params.interval == 0u || k == params.total_steps;
}
