//! 500 seeded random command lines over every command's flags, with values good, bad,
//! negative, non-finite, missing, absurd and extreme (1e+-300, 1e308, -0, subnormal): no
//! panic, no hang (each line bounded at 10 s), no exit code but 0, 1, 2 and 130, and every
//! exit 2 names what was wrong (a flag, or FILE). `FUZZ_SHOW=1` prints each line and
//! its outcome.

mod common;

use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;

use chaoscope::cli::Cli;
use clap::CommandFactory;

const LINES: usize = 500;

/// A flag and a plausible value for it (None: a switch).
type Flag = (String, Option<String>);

/// Values tried for every flag: good ones, bad ones, and the traps (a flag where a value
/// should be, NaN, infinities, absurd sizes). Large enough values stay below a few seconds of
/// work on the cheap base commands.
const VALUES: &[&str] = &[
    "0",
    "1",
    "2",
    "-1",
    "0.5",
    "-0.5",
    "300",
    "1e9",
    "1e-9",
    // Extreme magnitudes (issue 25's audit: 1e308 hung the stability analysis for ever).
    "1e300",
    "-1e300",
    "1e308",
    "1e155",
    "1e-300",
    "-0",
    "5e-324",
    "nan",
    "inf",
    "-inf",
    "pi",
    "-pi/2",
    "-pi:pi",
    "0:1",
    "1:0",
    "2,3",
    "1,1",
    "abc",
    "",
    "5mm",
    "-2cm",
    "g=1:2",
    "m2/m1=0:1",
    "2x3",
    "0x0",
    "--dt",
    "viridis",
    "gpu",
    "lab",
    "tangent",
    "bash",
];

/// Each command with flags that keep it cheap, so random extras decide what happens.
fn base(command: &str, data: &str) -> Vec<String> {
    let args: &[&str] = match command {
        "flip" => &["--size", "8", "--t-max", "1"],
        "lyapunov" => &["--size", "6", "--t-max", "0.5"],
        "trajectory" => &["--theta1", "1", "--theta2", "1", "--t-max", "0.5"],
        "traces" => &[
            "--theta1",
            "1",
            "--theta2",
            "1",
            "--exposure",
            "0.2",
            "--size",
            "32",
            "--runs",
            "3",
        ],
        "phase" => &["--t-max", "0.5", "--size", "32"],
        "sweep" => &[
            "--vary", "g=5:10", "--frames", "2", "--size", "6", "--t-max", "0.5",
        ],
        "fit" => &["--candidates", "64", "--window", "0.5"],
        _ => &[],
    };
    let mut out = vec![command.to_string()];
    if command == "fit" {
        out.push(data.to_string());
    }
    out.extend(args.iter().map(|s| s.to_string()));
    out
}

#[test]
fn random_command_lines_never_panic_and_name_what_is_wrong() {
    let cli = Cli::command();
    // bench times minutes of work whatever its flags; it is exercised in tests/cli.rs. serve
    // runs until stopped (tests/serve.rs).
    // (command, its flags with a plausible value each: None for a switch).
    let commands: Vec<(String, Vec<Flag>)> = cli
        .get_subcommands()
        .filter(|c| !["bench", "serve"].contains(&c.get_name()))
        .map(|c| {
            let flags = c
                .get_arguments()
                .filter(|a| a.get_long().is_some_and(|l| l != "help"))
                .map(|a| {
                    let good = if !a.get_action().takes_values() {
                        None
                    } else if let Some(v) = a.get_possible_values().first() {
                        Some(v.get_name().to_string())
                    } else {
                        Some("0.5".to_string())
                    };
                    (format!("--{}", a.get_long().unwrap()), good)
                })
                .collect();
            (c.get_name().to_string(), flags)
        })
        .collect();
    // Flags of any command: tried on the wrong one now and then, and on info and
    // completions, which have none of their own.
    let mut every_flag: Vec<Flag> = commands.iter().flat_map(|c| c.1.clone()).collect();
    every_flag.sort();
    every_flag.dedup();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab_table1.csv");
    let mut rng = fastrand::Rng::with_seed(20261201);
    let lines: Vec<Vec<String>> = (0..LINES)
        .map(|_| {
            let (name, flags) = &commands[rng.usize(..commands.len())];
            let mut line = base(name, data.to_str().unwrap());
            for _ in 0..rng.usize(1..=3) {
                let pool = if flags.is_empty() || rng.u8(..10) == 0 {
                    &every_flag
                } else {
                    flags
                };
                let (flag, good) = &pool[rng.usize(..pool.len())];
                line.push(flag.clone());
                // Half the time a plausible value (or none for a switch), else a trap or
                // nothing at all.
                match (rng.bool(), good) {
                    (true, Some(v)) => line.push(v.clone()),
                    (true, None) => {}
                    (false, _) if rng.u8(..10) < 8 => {
                        line.push(VALUES[rng.usize(..VALUES.len())].to_string())
                    }
                    (false, _) => {}
                }
            }
            line
        })
        .collect();
    let failures = Mutex::new(Vec::new());
    let counts = Mutex::new([0usize; 4]);
    let next = Mutex::new(0usize);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                let dir = tempfile::tempdir().unwrap();
                loop {
                    let k = {
                        let mut n = next.lock().unwrap();
                        *n += 1;
                        *n - 1
                    };
                    let Some(line) = lines.get(k) else { break };
                    let out = common::chaoscope()
                        .current_dir(dir.path())
                        .args(line)
                        .timeout(Duration::from_secs(10))
                        .output()
                        .unwrap();
                    let stderr = String::from_utf8_lossy(&out.stderr);
                    let code = out.status.code();
                    let problem = match code {
                        _ if stderr.contains("panicked") => Some("panicked"),
                        None => Some("killed (a hang past 10 s, or a signal)"),
                        Some(2)
                            if !(stderr.contains("--")
                                || stderr.contains("FILE")
                                || stderr.contains('<')) =>
                        {
                            Some("exit 2 naming no flag")
                        }
                        Some(0 | 1 | 2 | 130) => None,
                        Some(_) => Some("unexpected exit code"),
                    };
                    if let Some(c) = code {
                        let slot = match c {
                            0 => 0,
                            1 => 1,
                            2 => 2,
                            _ => 3,
                        };
                        counts.lock().unwrap()[slot] += 1;
                    }
                    if std::env::var("FUZZ_SHOW").is_ok() {
                        eprintln!(
                            "{code:?} chaoscope {} :: {}",
                            line.join(" "),
                            stderr.lines().next().unwrap_or("")
                        );
                    }
                    if let Some(p) = problem {
                        failures.lock().unwrap().push(format!(
                            "{p}: chaoscope {} -> {code:?}\n{stderr}",
                            line.join(" ")
                        ));
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    let [ok, one, two, other] = counts.into_inner().unwrap();
    eprintln!("{LINES} lines: {ok} exit 0, {one} exit 1, {two} exit 2, {other} other");
    assert!(
        failures.is_empty(),
        "{} of {LINES} lines failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // A fuzz run that only ever refused would test nothing: both outcomes must occur.
    assert!(ok >= 25 && two >= 25, "{ok} successes and {two} refusals");
}
