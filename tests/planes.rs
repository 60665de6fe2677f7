//! Maps of any plane (issue 22): the axes as data, on both paths. The (theta1, theta2) plane
//! through the new flags is today's map; a parameter plane's pixel is the map made with that
//! pixel's parameters; the equations depend on the mass ratio only.

mod common;

use common::argv;

use chaoscope::engine::{Backend, Engine, MapKernels};
use chaoscope::field::Field;
use chaoscope::model::Params;
use chaoscope::monitor::Monitor;
use chaoscope::spec::{
    Axis, FlipSpec, Grid, LyapunovSpec, MapSpec, Method, Precision, Range, Stepping, Var,
};

fn flip(grid: Grid, t_max: f64, precision: Precision) -> FlipSpec {
    FlipSpec {
        precision,
        ..FlipSpec::new(Params::default(), grid, Stepping { dt: 0.01, t_max })
    }
}

fn ftle(grid: Grid, precision: Precision) -> LyapunovSpec {
    LyapunovSpec {
        params: Params::default(),
        grid,
        stepping: Stepping {
            dt: 0.01,
            t_max: 2.0,
        },
        method: Method::Tangent,
        renorm: 0.1,
        use_symmetry: true,
        precision,
        band: None,
        integrator: Default::default(),
        indicator: Default::default(),
    }
}

/// The (m2/m1, l2/l1) plane at a fixed start that flips within a few seconds.
fn ratio_plane(n: u32) -> Grid {
    Grid {
        width: n,
        height: n,
        x: Axis::new(Var::MassRatio, 0.5, 2.0),
        y: Axis::new(Var::LengthRatio, 0.5, 2.0),
        fixed: chaoscope::model::State::at_rest(2.0, 2.5),
        sampling: Default::default(),
    }
}

/// The one-pixel (theta1, theta2) map of pixel (col, row) of `grid` with that pixel's own
/// parameters: the single map the plane's pixel must equal.
fn single<S: MapSpec>(spec: &S, col: u32, row: u32, with: impl Fn(Params, Grid) -> S) -> S {
    let (p, s) = spec.grid().pixel(&spec.params(), col, row);
    let around = |x: f64| Range {
        min: x - 1e-3,
        max: x + 1e-3,
    };
    with(
        p,
        Grid::angles(1, 1, around(s.theta1), around(s.theta2), s.omega1, s.omega2),
    )
}

fn map<S: MapKernels>(engine: &Engine, spec: &S) -> Field {
    spec.validate().expect("valid spec");
    engine.map(spec, &Monitor::hidden()).expect("map")
}

#[test]
fn a_parameter_planes_pixel_is_the_map_of_its_parameters_on_the_cpu_bit_for_bit() {
    let cpu = Engine::new(Backend::Cpu).unwrap();
    let plane = flip(ratio_plane(8), 4.0, Precision::F64);
    let field = map(&cpu, &plane);
    let lyap = ftle(ratio_plane(6), Precision::F64);
    let exponents = map(&cpu, &lyap);
    for (col, row) in [(0, 0), (3, 5), (7, 2), (6, 7)] {
        let one = single(&plane, col, row, |params, grid| FlipSpec {
            params,
            grid,
            ..plane
        });
        // Same parameters and start through the same CPU code: the same bits.
        assert_eq!(
            map(&cpu, &one).data[0].to_bits(),
            field.get(col, row).to_bits()
        );
        let (col, row) = (col.min(5), row.min(5));
        let one = single(&lyap, col, row, |params, grid| LyapunovSpec {
            params,
            grid,
            ..lyap
        });
        assert_eq!(
            map(&cpu, &one).data[0].to_bits(),
            exponents.get(col, row).to_bits()
        );
    }
}

#[test]
fn a_parameter_planes_pixel_is_the_map_of_its_parameters_on_the_gpu() {
    let Some(ctx) = common::f64_gpu() else { return };
    let gpu = Engine::on_gpu(ctx);
    for precision in [Precision::F32, Precision::F64] {
        let plane = flip(ratio_plane(8), 4.0, precision);
        let field = map(&gpu, &plane);
        let lyap = ftle(ratio_plane(8), precision);
        let exponents = map(&gpu, &lyap);
        // The plane forms each pixel's coefficients in the shader, the single map on the host
        // in f64 rounded once: a few ulp apart, grown by at most e^(lambda t) ~ e^(4/s * 4 s)
        // ~ 1e7 by the end: 1e-7 * 1e7 ~ 1 % of a flip time in f32 (a step or two), far
        // less in f64 (1e-16 * 1e7).
        let (flip_tol, ftle_tol) = match precision {
            Precision::F32 => (0.03, 0.02),
            Precision::F64 => (1e-6, 1e-6),
        };
        for (col, row) in [(0, 0), (3, 5), (7, 2), (6, 7), (4, 4)] {
            let one = single(&plane, col, row, |params, grid| FlipSpec {
                params,
                grid,
                ..plane
            });
            let (a, b) = (map(&gpu, &one).data[0], field.get(col, row));
            assert!(
                a == b || (a - b).abs() <= flip_tol * a.abs().max(1.0),
                "{precision:?} flip ({col}, {row}): single {a} vs plane {b}"
            );
            let one = single(&lyap, col, row, |params, grid| LyapunovSpec {
                params,
                grid,
                ..lyap
            });
            let (a, b) = (map(&gpu, &one).data[0], exponents.get(col, row));
            assert!(
                (a - b).abs() <= ftle_tol * a.abs().max(1.0),
                "{precision:?} FTLE ({col}, {row}): single {a} vs plane {b}"
            );
        }
    }
}

#[test]
fn gpu_equals_cpu_across_a_parameter_plane() {
    let Some(ctx) = common::gpu() else { return };
    let gpu = Engine::on_gpu(ctx);
    let cpu = Engine::new(Backend::Cpu).unwrap();
    // Short enough that most of the plane is regular: its flips within one step (as the
    // GPU-vs-CPU tests of the angle plane), the rest chaotic (f32 round-off grown).
    let plane = flip(ratio_plane(24), 3.0, Precision::F32);
    let (g, c) = (map(&gpu, &plane), map(&cpu, &plane));
    let agree = g
        .data
        .iter()
        .zip(&c.data)
        .filter(|(a, b)| (a.is_infinite() && b.is_infinite()) || (*a - *b).abs() <= 0.011)
        .count();
    let share = agree as f64 / g.data.len() as f64;
    // Measured 0.99+ (lavapipe); the chaotic minority may part by more than a step.
    assert!(share >= 0.95, "only {share:.3} of the plane agrees");
    let lyap = ftle(ratio_plane(16), Precision::F32);
    let (g, c) = (map(&gpu, &lyap), map(&cpu, &lyap));
    let close = g
        .data
        .iter()
        .zip(&c.data)
        .filter(|(a, b)| (*a - *b).abs() <= 0.05 * b.abs().max(0.4))
        .count();
    // The divergence family's agreement rule: 5 % or 0.02 /s; over 2 s nearly every pixel.
    let share = close as f64 / g.data.len() as f64;
    assert!(share >= 0.95, "only {share:.3} of the FTLE plane agrees");
}

#[test]
fn flip_times_depend_on_the_mass_ratio_only() {
    let n = 9;
    // m1 along x over [0.5, 1.5], m2 along y over twice that: the anti-diagonal pixel
    // (c, n - 1 - c) has m2 = 2 m1 (up to one rounding), the same ray of the (m1, m2) plane.
    let grid = Grid {
        width: n,
        height: n,
        x: Axis::new(Var::M1, 0.5, 1.5),
        y: Axis::new(Var::M2, 1.0, 3.0),
        fixed: chaoscope::model::State::at_rest(2.0, 2.5),
        sampling: Default::default(),
    };
    let mut engines = vec![("cpu", Engine::new(Backend::Cpu).unwrap(), Precision::F64)];
    if let Some(ctx) = common::gpu() {
        engines.push(("gpu", Engine::on_gpu(ctx), Precision::F32));
    }
    for (name, engine, precision) in engines {
        let field = map(&engine, &flip(grid, 5.0, precision));
        let ray: Vec<f32> = (0..n).map(|c| field.get(c, n - 1 - c)).collect();
        assert!(ray[0].is_finite(), "{name}: the start flips: {ray:?}");
        // Scaling every mass scales T, V and the losses alike: the motion is the same up to
        // round-off (1e-16 on the CPU, the f32 coefficients' 1e-7 on the GPU) grown over
        // the ~2 s to the flip; the flip's time within a hundredth of a step.
        let tol = match precision {
            Precision::F64 => 1e-4,
            Precision::F32 => 2e-3,
        };
        for t in &ray {
            assert!(
                (t - ray[0]).abs() <= tol,
                "{name}: along m2/m1 = 2: {ray:?}"
            );
        }
        // Not a property of every line: across the ray the ratio and the time change.
        let across: Vec<f32> = (0..n).map(|c| field.get(c, c)).collect();
        assert!(
            across.iter().any(|t| (t - across[0]).abs() > 0.05),
            "{name}: {across:?}"
        );
    }
}

#[test]
fn symmetry_only_where_the_plane_has_it() {
    let base = flip(Grid::square(16), 5.0, Precision::F64);
    assert_eq!(base.rows_to_integrate(), 8);
    let angles_and_speed = Grid {
        x: Axis::new(Var::Theta1, -3.0, 3.0),
        y: Axis::new(Var::Omega1, -4.0, 4.0),
        ..Grid::square(16)
    };
    let s = FlipSpec {
        grid: angles_and_speed,
        ..base
    };
    // (theta1, omega1) -> (-theta1, -omega1) with theta2 = omega2 = 0: symmetric.
    assert_eq!(s.rows_to_integrate(), 8);
    let mut moving = s;
    moving.grid.fixed.theta2 = 0.3;
    assert_eq!(moving.rows_to_integrate(), 16);
    let ratios = FlipSpec {
        grid: Grid {
            x: Axis::new(Var::MassRatio, 0.5, 2.0),
            y: Axis::new(Var::Theta2, -3.0, 3.0),
            ..Grid::square(16)
        },
        ..base
    };
    assert_eq!(ratios.rows_to_integrate(), 16);
    // The mirrored half of the (theta1, omega1) map is the integrated map bit for bit.
    let cpu = Engine::new(Backend::Cpu).unwrap();
    let mirrored = map(&cpu, &s);
    let whole = map(
        &cpu,
        &FlipSpec {
            use_symmetry: false,
            ..s
        },
    );
    assert_eq!(mirrored.data, whole.data);
}

#[test]
fn the_angle_plane_through_the_axis_flags_is_todays_map() {
    let dir = tempfile::tempdir().unwrap();
    for backend in ["cpu", "gpu"] {
        if backend == "gpu" && common::gpu().is_none() {
            continue;
        }
        let run = |name: &str, extra: &[&str]| {
            let data = dir.path().join(format!("{backend}-{name}.npy"));
            let output = dir.path().join(format!("{backend}-{name}.png"));
            common::chaoscope()
                .args([
                    "flip",
                    "--size",
                    "40x30",
                    "--t-max",
                    "4",
                    "--backend",
                    backend,
                ])
                .args(extra)
                .arg("--data")
                .arg(&data)
                .arg("--output")
                .arg(&output)
                .assert()
                .success();
            (std::fs::read(data).unwrap(), std::fs::read(output).unwrap())
        };
        let today = run("today", &["--theta1", "-2:2.5"]);
        let axes = run("axes", &["--x", "theta1=-2:2.5", "--y", "theta2"]);
        let swapped = run(
            "swapped",
            &[
                "--y",
                "theta2=-pi:pi",
                "--x",
                "theta1",
                "--theta1",
                "-2:2.5",
            ],
        );
        assert_eq!(today.0, axes.0, "{backend}: the .npy differs");
        assert_eq!(today.0, swapped.0, "{backend}: the .npy differs");
        // The PNG too: its reproducing command is written as today's flags.
        assert_eq!(today.1, axes.1, "{backend}: the PNG differs");
    }
}

#[test]
fn bad_axes_are_refused_naming_the_flag() {
    let cases: &[(&[&str], &str)] = &[
        (&["--x", "m2"], "--x"),
        (&["--x", "mass"], "--x"),
        (&["--x", "m2=1:1"], "--x"),
        (&["--x", "theta2", "--y", "theta2"], "--y"),
        (&["--x", "m2=1:2", "--y", "m2/m1=1:2"], "--y"),
        (
            &argv("--x omega1=-5:5 --y omega2=-5:5 --theta2 0:1"),
            "--theta2",
        ),
        (&["--x", "omega1=-5:5", "--omega1", "2"], "--omega1"),
        (&["--x", "theta1=-4:4"], "--theta1"),
        (&["--x", "m2/m1=0:2", "--theta1", "1"], "--x"),
        (
            &["--x", "l1=0.5:3", "--y", "omega2=-30:30", "--dt", "0.05"],
            "--dt",
        ),
    ];
    common::refuses(
        &["flip", "--size", "8", "--t-max", "1", "--backend", "cpu"],
        cases,
    );
}

#[test]
fn supersampling_reduces_the_finer_map_and_one_sample_is_the_plain_map() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, args: &[&str]| {
        let data = dir.path().join(format!("{name}.npy"));
        let resolved = dir.path().join(format!("{name}-resolved.npy"));
        common::chaoscope()
            .args("flip --t-max 6 --backend cpu --theta1 1:3".split(' '))
            .args(args)
            .arg("--data")
            .arg(&data)
            .arg("--resolved")
            .arg(&resolved)
            .arg("--output")
            .arg(dir.path().join(format!("{name}.png")))
            .assert()
            .success();
        (common::read_npy(&data), common::read_mask(&resolved).1)
    };
    let plain = run("plain", &["--size", "12x10"]);
    let one = run("one", &["--size", "12x10", "--samples", "1"]);
    assert_eq!(plain, one);
    let three = run("three", &["--size", "12x10", "--samples", "3"]);
    let fine = run("fine", &["--size", "36x30"]);
    assert_eq!(three.0.0, vec![10, 12]);
    // Each pixel: the geometric mean of its 3 x 3 sub-pixels' flip times over those that
    // flip (never where none does), resolved where all nine are.
    let ((_, f), mask) = (&fine.0, &fine.1);
    for row in 0..10usize {
        for col in 0..12usize {
            let subs: Vec<usize> = (0..9)
                .map(|k| (3 * row + k / 3) * 36 + 3 * col + k % 3)
                .collect();
            let logs: Vec<f64> = subs
                .iter()
                .map(|&i| f[i])
                .filter(|t| t.is_finite())
                .map(|t| (t as f64).ln())
                .collect();
            let want = match logs.len() {
                0 => f32::INFINITY,
                n => (logs.iter().sum::<f64>() / n as f64).exp() as f32,
            };
            let i = row * 12 + col;
            assert_eq!(
                three.0.1[i].to_bits(),
                want.to_bits(),
                "pixel ({col}, {row})"
            );
            let all = subs.iter().all(|&k| mask[k] == 1) as u8;
            assert_eq!(three.1[i], all, "pixel ({col}, {row})'s verdict");
        }
    }
    // Reproducible: the same flags, the same bits.
    assert_eq!(run("again", &["--size", "12x10", "--samples", "3"]), three);
}

/// `trajectory --at NAME=VALUE` runs a parameter plane's pixel: its parameters set as the map
/// sets them (a ratio after the value it multiplies, whichever comes first), the same rows as
/// the parameters given outright; a start's component, a value out of its range, two that
/// set one value, or one a flag gives too are refused naming the flag.
#[test]
fn a_parameter_planes_pixel_runs_as_a_trajectory() {
    let run = |extra: &str| {
        let out = common::chaoscope()
            .args("trajectory --theta1 2 --theta2 2 --t-max 1 --dt 0.01".split(' '))
            .args(extra.split(' '))
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (code, given, err) = run("--m1 2 --m2 5 --l1 0.5 --l2 0.35");
    assert_eq!(code, Some(0), "{err}");
    for at in [
        "--at l2/l1=0.7 --at m2/m1=2.5 --m1 2 --l1 0.5",
        "--m1 2 --l1 0.5 --at m2/m1=2.5 --at l2/l1=0.7",
        "--at m1=2 --at m2/m1=2.5 --l1 0.5 --l2 0.35",
    ] {
        let (code, rows, err) = run(at);
        assert_eq!(code, Some(0), "{at}: {err}");
        // The same parameters to rounding (2.5 x 2 and 0.7 x 0.5 are exact in binary but
        // 0.35 is not): the rows agree to the last digits of the CSV.
        let numbers = |s: &str| -> Vec<f64> {
            s.lines()
                .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
                .flat_map(|l| {
                    l.split(',')
                        .map(|x| x.parse::<f64>().unwrap())
                        .collect::<Vec<_>>()
                })
                .collect()
        };
        let (a, b) = (numbers(&rows), numbers(&given));
        assert_eq!(a.len(), b.len(), "{at}");
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{at}: {worst}");
    }
    for (bad, says) in [
        ("--at theta1=1", "--at"),
        ("--at g=-1", "--at"),
        ("--at m2=1 --at m2/m1=2", "--at"),
        ("--m2 3 --at m2/m1=2", "--m2"),
        ("--at mass=1", "--at"),
    ] {
        let (code, _, err) = run(bad);
        assert_eq!(code, Some(2), "{bad}: {err}");
        assert!(err.contains(says), "{bad}: {err}");
    }
}
