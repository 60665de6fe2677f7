//! Pictures are checked by what they must show, not by stored bytes.

mod common;

use std::path::Path;

use assert_cmd::Command;
use chaoscope::render::read_png;
use predicates::prelude::*;

fn chaoscope() -> Command {
    let mut cmd = Command::cargo_bin("chaoscope").expect("binary");
    cmd.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    cmd
}

fn text(png: &chaoscope::render::Png, key: &str) -> String {
    png.text
        .iter()
        .find(|(k, _)| k == key)
        .unwrap_or_else(|| panic!("no {key}"))
        .1
        .clone()
}

/// The backends a picture test runs on: the CPU always, the GPU when there is one.
fn backends() -> Vec<&'static str> {
    let mut b = vec!["cpu"];
    if common::gpu().is_some() {
        b.push("gpu");
    }
    b
}

#[test]
fn annotated_and_bare_maps_carry_the_same_data() {
    let dir = tempfile::tempdir().unwrap();
    for backend in backends() {
        for kind in ["flip", "lyapunov"] {
            let bare = dir.path().join(format!("{kind}-{backend}.png"));
            let framed = dir.path().join(format!("{kind}-{backend}-annotated.png"));
            for (path, extra) in [(&bare, None), (&framed, Some("--annotate"))] {
                chaoscope()
                    .args([
                        kind,
                        "--size",
                        "48x32",
                        "--t-max",
                        "4",
                        "--backend",
                        backend,
                    ])
                    .args(extra)
                    .arg("--output")
                    .arg(path)
                    .assert()
                    .success();
            }
            let (bare, framed) = (read_png(&bare).unwrap(), read_png(&framed).unwrap());
            assert_eq!((bare.width, bare.height), (48, 32));
            assert!(framed.width > 48 && framed.height > 32);
            // "48x32 map at x X, y Y (top left)": cut it out and compare pixel for pixel.
            let region = text(&framed, "chaoscope:map-region");
            let nums: Vec<u32> = region
                .split(|c: char| !c.is_ascii_digit())
                .filter(|s| !s.is_empty())
                .map(|s| s.parse().unwrap())
                .collect();
            let (x, y) = (nums[2], nums[3]);
            for row in 0..32u32 {
                let a = &bare.rgb[(row * 48 * 3) as usize..((row + 1) * 48 * 3) as usize];
                let at = (((y + row) * framed.width + x) * 3) as usize;
                assert_eq!(
                    a,
                    &framed.rgb[at..at + 48 * 3],
                    "{kind} {backend}: row {row}"
                );
            }
            assert!(text(&framed, "chaoscope:command").contains("--annotate"));
        }
    }
}

#[test]
fn colormaps_are_selectable() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    for (path, map) in [(&a, "inferno"), (&b, "viridis")] {
        chaoscope()
            .args(["flip", "--size", "16", "--t-max", "3", "--backend", "cpu"])
            .args(["--colormap", map, "--output"])
            .arg(path)
            .assert()
            .success();
    }
    let (a, b) = (read_png(&a).unwrap(), read_png(&b).unwrap());
    assert_ne!(a.rgb, b.rgb);
    assert!(text(&b, "chaoscope:command").contains("--colormap viridis"));
}

fn frame_count(path: &Path) -> u32 {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let reader = png::Decoder::new(file).read_info().unwrap();
    reader
        .info()
        .animation_control()
        .expect("an APNG")
        .num_frames
}

fn sweep(dir: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    chaoscope()
        .args([
            "sweep",
            "--size",
            "40x30",
            "--t-max",
            "5",
            "--backend",
            "cpu",
        ])
        .args(extra)
        .arg("--output")
        .arg(dir)
        .assert()
}

#[test]
fn a_sweep_over_a_parameter_that_does_not_change_the_physics_gives_identical_frames() {
    let dir = tempfile::tempdir().unwrap();
    for backend in backends() {
        let out = dir.path().join(backend);
        // Scaling both masses leaves the motion unchanged. Factors 1 and 4 scale every f32/f64
        // product exactly (powers of two), so those frames are bit-identical; the factor 2.5
        // rounds differently, which chaotic pixels may amplify: most pixels still agree.
        chaoscope()
            .args([
                "sweep",
                "--size",
                "40x30",
                "--t-max",
                "5",
                "--backend",
                backend,
            ])
            .args(["--vary", "mass=1:4", "--frames", "3", "--output"])
            .arg(&out)
            .assert()
            .success();
        let frames: Vec<_> = (0..3)
            .map(|k| {
                read_png(&out.join(format!("frame_{k:04}.png")))
                    .unwrap()
                    .rgb
            })
            .collect();
        assert_eq!(frames[0], frames[2], "{backend}");
        let same = frames[0]
            .chunks(3)
            .zip(frames[1].chunks(3))
            .filter(|(a, b)| a == b)
            .count();
        assert!(
            same * 100 >= 40 * 30 * 97,
            "{backend}: {same} of 1200 pixels"
        );
        assert_eq!(frame_count(&out.join("animation.png")), 3);
    }
}

#[test]
fn a_sweep_that_changes_the_physics_changes_the_frames_and_animates_them_all() {
    let dir = tempfile::tempdir().unwrap();
    sweep(dir.path(), &["--vary", "m2/m1=0.3:3", "--frames", "4"]).success();
    let frames: Vec<_> = (0..4)
        .map(|k| read_png(&dir.path().join(format!("frame_{k:04}.png"))).unwrap())
        .collect();
    for pair in frames.windows(2) {
        assert_ne!(pair[0].rgb, pair[1].rgb);
    }
    assert!(text(&frames[3], "chaoscope:command").contains("--m2 3 "));
    assert_eq!(frame_count(&dir.path().join("animation.png")), 4);
}

#[test]
fn an_interrupted_sweep_resumes_and_refuses_to_mix_sweeps() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--vary", "g=5:15", "--frames", "3"];
    sweep(dir.path(), &args).success();
    let kept = dir.path().join("frame_0000.png");
    let before = std::fs::metadata(&kept).unwrap().modified().unwrap();
    let lost = dir.path().join("frame_0001.png");
    let original = read_png(&lost).unwrap().rgb;
    std::fs::remove_file(&lost).unwrap();
    sweep(dir.path(), &args)
        .success()
        .stderr(predicate::str::contains("2 kept from an earlier run"));
    assert_eq!(
        std::fs::metadata(&kept).unwrap().modified().unwrap(),
        before
    );
    assert_eq!(read_png(&lost).unwrap().rgb, original);
    // Another sweep in the same directory is refused, naming the flag.
    sweep(dir.path(), &["--vary", "g=5:20", "--frames", "3"])
        .code(2)
        .stderr(predicate::str::contains("--output"));
}

#[test]
fn a_zoom_switches_to_f64_where_f32_runs_out() {
    let dir = tempfile::tempdir().unwrap();
    sweep(
        dir.path(),
        &["--zoom-to", "1.9,2.6", "--zoom", "1e6", "--frames", "3"],
    )
    .success();
    let last = read_png(&dir.path().join("frame_0002.png")).unwrap();
    let command = text(&last, "chaoscope:command");
    // The last window is 2 pi / 1e6 wide around the point.
    assert!(command.contains("--theta1 1.89999"), "{command}");
    if common::gpu().is_some() {
        let out = dir.path().join("gpu");
        chaoscope()
            .args([
                "sweep",
                "--size",
                "40x30",
                "--t-max",
                "5",
                "--backend",
                "gpu",
            ])
            .args([
                "--zoom-to",
                "1.9,2.6",
                "--zoom",
                "1e6",
                "--frames",
                "3",
                "--output",
            ])
            .arg(&out)
            .assert()
            .success()
            .stderr(predicate::str::contains("f64"));
        let first = read_png(&out.join("frame_0000.png")).unwrap();
        let last = read_png(&out.join("frame_0002.png")).unwrap();
        assert_eq!(text(&first, "chaoscope:backend"), "gpu");
        assert_eq!(text(&last, "chaoscope:backend"), "cpu");
    }
}

#[test]
fn sweep_bad_values_exit_2_and_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--frames", "0", "--vary", "g=1:2"], "--frames"),
        (&["--vary", "m2=1:-1"], "--vary"),
        (&["--vary", "spin=1:2"], "--vary"),
        (&["--zoom-to", "5,0", "--zoom", "10"], "--zoom-to"),
        (&["--zoom-to", "1,0", "--zoom", "0.5"], "--zoom"),
        (&[], "--vary"),
    ];
    for (args, flag) in cases {
        sweep(&dir.path().join("x"), args)
            .code(2)
            .stderr(predicate::str::contains(*flag));
    }
}
