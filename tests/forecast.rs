//! Ensemble forecasts of tracked data (`forecast`, `twin`): members with their own joint
//! damping on both paths, twin experiments against a hidden truth (zero noise, calibration),
//! and the commands' refusals.

mod common;

use std::path::Path;

use chaoscope::app::twin::{self, TwinJob};
use chaoscope::cpu;
use chaoscope::engine::{Backend, Engine};
use chaoscope::fit::window::{STEPS_PER_SECOND, track, track_with};
use chaoscope::forecast::outcome::ForecastSettings;
use chaoscope::forecast::twin::{experiment, make_track};
use chaoscope::forecast::{ForecastSpec, forecast, stepping};
use chaoscope::model::{Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::params::{ParamSources, Preset};
use chaoscope::spec::{EnsembleSpec, Keep, Precision};
use common::chaoscope;

fn lab_with_damping() -> Params {
    let mut p = Preset::Lab.params();
    (p.losses.joint1, p.losses.joint2) = (1e-3, 1e-3);
    p
}

/// A chaotic release of the lab pendulum (the twin command's default).
const RELEASE: State = State {
    theta1: 2.0,
    omega1: 0.0,
    theta2: 2.5,
    omega2: 0.0,
};

/// 64 releases near RELEASE, each with its own joint damping (0 .. 0.01 N m s at each joint).
fn damped_members() -> (Vec<State>, Vec<(f64, f64)>) {
    let starts = (0..64)
        .map(|k| State {
            theta1: 2.0 + 0.01 * k as f64,
            ..RELEASE
        })
        .collect();
    let damping = (0..64)
        .map(|k| (0.01 * (k % 8) as f64 / 7.0, 0.01 * (k / 8) as f64 / 7.0))
        .collect();
    (starts, damping)
}

/// The GPU engine in `precision`.
fn gpu_engine(precision: Precision) -> Engine {
    Engine::new(Backend::Gpu)
        .unwrap()
        .with_precision(precision, Backend::Gpu)
        .unwrap()
}

/// Members with their own joint damping: the GPU's runs equal the CPU's member by member.
/// Damping 0 .. 0.01 N m s changes the angular velocities by ~1 rad/s over these 0.5 s,
/// far beyond the tolerances, so a member run with another's (or a wrongly scaled) damping
/// fails.
#[test]
fn per_member_damping_agrees_on_gpu_and_cpu() {
    if common::f64_gpu().is_none() {
        return;
    }
    let p = Preset::Lab.params();
    let (starts, damping) = damped_members();
    let (dt, steps, stride) = (1e-3, 500, 5);
    let run = |engine: &Engine| {
        let mut out = Vec::new();
        engine
            .ensemble(
                &EnsembleSpec::new(p, &starts, dt, steps)
                    .damped(&damping)
                    .keeping(Keep::Every(stride)),
                &Monitor::hidden(),
                |_, runs| {
                    out.extend(runs.into_states());
                    Ok(())
                },
            )
            .unwrap();
        out
    };
    let cpu = run(&Engine::new(Backend::Cpu).unwrap());
    // The damping matters: the least and most damped members part by far more than the
    // tolerances.
    let last = |k: usize| cpu[k].last().unwrap().omega2;
    assert!((last(0) - last(63)).abs() > 0.1, "damping changes nothing?");
    // f64: the GPU's carried cos and sin are another O(dt^4) discretisation of the same
    // motion (tests/precision.rs), here ~1e-7 at dt 1e-3 over 0.5 s of this fast release.
    let (f64_gpu, f32_gpu) = (gpu_engine(Precision::F64), gpu_engine(Precision::F32));
    // f32: 6e-8 per step over 500 steps, grown by e^(lambda t) < e^2: 1e-4 rad and rad/s.
    for (engine, tolerance) in [(f64_gpu, 1e-6), (f32_gpu, 1e-4)] {
        let runs = run(&engine);
        let worst = runs
            .iter()
            .zip(&cpu)
            .flat_map(|(a, b)| a.iter().zip(b))
            .flat_map(|(x, y)| (0..4).map(move |i| (x.to_array()[i] - y.to_array()[i]).abs()))
            .fold(0.0, f64::max);
        eprintln!("per-member damping, GPU against CPU: {worst:e} (tolerance {tolerance:e})");
        for (k, (a, b)) in runs.iter().zip(&cpu).enumerate() {
            for (x, y) in a.iter().zip(b) {
                let d = x
                    .to_array()
                    .iter()
                    .zip(y.to_array())
                    .map(|(u, v)| (u - v).abs())
                    .fold(0.0, f64::max);
                assert!(d < tolerance, "member {k}: GPU and CPU differ by {d}");
            }
        }
    }
}

/// The positions at `times` of the members `starts` with their own damping on `engine`,
/// gathered time-major (time, coordinate, member) from however many chunks came.
fn positions_on(
    engine: &Engine,
    p: &Params,
    starts: &[State],
    damping: &[(f64, f64)],
    (dt, steps): (f64, u32),
    times: &[f64],
) -> Vec<f32> {
    let m = starts.len();
    let mut all = vec![f32::NAN; 4 * times.len() * m];
    engine
        .ensemble(
            &EnsembleSpec::new(*p, starts, dt, steps)
                .damped(damping)
                .keeping(Keep::At(times)),
            &Monitor::hidden(),
            |first, chunk| {
                let v = chunk.positions();
                let n = v.len() / (4 * times.len());
                for (row, chunk) in all.chunks_mut(m).zip(v.chunks(n)) {
                    row[first..first + n].copy_from_slice(chunk);
                }
                Ok(())
            },
        )
        .unwrap();
    all
}

/// The forecast's positions at given times (`shaders/positions.wgsl`, its dispatches
/// writing into one buffer, against `cpu::positions`): member by member, at the start, on
/// steps, between them and at the end. The GPU interpolates the carried cos and sin, the
/// CPU the angles; both err by O(h^4), 1e-9 m at h = 1e-3 s, far below the tolerances.
#[test]
fn ensemble_positions_agree_on_gpu_and_cpu() {
    if common::f64_gpu().is_none() {
        return;
    }
    let p = Preset::Lab.params();
    let (starts, damping) = damped_members();
    let cpu_engine = Engine::new(Backend::Cpu).unwrap();
    let compare = |engine: &Engine, stepping: (f64, u32), times: &[f64], tolerance: f64| {
        let (a, b) = (
            positions_on(engine, &p, &starts, &damping, stepping, times),
            positions_on(&cpu_engine, &p, &starts, &damping, stepping, times),
        );
        // Time 0 is the start itself (to f32's rounding of an arm's length).
        let start = p.positions(&starts[5]);
        assert!(
            (b[5] as f64 - start.x1).abs() < 1e-7 && (b[3 * 64 + 5] as f64 - start.y2).abs() < 1e-7
        );
        let mut worst = 0f64;
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            let d = (x - y).abs() as f64;
            worst = worst.max(d);
            let (j, c, i) = (k / 256, k / 64 % 4, k % 64);
            assert!(
                d < tolerance,
                "t {}, coordinate {c}, member {i}: GPU {x} CPU {y}",
                times[j]
            );
        }
        eprintln!("positions, GPU against CPU: {worst:e} m (tolerance {tolerance:e})");
    };
    // 0.5 s in 500 steps: the start, a step's end, within steps, the end. The states agree to
    // 1e-6 (f64) and 1e-4 (f32) rad and rad/s (per_member_damping_agrees_on_gpu_and_cpu),
    // times the arms' 0.36 m, plus f32's rounding of the positions (3e-8 m).
    let times = [0.0, 1e-3, 0.0105, 0.1234, 0.25, 0.3333, 0.4999, 0.5];
    compare(&gpu_engine(Precision::F64), (1e-3, 500), &times, 1e-6);
    compare(&gpu_engine(Precision::F32), (1e-3, 500), &times, 4e-5);
    // 2^18 + 1 steps: a dispatch holds 63 members (STEPS_PER_DISPATCH 2^24), so a second
    // one writes the last member at its place. f64 only (f32 loses a step's tiny increments).
    let steps = (1 << 18) + 1;
    compare(
        &gpu_engine(Precision::F64),
        (0.5 / steps as f64, steps),
        &times,
        1e-6,
    );
}

/// A positions dispatch holds at most STEPS_PER_DISPATCH (2^24) pendulum-steps: 8400 members
/// of 2000 steps come in two (8388 + 12 members), writing into one buffer. The members of the
/// second (and of the first) run alone give the same positions bit for bit: each reads its own
/// start and damping and writes its own place.
#[test]
fn positions_of_each_dispatch_are_its_members_own() {
    if common::gpu().is_none() {
        return;
    }
    let p = Params::default();
    let m = 8400;
    let starts: Vec<State> = (0..m)
        .map(|i| State::at_rest(1.0 + 1e-4 * i as f64, 0.5))
        .collect();
    let damping: Vec<(f64, f64)> = (0..m).map(|i| (1e-2 * (i % 7) as f64, 0.0)).collect();
    let (stepping, times) = ((1e-3, 2000), [0.5, 1.0, 2.0]);
    let engine = gpu_engine(Precision::F32);
    let all = positions_on(&engine, &p, &starts, &damping, stepping, &times);
    for range in [0..16, m - 16..m] {
        let alone = positions_on(
            &engine,
            &p,
            &starts[range.clone()],
            &damping[range.clone()],
            stepping,
            &times,
        );
        for (row, own) in all.chunks(m).zip(alone.chunks(16)) {
            assert_eq!(&row[range.clone()], own, "members {range:?}");
        }
    }
}

/// One forecast on the CPU in several chunks (gathered before the bands) and on the f64 GPU
/// in one (its bands computed where the buffer is mapped): the same members, the same
/// tracking errors, so the bands differ only as the members' positions do. A quantile moves
/// by at most the largest change of any value (order statistics are 1-Lipschitz), and the
/// members differ by the two discretisations' O(dt^4) (carried cos and sin on the GPU),
/// ~1e-5 rad at 1/300 s over 1.5 s of this release (1e-7 at 1e-3 s, times 3.3^4), times
/// the arms' 0.36 m: 2e-5 m.
#[test]
fn forecast_bands_agree_on_gpu_and_cpu_across_chunks() {
    if common::f64_gpu().is_none() {
        return;
    }
    let truth = lab_with_damping();
    let track_ = make_track(&truth, RELEASE, 100.0, 1.5, 0.002, 1);
    let settings = ForecastSettings {
        window: Some((0.0, 1.0)),
        members: 16,
        seed: 1,
        tolerance: Some(0.03),
        tracking_error: None,
        candidates: 256,
        // The model is the truth here: no model error to measure.
        held_out: 0,
        ahead: None,
        in_sample: false,
    };
    let cpu_engine = Engine::new(Backend::Cpu).unwrap();
    let fit = experiment(
        &truth,
        RELEASE,
        &track_,
        &settings,
        1.5,
        &cpu_engine,
        &Monitor::hidden(),
    )
    .unwrap()
    .0
    .fit;
    let spec = ForecastSpec {
        members: 5000,
        seed: 3,
        tolerance: 0.03,
        tracking_error: 0.002,
        end: 1.5,
        data_times: track_.t.clone(),
        cadence: 0.0,
        model_error: None,
        band_factors: None,
    };
    let (_, steps) = stepping(fit.t0, spec.end);
    assert!(
        cpu_engine.ensemble_chunk(
            &EnsembleSpec::new(fit.params, &vec![RELEASE; spec.members], 1e-3, steps)
                .keeping(Keep::Every(steps))
        ) < spec.members,
        "the CPU forecast should come in several chunks"
    );
    let on = |engine: &Engine| forecast(&fit, 1.0, &spec, engine, &Monitor::hidden()).unwrap();
    let (cpu, gpu) = (on(&cpu_engine), on(&gpu_engine(Precision::F64)));
    assert_eq!(cpu.times, gpu.times);
    let mut worst = 0f64;
    for (bands_a, bands_b) in [(&cpu.model, &gpu.model), (&cpu.observed, &gpu.observed)] {
        for (k, (a, b)) in bands_a.iter().zip(bands_b).enumerate() {
            for (qa, qb) in a.iter().flatten().zip(b.iter().flatten()) {
                let d = (qa - qb).abs();
                worst = worst.max(d);
                assert!(d < 2e-5, "t {}: cpu {a:?} gpu {b:?}", cpu.times[k]);
            }
        }
    }
    eprintln!("bands, GPU (one chunk) against CPU (chunks): {worst:e} m");
}

/// The model's step (1/300 s) against a ten times finer one along the release over 1.5 s:
/// the integration error the zero-noise twin below allows for.
fn integration_error(p: &Params, t: &[f64]) -> f64 {
    let coarse = track(p, RELEASE, t);
    let fine = track_with(p, RELEASE, t, 10.0 * STEPS_PER_SECOND);
    coarse
        .iter()
        .zip(&fine)
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0, f64::max)
}

/// The truth at time `t` (s after the release), by RK4 at 1/3000 s.
fn truth_at(p: &Params, t: f64) -> State {
    let n = (t * 3000.0).ceil().max(1.0) as u32;
    (0..n).fold(RELEASE, |y, _| cpu::rk4_step(p, &y, t / n as f64))
}

/// The forecast places the members at the band's times by cubic Hermite interpolation
/// between their RK4 steps `h` apart: that interpolation applied to the truth's own states
/// (here as a sum of Bernstein polynomials) against the truth at `times`, the largest
/// position error.
fn interpolation_error(p: &Params, h: f64, times: &[f64]) -> f64 {
    times
        .iter()
        .map(|&t| {
            let k = (t / h).floor();
            let (a, b, s) = (truth_at(p, k * h), truth_at(p, (k + 1.0) * h), t / h - k);
            let bezier = |x0: f64, w0: f64, x1: f64, w1: f64| {
                let c = [x0, x0 + h * w0 / 3.0, x1 - h * w1 / 3.0, x1];
                let r = 1.0 - s;
                r * r * r * c[0]
                    + 3.0 * r * r * s * c[1]
                    + 3.0 * r * s * s * c[2]
                    + s * s * s * c[3]
            };
            let y = State {
                theta1: bezier(a.theta1, a.omega1, b.theta1, b.omega1),
                theta2: bezier(a.theta2, a.omega2, b.theta2, b.omega2),
                ..State::default()
            };
            let (q, e) = (p.positions(&y), p.positions(&truth_at(p, t)));
            [q.x1 - e.x1, q.y1 - e.y1, q.x2 - e.x2, q.y2 - e.y2]
                .into_iter()
                .map(f64::abs)
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// With zero noise and the true parameters the band holds the truth at every time after the
/// window (within the integration and interpolation errors), and the spread stays below the tolerance to the
/// end of a short track: the horizon lies beyond it.
#[test]
fn zero_noise_twin_holds_the_truth() {
    let truth = lab_with_damping();
    let track_ = make_track(&truth, RELEASE, 100.0, 1.5, 0.0, 1);
    let error = integration_error(&truth, &track_.t);
    eprintln!("the model's step against a ten times finer one: {error:e} m");
    // RK4 at 1/300 s: its error over 1.5 s of this chaotic release is micrometres.
    assert!(error < 1e-5, "the model's step errs by {error} m");
    let settings = ForecastSettings {
        window: Some((0.0, 1.0)),
        members: 200,
        seed: 1,
        tolerance: Some(0.03),
        tracking_error: None,
        candidates: 1024,
        // The model is the truth here: no model error to measure.
        held_out: 0,
        ahead: None,
        in_sample: false,
    };
    let engine = Engine::new(Backend::Cpu).unwrap();
    let (o, at) = experiment(
        &truth,
        RELEASE,
        &track_,
        &settings,
        1.5,
        &engine,
        &Monitor::hidden(),
    )
    .unwrap();
    let f = &o.forecast;
    assert_eq!(f.spread_horizon, None, "the spread reached the tolerance");
    // The fit recovers the damping it was made with: the residuals are the integration
    // error's, so the damping is known to far better than its value.
    assert!((o.fit.values[4] - 1e-3).abs() < 1e-5, "{:?}", o.fit.values);
    // The fit's start (within the integration error) plus the error grown over the
    // forecast, and the interpolation between steps (the members' orbits are the truth's to
    // micrometres, so their interpolation errs as the truth's does): twice both.
    let (dt, _) = stepping(f.t0, 1.5);
    let after: Vec<f64> = f
        .times
        .iter()
        .copied()
        .filter(|&t| t > f.window_end)
        .collect();
    let interpolation = interpolation_error(&truth, dt, &after);
    eprintln!("Hermite interpolation between steps: {interpolation:e} m");
    // h^4/384 max|d^4 theta/dt^4| l with h = 1/300 s: under a micrometre.
    assert!(
        interpolation < 1e-6,
        "interpolation errs by {interpolation} m"
    );
    let slack = 2.0 * (error + interpolation);
    let mut checked = 0;
    for (k, &t) in f.times.iter().enumerate() {
        if t <= f.window_end {
            continue;
        }
        for (q, &x) in f.model[k].iter().zip(&at[k]) {
            assert!(
                x >= q[0] - slack && x <= q[4] + slack,
                "t {t}: truth {x} outside the band {q:?} (slack {slack})"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} coordinates after the window");
}

/// Calibration: in seeded twin experiments (a camera's 100 Hz, 2 mm noise, 24 releases near
/// the default one) the truth lies inside the model's 90 % band 85-95 % of the time before the
/// horizon. Tolerance: a replicate's coverage varies with an SD of about 0.12 (measured over
/// 16 replicates a noise, `chaoscope twin`), so a 24-replicate mean has an SE of 0.025 and
/// 90 % +- 5 % is two of them: a band too narrow or too wide by a tenth fails.
#[test]
fn twin_experiments_are_calibrated() {
    let dir = tempfile::tempdir().unwrap();
    let job = TwinJob {
        output: dir.path().to_path_buf(),
        sigmas: vec![0.002],
        rates: vec![100.0],
        replicates: 24,
        settings: ForecastSettings {
            window: Some((0.0, 1.0)),
            members: 1000,
            seed: 1,
            tolerance: Some(0.03),
            tracking_error: None,
            candidates: 1024,
            // The model is the truth here: no model error to measure.
            held_out: 0,
            ahead: None,
            in_sample: false,
        },
        duration: 2.5,
        start: RELEASE,
        params: ParamSources {
            preset: Some(Preset::Lab),
            joint_damping: Some((1e-3, 1e-3)),
            ..ParamSources::default()
        },
        backend: Backend::Cpu,
        precision: Precision::F32,
    };
    let engine = Engine::in_precision(job.backend, job.precision).unwrap();
    let s = twin::run(
        &job,
        &chaoscope::app::Running::new(&engine, "test".into(), &Monitor::hidden()),
    )
    .unwrap();
    let defined = s.rows.iter().filter(|r| r.coverage.is_some()).count();
    eprintln!(
        "twin calibration: coverage {} over {defined} replicates",
        s.coverage
    );
    assert!(
        defined >= 20,
        "only {defined} replicates before their horizon"
    );
    assert!(
        (0.85..=0.95).contains(&s.coverage),
        "coverage {} over {defined} replicates",
        s.coverage
    );
    for f in ["twin.csv", "twin.png", "twin_forecast.png", "summary.json"] {
        assert!(dir.path().join(f).exists(), "{f} missing");
    }
}

fn lab_csv() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv")
}

/// Bad input exits 2 naming the flag (or FILE:line), and writes nothing.
#[test]
fn forecast_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let csv = lab_csv();
    let no_time = dir.path().join("no_time.csv");
    std::fs::write(&no_time, "x1,y1,x2,y2\n0.1,-0.2,0.1,-0.4\n").unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--window", "25:30"], "--window"),
        (&["--window", "2:1"], "--window"),
        (&["--window", "0.6:21.5"], "--window"),
        // One row (0.667 s): four coordinates for six parameters.
        (&["--window", "0.6:0.7"], "--window"),
        (&["--members", "0"], "--members"),
        (&["--members", "100000000"], "--members"),
        (&["--held-out", "65"], "--held-out"),
        (&["--ahead", "0"], "--ahead"),
        (&["--ahead", "1e9"], "--ahead"),
        // The window must end before the last row unless --ahead says how far to go.
        (&["--window", "0.6:21.02"], "--window"),
        (&["--tolerance", "0"], "--tolerance"),
        (&["--tracking-error", "-1mm"], "--tracking-error"),
        (&["--window", "a:b"], "--window"),
        // Fitted to the data: a given value would change nothing but the summary's record.
        (&["--joint-damping", "0.01"], "--joint-damping"),
    ];
    for (args, flag) in cases {
        let assert = chaoscope()
            .arg("forecast")
            .arg(&csv)
            .args(*args)
            .args("--preset lab --backend cpu --candidates 64 --output".split(' '))
            .arg(&out)
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
        assert!(err.contains(flag), "{args:?}: {err}");
    }
    let assert = chaoscope()
        .arg("forecast")
        .arg(&no_time)
        .args(["--backend", "cpu", "--output"])
        .arg(&out)
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(
        err.contains("no_time.csv:1") && err.contains("`t`"),
        "{err}"
    );
    assert!(!out.exists(), "a refused run wrote {}", out.display());
}

/// The lab run end to end on the CPU: its files, and a summary whose horizons and
/// exponent are what they claim (the spread exceeds the tolerance at its horizon; the
/// horizon in Lyapunov times is the time after the window times the exponent).
#[test]
fn forecast_of_the_lab_run() {
    let dir = tempfile::tempdir().unwrap();
    chaoscope()
        .arg("forecast")
        .arg(lab_csv())
        .args("--preset lab --window 0.6:2.1 --tolerance 0.03 --members 500 --candidates 1024 --backend cpu --output".split(' '))
        .arg(dir.path())
        .assert()
        .success();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    let h = &s["horizon"];
    let lambda = s["lyapunov"]["exponent"].as_f64().unwrap();
    assert!(lambda.is_finite() && lambda > 0.0, "{lambda}");
    // The lab run's members spread past 3 cm just after the window (2.02 s measured).
    let after = h["spread_after_window"].as_f64().expect("a spread horizon");
    let lt = h["spread_lyapunov_times"].as_f64().unwrap();
    assert!((lt - after * lambda).abs() < 1e-9);
    // The bands: the spread column passes the tolerance at the spread horizon.
    let text = std::fs::read_to_string(dir.path().join("bands.csv")).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let spread = header.iter().position(|h| *h == "spread_lower").unwrap();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let window_end = 2.002;
    let t = h["spread"].as_f64().expect("a spread horizon");
    let before = rows
        .iter()
        .filter(|r| r[0] > window_end && r[0] < t - 1e-9)
        .all(|r| r[spread] <= 0.03);
    let after = rows.iter().find(|r| r[0] >= t - 1e-9).unwrap();
    assert!(before && after[spread] >= 0.03 * 0.999, "horizon {t}");
    for f in ["forecast.png", "bands.csv", "summary.json"] {
        assert!(dir.path().join(f).exists(), "{f} missing");
    }
}

/// A camera's scale and pivot, found by the window fit: a twin track (100 Hz, 0.2 mm noise)
/// seen through a camera whose metres are 1e-3 too long and whose origin is 1 mm and -0.5 mm
/// off the pivot, fitted with the arm lengths the data show (1e-3 too long as well). The fit
/// recovers the scale, the pivot and the lower arm (right as given) within three of their
/// standard errors; and the scale's error is under half its prior's (2e-3): the rows
/// measured it, the prior did not set it.
#[test]
fn a_cameras_scale_and_pivot_are_fitted() {
    use chaoscope::fit::TrackedRow;
    use chaoscope::fit::data::angles;
    use chaoscope::fit::window::{TrackRows, fit_window};
    let p = lab_with_damping();
    let (scale, pivot) = (1e-3, (1e-3, -5e-4));
    let track = make_track(&p, RELEASE, 100.0, 2.0, 2e-4, 3);
    let data: Vec<[f64; 4]> = track
        .measured
        .iter()
        .map(|m| {
            let s = 1.0 + scale;
            [
                s * m[0] + pivot.0,
                s * m[1] + pivot.1,
                s * m[2] + pivot.0,
                s * m[3] + pivot.1,
            ]
        })
        .collect();
    let frames: Vec<TrackedRow> = track
        .t
        .iter()
        .zip(&data)
        .map(|(&t, d)| TrackedRow {
            t,
            x1: d[0],
            y1: d[1],
            x2: d[2],
            y2: d[3],
        })
        .collect();
    let angle = angles(&frames, pivot);
    let rows = TrackRows {
        t: &track.t,
        data: &data,
        angles: &angle,
    };
    let mut seen = p;
    (seen.l1, seen.l2) = (p.l1 * (1.0 + scale), p.l2 * (1.0 + scale));
    let engine = Engine::in_precision(Backend::Cpu, Precision::F64).unwrap();
    let fit = fit_window(
        &rows,
        &seen,
        (0.0, 1.0),
        1024,
        None,
        &engine,
        &Monitor::hidden(),
    )
    .unwrap();
    let (v, e) = (fit.values, fit.errors);
    eprintln!(
        "scale {:.2e} +- {:.1e}, pivot ({:.2e} +- {:.1e}, {:.2e} +- {:.1e}) m",
        v[8], e[8], v[6], e[6], v[7], e[7]
    );
    let prior = chaoscope::fit::window::SCALE_PRIOR;
    assert!(e[8] < prior / 2.0, "the scale's error {:.1e}", e[8]);
    // The lower arm: the data's length is the true one, seen through the same scale.
    for (k, truth) in [(6, pivot.0), (7, pivot.1), (8, scale), (9, 0.0)] {
        assert!(
            (v[k] - truth).abs() < 3.0 * e[k],
            "{}: {:.3e} +- {:.1e}, truth {truth:.1e}",
            chaoscope::fit::window::FITTED[k],
            v[k],
            e[k]
        );
    }
}

/// A slow, heavy compound pendulum with air drag on its bars, which the model found from
/// its motion lacks, released from `start` and measured as an encoder would (12-bit angles,
/// positions made from them: they lie on their rods exactly), 6 s at 100 Hz, as a CSV.
fn encoder_recording(dir: &Path, name: &str, start: State) -> std::path::PathBuf {
    let mut p = Params {
        m1: 0.05,
        m2: 0.01,
        l1: 0.2,
        l2: 0.2,
        rod1: 0.4,
        rod2: 0.15,
        ..Params::default()
    };
    p.losses.joint1 = 2e-4;
    p.losses.joint2 = 5e-5;
    p.losses.rho = 1.2;
    p.losses.cw = 2.0;
    (p.losses.rod_area1, p.losses.rod_area2) = (4e-3, 4e-3);
    let states = cpu::trajectory(&p, start, 1e-3, 6000);
    let count = std::f64::consts::TAU / 4096.0;
    let mut csv = String::from("t,x1,y1,x2,y2\n");
    for (k, s) in states.iter().step_by(10).enumerate() {
        let (a1, a2) = (
            (s.theta1 / count).round() * count,
            (s.theta2 / count).round() * count,
        );
        let (x1, y1) = (0.2 * a1.sin(), -0.2 * a1.cos());
        // The lower marker at the lower bar's centre.
        let (x2, y2) = (x1 + 0.1 * a2.sin(), y1 - 0.1 * a2.cos());
        csv.push_str(&format!(
            "{},{x1:.6},{y1:.6},{x2:.6},{y2:.6}\n",
            k as f64 / 100.0
        ));
    }
    let file = dir.join(name);
    std::fs::write(&file, csv).unwrap();
    file
}

fn summary_of(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The model's own error in the bands, calibrated once: `fit` on one recording of the
/// encoder pendulum writes its model and calibration (the model's departure on held-out
/// stretches, by lead) into model.toml; a forecast of another launch of the same pendulum
/// with `--params model.toml` learns nothing from its own future. From a 1 s window the
/// data leave the ensemble's own bands (the state's uncertainty alone) within a second; the
/// calibration's model error widens them to hold most of the lower mass's coordinates to the
/// data's end, out of sample.
#[test]
fn bands_hold_the_models_own_error_on_precise_data() {
    let dir = tempfile::tempdir().unwrap();
    let calibration = encoder_recording(dir.path(), "calibration.csv", State::at_rest(1.2, 1.6));
    let launch = encoder_recording(dir.path(), "launch.csv", State::at_rest(1.0, 1.9));
    let cal = dir.path().join("cal");
    chaoscope()
        .arg("fit")
        .arg(&calibration)
        .args("--window 1 --lead 3 --candidates 4096 --backend cpu --output".split(' '))
        .arg(&cal)
        .assert()
        .success();
    let model = std::fs::read_to_string(cal.join("model.toml")).unwrap();
    assert!(model.contains("[calibration.model_error]"), "{model}");
    let band = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        chaoscope()
            .arg("forecast")
            .arg(&launch)
            .args(["--window", "2:3", "--members", "500", "--backend", "cpu"])
            .args(extra)
            .arg("--output")
            .arg(&out)
            .assert()
            .success();
        let s = summary_of(&out);
        assert_eq!(s["verdict"]["follows"], true, "{}", s["verdict"]);
        assert_eq!(s["sample"], "out of sample");
        s
    };
    let alone = band("alone", &["--held-out", "0"]);
    let params = cal.join("model.toml");
    let calibrated = band("calibrated", &["--params", params.to_str().unwrap()]);
    // The provenance says where each part came from.
    let learned = &calibrated["learned_from"];
    assert!(
        learned["model_error"]["from"]
            .as_str()
            .unwrap()
            .contains("the calibration"),
        "{learned}"
    );
    assert_eq!(learned["rows"]["to"], 3.0, "{learned}");
    // The joint damping each window's fit is held to: the calibration recording's motion's,
    // or, alone, the motion of the rows up to the window's end.
    let from = |s: &serde_json::Value| s["learned_from"]["damping"]["from"].to_string();
    assert!(from(&calibrated).contains("the calibration"), "{learned}");
    assert!(from(&alone).contains("up to the window's end"), "{alone}");
    assert_eq!(
        learned["damping"]["error"].as_array().map(Vec::len),
        Some(2)
    );
    // The lower mass's coordinates inside the 90 % band over the first second after the
    // window (the leads the targets pool), from the scores' lead bins.
    let inside = |s: &serde_json::Value| {
        let (mut n, mut hit) = (0.0, 0.0);
        for bin in s["scores"]["by_lead"].as_array().unwrap() {
            let k = bin["coordinates"].as_f64().unwrap();
            n += k;
            hit += k * bin["inside"].as_f64().unwrap_or(0.0);
        }
        hit / n
    };
    eprintln!("{}\n{}", alone["scores"], calibrated["scores"]);
    // One forecast's coverage is one draw: measured, the ensemble's own bands held 58 % of
    // the first second and the calibrated ones 88 % (77 % over all three seconds: the drag's
    // lag grows on past the calibration's leads).
    assert!(
        inside(&alone) < 0.7,
        "the ensemble alone holds {}",
        inside(&alone)
    );
    assert!(
        inside(&calibrated) > 0.8,
        "widened by the calibration's model error: {}",
        inside(&calibrated)
    );
}

/// A calibration made on a recording's first 3 s is measured again on the rows just before a
/// later window (as long a stretch as its span, and nothing after the window): the summary
/// says so and names that span; a window with fewer rows before it keeps the calibration's.
#[test]
fn a_calibrations_error_is_measured_again_just_before_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let recording = encoder_recording(dir.path(), "run.csv", State::at_rest(1.2, 1.6));
    let cal = dir.path().join("cal");
    chaoscope()
        .arg("fit")
        .arg(&recording)
        .args("--until 3 --window 0.4 --lead 0.5 --held-out 8 --candidates 1024 --backend cpu --output".split(' '))
        .arg(&cal)
        .assert()
        .success();
    let params = cal.join("model.toml");
    let model_error = |window: &str, name: &str| {
        let out = dir.path().join(name);
        chaoscope()
            .arg("forecast")
            .arg(&recording)
            .args([
                "--window",
                window,
                "--members",
                "200",
                "--candidates",
                "1024",
            ])
            .args(["--backend", "cpu", "--params", params.to_str().unwrap()])
            .arg("--output")
            .arg(&out)
            .assert()
            .success();
        summary_of(&out)["learned_from"].clone()
    };
    let learned = model_error("4.5:4.9", "later");
    let later = &learned["model_error"];
    assert!(
        later["from"]
            .as_str()
            .unwrap()
            .contains("just before the window"),
        "{later}"
    );
    // The 3 s before the window's start, to a row (100 rows a second).
    let span: Vec<f64> = serde_json::from_value(later["span"].clone()).unwrap();
    assert!(
        (span[0] - 1.5).abs() <= 0.01 && span[1] < 4.5 && span[1] > 4.48,
        "{span:?}"
    );
    // The damping (and the scale, the model) still come from the calibration's own span.
    let damping: Vec<f64> = serde_json::from_value(learned["damping"]["span"].clone()).unwrap();
    assert!(damping[0] == 0.0 && damping[1] <= 3.0, "{learned}");
    let early = model_error("2:2.4", "early")["model_error"].clone();
    assert!(
        early["from"].as_str().unwrap().contains("the calibration"),
        "{early}"
    );
}

/// Nothing is learned from the future: a forecast of the whole recording and one of the
/// same recording cut at its window's end, both run 1 s past the window (`--ahead`), give
/// the same bands and headline horizon. The model found from the motion, the pivot, the
/// arms and the held-out windows all come from the rows up to the window's end. Positions
/// are held as f32, and the cut file's band times past its last row are the cadence's
/// multiples, a rounding away from the data's own: so the bands agree to an f32 rounding of
/// a 0.4 m reach (3e-8 m), taken as 1e-7 m.
#[test]
fn a_forecast_never_sees_its_future() {
    let dir = tempfile::tempdir().unwrap();
    let whole = encoder_recording(dir.path(), "whole.csv", State::at_rest(1.2, 1.6));
    let text = std::fs::read_to_string(&whole).unwrap();
    let cut: String = text
        .lines()
        .take_while(|l| {
            l.split(',')
                .next()
                .unwrap()
                .parse::<f64>()
                .is_ok_and(|t| t <= 3.0)
                || l.starts_with('t')
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let cut_file = dir.path().join("cut.csv");
    std::fs::write(&cut_file, cut).unwrap();
    let bands = |file: &Path, name: &str| {
        let out = dir.path().join(name);
        chaoscope()
            .arg("forecast")
            .arg(file)
            .args("--window 2:3 --ahead 1 --members 300 --held-out 2 --candidates 1024 --backend cpu --output".split(' '))
            .arg(&out)
            .assert()
            .success();
        let text = std::fs::read_to_string(out.join("bands.csv")).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        (rows, summary_of(&out))
    };
    let (a, sa) = bands(&whole, "whole");
    let (b, sb) = bands(&cut_file, "cut");
    assert_eq!(sa["horizon"]["headline"], sb["horizon"]["headline"]);
    for key in ["from", "to", "count"] {
        assert_eq!(
            sa["learned_from"]["rows"][key],
            sb["learned_from"]["rows"][key]
        );
    }
    // The cut file has nothing to score; the whole one scores the second after the window.
    assert_eq!(sb["scores"]["rows"], 0);
    assert_eq!(sa["scores"]["rows"], 100);
    let mut compared = 0;
    for r in &a {
        let Some(s) = b.iter().find(|s| (s[0] - r[0]).abs() < 1e-9) else {
            continue;
        };
        compared += 1;
        for (x, y) in r.iter().zip(s).skip(1) {
            // The FTLE is NaN up to the window's end in both.
            let same = (x - y).abs() <= 1e-7 || (x.is_nan() && y.is_nan());
            assert!(same, "at {} s: {x} against {y}", r[0]);
        }
    }
    // Every band time of the cut forecast is one of the whole one's.
    assert_eq!(compared, b.len(), "{} of {} band times", compared, b.len());
    // Past the cut file's last row its bands go on at the data's cadence (100 Hz).
    assert!(b.iter().filter(|r| r[0] > 3.0 + 1e-9).count() >= 100);
}

/// A window of a quarter second hardly sees the joint damping; held to what a longer stretch
/// shows (the calibration's motion), its fit's damping is known as well as that at least, and
/// the truth lies within it. Without the prior the same window leaves the damping several
/// times as uncertain.
#[test]
fn a_windows_damping_is_held_to_what_the_motion_shows() {
    use chaoscope::fit::window::{DampingPrior, TrackRows, fit_window};
    let p = lab_with_damping();
    let track = make_track(&p, RELEASE, 100.0, 1.0, 2e-4, 5);
    let angle = track.angles();
    let rows = TrackRows {
        t: &track.t,
        data: &track.measured,
        angles: &angle,
    };
    let truth = [p.losses.joint1, p.losses.joint2];
    let prior = DampingPrior {
        damping: truth,
        error: truth.map(|d| 0.1 * d),
    };
    let engine = Engine::in_precision(Backend::Cpu, Precision::F64).unwrap();
    let fit = |prior: Option<&DampingPrior>| {
        fit_window(
            &rows,
            &p,
            (0.0, 0.25),
            1024,
            prior,
            &engine,
            &Monitor::hidden(),
        )
        .unwrap()
    };
    let (free, held) = (fit(None), fit(Some(&prior)));
    for (k, truth) in truth.into_iter().enumerate() {
        let (v, e, e_free) = (held.values[4 + k], held.errors[4 + k], free.errors[4 + k]);
        eprintln!(
            "damping {k}: {v:.3e} +- {e:.1e} held, {:.3e} +- {e_free:.1e} free, truth {:.3e}",
            free.values[4 + k],
            truth
        );
        // Information adds: the posterior's error is at most the prior's (times the rods'
        // inflation of the covariance for correlated tracking errors).
        assert!(
            e <= prior.error[k] * held.correlation.inflation.sqrt(),
            "{e:.1e}"
        );
        assert!(e < e_free, "held {e:.1e}, free {e_free:.1e}");
        assert!((v - truth).abs() < 3.0 * e, "{v:.3e} +- {e:.1e}");
    }
}
