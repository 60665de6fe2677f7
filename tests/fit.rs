//! `chaoscope fit` on the lab report's tracked data, and its parts on synthetic data whose
//! truth is known.

mod common;

use common::chaoscope;

use chaoscope::cpu;
use chaoscope::engine::{Backend, Engine};
use chaoscope::fit::{self, ModelFitSpec, TrackedRow};
use chaoscope::model::{Params, State};
use chaoscope::params::Preset;
use predicates::prelude::*;

/// Frames of a simulated pendulum hung from `pivot`, every `every` s for `n` frames.
fn synthetic(p: &Params, start: State, pivot: (f64, f64), every: f64, n: usize) -> Vec<TrackedRow> {
    let sub = 100;
    let states = cpu::trajectory(p, start, every / sub as f64, ((n - 1) * sub) as u32);
    states
        .iter()
        .step_by(sub)
        .enumerate()
        .map(|(k, s)| {
            let q = p.positions(s);
            TrackedRow {
                t: k as f64 * every,
                x1: q.x1 + pivot.0,
                y1: q.y1 + pivot.1,
                x2: q.x2 + pivot.0,
                y2: q.y2 + pivot.1,
            }
        })
        .collect()
}

#[test]
fn pivot_lengths_and_model_state_are_recovered_from_synthetic_tracking() {
    let mut p = Preset::Lab.params();
    p.losses.joint1 = 0.002;
    p.losses.joint2 = 0.001;
    let start = State {
        theta1: 0.6,
        omega1: -2.0,
        theta2: -0.9,
        omega2: 4.5,
    };
    let pivot = (0.012, -0.007);
    let frames = synthetic(&p, start, pivot, 1.0 / 3.0, 40);
    // Exact positions on exact circles: the fits recover them to round-off.
    let c = fit::fit_pivot(&frames).unwrap();
    assert!(
        (c.x - pivot.0).abs() < 1e-9 && (c.y - pivot.1).abs() < 1e-9,
        "{} {}",
        c.x,
        c.y
    );
    let (l1, l2) = fit::arm_lengths(&frames, (c.x, c.y));
    assert!((l1.value - p.l1).abs() < 1e-9 && (l2.value - p.l2).abs() < 1e-9);
    // The report's grid search lands on the grid point next to the true pivot.
    let g = fit::grid_pivot(&frames, (0.0, 0.0), 0.05, 0.001);
    assert!((g.0 - pivot.0).abs() <= 0.0005 + 1e-12 && (g.1 - pivot.1).abs() <= 0.0005 + 1e-12);
    // The model fit from the first interior row finds a state that reproduces the window.
    let angles = fit::angles(&frames, (c.x, c.y));
    let spec = ModelFitSpec {
        params: p,
        start_time: 1.0 / 3.0,
        window: 1.5,
        tolerance: 0.005,
        candidates: 4096,
    };
    let engine = Engine::new(if common::gpu().is_some() {
        Backend::Gpu
    } else {
        Backend::Cpu
    })
    .unwrap();
    let m = fit::fit_model(
        &frames,
        (c.x, c.y),
        &angles,
        &spec,
        &engine,
        &chaoscope::monitor::Monitor::hidden(),
    )
    .unwrap();
    // Same model, same data: the refinement converges to the truth; the positions match to
    // well under a millimetre over the window.
    assert!(m.rms < 1e-4, "rms {}", m.rms);
    assert!(
        m.agrees_until >= m.t0 + 1.5 - 1e-9,
        "agrees until {}",
        m.agrees_until
    );
}

/// Rows beside a gap (steps Tracker left unmarked) give no velocity and so no energy: a
/// central difference across the gap would average the motion over it (the audit: energies
/// 20 sigma off there). Elsewhere the energy of a lossless swing keeps its value.
#[test]
fn no_energy_is_differentiated_across_a_gap() {
    let p = Params::default();
    let start = State {
        theta1: 0.6,
        omega1: 0.0,
        theta2: -0.4,
        omega2: 0.0,
    };
    let mut rows = synthetic(&p, start, (0.0, 0.0), 0.005, 400);
    rows.drain(200..203);
    let en = fit::data::energies(&rows, (0.0, 0.0), (p.m1, p.m2), (p.l1, p.l2), p.g, 1e-4);
    // Interior row i is entry i - 1: rows 199 and 200 border the gap.
    let unknown: Vec<usize> = (0..en.e.len()).filter(|&k| en.e[k].is_nan()).collect();
    assert_eq!(unknown, [198, 199]);
    let truth = en.e[0];
    for (k, e) in en.e.iter().enumerate().filter(|(_, e)| e.is_finite()) {
        // Central differences over 2 x 5 ms: the velocity's truncation error, h^2/6 times
        // the third derivative (a few m/s^3 here), some 1e-4 of the energy.
        assert!(
            (e - truth).abs() < 2e-3 * truth.abs(),
            "row {k}: {e} against {truth}"
        );
    }
    // Across the gap the old difference was wrong by far more than that.
    let across = (rows[201].x2 - rows[198].x2) / (rows[201].t - rows[198].t);
    let within = (rows[199].x2 - rows[198].x2) / (rows[199].t - rows[198].t);
    assert!((across - within).abs() > 1e-2, "{across} {within}");
}

#[test]
fn decay_fits_recover_a_known_exponential() {
    let t: Vec<f64> = (1..60).map(|k| k as f64 / 3.0).collect();
    let e: Vec<f64> = t.iter().map(|&x| 0.8 * (-0.025 * x).exp()).collect();
    let en = fit::Energies {
        de: vec![0.01; t.len()],
        t,
        e,
    };
    let d = fit::fit_decay(&en);
    let (a, b) = (d.exponential.params[0], d.exponential.params[1]);
    assert!(
        (a - 0.8).abs() < 1e-9 && (b + 0.025).abs() < 1e-9,
        "{a} {b}"
    );
    // The exact law fits exactly; the other one does not.
    assert!(d.exponential.reduced_chi2() < 1e-12);
    assert!(d.inverse_square.reduced_chi2() > d.exponential.reduced_chi2());
}

#[test]
fn the_whole_fit_runs_on_the_lab_report_data() {
    let dir = tempfile::tempdir().unwrap();
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv");
    let backend = if common::gpu().is_some() {
        "gpu"
    } else {
        "cpu"
    };
    chaoscope()
        .arg("fit")
        .arg(&data)
        .args([
            "--preset",
            "lab",
            "--candidates",
            "8192",
            "--backend",
            backend,
            "--output",
        ])
        .arg(dir.path())
        .assert()
        .success()
        .stderr(predicate::str::contains("fits better"));
    let derived = std::fs::read_to_string(dir.path().join("derived.csv")).unwrap();
    assert_eq!(
        derived.lines().nth(1),
        Some("t,theta1,theta2,omega1,omega2,energy,energy_error")
    );
    assert_eq!(derived.lines().count(), 2 + 62, "interior rows of 64");
    for f in ["positions.png", "energy.png", "phase.png"] {
        let png = chaoscope::render::read_png(&dir.path().join(f)).unwrap();
        assert!(png.width > 500, "{f}");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    let num = |path: &str| s.pointer(path).and_then(|v| v.as_f64()).unwrap();
    // The report: pivot at the origin (its own grid search), l1 ~ 0.30 m, l2 ~ 0.19-0.20 m.
    assert!(num("/pivot/least_squares_circle/x").abs() < 0.01);
    assert!(num("/pivot/least_squares_circle/y").abs() < 0.01);
    assert!(
        (num("/pivot/report_grid_least_distance_variance/x")
            - num("/pivot/least_squares_circle/x"))
        .abs()
            <= 0.001
    );
    assert!((0.29..0.31).contains(&num("/arm_lengths/l1/value")));
    assert!((0.19..0.205).contains(&num("/arm_lengths/l2/value")));
    // Energy decays; the report's b = -0.024 1/s lies within 3 standard errors of ours.
    let (b, db) = (
        num("/energy/exponential/b"),
        num("/energy/exponential/b_error"),
    );
    assert!(b < 0.0 && (b + 0.024).abs() < 3.0 * db, "b = {b} +- {db}");
    // The report's hand-started simulation agreed for about 1.2 s (0.8 s to 2 s).
    assert!(
        num("/model/agrees_for") >= 1.0,
        "{}",
        num("/model/agrees_for")
    );
}

#[test]
fn bad_tracking_files_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let rows = "0,0.1,-0.28,0.1,-0.47\n0.33,0.2,-0.2,0.2,-0.4\n0.67,0.1,-0.28,0.1,-0.47\n1,0,-0.3,0,-0.5\n1.33,-0.1,-0.28,-0.1,-0.47\n";
    let cases = [
        ("t,x1,y1,x2\n0,1,2,3\n", "no column `y2`", ":1:"),
        (
            &*format!("# comment\nt,x1,y1,x2,y2\n{rows}1.67,abc,0,0,0\n"),
            "`abc`",
            ":8:",
        ),
        ("t,x1,y1,x2,y2\n0,1,1,1,1\n1,1,1,1,1\n", "at least 5", ":3:"),
        (
            &*format!("t,x1,y1,x2,y2\n{rows}1.2,0,0,0,0\n"),
            "does not increase",
            ":7:",
        ),
    ];
    for (text, what, line) in cases {
        let f = dir.path().join("bad.csv");
        std::fs::write(&f, text).unwrap();
        chaoscope()
            .arg("fit")
            .arg(&f)
            .args(["--backend", "cpu", "--output"])
            .arg(dir.path().join("out"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains(what).and(predicate::str::contains(line)));
    }
    assert!(
        !dir.path().join("out").exists(),
        "nothing written for a bad file"
    );
}

/// The fit finds the joint damping itself: a given one would be recorded in its command yet
/// change nothing, so the flag is refused (exit 2, naming it); a parameter file's (a model
/// `fit` wrote) is one of the fit's starts, and said so.
#[test]
fn a_given_joint_damping_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    chaoscope()
        .arg("fit")
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv"))
        .args(["--joint-damping", "0.05", "--backend", "cpu", "--output"])
        .arg(dir.path().join("out"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--joint-damping"));
    assert!(!dir.path().join("out").exists(), "nothing written");
    let file = dir.path().join("damped.toml");
    std::fs::write(&file, "joint_damping = [0.05, 0.05]\n").unwrap();
    chaoscope()
        .arg("fit")
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv"))
        .args("--preset lab --candidates 256 --backend cpu --params".split(' '))
        .arg(&file)
        .arg("--output")
        .arg(dir.path().join("out"))
        .assert()
        .stderr(predicate::str::contains("one of the fit's starts"));
}

/// A compound pendulum of bars: a heavy upper bar with a light bob at the joint, a light
/// lower bar with a small marker at its tip (about 7 : 1, as the filmed pendulums people build),
/// every mass times `scale`, with joint damping that scales with them.
fn compound(scale: f64) -> Params {
    let mut p = Params {
        m1: 0.01 * scale,
        m2: 0.002 * scale,
        l1: 0.10,
        l2: 0.08,
        g: 9.81,
        rod1: 0.2 * scale,
        rod2: 0.03 * scale,
        ..Params::default()
    };
    (p.losses.joint1, p.losses.joint2) = (2e-5 * scale, 4e-6 * scale);
    p
}

/// `p` released from `start`, its markers at the joint and the lower bar's tip, as a
/// tracked CSV: `fps` rows a second for `seconds`, each coordinate with Gaussian `noise` (m).
fn compound_csv(p: &Params, start: State, fps: f64, seconds: f64, noise: f64) -> String {
    markers_csv(p, start, (fps, seconds, noise), (1.0, 1.0))
}

/// As [`compound_csv`], the markers at shares `at` of each arm from its joint.
fn markers_csv(
    p: &Params,
    start: State,
    (fps, seconds, noise): (f64, f64, f64),
    at: (f64, f64),
) -> String {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let normal = Normal::new(0.0, noise).unwrap();
    let sub = 20;
    let frames = (seconds * fps) as usize;
    let states = cpu::trajectory(p, start, 1.0 / (fps * sub as f64), (frames * sub) as u32);
    let mut csv = String::from("t,x1,y1,x2,y2\n");
    for (k, s) in states.iter().step_by(sub).take(frames).enumerate() {
        let q = p.positions(s);
        let (x2, y2) = (q.x1 + at.1 * (q.x2 - q.x1), q.y1 + at.1 * (q.y2 - q.y1));
        let mut e = || normal.sample(&mut rng);
        csv.push_str(&format!(
            "{},{},{},{},{}\n",
            k as f64 / fps,
            at.0 * q.x1 + e(),
            at.0 * q.y1 + e(),
            x2 + e(),
            y2 + e()
        ));
    }
    csv
}

/// The identified moments over P in `summary` within four of their standard errors of
/// `truth`'s (a 1-in-15 000 miss for a normal estimate; the errors are the fit's own).
fn moments_within_errors(summary: &serde_json::Value, truth: &Params) {
    let k = truth.inertia();
    let over_p = &summary["identified"]["over_p"];
    for (name, value) in [("a", k.a / k.p), ("b", k.b / k.p), ("c", k.c / k.p)] {
        let (v, e) = (
            over_p[name].as_f64().unwrap(),
            over_p[format!("{name}_error")].as_f64().unwrap(),
        );
        assert!(
            (v - value).abs() < 4.0 * e,
            "{name}: {v} ± {e} against {value}"
        );
    }
}

/// Markers anywhere on the arms: the upper one at the upper bar's centre, the lower one at
/// the lower bar's. The joint is found where the lower arm turns (its distance from the
/// pivot within four of its standard errors of the truth), the moments as with markers at
/// the joints, and the model follows.
#[test]
fn markers_anywhere_on_the_arms() {
    let dir = tempfile::tempdir().unwrap();
    let truth = compound(1.0);
    let csv = dir.path().join("centres.csv");
    let start = State::at_rest(2.0, 2.6);
    std::fs::write(
        &csv,
        markers_csv(&truth, start, (200.0, 12.0, 1e-4), (0.5, 0.5)),
    )
    .unwrap();
    let out = dir.path().join("found");
    let (code, s, err) = fit_json(
        &[
            &[csv.to_str().unwrap(), "--output", out.to_str().unwrap()][..],
            &FIT_SETTINGS,
        ]
        .concat(),
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("the upper marker is not on the middle joint"),
        "{err}"
    );
    assert_eq!(s["verdict"]["follows"], true, "{s}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let joint = &summary["middle_joint_off_marker"];
    let (l, e) = (
        joint["joint"].as_f64().unwrap(),
        joint["error"].as_f64().unwrap(),
    );
    assert!((l - truth.l1).abs() < 4.0 * e, "{joint}");
    // The moments over P: the lower marker at the bar's centre changes none of them (they
    // are the arms', not the markers').
    moments_within_errors(&summary, &truth);
}

/// The fit's window and a small search on the CPU, for the compound pendulum's tracks.
const FIT_SETTINGS: [&str; 8] = [
    "--start",
    "1",
    "--window",
    "0.5",
    "--candidates",
    "512",
    "--backend",
    "cpu",
];

/// `fit FILE` with the summary as JSON.
fn fit_json(args: &[&str]) -> (Option<i32>, serde_json::Value, String) {
    let out = chaoscope()
        .arg("--json")
        .arg("fit")
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let summary = serde_json::from_str(&String::from_utf8_lossy(&out.stdout)).unwrap_or_default();
    (out.status.code(), summary, err)
}

/// Any pendulum, no model given: `fit` finds the pendulum's own moments from its motion
/// (within their stated errors of the truth), says so, follows the data (the verdict), and
/// writes the model as a parameter file that `--params` reads back as the same pendulum.
/// A model given by masses fits alike at 50 g and at 5 kg: the damping is searched on the
/// pendulum's own scale.
#[test]
fn any_pendulum_is_fitted_by_its_own_moments() {
    let dir = tempfile::tempdir().unwrap();
    let truth = compound(1.0);
    let csv = dir.path().join("compound.csv");
    std::fs::write(
        &csv,
        compound_csv(&truth, State::at_rest(2.0, 2.6), 200.0, 12.0, 1e-4),
    )
    .unwrap();
    let file = csv.to_str().unwrap();
    let out = dir.path().join("found");
    let common = FIT_SETTINGS;
    let (code, s, err) =
        fit_json(&[&[file, "--output", out.to_str().unwrap()][..], &common].concat());
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("found from its motion"), "{err}");
    assert_eq!(s["verdict"]["follows"], true, "{s}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["model"]["source"], "identified");
    moments_within_errors(&summary, &truth);
    // The model file, read back, is the same pendulum: fitted again as a given model, the
    // same agreement to a percent (the file's fitted damping is one more start of the
    // search, whose refinement then stops at another point of the same shallow valley).
    let model = out.join("model.toml");
    let again = dir.path().join("again");
    // `fit FILE --params PARAMS --output OUT` with the common settings.
    let with_params = |params: &std::path::Path, out: &std::path::Path| {
        let (params, out) = (params.to_str().unwrap(), out.to_str().unwrap());
        fit_json(&[&[file, "--params", params, "--output", out][..], &common].concat())
    };
    let (code, s2, err) = with_params(&model, &again);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        (s2["verdict"]["rms"].as_f64().unwrap() / s["verdict"]["rms"].as_f64().unwrap() - 1.0)
            .abs()
            < 1e-2,
        "{} against {}",
        s2["verdict"],
        s["verdict"]
    );
    chaoscope()
        .args("trajectory --theta1 2 --theta2 2.6 --t-max 1 --params".split(' '))
        .arg(&model)
        .arg("--output")
        .arg(dir.path().join("trajectory.csv"))
        .assert()
        .success();
    // Given by masses: 50 g or 5 kg, the same fit (the motion is the same).
    let mut fits = Vec::new();
    for scale in [0.2, 20.0] {
        let p = compound(scale);
        let params = dir.path().join(format!("scale{scale}.toml"));
        std::fs::write(
            &params,
            format!(
                "m1 = {}\nm2 = {}\nl1 = 0.1\nl2 = 0.08\nrod_mass = [{}, {}]\n",
                p.m1, p.m2, p.rod1, p.rod2
            ),
        )
        .unwrap();
        let o = dir.path().join(format!("scale{scale}"));
        let (code, s, err) = with_params(&params, &o);
        assert_eq!(code, Some(0), "{err}");
        fits.push(s["verdict"]["rms"].as_f64().unwrap());
    }
    // The same search in the pendulum's own units: the same result to rounding.
    assert!((fits[1] / fits[0] - 1.0).abs() < 1e-6, "{fits:?}");
}

/// A model that is not this pendulum's (the lab's apparatus forced on a compound pendulum)
/// is said not to follow: the verdict in the summary and exit status 3, no agreement
/// reported as a finding.
#[test]
fn a_model_that_does_not_follow_is_a_verdict_not_a_result() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("compound.csv");
    std::fs::write(
        &csv,
        compound_csv(&compound(1.0), State::at_rest(2.0, 2.6), 200.0, 4.0, 1e-4),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (code, s, err) = fit_json(
        &[
            &[
                csv.to_str().unwrap(),
                "--preset",
                "lab",
                "--output",
                out.to_str().unwrap(),
            ][..],
            &FIT_SETTINGS,
        ]
        .concat(),
    );
    assert_eq!(code, Some(3), "{err}");
    assert_eq!(s["verdict"]["follows"], false, "{s}");
    assert!(err.contains("DOES NOT FOLLOW"), "{err}");
    assert!(!err.contains("agrees within"), "{err}");
}

/// Files as users have them: frame numbers at a frame rate, pixels (y down) at a scale, a
/// pivot that moves, `;` separators with decimal commas, tabs and a byte-order mark; and what
/// cannot be metres or seconds refused, naming the option that fixes it.
#[test]
fn files_as_users_have_them() {
    use chaoscope::fit::data::{PixelScale, Units};
    let dir = tempfile::tempdir().unwrap();
    let semicolons = dir.path().join("semicolons.csv");
    let rows: String = (0..6)
        .map(|k| format!("{k};10,5;20;{};120;{};200\n", 10.5 + 300.0, 10.5 + 300.0))
        .collect();
    std::fs::write(&semicolons, format!("frame;x0;y0;x1;y1;x2;y2\n{rows}")).unwrap();
    let units = Units {
        pixels_per_metre: Some(PixelScale::PerMetre(1000.0)),
        frame_rate: Some(100.0),
        ..Default::default()
    };
    let read = fit::read_frames(&semicolons, &units).unwrap();
    // Frame 3 at 100 a second; 300 px right and 100 px down of the pivot at 1000 px/m.
    let r = read[3];
    assert!((r.t - 0.03).abs() < 1e-12, "{r:?}");
    assert!(
        (r.x1 - 0.3).abs() < 1e-12 && (r.y1 + 0.1).abs() < 1e-12,
        "{r:?}"
    );
    assert!((r.y2 + 0.18).abs() < 1e-12, "{r:?}");
    // Tabs and a byte-order mark, times in seconds and metres.
    let tabs = dir.path().join("tabs.csv");
    let rows: String = (0..6)
        .map(|k| format!("{}\t0,1\t-0,3\t0,1\t-0,5\n", k as f64 / 4.0))
        .collect();
    std::fs::write(
        &tabs,
        format!(
            "\u{feff}t\tx1\ty1\tx2\ty2\n{}",
            rows.replace("0.25", "0,25")
        ),
    )
    .unwrap();
    let read = fit::read_frames(&tabs, &Units::default()).unwrap();
    assert_eq!((read[1].t, read[1].x1, read[1].y2), (0.25, 0.1, -0.5));
    // Tracker's export of two point masses together (tabs, the tracks' names over `t x y x
    // y`, decimal commas in some locales); a step not marked is left empty: that row is
    // skipped.
    let tracker = dir.path().join("tracker.txt");
    let mut text = String::from("#multi:\n\tmass A\t\tmass B\t\t\nt\tx\ty\tx\ty\t\n");
    for k in 0..7 {
        let t = format!("{}", 0.04 * k as f64).replace('.', ",");
        match k {
            3 => text.push_str(&format!("{t}\t\t\t0,2\t-0,4\t\n")),
            _ => text.push_str(&format!("{t}\t0,1\t-0,3\t0,15\t-0,5\t\n")),
        }
    }
    std::fs::write(&tracker, text).unwrap();
    let read = fit::read_frames(&tracker, &Units::default()).unwrap();
    assert_eq!(read.len(), 6, "{read:?}");
    assert_eq!(
        (read[3].t, read[3].x1, read[3].x2, read[3].y2),
        (0.16, 0.1, 0.15, -0.5)
    );
    // Tracker's bare header (`t x y x y` without the tracks' names above it) reads the same
    // rows: before, it was refused for want of a column `x1`.
    let bare = dir.path().join("bare.txt");
    let text = std::fs::read_to_string(&tracker).unwrap();
    std::fs::write(&bare, text.replace("#multi:\n\tmass A\t\tmass B\t\t\n", "")).unwrap();
    assert_eq!(fit::read_frames(&bare, &Units::default()).unwrap(), read);
    // Frame numbers without a rate: the error names the rate.
    let e = fit::read_frames(&semicolons, &Units::default()).unwrap_err();
    assert!(
        matches!(
            &e,
            chaoscope::Error::InvalidSpec {
                field: "frame_rate",
                ..
            }
        ),
        "{e}"
    );
    // The command line: pixels read as metres, frame numbers read as seconds.
    let truth = compound(1.0);
    let csv = compound_csv(&truth, State::at_rest(2.0, 2.6), 200.0, 3.0, 1e-4);
    let scaled = |f: &dyn Fn(usize, f64) -> f64| -> String {
        csv.lines()
            .enumerate()
            .map(|(i, line)| match i {
                0 => format!("{line}\n"),
                _ => {
                    let v: Vec<String> = line
                        .split(',')
                        .enumerate()
                        .map(|(c, x)| f(c, x.parse().unwrap()).to_string())
                        .collect();
                    v.join(",") + "\n"
                }
            })
            .collect()
    };
    for (name, text, flag) in [
        (
            "pixels.csv",
            scaled(&|c, x| if c == 0 { x } else { 1200.0 * x }),
            "--pixels-per-metre",
        ),
        (
            "frames.csv",
            scaled(&|c, x| if c == 0 { 200.0 * x } else { x }),
            "--frame-rate",
        ),
    ] {
        let file = dir.path().join(name);
        std::fs::write(&file, text).unwrap();
        chaoscope()
            .arg("fit")
            .arg(&file)
            .args(["--backend", "cpu", "--output"])
            .arg(dir.path().join("out"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains(flag));
    }
    assert!(!dir.path().join("out").exists(), "nothing written");
}

/// Tracker exports pixels in its own frame, y up. Read so (`--y-up`), a film's track fits to
/// the moments its y-down twin does; read as images count (y down) it is refused naming the
/// flag, whether the scale comes from the motion (it would be negative) or is given (the
/// moments would all be negative), never fitted upside down.
#[test]
fn a_tracker_y_up_export_fits_as_its_y_down_twin() {
    use chaoscope::fit::data::{PixelScale, Units};
    use chaoscope::fit::pendulum::tracked_model;
    let dir = tempfile::tempdir().unwrap();
    let truth = compound(1.0);
    let csv = compound_csv(&truth, State::at_rest(2.0, 2.6), 200.0, 3.0, 1e-4);
    // The same positions in pixels (1200 a metre) with y down, and with y up.
    let pixels = |up: bool| -> String {
        let mut out = String::new();
        for (i, line) in csv.lines().enumerate() {
            if i == 0 {
                out += &format!("{line}\n");
                continue;
            }
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            let y = |y: f64| {
                if up {
                    300.0 + 1200.0 * y
                } else {
                    300.0 - 1200.0 * y
                }
            };
            out += &format!(
                "{},{},{},{},{}\n",
                v[0],
                500.0 + 1200.0 * v[1],
                y(v[2]),
                500.0 + 1200.0 * v[3],
                y(v[4])
            );
        }
        out
    };
    let (down, up) = (dir.path().join("down.csv"), dir.path().join("up.csv"));
    std::fs::write(&down, pixels(false)).unwrap();
    std::fs::write(&up, pixels(true)).unwrap();
    let model = |file: &std::path::Path, scale: PixelScale, y_up: bool| {
        let units = Units {
            pixels_per_metre: Some(scale),
            y_up,
            ..Default::default()
        };
        let rows = fit::read_frames(file, &units)?;
        tracked_model(
            &rows,
            &Default::default(),
            &units,
            &chaoscope::monitor::Monitor::hidden(),
        )
    };
    let twin = model(&down, PixelScale::FromMotion, false).unwrap();
    let turned = model(&up, PixelScale::FromMotion, true).unwrap();
    let (a, b) = (
        twin.identified.as_ref().unwrap().values,
        turned.identified.as_ref().unwrap().values,
    );
    for k in 0..4 {
        // The same rows to rounding (0.2 px of 1200 px/m in print): the same moments within
        // a part in 1e9.
        assert!((a[k] - b[k]).abs() <= 1e-9 * a[k].abs(), "{a:?} vs {b:?}");
    }
    for scale in [PixelScale::FromMotion, PixelScale::PerMetre(1200.0)] {
        let e = model(&up, scale, false).err().expect("refused");
        assert!(
            matches!(&e, chaoscope::Error::InvalidSpec { field: "y_up", .. }),
            "{scale:?}: {e}"
        );
    }
    // With the model stated (the preset's, the arms from the data), the motion still says so.
    let units = Units {
        pixels_per_metre: Some(PixelScale::PerMetre(1200.0)),
        ..Default::default()
    };
    let rows = fit::read_frames(&up, &units).unwrap();
    let stated = chaoscope::params::ParamSources {
        preset: Some(Preset::Lab),
        ..Default::default()
    };
    let e = tracked_model(
        &rows,
        &stated,
        &units,
        &chaoscope::monitor::Monitor::hidden(),
    )
    .err()
    .expect("refused");
    assert!(
        matches!(&e, chaoscope::Error::InvalidSpec { field: "y_up", .. }),
        "{e}"
    );
    // The command line names the flag.
    chaoscope()
        .arg("fit")
        .arg(&up)
        .args([
            "--pixels-per-metre",
            "motion",
            "--backend",
            "cpu",
            "--output",
        ])
        .arg(dir.path().join("out"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--y-up"));
}

/// A weighed pendulum (`--mass`, all that swings): the moments found from its motion come in
/// kg m^2 and J and the energies in joules. Bobs on uniform rods are their own equivalent,
/// so the masses written are the truth's within the moments' own errors; model.toml states
/// P and reads back in kilograms. A mass beside a stated model is refused naming the flag.
#[test]
fn a_weighed_pendulum_has_its_moments_in_kilograms() {
    let dir = tempfile::tempdir().unwrap();
    let truth = compound(1.0);
    let total = truth.m1 + truth.m2 + truth.rod1 + truth.rod2;
    let csv = dir.path().join("compound.csv");
    std::fs::write(
        &csv,
        compound_csv(&truth, State::at_rest(2.0, 2.6), 200.0, 12.0, 1e-4),
    )
    .unwrap();
    let out = dir.path().join("weighed");
    let mass = total.to_string();
    let (file, o) = (csv.to_str().unwrap(), out.to_str().unwrap());
    let (code, s, err) =
        fit_json(&[&[file, "--output", o, "--mass", &mass][..], &FIT_SETTINGS].concat());
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(s["energy_unit"], "J", "{s}");
    assert!(err.contains("kg m^2"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let params = &summary["model"]["parameters"];
    let found = |key: &str, k: usize| match key {
        "rod_mass" => params[key][k].as_f64().unwrap(),
        _ => params[key].as_f64().unwrap(),
    };
    // The scale puts the equivalent's total at the weighed mass, to rounding.
    let sum = found("m1", 0) + found("m2", 0) + found("rod_mass", 0) + found("rod_mass", 1);
    assert!((sum / total - 1.0).abs() < 1e-12, "{params}");
    // The masses follow from a, b, c with their stated relative errors (below 1e-3, asserted)
    // amplified by the differences that split them into bobs and rods (6 (c / l1 l2 - b /
    // l2^2) and the like: a few times): the rods within 0.5 %; the light bobs (4 and 1 % of
    // the total) are differences of the rods' large terms, so they are held to 0.5 % of the
    // total, as P, whose share of it they move.
    let over_p = &summary["identified"]["over_p"];
    let relative = ["a", "b", "c"]
        .iter()
        .map(|m| over_p[format!("{m}_error")].as_f64().unwrap() / over_p[m].as_f64().unwrap())
        .fold(0.0, f64::max);
    assert!(relative < 1e-3, "{over_p}");
    for (got, want, of) in [
        (found("rod_mass", 0), truth.rod1, truth.rod1),
        (found("rod_mass", 1), truth.rod2, truth.rod2),
        (found("m1", 0), truth.m1, total),
        (found("m2", 0), truth.m2, total),
    ] {
        assert!(
            (got - want).abs() < 5e-3 * of,
            "{got} against {want}: {params}"
        );
    }
    let p = summary["model"]["weighed"]["p"].as_f64().unwrap();
    let k = truth.inertia();
    assert!((p / k.p - 1.0).abs() < 5e-3, "P {p} against {}", k.p);
    // model.toml states P and reads back in kilograms: `trajectory --params` runs it, and
    // the fit of the same file with it is the same pendulum's.
    let model = std::fs::read_to_string(out.join("model.toml")).unwrap();
    assert!(model.contains("\np = "), "{model}");
    let again = dir.path().join("again");
    let (code, s2, err) = fit_json(
        &[
            &[
                file,
                "--params",
                out.join("model.toml").to_str().unwrap(),
                "--output",
                again.to_str().unwrap(),
            ][..],
            &FIT_SETTINGS,
        ]
        .concat(),
    );
    assert_eq!(code, Some(0), "{err}");
    let read: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(again.join("summary.json")).unwrap())
            .unwrap();
    let m1 = read["model"]["parameters"]["m1"].as_f64().unwrap();
    // Written to 17 digits and read back: the same masses to rounding.
    assert!((m1 / found("m1", 0) - 1.0).abs() < 1e-9, "{m1}");
    assert_eq!(s2["energy_unit"], "J");
    // A stated model states its own masses.
    chaoscope()
        .args(["fit", file, "--preset", "lab", "--mass", "0.2", "--output"])
        .arg(dir.path().join("refused"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--mass"));
}
