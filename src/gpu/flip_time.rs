//! Drives `shaders/flip_time.wgsl`: tiles the grid to fit a storage binding, splits the time
//! loop into dispatches of bounded work, and keeps the still-active pixels in a dense list.

use super::context::{GpuContext, map_read, read_f32s};
use super::layout::{FLIP_TIME_WGSL, GpuParams, NEVER};
use super::pipeline::{
    Tiling, Variants, bind_group, layouts, params_buffer, record_dispatch, shader_module,
    storage_buffer,
};
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::FlipSpec;

/// Pendulum-steps per dispatch: about 0.1 s on lavapipe (~1.5e8 steps/s), far less on a real
/// GPU, so no dispatch holds the device long enough to trip a driver watchdog.
pub const STEPS_PER_DISPATCH: u64 = 1 << 24;

/// Bytes of GPU memory per pixel of a tile: state (32), time (4), two active lists (4 + 4).
const BYTES_PER_PIXEL: u64 = 44;

pub struct FlipTimeKernel {
    /// (flip_init, flip_time), without and with losses.
    pipelines: Variants,
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

impl FlipTimeKernel {
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(ctx, "flip_time.wgsl", FLIP_TIME_WGSL);
        let (layout, pipeline_layout) =
            layouts(ctx, "flip_time", &[false, false, true, false, false]);
        let kernel = FlipTimeKernel {
            pipelines: Variants::new(
                module,
                pipeline_layout,
                ("flip_init", "flip_time"),
                Some("EARLY_EXIT"),
            ),
            layout,
        };
        // Compile what a map needs (lossless, early exit) now, so callers can time runs
        // without the compile; other variants compile on first use.
        kernel.pipelines.get(ctx, 0, true);
        kernel
    }

    fn buffers(&self, ctx: &GpuContext, capacity: u64) -> Buffers {
        let params = params_buffer(ctx);
        let states = storage_buffer(ctx, "states", capacity * 32);
        let times = storage_buffer(ctx, "times", capacity * 4);
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
        params: &GpuParams,
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
        record_dispatch(&mut encoder, pipeline, bind_group, params.count);
        if read_count {
            encoder.copy_buffer_to_buffer(&bufs.counter, 0, &bufs.counter_read, 0, 4);
        }
        ctx.queue.submit([encoder.finish()]);
        if read_count {
            let bytes = map_read(ctx, &bufs.counter_read)?;
            Ok(u32::from_le_bytes(bytes[..4].try_into().expect("4 bytes")))
        } else {
            ctx.wait()?;
            Ok(params.count)
        }
    }

    /// The flip-time map of `spec` (s, +inf = never flipped), in tiles as large as the
    /// device's storage bindings allow.
    pub fn run(&self, ctx: &GpuContext, spec: &FlipSpec, monitor: &Monitor) -> Result<Field> {
        let max_pixels = (ctx.max_binding() / 32).min(ctx.limits.max_buffer_size / BYTES_PER_PIXEL);
        self.run_tiled(ctx, spec, monitor, max_pixels)
    }

    /// As `run`, with tiles of at most `max_pixels` pixels (whole rows, at least one).
    pub fn run_tiled(
        &self,
        ctx: &GpuContext,
        spec: &FlipSpec,
        monitor: &Monitor,
        max_pixels: u64,
    ) -> Result<Field> {
        let grid = spec.grid;
        let (init, advance) = self
            .pipelines
            .get(ctx, spec.params.losses.kinds(), spec.early_exit);
        let total_steps = spec.stepping.steps();
        let rows_needed = spec.rows_to_integrate();
        let tiling = Tiling::new(grid.width, rows_needed, max_pixels);
        let bufs = self.buffers(ctx, tiling.capacity());
        let tiles = tiling.count();
        monitor.start("gpu", tiles as u64 * total_steps as u64);

        let mut field = Field::new(grid.width, grid.height, f32::INFINITY);
        let base = GpuParams::new(&spec.params, spec.stepping.dt).with_grid(&grid);
        let t_max = spec.stepping.t_max as f32;
        for (row0, rows) in tiling.tiles() {
            let pixels = rows * grid.width;
            let mut params = GpuParams {
                row0,
                rows,
                count: pixels,
                ..base
            };
            let mut active =
                self.dispatch(ctx, &bufs, init, &bufs.b_to_a, &params, spec.early_exit)?;
            if !spec.early_exit {
                active = pixels;
            }
            let mut step0 = 0;
            let mut a_to_b = true;
            while step0 < total_steps && active > 0 {
                monitor.check()?;
                let steps = (STEPS_PER_DISPATCH / active as u64)
                    .clamp(1, (total_steps - step0) as u64) as u32;
                params.step0 = step0;
                params.steps = steps;
                params.count = active;
                let bind = if a_to_b { &bufs.a_to_b } else { &bufs.b_to_a };
                active = self.dispatch(ctx, &bufs, advance, bind, &params, spec.early_exit)?;
                a_to_b = !a_to_b;
                step0 += steps;
                monitor.advance(steps as u64);
            }
            monitor.advance((total_steps - step0) as u64);
            let times = read_f32s(ctx, &bufs.times, pixels as u64)?;
            let start = row0 as usize * grid.width as usize;
            for (out, t) in field.data[start..start + pixels as usize]
                .iter_mut()
                .zip(times)
            {
                *out = if t == NEVER || t > t_max {
                    f32::INFINITY
                } else {
                    t
                };
            }
        }
        field.mirror_below(rows_needed);
        monitor.finish();
        Ok(field)
    }
}
