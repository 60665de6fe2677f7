//! The uncertainty exponent (issue 22): the estimator on boundaries of known dimension, the
//! seeded pairs on both paths, and `chaoscope boundary` end to end.

mod common;

use chaoscope::boundary::{Level, count, eps_levels, fit, level_seed};
use chaoscope::engine::{Backend, Engine};
use chaoscope::model::Params;
use chaoscope::monitor::Monitor;
use chaoscope::spec::{Axis, FlipMeasure, FlipSpec, Grid, Precision, Sampling, Stepping, Var};

/// Pairs over the unit square (x, y as two parameters' axes: only the geometry is used).
fn unit_pairs(pairs: u32, seed: u32, eps: f64) -> Grid {
    Grid {
        width: 2 * 256,
        height: pairs / 256,
        x: Axis::new(Var::Theta1, 0.0, 1.0),
        y: Axis::new(Var::Theta2, 0.0, 1.0),
        fixed: Default::default(),
        sampling: Sampling::Pairs { seed, eps },
    }
}

/// The levels of a synthetic class over the unit square, drawn as `boundary` draws them.
fn levels_of(class: impl Fn(f64, f64) -> u32, eps: (f64, f64), n: u32) -> Vec<Level> {
    eps_levels(eps.0, eps.1, n)
        .into_iter()
        .enumerate()
        .map(|(k, e)| {
            let g = unit_pairs(40960, level_seed(7, k as u32), e);
            let mut classes = Vec::new();
            for row in 0..g.height {
                for pair in 0..g.width / 2 {
                    let member = |m: u32| {
                        let (x, y) = g.xy(2 * pair + m, row);
                        Some(class(x, y))
                    };
                    classes.push([member(0), member(1)]);
                }
            }
            count(e, &classes)
        })
        .collect()
}

#[test]
fn a_smooth_boundary_has_alpha_one() {
    // A straight line: a pair straddles it with probability eps / 2 (half the pairs move
    // along x), f = eps / 2 exactly in expectation, alpha = 1.
    let levels = levels_of(|x, _| (x > 0.3) as u32, (1e-3, 1e-1), 7);
    let f = fit(&levels).expect("enough uncertain pairs");
    eprintln!("half-plane: alpha {:.4} +- {:.4}", f.alpha, f.alpha_se);
    // Binomial noise only: within three standard errors, and the error itself small.
    assert!(
        (f.alpha - 1.0).abs() <= 3.0 * f.alpha_se && f.alpha_se < 0.05,
        "{f:?}"
    );
    assert!((f.dimension() - 1.0).abs() <= 3.0 * f.alpha_se);
}

#[test]
fn a_cantor_set_of_stripes_has_its_dimension() {
    // Stripes in x coloured by the step of the middle-thirds construction that removes x
    // (odd or even): the boundary is the Cantor set times a line, D = 1 + ln 2 / ln 3,
    // alpha = 1 - ln 2 / ln 3 = 0.369 (Grebogi et al. 1983's own example).
    let cantor = |x: f64, _: f64| {
        let mut x = x;
        for depth in 0..30u32 {
            let digit = (x * 3.0).floor();
            if digit == 1.0 {
                return depth % 2;
            }
            x = x * 3.0 - digit;
        }
        2
    };
    let levels = levels_of(cantor, (1e-5, 1e-1), 13);
    let f = fit(&levels).expect("enough uncertain pairs");
    let alpha = 1.0 - 2f64.ln() / 3f64.ln();
    eprintln!(
        "Cantor stripes: alpha {:.4} +- {:.4} (exact {alpha:.4}), reduced chi2 {:.2}",
        f.alpha, f.alpha_se, f.reduced_chi2
    );
    // Within three standard errors (widened by the fit's scatter: f of a Cantor set
    // oscillates in log eps with period ln 3 about the power law).
    assert!(
        (f.alpha - alpha).abs() <= 3.0 * f.alpha_se && f.alpha_se < 0.05,
        "alpha {alpha} vs {f:?}"
    );
    // And not the smooth boundary's.
    assert!((f.alpha - 1.0).abs() > 10.0 * f.alpha_se, "{f:?}");
}

#[test]
fn pairs_are_seeded_inside_the_plane_and_eps_apart() {
    let g = unit_pairs(1024, 3, 1e-3);
    let again = unit_pairs(1024, 3, 1e-3);
    let other = unit_pairs(1024, 4, 1e-3);
    let mut moved = 0;
    for row in 0..g.height {
        for pair in 0..g.width / 2 {
            let (a, b) = (g.xy(2 * pair, row), g.xy(2 * pair + 1, row));
            assert_eq!(
                (a, b),
                (again.xy(2 * pair, row), again.xy(2 * pair + 1, row))
            );
            assert_ne!(a, other.xy(2 * pair, row));
            for v in [a.0, a.1, b.0, b.1] {
                assert!((0.0..=1.0).contains(&v), "{a:?} {b:?}");
            }
            let (dx, dy) = ((a.0 - b.0).abs(), (a.1 - b.1).abs());
            // One coordinate moved by eps (the width is 1), up to its rounding.
            assert!(
                (dx - 1e-3).abs() < 1e-15 && dy == 0.0 || (dy - 1e-3).abs() < 1e-15 && dx == 0.0
            );
            moved += (dx > 0.0) as u32;
        }
    }
    // Along x about half the time.
    assert!((400..624).contains(&moved), "{moved} of 1024 along x");
}

#[test]
fn gpu_pairs_are_the_cpus() {
    let Some(ctx) = common::f64_gpu() else { return };
    let gpu = Engine::on_gpu(ctx);
    let cpu = Engine::new(Backend::Cpu).unwrap();
    let spec = |precision| FlipSpec {
        measure: FlipMeasure::Time,
        precision,
        use_symmetry: false,
        ..FlipSpec::new(
            Params::default(),
            Grid {
                width: 64,
                height: 8,
                sampling: Sampling::Pairs {
                    seed: 11,
                    eps: 1e-4,
                },
                ..Grid::square(1)
            },
            Stepping {
                dt: 0.01,
                t_max: 2.0,
            },
        )
    };
    let c = cpu.map(&spec(Precision::F64), &Monitor::hidden()).unwrap();
    let g = gpu.map(&spec(Precision::F64), &Monitor::hidden()).unwrap();
    let flipped = c.data.iter().filter(|t| t.is_finite()).count();
    assert!(flipped > 50, "{flipped} of 512 starts flip within 2 s");
    for (a, b) in g.data.iter().zip(&c.data) {
        // The same starts (the hash and its arithmetic alike in f64), integrated by two
        // codes: round-off of 1e-16 grown by at most e^(10/s * 2 s) ~ 5e8 is far below
        // 1e-4 s; different starts (eps = 1e-4 of the plane apart or anywhere) would not be.
        assert!(
            a == b || (a - b).abs() <= 1e-4,
            "gpu {a} vs cpu {b}: not the same starts"
        );
    }
    // f32: the starts rounded to f32, so within a step where the motion is regular.
    let g32 = gpu.map(&spec(Precision::F32), &Monitor::hidden()).unwrap();
    let agree = g32
        .data
        .iter()
        .zip(&c.data)
        .filter(|(a, b)| a == b || (*a - *b).abs() <= 0.011)
        .count();
    assert!(agree >= 480, "{agree} of 512 within a step");
}

/// The job a command line describes.
fn job(line: &str) -> Option<chaoscope::cli::Job> {
    let words: Vec<String> = line.split_whitespace().map(String::from).collect();
    chaoscope::cli::Cli::parse_args(words)
        .unwrap()
        .command
        .job()
        .unwrap()
}

#[test]
fn the_chaotic_class_by_an_indicator_reproduces_too() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("c.png");
    let base = "boundary --t-max 2 --pairs 256 --levels 3 --eps 1e-2:1e-1 --class chaotic --indicator ftle --renorm 0.05";
    common::chaoscope()
        .args(base.split_whitespace())
        .arg("--output")
        .arg(&png)
        .assert()
        .success();
    let command = common::png_text(&png, "chaoscope:command");
    for flags in ["--class chaotic", "--indicator ftle --renorm 0.05"] {
        assert!(command.contains(flags), "{command}");
    }
    assert_eq!(job(&command), job(&format!("chaoscope {base}")));
}

#[test]
fn boundary_runs_end_to_end_and_its_command_reproduces_it() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("b.png");
    let csv = dir.path().join("b.csv");
    let out = common::chaoscope()
        .args("boundary --t-max 3 --pairs 512 --levels 4 --eps 1e-3:1e-1 --class flipped --json --output".split(' '))
        .arg(&png)
        .arg("--data")
        .arg(&csv)
        .output()
        .unwrap();
    let summary = common::summary(out);
    let levels = summary["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 4);
    for l in levels {
        assert_eq!(l["pairs"], 512);
        assert!(l["resolved"].as_u64().unwrap() <= 512);
    }
    let rows = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(rows.lines().count(), 2 + 4, "{rows}");
    let command = common::png_text(&png, "chaoscope:command");
    let again = job(&format!(
        "{command} --output {} --data {}",
        png.display(),
        csv.display()
    ));
    let original = job(&format!(
        "chaoscope boundary --t-max 3 --pairs 512 --levels 4 --eps 1e-3:1e-1 --class flipped --output {} --data {}",
        png.display(),
        csv.display()
    ));
    assert_eq!(again, original);
}

#[test]
fn bad_boundary_input_is_refused_naming_the_flag() {
    let cases: &[(&[&str], &str)] = &[
        (&["--pairs", "0"], "--pairs"),
        (&["--eps", "0:1e-1"], "--eps"),
        (&["--eps", "1e-1:1e-2"], "--eps"),
        (&["--eps", "1e-3:0.5"], "--eps"),
        (&["--levels", "2"], "--levels"),
        (&["--class", "chaos"], "--class"),
        (&["--x", "m2=0:1"], "--x"),
        (&["--indicator", "ftle"], "--indicator"),
        (&["--renorm", "0.1"], "--renorm"),
        (&["--class", "chaotic", "--renorm", "0.015"], "--renorm"),
    ];
    common::refuses(&["boundary", "--t-max", "1", "--backend", "cpu"], cases);
}
