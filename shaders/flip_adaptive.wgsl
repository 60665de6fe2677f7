// Flip-time map with adaptive steps: Dormand-Prince 5(4), every pendulum with its own step
// size. Twin of src/cpu/adaptive.rs (which holds the tableau as data; here the stages are
// unrolled); driven by src/gpu/flip_time.rs. `flip_adaptive_init` sets up a tile,
// `flip_adaptive` gives every active pixel up to `params.steps` more step attempts.

// Mirror of src/gpu/layout.rs `GpuAdaptiveSlot`: a pendulum and its clock.
struct AdaptiveSlot {
    y: vec4<f32>,
    u: vec4<f32>,
    // (t, the next step's size, attempts so far, unused).
    clock: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<AdaptiveSlot>;
// Flip time (s) per pixel; NEVER until it flips, NONFINITE if the run stalled.
@group(0) @binding(2) var<storage, read_write> times: array<f32>;
@group(0) @binding(3) var<storage, read> active_in: array<u32>;
@group(0) @binding(4) var<storage, read_write> active_out: array<u32>;
// [0]: length of active_out.
@group(0) @binding(5) var<storage, read_write> counter: array<atomic<u32>>;

// As in flip_time.wgsl: stop a pixel at its flip, skip starts that cannot flip.
override EARLY_EXIT: bool = false;

// Dormand & Prince (1980): the stages' weights (Hairer, Norsett & Wanner, table 5.2) ...
const A21 = 0.2;
const A31 = 3.0 / 40.0;
const A32 = 9.0 / 40.0;
const A41 = 44.0 / 45.0;
const A42 = -56.0 / 15.0;
const A43 = 32.0 / 9.0;
const A51 = 19372.0 / 6561.0;
const A52 = -25360.0 / 2187.0;
const A53 = 64448.0 / 6561.0;
const A54 = -212.0 / 729.0;
const A61 = 9017.0 / 3168.0;
const A62 = -355.0 / 33.0;
const A63 = 46732.0 / 5247.0;
const A64 = 49.0 / 176.0;
const A65 = -5103.0 / 18656.0;
// ... the fifth-order solution's (its last stage, at that solution, starts the next step) ...
const B1 = 35.0 / 384.0;
const B3 = 500.0 / 1113.0;
const B4 = 125.0 / 192.0;
const B5 = -2187.0 / 6784.0;
const B6 = 11.0 / 84.0;
// ... the error estimate's (fifth minus embedded fourth order) ...
const E1 = 71.0 / 57600.0;
const E3 = -71.0 / 16695.0;
const E4 = 71.0 / 1920.0;
const E5 = -17253.0 / 339200.0;
const E6 = 22.0 / 525.0;
const E7 = -1.0 / 40.0;
// ... and the dense output's (dopri5.f).
const D1 = -12715105075.0 / 11282082432.0;
const D3 = 87487479700.0 / 32700410799.0;
const D4 = -10690763975.0 / 1880347072.0;
const D5 = 701980252875.0 / 199316789632.0;
const D6 = -1453857185.0 / 822651844.0;
const D7 = 69997945.0 / 29380423.0;

// The step-size controller (src/cpu/adaptive.rs SAFETY, SHRINK, GROW).
const SAFETY = 0.9;
const SHRINK = 0.2;
const GROW = 5.0;

fn push_active(i: u32) {
    active_out[atomicAdd(&counter[0], 1u)] = i;
}

// p + h (w1 k1 + w2 k2), and so on: a stage's state.
fn along2(p: Pendulum, h: f32, w1: f32, k1: Rate, w2: f32, k2: Rate) -> Pendulum {
    return Pendulum(p.y + h * (w1 * k1.dy + w2 * k2.dy), p.u + h * (w1 * k1.du + w2 * k2.du));
}

fn along3(p: Pendulum, h: f32, w1: f32, k1: Rate, w2: f32, k2: Rate, w3: f32, k3: Rate) -> Pendulum {
    return Pendulum(
        p.y + h * (w1 * k1.dy + w2 * k2.dy + w3 * k3.dy),
        p.u + h * (w1 * k1.du + w2 * k2.du + w3 * k3.du),
    );
}

fn along4(p: Pendulum, h: f32, w1: f32, k1: Rate, w2: f32, k2: Rate, w3: f32, k3: Rate, w4: f32, k4: Rate) -> Pendulum {
    return Pendulum(
        p.y + h * (w1 * k1.dy + w2 * k2.dy + w3 * k3.dy + w4 * k4.dy),
        p.u + h * (w1 * k1.du + w2 * k2.du + w3 * k3.du + w4 * k4.du),
    );
}

fn along5(p: Pendulum, h: f32, w1: f32, k1: Rate, w2: f32, k2: Rate, w3: f32, k3: Rate, w4: f32, k4: Rate, w5: f32, k5: Rate) -> Pendulum {
    return Pendulum(
        p.y + h * (w1 * k1.dy + w2 * k2.dy + w3 * k3.dy + w4 * k4.dy + w5 * k5.dy),
        p.u + h * (w1 * k1.du + w2 * k2.du + w3 * k3.du + w4 * k4.du + w5 * k5.du),
    );
}

// The dense output of one angle over a step of length h: a0, a1 the angle at its ends, w0,
// w1 the angular velocities (the angle's rate at the first and last stage), d the sum of
// D_i times the angle's rate at stage i; s the fraction of the step.
fn dense_angle(a0: f32, a1: f32, w0: f32, w1: f32, d: f32, h: f32, s: f32) -> f32 {
    let dy = a1 - a0;
    let b = h * w0 - dy;
    let r = dy - h * w1 - b;
    return a0 + s * (dy + (1.0 - s) * (b + s * (r + (1.0 - s) * h * d)));
}

// d/ds of `dense_angle`.
fn dense_slope(a0: f32, a1: f32, w0: f32, w1: f32, d: f32, h: f32, s: f32) -> f32 {
    let dy = a1 - a0;
    let b = h * w0 - dy;
    let r = dy - h * w1 - b;
    return dy + (1.0 - 2.0 * s) * b + s * (2.0 - 3.0 * s) * r + 2.0 * s * (1.0 - s) * (1.0 - 2.0 * s) * h * d;
}

// Whether the angle may pass |angle| = pi inside the step and come back: it turns inside
// (w0 and w1 of opposite signs) and a bound of the dense output's excursion reaches pi
// (|a0 + s dy| <= max |a|, s (1 - s) <= 1/4, s^2 (1 - s) <= 4/27, s^2 (1 - s)^2 <= 1/16).
// Cheap and conservative: `dense_crossing` decides.
fn may_turn_past_pi(a0: f32, a1: f32, w0: f32, w1: f32, d: f32, h: f32) -> bool {
    let dy = a1 - a0;
    let b = h * w0 - dy;
    let r = dy - h * w1 - b;
    let bound = max(abs(a0), abs(a1)) + 0.25 * abs(b) + (4.0 / 27.0) * abs(r) + 0.0625 * abs(h * d);
    return w0 * w1 <= 0.0 && bound > PI;
}

// Fraction of the step at which the dense output of the angle first reaches |angle| = pi,
// or 2 if it does not within the step. Needs |a0| <= pi. If the angle ends the step within
// pi it can only have passed pi at a turning point: bisect the slope for the turn first.
fn dense_crossing(a0: f32, a1: f32, w0: f32, w1: f32, d: f32, h: f32) -> f32 {
    var end: f32 = 1.0;
    var peak = a1;
    if abs(a1) <= PI {
        if !(w0 * w1 <= 0.0) {
            return 2.0;
        }
        let start = sign(w0);
        var lo: f32 = 0.0;
        var hi: f32 = 1.0;
        for (var i = 0; i < 24; i++) {
            let s = 0.5 * (lo + hi);
            if sign(dense_slope(a0, a1, w0, w1, d, h, s)) == start {
                lo = s;
            } else {
                hi = s;
            }
        }
        end = lo;
        peak = dense_angle(a0, a1, w0, w1, d, h, end);
        if abs(peak) <= PI {
            return 2.0;
        }
    }
    let sgn = sign(peak);
    var lo: f32 = 0.0;
    var hi: f32 = end;
    for (var i = 0; i < 24; i++) {
        let s = 0.5 * (lo + hi);
        if sgn * dense_angle(a0, a1, w0, w1, d, h, s) > PI {
            hi = s;
        } else {
            lo = s;
        }
    }
    return hi;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_adaptive_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let y = grid_start(params, i);
    let p = pendulum_from(y);
    states[i] = AdaptiveSlot(p.y, p.u, vec4<f32>(0.0, params.dt, 0.0, 0.0));
    times[i] = NEVER;
    if !EARLY_EXIT || energy(coeffs_from(params), y) >= params.no_flip_energy {
        push_active(i);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_adaptive(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = linear_index(gid, groups);
    if n >= params.count {
        return;
    }
    let i = active_in[n];
    let c = coeffs_from(params);
    let t_max = params.t_max;
    let slot = states[i];
    var p = Pendulum(slot.y, slot.u);
    let clock = slot.clock;
    var t = clock.x;
    var h = clock.y;
    var attempts = clock.z;
    var t_flip = times[i];
    var stalled = false;
    // A step that may have flipped, decided after the loop to keep the loop small.
    var candidate = false;
    var flip_t: f32 = 0.0;
    var flip_h: f32 = 0.0;
    var flip_y0 = vec4<f32>();
    var flip_y1 = vec4<f32>();
    var flip_d = vec2<f32>();
    var k1 = rate(c, p);
    for (var k = 0u; k < params.steps; k++) {
        if t >= t_max || candidate {
            break;
        }
        if attempts >= f32(params.total_steps) {
            stalled = true;
            break;
        }
        attempts += 1.0;
        let last = t + h >= t_max;
        var step = h;
        if last {
            step = t_max - t;
        }
        // The step no longer advances the time (or is not a number): nothing more to say.
        if !(t + step > t) {
            stalled = true;
            break;
        }
        let k2 = rate(c, advanced(p, A21 * step, k1));
        let k3 = rate(c, along2(p, step, A31, k1, A32, k2));
        let k4 = rate(c, along3(p, step, A41, k1, A42, k2, A43, k3));
        let k5 = rate(c, along4(p, step, A51, k1, A52, k2, A53, k3, A54, k4));
        let k6 = rate(c, along5(p, step, A61, k1, A62, k2, A63, k3, A64, k4, A65, k5));
        let next = along5(p, step, B1, k1, B3, k3, B4, k4, B5, k5, B6, k6);
        let k7 = rate(c, next);
        let e = step * (E1 * k1.dy + E3 * k3.dy + E4 * k4.dy + E5 * k5.dy + E6 * k6.dy + E7 * k7.dy);
        let scale = params.atol + params.rtol * max(abs(p.y), abs(next.y));
        let q = e / scale;
        let err = sqrt(0.25 * dot(q, q));
        let factor = clamp(SAFETY / sqrt(sqrt(err)), SHRINK, GROW);
        if err <= 1.0 {
            let d = (D1 * k1.dy + D3 * k3.dy + D4 * k4.dy + D5 * k5.dy + D6 * k6.dy + D7 * k7.dy).xz;
            let a = p.y;
            let b = next.y;
            if t_flip == NEVER && !candidate && (max(abs(b.x), abs(b.z)) > PI
                || may_turn_past_pi(a.x, b.x, a.y, b.y, d.x, step)
                || may_turn_past_pi(a.z, b.z, a.w, b.w, d.y, step)) {
                // Decided after the loop; the pixel's dispatch ends with this step.
                candidate = true;
                flip_t = t;
                flip_h = step;
                flip_y0 = a;
                flip_y1 = b;
                flip_d = d;
            }
            t = select(t + step, t_max, last);
            // Back onto the unit circles, as after an RK4 step.
            let u = next.u;
            let n1 = fma(u.x * u.x + u.y * u.y, -0.5, 1.5);
            let n2 = fma(u.z * u.z + u.w * u.w, -0.5, 1.5);
            p = Pendulum(next.y, u * vec4<f32>(n1, n1, n2, n2));
            k1 = k7;
        }
        h = min(h * factor, params.dt);
    }
    if candidate {
        let s = min(
            dense_crossing(flip_y0.x, flip_y1.x, flip_y0.y, flip_y1.y, flip_d.x, flip_h),
            dense_crossing(flip_y0.z, flip_y1.z, flip_y0.w, flip_y1.w, flip_d.y, flip_h),
        );
        if s <= 1.0 {
            t_flip = flip_t + s * flip_h;
        }
    }
    // A run that stalled before flipping (its state left the numbers, or its step shrank to
    // nothing) has no flip time: say so, never "never".
    if t_flip == NEVER && stalled {
        t_flip = NONFINITE;
    }
    states[i] = AdaptiveSlot(p.y, p.u, vec4<f32>(t, h, attempts, 0.0));
    times[i] = t_flip;
    let running = t < t_max && !stalled;
    if running && (!EARLY_EXIT || t_flip == NEVER) {
        push_active(i);
    }
}
