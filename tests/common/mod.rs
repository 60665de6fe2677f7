//! Shared by the integration tests.
#![allow(dead_code)]

use chaoscope::Error;
use chaoscope::gpu::GpuContext;

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
        chaoscope::render::write_png(&path, field.width, field.height, &rgb, &[])
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
