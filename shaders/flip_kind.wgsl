// Flip-kind map: which arm flips first and which way, from flip_time.wgsl's loop and flip
// location (this file is appended to it). Twin of src/cpu/flip_kind.rs; driven by
// src/gpu/flip_time.rs. `times` holds the class code (src/quantity.rs `FlipKind`: 1 upper +,
// 2 upper -, 3 lower +, 4 lower -), NEVER until the pixel flips within t-max, NONFINITE when
// its state left the numbers first.

@compute @workgroup_size(WORKGROUP_SIZE)
fn flip_kind(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let n = linear_index(gid, groups);
    if n >= params.count {
        return;
    }
    var i = n;
    if EARLY_EXIT {
        i = active_in[n];
    }
    var p = Pendulum(states[2u * i], states[2u * i + 1u]);
    var kind = times[i];
    let f = advance(pixel_coeffs(params, i), &p, kind != NEVER);
    if f.flipped {
        let at = crossing(f, params.dt);
        // The flip time exactly as flip_time writes it: a flip past t-max is none.
        if (real(f.k) + at.x) * params.dt <= params.t_max {
            var angle = f.after.x;
            if at.y == 2.0 {
                angle = f.after.z;
            }
            kind = 2.0 * at.y - 1.0;
            if angle < 0.0 {
                kind += 1.0;
            }
        }
    }
    if kind == NEVER && !is_finite4(p.y) {
        kind = NONFINITE;
    }
    states[2u * i] = p.y;
    states[2u * i + 1u] = p.u;
    times[i] = kind;
    if EARLY_EXIT && kind == NEVER && !f.flipped {
        push_active(i);
    }
}
