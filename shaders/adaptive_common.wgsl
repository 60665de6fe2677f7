// What every adaptive flip kernel shares (shaders/flip_adaptive.wgsl: DP54;
// shaders/flip_dop853.wgsl: DOP853): the per-pixel slot and the bindings, the tile's set-up,
// and the location of the flip on a step's dense output. The method's file defines `Dense`
// (one angle's dense output over a step), `dense_value` and `dense_slope` (in the step's
// fraction s), and the `flip_adaptive` entry point. Driven by src/gpu/flip_time.rs.

// Mirror of src/gpu/layout.rs `GpuAdaptiveSlot`: a pendulum and its clock.
struct AdaptiveSlot {
    y: vec4<real>,
    u: vec4<real>,
    // (t, the next step's size, attempts so far, unused).
    clock: vec4<real>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<AdaptiveSlot>;
// Flip time (s) per pixel; NEVER until it flips, NONFINITE if the run stalled.
@group(0) @binding(2) var<storage, read_write> times: array<real>;
@group(0) @binding(3) var<storage, read> active_in: array<u32>;
@group(0) @binding(4) var<storage, read_write> active_out: array<u32>;
// [0]: length of active_out.
@group(0) @binding(5) var<storage, read_write> counter: array<atomic<u32>>;

// As in flip_time.wgsl: stop a pixel at its flip, skip starts that cannot flip.
override EARLY_EXIT: bool = false;

fn push_active(i: u32) {
    active_out[atomicAdd(&counter[0], 1u)] = i;
}

// One more step attempt from t with the proposed step h, counted in `attempts`: the step
// (shortened to land on t-max, `last` then), or stalled: too many attempts, or a step that no
// longer advances the time (or is not a number), so the run has nothing more to say.
struct Attempt {
    step: real,
    last: bool,
    stalled: bool,
}

fn attempt(t: real, h: real, attempts: ptr<function, real>) -> Attempt {
    if *attempts >= real(params.total_steps) {
        return Attempt(0.0, false, true);
    }
    *attempts += 1.0;
    let last = t + h >= params.t_max;
    var step = h;
    if last {
        step = params.t_max - t;
    }
    return Attempt(step, last, !(t + step > t));
}

// Back onto the unit circles after a step, as after an RK4 step.
fn on_circles(next: Pendulum) -> Pendulum {
    let u = next.u;
    let n1 = fma(u.x * u.x + u.y * u.y, -0.5, 1.5);
    let n2 = fma(u.z * u.z + u.w * u.w, -0.5, 1.5);
    return Pendulum(next.y, u * vec4<real>(n1, n1, n2, n2));
}

// Whether an angle from a0 to a1 over a step h, with rates w0 and w1 at its ends, may reach
// |angle| = pi within the step: beyond its ends by at most h (|w0| + |w1|) (the CPU twins'
// `may_reach_pi`); the method's bound of its dense output decides after.
fn may_reach_pi(a0: real, a1: real, w0: real, w1: real, h: real) -> bool {
    return max(abs(a0), abs(a1)) + h * (abs(w0) + abs(w1)) > PI;
}

// Fraction of the step at which the dense output `q` of an angle first reaches |angle| = pi,
// or 2 if it does not within the step; needs the angle within pi at the start. An angle can
// pass pi and come back at a turning point inside the step (a long step may hold two): the
// step is searched in 8 pieces in order (src/cpu/adaptive.rs PIECES), each for a crossing at
// its end or a turn beyond pi inside, found by bisecting the slope, then the angle.
fn dense_crossing(q: Dense) -> real {
    for (var k = 0; k < 8; k++) {
        let lo = real(k) / 8.0;
        let hi = real(k + 1) / 8.0;
        var top = hi;
        var peak = dense_value(q, hi);
        if abs(peak) <= PI {
            let rising = sign(dense_slope(q, lo));
            if sign(dense_slope(q, hi)) == rising {
                continue;
            }
            var a = lo;
            var b = hi;
            for (var i = 0; i < BISECTIONS; i++) {
                let s = 0.5 * (a + b);
                if sign(dense_slope(q, s)) == rising {
                    a = s;
                } else {
                    b = s;
                }
            }
            top = a;
            peak = dense_value(q, top);
            if abs(peak) <= PI {
                continue;
            }
        }
        let sgn = sign(peak);
        var a = lo;
        var b = top;
        for (var i = 0; i < BISECTIONS; i++) {
            let s = 0.5 * (a + b);
            if sgn * dense_value(q, s) > PI {
                b = s;
            } else {
                a = s;
            }
        }
        return b;
    }
    return 2.0;
}

// A step that may have flipped, decided after the step loop to keep the loop small: where
// it starts, its length, and the dense outputs of theta1 and theta2 over it.
struct Candidate {
    found: bool,
    t: real,
    h: real,
    q1: Dense,
    q2: Dense,
}

// The end of a pixel's dispatch: the candidate step decided on its dense output, a stall
// reported, the slot and time written, the pixel listed again while it runs.
fn settle(i: u32, p: Pendulum, clock: vec3<real>, time: real, stalled: bool, flip: Candidate) {
    let t = clock.x;
    let t_max = params.t_max;
    var t_flip = time;
    if flip.found {
        let s = min(dense_crossing(flip.q1), dense_crossing(flip.q2));
        if s <= 1.0 {
            t_flip = flip.t + s * flip.h;
        }
    }
    // A run that stalled before flipping (its state left the numbers, or its step shrank to
    // nothing) has no flip time: say so, never "never".
    if t_flip == NEVER && stalled {
        t_flip = NONFINITE;
    }
    states[i] = AdaptiveSlot(p.y, p.u, vec4<real>(clock, 0.0));
    times[i] = t_flip;
    let running = t < t_max && !stalled;
    if running && (!EARLY_EXIT || t_flip == NEVER) {
        push_active(i);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_adaptive_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let y = grid_start(params, i);
    let p = pendulum_from(y);
    states[i] = AdaptiveSlot(p.y, p.u, vec4<real>(0.0, params.dt, 0.0, 0.0));
    times[i] = NEVER;
    if !EARLY_EXIT || can_flip(params, i, y) {
        push_active(i);
    }
}

