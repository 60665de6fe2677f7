// Flip-time map with adaptive steps: Dormand-Prince 8(5,3) (Hairer's DOP853), every
// pendulum with its own step size; the higher-order pair for tight tolerances. Twin of
// src/cpu/dop853.rs. The lines marked STAGES and DENSE_STAGES are written out from the
// tableau in src/tableau.rs by src/gpu/layout.rs (`flip_dop853_wgsl`); follows
// shaders/adaptive_common.wgsl.

// The step-size controller (src/cpu/dop853.rs SAFETY, SHRINK, GROW).
const SAFETY = 0.9;
const SHRINK = 1.0 / 3.0;
const GROW = 6.0;

// One angle's dense output over a step (dop853.f's contd8), s the fraction of the step:
// a0 + s (f0 + (1 - s) (f1 + s (f2 + (1 - s) (f3 + s (f4 + (1 - s) (f5 + s f6)))))).
struct Dense {
    a0: real,
    f0: real,
    f1: real,
    f2: real,
    f3: real,
    f4: real,
    f5: real,
    f6: real,
}

// From the angle at the step's ends (a0, a1), its rates there (w0, w1), the step h and
// hd = h times the sums of the dense weights D_m,i times the angle's rate at stage i.
fn dense_of(a0: real, a1: real, w0: real, w1: real, h: real, hd: vec4<real>) -> Dense {
    let f0 = a1 - a0;
    return Dense(a0, f0, h * w0 - f0, 2.0 * f0 - h * (w1 + w0), hd.x, hd.y, hd.z, hd.w);
}

fn dense_value(q: Dense, s: real) -> real {
    let r = 1.0 - s;
    return q.a0 + s * (q.f0 + r * (q.f1 + s * (q.f2 + r * (q.f3 + s * (q.f4 + r * (q.f5 + s * q.f6))))));
}

// d/ds of `dense_value`: the nested products and their derivatives, inside out.
fn dense_slope(q: Dense, s: real) -> real {
    let r = 1.0 - s;
    let p5 = q.f5 + s * q.f6;
    let p4 = q.f4 + r * p5;
    let p3 = q.f3 + s * p4;
    let p2 = q.f2 + r * p3;
    let p1 = q.f1 + s * p2;
    let p0 = q.f0 + r * p1;
    let d4 = r * q.f6 - p5;
    let d3 = s * d4 + p4;
    let d2 = r * d3 - p3;
    let d1 = s * d2 + p2;
    let d0 = r * d1 - p1;
    return p0 + s * d0;
}

// Whether the dense output may reach |angle| = pi within the step: a bound of it reaches pi
// (the chord a0 + s f0 stays within max |a|, and s^a (1 - s)^b <= a^a b^b / (a + b)^(a + b)
// bounds each further term). Cheap and conservative: `dense_crossing` decides.
fn dense_may_reach_pi(q: Dense, a1: real) -> bool {
    let bound = max(abs(q.a0), abs(a1)) + 0.25 * abs(q.f1) + (4.0 / 27.0) * abs(q.f2)
        + 0.0625 * abs(q.f3) + 0.03456 * abs(q.f4) + 0.015625 * abs(q.f5) + 0.0083931 * abs(q.f6);
    return bound > PI;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_adaptive(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = linear_index(gid, groups);
    if n >= params.count {
        return;
    }
    let i = active_in[n];
    let c = pixel_coeffs(params, i);
    let t_max = params.t_max;
    let slot = states[i];
    var p = Pendulum(slot.y, slot.u);
    let clock = slot.clock;
    var t = clock.x;
    var h = clock.y;
    var attempts = clock.z;
    var t_flip = times[i];
    var stalled = false;
    var flip = Candidate();
    var k1 = rate(c, p);
    for (var k = 0u; k < params.steps; k++) {
        if t >= t_max || flip.found {
            break;
        }
        let at = attempt(t, h, &attempts);
        if at.stalled {
            stalled = true;
            break;
        }
        let step = at.step;
        let last = at.last;
        // STAGES: k2..k12, `next` (the eighth-order solution), `e5` and `e3` (the error
        // estimates' sums, angles and angular velocities).
        //{{STAGES}}
        let scale = params.atol + params.rtol * max(abs(p.y), abs(next.y));
        let q5 = step * e5 / scale;
        let q3 = step * e3 / scale;
        let n5 = dot(q5, q5);
        let n3 = dot(q3, q3);
        // Hairer's error: the fifth-order estimate, damped where the third-order one is much
        // larger (src/cpu/dop853.rs `scaled_error`).
        var err = n5 / sqrt((n5 + 0.01 * n3) * 4.0);
        if n5 == 0.0 && n3 == 0.0 {
            err = 0.0;
        }
        let factor = clamp(SAFETY / sqrt(sqrt(sqrt(err))), SHRINK, GROW);
        if err <= 1.0 {
            // The next step's first stage, at the propagated solution.
            let k13 = rate(c, next);
            let a = p.y;
            let b = next.y;
            // The three more stages only for steps that may reach pi.
            let near1 = may_reach_pi(a.x, b.x, a.y, b.y, step);
            let near2 = may_reach_pi(a.z, b.z, a.w, b.w, step);
            if t_flip == NEVER && !flip.found && (near1 || near2) {
                // DENSE_STAGES: k14..k16 and `hd0`..`hd3`, h times the dense weights' sums.
                //{{DENSE_STAGES}}
                let q1 = dense_of(a.x, b.x, a.y, b.y, step, vec4<real>(hd0.x, hd1.x, hd2.x, hd3.x));
                let q2 = dense_of(a.z, b.z, a.w, b.w, step, vec4<real>(hd0.z, hd1.z, hd2.z, hd3.z));
                if (near1 && dense_may_reach_pi(q1, b.x)) || (near2 && dense_may_reach_pi(q2, b.z)) {
                    // Decided after the loop; the pixel's dispatch ends with this step.
                    flip = Candidate(true, t, step, q1, q2);
                }
            }
            t = select(t + step, t_max, last);
            p = on_circles(next);
            k1 = k13;
        }
        h = min(h * factor, params.dt);
    }
    settle(i, p, vec3<real>(t, h, attempts), t_flip, stalled, flip);
}
