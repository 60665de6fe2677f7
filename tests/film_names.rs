//! Film names reach FFmpeg as those files and nothing else: every command that reads or
//! writes a film, given names that FFmpeg would otherwise take for a URL (`concat:`, `file:`,
//! `subfile`, `data:`, `pipe:`, `tee:`) or an option (a leading `-`), and legal names with
//! `:`, spaces, a newline and letters beyond ASCII. Each run must succeed on the named file
//! and leave its folder as it was but for its own outputs: the files a URL would have read
//! hold no film (reading them fails the run), and every file there keeps its bytes.

mod common;

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

use chaoscope::model::State;
use chaoscope::params::Preset;
use chaoscope::track::synth::{Scene, film};
use common::{argv, chaoscope};

/// Names as a user may type them, each with what FFmpeg would make of it as written.
const NAMES: [&str; 13] = [
    "concat:decoy.mp4",                   // the concat protocol: reads decoy.mp4
    "file:decoy.mp4",                     // the file protocol: decoy.mp4
    "subfile,,start,0,end,0,,:decoy.mp4", // a part of decoy.mp4
    "data:,decoy.mp4",                    // a data URL: the text after the comma
    "pipe:0.mp4",                         // standard input
    "tee:decoy.mp4|other.mp4",            // writes both
    "-report",                            // an option: writes ffprobe-*.log
    "-film.mp4",                          // an option FFmpeg does not know
    "a:b.mp4",                            // protocol `a`, unknown
    "with space.mp4",
    "new\nline.mp4",
    "ünïcödé 映画.mp4",
    "frame%03d.mp4", // an image sequence's pattern
];

/// The files a crafted name's URL would read, present in every folder, holding no film.
const DECOYS: [&str; 2] = ["decoy.mp4", "other.mp4"];

/// Every file under `dir` (relative path) with its bytes.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), bytes);
            }
        }
    }
    out
}

/// A folder holding the decoys, and `film` at `name` when given.
fn folder(name: Option<&str>, film: &[u8]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for d in DECOYS {
        std::fs::write(dir.path().join(d), "no film here\n").unwrap();
    }
    if let Some(name) = name {
        std::fs::write(dir.path().join(name), film).unwrap();
    }
    dir
}

/// Asserts that `after` is `before` with `made` (paths under the folder) added, no other
/// file added, changed or removed.
fn only_made(
    name: &str,
    before: &BTreeMap<PathBuf, Vec<u8>>,
    after: &BTreeMap<PathBuf, Vec<u8>>,
    made: &[&Path],
) {
    for (p, bytes) in before {
        assert!(
            after.get(p) == Some(bytes),
            "{name:?}: {} changed or went",
            p.display()
        );
    }
    let added: Vec<&PathBuf> = after.keys().filter(|p| !before.contains_key(*p)).collect();
    for m in made {
        assert!(
            added.iter().any(|p| p.starts_with(m)),
            "{name:?}: {} was not made ({added:?})",
            m.display()
        );
    }
    for p in &added {
        assert!(
            made.iter().any(|m| p.starts_with(m)),
            "{name:?}: {} was made besides the outputs",
            p.display()
        );
    }
}

/// A small film of the lab's pendulum (320 x 180, 3 s at 30 frames a second) and its bytes.
fn small_film() -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("film.mp4");
    let start = State::at_rest(2.0, 2.6);
    film(
        &Scene::lab(320, 180, 0.5),
        &Preset::Lab.params(),
        start,
        90,
        14,
        &path,
    )
    .unwrap();
    std::fs::read(&path).unwrap()
}

/// `chaoscope` in `dir`, standard input holding bytes that are no film (a `pipe:` reading
/// it would fail).
fn chaoscope_in(dir: &Path) -> assert_cmd::Command {
    let mut c = chaoscope();
    c.current_dir(dir)
        .write_stdin(&b"no film on standard input\n"[..]);
    c
}

/// `--flag=value` as one argument (so that a value with a leading `-` stays a value).
fn flag(flag: &str, value: &str) -> OsString {
    let mut s = OsString::from(format!("--{flag}="));
    s.push(value);
    s
}

/// The pixel size of the film at `path`, as the library's prober reads it.
fn size(path: &Path) -> (u32, u32) {
    let p = chaoscope::video::probe(path).unwrap();
    (p.width, p.height)
}

/// A name as the written film's: an MP4's extension where it has none.
fn as_mp4(name: &str) -> String {
    match name.ends_with(".mp4") {
        true => name.to_string(),
        false => format!("{name}.mp4"),
    }
}

/// `track` and `forecast --video` read each name's film (and no decoy), and the forecast's
/// overlay goes into a folder of that name.
#[test]
fn films_are_read_by_their_names_alone() {
    if !common::ffmpeg() {
        return;
    }
    let bytes = small_film();
    for name in NAMES {
        let dir = folder(Some(name), &bytes);
        let before = contents(dir.path());
        chaoscope_in(dir.path())
            .args(["track", "--l1", "0.30", "--output", "track.csv", "--"])
            .arg(name)
            .assert()
            .success();
        let out = format!("{}.out", name.trim_end_matches(".mp4"));
        chaoscope_in(dir.path())
            .args("forecast track.csv --window 0.5:1.5 --members 100".split(' '))
            // The film is of the lab's apparatus, too short to find its moments from.
            .args(["--preset", "lab", "--held-out", "0"])
            .args(["--candidates", "256", "--backend", "cpu"])
            .arg(flag("video", name))
            .arg(flag("output", &out))
            .assert()
            .success();
        let overlay = Path::new(&out).join("overlay.mp4");
        assert_eq!(size(&dir.path().join(&overlay)), (320, 180), "{name:?}");
        let after = contents(dir.path());
        only_made(
            name,
            &before,
            &after,
            &[Path::new("track.csv"), Path::new(&out)],
        );
    }
}

/// A writing command: its name, its words, its output (beside the film), the film's size.
type Run<'a> = (&'a str, Vec<&'a str>, &'a str, (u32, u32));

/// `sweep`, `traces` and `zoom` write their films to each name and into a folder of each
/// name (an MP4 there, nothing else made or changed).
#[test]
fn films_are_written_to_their_names_alone() {
    if !common::ffmpeg() {
        return;
    }
    // The name as the film's, and as the folder it goes into: FFmpeg writes a staged file
    // beside the film, so the folder's name is what it is handed.
    let names = NAMES
        .iter()
        .flat_map(|n| [as_mp4(n), format!("{n}.d/film.mp4")]);
    for name in names {
        let runs: [Run; 3] = [
            (
                "sweep",
                vec![
                    "sweep", "--vary", "g=5:10", "--frames", "2", "--size", "16x12",
                ],
                "sweep",
                (16, 12),
            ),
            (
                "traces",
                argv("traces --theta1 1 --theta2 1 --exposure 0.2 --size 32 --output traces.png"),
                "traces.png",
                (32, 32),
            ),
            (
                "zoom",
                vec!["zoom", "--to=0,0,1", "--frames", "2", "--output", "zoom"],
                "zoom",
                (16, 12),
            ),
        ];
        for (command, words, output, expected) in runs {
            let dir = folder(None, &[]);
            let before = contents(dir.path());
            let mut c = chaoscope_in(dir.path());
            c.args(&words).arg(flag("film", &name));
            match command {
                "zoom" => c.args(["flip", "--size", "16x12", "--t-max", "1"]),
                "sweep" => c.args(["--output", output]),
                _ => &mut c,
            };
            c.args(["--backend", "cpu"]);
            c.assert().success();
            assert_eq!(
                size(&dir.path().join(&name)),
                expected,
                "{command} {name:?}"
            );
            let after = contents(dir.path());
            only_made(
                &format!("{command} {name}"),
                &before,
                &after,
                &[Path::new(&name), Path::new(output)],
            );
        }
    }
}

/// A film named as one of its run's own frames (through `./`, `..`, an absolute path or a
/// link) is refused before any work, naming `--film`, and the frames already there keep
/// their bytes: `zoom` and `sweep`, each after a first run that made the frames.
#[test]
fn a_film_is_none_of_its_runs_frames() {
    if !common::ffmpeg() {
        return;
    }
    let runs: [(&str, Vec<&str>, &str); 2] = [
        (
            "zoom",
            vec!["zoom", "--to=0,0,1", "--frames", "2", "--output", "z"],
            "z",
        ),
        (
            "sweep",
            vec![
                "sweep", "--vary", "g=5:10", "--frames", "2", "--size", "16x12",
            ],
            "z",
        ),
    ];
    for (command, words, folder) in runs {
        let dir = folder_with_link(folder);
        let made = |c: &mut assert_cmd::Command| {
            match command {
                "zoom" => c.args(["flip", "--size", "16x12", "--t-max", "1"]),
                _ => c.args(["--output", folder]),
            };
            c.args(["--backend", "cpu"]);
        };
        // Before the run has made its folder, a way round through `..` is its first frame
        // all the same: seen as the path the run will make.
        let round = format!("{folder}/../{folder}/frame_0001.png");
        let mut c = chaoscope_in(dir.path());
        c.args(&words).arg(flag("film", &round));
        made(&mut c);
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{command} {round}: {err}");
        assert!(err.contains("--film"), "{command} {round}: {err}");
        let mut c = chaoscope_in(dir.path());
        c.args(&words).arg(flag("film", "film.mp4"));
        made(&mut c);
        c.assert().success();
        let before = contents(dir.path());
        let absolute = dir.path().join("z/frame_0001.png");
        for film in [
            "./z/frame_0001.png",
            "z/../z/frame_0001.png",
            absolute.to_str().unwrap(),
            "link/frame_0001.png",
        ] {
            let mut c = chaoscope_in(dir.path());
            c.args(&words).arg(flag("film", film));
            made(&mut c);
            let o = c.output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{command} {film}: {err}");
            assert!(err.contains("--film"), "{command} {film}: {err}");
            assert_eq!(contents(dir.path()), before, "{command} {film}");
        }
    }
}

/// A folder with the decoys and `link`, a link to `target` (made by the run).
fn folder_with_link(target: &str) -> tempfile::TempDir {
    let dir = folder(None, &[]);
    std::os::unix::fs::symlink(target, dir.path().join("link")).unwrap();
    dir
}

/// What is no film (a folder, a FIFO, text, an empty file) given to `track` or to
/// `forecast --video` is refused as a bad value of the film's argument (exit 2, its name in
/// the message), before any work and without waiting on the FIFO.
#[test]
fn what_is_no_film_is_refused_naming_the_film() {
    if !common::ffmpeg() {
        return;
    }
    let dir = folder(Some("film.mp4"), &small_film());
    let d = dir.path();
    chaoscope_in(d)
        .args(["track", "film.mp4", "--l1", "0.30", "--output", "track.csv"])
        .assert()
        .success();
    std::fs::create_dir(d.join("folder.mp4")).unwrap();
    let fifo = std::process::Command::new("mkfifo")
        .arg(d.join("fifo.mp4"))
        .status()
        .unwrap();
    assert!(fifo.success());
    std::fs::write(d.join("text.mp4"), "no film here\n").unwrap();
    std::fs::write(d.join("empty.mp4"), "").unwrap();
    for bad in ["folder.mp4", "fifo.mp4", "text.mp4", "empty.mp4"] {
        let runs: [Vec<&str>; 2] = [
            vec!["track", bad, "--l1", "0.30", "--output", "again.csv"],
            argv("forecast track.csv --window 0.5:1.5 --members 100"),
        ];
        for (k, words) in runs.iter().enumerate() {
            let mut c = chaoscope_in(d);
            c.args(words).timeout(std::time::Duration::from_secs(60));
            if k == 1 {
                c.args(["--backend", "cpu", "--output", "fc"])
                    .arg(flag("video", bad));
            }
            let o = c.output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr).to_lowercase();
            assert_eq!(o.status.code(), Some(2), "{words:?} {bad}: {err}");
            assert!(
                err.contains("video") && err.contains(bad),
                "{words:?} {bad}: {err}"
            );
            assert!(
                !d.join("again.csv").exists() && !d.join("fc").exists(),
                "{bad}"
            );
        }
    }
}
