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
