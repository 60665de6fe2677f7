// Chaos indicators beyond the largest exponent: the spectrum, SALI and GALI_k, MEGNO and the
// FLI, Lagrangian descriptors. Twin of src/cpu/indicators.rs; driven by
// src/gpu/indicators.rs. After tangent.wgsl, whose Tangent and tangent_step it uses: per
// pixel an IndicatorSlot in `slots`, the map's value so far in `log_sums` (an exponent as its
// log sum: the host divides by t-max, as for the FTLE).
// `params.measure` picks the value; `params.setting` is the alignment threshold or the
// descriptor's exponent p.

// Mirror of src/gpu/layout.rs `GpuIndicatorSlot`.
struct IndicatorSlot {
    // The state; for a descriptor the forward run (the backward one is in v[0], v[1]).
    y: vec4<real>,
    u: vec4<real>,
    // Tangent vectors (src/cpu/indicators.rs FRAME at the start, and why its order); an
    // alignment index's unused ones are normalised but never stepped.
    v: array<vec4<real>, 4>,
    // Spectrum: the four log sums. Alignment: (log10 index, the time it fell below the
    // threshold, stopped, -). Growth: (s-weighted ln |v| sum, time integral of Y,
    // ln |v| so far, the largest log10 |v|). Descriptor: (left sums of both ways, g at the start, -, -).
    sums: vec4<real>,
    // The adaptive spectrum's clock: (next step, attempts so far (-1: stalled), windows done,
    // the time into the next), as lyapunov.wgsl's adaptive tangent keeps it.
    clock: vec4<real>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> slots: array<IndicatorSlot>;
@group(0) @binding(2) var<storage, read_write> log_sums: array<real>;

const LOG10_E: real = 0.4342944819032518;
// As lyapunov.wgsl STALLED_LOG_SUM: the host reads a value below -1e38 as NaN.
const LEFT_THE_NUMBERS: real = -3.0e38;

fn frame_vector(j: u32) -> vec4<real> {
    switch j {
        case 0u: { return TANGENT_START; }
        case 1u: { return vec4<real>(0.5, 0.5, -0.5, -0.5); }
        case 2u: { return vec4<real>(0.5, -0.5, 0.5, -0.5); }
        default: { return vec4<real>(0.5, -0.5, -0.5, 0.5); }
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn indicator_init(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let p = pendulum_from(grid_start(params, i));
    slots[i].y = p.y;
    slots[i].u = p.u;
    for (var j = 0u; j < 4u; j++) {
        slots[i].v[j] = frame_vector(j);
    }
    slots[i].sums = vec4<real>();
    slots[i].clock = vec4<real>(params.dt, 0.0, 0.0, 0.0);
    log_sums[i] = 0.0;
}

// The tangent vectors as named fields, not an array: indexed by a loop variable, an array
// in function memory stays in memory on lavapipe (measured 1.6x the cost of SALI's steps).
struct Vectors {
    a: vec4<real>,
    b: vec4<real>,
    c: vec4<real>,
    d: vec4<real>,
}

fn load_vectors(i: u32) -> Vectors {
    return Vectors(slots[i].v[0], slots[i].v[1], slots[i].v[2], slots[i].v[3]);
}

fn store_vectors(i: u32, v: Vectors) {
    slots[i].v[0] = v.a;
    slots[i].v[1] = v.b;
    slots[i].v[2] = v.c;
    slots[i].v[3] = v.d;
}

// One RK4 step of the state and the first n vectors (n a constant at every call). Without air
// drag and bearing friction, by the closed-form Jacobian (`rate_jacobian`), once a stage for
// every vector; with them, each vector by the FTLE's own dual-number tangent_step.
fn step_vectors(c: Coeffs, t: ptr<function, Tangent>, v: ptr<function, Vectors>, n: u32, dt: real) {
    if (LOSSES & 6u) == 0u {
        step_vectors_closed(c, t, v, n, dt);
        return;
    }
    let y = (*t).y;
    let u = (*t).u;
    let first = tangent_step(c, Tangent(y, u, (*v).a), dt);
    (*v).a = first.v;
    if n > 1u {
        (*v).b = tangent_step(c, Tangent(y, u, (*v).b), dt).v;
    }
    if n > 2u {
        (*v).c = tangent_step(c, Tangent(y, u, (*v).c), dt).v;
    }
    if n > 3u {
        (*v).d = tangent_step(c, Tangent(y, u, (*v).d), dt).v;
    }
    *t = first;
}

// The rate at a pendulum and the two nontrivial rows of its Jacobian, d(a1, a2)/d(theta1,
// omega1, theta2, omega2), in closed form for the conservative forces and joint damping (the
// rows of theta-dot are unit vectors): a_i = N_i / det with N1 = B f1 - C cos D f2,
// N2 = A f2 - C cos D f1 (common.wgsl), so d a_i = (d N_i - a_i d det) / det.
struct RateJacobian {
    r: Rate,
    a1: vec4<real>,
    a2: vec4<real>,
}

fn rate_jacobian(c: Coeffs, p: Pendulum) -> RateJacobian {
    let w1 = p.y.y;
    let w2 = p.y.w;
    let c1 = p.u.x;
    let s1 = p.u.y;
    let c2 = p.u.z;
    let s2 = p.u.w;
    let sd = s1 * c2 - c1 * s2;
    let cd = c1 * c2 + s1 * s2;
    // Joint damping: tau = -(j1 + j2) w1 + j2 w2 and j2 w1 - j2 w2 (0 when compiled out).
    var j1: real = 0.0;
    var j2: real = 0.0;
    if has_losses() {
        j1 = c.joint1;
        j2 = c.joint2;
    }
    let tau1 = -(j1 + j2) * w1 + j2 * w2;
    let tau2 = j2 * w1 - j2 * w2;
    let csd = c.c * sd;
    let ccd = c.c * cd;
    let f1 = -csd * w2 * w2 - c.p * s1 + tau1;
    let f2 = csd * w1 * w1 - c.q * s2 + tau2;
    let inv_det = 1.0 / (c.a * c.b - ccd * ccd);
    let a1 = (c.b * f1 - ccd * f2) * inv_det;
    let a2 = (c.a * f2 - ccd * f1) * inv_det;
    // Over (theta1, omega1, theta2, omega2): d sin D = cos D (1, 0, -1, 0), d cos D = -sin D
    // (1, 0, -1, 0).
    let df1 = vec4<real>(-ccd * w2 * w2 - c.p * c1, -(j1 + j2), ccd * w2 * w2, -2.0 * csd * w2 + j2);
    let df2 = vec4<real>(ccd * w1 * w1, 2.0 * csd * w1 + j2, -ccd * w1 * w1 - c.q * c2, -j2);
    let dccd = vec4<real>(-csd, 0.0, csd, 0.0);
    let ddet = -2.0 * ccd * dccd;
    let dn1 = c.b * df1 - f2 * dccd - ccd * df2;
    let dn2 = c.a * df2 - f1 * dccd - ccd * df1;
    return RateJacobian(
        Rate(vec4<real>(w1, a1, w2, a2), vec4<real>(-w1 * s1, w1 * c1, -w2 * s2, w2 * c2)),
        (dn1 - a1 * ddet) * inv_det,
        (dn2 - a2 * ddet) * inv_det,
    );
}

// J v for the Jacobian of `k`.
fn jacobian_times(k: RateJacobian, v: vec4<real>) -> vec4<real> {
    return vec4<real>(v.y, dot(k.a1, v), v.w, dot(k.a2, v));
}

// RK4 over the state and the first n vectors, the Jacobian evaluated once a stage.
fn step_vectors_closed(c: Coeffs, t: ptr<function, Tangent>, v: ptr<function, Vectors>, n: u32, dt: real) {
    let p = Pendulum((*t).y, (*t).u);
    let h = 0.5 * dt;
    let v0 = *v;
    let k1 = rate_jacobian(c, p);
    var s = Vectors(jacobian_times(k1, v0.a), jacobian_times(k1, v0.b), jacobian_times(k1, v0.c), jacobian_times(k1, v0.d));
    var sum = s;
    var r = k1.r;
    let k2 = rate_jacobian(c, advanced(p, h, k1.r));
    s = Vectors(jacobian_times(k2, v0.a + h * s.a), jacobian_times(k2, v0.b + h * s.b), jacobian_times(k2, v0.c + h * s.c), jacobian_times(k2, v0.d + h * s.d));
    sum = Vectors(sum.a + 2.0 * s.a, sum.b + 2.0 * s.b, sum.c + 2.0 * s.c, sum.d + 2.0 * s.d);
    r = Rate(r.dy + 2.0 * k2.r.dy, r.du + 2.0 * k2.r.du);
    let k3 = rate_jacobian(c, advanced(p, h, k2.r));
    s = Vectors(jacobian_times(k3, v0.a + h * s.a), jacobian_times(k3, v0.b + h * s.b), jacobian_times(k3, v0.c + h * s.c), jacobian_times(k3, v0.d + h * s.d));
    sum = Vectors(sum.a + 2.0 * s.a, sum.b + 2.0 * s.b, sum.c + 2.0 * s.c, sum.d + 2.0 * s.d);
    r = Rate(r.dy + 2.0 * k3.r.dy, r.du + 2.0 * k3.r.du);
    let k4 = rate_jacobian(c, advanced(p, dt, k3.r));
    s = Vectors(jacobian_times(k4, v0.a + dt * s.a), jacobian_times(k4, v0.b + dt * s.b), jacobian_times(k4, v0.c + dt * s.c), jacobian_times(k4, v0.d + dt * s.d));
    sum = Vectors(sum.a + s.a, sum.b + s.b, sum.c + s.c, sum.d + s.d);
    r = Rate(r.dy + k4.r.dy, r.du + k4.r.du);
    let w = dt / c.six;
    let next = tangent_on_circles(Tangent(p.y + w * r.dy, p.u + w * r.du, vec4<real>()));
    *t = next;
    (*v).a = v0.a + w * sum.a;
    if n > 1u {
        (*v).b = v0.b + w * sum.b;
    }
    if n > 2u {
        (*v).c = v0.c + w * sum.c;
    }
    if n > 3u {
        (*v).d = v0.d + w * sum.d;
    }
}

// `w` made orthogonal to the unit vector `e`.
fn without(w: vec4<real>, e: vec4<real>) -> vec4<real> {
    return w - dot(e, w) * e;
}

// Modified Gram-Schmidt of the first n vectors in place; the lengths they had (1 beyond n).
fn gram_schmidt(v: ptr<function, Vectors>, n: u32) -> vec4<real> {
    var lengths = vec4<real>(1.0);
    lengths.x = length((*v).a);
    (*v).a = (*v).a / lengths.x;
    if n > 1u {
        let w = without((*v).b, (*v).a);
        lengths.y = length(w);
        (*v).b = w / lengths.y;
    }
    if n > 2u {
        let w = without(without((*v).c, (*v).a), (*v).b);
        lengths.z = length(w);
        (*v).c = w / lengths.z;
    }
    if n > 3u {
        let w = without(without(without((*v).d, (*v).a), (*v).b), (*v).c);
        lengths.w = length(w);
        (*v).d = w / lengths.w;
    }
    return lengths;
}

// The spectrum: four vectors, re-orthonormalised after every `interval`-th step.
@compute @workgroup_size(WORKGROUP_SIZE)
fn spectrum_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    var t = Tangent(slots[i].y, slots[i].u, vec4<real>());
    var v = load_vectors(i);
    var sums = slots[i].sums;
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
        step_vectors(c, &t, &v, 4u, params.dt);
        if renormalise_after(k) {
            let l = gram_schmidt(&v, 4u);
            sums += vec4<real>(ln_real(l.x), ln_real(l.y), ln_real(l.z), ln_real(l.w));
        }
    }
    slots[i].y = t.y;
    slots[i].u = t.u;
    store_vectors(i, v);
    slots[i].sums = sums;
    // measure 0..3: exponent 1..4; 4: their sum.
    log_sums[i] = select(sums.x + sums.y + sums.z + sums.w, sums[min(params.measure, 3u)], params.measure < 4u);
}

// A state and four vectors, and their rates: the adaptive spectrum's variables.
struct Set {
    y: vec4<real>,
    u: vec4<real>,
    v: Vectors,
}

// The rates of a set: the pendulum's, and J v for each vector (closed form without drag and
// bearings, else the dual-number tangent rate of each).
fn set_rate(c: Coeffs, x: Set) -> Set {
    if (LOSSES & 6u) == 0u {
        let k = rate_jacobian(c, Pendulum(x.y, x.u));
        return Set(k.r.dy, k.r.du, Vectors(jacobian_times(k, x.v.a), jacobian_times(k, x.v.b), jacobian_times(k, x.v.c), jacobian_times(k, x.v.d)));
    }
    let a = tangent_rate(c, Tangent(x.y, x.u, x.v.a));
    let b = tangent_rate(c, Tangent(x.y, x.u, x.v.b)).v;
    let cc = tangent_rate(c, Tangent(x.y, x.u, x.v.c)).v;
    let d = tangent_rate(c, Tangent(x.y, x.u, x.v.d)).v;
    return Set(a.y, a.u, Vectors(a.v, b, cc, d));
}

fn set_ahead(x: Set, h: real, k: Set) -> Set {
    return Set(x.y + h * k.y, x.u + h * k.u, Vectors(x.v.a + h * k.v.a, x.v.b + h * k.v.b, x.v.c + h * k.v.c, x.v.d + h * k.v.d));
}

// Sum of squares of e / (atol + rtol max(|x|, |next|)) over a vec4.
fn scaled_squares(e: vec4<real>, x: vec4<real>, next: vec4<real>) -> real {
    let q = e / (params.atol + params.rtol * max(abs(x), abs(next)));
    return dot(q, q);
}

// The spectrum with DP54 steps (dp54.wgsl) over the state and the four vectors, the error
// controlled over the twenty components (RMS), as lyapunov.wgsl's tangent_adaptive does for
// one, through renormalisation windows as shaders/adaptive_windows.wgsl steps them; a pixel
// keeps its own place in its clock (the slot's last vec4).
@compute @workgroup_size(WORKGROUP_SIZE)
fn spectrum_adaptive(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    var x = Set(slots[i].y, slots[i].u, load_vectors(i));
    var sums = slots[i].sums;
    let clock = slots[i].clock;
    var h = clock.x;
    var attempts = clock.y;
    var stalled = attempts < 0.0;
    var done = u32(clock.z);
    var s = clock.w;
    //{{ADAPTIVE_WINDOWS}} (shaders/adaptive_windows.wgsl), filled by:
    //{{RATE}}
    set_rate(c, x)
    //{{ERROR}}
            // The error estimate: sum_j E_j k_j, times the step.
            let e = set_ahead(set_ahead(set_ahead(set_ahead(set_ahead(set_ahead(Set(vec4<real>(), vec4<real>(), Vectors(vec4<real>(), vec4<real>(), vec4<real>(), vec4<real>())), E1, k1), E3, k3), E4, k4), E5, k5), E6, k6), E7, k7);
            let squares = scaled_squares(step * e.y, x.y, next.y)
                + scaled_squares(step * e.v.a, x.v.a, next.v.a)
                + scaled_squares(step * e.v.b, x.v.b, next.v.b)
                + scaled_squares(step * e.v.c, x.v.c, next.v.c)
                + scaled_squares(step * e.v.d, x.v.d, next.v.d);
            let err = sqrt(squares / 20.0);
    //{{ACCEPT}}
                let on = tangent_on_circles(Tangent(next.y, next.u, vec4<real>()));
                x = Set(on.y, on.u, next.v);
    //{{STALLED}}
            sums = vec4<real>(LEFT_THE_NUMBERS);
    //{{WINDOW_END}}
        // (A pointer to a member of `x` trips naga 30's SPIR-V writer: a copy.)
        var v = x.v;
        let l = gram_schmidt(&v, 4u);
        x.v = v;
        sums += vec4<real>(ln_real(l.x), ln_real(l.y), ln_real(l.z), ln_real(l.w));
    //{{END}}
    slots[i].y = x.y;
    slots[i].u = x.u;
    store_vectors(i, x.v);
    slots[i].sums = sums;
    slots[i].clock = vec4<real>(h, select(attempts, -1.0, stalled), real(done), s);
    log_sums[i] = select(sums.x + sums.y + sums.z + sums.w, sums[min(params.measure, 3u)], params.measure < 4u);
}

// An alignment index of n vectors, normalised after every `interval`-th step; the pixel
// stops once the index falls below params.setting. measure 0: log10 index, 1: the time.
fn alignment_advance(i: u32, n: u32, sali: bool) {
    let c = pixel_coeffs(params, i);
    var at = slots[i].sums;
    if at.z == 0.0 {
        var t = Tangent(slots[i].y, slots[i].u, vec4<real>());
        var v = load_vectors(i);
        for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
            step_vectors(c, &t, &v, n, params.dt);
            if renormalise_after(k) {
                v = Vectors(v.a / length(v.a), v.b / length(v.b), v.c / length(v.c), v.d / length(v.d));
                var index: real;
                if sali {
                    index = min(length(v.a + v.b), length(v.a - v.b));
                } else {
                    var w = v;
                    let l = gram_schmidt(&w, n);
                    index = l.x * l.y * l.z * l.w;
                }
                at.x = ln_real(index) * LOG10_E;
                if index < params.setting {
                    at.y = real(k) * params.dt;
                    at.z = 1.0;
                    break;
                }
            }
        }
        slots[i].y = t.y;
        slots[i].u = t.u;
        store_vectors(i, v);
        slots[i].sums = at;
    }
    log_sums[i] = select(at.x, select(NEVER, at.y, at.z != 0.0), params.measure == 1u);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn sali_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i < params.count {
        alignment_advance(i, 2u, true);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn gali2_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i < params.count {
        alignment_advance(i, 2u, false);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn gali3_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i < params.count {
        alignment_advance(i, 3u, false);
    }
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn gali4_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i < params.count {
        alignment_advance(i, 4u, false);
    }
}

// MEGNO and the FLI of one vector, renormalised after every step: ln |v| of a step is the
// integrand of both. measure 0: <Y>, 1: the FLI.
@compute @workgroup_size(WORKGROUP_SIZE)
fn growth_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    let dt = params.dt;
    var t = Tangent(slots[i].y, slots[i].u, slots[i].v[0]);
    var g = slots[i].sums;
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
        t = tangent_step(c, t, dt);
        let n = length(t.v);
        t.v = t.v / n;
        let l = ln_real(n);
        let s = real(k) * dt;
        // Y(s) = 2/s int_0^s r d(ln |v|), r at the step's middle; <Y> its time mean.
        g.x += (s - 0.5 * dt) * l;
        g.y += dt * (2.0 * g.x / s);
        g.z += l;
        g.w = max(g.w, g.z * LOG10_E);
    }
    slots[i].y = t.y;
    slots[i].u = t.u;
    slots[i].v[0] = t.v;
    slots[i].sums = g;
    let now = real(params.step0 + params.steps) * dt;
    // A NaN or infinite log makes max() meaningless: say the pixel left the numbers.
    let finite = abs(g.z) <= 1.0e30 && abs(g.y) <= 1.0e30;
    log_sums[i] = select(LEFT_THE_NUMBERS, select(g.y / now, g.w, params.measure == 1u), finite);
}

// sum_i |f_i|^p for p = params.setting in 0.25, 0.5, 1, 2 (the ones built from sqrt and
// products, which f64 has on every driver).
fn velocity_measure(f: vec4<real>) -> real {
    let a = abs(f);
    var m = a * a;
    if params.setting == 0.5 {
        m = sqrt(a);
    } else if params.setting == 0.25 {
        m = sqrt(sqrt(a));
    } else if params.setting == 1.0 {
        m = a;
    }
    return m.x + m.y + m.z + m.w;
}

// The descriptor: one plain trajectory forward and one backward, the trapezoid rule on
// sum_i |f_i|^p each way (as left sums here, the end corrections on the last step).
@compute @workgroup_size(WORKGROUP_SIZE)
fn descriptor_advance(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_index(gid, groups);
    if i >= params.count {
        return;
    }
    let c = pixel_coeffs(params, i);
    let dt = params.dt;
    var ahead = Pendulum(slots[i].y, slots[i].u);
    var back = Pendulum(slots[i].y, slots[i].u);
    var sums = slots[i].sums;
    if params.step0 == 0u {
        sums.y = velocity_measure(rate(c, ahead).dy);
    } else {
        back = Pendulum(slots[i].v[0], slots[i].v[1]);
    }
    for (var k = params.step0 + 1u; k <= params.step0 + params.steps; k++) {
        let ka = rate(c, ahead);
        let kb = rate(c, back);
        sums.x += dt * (velocity_measure(ka.dy) + velocity_measure(kb.dy));
        ahead = rk4_step_with(c, ahead, ka, dt);
        back = rk4_step_with(c, back, kb, -dt);
    }
    slots[i].y = ahead.y;
    slots[i].u = ahead.u;
    slots[i].v[0] = back.y;
    slots[i].v[1] = back.u;
    slots[i].sums = sums;
    var m = sums.x;
    if params.step0 + params.steps == params.total_steps {
        let ends = velocity_measure(rate(c, ahead).dy) + velocity_measure(rate(c, back).dy);
        m += 0.5 * dt * (ends - 2.0 * sums.y);
    }
    log_sums[i] = select(LEFT_THE_NUMBERS, m, abs(m) <= 1.0e30);
}
