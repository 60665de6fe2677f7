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

// Its arithmetic: tangent.wgsl.

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
    // The adaptive tangent's clock: the next step, attempts so far (-1: stalled), windows
    // done, the time into the next.
    states[4u * i + 3u] = vec4<real>(params.dt, 0.0, 0.0, 0.0);
    log_sums[i] = 0.0;
}

// The log sum of a run that stalled (src/gpu/lyapunov.rs STALLED_LOG_SUM): its exponent is NaN.
const STALLED_LOG_SUM: real = -3.0e38;

// The adaptive tangent: DP54 (dp54.wgsl) over the state and the tangent vector, the error
// controlled over both (RMS of error / (atol + rtol |y|) over the eight components). Here
// step0 and steps count renormalisation windows: window k ends at step min(k interval,
// total_steps) of dt, and every pixel lands on it exactly; steps are at most dt. A pixel
// takes at most ATTEMPTS_PER_DISPATCH attempts a dispatch (lavapipe ends all of an
// invocation's loops after 65,535 iterations, silently) and keeps its own place: the
// windows it has done and the time into the next (the clock), so a pixel the budget stopped
// mid-window goes on from there in the next dispatch, up to that dispatch's last window
// (the host dispatches the last window again until every pixel is there: `catch_up`).
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
    var stalled = attempts < 0.0;
    var done = u32(clock.z);
    var s = clock.w;
    var budget = ATTEMPTS_PER_DISPATCH;
    var log_sum = log_sums[i];
    loop {
        if stalled || done >= params.step0 + params.steps || budget == 0u {
            break;
        }
        let first = done * params.interval;
        let window = real(min((done + 1u) * params.interval, params.total_steps) - first) * params.dt;
        var k1 = tangent_rate(c, t);
        loop {
            if s >= window || budget == 0u {
                break;
            }
            budget -= 1u;
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
            // The stages (src/gpu/shaders.rs writes them from the tableau):
            //{{DP54_STAGES}}
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
            break;
        }
        if s < window {
            // The budget ran out mid-window.
            break;
        }
        log_sum += ln_real(unit_tangent(&t));
        done += 1u;
        s = 0.0;
    }
    states[4u * i] = t.y;
    states[4u * i + 1u] = t.u;
    states[4u * i + 2u] = t.v;
    states[4u * i + 3u] = vec4<real>(h, select(attempts, -1.0, stalled), real(done), s);
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
