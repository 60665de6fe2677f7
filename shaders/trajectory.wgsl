// Trajectories of `params.count` pendulums, one per invocation, keeping every
// `params.interval`-th state: with n = steps / interval + 1 states a run, states[i n] is the
// start of pendulum i and states[i n + k] its state after k * interval steps.
// Twin of src/cpu/mod.rs `trajectory`; used to compare the two paths step by step and for
// ensembles (traces, phase portraits, fitting tracked data).

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<vec4<real>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn trajectory(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let kept = params.steps / params.interval + 1u;
    let base = i * kept;
    let c = coeffs_from(params);
    var p = pendulum_from(states[base]);
    for (var k = 1u; k <= params.steps; k++) {
        p = rk4_step(c, p, params.dt);
        if k % params.interval == 0u {
            states[base + k / params.interval] = p.y;
        }
    }
}
