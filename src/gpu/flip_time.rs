//! Drives `shaders/flip_time.wgsl`: keeps the still-active pixels of a tile in a dense list,
//! inside the tiled loop of `tiled.rs`.

use super::context::{GpuContext, map_read, read_buffer};
use super::layout::{NEVER, NONFINITE, Real, Run, RunParams, TileParams, read_reals, with_real};
use super::pipeline::{
    Variants, bind_group, kernel_module, layouts, params_buffer_of, record_dispatch, storage_buffer,
};
use super::shaders::Kernel;
use super::tiled::{TileWork, Tiling, adaptive_loop, map_tiles, max_pixels, time_loop};
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::quantity::FlipKind;
use crate::spec::{FlipMeasure, FlipSpec, Grid, Integrator, MAX_STEPS, Precision, Range};

pub struct FlipTimeKernel {
    precision: Precision,
    /// (flip_init, flip_time) per kind of loss and early exit.
    pipelines: Variants,
    /// (flip_adaptive_init, flip_adaptive), the same: DP54 ...
    adaptive: Variants,
    /// ... and DOP853.
    dop853: Variants,
    /// (flip_init, flip_kind): the flip-kind map, RK4 (flip_kind.wgsl over flip_time.wgsl).
    kind: Variants,
    layout: wgpu::BindGroupLayout,
}

struct Buffers {
    params: wgpu::Buffer,
    // Kept with the bind groups that use it.
    _states: wgpu::Buffer,
    times: wgpu::Buffer,
    counter: wgpu::Buffer,
    counter_read: wgpu::Buffer,
    /// Bind groups reading list A and writing list B, and the reverse.
    a_to_b: wgpu::BindGroup,
    b_to_a: wgpu::BindGroup,
}

/// Bytes per pixel of the pendulum (with its clock when `adaptive`), the flip time and the
/// params, in `precision`.
fn sizes(precision: Precision, adaptive: bool) -> (u64, u64, u64) {
    use std::mem::size_of;
    with_real!(precision, R => (
        match adaptive {
            true => size_of::<<R as Real>::AdaptiveSlot>(),
            false => size_of::<<R as Real>::Pendulum>(),
        } as u64,
        size_of::<R>() as u64,
        size_of::<<R as Real>::Params>() as u64,
    ))
}

/// t-max as the kernel compares flip times with it: rounded to the kernel's precision (so
/// f32 maps keep the bits they had before f64 kernels existed).
fn t_max_of(t_max: f64, precision: Precision) -> f64 {
    with_real!(precision, R => R::from_f64(t_max).to_f64())
}

/// Maps integrating more pixels than this estimate their work from a sample first.
const ESTIMATE_ABOVE: u64 = 1 << 20;

/// Every 16th start each way of the part of `spec`'s grid that is integrated.
fn sample_spec(spec: &FlipSpec) -> FlipSpec {
    let g = &spec.grid;
    let rows = spec.rows_to_integrate();
    let mut grid = Grid {
        width: (g.width / 16).max(1),
        height: (rows / 16).max(1),
        ..*g
    };
    grid.y.range = Range {
        min: g.y.range.max - rows as f64 * g.y_step(),
        max: g.y.range.max,
    };
    FlipSpec {
        grid,
        use_symmetry: false,
        measure: FlipMeasure::Time,
        ..*spec
    }
}

/// Mean pendulum-steps a start of `sample` took: to its flip, all of them if it never
/// flipped (or blew up), none if it lay below the no-flip energy.
fn work_per_pixel(spec: &FlipSpec, sample: &Field) -> f64 {
    let steps = spec.stepping.steps() as f64;
    let g = sample_spec(spec).grid;
    let total: f64 = (0..g.height)
        .flat_map(|row| (0..g.width).map(move |col| (col, row)))
        .map(|(col, row)| {
            let t = sample.get(col, row) as f64;
            if t.is_finite() {
                (t / spec.stepping.dt).ceil().clamp(1.0, steps)
            } else if let (p, s) = g.pixel(&spec.params, col, row)
                && p.energy(&s) < p.no_flip_threshold(f32::EPSILON as f64)
            {
                0.0
            } else {
                steps
            }
        })
        .sum();
    total / g.pixels() as f64
}

impl FlipTimeKernel {
    /// The f32 kernel.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_precision(ctx, Precision::F32)
    }

    /// The kernel in `precision` (f64 needs a context with `GpuContext::has_f64`).
    pub fn with_precision(ctx: &GpuContext, precision: Precision) -> Self {
        let module = kernel_module(ctx, Kernel::FlipTime, precision);
        let kind = kernel_module(ctx, Kernel::FlipKind, precision);
        let adaptive = kernel_module(ctx, Kernel::FlipDp54, precision);
        let dop853 = kernel_module(ctx, Kernel::FlipDop853, precision);
        let (layout, pipeline_layout) =
            layouts(ctx, "flip_time", &[false, false, true, false, false]);
        let kernel = FlipTimeKernel {
            precision,
            pipelines: Variants::new(
                module,
                pipeline_layout.clone(),
                &["flip_init", "flip_time"],
                Some("EARLY_EXIT"),
            ),
            adaptive: Variants::new(
                adaptive,
                pipeline_layout.clone(),
                &["flip_adaptive_init", "flip_adaptive"],
                Some("EARLY_EXIT"),
            ),
            dop853: Variants::new(
                dop853,
                pipeline_layout.clone(),
                &["flip_adaptive_init", "flip_adaptive"],
                Some("EARLY_EXIT"),
            ),
            kind: Variants::new(
                kind,
                pipeline_layout,
                &["flip_init", "flip_kind"],
                Some("EARLY_EXIT"),
            ),
            layout,
        };
        // Compile what a map needs (lossless, early exit) now, so callers can time runs
        // without the compile; other variants compile on first use.
        kernel.pipelines.get(ctx, 0, true, false);
        kernel
    }

    fn buffers(&self, ctx: &GpuContext, capacity: u64, adaptive: bool) -> Buffers {
        let (pendulum, time, params) = sizes(self.precision, adaptive);
        let params = params_buffer_of(ctx, params);
        let states = storage_buffer(ctx, "states", capacity * pendulum);
        let times = storage_buffer(ctx, "times", capacity * time);
        let list_a = storage_buffer(ctx, "active list a", capacity * 4);
        let list_b = storage_buffer(ctx, "active list b", capacity * 4);
        let counter = storage_buffer(ctx, "counter", 4);
        let counter_read = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("counter readback"),
            size: 4,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let bind = |label, list_in: &wgpu::Buffer, list_out: &wgpu::Buffer| {
            let buffers = [&params, &states, &times, list_in, list_out, &counter];
            bind_group(ctx, label, &self.layout, &buffers)
        };
        let a_to_b = bind("a -> b", &list_a, &list_b);
        let b_to_a = bind("b -> a", &list_b, &list_a);
        Buffers {
            params,
            _states: states,
            times,
            counter,
            counter_read,
            a_to_b,
            b_to_a,
        }
    }

    /// Runs one dispatch; with `read_count`, returns the number of pixels it left active.
    fn dispatch(
        &self,
        ctx: &GpuContext,
        bufs: &Buffers,
        pipeline: &wgpu::ComputePipeline,
        bind_group: &wgpu::BindGroup,
        params: &impl TileParams,
        read_count: bool,
    ) -> Result<u32> {
        ctx.queue
            .write_buffer(&bufs.params, 0, bytemuck::bytes_of(params));
        ctx.queue
            .write_buffer(&bufs.counter, 0, &0u32.to_le_bytes());
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("flip"),
            });
        record_dispatch(&mut encoder, pipeline, bind_group, params.count());
        if read_count {
            encoder.copy_buffer_to_buffer(&bufs.counter, 0, &bufs.counter_read, 0, 4);
        }
        ctx.queue.submit([encoder.finish()]);
        if read_count {
            let bytes = map_read(ctx, &bufs.counter_read)?;
            Ok(u32::from_le_bytes(bytes[..4].try_into().expect("4 bytes")))
        } else {
            ctx.wait()?;
            Ok(params.count())
        }
    }

    /// The flip-time map of `spec` (s, +inf = never flipped), in tiles as large as the
    /// device's storage bindings allow.
    pub fn run(&self, ctx: &GpuContext, spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
        let adaptive = spec.integrator != Integrator::Rk4;
        let (pendulum, time, _) = sizes(self.precision, adaptive);
        // The pendulum, the flip time and two active-list entries a pixel.
        let max = max_pixels(ctx, pendulum, pendulum + time + 8);
        // Large early-exit maps first integrate a sparse sample of their starts (1 in 256),
        // whose work per pixel foretells the whole map's: the progress bar's ETA then holds
        // from the start instead of following the flips' uneven waves.
        let pixels = spec.rows_to_integrate() as u64 * spec.grid.width as u64;
        if spec.early_exit && !adaptive && spec.band.is_none() && pixels > ESTIMATE_ABOVE {
            let sample = self.run_tiled(ctx, &sample_spec(spec), &monitor.quiet(), max)?;
            monitor.estimate(work_per_pixel(spec, &sample) * pixels as f64);
        }
        self.run_tiled(ctx, spec, monitor, max)
    }

    /// As `run`, with tiles of at most `max_pixels` pixels (whole rows, at least one).
    pub fn run_tiled(
        &self,
        ctx: &GpuContext,
        spec: &FlipSpec,
        monitor: &Monitor,
        max_pixels: u64,
    ) -> Result<Field> {
        with_real!(self.precision, R => self.integrate::<R>(ctx, spec, monitor, max_pixels))
    }

    /// The tiled loop in the kernel's scalar `R`.
    fn integrate<R: Real>(
        &self,
        ctx: &GpuContext,
        spec: &FlipSpec,
        monitor: &Monitor,
        max_pixels: u64,
    ) -> Result<Field> {
        let (rtol, atol) = spec.integrator.tolerances().unwrap_or_default();
        let base = R::Params::of(&spec.params, spec.stepping.dt)
            .over(&spec.grid, &spec.params)
            .with_run(Run {
                rtol,
                atol,
                t_max: spec.stepping.t_max,
                ..Run::default()
            });
        let grid = spec.grid;
        let adaptive = spec.integrator != Integrator::Rk4;
        let variants = match (spec.measure, spec.integrator) {
            (FlipMeasure::Kind, _) => &self.kind,
            (FlipMeasure::Time, Integrator::Rk4) => &self.pipelines,
            (FlipMeasure::Time, Integrator::Dp54 { .. }) => &self.adaptive,
            (FlipMeasure::Time, Integrator::Dop853 { .. }) => &self.dop853,
        };
        let [init, advance] = variants.map_pair(ctx, &spec.params, &spec.grid, spec.early_exit);
        let total_steps = spec.stepping.steps();
        let tiling = Tiling::new(grid.width, spec.row_span(), max_pixels);
        let bufs = self.buffers(ctx, tiling.capacity(), adaptive);
        let t_max = spec.stepping.t_max;
        let time_bytes = sizes(self.precision, adaptive).1;
        map_tiles(&grid, &tiling, total_steps, monitor, |row0, rows, later| {
            let pixels = rows * grid.width;
            let mut params = base;
            params.set_tile(row0, rows, pixels);
            // The adaptive kernel lists every pixel it integrates, early exit or not.
            let read_count = spec.early_exit || adaptive;
            let listed = self.dispatch(ctx, &bufs, init, &bufs.b_to_a, &params, read_count)?;
            let active = if read_count { listed } else { pixels };
            if adaptive {
                // The attempts a pixel may take in all (the kernel's `total_steps`).
                params.set_total(MAX_STEPS);
            }
            let mut a_to_b = true;
            let mut advance_by = |step0, steps, active| {
                params.set_steps(step0, steps, active);
                let bind = if a_to_b { &bufs.a_to_b } else { &bufs.b_to_a };
                a_to_b = !a_to_b;
                self.dispatch(ctx, &bufs, advance, bind, &params, read_count)
            };
            if adaptive {
                adaptive_loop(
                    pixels,
                    active,
                    total_steps,
                    later,
                    monitor,
                    |steps, active| advance_by(0, steps, active),
                )?;
            } else {
                let work = TileWork {
                    active,
                    ..TileWork::new(total_steps, pixels, 1, later)
                };
                time_loop(work, monitor, advance_by)?;
            }
            let bytes = read_buffer(ctx, &bufs.times, pixels as u64 * time_bytes)?;
            let t_max = t_max_of(t_max, self.precision);
            Ok(read_reals::<R>(&bytes)
                .into_iter()
                .map(|t| match spec.measure {
                    _ if t == NONFINITE as f64 => f32::NAN,
                    FlipMeasure::Time if t == NEVER as f64 || t > t_max => f32::INFINITY,
                    FlipMeasure::Kind if t == NEVER as f64 => FlipKind::Never.code(),
                    FlipMeasure::Time | FlipMeasure::Kind => t as f32,
                })
                .collect())
        })
    }
}
