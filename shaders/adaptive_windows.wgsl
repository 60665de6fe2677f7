// A template, not a module: the adaptive windows' loop, written once for every state kind
// that steps with DP54 through renormalisation windows (lyapunov.wgsl's tangent_adaptive,
// indicators.wgsl's spectrum_adaptive). src/gpu/shaders.rs `with_adaptive_windows` puts it
// where a kernel marks `//{{ADAPTIVE_WINDOWS}}`, filled from the kernel's own sections:
// {{RATE}} the state's first rate, {{ERROR}} lines that set `err` (the scaled error's RMS)
// from the stages, {{ACCEPT}} what an accepted step does with `next`, {{STALLED}} what a
// stalled pixel reports, {{WINDOW_END}} the renormalisation at a window's end. The kernel
// declares before it: `c`, the state, `h`, `attempts`, `stalled`, `done`, `s`.
//
// step0 and steps count windows: window k ends at step min(k interval, total_steps) of dt,
// and every pixel lands on it exactly; steps are at most dt. A pixel takes at most
// ATTEMPTS_PER_DISPATCH attempts a dispatch (lavapipe ends all of an invocation's loops
// after 65,535 iterations, silently) and keeps its own place: the windows it has done and
// the time into the next, so a pixel the budget stopped mid-window goes on from there in
// the next dispatch (the host dispatches the last window again until every pixel is there).
    var budget = ATTEMPTS_PER_DISPATCH;
    loop {
        if stalled || done >= params.step0 + params.steps || budget == 0u {
            break;
        }
        let first = done * params.interval;
        let window = real(min((done + 1u) * params.interval, params.total_steps) - first) * params.dt;
        var k1 = {{RATE}};
        loop {
            if s >= window || budget == 0u {
                break;
            }
            budget -= 1u;
            // At most MAX_WINDOW_ATTEMPTS attempts, and a step that still advances the time.
            if attempts >= MAX_WINDOW_ATTEMPTS {
                stalled = true;
                break;
            }
            attempts += 1.0;
            let last = s + h >= window;
            var step = h;
            if last {
                step = window - s;
            }
            if !(s + step > s) {
                stalled = true;
                break;
            }
            // The stages (src/gpu/shaders.rs writes them from the tableau):
            //{{DP54_STAGES}}
{{ERROR}}
            let factor = clamp(SAFETY / sqrt(sqrt(err)), SHRINK, GROW);
            if err <= 1.0 {
                s = select(s + step, window, last);
{{ACCEPT}}
                k1 = k7;
            }
            h = min(h * factor, params.dt);
        }
        if stalled {
{{STALLED}}
            break;
        }
        if s < window {
            // The budget ran out mid-window.
            break;
        }
{{WINDOW_END}}
        done += 1u;
        s = 0.0;
    }
