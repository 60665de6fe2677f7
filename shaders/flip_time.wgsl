// Flip-time map. Twin of src/cpu/flip_time.rs; driven by src/gpu/flip_time.rs. The step loop
// (`advance`) and the flip's location (`crossing`) serve flip_kind.wgsl too.
// `flip_init` sets up a tile, `flip_time` advances it by `params.steps` steps. With early exit
// the pixels still to integrate are kept as a dense list (active_in -> active_out), so
// finished pixels cost no SIMD lanes in later dispatches.

@group(0) @binding(0) var<uniform> params: Params;
// Per pixel i: states[2 i] = Pendulum.y, states[2 i + 1] = Pendulum.u.
@group(0) @binding(1) var<storage, read_write> states: array<vec4<real>>;
// Flip time (s) per pixel; NEVER until it flips.
@group(0) @binding(2) var<storage, read_write> times: array<real>;
@group(0) @binding(3) var<storage, read> active_in: array<u32>;
@group(0) @binding(4) var<storage, read_write> active_out: array<u32>;
// [0]: length of active_out.
@group(0) @binding(5) var<storage, read_write> counter: array<atomic<u32>>;

// Set per pipeline (src/gpu/flip_time.rs): true stops a pixel when it flips and integrates only
// the listed active pixels. A constant, so the full-run loop has no exit per pixel (14 % faster
// on lavapipe than a branch on a uniform).
override EARLY_EXIT: bool = false;

fn push_active(i: u32) {
    active_out[atomicAdd(&counter[0], 1u)] = i;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let y = grid_start(params, i);
    let p = pendulum_from(y);
    states[2u * i] = p.y;
    states[2u * i + 1u] = p.u;
    times[i] = NEVER;
    if EARLY_EXIT && can_flip(params, i, y) {
        push_active(i);
    }
}

// The first flip among a dispatch's steps: the step k that took an angle past pi, and the
// states before and after it (located after the loop, to keep the loop small).
struct FirstFlip {
    flipped: bool,
    k: u32,
    before: vec4<real>,
    after: vec4<real>,
}

// Advances `p` by this dispatch's steps; `done`: it flipped in an earlier dispatch. With early
// exit the pendulum stops at its flip.
fn advance(c: Coeffs, p: ptr<function, Pendulum>, done: bool) -> FirstFlip {
    let dt = params.dt;
    var f = FirstFlip(false, 0u, vec4<real>(), vec4<real>());
    let k_end = params.step0 + params.steps;
    for (var k = params.step0; k < k_end; k++) {
        let next = rk4_step(c, *p, dt);
        if !f.flipped && !done && max(abs(next.y.x), abs(next.y.z)) > PI {
            f = FirstFlip(true, k, (*p).y, next.y);
            if EARLY_EXIT {
                *p = next;
                break;
            }
        }
        *p = next;
    }
    return f;
}

// Where in its step the flip happens (fraction s of the step), and which arm crossed first
// (1 upper, 2 lower; the upper on a tie), as (s, arm).
fn crossing(f: FirstFlip, dt: real) -> vec2<real> {
    var s: real = 1.0;
    var arm: real = 1.0;
    if abs(f.after.x) > PI {
        s = min(s, hermite_crossing(f.before.x, f.before.y, f.after.x, f.after.y, dt));
    }
    if abs(f.after.z) > PI {
        let s2 = hermite_crossing(f.before.z, f.before.w, f.after.z, f.after.w, dt);
        if abs(f.after.x) <= PI || s2 < s {
            arm = 2.0;
        }
        s = min(s, s2);
    }
    return vec2<real>(s, arm);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_time(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = linear_index(gid, groups);
    if n >= params.count {
        return;
    }
    var i = n;
    if EARLY_EXIT {
        i = active_in[n];
    }
    var p = Pendulum(states[2u * i], states[2u * i + 1u]);
    var t_flip = times[i];
    let f = advance(pixel_coeffs(params, i), &p, t_flip != NEVER);
    if f.flipped {
        t_flip = (real(f.k) + crossing(f, params.dt).x) * params.dt;
    }
    // A state that left the numbers (the step blew up): no flip time, never "never".
    // Checked once a dispatch, outside the loop.
    if t_flip == NEVER && !is_finite4(p.y) {
        t_flip = NONFINITE;
    }
    states[2u * i] = p.y;
    states[2u * i + 1u] = p.u;
    times[i] = t_flip;
    if EARLY_EXIT && t_flip == NEVER {
        push_active(i);
    }
}
