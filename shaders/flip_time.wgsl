// Flip-time map. Twin of src/cpu/flip_time.rs; driven by src/gpu/flip_time.rs.
// `flip_init` sets up a tile, `flip_time` advances it by `params.steps` steps. With early exit
// the pixels still to integrate are kept as a dense list (active_in -> active_out), so
// finished pixels cost no SIMD lanes in later dispatches.

@group(0) @binding(0) var<uniform> params: Params;
// Per pixel i: states[2 i] = Pendulum.y, states[2 i + 1] = Pendulum.u.
@group(0) @binding(1) var<storage, read_write> states: array<vec4<f32>>;
// Flip time (s) per pixel; NEVER until it flips.
@group(0) @binding(2) var<storage, read_write> times: array<f32>;
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
    if EARLY_EXIT && energy(coeffs_from(params), y) >= params.no_flip_energy {
        push_active(i);
    }
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
    let c = coeffs_from(params);
    let dt = params.dt;
    var p = Pendulum(states[2u * i], states[2u * i + 1u]);
    var t_flip = times[i];
    // The step that flipped, located after the loop to keep the loop small.
    var flipped = false;
    var k_flip = 0u;
    var before = vec4<f32>();
    var after = vec4<f32>();
    let k_end = params.step0 + params.steps;
    for (var k = params.step0; k < k_end; k++) {
        let next = rk4_step(c, p, dt);
        if !flipped && t_flip == NEVER && max(abs(next.y.x), abs(next.y.z)) > PI {
            flipped = true;
            k_flip = k;
            before = p.y;
            after = next.y;
            if EARLY_EXIT {
                p = next;
                break;
            }
        }
        p = next;
    }
    if flipped {
        var s: f32 = 1.0;
        if abs(after.x) > PI {
            s = min(s, hermite_crossing(before.x, before.y, after.x, after.y, dt));
        }
        if abs(after.z) > PI {
            s = min(s, hermite_crossing(before.z, before.w, after.z, after.w, dt));
        }
        t_flip = (f32(k_flip) + s) * dt;
    }
    // A state that left the numbers (the step blew up) has no flip time: say so, never
    // "never". Checked once a dispatch, outside the loop.
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
