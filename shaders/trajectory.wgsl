// Trajectories of `params.count` pendulums, one per invocation: states[i (steps + 1)] is the
// start of pendulum i, states[i (steps + 1) + k + 1] its state after step k.
// Twin of src/cpu/mod.rs `trajectory`; used to compare the two paths step by step and for
// ensembles (traces, phase portraits).

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn trajectory(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let base = i * (params.steps + 1u);
    let c = coeffs_from(params);
    var p = pendulum_from(states[base]);
    for (var k = 0u; k < params.steps; k++) {
        p = rk4_step(c, p, params.dt);
        states[base + k + 1u] = p.y;
    }
}
