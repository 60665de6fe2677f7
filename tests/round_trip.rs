//! Every command's stored command line (PNG text, CSV `#` line, summary.json) parses back to
//! the job that made it, and running it again writes the same bytes.

mod common;

use std::path::{Path, PathBuf};

use chaoscope::cli::{Cli, Job, LyapunovJob};
use clap::Parser;
use common::{argv, chaoscope, png_text};

/// The job of a command line, with its output paths cleared (they are not part of the
/// stored command).
fn job(args: &[String]) -> Job {
    let cli = Cli::try_parse_from(args).unwrap_or_else(|e| panic!("{args:?} does not parse: {e}"));
    let mut job = cli
        .command
        .job()
        .unwrap()
        .expect("a command that makes files");
    let none = PathBuf::new;
    match &mut job {
        Job::Flip(j) => (j.files.output, j.files.data, j.files.resolved) = (none(), None, None),
        Job::Lyapunov(LyapunovJob::Map(j)) => {
            (j.files.output, j.files.data, j.files.resolved) = (none(), None, None)
        }
        Job::Lyapunov(LyapunovJob::Point(j)) => j.output = None,
        Job::Trajectory(j) => j.output = None,
        Job::Sweep(j) => (j.output, j.film.path) = (none(), none()),
        Job::Traces(j) => (j.output, j.film, j.data) = (none(), None, None),
        Job::Phase(j) => j.output = none(),
        Job::Fit(j) => j.output = none(),
        Job::Forecast(j) => j.output = none(),
        Job::Twin(j) => j.output = none(),
        Job::Boundary(j) => (j.output, j.data) = (none(), None),
    }
    job
}

fn words(line: &str) -> Vec<String> {
    line.split_whitespace().map(String::from).collect()
}

/// Runs `args` followed by `outputs` (output flags and paths), reads the stored command with
/// `stored`, checks it parses to the same job, runs it followed by `outputs2` and compares
/// each pair of `compare` byte for byte.
fn round_trip(
    args: &[&str],
    outputs: &[&Path],
    stored: impl Fn() -> String,
    outputs2: &[&Path],
    compare: &[(&Path, &Path)],
) {
    let given: Vec<String> = std::iter::once("chaoscope")
        .chain(args.iter().copied())
        .map(String::from)
        .collect();
    let run = |line: &[String], outs: &[&Path]| {
        let mut cmd = chaoscope();
        cmd.args(&line[1..]);
        for o in outs {
            cmd.arg(o);
        }
        cmd.assert().success();
    };
    run(&given, outputs);
    let command = stored();
    let again = words(&command);
    assert_eq!(
        job(&again),
        job(&given),
        "stored command `{command}` is another job than {given:?}"
    );
    run(&again, outputs2);
    for (a, b) in compare {
        assert!(
            std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
            "{} and {} differ (command `{command}`)",
            a.display(),
            b.display()
        );
    }
}

/// The GPU when there is one (lavapipe in CI), else the CPU.
fn backend() -> &'static str {
    if common::gpu().is_some() {
        "gpu"
    } else {
        "cpu"
    }
}

#[test]
fn flip_maps_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    for (k, extra) in [
        vec!["--size", "40x24", "--t-max", "3", "--theta2", "-3:3"],
        argv("--size 16 --t-max 2 --preset lab --no-symmetry --annotate"),
        argv("--size 12 --t-max 2 --full --colormap viridis --omega1 -1"),
        vec!["--size", "10", "--t-max", "2", "--precision", "f64"],
        vec!["--size", "10", "--t-max", "3", "--accurate"],
        vec!["--size", "6", "--t-max", "2", "--samples", "2"],
        argv("--size 12x8 --t-max 2 --x theta1 --y omega1=-3:3 --theta2 0.5 --omega2 0.25 --annotate"),
        argv("--size 10 --t-max 2 --x m2/m1=0.5:2 --y l2/l1=0.5:2 --theta1 2 --theta2 2.5 --m1 0.8"),
        argv("--size 10 --t-max 3 --integrator dp54 --atol 1e-4"),
    ]
    .into_iter()
    .enumerate()
    {
        let (png, npy, png2, npy2) = (
            d(&format!("a{k}.png")),
            d(&format!("a{k}.npy")),
            d(&format!("b{k}.png")),
            d(&format!("b{k}.npy")),
        );
        let mut args = vec!["flip", "--backend", backend()];
        args.extend(extra);
        args.extend([
            "--output",
            png.to_str().unwrap(),
            "--data",
            npy.to_str().unwrap(),
        ]);
        round_trip(
            &args,
            &[],
            || png_text(&png, "chaoscope:command"),
            &[Path::new("--output"), &png2, Path::new("--data"), &npy2],
            &[(&png, &png2), (&npy, &npy2)],
        );
    }
}

#[test]
fn lyapunov_maps_and_points_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let (png, png2) = (d("a.png"), d("b.png"));
    round_trip(
        &[
            "lyapunov",
            "--size",
            "24x16",
            "--t-max",
            "2",
            "--backend",
            backend(),
            "--annotate",
        ],
        &[Path::new("--output"), &png],
        || png_text(&png, "chaoscope:command"),
        &[Path::new("--output"), &png2],
        &[(&png, &png2)],
    );
    let (png, png2) = (d("c.png"), d("d.png"));
    round_trip(
        &argv(
            "lyapunov --size 8 --t-max 1 --backend cpu --method twin --eps 1e-6 --joint-damping 0.01,0.02 --colour-range 0.1:0.75",
        ),
        &[Path::new("--output"), &png],
        || png_text(&png, "chaoscope:command"),
        &[Path::new("--output"), &png2],
        &[(&png, &png2)],
    );
    // Every indicator and its settings come back from the PNG's command.
    for (k, flags) in [
        &["--indicator", "exponent", "--exponent", "3"][..],
        &["--indicator", "exponent-sum"],
        &["--indicator", "sali"],
        &[
            "--indicator",
            "gali-time",
            "--gali",
            "3",
            "--threshold",
            "1e-4",
        ],
        &["--indicator", "megno"],
        &["--indicator", "fli"],
        &["--indicator", "descriptor", "--ld-p", "0.25"],
    ]
    .into_iter()
    .enumerate()
    {
        let (png, png2) = (d(&format!("i{k}.png")), d(&format!("j{k}.png")));
        let mut args = vec![
            "lyapunov",
            "--size",
            "8x6",
            "--t-max",
            "1",
            "--backend",
            backend(),
        ];
        args.extend(flags);
        round_trip(
            &args,
            &[Path::new("--output"), &png],
            || png_text(&png, "chaoscope:command"),
            &[Path::new("--output"), &png2],
            &[(&png, &png2)],
        );
    }
    let (csv, csv2) = (d("a.csv"), d("b.csv"));
    round_trip(
        &[
            "lyapunov", "--theta1", "pi/2", "--theta2", "2", "--t-max", "2", "--renorm", "0.2",
        ],
        &[Path::new("--output"), &csv],
        || first_line(&csv),
        &[Path::new("--output"), &csv2],
        &[(&csv, &csv2)],
    );
}

/// The `#` line of a CSV, without the `# `.
fn first_line(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .next()
        .and_then(|l| l.strip_prefix("# "))
        .expect("a # line with the command")
        .to_string()
}

#[test]
fn trajectories_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, csv2) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    round_trip(
        &argv(
            "trajectory --theta1 1 --theta2 -2 --omega2 0.5 --t-max 1 --every 0.05 --air-drag --m2 0.5",
        ),
        &[Path::new("--output"), &csv],
        || first_line(&csv),
        &[Path::new("--output"), &csv2],
        &[(&csv, &csv2)],
    );
    if common::gpu().is_some_and(|c| c.has_f64()) {
        let (csv, csv2) = (dir.path().join("c.csv"), dir.path().join("d.csv"));
        round_trip(
            &argv("trajectory --theta1 1 --theta2 2 --t-max 0.5 --backend gpu --precision f64"),
            &[Path::new("--output"), &csv],
            || first_line(&csv),
            &[Path::new("--output"), &csv2],
            &[(&csv, &csv2)],
        );
    }
}

#[test]
fn traces_and_phase_portraits_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let (png, png2, npy, npy2) = (d("t.png"), d("t2.png"), d("t.npy"), d("t2.npy"));
    round_trip(
        &argv(
            "traces --theta1 2.4 --theta2 2 --exposure 0.5 --size 64 --runs 4 --spread 2cm --backend cpu",
        ),
        &[Path::new("--output"), &png, Path::new("--data"), &npy],
        || png_text(&png, "chaoscope:command"),
        &[Path::new("--output"), &png2, Path::new("--data"), &npy2],
        &[(&png, &png2), (&npy, &npy2)],
    );
    let (png, png2) = (d("p.png"), d("p2.png"));
    round_trip(
        &argv(
            "phase --theta1 1 --theta2 1.5 --t-max 2 --size 64 --runs 2 --spread 0.02 --colormap magma --backend cpu",
        ),
        &[Path::new("--output"), &png],
        || png_text(&png, "chaoscope:command"),
        &[Path::new("--output"), &png2],
        &[(&png, &png2)],
    );
    let (png, png2) = (d("s.png"), d("s2.png"));
    round_trip(
        &[
            "phase", "--single", "--t-max", "3", "--size", "64", "--l1", "0.5",
        ],
        &[Path::new("--output"), &png],
        || png_text(&png, "chaoscope:command"),
        &[Path::new("--output"), &png2],
        &[(&png, &png2)],
    );
    if common::gpu().is_some_and(|c| c.has_f64()) {
        let (png, png2) = (d("f.png"), d("f2.png"));
        round_trip(
            &argv(
                "traces --theta1 2 --theta2 2 --exposure 0.3 --size 32 --backend gpu --precision f64",
            ),
            &[Path::new("--output"), &png],
            || png_text(&png, "chaoscope:command"),
            &[Path::new("--output"), &png2],
            &[(&png, &png2)],
        );
        assert_eq!(png_text(&png, "chaoscope:backend"), "gpu f64");
    }
}

#[test]
fn sweeps_and_their_frames_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    round_trip(
        &[
            "sweep",
            "--vary",
            "m2/m1=0.5:2",
            "--frames",
            "3",
            "--size",
            "16",
            "--t-max",
            "2",
            "--backend",
            backend(),
            "--annotate",
        ],
        &[Path::new("--output"), &a],
        || png_text(&a.join("animation.png"), "chaoscope:command"),
        &[Path::new("--output"), &b],
        &[
            (&a.join("animation.png"), &b.join("animation.png")),
            (&a.join("frame_0002.png"), &b.join("frame_0002.png")),
        ],
    );
    // A frame's own command is the single map it shows.
    let frame = a.join("frame_0001.png");
    let single = dir.path().join("single.png");
    let mut line = words(&png_text(&frame, "chaoscope:command"));
    line.extend(["--output".into(), single.display().to_string()]);
    chaoscope().args(&line[1..]).assert().success();
    let (f, s) = (
        chaoscope::render::read_png(&frame).unwrap(),
        chaoscope::render::read_png(&single).unwrap(),
    );
    assert!(f.rgb == s.rgb, "frame 1 differs from its own command's map");
}

#[test]
fn fits_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv");
    round_trip(
        &[
            "fit",
            data.to_str().unwrap(),
            "--candidates",
            "256",
            "--start",
            "0.8",
            "--window",
            "1",
            "--backend",
            "cpu",
            "--preset",
            "lab",
            "--m1",
            "0.3",
        ],
        &[Path::new("--output"), &a],
        || {
            let text = std::fs::read_to_string(a.join("summary.json")).unwrap();
            let json: serde_json::Value = serde_json::from_str(&text).unwrap();
            json["command"].as_str().expect("a command").to_string()
        },
        &[Path::new("--output"), &b],
        &[
            (&a.join("summary.json"), &b.join("summary.json")),
            (&a.join("positions.png"), &b.join("positions.png")),
        ],
    );
}

#[test]
fn forecasts_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv");
    let stored = |dir: &Path| {
        let dir = dir.to_path_buf();
        move || {
            let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
            let json: serde_json::Value = serde_json::from_str(&text).unwrap();
            json["command"].as_str().expect("a command").to_string()
        }
    };
    round_trip(
        &[
            "forecast",
            data.to_str().unwrap(),
            "--window",
            "0.6:1.7",
            "--members",
            "200",
            "--candidates",
            "256",
            "--seed",
            "7",
            "--tracking-error",
            "1cm",
            "--preset",
            "lab",
            "--backend",
            "cpu",
        ],
        &[Path::new("--output"), &a],
        stored(&a),
        &[Path::new("--output"), &b],
        &[
            (&a.join("summary.json"), &b.join("summary.json")),
            (&a.join("bands.csv"), &b.join("bands.csv")),
            (&a.join("forecast.png"), &b.join("forecast.png")),
        ],
    );
    let (c, d) = (dir.path().join("c"), dir.path().join("d"));
    round_trip(
        &argv(
            "twin --sigma 2mm --rate 50 --replicates 1 --duration 1.5 --members 100 --candidates 256 --backend cpu",
        ),
        &[Path::new("--output"), &c],
        stored(&c),
        &[Path::new("--output"), &d],
        &[
            (&c.join("summary.json"), &d.join("summary.json")),
            (&c.join("twin.csv"), &d.join("twin.csv")),
        ],
    );
}
