// The bobs' positions (x1, y1, x2, y2) of `params.count` pendulums at given times, one
// invocation a pendulum: RK4 steps of params.dt, each time placed between the two states
// around it by the cubic Hermite interpolant of the carried cos and sin (the rates give the
// slopes). Written time-major, out[(j * 4 + c) * count + i], so that a time's values lie
// together for the bands' quantiles; nothing else is read back.
// A dispatch runs pendulums row0 .. row0 + rows over steps step0 .. step0 + steps, from and
// back to states[i], placing the times from times[params.interval] on that fall there:
// lavapipe ends every loop of an invocation after 65535 iterations in all (llvmpipe's
// LP_MAX_TGSI_LOOP_ITERATIONS), so the host keeps each dispatch's steps and times below it.
// Twin of src/cpu/mod.rs `positions`; the forecasts' ensembles.
// With PER_PIXEL on, a run is a "pixel" with its own joint damping (N m s) at the pivot and
// the middle joint, damping[i]: a forecast's members drawn from a fit's uncertainty.

// A time as the step it falls in (from the state after `step` steps to the next) and the
// fraction of that step, computed on the host in f64.
struct BandTime {
    step: u32,
    fraction: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> states: array<Pendulum>;
@group(0) @binding(2) var<storage, read> damping: array<vec2<real>>;
@group(0) @binding(3) var<storage, read> times: array<BandTime>;
@group(0) @binding(4) var<storage, read_write> out: array<f32>;

// The rates of a state's cosines and sines.
fn trig_rate(p: Pendulum) -> vec4<real> {
    return vec4<real>(-p.y.y * p.u.y, p.y.y * p.u.x, -p.y.w * p.u.w, p.y.w * p.u.z);
}

// Writes the positions at fraction s of the step of length h from a to b: the cubic Hermite
// interpolant of each angle's cosine and sine (values and slopes at both ends, the slopes
// from the rates), which needs no trigonometry; it errs by O(h^4) as the angle's does.
fn place(c: Coeffs, a: Pendulum, b: Pendulum, s: real, h: real, j: u32, i: u32) {
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = (s3 - 2.0 * s2 + s) * h;
    let h01 = 3.0 * s2 - 2.0 * s3;
    let h11 = (s3 - s2) * h;
    // u = (cos theta1, sin theta1, cos theta2, sin theta2), u' = (-w1 sin, w1 cos, -w2 sin, w2 cos).
    let u = h00 * a.u + h10 * trig_rate(a) + h01 * b.u + h11 * trig_rate(b);
    let x1 = c.l1 * u.y;
    let y1 = -c.l1 * u.x;
    let n = params.count;
    let at = 4u * j * n + i;
    out[at] = f32(x1);
    out[at + n] = f32(y1);
    out[at + 2u * n] = f32(fma(c.l2, u.w, x1));
    out[at + 3u * n] = f32(fma(-c.l2, u.z, y1));
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn positions(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = linear_index(gid, groups);
    if local >= params.rows {
        return;
    }
    let i = params.row0 + local;
    var c = coeffs_from(params);
    if PER_PIXEL {
        c.joint1 = damping[i].x;
        c.joint2 = damping[i].y;
    }
    let h = params.dt;
    let end = params.step0 + params.steps;
    // Steps up to each time in turn (a tight loop, as the maps' kernels step), then places it
    // between the last two states.
    var a = states[i];
    var b = a;
    var k = params.step0;
    for (var j = params.interval; j < arrayLength(&times) && times[j].step < end; j++) {
        let t = times[j];
        for (; k <= t.step; k++) {
            a = b;
            b = rk4_step(c, b, h);
        }
        place(c, a, b, real(t.fraction), h, j, i);
    }
    for (; k < end; k++) {
        b = rk4_step(c, b, h);
    }
    states[i] = b;
}
