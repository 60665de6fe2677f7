// The relative Lyapunov indicator (Sándor, Érdi, Széll, Funk 2004): the time average of
// |L_b - L_a|, L = ln |v| / t the finite-time exponent of one tangent vector along each of
// two orbits, the second started params.setting away along +-TANGENT_START (the sign of
// the start's first non-zero coordinate: the mirrored start -y gets the mirrored pair, so
// that the map keeps the pendulum's point symmetry bit for bit). Each vector
// renormalised every step, its length kept as a log (as growth_advance). Appended to
// indicators.wgsl; twin: src/measure/rli.rs. Slot: the first orbit in y, u with its vector
// in v[0]; the second's vector in v[1], its state in v[2], v[3]; sums: (ln |v_a| so far,
// ln |v_b| so far, the sum of |L_b - L_a| over the steps, -).

// The sign of the first non-zero coordinate of y (+1 at the origin).
fn side(y: vec4<real>) -> real {
    for (var k = 0u; k < 4u; k++) {
        if y[k] != 0.0 {
            return sign(y[k]);
        }
    }
    return 1.0;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn rli_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    var a = Tangent(slots[i].y, slots[i].u, slots[i].v[0]);
    var b = Tangent(slots[i].v[2], slots[i].v[3], slots[i].v[1]);
    if params.step0 == 0u {
        let near = pendulum_from(a.y + side(a.y) * real(params.setting) * TANGENT_START);
        b = Tangent(near.y, near.u, TANGENT_START);
    }
    var g = slots[i].sums;
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
        a = tangent_step(c, a, params.dt);
        b = tangent_step(c, b, params.dt);
        let na = length(a.v);
        let nb = length(b.v);
        a.v = a.v / na;
        b.v = b.v / nb;
        g.x += ln_real(na);
        g.y += ln_real(nb);
        g.z += abs(g.x - g.y) / (real(k) * params.dt);
    }
    slots[i].y = a.y;
    slots[i].u = a.u;
    slots[i].v[0] = a.v;
    slots[i].v[1] = b.v;
    slots[i].v[2] = b.y;
    slots[i].v[3] = b.u;
    slots[i].sums = g;
    let rli = ln_real(g.z / real(params.step0 + params.steps)) * LOG10_E;
    // A NaN or infinite log: say the pixel left the numbers.
    log_sums[i] = select(LEFT_THE_NUMBERS, rli, abs(rli) <= 1.0e30);
}
