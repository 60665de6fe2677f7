// The orthogonal fast Lyapunov indicator (Fouchard, Froeschlé, Valsecchi, Rickman 2002): the
// largest log10 |v_perp| so far, v_perp the part of one tangent vector across the flow f,
// v - (v . f) f / |f|^2. Periodic orbits keep it bounded (their tangent vectors shear only
// along the flow), quasi-periodic ones grow like log t, chaotic ones like λ t. One vector
// renormalised every step, its length kept as a log (as growth_advance). Appended to
// indicators.wgsl; twin: src/measure/ofli.rs. Slot sums: (-, -, ln |v| so far, the OFLI).

// log10 |v_perp| of the unit vector v at the pendulum p (|v| where the flow stops).
fn log10_across(c: Coeffs, p: Pendulum, v: vec4<real>) -> real {
    let f = rate(c, p).dy;
    let ff = dot(f, f);
    var w = v;
    if ff > 0.0 {
        w = v - (dot(v, f) / ff) * f;
    }
    return ln_real(length(w)) * LOG10_E;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn ofli_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    var t = Tangent(slots[i].y, slots[i].u, slots[i].v[0]);
    var g = slots[i].sums;
    if params.step0 == 0u {
        g.w = log10_across(c, Pendulum(t.y, t.u), t.v);
    }
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
        t = tangent_step(c, t, params.dt);
        let n = length(t.v);
        t.v = t.v / n;
        g.z += ln_real(n);
        g.w = max(g.w, g.z * LOG10_E + log10_across(c, Pendulum(t.y, t.u), t.v));
    }
    slots[i].y = t.y;
    slots[i].u = t.u;
    slots[i].v[0] = t.v;
    slots[i].sums = g;
    // A NaN or infinite log makes max() meaningless: say the pixel left the numbers.
    let finite = abs(g.z) <= 1.0e30 && abs(g.w) <= 1.0e30;
    log_sums[i] = select(LEFT_THE_NUMBERS, g.w, finite);
}
