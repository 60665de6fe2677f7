// Flip-time map with adaptive steps: Dormand-Prince 5(4), every pendulum with its own step
// size. Twin of src/cpu/adaptive.rs (which holds the tableau as data; here the stages are
// written out from it by src/gpu/shaders.rs); follows shaders/adaptive_common.wgsl. `flip_adaptive_init` sets up a tile,
// `flip_adaptive` gives every active pixel up to `params.steps` more step attempts.



// p + h (w1 k1 + w2 k2), and so on: a stage's state.
fn along2(p: Pendulum, h: real, w1: real, k1: Rate, w2: real, k2: Rate) -> Pendulum {
    return Pendulum(p.y + h * (w1 * k1.dy + w2 * k2.dy), p.u + h * (w1 * k1.du + w2 * k2.du));
}

fn along3(p: Pendulum, h: real, w1: real, k1: Rate, w2: real, k2: Rate, w3: real, k3: Rate) -> Pendulum {
    return Pendulum(
        p.y + h * (w1 * k1.dy + w2 * k2.dy + w3 * k3.dy),
        p.u + h * (w1 * k1.du + w2 * k2.du + w3 * k3.du),
    );
}

fn along4(p: Pendulum, h: real, w1: real, k1: Rate, w2: real, k2: Rate, w3: real, k3: Rate, w4: real, k4: Rate) -> Pendulum {
    return Pendulum(
        p.y + h * (w1 * k1.dy + w2 * k2.dy + w3 * k3.dy + w4 * k4.dy),
        p.u + h * (w1 * k1.du + w2 * k2.du + w3 * k3.du + w4 * k4.du),
    );
}

fn along5(p: Pendulum, h: real, w1: real, k1: Rate, w2: real, k2: Rate, w3: real, k3: Rate, w4: real, k4: Rate, w5: real, k5: Rate) -> Pendulum {
    return Pendulum(
        p.y + h * (w1 * k1.dy + w2 * k2.dy + w3 * k3.dy + w4 * k4.dy + w5 * k5.dy),
        p.u + h * (w1 * k1.du + w2 * k2.du + w3 * k3.du + w4 * k4.du + w5 * k5.du),
    );
}

// One angle's dense output over a step (dopri5's contd5):
// a0 + s (dy + (1 - s) (b + s (r + (1 - s) hd))), s the fraction of the step.
struct Dense {
    a0: real,
    dy: real,
    b: real,
    r: real,
    hd: real,
}

// From the angle at the step's ends (a0, a1), its rates there (w0, w1; the rates at the first
// and last stage), d = the sum of D_i times the angle's rate at stage i, and the step h.
fn dense_of(a0: real, a1: real, w0: real, w1: real, d: real, h: real) -> Dense {
    let dy = a1 - a0;
    let b = h * w0 - dy;
    let r = dy - h * w1 - b;
    return Dense(a0, dy, b, r, h * d);
}

fn dense_value(q: Dense, s: real) -> real {
    return q.a0 + s * (q.dy + (1.0 - s) * (q.b + s * (q.r + (1.0 - s) * q.hd)));
}

// d/ds of `dense_value`.
fn dense_slope(q: Dense, s: real) -> real {
    return q.dy + (1.0 - 2.0 * s) * q.b + s * (2.0 - 3.0 * s) * q.r + 2.0 * s * (1.0 - s) * (1.0 - 2.0 * s) * q.hd;
}

// Whether the dense output may reach |angle| = pi within the step: a bound of it reaches pi
// (|a0 + s dy| <= max |a|, s (1 - s) <= 1/4, s^2 (1 - s) <= 4/27, s^2 (1 - s)^2 <= 1/16).
// Cheap and conservative: `dense_crossing` decides.
fn dense_may_reach_pi(q: Dense, a1: real) -> bool {
    let bound = max(abs(q.a0), abs(a1)) + 0.25 * abs(q.b) + (4.0 / 27.0) * abs(q.r) + 0.0625 * abs(q.hd);
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
        // The stages (src/gpu/shaders.rs writes them from the tableau):
        //{{DP54_STAGES}}
        let e = step * (E1 * k1.dy + E3 * k3.dy + E4 * k4.dy + E5 * k5.dy + E6 * k6.dy + E7 * k7.dy);
        let scale = params.atol + params.rtol * max(abs(p.y), abs(next.y));
        let q = e / scale;
        let err = sqrt(0.25 * dot(q, q));
        let factor = clamp(SAFETY / sqrt(sqrt(err)), SHRINK, GROW);
        if err <= 1.0 {
            let d = (D1 * k1.dy + D3 * k3.dy + D4 * k4.dy + D5 * k5.dy + D6 * k6.dy + D7 * k7.dy).xz;
            let a = p.y;
            let b = next.y;
            let q1 = dense_of(a.x, b.x, a.y, b.y, d.x, step);
            let q2 = dense_of(a.z, b.z, a.w, b.w, d.y, step);
            let reach1 = may_reach_pi(a.x, b.x, a.y, b.y, step) && dense_may_reach_pi(q1, b.x);
            let reach2 = may_reach_pi(a.z, b.z, a.w, b.w, step) && dense_may_reach_pi(q2, b.z);
            if t_flip == NEVER && !flip.found && (reach1 || reach2) {
                // Decided after the loop; the pixel's dispatch ends with this step.
                flip = Candidate(true, t, step, q1, q2);
            }
            t = select(t + step, t_max, last);
            p = on_circles(next);
            k1 = k7;
        }
        h = min(h * factor, params.dt);
    }
    settle(i, p, vec3<real>(t, h, attempts), t_flip, stalled, flip);
}
