//! Shared by the integration tests.
#![allow(dead_code)]

use std::path::Path;

use assert_cmd::Command;
use chaoscope::Error;
use chaoscope::gpu::GpuContext;
use chaoscope::model::{Losses, Params, State};
use chaoscope::params::Preset;

/// The binary, with lavapipe's runtime directory set so it does not warn.
pub fn chaoscope() -> Command {
    let mut cmd = Command::cargo_bin("chaoscope").expect("binary");
    cmd.env("XDG_RUNTIME_DIR", std::env::temp_dir());
    cmd
}

/// (shape, data) of a float32 .npy file written in C order.
pub fn read_npy(path: &Path) -> (Vec<u64>, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.order(), npyz::Order::C);
    let shape = npy.shape().to_vec();
    (shape, npy.into_vec::<f32>().unwrap())
}

/// (shape, data) of a uint8 .npy file (a verdict's mask).
pub fn read_mask(path: &Path) -> (Vec<u64>, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    let shape = npy.shape().to_vec();
    (shape, npy.into_vec::<u8>().unwrap())
}

/// The text chunk `key` of a decoded PNG.
pub fn text_of(png: &chaoscope::render::Png, key: &str) -> String {
    png.text
        .iter()
        .find(|(k, _)| k == key)
        .unwrap_or_else(|| panic!("no {key} in the PNG"))
        .1
        .clone()
}

/// The text chunk `key` of the PNG at `path`.
pub fn png_text(path: &Path, key: &str) -> String {
    text_of(&chaoscope::render::read_png(path).unwrap(), key)
}

/// Every loss on, rods with mass: the hardest case for both paths.
pub fn rods_and_every_loss() -> Params {
    Params {
        m1: 0.8,
        m2: 0.5,
        l1: 0.7,
        l2: 0.5,
        rod1: 0.2,
        rod2: 0.1,
        losses: Losses {
            joint1: 0.02,
            joint2: 0.01,
            rho: 1.2,
            cw: 2.0,
            bob_area1: 3e-3,
            bob_area2: 3e-3,
            rod_area1: 4e-3,
            rod_area2: 3e-3,
            // 100x the report's, to be visible in short runs.
            bearing: 0.05,
            bearing_radius: 0.004,
        },
        ..Params::default()
    }
}

/// The lab preset (drag, bearings, rods) with joint damping too: every kind of loss at the
/// apparatus' scale (all odd in the velocities, as they must be for the symmetry).
pub fn lab_with_every_loss() -> Params {
    let mut p = Preset::Lab.params();
    p.losses.joint1 = 2e-4;
    p.losses.joint2 = 1e-4;
    p
}

/// One GPU trajectory: the state at every step.
pub fn gpu_trajectory(
    ctx: &GpuContext,
    p: &Params,
    start: State,
    dt: f64,
    steps: u32,
) -> Vec<State> {
    chaoscope::gpu::TrajectoryKernel::new(ctx)
        .run(
            ctx,
            &chaoscope::spec::EnsembleSpec::new(*p, &[start], dt, steps),
        )
        .expect("gpu trajectory")
        .remove(0)
}

/// A real GPU adapter (lavapipe in CI). Under CI=true a missing adapter fails the test; on a
/// developer's machine without one the GPU test says so and does nothing else.
pub fn gpu() -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(ctx) => Some(ctx),
        Err(Error::NoAdapter) if std::env::var("CI").as_deref() != Ok("true") => {
            eprintln!(
                "SKIPPED: no GPU adapter (install mesa-vulkan-drivers); under CI=true this fails"
            );
            None
        }
        Err(e) => panic!("no usable GPU adapter, and GPU tests must run: {e}"),
    }
}

/// A GPU adapter with f64 (`gpu`'s rules); lavapipe has it, so under CI its absence fails.
pub fn f64_gpu() -> Option<GpuContext> {
    let ctx = gpu()?;
    assert!(
        ctx.has_f64(),
        "lavapipe offers SHADER_F64; this adapter does not"
    );
    Some(ctx)
}

/// Writes a failing map comparison as PNGs to out/test-failures/ and returns their paths.
pub fn dump_maps(name: &str, maps: &[(&str, &chaoscope::Field)], t_max: f64) -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("out/test-failures");
    let mut paths = Vec::new();
    for (label, field) in maps {
        let rgb = chaoscope::render::flip_colors(
            field,
            chaoscope::render::FlipColors {
                t_lo: 0.32,
                t_max,
                colormap: chaoscope::render::Colormap::Inferno,
            },
        );
        let path = dir.join(format!("{name}-{label}.png"));
        chaoscope::render::write_png(&path, (field.width, field.height), &rgb, &[])
            .expect("write failure map");
        paths.push(path.display().to_string());
    }
    paths.join(", ")
}

/// The map with every pixel integrated, checked to be point-symmetric bit for bit, and the
/// map that integrates the top half and mirrors it, checked to be the same map.
pub fn check_mirror(full: &chaoscope::Field, half: &chaoscope::Field, what: &str) {
    let (w, h) = (full.width, full.height);
    let asymmetric = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .filter(|&(c, r)| full.get(c, r).to_bits() != full.get(w - 1 - c, h - 1 - r).to_bits())
        .count();
    // Not a tolerance: the starts are exact negatives (odd half-steps from 0) and every
    // operation of the integrator commutes with negation under round-to-nearest, so mirrored
    // starts run through the same numbers with opposite signs, chaotic or not.
    assert_eq!(
        asymmetric, 0,
        "{what}: pixels that differ from their mirror image"
    );
    assert_eq!(
        full, half,
        "{what}: mirrored half differs from the whole map"
    );
}

/// The shader's dual-number Jacobians at `states` against the CPU's (num-dual through the
/// nalgebra solve), entry by entry.
pub fn check_jacobians(
    ctx: &GpuContext,
    p: &chaoscope::model::Params,
    states: &[chaoscope::model::State],
) {
    let gpu_j = chaoscope::gpu::JacobianKernel::new(ctx)
        .run(ctx, p, states)
        .unwrap();
    for (s, g) in states.iter().zip(&gpu_j) {
        let c = chaoscope::cpu::jacobian(p, s);
        let scale = 1.0 + c.abs().max();
        for r in 0..4 {
            for k in 0..4 {
                // f32 evaluation of ~30 operations, each rounding by 2^-24 relative, on
                // terms up to the matrix scale: a few 1e-6 of it.
                assert!(
                    (g[r][k] - c[(r, k)]).abs() < 2e-5 * scale,
                    "J[{r}][{k}] gpu {} cpu {} at {s:?}",
                    g[r][k],
                    c[(r, k)]
                );
            }
        }
    }
}

/// Every file under `dir`.
pub fn walk(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let path = e.unwrap().path();
        if path.is_dir() {
            out.extend(walk(&path));
        } else {
            out.push(path.display().to_string());
        }
    }
    out
}

/// Each case's flags after `prefix` exit 2 naming its flag, and write nothing.
pub fn refuses(prefix: &[&str], cases: &[(&[&str], &str)]) {
    let dir = tempfile::tempdir().unwrap();
    for (args, flag) in cases {
        let out = chaoscope()
            .args(prefix)
            .args(*args)
            .arg("--output")
            .arg(dir.path().join("never.png"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?} should name {flag}: {err}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// The JSON summary of a finished run that must have succeeded.
pub fn summary(out: std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Whether FFmpeg is here: films need it; without it a film's test cannot say anything, and
/// under CI (where scripts/test installs it) its absence is a failure, never a skip.
pub fn ffmpeg() -> bool {
    let found = std::process::Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var("CI").is_err(),
            "ffmpeg is missing (scripts/test installs it)"
        );
        eprintln!("SKIPPED: no ffmpeg");
    }
    found
}

/// A fuzzed flag's value: half the time its plausible one `good` (none for a switch), else
/// one of `traps` or nothing at all.
pub fn fuzz_value(rng: &mut fastrand::Rng, good: Option<&str>, traps: &[&str]) -> Option<String> {
    match (rng.bool(), good) {
        (true, good) => good.map(str::to_string),
        (false, _) if rng.u8(..10) < 8 => Some(traps[rng.usize(..traps.len())].to_string()),
        (false, _) => None,
    }
}

/// The Python with selenium that scripts/test installs, and Debian's chromium and its
/// driver; None (a skip, or a failure under CI=true) without them.
pub fn browser_tools() -> Option<String> {
    let python = std::env::var("CHAOSCOPE_PYTHON").unwrap_or_else(|_| {
        let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/pyenv/bin/python");
        venv.to_str().unwrap().to_string()
    });
    let has_selenium = std::process::Command::new(&python)
        .args(["-c", "import selenium"])
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    let present = has_selenium
        && Path::new("/usr/bin/chromium").exists()
        && Path::new("/usr/bin/chromedriver").exists();
    if !present {
        assert_ne!(
            std::env::var("CI").as_deref(),
            Ok("true"),
            "no selenium in {python}, or no /usr/bin/chromium and chromedriver (scripts/test installs them)"
        );
        eprintln!("SKIPPED: no selenium, chromium or chromedriver (scripts/test installs them)");
        return None;
    }
    Some(python)
}

/// Runs tests/browser/`script` with `python` and `args`, and returns the JSON report it
/// prints (failing with it when the script fails).
pub fn browser_report(python: &str, script: &str, args: &[&std::ffi::OsStr]) -> serde_json::Value {
    let out = std::process::Command::new(python)
        .arg(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/browser")
                .join(script),
        )
        .args(args)
        .stderr(std::process::Stdio::inherit())
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "the browser script failed: {report}");
    eprintln!("browser: {report}");
    serde_json::from_str(&report).unwrap()
}

/// A command line's words, written as one line: `argv("flip --size 8")`.
pub fn argv(line: &str) -> Vec<&str> {
    line.split(' ').collect()
}
