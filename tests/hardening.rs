//! The audit's cases (issue 14), each kept as a test named after what it guards.

mod common;

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use chaoscope::model::State;
use chaoscope::params::Preset;
use chaoscope::spec::{Stepping, largest_stable_dt, speed_bound};
use common::{argv, chaoscope, png_text, read_npy};
use predicates::prelude::*;

#[test]
fn a_bogus_adapter_name_falls_back_instead_of_panicking() {
    let dir = tempfile::tempdir().unwrap();
    chaoscope()
        .env("WGPU_ADAPTER_NAME", "bogus")
        .args(["flip", "--size", "8", "--t-max", "1", "--output"])
        .arg(dir.path().join("a.png"))
        .assert()
        .success()
        .stderr(predicate::str::contains("no GPU adapter found"));
    chaoscope()
        .env("WGPU_ADAPTER_NAME", "bogus")
        .arg("info")
        .assert()
        .success()
        .stdout(predicate::str::contains("chosen: none"));
    chaoscope()
        .env("WGPU_ADAPTER_NAME", "bogus")
        .args(["flip", "--size", "8", "--backend", "gpu", "--output"])
        .arg(dir.path().join("b.png"))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("no GPU adapter"));
}

#[test]
fn a_fit_on_absurd_time_steps_ends() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("tiny.csv");
    let mut text = String::from("t,x1,y1,x2,y2\n");
    for k in 0..40 {
        let a = 0.1 * k as f64;
        let (x1, y1) = (0.3 * a.sin(), -0.3 * a.cos());
        text += &format!(
            "{:e},{x1},{y1},{},{}\n",
            k as f64 * 1e-155,
            x1 + 0.2,
            y1 - 0.1
        );
    }
    std::fs::write(&csv, text).unwrap();
    // It used to loop forever plotting a non-finite energy range; now the file is refused
    // (any clean end would do).
    let out = chaoscope()
        .arg("fit")
        .arg(&csv)
        .args(["--candidates", "64", "--backend", "cpu", "--output"])
        .arg(dir.path().join("out"))
        .timeout(Duration::from_secs(120))
        .output()
        .unwrap();
    assert!(
        matches!(out.status.code(), Some(0..=2)),
        "{:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Starts `args`, sends `signal` after `after`, and expects exit 130 within a few seconds,
/// no temporary file in `dir`, and no file at all unless `keeps` (a sweep keeps its finished
/// frames, to resume).
fn stops_on(signal: &str, dir: &Path, args: &[&str], after: Duration, keeps: bool) {
    let bin = assert_cmd::cargo::cargo_bin("chaoscope");
    // Its words kept outside `dir` (which must hold nothing the command did not write), to
    // say why a command ended before it was stopped.
    let said = tempfile::NamedTempFile::new().unwrap();
    let mut child = std::process::Command::new(bin)
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::null())
        .stderr(said.reopen().unwrap())
        .spawn()
        .unwrap();
    std::thread::sleep(after);
    if let Some(status) = child.try_wait().unwrap() {
        let words = std::fs::read_to_string(said.path()).unwrap_or_default();
        panic!("{args:?} ended before the {signal} ({status}): make it longer\n{words}");
    }
    let sent = Instant::now();
    std::process::Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        // A second is the target; the machine may be loaded, so allow a few.
        assert!(
            sent.elapsed() < Duration::from_secs(5),
            "{args:?} ignored {signal}"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(130), "{args:?} after {signal}");
    let left = common::walk(dir);
    assert!(
        !left.iter().any(|f| f.contains(".chaoscope-")),
        "{args:?} left temporary files {left:?}"
    );
    assert!(keeps || left.is_empty(), "{args:?} left {left:?}");
}

#[test]
fn ctrl_c_and_sigterm_stop_long_commands_without_leaving_files() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv");
    let data = data.to_str().unwrap();
    let cases: Vec<(&str, Vec<&str>, bool)> = vec![
        (
            "TERM",
            argv(
                "traces --theta1 2 --theta2 2 --runs 100000 --backend cpu --output @/a.png --film @/a.gif",
            ),
            false,
        ),
        (
            "INT",
            argv(
                "zoom --to -1.689,0.742,1e-3 --frames 50 --output @/z flip --size 128 --backend cpu",
            ),
            true,
        ),
        (
            "INT",
            argv("phase --runs 100000 --backend cpu --output @/a.png"),
            false,
        ),
        (
            "TERM",
            argv(
                "lyapunov --theta1 2 --theta2 2 --dt 1e-4 --t-max 1000 --backend cpu --output @/a.csv",
            ),
            false,
        ),
        (
            "INT",
            argv("flip --size 600 --t-max 30 --backend cpu --output @/a.png"),
            false,
        ),
        (
            "TERM",
            argv("lyapunov --size 200 --backend cpu --output @/a.png"),
            false,
        ),
        (
            "INT",
            vec![
                "fit",
                data,
                "--preset",
                "lab",
                "--candidates",
                "4000000",
                "--backend",
                "cpu",
                "--output",
                "@/out",
            ],
            false,
        ),
        (
            "TERM",
            argv("sweep --vary g=5:15 --frames 50 --size 128 --backend cpu --output @/s"),
            true,
        ),
        (
            "INT",
            argv(
                "lyapunov --theta1 2 --theta2 2 --dt 1e-4 --t-max 1600 --backend gpu --output @/a.csv",
            ),
            false,
        ),
        // Stopped while FFmpeg encodes the film (600 frames of 720 px: some 10 s): FFmpeg is
        // stopped too, and its half film removed.
        (
            "INT",
            argv(
                "traces --theta1 2 --theta2 2 --runs 3 --exposure 20 --size 720 --fps 30 --backend cpu --output @/a.png --film @/a.mp4",
            ),
            false,
        ),
    ];
    for (signal, args, keeps) in cases {
        if args.contains(&"gpu") && common::gpu().is_none() {
            continue;
        }
        let dir = tempfile::tempdir().unwrap();
        let at = dir.path().display().to_string();
        let args: Vec<String> = args.iter().map(|a| a.replace('@', &at)).collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        stops_on(
            signal,
            dir.path(),
            &args,
            Duration::from_millis(1500),
            keeps,
        );
    }
}

/// A long recording's motion is identified with the monitor checked between blocks of rows
/// (before, a million rows held Ctrl-C for 11 s while their velocities were differentiated):
/// `fit` of a million rows stops within the few seconds `stops_on` allows.
#[test]
fn ctrl_c_stops_the_identification_of_a_long_recording() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("long.csv");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&csv).unwrap());
    writeln!(w, "t,x1,y1,x2,y2").unwrap();
    for k in 0..1_000_000 {
        let t = k as f64 / 1000.0;
        let (a, b) = (0.8 * (4.1 * t).sin(), 1.1 * (6.3 * t + 1.0).sin());
        let (x1, y1) = (0.3 * a.sin(), -0.3 * a.cos());
        let (x2, y2) = (x1 + 0.2 * b.sin(), y1 - 0.2 * b.cos());
        writeln!(w, "{t:.3},{x1:.6},{y1:.6},{x2:.6},{y2:.6}").unwrap();
    }
    drop(w);
    let outputs = dir.path().join("outputs");
    std::fs::create_dir(&outputs).unwrap();
    let out = outputs.join("fit");
    let args = [
        "fit",
        csv.to_str().unwrap(),
        "--held-out",
        "0",
        "--backend",
        "cpu",
        "--output",
        out.to_str().unwrap(),
    ];
    stops_on("INT", &outputs, &args, Duration::from_millis(2500), false);
}

#[test]
fn outputs_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    std::fs::write(&file, "x").unwrap();
    let started = Instant::now();
    chaoscope()
        .args(["flip", "--size", "1024", "--t-max", "30", "--output"])
        .arg(file.join("o.png"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--output").and(predicate::str::contains("plain-file")));
    // The refusal comes before the ~2 s map.
    assert!(
        started.elapsed() < Duration::from_secs(1),
        "{:?}",
        started.elapsed()
    );
    // A --data that cannot be written: no PNG either.
    let png = dir.path().join("m.png");
    chaoscope()
        .args(["flip", "--size", "8", "--t-max", "1", "--output"])
        .arg(&png)
        .arg("--data")
        .arg(dir.path())
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--data"));
    assert!(!png.exists());
}

#[test]
fn an_unstable_step_is_refused_naming_dt_and_the_limit() {
    for args in [
        vec!["flip", "--preset", "lab", "--joint-damping", "1"],
        vec!["flip", "--dt", "2", "--t-max", "4"],
        vec!["flip", "--omega1", "1e6"],
        vec!["lyapunov", "--preset", "lab", "--joint-damping", "2"],
        argv("trajectory --theta1 1 --theta2 1 --dt 0.5"),
    ] {
        chaoscope()
            .args(&args)
            .assert()
            .code(2)
            .stderr(predicate::str::contains("--dt").and(predicate::str::contains("unstable")));
    }
}

/// The limit is RK4's: just above it the damped lab pendulum's energy grows, just below it
/// decays; and an undamped small swing gives 2 sqrt(2) / omega of the fast mode.
#[test]
fn the_stability_limit_is_where_rk4_starts_to_blow_up() {
    let mut p = Preset::Lab.params();
    p.losses.joint1 = 1.0;
    p.losses.joint2 = 1.0;
    let limit = largest_stable_dt(&p);
    let energy_after = |dt: f64| {
        let start = State::at_rest(0.3, 0.3);
        let steps = Stepping { dt, t_max: 2.0 }.steps();
        let run = chaoscope::cpu::trajectory(&p, start, dt, steps);
        p.energy(run.last().unwrap()) - p.energy(&State::at_rest(0.0, 0.0))
    };
    // Released from rest with the arms aligned (D = 0, where the mass matrix is nearest
    // singular and the fast mode fastest: the configuration that sets the limit).
    let start = p.energy(&State::at_rest(0.3, 0.3)) - p.energy(&State::at_rest(0.0, 0.0));
    let (below, above) = (energy_after(0.95 * limit), energy_after(1.05 * limit));
    // Damping only takes energy: below the limit it has fallen; above it the fast mode's
    // amplification |R(lambda dt)| > 1 compounds over the ~1000 steps into a blow-up.
    assert!(
        (0.0..start).contains(&below),
        "below the limit: {below} J above rest, from {start}"
    );
    assert!(
        above.partial_cmp(&start) != Some(std::cmp::Ordering::Less),
        "above the limit: {above} J above rest, from {start}"
    );
    let q = chaoscope::model::Params::default();
    let (_, fast) = q.normal_modes_squared();
    // Bisection to 2^-60 of the bracket; the worst relative angle is D = 0 for the fast mode.
    let expected = 2.0 * std::f64::consts::SQRT_2 / fast.sqrt();
    assert!(
        (largest_stable_dt(&q) - expected).abs() < 1e-9 * expected,
        "{} vs {expected}",
        largest_stable_dt(&q)
    );
    // Any speed the energy bound allows is never exceeded on a chaotic run.
    let start = State::at_rest(2.9, 2.9);
    let bound = speed_bound(&q, 0.0, 0.0);
    let run = chaoscope::cpu::trajectory(&q, start, 0.005, 4000);
    let fastest = run
        .iter()
        .map(|s| s.omega1.abs().max(s.omega2.abs()))
        .fold(0.0, f64::max);
    assert!(fastest <= bound, "{fastest} > {bound}");
}

#[test]
fn masses_scale_out_of_gpu_maps_and_nan_pixels_are_nan() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let flipped = |extra: &[&str], name: &str| {
        let npy = dir.path().join(format!("{name}.npy"));
        chaoscope()
            .args(["flip", "--size", "64", "--t-max", "10", "--backend", "gpu"])
            .args(extra)
            .arg("--output")
            .arg(dir.path().join(format!("{name}.png")))
            .arg("--data")
            .arg(&npy)
            .assert()
            .success();
        let (_, data) = read_npy(&npy);
        assert!(data.iter().all(|t| !t.is_nan()), "{name}: NaN pixels");
        data.iter().filter(|t| t.is_finite()).count() as f64 / data.len() as f64
    };
    let unit = flipped(&[], "unit");
    // Masses drop out of the motion; a power of two scales the GPU's coefficients exactly.
    for (m, name) in [("1e19", "heavy"), ("1e-19", "light")] {
        let other = flipped(&["--m1", m, "--m2", m], name);
        // Same motion, coefficients rounded differently to f32: the chaotic pixels may move.
        assert!((other - unit).abs() < 0.02, "{name}: {other} vs {unit}");
    }
}

#[test]
fn maps_finer_than_f32_run_in_f64_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let (png, npy) = (dir.path().join("z.png"), dir.path().join("z.npy"));
    let assert = chaoscope()
        .args(
            "flip --size 64x4 --theta1 2.4:2.400001 --theta2 2:2.000001 --t-max 5 --output"
                .split(' '),
        )
        .arg(&png)
        .arg("--data")
        .arg(&npy)
        .assert()
        .success();
    if common::gpu().is_some() {
        // On the GPU when it has f64 (lavapipe does), else on the CPU.
        assert.stderr(predicate::str::contains("in f64"));
    }
    let backend = png_text(&png, "chaoscope:backend");
    assert!(backend == "cpu" || backend == "gpu f64", "{backend}");
    let (_, data) = read_npy(&npy);
    let mut row: Vec<u32> = data[..64].iter().map(|t| t.to_bits()).collect();
    row.sort();
    row.dedup();
    // f32 starts collapse these 64 columns onto about 5 angles; in f64 the flip time varies
    // smoothly across them.
    assert!(
        row.len() >= 32,
        "{} distinct flip times in a row of 64",
        row.len()
    );
}

fn data_of_lab() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv")
}

#[test]
fn bad_inputs_are_refused_naming_their_flag() {
    let dir = tempfile::tempdir().unwrap();
    let line = dir.path().join("line.csv");
    let mut text = String::from("t,x1,y1,x2,y2\n");
    for k in 0..20 {
        let x = 0.01 * k as f64;
        text += &format!(
            "{},{x},{},{x},{}\n",
            k as f64 / 3.0,
            -0.3 + 0.001 * k as f64,
            -0.5
        );
    }
    std::fs::write(&line, text).unwrap();
    // Issue 25's fit findings: a header naming `t` twice, and times of 1e300 s.
    let lab = std::fs::read_to_string(data_of_lab()).unwrap();
    let twice = dir.path().join("twice.csv");
    std::fs::write(&twice, lab.replace("t,x1,y1,x2,y2", "t,x1,y1,x2,y2,t")).unwrap();
    let huge = dir.path().join("huge.csv");
    let mut text = String::from("t,x1,y1,x2,y2\n");
    for k in 1..20 {
        text += &format!("{}e300,0.1,-0.3,0.2,-0.5\n", k);
    }
    std::fs::write(&huge, text).unwrap();
    let toml3 = dir.path().join("three.toml");
    std::fs::write(&toml3, "rod_mass = [0.1, 0.2, 0.3]\n").unwrap();
    let no_area = dir.path().join("no-area.toml");
    std::fs::write(&no_area, "[air_drag]\nrho = 1.2\n").unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv");
    let out = dir.path().join("out");
    let png = dir.path().join("x.png");
    let p = |x: &Path| x.display().to_string();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["fit".into(), p(&data), "--start".into(), "nan".into()],
            "--start",
        ),
        (vec!["fit".into(), p(&line)], "FILE"),
        (vec!["fit".into(), p(&twice)], "`t` twice"),
        (vec!["fit".into(), p(&huge)], "are the times in seconds"),
        (
            vec!["fit".into(), p(&data), "--start".into(), "-1".into()],
            "--start",
        ),
        (
            vec!["fit".into(), p(&data), "--start".into(), "1e300".into()],
            "--start",
        ),
        (
            vec!["phase".into(), "--spread".into(), "nan".into()],
            "--spread",
        ),
        (
            vec!["flip".into(), "--params".into(), p(&toml3)],
            "rod_mass",
        ),
        (
            vec!["flip".into(), "--params".into(), p(&no_area)],
            "--params",
        ),
        (
            vec![
                "sweep".into(),
                "--vary".into(),
                "g=1:2".into(),
                "--fps".into(),
                "0.001".into(),
            ],
            "--fps",
        ),
        (
            vec![
                "sweep".into(),
                "--zoom-to".into(),
                "1,1".into(),
                "--zoom".into(),
                "1e20".into(),
            ],
            "--zoom",
        ),
        (
            vec![
                "trajectory".into(),
                "--theta1".into(),
                "1".into(),
                "--theta2".into(),
                "1".into(),
            ],
            "--output",
        ),
    ];
    for (args, flag) in cases {
        chaoscope()
            .args(&args)
            .args(["--backend", "cpu", "--output"])
            // Directories for fit and sweep, files for the rest (the trajectory's is wrong).
            .arg(if ["fit", "sweep"].contains(&args[0].as_str()) {
                p(&out)
            } else {
                p(&png)
            })
            .assert()
            .code(2)
            .stderr(predicate::str::contains(flag));
    }
    assert!(!out.exists() && !png.exists(), "nothing written");
    // A byte-order mark before the header is not part of the column `t`.
    let bom = dir.path().join("bom.csv");
    let mut bytes = vec![0xef, 0xbb, 0xbf];
    bytes.extend(std::fs::read(&data).unwrap());
    std::fs::write(&bom, bytes).unwrap();
    chaoscope()
        .arg("fit")
        .arg(&bom)
        .args("--preset lab --candidates 64 --backend cpu --output".split(' '))
        .arg(&out)
        .assert()
        .success();
}

#[test]
fn negative_and_missing_values_name_the_flag() {
    let cases: &[(&[&str], &str)] = &[
        (&["flip", "--size", "-1"], "--size"),
        (
            &["traces", "--theta1", "1", "--theta2", "1", "--runs", "-5"],
            "--runs",
        ),
        (
            &["traces", "--theta1", "1", "--theta2", "1", "--size", "-5"],
            "--size",
        ),
        (&["phase", "--size", "-1"], "--size"),
        (&["phase", "--runs", "-1"], "--runs"),
        (&["sweep", "--vary", "g=1:2", "--frames", "-1"], "--frames"),
        (&["sweep", "--zoom-to", "1,1", "--zoom", "-2"], "--zoom"),
        (&["sweep", "--vary", "g=1:2", "--fps", "-1"], "--fps"),
        (&["fit", "x.csv", "--candidates", "-1"], "--candidates"),
        (&["fit", "x.csv", "--window", "-1"], "--window"),
        (&["fit", "x.csv", "--tolerance", "-1"], "--tolerance"),
        (&["bench", "--repeat", "-1"], "--repeat"),
        (&["bench", "--size", "-1"], "--size"),
        (&["bench", "--accurate-t-max", "-1"], "--accurate-t-max"),
        (&["flip", "--integrator", "dp54", "--rtol", "-1"], "--rtol"),
        (&["flip", "--l1", "--cw", "2"], "--l1"),
        (&["flip", "--dt", "--t-max", "2"], "--dt"),
    ];
    for (args, flag) in cases {
        chaoscope()
            .args(*args)
            .assert()
            .code(2)
            .stderr(predicate::str::contains(*flag));
    }
    chaoscope()
        .args(["flip", "--l1", "--cw", "2"])
        .assert()
        .stderr(predicate::str::contains("a value is required"));
}

#[cfg(unix)]
#[test]
fn outputs_take_the_users_umask() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let bin = assert_cmd::cargo::cargo_bin("chaoscope");
    for (umask, mode) in [("022", 0o644), ("077", 0o600)] {
        let png = dir.path().join(format!("u{umask}.png"));
        let status = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!(
                "umask {umask} && exec \"$0\" flip --size 8 --t-max 1 --backend cpu --output \"$1\""
            ))
            .arg(&bin)
            .arg(&png)
            .status()
            .unwrap();
        assert!(status.success());
        let got = std::fs::metadata(&png).unwrap().permissions().mode() & 0o777;
        assert_eq!(got, mode, "umask {umask}");
    }
}

#[test]
fn completions_and_the_bench_peers_directory() {
    chaoscope()
        .args(["completions", "bash"])
        .assert()
        .success()
        .stdout(predicate::str::contains("chaoscope"));
    let started = Instant::now();
    chaoscope()
        .args(["bench", "--peers", "/no/such/dir"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--peers"));
    assert!(
        started.elapsed() < Duration::from_secs(2),
        "checked before timing"
    );
}

/// The memory estimate reads the process's own limit (here `ulimit -v`), not only what the
/// machine has free: a map that cannot fit is refused before any work.
#[cfg(unix)]
#[test]
fn a_map_larger_than_the_process_may_take_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let bin = assert_cmd::cargo::cargo_bin("chaoscope");
    let started = Instant::now();
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 1300000 && exec \"$0\" flip --size 16384 --backend cpu --output \"$1\"")
        .arg(&bin)
        .arg(dir.path().join("big.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--size") && stderr.contains("MiB"),
        "{stderr}"
    );
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "refused before the work"
    );
}

/// Issue 25's audit: physics whose coefficients overflow (`--m1 1e308`, in flags, in a
/// `--params` file, in `sweep --vary`, on every command) ran nalgebra's unbounded Schur
/// decomposition in the stability analysis until SIGKILL, deaf to Ctrl-C and `timeout`. Each
/// is now refused up front, exit 2 naming the flag and its range, well within a 10 s bound.
#[test]
fn overflowing_physics_is_refused_at_once_on_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("big.toml");
    std::fs::write(&toml, "m1 = 1e308\n").unwrap();
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let map = ["flip", "--size", "16", "--t-max", "1", "--output"];
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["--m1", "1e308"], "--m1"),
        (vec!["--l1", "1e155"], "--l1"),
        (vec!["--m2", "1e300"], "--m2"),
        (vec!["--g", "1e308"], "--g"),
        (vec!["--rod-mass", "1e308"], "--rod-mass"),
        (vec!["--bearing-friction", "1e308"], "--bearing-friction"),
        (vec!["--joint-damping", "1e308"], "--joint-damping"),
        (vec!["--m1", "1e-300"], "--m1"),
        (
            vec!["--bearing-friction", "0.001", "--bearing-radius", "0"],
            "--bearing-radius",
        ),
        (vec!["--params", &toml.to_string_lossy()], "--params"),
    ]
    .into_iter()
    .map(|(extra, flag)| {
        let mut args: Vec<String> = map.iter().map(|s| s.to_string()).collect();
        args.push(out("m.png"));
        args.extend(extra.into_iter().map(String::from));
        (args, flag)
    })
    .chain([
        (
            [
                "sweep",
                "--vary",
                "m1=1:1e308",
                "--frames",
                "2",
                "--size",
                "8",
                "--output",
            ]
            .map(String::from)
            .into_iter()
            .chain([out("sweep")])
            .collect(),
            "--vary",
        ),
        (
            [
                "lyapunov", "--size", "8", "--t-max", "1", "--omega1", "1e300", "--output",
            ]
            .map(String::from)
            .into_iter()
            .chain([out("l.png")])
            .collect(),
            "--omega1",
        ),
        (
            [
                "trajectory",
                "--theta1",
                "1",
                "--theta2",
                "1",
                "--l2",
                "1e155",
            ]
            .map(String::from)
            .to_vec(),
            "--l2",
        ),
        (
            [
                "traces", "--theta1", "1", "--theta2", "1", "--g", "1e308", "--output",
            ]
            .map(String::from)
            .into_iter()
            .chain([out("t.png")])
            .collect(),
            "--g",
        ),
    ])
    .collect();
    for (args, flag) in cases {
        let started = Instant::now();
        chaoscope()
            .args(&args)
            .timeout(Duration::from_secs(10))
            .assert()
            .code(2)
            .stderr(predicate::str::contains(format!(
                "invalid value for {flag}"
            )));
        assert!(started.elapsed() < Duration::from_secs(10), "{args:?}");
    }
}

/// Issue 25's smaller findings: a completion script written to a full device is an error,
/// not a panic; the verdict's mask cannot overwrite the map it judges; a tolerance too loose
/// in f64 is not answered with advice to use f64.
#[test]
fn small_findings_of_the_audit() {
    if Path::new("/dev/full").exists() {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = std::process::Command::new(assert_cmd::cargo::cargo_bin("chaoscope"))
            .args(["completions", "bash"])
            .stdout(full)
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{said}");
        assert!(
            said.contains("No space left") && !said.contains("panicked"),
            "{said}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("x.npy");
    chaoscope()
        .args(["flip", "--size", "8", "--t-max", "1", "--output"])
        .arg(dir.path().join("x.png"))
        .arg("--data")
        .arg(&npy)
        .arg("--resolved")
        .arg(&npy)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--resolved"));
    assert!(!npy.exists(), "nothing written");
    chaoscope()
        .args(["flip", "--size", "8", "--t-max", "1", "--backend", "cpu"])
        .args("--integrator dp54 --rtol 1 --precision f64 --output".split(' '))
        .arg(dir.path().join("y.png"))
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("--rtol")
                .and(predicate::str::contains("use --precision f64").not()),
        );
}

/// Issue 25's audit: `status --json` and `serve --json` printed other lines beside the JSON,
/// `completions --json` printed no JSON. With --json, standard output now holds JSON alone
/// (status's words go to standard error; serve's URL comes as `{"url": ...}`), and
/// completions refuses --json naming it.
#[test]
fn json_output_is_json_alone() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    chaoscope()
        .args(["flip", "--size", "32", "--t-max", "1", "--data"])
        .arg(&store)
        .assert()
        .success();
    let out = chaoscope()
        .args(["--json", "status"])
        .arg(&store)
        .output()
        .unwrap();
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    for line in stdout.lines() {
        serde_json::from_str::<serde_json::Value>(line)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {line}"));
    }
    assert!(String::from_utf8_lossy(&out.stderr).contains("complete"));
    chaoscope()
        .args(["--json", "completions", "bash"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--json"));
    let mut serve = std::process::Command::new(assert_cmd::cargo::cargo_bin("chaoscope"))
        .args(["--json", "serve", "--port", "0", "--backend", "cpu"])
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(serve.stdout.take().unwrap()),
        &mut first,
    )
    .unwrap();
    serve.kill().unwrap();
    serve.wait().unwrap();
    let ready: serde_json::Value = serde_json::from_str(&first).unwrap();
    assert!(
        ready["url"]
            .as_str()
            .unwrap()
            .starts_with("http://127.0.0.1:"),
        "{first}"
    );
}

#[test]
fn a_motion_too_slow_blames_what_the_user_gave() {
    let dir = tempfile::tempdir().unwrap();
    // A swing sampled every 10 ms, its times written in milliseconds: to the reader a
    // pendulum turning a thousand times too slowly.
    let swing = |k: usize| {
        let t = k as f64 * 0.01;
        let (a, b) = (0.8 * (4.1 * t).sin(), 1.1 * (6.3 * t + 1.0).sin());
        let (x1, y1) = (0.3 * a.sin(), -0.3 * a.cos());
        (x1, y1, x1 + 0.2 * b.sin(), y1 - 0.2 * b.cos())
    };
    let (mut ms, mut frames) = (
        String::from("t,x1,y1,x2,y2\n"),
        String::from("frame,x1,y1,x2,y2\n"),
    );
    for k in 0..300 {
        let (x1, y1, x2, y2) = swing(k);
        ms += &format!("{},{x1},{y1},{x2},{y2}\n", k * 10);
        frames += &format!("{k},{x1},{y1},{x2},{y2}\n");
    }
    std::fs::write(dir.path().join("ms.csv"), ms).unwrap();
    std::fs::write(dir.path().join("frames.csv"), frames).unwrap();
    // No frame rate was given: the file's times are named, not the flag.
    chaoscope()
        .current_dir(dir.path())
        .args(["fit", "ms.csv", "--held-out", "0", "--output", "a"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("FILE").and(predicate::str::contains("not in seconds")))
        .stderr(predicate::str::contains("--frame-rate").not());
    // Frames at 0.1 a second (100 frames a second meant): the frame rate is named.
    chaoscope()
        .current_dir(dir.path())
        .args([
            "fit",
            "frames.csv",
            "--frame-rate",
            "0.1",
            "--held-out",
            "0",
            "--output",
            "b",
        ])
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("--frame-rate")
                .and(predicate::str::contains("0.1 frames a second")),
        );
}
