//! Pictures are checked by what they must show, not by stored bytes.

mod common;

use common::{chaoscope, read_npy, text_of as text};

use std::path::Path;

use chaoscope::render::read_png;
use predicates::prelude::*;

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

/// The frames of the GIF at `path`.
fn gif_frames(path: &Path) -> u32 {
    let mut decoder = gif::DecodeOptions::new()
        .read_info(std::fs::File::open(path).unwrap())
        .unwrap();
    let mut frames = 0;
    while decoder.read_next_frame().unwrap().is_some() {
        frames += 1;
    }
    frames
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

fn sweep(dir: &Path, backend: &str, extra: &[&str]) -> assert_cmd::assert::Assert {
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
        sweep(&out, backend, &["--vary", "mass=1:4", "--frames", "3"]).success();
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
    sweep(
        dir.path(),
        "cpu",
        &["--vary", "m2/m1=0.3:3", "--frames", "4"],
    )
    .success();
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
    sweep(dir.path(), "cpu", &args).success();
    let kept = dir.path().join("frame_0000.png");
    let before = std::fs::metadata(&kept).unwrap().modified().unwrap();
    let lost = dir.path().join("frame_0001.png");
    let original = read_png(&lost).unwrap().rgb;
    std::fs::remove_file(&lost).unwrap();
    sweep(dir.path(), "cpu", &args)
        .success()
        .stderr(predicate::str::contains("2 kept from an earlier run"));
    assert_eq!(
        std::fs::metadata(&kept).unwrap().modified().unwrap(),
        before
    );
    assert_eq!(read_png(&lost).unwrap().rgb, original);
    // Another sweep in the same directory is refused, naming the flag.
    sweep(dir.path(), "cpu", &["--vary", "g=5:20", "--frames", "3"])
        .code(2)
        .stderr(predicate::str::contains("--output"));
}

/// A sweep is a film of maps as a zoom is: made in tiles that add up to the whole, a
/// damaged frame made again, and a table of what each frame varied.
#[test]
fn a_sweep_in_tiles_adds_up_to_the_whole_and_remakes_a_damaged_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, tiled) = (dir.path().join("whole"), dir.path().join("tiled"));
    let args = ["--vary", "g=5:15", "--frames", "3"];
    sweep(&whole, "cpu", &args).success();
    for tile in ["0/2", "1/2"] {
        sweep(&tiled, "cpu", &[&args[..], &["--tile", tile]].concat())
            .success()
            .stderr(predicate::str::contains(format!("tile {tile} done")));
    }
    assert!(
        !tiled.join("animation.png").exists(),
        "a tile makes no film"
    );
    // Damage one frame's pixels (its digest no longer matches): it is made again.
    let damaged = tiled.join("frame_0002.png");
    let mut png = read_png(&damaged).unwrap();
    png.rgb[0] ^= 0xff;
    chaoscope::render::write_png(&damaged, (png.width, png.height), &png.rgb, &png.text).unwrap();
    sweep(&tiled, "cpu", &args)
        .success()
        .stderr(predicate::str::contains("1 made, 2 kept"))
        .stderr(predicate::str::contains("damaged"));
    for k in 0..3 {
        let name = format!("frame_{k:04}.png");
        assert_eq!(
            read_png(&whole.join(&name)).unwrap().rgb,
            read_png(&tiled.join(&name)).unwrap().rgb,
            "{name}"
        );
    }
    let table = std::fs::read_to_string(tiled.join("frames.csv")).unwrap();
    let rows: Vec<&str> = table.lines().skip(1).collect();
    assert_eq!(rows[0], "frame,g,precision,place");
    assert_eq!(&rows[1..], ["0,5,f64,cpu", "1,10,f64,cpu", "2,15,f64,cpu"]);
    // A sweep's store is one task's.
    sweep(
        &tiled,
        "cpu",
        &[&args[..], &["--tile", "0/2", "--data", "s.zarr"]].concat(),
    )
    .code(2)
    .stderr(predicate::str::contains("--tile"));
}

/// Sweep's zoom moved to `chaoscope zoom`: the flags are refused with the zoom that does
/// it, its last view's width the grid's over the magnification (2 pi / 1e6 here).
#[test]
fn a_sweep_zoom_names_the_zoom_that_does_it() {
    let dir = tempfile::tempdir().unwrap();
    sweep(
        dir.path(),
        "cpu",
        &["--zoom-to", "1.9,2.6", "--zoom", "1e6", "--frames", "3"],
    )
    .code(2)
    .stderr(predicate::str::contains("--zoom-to"))
    .stderr(predicate::str::contains(
        "chaoscope zoom --to 1.9,2.6,6.28318530717958",
    ));
}

#[test]
fn sweep_bad_values_exit_2_and_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--frames", "0", "--vary", "g=1:2"], "--frames"),
        (&["--vary", "m2=1:-1"], "--vary"),
        (&["--vary", "spin=1:2"], "--vary"),
        (&[], "--vary"),
    ];
    for (args, flag) in cases {
        sweep(&dir.path().join("x"), "cpu", args)
            .code(2)
            .stderr(predicate::str::contains(*flag));
    }
}

/// Lower-bob distance (m) between runs a and b at each sample of a traces .npy.
fn separation(shape: &[u64], data: &[f32], a: usize, b: usize) -> Vec<f32> {
    let samples = shape[1] as usize;
    (0..samples)
        .map(|k| {
            let at = |r: usize| &data[(r * samples + k) * 4..(r * samples + k) * 4 + 4];
            let (p, q) = (at(a), at(b));
            ((p[2] - q[2]).powi(2) + (p[3] - q[3]).powi(2)).sqrt()
        })
        .collect()
}

#[test]
fn trails_of_identical_starts_coincide_and_of_different_starts_part() {
    let dir = tempfile::tempdir().unwrap();
    for backend in backends() {
        let same = dir.path().join(format!("same-{backend}.npy"));
        let apart = dir.path().join(format!("apart-{backend}.npy"));
        for (npy, spread) in [(&same, "0"), (&apart, "5mm")] {
            chaoscope()
                .args([
                    "traces", "--theta1", "2.4", "--theta2", "2.0", "--runs", "3",
                ])
                .args(["--exposure", "8", "--dt", "0.002", "--size", "200"])
                .args(["--spread", spread, "--backend", backend, "--output"])
                .arg(npy.with_extension("png"))
                .arg("--data")
                .arg(npy)
                .assert()
                .success();
        }
        let (shape, data) = read_npy(&same);
        assert_eq!(shape, vec![3, 4001, 4]);
        for b in 1..3 {
            assert!(
                separation(&shape, &data, 0, b).iter().all(|d| *d == 0.0),
                "{backend}: identical starts must give identical trails"
            );
        }
        let (shape, data) = read_npy(&apart);
        let d = separation(&shape, &data, 0, 1);
        // 5 mm apart at the start; the first 0.5 s (250 samples) stay within a few times
        // that, then chaos parts them by more than 20 cm within 8 s.
        assert!(d[0] > 0.001 && d[0] < 0.02, "{backend}: start {}", d[0]);
        assert!(d[..250].iter().all(|x| *x < 0.05), "{backend}: early");
        assert!(d.iter().any(|x| *x > 0.2), "{backend}: never parted");
        let png = read_png(&apart.with_extension("png")).unwrap();
        assert_eq!((png.width, png.height), (200, 200));
    }
}

#[test]
fn traces_bad_values_exit_2_and_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    for (args, flag) in [
        (&["--exposure", "0"][..], "--exposure"),
        (&["--runs", "0"][..], "--runs"),
        (&["--spread", "2"][..], "--spread"),
        (&["--size", "8"][..], "--size"),
    ] {
        chaoscope()
            .args("traces --theta1 1 --theta2 1 --backend cpu".split(' '))
            .args(args)
            .arg("--output")
            .arg(dir.path().join("t.png"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains(flag));
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn the_traces_animation_has_the_asked_frames() {
    let dir = tempfile::tempdir().unwrap();
    let gif_path = dir.path().join("t.gif");
    chaoscope()
        .args("traces --theta1 2 --theta2 1 --exposure 1.2".split(' '))
        .args(["--size", "120", "--backend", "cpu", "--output"])
        .arg(dir.path().join("t.png"))
        .arg("--gif")
        .arg(&gif_path)
        .assert()
        .success();
    let frames = gif_frames(&gif_path);
    // 25 frames a second of exposure.
    assert_eq!(frames, 30);
}

#[test]
fn phase_density_holds_all_the_time_and_the_single_pendulum_has_its_period() {
    use chaoscope::app::phase::{phase_density, single_pendulum};
    // Small oscillations: period 2 pi sqrt(l/g); RK4 at dt 1e-3 is far more accurate than
    // the 1e-3 relative tolerance, which covers the amplitude correction (theta0^2/16 = 6e-4).
    let g_over_l = 9.81;
    let run = single_pendulum(g_over_l, 0.1, 0.0, 1e-3, 10_000);
    let crossings: Vec<f64> = run
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0].1 < 0.0 && w[1].1 >= 0.0)
        .map(|(k, w)| (k as f64 - w[0].1 / (w[1].1 - w[0].1)) * 1e-3)
        .collect();
    let period = crossings[1] - crossings[0];
    let expected = 2.0 * std::f64::consts::PI / g_over_l.sqrt();
    assert!(
        (period / expected - 1.0).abs() < 1e-3,
        "{period} vs {expected}"
    );
    // Every step's time lands in the picture: the density sums to the run's duration (10 s),
    // up to the f32 sums in the cells (hundreds of additions each at 6e-8 relative: ~1e-4 s
    // in all; measured 3e-5) - asserted 1e-3.
    let field = phase_density(&[run], 1e-3, 64, 1.5);
    let total: f64 = field.data.iter().map(|&x| x as f64).sum();
    assert!((total - 10.0).abs() < 1e-3, "{total}");
}

#[test]
fn phase_portraits_render_both_arms_and_the_single_pendulum() {
    let dir = tempfile::tempdir().unwrap();
    for extra in [&["--runs", "4"][..], &["--single"][..]] {
        let out = dir.path().join("p.png");
        chaoscope()
            .args(["phase", "--t-max", "5", "--size", "100", "--backend", "cpu"])
            .args(extra)
            .arg("--output")
            .arg(&out)
            .assert()
            .success();
        let png = read_png(&out).unwrap();
        // Two framed panels side by side, or one.
        let panels = if extra[0] == "--single" { 1 } else { 2 };
        assert!(
            png.width > panels * 100 && png.width < panels * 300,
            "{}",
            png.width
        );
        assert!(text(&png, "chaoscope:command").starts_with("chaoscope phase"));
    }
}

/// More releases than one chunk holds are streamed (two passes, nothing kept): the .npy still
/// holds every run exactly as the CPU integrates it, and the GIF every frame.
#[test]
fn many_releases_stream_through_bounded_memory() {
    use chaoscope::model::{Params, State};
    use chaoscope::spec::{Spread, releases};
    let dir = tempfile::tempdir().unwrap();
    let (npy, gif_path) = (dir.path().join("r.npy"), dir.path().join("r.gif"));
    // 2500 runs of 500 steps: the CPU takes 2^20 pendulum-steps a chunk, 2097 runs.
    chaoscope()
        .args("traces --theta1 2.4 --theta2 2 --runs 2500 --exposure 0.5".split(' '))
        .args("--spread 0.01 --size 64 --backend cpu --output".split(' '))
        .arg(dir.path().join("r.png"))
        .arg("--data")
        .arg(&npy)
        .arg("--gif")
        .arg(&gif_path)
        .assert()
        .success();
    let (shape, data) = read_npy(&npy);
    assert_eq!(shape, vec![2500, 501, 4]);
    let p = Params::default();
    let starts = releases(&p, State::at_rest(2.4, 2.0), 2500, Spread::Radians(0.01));
    for k in [0, 2096, 2097, 2499] {
        let run = chaoscope::cpu::trajectory(&p, starts[k], 0.001, 500);
        for (i, s) in run.iter().enumerate().step_by(50) {
            let q = p.positions(s);
            let at = (k * 501 + i) * 4;
            assert_eq!(
                &data[at..at + 4],
                &[q.x1 as f32, q.y1 as f32, q.x2 as f32, q.y2 as f32],
                "run {k}, sample {i}"
            );
        }
    }
    let frames = gif_frames(&gif_path);
    assert_eq!(frames, 13, "25 frames a second of exposure");
}
