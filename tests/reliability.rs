//! The third audit's cases (issue 35): no output replaces what is not a regular file, no
//! input is read without a bound, no two files of a run are one, no axis overrides a flag,
//! every listed plane works, and each message names what is wrong. FIFOs are made in temporary
//! directories: a test never touches a real /dev node.

mod common;

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use chaoscope::spec::{AxisAsked, PlaneAsked, Var};
use common::{argv, chaoscope};

fn lab() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv")
}

fn mkfifo(path: &Path) {
    let status = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap();
    assert!(status.success(), "mkfifo {}", path.display());
}

fn is_fifo(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// Runs `args` and expects exit 2 with `words` on stderr, within a bound that only a hang
/// (a blocked read of a FIFO, an endless read of a device) passes; returns the time taken.
fn refused(args: &[String], words: &[&str]) -> Duration {
    let started = Instant::now();
    let out = chaoscope()
        .args(args)
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    let took = started.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    for w in words {
        assert!(stderr.contains(w), "{args:?} does not name {w}: {stderr}");
    }
    took
}

fn words(s: &[&str]) -> Vec<String> {
    s.iter().map(|s| s.to_string()).collect()
}

/// Every command and output flag, its file's extension ("" for a directory) and the flags
/// that keep the command cheap.
fn output_flags(store: &Path) -> Vec<(Vec<String>, &'static str, &'static str)> {
    let lab = lab().display().to_string();
    let map = words(&["flip", "--size", "8", "--t-max", "1", "--backend", "cpu"]);
    let lyap = words(&argv("lyapunov --size 8 --t-max 1 --backend cpu"));
    let spectrum = words(&argv(
        "lyapunov --size 8 --t-max 1 --indicator exponent-sum --backend cpu",
    ));
    let point = words(&["lyapunov", "--theta1", "1", "--theta2", "1", "--t-max", "1"]);
    let trajectory = words(&argv("trajectory --theta1 1 --theta2 1 --t-max 1"));
    let boundary = words(&["boundary", "--pairs", "16", "--levels", "3", "--t-max", "1"]);
    let sweep = words(&["sweep", "--vary", "g=5:10", "--frames", "2", "--size", "8"]);
    let traces = words(&argv(
        "traces --theta1 1 --theta2 1 --exposure 0.2 --size 32",
    ));
    let phase = words(&["phase", "--t-max", "0.5", "--size", "32"]);
    let fit = words(&["fit", &lab, "--preset", "lab"]);
    let forecast = words(&["forecast", &lab, "--preset", "lab"]);
    let twin = words(&["twin", "--replicates", "1"]);
    let render = vec!["render".to_string(), store.display().to_string()];
    vec![
        (map.clone(), "--output", "png"),
        (map.clone(), "--data", "npy"),
        (map, "--resolved", "npy"),
        (lyap.clone(), "--output", "png"),
        (lyap.clone(), "--data", "npy"),
        (lyap, "--resolved", "npy"),
        (spectrum, "--spectrum", "npy"),
        (point, "--output", "csv"),
        (trajectory, "--output", "csv"),
        (boundary.clone(), "--output", "png"),
        (boundary, "--data", "csv"),
        (sweep.clone(), "--output", ""),
        (sweep, "--film", "mp4"),
        (traces.clone(), "--output", "png"),
        (traces.clone(), "--film", "gif"),
        (traces.clone(), "--film", "mp4"),
        (traces, "--data", "npy"),
        (phase, "--output", "png"),
        (fit, "--output", ""),
        (forecast, "--output", ""),
        (twin, "--output", ""),
        (render, "--output", "png"),
    ]
}

/// Issue 35, item 1: run as root, `boundary --output /dev/null` renamed its PNG over the
/// device. Every output flag of every command, pointed at a FIFO and at a link to one (and,
/// for a directory's outputs, at a FIFO inside it), is refused naming the flag, and the FIFO
/// stays a FIFO.
#[test]
fn no_output_replaces_what_is_not_a_regular_file() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("s.zarr");
    chaoscope()
        .args("flip --size 8 --t-max 1 --backend cpu --data".split(' '))
        .arg(&store)
        .assert()
        .success();
    let mut count = 0;
    for (k, (args, flag, ext)) in output_flags(&store).into_iter().enumerate() {
        let here = dir.path().join(format!("case{k}"));
        std::fs::create_dir(&here).unwrap();
        let name = |n: &str| match ext {
            "" => here.join(n),
            e => here.join(format!("{n}.{e}")),
        };
        let (fifo, link) = (name("fifo"), name("link"));
        mkfifo(&fifo);
        std::os::unix::fs::symlink(&fifo, &link).unwrap();
        let mut targets = vec![fifo.clone(), link.clone()];
        if ext.is_empty() {
            // A directory's output: one of the files it writes is a FIFO.
            let inside = here.join("inside");
            std::fs::create_dir(&inside).unwrap();
            let file = match args[0].as_str() {
                "sweep" => "animation.png",
                _ => "summary.json",
            };
            mkfifo(&inside.join(file));
            targets.push(inside);
        }
        for target in targets {
            let mut line = args.clone();
            line.push(flag.to_string());
            line.push(target.display().to_string());
            refused(&line, &[flag]);
            count += 1;
        }
        assert!(is_fifo(&fifo), "{args:?} {flag}: the FIFO was replaced");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink(),
            "{args:?} {flag}: the link was replaced"
        );
    }
    eprintln!("{count} command lines (commands x output flags x non-regular targets) refused");
    assert_eq!(count, 2 * 22 + 4);
}

/// Issue 35, item 2: `fit /dev/zero` read until the kernel killed it at 24 GB. Inputs that
/// are devices, FIFOs, directories or larger than their format's cap (a 10 GB sparse file)
/// are refused naming the file, before a byte is read; the time each took is printed (the
/// bound here only catches a hang: timings belong in benchmarks).
#[test]
fn every_read_is_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.csv");
    mkfifo(&fifo);
    let sparse = dir.path().join("sparse.csv");
    std::fs::File::create(&sparse)
        .unwrap()
        .set_len(10 << 30)
        .unwrap();
    let sparse_toml = dir.path().join("sparse.toml");
    std::fs::File::create(&sparse_toml)
        .unwrap()
        .set_len(10 << 30)
        .unwrap();
    let (fifo, sparse, sparse_toml) = (
        fifo.display().to_string(),
        sparse.display().to_string(),
        sparse_toml.display().to_string(),
    );
    let flip = [
        "flip",
        "--size",
        "4",
        "--t-max",
        "1",
        "--backend",
        "cpu",
        "--params",
    ];
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (
            words(&["fit", "/dev/zero"]),
            vec!["FILE", "not a regular file"],
        ),
        (
            words(&["forecast", "/dev/zero"]),
            vec!["FILE", "not a regular file"],
        ),
        (
            words(&[&flip[..], &["/dev/zero"]].concat()),
            vec!["--params", "not a regular file"],
        ),
        (words(&["fit", &fifo]), vec!["FILE", "not a regular file"]),
        (
            words(&[&flip[..], &[fifo.as_str()]].concat()),
            vec!["--params", "not a regular file"],
        ),
        (
            words(&["fit", &sparse]),
            vec!["FILE", "10.0 GiB", "256.0 MiB"],
        ),
        (
            words(&[&flip[..], &[sparse_toml.as_str()]].concat()),
            vec!["--params", "64.0 KiB"],
        ),
        (
            words(&["fit", "/nonexistent.csv"]),
            vec!["FILE", "no such file"],
        ),
        (words(&["fit", "/tmp"]), vec!["FILE", "a directory"]),
    ];
    for (args, expect) in cases {
        let took = refused(&args, &expect);
        eprintln!("{args:?}: refused in {took:?}");
    }
}

/// Issue 35, item 3: `--spectrum x.npy --data x.npy` left the spectrum where the map was.
#[test]
fn no_two_files_of_a_run_are_one() {
    let dir = tempfile::tempdir().unwrap();
    let at = |n: &str| dir.path().join(n).display().to_string();
    let spectrum = words(&argv(
        "lyapunov --indicator exponent-sum --size 4 --t-max 1 --backend cpu",
    ));
    let line = |base: &[String], extra: &[&str]| [base, &words(extra)[..]].concat();
    refused(
        &line(
            &spectrum,
            &["--spectrum", &at("x.npy"), "--data", &at("x.npy")],
        ),
        &["--spectrum", "--data"],
    );
    // The same file by another name (a link, a `..`).
    std::fs::write(dir.path().join("x.npy"), "kept").unwrap();
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    std::os::unix::fs::symlink(dir.path().join("x.npy"), dir.path().join("y.npy")).unwrap();
    refused(
        &line(
            &spectrum,
            &["--data", &at("x.npy"), "--spectrum", &at("y.npy")],
        ),
        &["--spectrum", "--data"],
    );
    refused(
        &line(
            &spectrum,
            &["--data", &at("x.npy"), "--resolved", &at("sub/../x.npy")],
        ),
        &["--resolved"],
    );
    // An input where the output directory writes one of its files.
    let out = dir.path().join("fit");
    std::fs::create_dir(&out).unwrap();
    std::fs::copy(lab(), out.join("derived.csv")).unwrap();
    refused(
        &words(&["fit", &at("fit/derived.csv"), "--output", &at("fit")]),
        &["--output", "reads"],
    );
    assert_eq!(
        std::fs::read(out.join("derived.csv")).unwrap(),
        std::fs::read(lab()).unwrap()
    );
    assert_eq!(std::fs::read_to_string(at("x.npy")).unwrap(), "kept");
}

/// Issue 35, item 4: `flip --m2 2 --x m2/m1=0.5:2` mapped m2 = ratio x m1, ignoring --m2.
#[test]
fn no_axis_overrides_a_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png").display().to_string();
    for command in ["flip", "lyapunov", "sweep", "boundary"] {
        let mut base = words(&[command, "--t-max", "1", "--backend", "cpu"]);
        match command {
            "sweep" => base.extend(words(&["--vary", "l1=1:2", "--frames", "2", "--size", "4"])),
            "boundary" => base.extend(words(&["--pairs", "16", "--levels", "3"])),
            _ => base.extend(words(&["--size", "4", "--output", &out])),
        }
        let cases: &[(&[&str], &[&str])] = &[
            (&["--m2", "2", "--x", "m2/m1=0.5:2"], &["--m2", "m2/m1"]),
            (&["--g", "5", "--y", "g=1:20"], &["--g", "g along y"]),
            (
                &["--joint-damping", "0.1", "--x", "joint1=0:0.2"],
                &["--joint-damping", "joint1"],
            ),
            (
                &["--rod-mass", "0.1,0", "--x", "rod1=0:0.2"],
                &["--rod-mass", "rod1"],
            ),
        ];
        for (extra, names) in cases {
            refused(&[&base[..], &words(extra)[..]].concat(), names);
        }
    }
    // A sweep's varied parameter is an axis too.
    let sweep = words(&["sweep", "--frames", "2", "--size", "4", "--t-max", "1"]);
    refused(
        &[&sweep[..], &words(&["--m2", "2", "--vary", "m2=1:2"])[..]].concat(),
        &["--m2", "m2"],
    );
    refused(
        &[
            &sweep[..],
            &words(&["--omega1", "1", "--vary", "omega1=0:1"])[..],
        ]
        .concat(),
        &["--omega1"],
    );
    // A pair's part an axis sets may be given as 0, and the map's command says so: it
    // remakes the map.
    chaoscope()
        .args(["flip", "--size", "4", "--t-max", "1", "--backend", "cpu"])
        .args([
            "--joint-damping",
            "0,0.02",
            "--x",
            "joint1=0:0.1",
            "--output",
            &out,
        ])
        .assert()
        .success();
    let command = common::png_text(Path::new(&out), "chaoscope:command");
    assert!(command.contains("--joint-damping 0,0.02"), "{command}");
    let again = dir.path().join("b.png");
    let mut args: Vec<String> = command
        .split_whitespace()
        .skip(1)
        .map(String::from)
        .collect();
    args.extend(["--output".to_string(), again.display().to_string()]);
    chaoscope().args(&args).assert().success();
    assert_eq!(
        chaoscope::render::read_png(Path::new(&out)).unwrap().rgb,
        chaoscope::render::read_png(&again).unwrap().rgb
    );
}

/// Issue 35, item 5: `--x joint1 --y joint2` was refused as "the same value". Every pair of
/// the axis names --x lists is accepted, or --x's help names the pair as one that sets one
/// value.
#[test]
fn every_plane_the_help_lists_works() {
    use clap::CommandFactory;
    let cli = chaoscope::cli::Cli::command();
    let flip = cli.find_subcommand("flip").unwrap();
    let help = flip
        .get_arguments()
        .find(|a| a.get_long() == Some("x"))
        .and_then(|a| a.get_help())
        .unwrap()
        .to_string()
        .replace('\n', " ");
    let listed: Vec<Var> = Var::ALL
        .into_iter()
        .filter(|v| help.contains(&format!(" {}", v.name())))
        .collect();
    assert_eq!(listed.len(), Var::ALL.len(), "--x lists every axis: {help}");
    let (mut accepted, mut refused) = (0, 0);
    for x in listed.iter().copied() {
        for y in listed.iter().copied().filter(|&y| y != x) {
            let asked = PlaneAsked {
                x: Some(AxisAsked {
                    var: x,
                    range: Some(x.default_range()),
                }),
                y: Some(AxisAsked {
                    var: y,
                    range: Some(y.default_range()),
                }),
                ..Default::default()
            };
            let checked = asked.grid((4, 4)).and_then(|g| g.validate_axes());
            match checked {
                Ok(()) => accepted += 1,
                Err(e) => {
                    // Refused only where the help says the two set one value.
                    let pair = [x.name(), y.name()];
                    assert!(
                        help.contains(&format!("{} and {}", pair[0], pair[1]))
                            || help.contains(&format!("{} and {}", pair[1], pair[0])),
                        "{x:?} x {y:?} refused ({e}) but --x's help does not say so: {help}"
                    );
                    refused += 1;
                }
            }
        }
    }
    eprintln!("{accepted} planes accepted, {refused} refused as the help says");
    assert!(accepted > 200, "{accepted}");
    // The audit's pair, run end to end.
    let dir = tempfile::tempdir().unwrap();
    chaoscope()
        .args(["flip", "--size", "4", "--t-max", "1", "--backend", "cpu"])
        .args(["--x", "joint1=0:0.2", "--y", "joint2=0:0.2", "--output"])
        .arg(dir.path().join("j.png"))
        .assert()
        .success();
}

/// Issue 35, item 7: each message names what is wrong.
#[test]
fn messages_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let lab = std::fs::read_to_string(lab()).unwrap();
    let mut lines: Vec<String> = lab.lines().map(String::from).collect();
    let header = lines.iter().position(|l| l.starts_with("t,")).unwrap();
    let csv = |name: &str, lines: &[String]| {
        let path = dir.path().join(name);
        std::fs::write(&path, lines.join("\n")).unwrap();
        path.display().to_string()
    };
    // A cell of 1e300 names the file, row and column (it was "--l1: NaN").
    let row = header + 5;
    let mut cells: Vec<String> = lines[row].split(',').map(String::from).collect();
    cells[1] = "1e300".into();
    let mut huge = lines.clone();
    huge[row] = cells.join(",");
    let path = csv("huge.csv", &huge);
    refused(
        &words(&["fit", &path]),
        &[&format!("{path}:{}", row + 1), "x1", "metres"],
    );
    // A ragged row names its row.
    lines[row].push_str(",7");
    let path = csv("ragged.csv", &lines);
    refused(
        &words(&["fit", &path]),
        &[&format!("{path}:{}", row + 1), "fields"],
    );
    // A plane's own error names its flag, not the sweep's.
    refused(
        &words(&["sweep", "--x", "m1=1:1", "--vary", "g=1:2", "--size", "4"]),
        &["--x"],
    );
    // A negative value given as its own word names the flag and its range.
    for (args, flag, range) in [
        (
            &["lyapunov", "--indicator", "exponent", "--exponent", "-1"][..],
            "--exponent",
            "1..=4",
        ),
        (
            &["lyapunov", "--indicator", "gali", "--gali", "-2"][..],
            "--gali",
            "2..=4",
        ),
        (&["twin", "--sigma", "-1mm"][..], "--sigma", "(0, 0.1]"),
        (&["twin", "--rate", "-3"][..], "--rate", "[0.5, 10000]"),
        (&["twin", "--sigma", "0"][..], "--sigma", "(0, 0.1]"),
    ] {
        refused(&words(args), &[flag, range]);
    }
}

/// Issue 35, item 10: the explorer said "dark: soon, bright: late" of flip times that its
/// colour bar, tiles and README draw pale yellow when fast. Every kind's legend names its
/// picture's ends as the picture draws them: fast flips and chaos bright, everywhere.
#[test]
fn every_legend_names_its_colours_ends() {
    use chaoscope::spec::MapKind;
    for &kind in MapKind::all() {
        let entry = kind.entry();
        let legend = chaoscope::render::legend(kind);
        assert!(!legend.contains('{'), "{kind:?}: {legend}");
        if entry.low.is_empty() {
            assert!(!legend.contains("dark:"), "{kind:?}: {legend}");
            continue;
        }
        // Chaos is drawn bright in every map of the divergence family (its pictures reverse
        // the colours of indicators that fall with chaos), and a fast flip is bright.
        let bright = legend.split("bright: ").nth(1).unwrap_or("");
        let expected = match kind.name() {
            "flip" => "soon",
            "alignment-time" => "soon, strongly chaotic",
            _ => "chaotic",
        };
        assert!(bright.starts_with(expected), "{kind:?}: {legend}");
        assert!(legend.contains("dark: "), "{kind:?}: {legend}");
    }
}

/// Issue 35, item 11: 160 seeded random command lines over the new surfaces: planes (any two
/// axis names, ranges good and bad, physics flags that an axis may set), indicator flags
/// (any indicator with --exponent, --gali, --threshold, --ld-p, negative words included),
/// and output paths (new files, FIFOs, links to FIFOs, directories, one file given twice).
/// No panic, no hang (10 s a line), exit 0 or 2, every exit 2 naming a flag, no FIFO or link
/// replaced, no temporary file left.
#[test]
fn random_planes_indicators_and_outputs_are_refused_or_run() {
    const LINES: usize = 160;
    let names: Vec<&str> = Var::ALL.iter().map(|v| v.name()).collect();
    let ranges = [
        "0.5:2", "-1:1", "0:0.2", "2:1", "1:1", "-pi:pi", "nan:1", "0:1e300",
    ];
    let physics = [
        ("--m1", "2"),
        ("--m2", "0.5"),
        ("--l2", "0.7"),
        ("--g", "5"),
        ("--joint-damping", "0.01"),
        ("--joint-damping", "0,0.01"),
        ("--rod-mass", "0.1,0"),
        ("--omega1", "1"),
        ("--theta1", "0.5"),
    ];
    let indicators = chaoscope::measure::names();
    let numbers = [
        "1", "2", "3", "4", "5", "0", "-1", "-2", "1e-8", "0.5", "nan",
    ];
    let mut rng = fastrand::Rng::with_seed(20261203);
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.png");
    mkfifo(&fifo);
    let link = dir.path().join("link.npy");
    std::os::unix::fs::symlink(&fifo, &link).unwrap();
    let (mut ok, mut refusals) = (0, 0);
    for k in 0..LINES {
        let here = dir.path().join(format!("line{k}"));
        std::fs::create_dir(&here).unwrap();
        let file = |ext: &str| here.join(format!("out.{ext}")).display().to_string();
        let command = if rng.bool() { "flip" } else { "lyapunov" };
        let mut line = words(&[command, "--size", "4", "--t-max", "0.5", "--backend", "cpu"]);
        if rng.u8(..3) > 0 {
            for axis in ["--x", "--y"] {
                let name = names[rng.usize(..names.len())];
                line.push(axis.into());
                line.push(format!("{name}={}", ranges[rng.usize(..ranges.len())]));
            }
        }
        if rng.bool() {
            let (flag, value) = physics[rng.usize(..physics.len())];
            line.extend(words(&[flag, value]));
        }
        if command == "lyapunov" && rng.bool() {
            line.push("--indicator".into());
            line.push(indicators[rng.usize(..indicators.len())].into());
            for flag in ["--exponent", "--gali", "--threshold", "--ld-p"] {
                if rng.u8(..3) == 0 {
                    line.push(flag.into());
                    line.push(numbers[rng.usize(..numbers.len())].into());
                }
            }
        }
        let outputs = [
            ("--output", file("png")),
            ("--output", fifo.display().to_string()),
            ("--output", here.display().to_string()),
            ("--data", file("npy")),
            ("--data", link.display().to_string()),
            ("--resolved", file("npy")),
            ("--output", file("npy")),
        ];
        for _ in 0..rng.usize(1..=3) {
            let (flag, path) = &outputs[rng.usize(..outputs.len())];
            line.extend([flag.to_string(), path.clone()]);
        }
        let out = chaoscope()
            .current_dir(&here)
            .args(&line)
            .timeout(Duration::from_secs(10))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let shown = line.join(" ");
        assert!(!stderr.contains("panicked"), "{shown}: {stderr}");
        match out.status.code() {
            Some(0) => ok += 1,
            Some(2) => {
                assert!(
                    stderr.contains("--"),
                    "exit 2 naming no flag: {shown}: {stderr}"
                );
                refusals += 1;
            }
            code => panic!("{shown}: {code:?}: {stderr}"),
        }
        assert!(is_fifo(&fifo), "{shown} replaced the FIFO");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink(),
            "{shown} replaced the link"
        );
        let left: Vec<_> = std::fs::read_dir(&here)
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with(".chaoscope-"))
            .collect();
        assert!(left.is_empty(), "{shown} left {left:?}");
    }
    eprintln!("{LINES} lines: {ok} ran, {refusals} refused naming a flag");
    // A fuzz run that only ever refused would test nothing.
    assert!(ok >= 10 && refusals >= 10, "{ok} ran, {refusals} refused");
}

/// Issue 35, item 9: `render` of a 65536^2 store under `ulimit -v 6 GiB` aborted (exit 134)
/// allocating the picture; it is refused up front naming --max-size, and renders with it.
#[test]
fn render_refuses_a_picture_larger_than_the_process_may_hold() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("big.zarr");
    // One chunk of the 65536^2 map is computed: the store exists, its picture is 40 GB.
    chaoscope()
        .args("flip --size 65536 --t-max 0.1 --backend cpu".split(' '))
        .args(["--tile", "1/16384", "--data"])
        .arg(&store)
        .assert()
        .success();
    let bin = assert_cmd::cargo::cargo_bin("chaoscope");
    let render = |extra: &str| {
        std::process::Command::new("bash")
            .arg("-c")
            .arg(format!(
                "ulimit -v 6291456; exec {} render {} --output {} {extra}",
                bin.display(),
                store.display(),
                dir.path().join("big.png").display()
            ))
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .output()
            .unwrap()
    };
    let out = render("");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--max-size"), "{stderr}");
    let out = render("--max-size 1024");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Issue 36, item 5: the library names the setting a message asks to change; the command
/// line words it as its flag (and Python as its keyword: python/tests).
#[test]
fn messages_name_settings_as_the_commands_flags() {
    for (args, expected) in [
        (
            vec!["flip", "--size", "8", "--t-max", "1", "--dt", "0.05"],
            "take --dt 0.01 or finer",
        ),
        (
            argv("lyapunov --size 8 --t-max 1 --indicator sali --threshold 1e-8 --backend gpu"),
            "take --precision f64",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = common::chaoscope()
            .args(&args)
            .arg("--resolved")
            .arg(dir.path().join("r.npy"))
            .arg("--output")
            .arg(dir.path().join("m.png"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("[["), "{args:?}: {stderr}");
    }
}
