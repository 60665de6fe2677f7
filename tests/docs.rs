//! The user's documents (README.md, docs/guide/, BENCH.md, ARCHITECTURE.md): every command in
//! them parses; every one runs, unless listed below as long; every picture in docs/ is,
//! pixel for pixel, what its command makes; no document names a path outside the repository
//! and every relative link resolves; the command reference is the commands' own --help.
//! `CHAOSCOPE_WRITE_PICTURES=1` regenerates the pictures (docs/*.png, *.gif) from their
//! commands, `CHAOSCOPE_WRITE_REFERENCE=1` the reference.

mod common;

use std::path::{Path, PathBuf};
use std::time::Instant;

use chaoscope::cli::Cli;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The documents a user reads.
fn documents() -> Vec<PathBuf> {
    let mut docs: Vec<PathBuf> = ["README.md", "BENCH.md", "ARCHITECTURE.md", "data/README.md"]
        .iter()
        .map(|p| root().join(p))
        .collect();
    let mut guide: Vec<PathBuf> = std::fs::read_dir(root().join("docs/guide"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guide.sort();
    docs.extend(guide);
    docs
}

const COMMANDS: [&str; 19] = [
    "flip",
    "zoom",
    "lyapunov",
    "trajectory",
    "boundary",
    "sweep",
    "traces",
    "track",
    "phase",
    "fit",
    "forecast",
    "twin",
    "serve",
    "web",
    "status",
    "render",
    "info",
    "bench",
    "completions",
];

/// The commands of a document: the lines of its code blocks that start with `chaoscope` (or
/// `cargo run --release --`), and the inline code that is a whole command (a command name
/// and an `--output`); each as the words after `chaoscope`, without a trailing `# comment`.
fn commands(text: &str) -> Vec<Vec<String>> {
    let words = |s: &str| -> Option<Vec<String>> {
        let s = s.split(" #").next().unwrap_or("").trim();
        let s = s
            .strip_prefix("cargo run --release -- ")
            .or_else(|| s.strip_prefix("chaoscope "))
            .unwrap_or(s);
        let w = shell_words(s);
        w.first()
            .is_some_and(|c| COMMANDS.contains(&c.as_str()))
            .then_some(w)
    };
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.strip_prefix("    ").unwrap_or("");
        if code.starts_with("chaoscope ") || code.starts_with("cargo run --release -- ") {
            out.extend(words(code));
        }
    }
    for (k, span) in text.split('`').enumerate() {
        if k % 2 == 1 && span.contains("--output") && !span.contains('\n') {
            out.extend(words(span));
        }
    }
    out
}

/// A command line's words as a shell splits them: at spaces, but not within double quotes
/// (`--name "our pendulum"`), which it drops.
fn shell_words(line: &str) -> Vec<String> {
    let (mut words, mut word, mut quoted, mut any) = (Vec::new(), String::new(), false, false);
    for c in line.chars() {
        match c {
            '"' => (quoted, any) = (!quoted, true),
            c if c.is_whitespace() && !quoted => {
                if any {
                    words.push(std::mem::take(&mut word));
                }
                any = false;
            }
            c => (word, any) = (word + &c.to_string(), true),
        }
    }
    if any {
        words.push(word);
    }
    words
}

/// Commands not run here, each with why: every other one runs.
const LONG: [(&str, &str); 4] = [
    (
        "serve",
        "a server runs until it is stopped (tests/serve.rs drives it)",
    ),
    (
        "bench",
        "the benchmark: 20 minutes with its peers (tests/cli.rs runs a small one)",
    ),
    (
        "boundary --t-max 30",
        "20 000 pairs at 20 levels over 30 s, with the verdict: minutes on lavapipe",
    ),
    (
        "twin --replicates 48",
        "48 replicates of 8 twin experiments: minutes (scripts/forecast-pictures)",
    ),
];

/// Pictures in docs/ made by a script rather than by one command of the guide.
const BY_SCRIPT: [(&str, &str); 5] = [
    (
        "explorer.png",
        "scripts/explorer-picture (the page in headless Chromium)",
    ),
    ("explorer_plane.png", "scripts/explorer-picture"),
    (
        "web.png",
        "scripts/web-picture (the static page in headless Chromium, WebGPU)",
    ),
    (
        "twin.png",
        "scripts/forecast-pictures (twin --replicates 48)",
    ),
    (
        "twin_forecast.png",
        "scripts/forecast-pictures (twin --replicates 48)",
    ),
];

fn is_long(command: &[String]) -> bool {
    let line = command.join(" ");
    LONG.iter().any(|(start, _)| line.starts_with(start))
}

/// The folder a command's outputs go to, and where in docs/ each output's picture is.
fn pictures_of(command: &[String], at: &Path) -> Vec<(PathBuf, PathBuf)> {
    let docs = root().join("docs");
    let mut out = Vec::new();
    for pair in command.windows(2) {
        if !matches!(pair[0].as_str(), "--output" | "--film") {
            continue;
        }
        let made = at.join(&pair[1]);
        let name = Path::new(&pair[1])
            .file_name()
            .unwrap()
            .to_string_lossy()
            .to_string();
        if command[0] == "sweep" && pair[0] == "--output" {
            if command.iter().any(|w| w == "--film") {
                // Its animation is the film, not the picture.
                continue;
            }
            // A sweep's folder: its animation is the picture.
            out.push((made.join("animation.png"), docs.join(format!("{name}.png"))));
        } else if docs.join(&name).exists() {
            out.push((made, docs.join(&name)));
        } else if Path::new(&pair[1]).extension().is_none() && made.is_dir() {
            // A folder of plots (fit, forecast): each plot's picture is docs/<plot> where the
            // plot is named after its folder (forecast/forecast.png), else docs/<folder>_<plot>.
            let mut plots: Vec<PathBuf> = std::fs::read_dir(&made)
                .unwrap()
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "png"))
                .collect();
            plots.sort();
            for plot in plots {
                let file = plot.file_name().unwrap().to_string_lossy().to_string();
                let doc = match file.starts_with(&name) {
                    true => docs.join(&file),
                    false => docs.join(format!("{name}_{file}")),
                };
                if doc.exists() {
                    out.push((plot, doc));
                }
            }
        }
    }
    out
}

#[test]
fn every_command_in_the_guide_parses_runs_and_remakes_its_picture() {
    let dir = tempfile::tempdir().unwrap();
    for shared in ["data", "examples"] {
        std::os::unix::fs::symlink(root().join(shared), dir.path().join(shared)).unwrap();
    }
    let mut accounted: Vec<PathBuf> = BY_SCRIPT
        .iter()
        .map(|(p, _)| root().join("docs").join(p))
        .collect();
    let (mut ran, mut parsed) = (0, 0);
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for command in commands(&text) {
            let shown = format!("{}: chaoscope {}", doc.display(), command.join(" "));
            let argv = std::iter::once("chaoscope".to_string()).chain(command.iter().cloned());
            if let Err(e) = Cli::parse_args(argv) {
                panic!("{shown} does not parse:\n{e}");
            }
            parsed += 1;
            if is_long(&command) {
                let pictures = pictures_of(&command, dir.path());
                accounted.extend(pictures.into_iter().map(|(_, doc)| doc));
                continue;
            }
            let started = Instant::now();
            let out = common::chaoscope()
                .current_dir(dir.path())
                .args(&command)
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{shown}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            eprintln!("{shown}: {:.1} s", started.elapsed().as_secs_f64());
            ran += 1;
            for (made, picture) in pictures_of(&command, dir.path()) {
                if std::env::var("CHAOSCOPE_WRITE_PICTURES").is_ok() {
                    // Regenerating the pictures: what the command made replaces docs/'s.
                    std::fs::copy(&made, &picture).unwrap();
                }
                if picture.extension().is_some_and(|e| e == "gif") {
                    // An animation: the same bytes (GIF holds no text of the machine).
                    assert!(
                        std::fs::read(&made).unwrap() == std::fs::read(&picture).unwrap(),
                        "{} is not what `{shown}` makes: regenerate it",
                        picture.display()
                    );
                    continue;
                }
                let (a, b) = (
                    chaoscope::render::read_png(&made).unwrap(),
                    chaoscope::render::read_png(&picture).unwrap(),
                );
                let differ = a.rgb.iter().zip(&b.rgb).filter(|(x, y)| x != y).count();
                assert!(
                    (a.width, a.height) == (b.width, b.height) && differ == 0,
                    "{} is not what `{shown}` makes ({} of its bytes differ): regenerate it",
                    picture.display(),
                    differ
                );
                accounted.push(picture);
            }
        }
    }
    eprintln!("{parsed} commands parsed, {ran} run");
    // Every picture in docs/ is made by a command of the guide (or a script named above).
    let mut pictures: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    pictures.sort();
    let orphans: Vec<_> = pictures.iter().filter(|p| !accounted.contains(p)).collect();
    assert!(
        orphans.is_empty(),
        "pictures no command of the guide makes: {orphans:?}"
    );
}

#[test]
fn documents_name_no_path_outside_the_repository_and_their_links_resolve() {
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for outside in ["../shared", "/tmp/", "/work/", "/home/"] {
            assert!(
                !text.contains(outside),
                "{} names {outside}, which a clone does not have",
                doc.display()
            );
        }
        // Markdown links and pictures to files of the repository: [..](path) not a URL.
        for (k, part) in text.split("](").enumerate().skip(1) {
            let target = part.split(')').next().unwrap_or("");
            let target = target.split('#').next().unwrap_or("");
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let path = doc.parent().unwrap().join(target);
            assert!(
                path.exists(),
                "{} link {k} points at {target}, which does not exist",
                doc.display()
            );
        }
    }
}

/// docs/guide/reference.md: every command's --help, as clap renders it 100 columns wide.
fn reference() -> String {
    use clap::CommandFactory;
    let mut cli = Cli::command().term_width(100);
    let mut out = String::from(
        "# Command reference\n\nEvery command's `--help`, generated from the program itself \
         (`CHAOSCOPE_WRITE_REFERENCE=1 cargo test --release --test docs` rewrites this page; the \
         same test fails when it is out of date).\n\n## chaoscope\n\n```text\n",
    );
    out += &cli.render_long_help().to_string();
    out += "```\n";
    let names: Vec<String> = cli
        .get_subcommands()
        .map(|s| s.get_name().to_string())
        .collect();
    for name in names {
        let sub = cli.find_subcommand_mut(&name).unwrap();
        let mut sub = sub
            .clone()
            .bin_name(format!("chaoscope {name}"))
            .term_width(100);
        out += &format!("\n## chaoscope {name}\n\n```text\n");
        out += &sub.render_long_help().to_string();
        out += "```\n";
    }
    out
}

#[test]
fn the_command_reference_is_the_commands_own_help() {
    let path = root().join("docs/guide/reference.md");
    let made = reference();
    if std::env::var("CHAOSCOPE_WRITE_REFERENCE").is_ok() {
        std::fs::write(&path, &made).unwrap();
    }
    let written = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        written == made,
        "docs/guide/reference.md is out of date: CHAOSCOPE_WRITE_REFERENCE=1 cargo test --release --test docs"
    );
}
