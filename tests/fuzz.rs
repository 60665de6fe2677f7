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
        "forecast" => &[
            // Each held-out window is a fit of its own: the lines here test the flags.
            "--held-out",
            "0",
            "--candidates",
            "64",
            "--members",
            "50",
            "--window",
            "0.6:1.7",
        ],
        "twin" => &[
            "--sigma",
            "2mm",
            "--rate",
            "20",
            "--replicates",
            "1",
            "--window",
            "0:0.3",
            "--duration",
            "0.6",
            "--members",
            "20",
            "--candidates",
            "64",
        ],
        "boundary" => &[
            "--pairs",
            "256",
            "--levels",
            "3",
            "--eps",
            "1e-2:1e-1",
            "--t-max",
            "1",
        ],
        _ => &[],
    };
    let mut out = vec![command.to_string()];
    if command == "fit" || command == "forecast" {
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
                line.extend(common::fuzz_value(&mut rng, good.as_deref(), VALUES));
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
                        // 3: a fit that ran but whose model does not follow its data.
                        Some(0 | 1 | 2 | 3 | 130) => None,
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

/// A seeded random damage to the store at `store`: a metadata value replaced (extreme
/// numbers, wrong types, removed), a metadata file cut short or garbled, or a chunk damaged
/// (cut short, emptied, garbage, grown, a directory, removed). Says what it did.
fn damage(store: &Path, rng: &mut fastrand::Rng) -> String {
    let metas = ["zarr.json", "map/zarr.json"];
    let meta = store.join(metas[rng.usize(..metas.len())]);
    match rng.u8(..10) {
        0..=5 => {
            let mut json: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&meta).unwrap()).unwrap();
            // Every value's JSON pointer, containers included.
            fn pointers(v: &serde_json::Value, at: String, out: &mut Vec<String>) {
                match v {
                    serde_json::Value::Object(m) => {
                        for (k, v) in m {
                            pointers(v, format!("{at}/{k}"), out);
                        }
                    }
                    serde_json::Value::Array(a) => {
                        for (k, v) in a.iter().enumerate() {
                            pointers(v, format!("{at}/{k}"), out);
                        }
                    }
                    _ => {}
                }
                out.push(at);
            }
            let mut all = Vec::new();
            pointers(&json, String::new(), &mut all);
            all.retain(|p| !p.is_empty());
            let at = all[rng.usize(..all.len())].clone();
            let values = [
                serde_json::json!(0),
                serde_json::json!(-1),
                serde_json::json!(1e308),
                serde_json::json!(-1e300),
                serde_json::json!(1e-300),
                serde_json::json!(5e-324),
                serde_json::json!(-0.0),
                serde_json::json!(u64::MAX),
                serde_json::json!(65536),
                serde_json::json!(4294967296u64),
                serde_json::json!("x"),
                serde_json::json!("/etc/passwd"),
                serde_json::json!(null),
                serde_json::json!(true),
                serde_json::json!([]),
                serde_json::json!([0]),
                serde_json::json!([1, 0]),
                serde_json::json!([65536, 65536]),
                serde_json::json!({}),
            ];
            let value = values[rng.usize(..values.len())].clone();
            let (parent, key) = at.rsplit_once('/').unwrap();
            let what = match json.pointer_mut(parent).unwrap() {
                serde_json::Value::Object(m) if rng.u8(..5) == 0 => {
                    m.remove(key);
                    format!("{} {at} removed", meta.display())
                }
                _ => {
                    let what = format!("{} {at} = {value}", meta.display());
                    *json.pointer_mut(&at).unwrap() = value;
                    what
                }
            };
            std::fs::write(&meta, json.to_string()).unwrap();
            what
        }
        6 => {
            let bytes = std::fs::read(&meta).unwrap();
            let cut = rng.usize(..bytes.len());
            match rng.bool() {
                true => std::fs::write(&meta, &bytes[..cut]).unwrap(),
                false => {
                    let mut b = bytes;
                    b[cut] = rng.u8(..);
                    std::fs::write(&meta, b).unwrap()
                }
            }
            format!("{} cut or garbled at byte {cut}", meta.display())
        }
        _ => {
            let chunks: Vec<_> = std::fs::read_dir(store.join("map/c"))
                .unwrap()
                .flat_map(|row| std::fs::read_dir(row.unwrap().path()).unwrap())
                .map(|c| c.unwrap().path())
                .collect();
            let chunk = &chunks[rng.usize(..chunks.len())];
            let size = std::fs::metadata(chunk).unwrap().len() as usize;
            let how = rng.u8(..6);
            match how {
                0 => std::fs::write(chunk, vec![0u8; rng.usize(..size)]).unwrap(),
                1 => std::fs::write(chunk, []).unwrap(),
                2 => std::fs::write(chunk, (0..size).map(|_| rng.u8(..)).collect::<Vec<_>>())
                    .unwrap(),
                3 => {
                    let mut b = std::fs::read(chunk).unwrap();
                    b.extend(std::iter::repeat_n(7u8, rng.usize(1..4096)));
                    std::fs::write(chunk, b).unwrap()
                }
                4 => {
                    std::fs::remove_file(chunk).unwrap();
                    std::fs::create_dir(chunk).unwrap();
                }
                _ => std::fs::remove_file(chunk).unwrap(),
            }
            format!("chunk {} damaged ({how})", chunk.display())
        }
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// Issue 25: seeded random damage to a store's metadata and chunks, each followed by
/// `status`, `render` and the command run again (a resume): no panic, no hang (10 s each),
/// exit 0, 1 or 2 only, and every refusal names what it refuses (a flag, the store's file
/// or field, or its chunk).
#[test]
fn random_store_damage_never_panics_or_hangs() {
    const CASES: usize = 80;
    let dir = tempfile::tempdir().unwrap();
    let pristine = dir.path().join("pristine.zarr");
    let map = [
        "flip",
        "--size",
        "512",
        "--t-max",
        "0.5",
        "--backend",
        "cpu",
    ];
    common::chaoscope()
        .args(map)
        .arg("--data")
        .arg(&pristine)
        .assert()
        .success();
    let mut rng = fastrand::Rng::with_seed(20261202);
    let mut failures = Vec::new();
    let mut counts = [0usize; 3];
    for case in 0..CASES {
        let store = dir.path().join(format!("s{case}.zarr"));
        copy_dir(&pristine, &store);
        let what = damage(&store, &mut rng);
        let png = dir.path().join("r.png");
        let s = store.to_str().unwrap();
        let runs: [Vec<&str>; 3] = [
            vec!["status", s],
            vec!["render", s, "--output", png.to_str().unwrap()],
            map.iter().copied().chain(["--data", s]).collect(),
        ];
        for run in runs {
            let out = common::chaoscope()
                .args(&run)
                .timeout(Duration::from_secs(10))
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            let code = out.status.code();
            if std::env::var("FUZZ_SHOW").is_ok() {
                eprintln!(
                    "{code:?} {what} :: {} :: {}",
                    run[0],
                    stderr.lines().next().unwrap_or("")
                );
            }
            let problem = match code {
                _ if stderr.contains("panicked") => Some("panicked"),
                None => Some("killed (a hang past 10 s, or a signal)"),
                Some(1 | 2)
                    if !(stderr.contains("--")
                        || stderr.contains("zarr.json")
                        || stderr.contains("chunk")
                        || stderr.contains(s)) =>
                {
                    Some("refused naming nothing")
                }
                Some(c @ 0..=2) => {
                    counts[c as usize] += 1;
                    None
                }
                Some(_) => Some("unexpected exit code"),
            };
            if let Some(p) = problem {
                failures.push(format!(
                    "{p}: {what}: chaoscope {}\n{stderr}",
                    run.join(" ")
                ));
            }
        }
        std::fs::remove_dir_all(&store).unwrap();
    }
    eprintln!(
        "{CASES} damaged stores x 3 commands: {} exit 0, {} exit 1, {} exit 2",
        counts[0], counts[1], counts[2]
    );
    assert!(
        failures.is_empty(),
        "{} failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Issue 25: every key of a parameter file, and every parameter `sweep --vary` takes, with
/// extreme values (1e+-300, 1e308, 1e155, -0, a subnormal, infinities, NaN, a huge whole
/// number): each run bounded at 10 s, no panic, exit 0 or 2, and a refusal names the key
/// (or, for a step the physics cannot take, --dt).
#[test]
fn extreme_values_of_every_params_key_and_vary_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let values = [
        "1e300",
        "-1e300",
        "1e308",
        "1e155",
        "1e-300",
        "-0.0",
        "5e-324",
        "inf",
        "-inf",
        "nan",
        "4294967296",
    ];
    // (what the file says with V for the value, the key an error names)
    let keys = [
        ("m1 = V", "m1"),
        ("m2 = V", "m2"),
        ("l1 = V", "l1"),
        ("l2 = V", "l2"),
        ("g = V", "g"),
        ("rod_mass = [V, 0.1]", "rod_mass"),
        ("joint_damping = [0.0, V]", "joint_damping"),
        ("bearing_friction = V", "bearing_friction"),
        (
            "bearing_friction = 0.001\nbearing_radius = V",
            "bearing_radius",
        ),
        (
            "[air_drag]\nrho = V\nbob_area = [0.001, 0.001]",
            "air_drag.rho",
        ),
        (
            "[air_drag]\ncw = V\nbob_area = [0.001, 0.001]",
            "air_drag.cw",
        ),
        ("[air_drag]\nbob_area = [V, 0.001]", "air_drag.bob_area"),
        ("[air_drag]\nrod_area = [0.001, V]", "air_drag.rod_area"),
    ];
    let vary = [
        "m1", "m2", "l1", "l2", "g", "m2/m1", "l2/l1", "mass", "omega1", "omega2", "damping",
    ];
    let mut runs: Vec<(Vec<String>, String)> = Vec::new();
    for (k, (text, key)) in keys.iter().enumerate() {
        for (v, value) in values.iter().enumerate() {
            let file = dir.path().join(format!("p{k}-{v}.toml"));
            std::fs::write(&file, text.replace('V', value)).unwrap();
            let line = ["flip", "--size", "8", "--t-max", "1", "--params"]
                .map(String::from)
                .into_iter()
                .chain([file.display().to_string()])
                .collect();
            runs.push((line, key.to_string()));
        }
    }
    for param in vary {
        for value in values {
            let value = value.trim_end_matches(".0");
            for range in [format!("{value}:1"), format!("1:{value}")] {
                let out = format!("sweep{}", runs.len());
                let line = ["sweep", "--frames", "2", "--size", "6", "--t-max", "0.5"]
                    .map(String::from)
                    .into_iter()
                    .chain(["--vary".into(), format!("{param}={range}")])
                    .chain(["--output".into(), out])
                    .collect();
                runs.push((line, "--vary".to_string()));
            }
        }
    }
    let (mut ok, mut refused, mut failures) = (0, 0, Vec::new());
    for (line, key) in &runs {
        let out = common::chaoscope()
            .current_dir(dir.path())
            .args(line)
            .args(["--backend", "cpu"])
            .timeout(Duration::from_secs(10))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        match out.status.code() {
            _ if stderr.contains("panicked") => failures.push(format!("panicked: {line:?}")),
            Some(0) => ok += 1,
            Some(2) if stderr.contains(key.as_str()) || stderr.contains("--dt") => refused += 1,
            code => failures.push(format!("{code:?} {line:?}: {stderr}")),
        }
    }
    eprintln!(
        "{} runs: {ok} exit 0, {refused} refused naming the key",
        runs.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
