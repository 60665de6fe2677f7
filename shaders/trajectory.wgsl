// One trajectory: states[0] is the start, states[k + 1] the state after step k.
// Twin of src/cpu/mod.rs `trajectory`; used to compare the two paths step by step.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<vec4<f32>>;

@compute @workgroup_size(1)
fn trajectory() {
    let c = coeffs_from(params);
    var p = pendulum_from(states[0]);
    for (var k = 0u; k < params.steps; k++) {
        p = rk4_step(c, p, params.dt);
        states[k + 1u] = p.y;
    }
}
