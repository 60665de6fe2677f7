// Divergence map: the largest finite-time Lyapunov exponent of every pixel. Twin of
// src/cpu/lyapunov.rs; driven by src/gpu/lyapunov.rs. Every pixel integrates the whole run
// (no early exit); `*_init` sets up a tile, `*_advance` runs steps step0+1 ..= step0+steps and
// renormalises after every `interval`-th step and after the last one, adding the log of
// the stretch to `log_sums`. The host divides by t-max.

@group(0) @binding(0) var<uniform> params: Params;
// Per pixel i a LyapunovSlot, as vec4s: states[4 i ..= 4 i + 2] = Tangent.y, .u, .v (twin:
// 4 i ..= 4 i + 3 = y, u, y2, u2).
@group(0) @binding(1) var<storage, read_write> states: array<vec4<real>>;

// Mirror of src/gpu/layout.rs `GpuLyapunovSlot`: the layout of one pixel's states.
struct LyapunovSlot {
    a: Pendulum,
    b: Pendulum,
}
// Sum of the log stretch factors so far.
@group(0) @binding(2) var<storage, read_write> log_sums: array<real>;

// The unit tangent vector every run starts from (src/cpu/lyapunov.rs TANGENT_START).
const TANGENT_START: vec4<real> = vec4<real>(0.5, 0.5, 0.5, 0.5);

// Dual numbers as vec2: .x the value, .y the derivative along the tangent vector. Sums and
// products with plain numbers are the vector operations; these are the rest.
fn dmul(a: vec2<real>, b: vec2<real>) -> vec2<real> {
    return vec2<real>(a.x * b.x, fma(a.x, b.y, a.y * b.x));
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
    let r = inverseSqrt(w.x * w.x + s2);
    return vec2<real>(w.x * r, s2 * r * r * r * w.y);
}

// |(x, y)| of dual components.
fn dlength(x: vec2<real>, y: vec2<real>) -> vec2<real> {
    return dsqrt(dmul(x, x) + dmul(y, y));
}

// `bearing_torques` of common.wgsl in dual numbers.
fn dual_bearing_torques(c: Coeffs, w1: vec2<real>, w2: vec2<real>, c1: vec2<real>, s1: vec2<real>, c2: vec2<real>, s2: vec2<real>, a1: vec2<real>, a2: vec2<real>) -> array<vec2<real>, 2> {
    let w1sq = dmul(w1, w1);
    let w2sq = dmul(w2, w2);
    let arm1x = dmul(a1, c1) - dmul(w1sq, s1);
    let arm1y = dmul(a1, s1) + dmul(w1sq, c1);
    let arm2x = dmul(a2, c2) - dmul(w2sq, s2);
    let arm2y = dmul(a2, s2) + dmul(w2sq, c2);
    let s_1 = c.p / c.g;
    let s_2 = c.q / c.g;
    let low = c.mass_lower * c.l1;
    let pivot = dlength(s_1 * arm1x + s_2 * arm2x, s_1 * arm1y + s_2 * arm2y + dconst(c.mass_total * c.g));
    let joint = dlength(low * arm1x + s_2 * arm2x, low * arm1y + s_2 * arm2y + dconst(c.mass_lower * c.g));
    let t_pivot = c.bearing * dmul(pivot, dsmooth_sign(w1));
    let t_joint = c.bearing * dmul(joint, dsmooth_sign(w2 - w1));
    return array<vec2<real>, 2>(-t_pivot + t_joint, -t_joint);
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
    let f1 = -dmul(dmul(csd, w2), w2) - c.p * s1 + tau1;
    let f2 = dmul(dmul(csd, w1), w1) - c.q * s2 + tau2;
    let ccd = c.c * cd;
    let inv_det = drecip(dconst(c.a * c.b) - dmul(ccd, ccd));
    var a1 = dmul(c.b * f1 - dmul(ccd, f2), inv_det);
    var a2 = dmul(c.a * f2 - dmul(ccd, f1), inv_det);
    if has_bearings() {
        let b = dual_bearing_torques(c, w1, w2, c1, s1, c2, s2, a1, a2);
        a1 += dmul(c.b * b[0] - dmul(ccd, b[1]), inv_det);
        a2 += dmul(c.a * b[1] - dmul(ccd, b[0]), inv_det);
    }
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
    return tangent_on_circles(tangent_ahead(t, dt / 6.0, sum));
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

@compute @workgroup_size(WORKGROUP_SIZE)
fn tangent_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let p = pendulum_from(grid_start(params, i));
    states[4u * i] = p.y;
    states[4u * i + 1u] = p.u;
    states[4u * i + 2u] = TANGENT_START;
    // The adaptive tangent's clock: the next step, attempts so far, stalled.
    states[4u * i + 3u] = vec4<real>(params.dt, 0.0, 0.0, 0.0);
    log_sums[i] = 0.0;
}

// The log sum of a run that stalled (src/gpu/lyapunov.rs STALLED_LOG_SUM): its exponent is NaN.
const STALLED_LOG_SUM: real = -3.0e38;

// The adaptive tangent: DP54 (dp54.wgsl) over the state and the tangent vector, the error
// controlled over both (RMS of error / (atol + rtol |y|) over the eight components). Here
// step0 and steps count renormalisation windows: window k ends at step min(k interval,
// total_steps) of dt, and every pixel lands on it exactly; steps are at most dt.
@compute @workgroup_size(WORKGROUP_SIZE)
fn tangent_adaptive(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    var t = Tangent(states[4u * i], states[4u * i + 1u], states[4u * i + 2u]);
    let clock = states[4u * i + 3u];
    var h = clock.x;
    var attempts = clock.y;
    var stalled = clock.z != 0.0;
    var log_sum = log_sums[i];
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps && !stalled; k++) {
        let first = (k - 1u) * params.interval;
        let window = real(min(k * params.interval, params.total_steps) - first) * params.dt;
        var s: real = 0.0;
        var k1 = tangent_rate(c, t);
        loop {
            if s >= window {
                break;
            }
            // As adaptive_common.wgsl's `attempt`: 2^24 attempts at most, and a step that
            // still advances the time.
            if attempts >= 16777216.0 {
                stalled = true;
                break;
            }
            attempts += 1.0;
            let last = s + h >= window;
            var step = h;
            if last {
                step = window - s;
            }
            if !(s + step > s) {
                stalled = true;
                break;
            }
            let k2 = tangent_rate(c, tangent_ahead(t, A21 * step, k1));
            let k3 = tangent_rate(c, tangent_ahead(tangent_ahead(t, A31 * step, k1), A32 * step, k2));
            let k4 = tangent_rate(c, tangent_ahead(tangent_ahead(tangent_ahead(t, A41 * step, k1), A42 * step, k2), A43 * step, k3));
            let k5 = tangent_rate(c, tangent_ahead(tangent_ahead(tangent_ahead(tangent_ahead(t, A51 * step, k1), A52 * step, k2), A53 * step, k3), A54 * step, k4));
            let k6 = tangent_rate(c, tangent_ahead(tangent_ahead(tangent_ahead(tangent_ahead(tangent_ahead(t, A61 * step, k1), A62 * step, k2), A63 * step, k3), A64 * step, k4), A65 * step, k5));
            let next = tangent_ahead(tangent_ahead(tangent_ahead(tangent_ahead(tangent_ahead(t, B1 * step, k1), B3 * step, k3), B4 * step, k4), B5 * step, k5), B6 * step, k6);
            let k7 = tangent_rate(c, next);
            let ey = step * (E1 * k1.y + E3 * k3.y + E4 * k4.y + E5 * k5.y + E6 * k6.y + E7 * k7.y);
            let ev = step * (E1 * k1.v + E3 * k3.v + E4 * k4.v + E5 * k5.v + E6 * k6.v + E7 * k7.v);
            let qy = ey / (params.atol + params.rtol * max(abs(t.y), abs(next.y)));
            let qv = ev / (params.atol + params.rtol * max(abs(t.v), abs(next.v)));
            let err = sqrt((dot(qy, qy) + dot(qv, qv)) / 8.0);
            let factor = clamp(SAFETY / sqrt(sqrt(err)), SHRINK, GROW);
            if err <= 1.0 {
                s = select(s + step, window, last);
                t = tangent_on_circles(next);
                k1 = k7;
            }
            h = min(h * factor, params.dt);
        }
        if stalled {
            log_sum = STALLED_LOG_SUM;
        } else {
            log_sum += ln_real(unit_tangent(&t));
        }
    }
    states[4u * i] = t.y;
    states[4u * i + 1u] = t.u;
    states[4u * i + 2u] = t.v;
    states[4u * i + 3u] = vec4<real>(h, attempts, real(select(0u, 1u, stalled)), 0.0);
    log_sums[i] = log_sum;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn tangent_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    let dt = params.dt;
    var t = Tangent(states[4u * i], states[4u * i + 1u], states[4u * i + 2u]);
    var log_sum = log_sums[i];
    let k_end = params.step0 + params.steps;
    for (var k = params.step0 + 1u; k <= k_end; k++) {
        t = tangent_step(c, t, dt);
        if renormalise_after(k) {
            log_sum += ln_real(unit_tangent(&t));
        }
    }
    states[4u * i] = t.y;
    states[4u * i + 1u] = t.u;
    states[4u * i + 2u] = t.v;
    log_sums[i] = log_sum;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn twin_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let y = grid_start(params, i);
    let a = pendulum_from(y);
    let b = pendulum_from(y + params.setting * TANGENT_START);
    states[4u * i] = a.y;
    states[4u * i + 1u] = a.u;
    states[4u * i + 2u] = b.y;
    states[4u * i + 3u] = b.u;
    log_sums[i] = 0.0;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn twin_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    let dt = params.dt;
    let eps = params.setting;
    var a = Pendulum(states[4u * i], states[4u * i + 1u]);
    var b = Pendulum(states[4u * i + 2u], states[4u * i + 3u]);
    var log_sum = log_sums[i];
    let k_end = params.step0 + params.steps;
    for (var k = params.step0 + 1u; k <= k_end; k++) {
        a = rk4_step(c, a, dt);
        b = rk4_step(c, b, dt);
        if renormalise_after(k) {
            let d = b.y - a.y;
            // In f32 a separation much below ~1e-6 |y| is round-off: that is why the tangent
            // method is the default. max() keeps a collapsed twin finite.
            let n = max(length(d), 1e-30);
            log_sum += ln_real(n / eps);
            // The twin's cos and sin are a's carried ones rotated by the angle offsets, so
            // the two stay consistent: fresh ones would differ from a's by the carried
            // values' own discretisation error, which an f64 twin 1e-8 away would read.
            let yb = a.y + d * (eps / n);
            let r1 = sincos(yb.x - a.y.x);
            let r2 = sincos(yb.z - a.y.z);
            let ub = vec4<real>(
                a.u.x * r1.y - a.u.y * r1.x,
                a.u.y * r1.y + a.u.x * r1.x,
                a.u.z * r2.y - a.u.w * r2.x,
                a.u.w * r2.y + a.u.z * r2.x,
            );
            b = Pendulum(yb, ub);
        }
    }
    states[4u * i] = a.y;
    states[4u * i + 1u] = a.u;
    states[4u * i + 2u] = b.y;
    states[4u * i + 3u] = b.u;
    log_sums[i] = log_sum;
}

// For the tests: the Jacobian d(rate)/d(theta1, omega1, theta2, omega2) at states[4 i] (read
// as y), written as its columns J e_j to states[4 i + j], from the same dual-number rate.
@compute @workgroup_size(WORKGROUP_SIZE)
fn jacobian_columns(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let p = pendulum_from(states[4u * i]);
    let c = coeffs_from(params);
    for (var j = 0u; j < 4u; j++) {
        var v = vec4<real>();
        v[j] = 1.0;
        states[4u * i + j] = tangent_rate(c, Tangent(p.y, p.u, v)).v;
    }
}
