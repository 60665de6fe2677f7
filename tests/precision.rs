//! f64 on the GPU: its own sin and cos against Rust's, and its maps against the f64 CPU's.

mod common;

use chaoscope::cpu;
use chaoscope::gpu::{FlipTimeKernel, GpuContext, shaders};
use chaoscope::model::Params;
use chaoscope::monitor::Monitor;
use chaoscope::spec::{FlipSpec, Grid, Precision, Stepping};

fn spec(n: u32, t_max: f64, dt: f64) -> FlipSpec {
    FlipSpec::new(Params::default(), Grid::square(n), Stepping { dt, t_max })
}

/// The f64 shaders' `sincos` at `xs`, through a kernel of its own.
fn gpu_sincos(ctx: &GpuContext, xs: &[f64]) -> Vec<[f64; 2]> {
    gpu_eval(ctx, xs, "data[gid.x] = sincos(data[gid.x].x);")
}

/// The f64 shaders' natural logarithm (`ln_real`, their own: SPIR-V's log is f32 only) at
/// `xs` (in .y).
fn gpu_ln(ctx: &GpuContext, xs: &[f64]) -> Vec<f64> {
    let body =
        "var r: real = 0.0;\n        r += ln_real(data[gid.x].x);\n        data[gid.x].y = r;";
    gpu_eval(ctx, xs, body).into_iter().map(|v| v[1]).collect()
}

/// (x, 0) for each of `xs` through `body` in an f64 kernel of its own; the pairs after.
fn gpu_eval(ctx: &GpuContext, xs: &[f64], body: &str) -> Vec<[f64; 2]> {
    let kernel = format!(
        "
@group(0) @binding(0) var<storage, read_write> data: array<vec2<real>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    if gid.x < arrayLength(&data) {{
        {body}
    }}
}}"
    );
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sincos"),
            source: wgpu::ShaderSource::Wgsl(shaders::assemble(&kernel, Precision::F64).into()),
        });
    let pipeline = ctx
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("sincos"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
    let input: Vec<f64> = xs.iter().flat_map(|&x| [x, 0.0]).collect();
    let bytes = (input.len() * 8) as u64;
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.queue
        .write_buffer(&buffer, 0, bytemuck::cast_slice(&input));
    let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((xs.len() as u32).div_ceil(64), 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let out: Vec<f64> =
        bytemuck::pod_collect_to_vec(&chaoscope::gpu::read_buffer(ctx, &buffer, bytes).unwrap());
    out.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
}

#[test]
fn f64_sin_and_cos_are_within_a_few_ulps_of_rusts() {
    let Some(ctx) = common::f64_gpu() else { return };
    // The starts' angles (|theta| <= pi) and well beyond, densely and at the quadrant edges.
    let mut xs: Vec<f64> = (0..20001).map(|k| -10.0 + 1e-3 * k as f64).collect();
    xs.extend((-8..=8).map(|q| q as f64 * std::f64::consts::FRAC_PI_2));
    let got = gpu_sincos(&ctx, &xs);
    let ulps = |a: f64, b: f64| ((a - b).abs() / f64::EPSILON).max(0.0);
    let worst = xs
        .iter()
        .zip(&got)
        .map(|(&x, &[s, c])| ulps(s, x.sin()).max(ulps(c, x.cos())))
        .fold(0.0f64, f64::max);
    eprintln!("f64 sincos: worst {worst:.2} ulp (of 1) over |x| <= 10");
    // Cody-Waite with three parts of pi/2 and degree-17/18 polynomials: a few roundings.
    assert!(worst <= 4.0, "{worst} ulp");
}

#[test]
fn f64_gpu_flip_maps_match_the_f64_cpu() {
    let Some(ctx) = common::f64_gpu() else { return };
    let kernel = FlipTimeKernel::with_precision(&ctx, Precision::F64);
    // At dt 0.001 the GPU's carried cos and sin (an O(dt^4) different discretisation than the
    // CPU's angles) and the two formulas' round-off differ by far less than the f32 in which
    // flip times are stored (2.4e-7 s at 3 s).
    let s = spec(64, 3.0, 0.001);
    let gpu = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
    let cpu = cpu::flip_map(&s, &Monitor::hidden()).unwrap();
    let mut worst = 0.0f64;
    for (g, c) in gpu.data.iter().zip(&cpu.data) {
        assert_eq!(g.is_infinite(), c.is_infinite(), "{g} vs {c}");
        if g.is_finite() {
            worst = worst.max((*g as f64 - *c as f64).abs());
        }
    }
    assert!(worst <= 1e-6, "{worst} s");
    // And f32 is visibly coarser on the same map (its round-off, amplified by the chaos).
    let f32_map = FlipTimeKernel::new(&ctx)
        .run(&ctx, &s, &Monitor::hidden())
        .unwrap();
    let worst32 = f32_map
        .data
        .iter()
        .zip(&cpu.data)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a as f64 - *b as f64).abs())
        .fold(0.0f64, f64::max);
    eprintln!("flip times vs CPU f64 at dt 0.001, 3 s: f64 GPU {worst:e} s, f32 GPU {worst32:e} s");
    assert!(worst32 > 10.0 * worst.max(1e-7), "{worst32} vs {worst}");
}

/// Largest difference of any state component between the GPU (in `precision`) and the f64
/// CPU over 1 s from (2, -1) at rest with step `dt`.
fn gpu_cpu_difference(ctx: &GpuContext, p: &Params, precision: Precision, dt: f64) -> f64 {
    use chaoscope::gpu::TrajectoryKernel;
    use chaoscope::model::State;
    let start = State::at_rest(2.0, -1.0);
    let steps = (1.0 / dt).round() as u32;
    let gpu = TrajectoryKernel::with_precision(ctx, precision)
        .run(
            ctx,
            &chaoscope::spec::EnsembleSpec::new(*p, &[start], dt, steps),
        )
        .unwrap()
        .remove(0);
    let cpu = cpu::trajectory(p, start, dt, steps);
    gpu.iter()
        .zip(&cpu)
        .flat_map(|(g, c)| {
            let (g, c) = (g.to_array(), c.to_array());
            (0..4).map(move |i| (g[i] - c[i]).abs())
        })
        .fold(0.0f64, f64::max)
}

#[test]
fn f64_gpu_trajectories_match_the_f64_cpu() {
    let Some(ctx) = common::f64_gpu() else { return };
    for (p, what) in [
        (Params::default(), "point masses"),
        (common::rods_and_every_loss(), "rods and every loss"),
    ] {
        let d = |dt| gpu_cpu_difference(&ctx, &p, Precision::F64, dt);
        let (coarse, half, fine) = (d(1e-3), d(5e-4), d(1e-4));
        // The paths differ by the GPU's carried cos and sin, another fourth-order
        // discretisation of the same motion: the difference is O(dt^4) (measured 6.6e-9 at
        // dt 1e-3, 4.1e-10 at 5e-4, 6.3e-13 at 1e-4), halving dt divides it by 16, and at
        // dt 1e-4 it is ~1e-12 with f64 round-off (1e-16 a step, 1e4 steps) below it.
        let ratio = coarse / half;
        assert!((12.0..20.0).contains(&ratio), "{what}: dt^4 ratio {ratio}");
        assert!(fine < 2e-12, "{what}: {fine} at dt 1e-4");
        // f32 stays at its round-off, ~1e-5, whatever the step.
        let f32_fine = gpu_cpu_difference(&ctx, &p, Precision::F32, 1e-4);
        assert!(
            f32_fine > 1e4 * fine,
            "{what}: f32 {f32_fine} vs f64 {fine}"
        );
    }
}

#[test]
fn f64_logarithm_is_within_a_few_ulps_of_rusts() {
    let Some(ctx) = common::f64_gpu() else { return };
    // Log stretches of renormalisations: around 1, and far out both ways.
    let mut xs: Vec<f64> = (1..20000).map(|k| 1e-3 * k as f64).collect();
    xs.extend((-300..=300).map(|k| 1.7f64.powi(k)));
    let got = gpu_ln(&ctx, &xs);
    let worst = xs
        .iter()
        .zip(&got)
        .map(|(&x, &l)| (l - x.ln()).abs() / (f64::EPSILON * x.ln().abs().max(1.0)))
        .fold(0.0f64, f64::max);
    eprintln!("f64 ln: worst {worst:.2} ulp (of max(|ln x|, 1))");
    // Exact scaling by powers of two, then the atanh series: a few roundings.
    assert!(worst <= 4.0, "{worst} ulp");
}

#[test]
fn f64_gpu_divergence_maps_match_the_f64_cpu() {
    use chaoscope::gpu::LyapunovKernel;
    use chaoscope::spec::{LyapunovSpec, Method};
    let Some(ctx) = common::f64_gpu() else { return };
    for method in [Method::Tangent, Method::Twin { eps: 1e-8 }] {
        let spec = LyapunovSpec {
            params: Params::default(),
            grid: Grid::square(16),
            stepping: Stepping {
                dt: 0.001,
                t_max: 2.0,
            },
            method,
            renorm: 0.1,
            use_symmetry: true,
            precision: Precision::F64,
            band: None,
            integrator: chaoscope::spec::Integrator::Rk4,
            indicator: chaoscope::spec::Indicator::Ftle,
        };
        let gpu = LyapunovKernel::with_precision(&ctx, method, Precision::F64)
            .run(&ctx, &spec, &Monitor::hidden())
            .unwrap();
        let cpu = cpu::ftle_map(&spec, &Monitor::hidden()).unwrap();
        let worst = gpu
            .data
            .iter()
            .zip(&cpu.data)
            .map(|(g, c)| (*g as f64 - *c as f64).abs())
            .fold(0.0f64, f64::max);
        eprintln!("{method:?}: f64 GPU vs CPU exponents differ by {worst:e} /s at most");
        // Tangent: at dt 0.001 over 2 s the paths' O(dt^4) difference and round-off are
        // below the f32 the exponents are stored in (~1e-7 of ~1 /s; measured 1.2e-7). Twin:
        // a finite difference over 1e-8 (resolved in f64; in f32 it is round-off) that
        // differentiates that O(dt^4) difference of the schemes as well (measured 5.6e-5).
        let bound = match method {
            Method::Tangent => 1e-5,
            Method::Twin { .. } => 1e-3,
        };
        assert!(worst < bound, "{method:?}: {worst}");
    }
}
