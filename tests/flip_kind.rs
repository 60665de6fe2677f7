//! The flip-kind quantity (`flip --colour-by kind`): which arm flips first and which way, on
//! both paths, against the flip time it is read off, the map's symmetry, and its files.

mod common;

use chaoscope::Field;
use chaoscope::engine::{Backend, Engine};
use chaoscope::model::Params;
use chaoscope::monitor::Monitor;
use chaoscope::quantity::FlipKind;
use chaoscope::spec::{FlipMeasure, FlipSpec, Grid, Stepping};
use common::{chaoscope, png_text, read_npy};
use predicates::prelude::*;

fn kind_spec(n: u32, t_max: f64, params: Params) -> FlipSpec {
    FlipSpec {
        measure: FlipMeasure::Kind,
        ..FlipSpec::new(params, Grid::square(n), Stepping { dt: 0.01, t_max })
    }
}

/// The engines to check: the CPU always, the GPU where there is one (under CI=true always).
fn engines() -> Vec<(&'static str, Engine)> {
    let mut out = vec![("cpu", Engine::new(Backend::Cpu).unwrap())];
    if let Some(ctx) = common::gpu() {
        out.push(("gpu", Engine::on_gpu(ctx)));
    }
    out
}

/// The class named `x` (a code), `swapped` to the other direction.
fn mirrored(x: f32) -> f32 {
    match FlipKind::from_code(x) {
        Some(FlipKind::UpperPlus) => FlipKind::UpperMinus.code(),
        Some(FlipKind::UpperMinus) => FlipKind::UpperPlus.code(),
        Some(FlipKind::LowerPlus) => FlipKind::LowerMinus.code(),
        Some(FlipKind::LowerMinus) => FlipKind::LowerPlus.code(),
        _ => x,
    }
}

/// On each path the kind is read off the same flip as the time: never exactly where the time
/// map says never, NaN exactly where it says NaN, a class elsewhere.
#[test]
fn the_kind_names_the_flip_the_time_map_finds() {
    for (name, engine) in engines() {
        let kinds = engine
            .map(
                &kind_spec(64, 20.0, common::lab_with_every_loss()),
                &Monitor::hidden(),
            )
            .unwrap();
        let times = engine
            .map(
                &FlipSpec {
                    measure: FlipMeasure::Time,
                    ..kind_spec(64, 20.0, common::lab_with_every_loss())
                },
                &Monitor::hidden(),
            )
            .unwrap();
        let mut seen = [0usize; 5];
        for (&k, &t) in kinds.data.iter().zip(&times.data) {
            let class = FlipKind::from_code(k);
            match class {
                Some(FlipKind::Never) => assert!(t.is_infinite(), "{name}: never, time {t}"),
                Some(c) => {
                    assert!(t.is_finite(), "{name}: {c:?} with time {t}");
                    seen[c as usize] += 1;
                }
                None => assert!(k.is_nan() && t.is_nan(), "{name}: code {k}, time {t}"),
            }
        }
        // The lab pendulum's 64^2 map at 20 s: every class occurs (the picture shows them).
        assert!(seen[1..].iter().all(|&n| n > 0), "{name}: classes {seen:?}");
    }
}

/// The equations are odd under y -> -y, so the mirrored start flips the same arm the other
/// way at the same time, bit for bit (exactly opposite states, see common::check_mirror):
/// the kind map is its own point reflection with the directions swapped, on both paths.
#[test]
fn mirrored_starts_flip_the_same_arm_the_other_way() {
    for (name, engine) in engines() {
        let mut s = kind_spec(48, 15.0, Params::default());
        s.grid.height = 37;
        let k = engine.map(&s, &Monitor::hidden()).unwrap();
        let (w, h) = (k.width, k.height);
        let wrong = (0..h)
            .flat_map(|r| (0..w).map(move |c| (c, r)))
            .filter(|&(c, r)| {
                k.get(c, r).to_bits() != mirrored(k.get(w - 1 - c, h - 1 - r)).to_bits()
            })
            .count();
        assert_eq!(wrong, 0, "{name}: pixels unlike their mirror image");
    }
}

/// GPU against the CPU twin: the same class on every pixel both verdicts vouch for (the
/// kind agreeing at half the step in f64 and the flip time agreeing too), but for at most
/// the verdict's promise of 0.1 % wrong among the resolved pixels.
#[test]
fn gpu_and_cpu_name_the_same_first_flip_where_resolved() {
    let Some(ctx) = common::gpu() else { return };
    let spec = kind_spec(96, 20.0, Params::default());
    let run = |engine: &Engine| -> (Field, Vec<u8>) {
        let (map, mask) = engine
            .planned_map(&engine.plan(&spec, true).unwrap(), &Monitor::hidden())
            .unwrap();
        (map, mask.unwrap())
    };
    let (gpu, gpu_mask) = run(&Engine::on_gpu(ctx));
    let (cpu, cpu_mask) = run(&Engine::new(Backend::Cpu).unwrap());
    let both: Vec<usize> = (0..gpu.data.len())
        .filter(|&i| gpu_mask[i] == 1 && cpu_mask[i] == 1)
        .collect();
    let differ = both
        .iter()
        .filter(|&&i| gpu.data[i].to_bits() != cpu.data[i].to_bits())
        .count();
    // Most of a 20 s map is resolved at dt 0.01 (the flip maps' verdict: ~98 %).
    assert!(
        both.len() * 10 > gpu.data.len() * 9,
        "{} resolved",
        both.len()
    );
    assert!(
        differ * 1000 <= both.len(),
        "{differ} of {} resolved pixels differ",
        both.len()
    );
}

/// The command line: the PNG with its legend and the command that remakes it, the .npy of
/// class codes, a store that `render` draws as the PNG, and the refusals.
#[test]
fn flip_kind_files_and_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let base = [
        "flip",
        "--colour-by",
        "kind",
        "--size",
        "40",
        "--t-max",
        "10",
    ];
    chaoscope()
        .args(base)
        .arg("--output")
        .arg(d("k.png"))
        .arg("--data")
        .arg(d("k.npy"))
        .assert()
        .success();
    let (shape, codes) = read_npy(&d("k.npy"));
    assert_eq!(shape, [40, 40]);
    assert!(
        codes
            .iter()
            .all(|&x| x.is_nan() || FlipKind::from_code(x).is_some())
    );
    let command = png_text(&d("k.png"), "chaoscope:command");
    assert!(command.contains("--colour-by kind"), "{command}");
    // The recorded command makes the same codes again.
    let words: Vec<&str> = command.split_whitespace().skip(1).collect();
    chaoscope()
        .args(&words)
        .arg("--output")
        .arg(d("again.png"))
        .arg("--data")
        .arg(d("again.npy"))
        .assert()
        .success();
    let (_, again) = read_npy(&d("again.npy"));
    assert!(
        codes
            .iter()
            .zip(&again)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    // Annotated: the legend's labels are drawn (the picture is larger than the map).
    chaoscope()
        .args(base)
        .args(["--annotate", "--output"])
        .arg(d("legend.png"))
        .assert()
        .success();
    let legend = chaoscope::render::read_png(&d("legend.png")).unwrap();
    assert!(legend.width > 40 && legend.height > 40);
    // Into a store, drawn by render: the same picture as the PNG.
    chaoscope()
        .args(base)
        .arg("--data")
        .arg(d("k.zarr"))
        .assert()
        .success();
    chaoscope()
        .args(["render", d("k.zarr").to_str().unwrap(), "--output"])
        .arg(d("rendered.png"))
        .assert()
        .success();
    let (a, b) = (
        chaoscope::render::read_png(&d("k.png")).unwrap(),
        chaoscope::render::read_png(&d("rendered.png")).unwrap(),
    );
    assert_eq!(a.rgb, b.rgb);
    for (extra, flag) in [
        (&["--colormap", "viridis"][..], "--colormap"),
        (&["--integrator", "dp54"][..], "--integrator"),
    ] {
        chaoscope()
            .args(base)
            .args(extra)
            .arg("--output")
            .arg(d("x.png"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains(flag));
    }
}

/// A sweep of flip-kind frames: each frame is the flip-kind map its command names.
#[test]
fn a_sweep_of_flip_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    chaoscope()
        .args("sweep --map flip-kind --vary m2=1:2 --frames 2".split(' '))
        .args(["--size", "24", "--t-max", "5", "--output"])
        .arg(&out)
        .assert()
        .success();
    let frames: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().contains("frame_"))
        .collect();
    assert_eq!(frames.len(), 2);
    for frame in frames {
        let command = png_text(&frame, "chaoscope:command");
        assert!(command.contains("--colour-by kind"), "{command}");
    }
}
