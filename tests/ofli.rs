//! The orthogonal FLI against structural truths: without gravity a uniform rigid rotation is
//! a periodic orbit whose tangent vector grows only along the flow (in closed form);
//! |v_perp| <= |v| at every step; in chaos the tangent vector grows across the flow (whose own
//! exponent is 0); and the GPU (f32, f64) against the f64 CPU twin through every indicator's
//! check in tests/indicators.rs.

mod common;

use chaoscope::cpu;
use chaoscope::engine::Engine;
use chaoscope::model::{Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::spec::{Grid, Indicator, LyapunovSpec, Precision, Stepping};

fn spec(params: Params, t_max: f64) -> LyapunovSpec {
    LyapunovSpec {
        precision: Precision::F64,
        indicator: Indicator::Ofli,
        ..LyapunovSpec::new(params, Grid::square(16), Stepping { dt: 0.01, t_max })
    }
}

/// (t, [ofli, fli]) at every renormalisation of one start.
fn trace(spec: &LyapunovSpec, start: State) -> Vec<(f64, Vec<f64>)> {
    let mut rows = Vec::new();
    cpu::indicator_run(spec, start, None, &mut |t, row| {
        rows.push((t, row.to_vec()))
    })
    .unwrap();
    rows
}

fn at(rows: &[(f64, Vec<f64>)], t: f64) -> &[f64] {
    &rows.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1
}

/// Gravity at the smallest the parameters take (1e-6 m/s^2): at 5 rad/s its pull is
/// g / (l w^2) ~ 4e-8 of the centripetal one, so the motion is the integrable one's.
fn weightless() -> Params {
    Params {
        g: 1e-6,
        ..Params::default()
    }
}

#[test]
fn on_a_periodic_orbit_the_ofli_stays_put_while_the_fli_grows_like_log_t() {
    let s = spec(weightless(), 40.0);
    // Rigid rotation, both arms in line at 5 rad/s: a periodic orbit. The tangent start
    // (0.5, 0.5, 0.5, 0.5) in (theta1, omega1, theta2, omega2) is a faster rotation half a
    // rad/s up, turned half a radian ahead: v(t) = (0.5 + 0.5 t, 0.5, 0.5 + 0.5 t, 0.5), whose
    // growth is all along the flow f = (5, 0, 5, 0). So |v| grows like t and v_perp stays
    // (0, 0.5, 0, 0.5): log10 |v_perp| = log10 sqrt(0.5) at every step.
    let rows = trace(&s, State::from_array([0.0, 5.0, 0.0, 5.0]));
    let across = 0.5f64.sqrt().log10();
    for (t, row) in &rows {
        let along = 0.5 + 0.5 * t;
        let fli = (2.0 * along * along + 0.5).sqrt().log10();
        // RK4 on a uniform rotation is exact but for gravity's 4e-8 pull and round-off.
        assert!((row[0] - across).abs() < 1e-6, "OFLI at {t}: {row:?}");
        assert!(
            (row[1] - fli).abs() < 1e-6,
            "FLI at {t}: {row:?} against {fli}"
        );
    }
    assert!(
        at(&rows, 40.0)[1] - at(&rows, 4.0)[1] > 0.9,
        "a decade of t is 0.9 of FLI"
    );
}

#[test]
fn the_ofli_never_exceeds_the_fli_and_follows_it_in_chaos() {
    let s = spec(Params::default(), 20.0);
    let mut chaotic = 0;
    for (a, b) in [(1.0, 0.0), (2.0, 1.0), (3.0, 0.0), (1.0, -2.5)] {
        let rows = trace(&s, State::at_rest(a, b));
        // |v_perp| <= |v| at every step, so the largest log10 of one is at most the other's
        // (1e-12: the two logs' round-off).
        for (t, row) in &rows {
            assert!(row[0] <= row[1] + 1e-12, "({a}, {b}) at {t}: {row:?}");
        }
        let last = &rows.last().unwrap().1;
        eprintln!("({a}, {b}): OFLI {:.2}, FLI {:.2}", last[0], last[1]);
        // In chaos the vector aligns with the unstable direction, which the flow's own
        // neutral direction does not contain: v_perp keeps a fixed share of v (a decade).
        if last[1] > 5.0 {
            chaotic += 1;
            assert!(last[0] > last[1] - 1.0, "({a}, {b}): {last:?}");
        }
    }
    // Three of the four are chaotic at 20 s (FLI 9 to 11): the comparison above ran.
    assert!(chaotic >= 2, "{chaotic} chaotic starts");
}

#[test]
fn the_ofli_map_runs_through_every_door_of_the_registry() {
    // Its name, its map on the CPU, its picture's range.
    let asked = chaoscope::measure::IndicatorAsked::named("ofli");
    assert_eq!(asked.indicator().unwrap(), Indicator::Ofli);
    assert!(
        chaoscope::spec::MapKind::all()
            .iter()
            .any(|k| k.name() == "ofli")
    );
    let s = LyapunovSpec {
        grid: Grid::square(12),
        ..spec(Params::default(), 2.0)
    };
    s.validate().unwrap();
    let cpu = Engine::new(chaoscope::engine::Backend::Cpu).unwrap();
    let map = cpu.map(&s, &Monitor::hidden()).unwrap();
    assert!(map.data.iter().all(|x| x.is_finite()), "{:?}", map.data);
    let fli = cpu
        .map(
            &LyapunovSpec {
                indicator: Indicator::Fli,
                ..s
            },
            &Monitor::hidden(),
        )
        .unwrap();
    // Pixel by pixel, OFLI <= FLI (f32's rounding of both: 1e-6 of values near 1).
    for (o, f) in map.data.iter().zip(&fli.data) {
        assert!(o <= &(f + 1e-5), "{o} > {f}");
    }
    // And through the command line: a map, and a single start's running columns.
    let run = |args: &[&str]| {
        let out = common::chaoscope().args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{args:?}: {stderr}");
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("ofli.png");
    let flags = "lyapunov --size 8 --t-max 1 --indicator ofli --backend cpu --output";
    let mut args: Vec<&str> = flags.split(' ').collect();
    args.push(png.to_str().unwrap());
    run(&args);
    let command = common::png_text(&png, "chaoscope:command");
    assert!(command.contains("--indicator ofli"), "{command}");
    let csv = run(&[
        "lyapunov",
        "--theta1",
        "2",
        "--theta2",
        "1",
        "--t-max",
        "1",
        "--indicator",
        "ofli",
    ]);
    assert!(csv.lines().any(|l| l == "t,ofli,fli"), "{csv}");
}
