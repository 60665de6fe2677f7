//! No GPU needed: every shader parses and validates with naga, and the WGSL structs match
//! their Rust mirrors in size and member offsets.

use chaoscope::gpu::layout::{
    GpuAdaptiveSlot, GpuAdaptiveSlot64, GpuBandTime, GpuIndicatorSlot, GpuIndicatorSlot64,
    GpuLyapunovSlot, GpuParams, GpuParams64, GpuPendulum, GpuPendulum64,
};
use chaoscope::gpu::shaders::all_shaders;
use wgpu::naga;

fn module(name: &str, source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}.wgsl does not parse:\n{}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        // f64 for the f64 kernels (the device asks for SHADER_F64 when it runs them).
        naga::valid::Capabilities::FLOAT64,
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}.wgsl does not validate: {e:?}"));
    module
}

#[test]
fn every_shader_parses_and_validates() {
    for (name, source) in all_shaders() {
        module(&name, &source);
    }
}

/// (name, offset) of each member of the WGSL struct `name`, and its size.
fn wgsl_struct(module: &naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the shader"))
        .1;
    match &ty.inner {
        naga::TypeInner::Struct { members, span } => (
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
            *span,
        ),
        other => panic!("{name} is not a struct: {other:?}"),
    }
}

macro_rules! rust_offsets {
    ($ty:ty; $($field:ident),* $(,)?) => {
        vec![$((stringify!($field).to_string(), std::mem::offset_of!($ty, $field) as u32)),*]
    };
}

/// The members of a `Params` mirror, in the WGSL struct's order, with their offsets.
macro_rules! params_offsets {
    ($ty:ty) => {
        rust_offsets!($ty;
            a, b, c, p, q, l1, l2, dt, x_mid, x_half_step, y_mid, y_half_step, omega1, omega2,
            no_flip_energy, joint1, joint2, drag_bob1, drag_bob2, drag_rod1, drag_rod2, g,
            mass_total, mass_lower, bearing, theta1, theta2, m1, m2, rod1, rod2, eps,
            width, height, rows, row0, step0, steps, count, interval, total_steps,
            setting, rtol, atol, t_max, measure, x_var, y_var, seed, six)
    };
}

#[test]
fn params_struct_matches_its_rust_mirror() {
    let rust = params_offsets!(GpuParams);
    // The f64 mirror's explicit padding (_pad_a) is implicit in WGSL.
    let rust64 = params_offsets!(GpuParams64);
    for (name, source) in all_shaders() {
        let (wgsl, span) = wgsl_struct(&module(&name, &source), "Params");
        let (rust, size) = if name.ends_with("_f64") {
            (&rust64, std::mem::size_of::<GpuParams64>())
        } else {
            (&rust, std::mem::size_of::<GpuParams>())
        };
        assert_eq!(span as usize, size, "{name}: size of Params");
        assert_eq!(
            &wgsl, rust,
            "{name}: members and offsets of Params (WGSL left, Rust right)"
        );
    }
}

/// The per-pixel storage mirrors, from whose sizes the tiles' bytes per pixel are computed.
#[test]
fn storage_structs_match_their_rust_mirrors() {
    let pendulum = rust_offsets!(GpuPendulum; y, u);
    let pendulum64 = rust_offsets!(GpuPendulum64; y, u);
    let slot = rust_offsets!(GpuLyapunovSlot; y, u, v, w);
    for (name, source) in all_shaders() {
        let module = module(&name, &source);
        let (wgsl, span) = wgsl_struct(&module, "Pendulum");
        let (rust, size) = if name.ends_with("_f64") {
            (&pendulum64, std::mem::size_of::<GpuPendulum64>())
        } else {
            (&pendulum, std::mem::size_of::<GpuPendulum>())
        };
        assert_eq!(span as usize, size, "{name}: Pendulum");
        assert_eq!(&wgsl, rust, "{name}: members and offsets of Pendulum");
        if name == "lyapunov" {
            let (wgsl, span) = wgsl_struct(&module, "LyapunovSlot");
            assert_eq!(
                span as usize,
                std::mem::size_of::<GpuLyapunovSlot>(),
                "LyapunovSlot"
            );
            assert_eq!(wgsl, slot, "members and offsets of LyapunovSlot");
        }
        if name.starts_with("flip_adaptive") {
            let (wgsl, span) = wgsl_struct(&module, "AdaptiveSlot");
            let (rust, size) = if name.ends_with("_f64") {
                (
                    rust_offsets!(GpuAdaptiveSlot64; y, u, clock),
                    std::mem::size_of::<GpuAdaptiveSlot64>(),
                )
            } else {
                (
                    rust_offsets!(GpuAdaptiveSlot; y, u, clock),
                    std::mem::size_of::<GpuAdaptiveSlot>(),
                )
            };
            assert_eq!(span as usize, size, "{name}: AdaptiveSlot");
            assert_eq!(wgsl, rust, "{name}: members and offsets of AdaptiveSlot");
        }
        if name.starts_with("positions") {
            let (wgsl, span) = wgsl_struct(&module, "BandTime");
            assert_eq!(
                span as usize,
                std::mem::size_of::<GpuBandTime>(),
                "{name}: BandTime"
            );
            assert_eq!(
                wgsl,
                rust_offsets!(GpuBandTime; step, fraction),
                "{name}: members and offsets of BandTime"
            );
        }
        if name.starts_with("indicators") {
            let (wgsl, span) = wgsl_struct(&module, "IndicatorSlot");
            let (rust, size) = if name.ends_with("_f64") {
                (
                    rust_offsets!(GpuIndicatorSlot64; y, u, v, sums, clock),
                    std::mem::size_of::<GpuIndicatorSlot64>(),
                )
            } else {
                (
                    rust_offsets!(GpuIndicatorSlot; y, u, v, sums, clock),
                    std::mem::size_of::<GpuIndicatorSlot>(),
                )
            };
            assert_eq!(span as usize, size, "{name}: IndicatorSlot");
            assert_eq!(wgsl, rust, "{name}: members and offsets of IndicatorSlot");
        }
    }
}
