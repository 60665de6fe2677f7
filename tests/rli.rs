//! The relative Lyapunov indicator against structural truths: on a regular orbit two
//! neighbours' finite-time exponents differ in proportion to their distance (the RLI scales
//! with `rli_delta`); in chaos they part whatever the distance (the RLI saturates near the
//! exponent's size); its option travels through the registry's doors (the flag, its range,
//! the picture's command); and the GPU (f32, f64) against the f64 CPU twin through every
//! indicator's check in tests/indicators.rs.

mod common;

use chaoscope::cpu;
use chaoscope::model::{Params, State};
use chaoscope::spec::{Grid, Indicator, LyapunovSpec, Precision, Stepping};

fn spec(delta: f64, t_max: f64) -> LyapunovSpec {
    LyapunovSpec {
        precision: Precision::F64,
        indicator: Indicator::Rli { delta },
        ..LyapunovSpec::new(
            Params::default(),
            Grid::square(16),
            Stepping { dt: 0.01, t_max },
        )
    }
}

/// log10 RLI at t-max of one start.
fn rli(delta: f64, start: State) -> f64 {
    cpu::indicator_run(&spec(delta, 20.0), start, None, &mut |_, _| {}).unwrap()
}

#[test]
fn on_a_regular_orbit_the_rli_scales_with_the_distance_and_in_chaos_it_saturates() {
    // Small swings (0.3, 0.2 rad) lie on a torus: L of either neighbour is a smooth
    // function of the start, so |ΔL| is linear in the distance: a hundred times the
    // distance, a hundred times the RLI (log10: 2), to the linear term's accuracy (the
    // quadratic one is 1e-6 / 1e-8 of it at these distances: 0.05 in log10 covers the
    // round-off of differences 1e-8 small).
    let regular = State::at_rest(0.3, 0.2);
    let (near, far) = (rli(1e-8, regular), rli(1e-6, regular));
    eprintln!("regular: log10 RLI {near:.3} at 1e-8, {far:.3} at 1e-6");
    assert!((far - near - 2.0).abs() < 0.05, "{near} {far}");
    // And it stays near the distance's size: far below the chaotic rule's -3.
    assert!(near < -6.0, "{near}");
    // Released high (2.0, 2.6 rad: it flips) the neighbours part within ln(1/delta)/λ,
    // a few seconds, whatever the distance: both RLIs of the order of the exponent (log10
    // above -2), within a decade of each other.
    let chaotic = State::at_rest(2.0, 2.6);
    let (near, far) = (rli(1e-8, chaotic), rli(1e-6, chaotic));
    eprintln!("chaotic: log10 RLI {near:.3} at 1e-8, {far:.3} at 1e-6");
    assert!(near > -2.0 && far > -2.0, "{near} {far}");
    assert!((far - near).abs() < 1.0, "{near} {far}");
}

#[test]
fn the_rli_and_its_distance_go_through_every_door() {
    let asked = chaoscope::measure::IndicatorAsked {
        options: &[("rli_delta", 1e-6)],
        ..chaoscope::measure::IndicatorAsked::named("rli")
    };
    assert_eq!(asked.indicator().unwrap(), Indicator::Rli { delta: 1e-6 });
    // Its defaults: f64's 1e-8, f32's 1e-4 (the least f32 separates from an angle of 3).
    let f32_gpu = chaoscope::measure::IndicatorAsked {
        gpu_f32: true,
        ..chaoscope::measure::IndicatorAsked::named("rli")
    };
    assert_eq!(f32_gpu.indicator().unwrap(), Indicator::Rli { delta: 1e-4 });
    assert!(
        chaoscope::spec::MapKind::all()
            .iter()
            .any(|k| k.name() == "rli")
    );
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("rli.png");
    // An 8 x 8 map over 1 s on `backend` of `indicator` with its neighbour `delta` away.
    let map = |backend: &str, indicator: &str, delta: &str, precision: &str| {
        common::chaoscope()
            .args([
                "lyapunov",
                "--size",
                "8",
                "--t-max",
                "1",
                "--backend",
                backend,
            ])
            .args(["--indicator", indicator, "--rli-delta", delta])
            .args(["--precision", precision, "--output"])
            .arg(&png)
            .output()
            .unwrap()
    };
    let out = map("cpu", "rli", "1e-6", "f64");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The picture's command gives the distance back.
    let command = common::png_text(&png, "chaoscope:command");
    assert!(
        command.contains("--indicator rli --rli-delta 1e-6"),
        "{command}"
    );
    // Out of range, or with another indicator: refused naming the flag.
    for (backend, args, says) in [
        ("cpu", ["rli", "1", "f64"], "1e-2"),
        // f32 is the GPU's (lavapipe here).
        ("gpu", ["rli", "1e-6", "f32"], "1e-4"),
        ("cpu", ["fli", "1e-6", "f64"], "rli"),
    ] {
        let out = map(backend, args[0], args[1], args[2]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("--rli-delta") && err.contains(says),
            "{args:?}: {err}"
        );
    }
}
