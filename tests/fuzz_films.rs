//! Films as they come damaged, and the film commands' flags at random (the names given to
//! FFmpeg are tests/film_names.rs'): `track` and `forecast --video` on seeded mutations of a
//! small real film (cut at any byte, bytes flipped or zeroed, pieces swapped, garbage before
//! it) and on things that are no film at all; random flags on both. Every line ends within
//! its bound (30 s), never panics, exits 0 or 2 (a bad input file is the user's input: 2,
//! naming it), and nothing is left half written. `FUZZ_SHOW=1` prints each case.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

/// Mutated films per run.
const MUTANTS: usize = 40;

/// Random flag lines per run.
const LINES: usize = 40;

/// A small film of the pendulum (640 x 360, 60 frames of data/test_film.mp4) in `dir`.
fn small_film(dir: &Path) -> PathBuf {
    let film = dir.join("small.mp4");
    let made = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/test_film.mp4"))
        .args(["-frames:v", "60", "-vf", "scale=640:360", "-c:v", "libx264"])
        .args(["-crf", "23"])
        .arg(&film)
        .status()
        .unwrap();
    assert!(made.success());
    film
}

/// Runs chaoscope with `args` in `dir`; a problem with the outcome, if any.
fn outcome(dir: &Path, args: &[String], names: &[&str]) -> Option<String> {
    let out = common::chaoscope()
        .current_dir(dir)
        .args(args)
        .timeout(Duration::from_secs(30))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    if std::env::var("FUZZ_SHOW").is_ok() {
        eprintln!(
            "{code:?} chaoscope {} :: {}",
            args.join(" "),
            stderr.lines().next().unwrap_or("")
        );
    }
    // Nothing half written: no staged file left beside the outputs.
    let staged = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .any(|e| e.file_name().to_string_lossy().starts_with(".tmp"));
    let problem = match code {
        _ if stderr.contains("panicked") => "panicked",
        None => "killed (a hang past 30 s, or a signal)",
        _ if staged => "a staged file left behind",
        Some(0) => return None,
        Some(2) if names.iter().any(|n| stderr.contains(n)) => return None,
        Some(2) => "exit 2 naming no input",
        Some(_) => "an exit other than 0 or 2",
    };
    Some(format!(
        "{problem}: chaoscope {} -> {code:?}\n{stderr}",
        args.join(" ")
    ))
}

fn words(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

#[test]
fn damaged_films_are_refused_by_name_or_tracked() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = small_film(dir.path());
    let whole = std::fs::read(&film).unwrap();
    let mut rng = fastrand::Rng::with_seed(20261205);
    let mut cases: Vec<(String, Vec<u8>)> = vec![
        ("empty".into(), Vec::new()),
        ("text".into(), b"t,x1,y1,x2,y2\n0,0,0,0,0\n".to_vec()),
        ("a PNG".into(), {
            let mut png = Vec::new();
            image_png(&mut png);
            png
        }),
        ("its first 100 bytes".into(), whole[..100].to_vec()),
    ];
    for k in 0..MUTANTS {
        let mut bytes = whole.clone();
        let n = bytes.len();
        let what = match k % 5 {
            0 => {
                let at = rng.usize(1..n);
                bytes.truncate(at);
                format!("cut at {at}")
            }
            1 => {
                for _ in 0..16 {
                    let at = rng.usize(..n);
                    bytes[at] ^= 1 << rng.u8(..8);
                }
                "16 bits flipped".into()
            }
            2 => {
                let at = rng.usize(..n);
                let len = rng.usize(1..=(n - at).min(512));
                bytes[at..at + len].fill(0);
                format!("{len} bytes zeroed at {at}")
            }
            3 => {
                let at = rng.usize(1..n);
                bytes.rotate_left(at);
                format!("halves swapped at {at}")
            }
            _ => {
                let garbage: Vec<u8> = (0..rng.usize(1..64)).map(|_| rng.u8(..)).collect();
                bytes.splice(0..0, garbage);
                "garbage before it".into()
            }
        };
        cases.push((what, bytes));
    }
    let mut failures = Vec::new();
    for (k, (what, bytes)) in cases.iter().enumerate() {
        let name = format!("case{k}.mp4");
        std::fs::write(dir.path().join(&name), bytes).unwrap();
        let csv = format!("case{k}.csv");
        let args = words(&["track", &name, "--l1", "0.3", "--output", &csv]);
        if let Some(p) = outcome(dir.path(), &args, &["VIDEO", "--video"]) {
            failures.push(format!("{what}: {p}"));
        }
    }
    // A folder and a FIFO where a film should be.
    std::fs::create_dir(dir.path().join("folder.mp4")).unwrap();
    let fifo = dir.path().join("fifo.mp4");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    for name in ["folder.mp4", "fifo.mp4"] {
        let args = words(&["track", name, "--l1", "0.3", "--output", "x.csv"]);
        if let Some(p) = outcome(dir.path(), &args, &["VIDEO", "--video"]) {
            failures.push(format!("{name}: {p}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        cases.len() + 2,
        failures.join("\n")
    );
}

/// A one-pixel PNG's bytes.
fn image_png(out: &mut Vec<u8>) {
    let mut encoder = png::Encoder::new(out, 1, 1);
    encoder.set_color(png::ColorType::Rgb);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&[0, 0, 0]).unwrap();
}

/// Random flags on `track` and on `forecast --video` (a film mutated now and then): the
/// same rules as tests/fuzz.rs, on the film surfaces.
#[test]
fn random_film_flags_never_panic_and_name_what_is_wrong() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = small_film(dir.path());
    let track = common::chaoscope()
        .current_dir(dir.path())
        .args(["track", "small.mp4", "--l1", "0.3", "--output", "small.csv"])
        .output()
        .unwrap();
    assert!(track.status.success());
    let whole = std::fs::read(&film).unwrap();
    std::fs::write(dir.path().join("cut.mp4"), &whole[..whole.len() / 2]).unwrap();
    const VALUES: &[&str] = &[
        "0",
        "1",
        "-1",
        "0.5",
        "nan",
        "inf",
        "1e308",
        "abc",
        "",
        "0:1",
        "1:0",
        "0,0,10,10",
        "9999,9999,1,1",
        "leds",
        "white",
        "lab",
        "small.mp4",
        "cut.mp4",
        "missing.mp4",
        "small.csv",
        "out",
        "--l1",
    ];
    // Flags the base lines do not already hold (a second one is only clap's refusal).
    // Flags the base lines do not already hold (a second one is only clap's refusal), each
    // with a good value (None: a switch).
    let track_flags = [
        ("--markers", Some("ffffff")),
        ("--region", Some("0,0,640,360")),
        ("--bridge", None),
        ("--preset", Some("lab")),
        ("--json", None),
    ];
    let forecast_flags = [
        ("--window", Some("0.3:1.2")),
        ("--tolerance", Some("0.02")),
        ("--seed", Some("7")),
        ("--tracking-error", Some("0.001")),
        ("--json", None),
    ];
    let mut rng = fastrand::Rng::with_seed(20261206);
    let mut failures = Vec::new();
    for k in 0..LINES {
        let mut line: Vec<String> = if k % 2 == 0 {
            words(&["track", "small.mp4", "--l1", "0.3"])
                .into_iter()
                .chain(["--output".to_string(), format!("t{k}.csv")])
                .collect()
        } else {
            words(&[
                "forecast",
                "small.csv",
                "--video",
                if rng.u8(..4) == 0 {
                    "cut.mp4"
                } else {
                    "small.mp4"
                },
                "--preset",
                "lab",
                "--held-out",
                "0",
                "--members",
                "20",
                "--candidates",
                "64",
                "--backend",
                "cpu",
                "--output",
                &format!("f{k}"),
            ])
        };
        let flags: &[(&str, Option<&str>)] = if k % 2 == 0 {
            &track_flags
        } else {
            &forecast_flags
        };
        let mut picked: Vec<&str> = Vec::new();
        for _ in 0..rng.usize(1..=2) {
            let (flag, good) = flags[rng.usize(..flags.len())];
            if picked.contains(&flag) {
                continue;
            }
            picked.push(flag);
            line.push(flag.to_string());
            line.extend(common::fuzz_value(&mut rng, good, VALUES));
        }
        if let Some(p) = outcome(dir.path(), &line, &["--", "FILE", "VIDEO", "<"]) {
            failures.push(p);
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {LINES} lines:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
