//! The binary end to end in a temporary directory.

mod common;

use common::{chaoscope, png_text, read_npy};

use predicates::prelude::*;

#[test]
fn flip_writes_a_png_and_npy_of_the_right_shape() {
    let dir = tempfile::tempdir().unwrap();
    let (png, npy) = (dir.path().join("m.png"), dir.path().join("m.npy"));
    // The CPU backend needs no adapter; the GPU path is the same command with --backend gpu.
    for backend in ["cpu", "gpu"] {
        if backend == "gpu" && common::gpu().is_none() {
            continue;
        }
        chaoscope()
            .args([
                "flip", "--size", "40x24", "--t-max", "3", "--theta1", "-pi:pi", "--theta2", "-3:3",
            ])
            .args(["--backend", backend, "--output"])
            .arg(&png)
            .arg("--data")
            .arg(&npy)
            .assert()
            .success();
        let (shape, data) = read_npy(&npy);
        assert_eq!(shape, vec![24, 40], "{backend}: (height, width)");
        assert!(
            data.iter().any(|t| t.is_finite()) && data.iter().any(|t| t.is_infinite()),
            "{backend}"
        );
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
        let reader = decoder.read_info().unwrap();
        let info = reader.info();
        assert_eq!((info.width, info.height), (40, 24));
        let command = info
            .uncompressed_latin1_text
            .iter()
            .find(|t| t.keyword == "chaoscope:command")
            .expect("run specification in the PNG")
            .text
            .clone();
        assert!(
            command.contains("--size 40x24") && command.contains(&format!("--backend {backend}")),
            "{command}"
        );
    }
    // Nothing but the two outputs: no temporary files left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn bad_values_exit_2_and_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad.png");
    let cases: &[(&[&str], &str)] = &[
        (&["--m1", "-1"], "--m1"),
        (&["--l2", "0"], "--l2"),
        (&["--theta1", "3:1"], "--theta1"),
        (&["--theta2", "-4:4"], "--theta2"),
        (&["--dt", "0"], "--dt"),
        (&["--t-max", "-5"], "--t-max"),
        (&["--size", "0"], "--size"),
        (&["--size", "65536x65536"], "--size"),
        (&["--size", "ten"], "--size"),
        (&["--g", "nan"], "--g"),
    ];
    for (args, flag) in cases {
        chaoscope()
            .args(["flip", "--backend", "cpu", "--output"])
            .arg(&out)
            .args(*args)
            .assert()
            .code(2)
            .stderr(predicate::str::contains(*flag));
        assert!(!out.exists(), "{args:?} left an output file");
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no partial files"
    );
}

#[test]
fn trajectory_csv_has_the_columns_and_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("t.csv");
    chaoscope()
        .args(
            "trajectory --theta1 pi/2 --theta2 -0.5 --omega1 -1 --t-max 1 --every 0.1 --output"
                .split(' '),
        )
        .arg(&csv)
        .assert()
        .success();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("# chaoscope trajectory --theta1 ")
    );
    assert_eq!(
        lines.next().unwrap(),
        "t,theta1,omega1,theta2,omega2,x1,y1,x2,y2,energy,dissipated"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 11, "t = 0, 0.1, ... 1");
    assert_eq!(
        rows[0][1],
        std::f64::consts::FRAC_PI_2,
        "shortest round-trip form reads back exactly"
    );
    assert_eq!(rows[0][2], -1.0);
    // The CSV's state reproduces the library's trajectory bit for bit.
    let p = chaoscope::model::Params::default();
    let start = chaoscope::model::State {
        theta1: std::f64::consts::FRAC_PI_2,
        omega1: -1.0,
        theta2: -0.5,
        omega2: 0.0,
    };
    let traj = chaoscope::cpu::trajectory(&p, start, 0.01, 100);
    assert_eq!(rows[10][1], traj[100].theta1);
    // Energy is conserved along the run to RK4's error, which on this energetic start at
    // dt 0.01 stays below 1e-4 of the energy scale over 1 s.
    let e: Vec<f64> = rows.iter().map(|r| r[9]).collect();
    assert!(e.iter().all(|v| (v - e[0]).abs() < 1e-4 * p.energy_scale()));
    assert!(
        rows.iter().all(|r| r[10] == 0.0),
        "no losses, nothing dissipated"
    );
    chaoscope()
        .args("trajectory --theta1 1 --theta2 1 --every 0.015".split(' '))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--every"));
}

#[test]
fn lyapunov_map_writes_png_and_npy_on_both_backends() {
    let dir = tempfile::tempdir().unwrap();
    let (png, npy) = (dir.path().join("l.png"), dir.path().join("l.npy"));
    let mut maps = Vec::new();
    for backend in ["cpu", "gpu"] {
        if backend == "gpu" && common::gpu().is_none() {
            continue;
        }
        chaoscope()
            .args([
                "lyapunov",
                "--size",
                "24x16",
                "--t-max",
                "5",
                "--backend",
                backend,
            ])
            .arg("--output")
            .arg(&png)
            .arg("--data")
            .arg(&npy)
            .assert()
            .success()
            .stderr(predicate::str::contains("chaotic"));
        let (shape, data) = read_npy(&npy);
        assert_eq!(shape, vec![16, 24], "{backend}: (height, width)");
        assert!(data.iter().all(|x| x.is_finite()), "{backend}");
        let command = png_text(&png, "chaoscope:command");
        assert!(
            command.contains("chaoscope lyapunov --size 24x16")
                && command.contains("--method tangent"),
            "{command}"
        );
        assert!(png_text(&png, "chaoscope:colour-range").contains("1/s"));
        maps.push(data);
    }
    // Both backends see the same picture. Over 5 s, f32 and f64 agree to ~1e-4 /s on
    // regular pixels (tests/lyapunov.rs); chaotic ones part after a few Lyapunov times and
    // may differ by more, so 90 % of pixels within 0.05 /s.
    if let [cpu, gpu] = &maps[..] {
        let close = cpu
            .iter()
            .zip(gpu)
            .filter(|(a, b)| (*a - *b).abs() < 0.05)
            .count();
        assert!(
            close * 10 >= cpu.len() * 9,
            "{close} of {} close",
            cpu.len()
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn lyapunov_single_point_writes_the_convergence_csv() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("conv.csv");
    chaoscope()
        .args([
            "lyapunov", "--theta1", "pi/2", "--theta2", "pi/2", "--t-max", "4", "--renorm", "0.5",
        ])
        .arg("--output")
        .arg(&csv)
        .assert()
        .success();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .is_some_and(|l| l.starts_with("# chaoscope lyapunov --theta1 ")),
        "the command line first"
    );
    assert_eq!(lines.next(), Some("t,ftle"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let (t, f) = l.split_once(',').unwrap();
            (t.parse().unwrap(), f.parse().unwrap())
        })
        .collect();
    // One row per renormalisation; the last is the exponent at t-max, equal to the library's.
    assert_eq!(rows.len(), 8);
    assert!((rows[7].0 - 4.0).abs() < 1e-12);
    let spec = chaoscope::spec::LyapunovSpec {
        params: chaoscope::model::Params::default(),
        grid: chaoscope::spec::Grid::square(1),
        stepping: chaoscope::spec::Stepping {
            dt: 0.01,
            t_max: 4.0,
        },
        method: chaoscope::spec::Method::Tangent,
        renorm: 0.5,
        use_symmetry: true,
        precision: chaoscope::spec::Precision::F32,
        band: None,
        integrator: chaoscope::spec::Integrator::Rk4,
        indicator: chaoscope::spec::Indicator::Ftle,
    };
    let start =
        chaoscope::model::State::at_rest(std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);
    assert_eq!(rows[7].1, chaoscope::cpu::ftle(&spec, start).last());
}

#[test]
fn lyapunov_bad_values_exit_2_and_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad.png");
    let cases: &[(&[&str], &str)] = &[
        (&["--renorm", "0.015"], "--renorm"),
        (&["--renorm", "0"], "--renorm"),
        (&["--renorm", "50"], "--renorm"),
        (&["--method", "twin", "--eps", "0"], "--eps"),
        (&["--theta1", "1.0"], "--theta2"),
        (&["--theta1", "-pi:pi", "--theta2", "0.5"], "--theta1"),
        (&["--m2", "0"], "--m2"),
    ];
    for (args, flag) in cases {
        chaoscope()
            .args("lyapunov --size 8 --t-max 2 --backend cpu --output".split(' '))
            .arg(&out)
            .args(*args)
            .assert()
            .code(2)
            .stderr(predicate::str::contains(*flag));
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no partial files"
    );
}

#[test]
fn bench_reports_every_mode_of_both_paths() {
    if common::gpu().is_none() {
        return;
    }
    let out = chaoscope()
        .args(["bench", "--size", "32", "--cpu-size", "8", "--t-max", "0.5"])
        .args(["--repeat", "1"])
        .args(["--accurate-size", "16", "--accurate-t-max", "3"])
        .args(["--forecast-members", "256"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).unwrap();
    // The forecast's row, and its sentence.
    assert!(
        text.lines()
            .any(|l| l.starts_with("chaoscope gpu forecast") && l.contains("forecast")),
        "no forecast row:\n{text}"
    );
    assert!(text.contains("forecast: the ensemble"), "{text}");
    for mode in ["early", "early-all", "full", "full-half"] {
        assert!(
            text.lines()
                .any(|l| l.starts_with("chaoscope gpu") && l.split_whitespace().any(|w| w == mode)),
            "no GPU row for {mode}:\n{text}"
        );
    }
    assert!(
        text.lines().any(|l| l.starts_with("chaoscope cpu")),
        "{text}"
    );
    // The accurate-map rows, each with the share of its pixels the reference confirms.
    for path in [
        "chaoscope --accurate",
        "chaoscope gpu f32 rk4",
        "chaoscope gpu f64 dop853",
    ] {
        assert!(
            text.lines()
                .any(|l| l.starts_with(path) && l.contains(" accurate ") && l.ends_with('%')),
            "no accurate row for {path}:\n{text}"
        );
    }
    // The divergence-map rows beside them, each with the share of its exponents confirmed.
    for path in [
        "chaoscope gpu f32 rk4",
        "chaoscope gpu f64 rk4",
        "chaoscope lyapunov --accurate",
    ] {
        assert!(
            text.lines()
                .any(|l| l.starts_with(path) && l.contains(" accurate-ftle ") && l.ends_with('%')),
            "no accurate-ftle row for {path}:\n{text}"
        );
    }
    assert!(
        text.contains("accurate divergence map: lyapunov --accurate agrees"),
        "{text}"
    );
}

#[test]
fn json_summaries_on_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("j.png");
    let out = chaoscope()
        .args("flip --size 16 --t-max 2 --backend cpu --json --output".split(' '))
        .arg(&png)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).expect("one JSON object");
    assert_eq!(v["command"], "flip");
    assert_eq!(v["width"], 16);
    assert_eq!(v["files"][0], png.display().to_string());
    assert!(
        v["flipped"]
            .as_f64()
            .is_some_and(|f| (0.0..=1.0).contains(&f))
    );
    assert!(v["seconds"].as_f64().is_some());
    let out = chaoscope()
        .args(["info", "--json"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).expect("one JSON object");
    assert!(v["adapters"].is_array(), "{v}");
    // Without --output the CSV itself is on standard output: no room for JSON.
    chaoscope()
        .args(["trajectory", "--theta1", "1", "--theta2", "1", "--json"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--json"));
    // A divergence map into a store has no CSV on standard output (it was refused as if it
    // were a single-point run): its summary counts the chaotic share, and a store has no
    // colour range.
    let store = dir.path().join("l.zarr");
    let out = chaoscope()
        .args("lyapunov --size 16 --t-max 1 --backend cpu".split(' '))
        .args(["--json", "--data"])
        .arg(&store)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let v: serde_json::Value = serde_json::from_slice(&out).expect("one JSON object");
    assert_eq!(v["command"], "lyapunov");
    assert!(
        v["chaotic"]
            .as_f64()
            .is_some_and(|f| (0.0..=1.0).contains(&f)),
        "{v}"
    );
    assert!(v["range"][0].is_null() && v.get("flipped").is_none(), "{v}");
}

/// Issue 25's audit: `--precision f32 --backend cpu` ran f64 without a word. Now it says so
/// (the CPU computes in f64 only), on every command with --precision; without --precision,
/// or with f64, nothing is said.
#[test]
fn f32_asked_of_the_cpu_is_said_to_run_in_f64() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let note = "--precision f32 is the GPU's; the CPU backend computes in f64";
    let map = [
        "--size",
        "8",
        "--t-max",
        "0.5",
        "--backend",
        "cpu",
        "--output",
    ];
    for (command, precision, said) in [
        ("flip", Some("f32"), true),
        ("flip", None, false),
        ("flip", Some("f64"), false),
        ("lyapunov", Some("f32"), true),
    ] {
        let mut run = chaoscope();
        run.arg(command).args(map).arg(&png);
        if let Some(p) = precision {
            run.args(["--precision", p]);
        }
        let out = run.output().unwrap();
        assert!(out.status.success(), "{command} {precision:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            stderr.contains(note),
            said,
            "{command} {precision:?}: {stderr}"
        );
    }
    // trajectory runs on the CPU by default.
    let out = chaoscope()
        .args("trajectory --theta1 1 --theta2 1 --t-max 0.1".split(' '))
        .args(["--precision", "f32", "--output"])
        .arg(dir.path().join("t.csv"))
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(note));
}

/// Every command that writes a file says so in one line (trajectory said nothing), and a
/// value the command rounds is said rounded (`boundary --pairs 2000` drew 2048 silently).
#[test]
fn trajectory_and_boundary_say_what_they_did() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("t.csv");
    common::chaoscope()
        .args("trajectory --theta1 1 --theta2 1 --t-max 1 --output".split(' '))
        .arg(&csv)
        .assert()
        .success()
        .stderr(predicate::str::contains(format!(
            "101 rows from t = 0 to 1 s -> {}",
            csv.display()
        )));
    common::chaoscope()
        .args([
            "boundary", "--t-max", "0.5", "--pairs", "300", "--levels", "3",
        ])
        .args(["--backend", "cpu", "--output"])
        .arg(dir.path().join("b.png"))
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "512 pairs a level drawn for the 300 asked",
        ));
}
