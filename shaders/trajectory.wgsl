// Trajectories of `params.count` pendulums, one per invocation, keeping every
// `params.interval`-th state: with n = total_steps / interval + 1 states a run, states[i n]
// is the start of pendulum i and states[i n + k] its state after k * interval steps.
// Twin of src/cpu/mod.rs `trajectory`; used to compare the two paths step by step and for
// ensembles (traces, phase portraits, fitting tracked data).
// With PER_PIXEL on, a run is a "pixel" with its own joint damping (N m s) at the pivot and
// the middle joint, damping[i]: a fit's candidates.
// A dispatch takes steps step0 + 1 .. step0 + steps of params.total_steps, from and back to
// carried[i] (the state with its cos and sin): lavapipe ends every loop of an invocation
// after 65535 iterations in all, so the host keeps a dispatch's steps below that.

// On for the explorer's click on a parameter plane: run i is pixel i of the params' plane
// (its grid of one pixel at the click), its coefficients that pixel's parameters, as the
// map's kernels form them.
override PLANE_RUN: bool = false;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<vec4<real>>;
@group(0) @binding(2) var<storage, read> damping: array<vec2<real>>;
@group(0) @binding(3) var<storage, read_write> carried: array<Pendulum>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn trajectory(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let kept = params.total_steps / params.interval + 1u;
    let base = i * kept;
    var c = coeffs_from(params);
    if PLANE_RUN {
        c = plane_coeffs(params, i);
    }
    if PER_PIXEL {
        c.joint1 = damping[i].x;
        c.joint2 = damping[i].y;
    }
    var p = carried[i];
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
        p = rk4_step(c, p, params.dt);
        if k % params.interval == 0u {
            states[base + k / params.interval] = p.y;
        }
    }
    carried[i] = p;
}
