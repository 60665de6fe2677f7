// Divergence map: the largest finite-time Lyapunov exponent of every pixel. Twin of
// src/cpu/lyapunov.rs; driven by src/gpu/lyapunov.rs. Every pixel integrates the whole run
// (no early exit); `*_init` sets up a tile, `*_advance` runs steps step0+1 ..= step0+steps and
// renormalises after every `interval`-th step and after the last one, adding the log of
// the stretch to `log_sums`. The host divides by t-max.

@group(0) @binding(0) var<uniform> params: Params;
// Mirror of src/gpu/layout.rs `GpuLyapunovSlot`: one pixel's states.
struct LyapunovSlot {
    // The pendulum (Tangent.y, .u).
    y: vec4<real>,
    u: vec4<real>,
    // Tangent method: the tangent vector; twin method: the twin's y.
    v: vec4<real>,
    // Tangent method: the adaptive tangent's clock (the next step, attempts so far (-1:
    // stalled), windows done, the time into the next); twin method: the twin's u.
    w: vec4<real>,
}
@group(0) @binding(1) var<storage, read_write> states: array<LyapunovSlot>;
// Sum of the log stretch factors so far.
@group(0) @binding(2) var<storage, read_write> log_sums: array<real>;

// Its arithmetic: tangent.wgsl.

@compute @workgroup_size(WORKGROUP_SIZE)
fn tangent_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let p = pendulum_from(grid_start(params, i));
    states[i].y = p.y;
    states[i].u = p.u;
    states[i].v = TANGENT_START;
    // The adaptive tangent's clock: the next step, attempts so far (-1: stalled), windows
    // done, the time into the next.
    states[i].w = vec4<real>(params.dt, 0.0, 0.0, 0.0);
    log_sums[i] = 0.0;
}

// The log sum of a run that stalled (src/gpu/lyapunov.rs STALLED_LOG_SUM): its exponent is NaN.
const STALLED_LOG_SUM: real = -3.0e38;

// The adaptive tangent: DP54 (dp54.wgsl) over the state and the tangent vector, the error
// controlled over both (RMS of error / (atol + rtol |y|) over the eight components), through
// renormalisation windows as shaders/adaptive_windows.wgsl steps them; its clock in the
// slot's last vec4 (`catch_up` on the host dispatches the last window again until every
// pixel is there).
@compute @workgroup_size(WORKGROUP_SIZE)
fn tangent_adaptive(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    var t = Tangent(states[i].y, states[i].u, states[i].v);
    let clock = states[i].w;
    var h = clock.x;
    var attempts = clock.y;
    var stalled = attempts < 0.0;
    var done = u32(clock.z);
    var s = clock.w;
    var log_sum = log_sums[i];
    //{{ADAPTIVE_WINDOWS}} (shaders/adaptive_windows.wgsl), filled by:
    //{{RATE}}
    tangent_rate(c, t)
    //{{ERROR}}
            let ey = step * (E1 * k1.y + E3 * k3.y + E4 * k4.y + E5 * k5.y + E6 * k6.y + E7 * k7.y);
            let ev = step * (E1 * k1.v + E3 * k3.v + E4 * k4.v + E5 * k5.v + E6 * k6.v + E7 * k7.v);
            let qy = ey / (params.atol + params.rtol * max(abs(t.y), abs(next.y)));
            let qv = ev / (params.atol + params.rtol * max(abs(t.v), abs(next.v)));
            let err = sqrt((dot(qy, qy) + dot(qv, qv)) / 8.0);
    //{{ACCEPT}}
                t = tangent_on_circles(next);
    //{{STALLED}}
            log_sum = STALLED_LOG_SUM;
    //{{WINDOW_END}}
        log_sum += ln_real(unit_tangent(&t));
    //{{END}}
    states[i].y = t.y;
    states[i].u = t.u;
    states[i].v = t.v;
    states[i].w = vec4<real>(h, select(attempts, -1.0, stalled), real(done), s);
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
    var t = Tangent(states[i].y, states[i].u, states[i].v);
    var log_sum = log_sums[i];
    let k_end = params.step0 + params.steps;
    for (var k = params.step0 + 1u; k <= k_end; k++) {
        t = tangent_step(c, t, dt);
        if renormalise_after(k) {
            log_sum += ln_real(unit_tangent(&t));
        }
    }
    states[i].y = t.y;
    states[i].u = t.u;
    states[i].v = t.v;
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
    states[i].y = a.y;
    states[i].u = a.u;
    states[i].v = b.y;
    states[i].w = b.u;
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
    var a = Pendulum(states[i].y, states[i].u);
    var b = Pendulum(states[i].v, states[i].w);
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
    states[i].y = a.y;
    states[i].u = a.u;
    states[i].v = b.y;
    states[i].w = b.u;
    log_sums[i] = log_sum;
}

// For the tests: the Jacobian d(rate)/d(theta1, omega1, theta2, omega2) at states[i].y,
// written as its columns J e_j to the slot's four vec4s in order, from the same dual-number
// rate.
@compute @workgroup_size(WORKGROUP_SIZE)
fn jacobian_columns(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let p = pendulum_from(states[i].y);
    let c = coeffs_from(params);
    var columns: array<vec4<real>, 4>;
    for (var j = 0u; j < 4u; j++) {
        var v = vec4<real>();
        v[j] = 1.0;
        columns[j] = tangent_rate(c, Tangent(p.y, p.u, v)).v;
    }
    states[i] = LyapunovSlot(columns[0], columns[1], columns[2], columns[3]);
}
