//! Drives `shaders/lyapunov.wgsl`: divergence maps, tiled like the flip map, every pixel
//! integrating the whole run in dispatches of bounded work.

use super::context::{GpuContext, read_f32s};
use super::flip_time::STEPS_PER_DISPATCH;
use super::layout::{GpuParams, LYAPUNOV_WGSL};
use super::pipeline::{
    Tiling, Variants, bind_group, compute_pipeline, dispatch_and_wait, layouts, params_buffer,
    shader_module, storage_buffer,
};
use crate::cpu::Convergence;
use crate::error::Result;
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{LyapunovSpec, Method};

/// Bytes of GPU memory per pixel: state and tangent (or twin) 64, log sum 4.
const BYTES_PER_PIXEL: u64 = 68;

/// A tangent step costs about this many plain steps (BENCH.md), so dispatches hold fewer.
const STEP_COST: u64 = 3;

pub struct LyapunovKernel {
    /// (init, advance) of the method, without and with losses.
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl LyapunovKernel {
    /// Compiles the entry points of `method` only (lavapipe compiles each pipeline anew).
    pub fn new(ctx: &GpuContext, method: Method) -> Self {
        let module = shader_module(ctx, "lyapunov.wgsl", LYAPUNOV_WGSL);
        let (layout, pipeline_layout) = layouts(ctx, "lyapunov", &[false, false]);
        let (init, advance) = match method {
            Method::Tangent => ("tangent_init", "tangent_advance"),
            Method::Twin { .. } => ("twin_init", "twin_advance"),
        };
        let kernel = LyapunovKernel {
            pipelines: Variants::new(module, pipeline_layout, (init, advance), None),
            layout,
        };
        kernel.pipelines.get(ctx, 0, false);
        kernel
    }

    /// The FTLE map of `spec` (1/s at t-max).
    pub fn run(&self, ctx: &GpuContext, spec: &LyapunovSpec, monitor: &Monitor) -> Result<Field> {
        let max_pixels = (ctx.max_binding() / 64).min(ctx.limits.max_buffer_size / BYTES_PER_PIXEL);
        self.run_tiled(ctx, spec, monitor, max_pixels)
    }

    /// As `run`, with tiles of at most `max_pixels` pixels (whole rows, at least one).
    pub fn run_tiled(
        &self,
        ctx: &GpuContext,
        spec: &LyapunovSpec,
        monitor: &Monitor,
        max_pixels: u64,
    ) -> Result<Field> {
        self.integrate(ctx, spec, monitor, max_pixels, None)
    }

    /// The running FTLE of the first pixel of `spec`'s grid at every renormalisation (one
    /// dispatch and read-back per interval: meant for a 1x1 grid).
    pub fn convergence(
        &self,
        ctx: &GpuContext,
        spec: &LyapunovSpec,
        monitor: &Monitor,
    ) -> Result<Convergence> {
        let mut trace = Convergence::default();
        self.integrate(ctx, spec, monitor, 1, Some(&mut trace))?;
        Ok(trace)
    }

    fn integrate(
        &self,
        ctx: &GpuContext,
        spec: &LyapunovSpec,
        monitor: &Monitor,
        max_pixels: u64,
        mut trace: Option<&mut Convergence>,
    ) -> Result<Field> {
        let grid = spec.grid;
        let (init, advance) = self.pipelines.get(ctx, spec.params.losses.kinds(), false);
        let total_steps = spec.stepping.steps();
        let rows_needed = spec.rows_to_integrate();
        let tiling = Tiling::new(grid.width, rows_needed, max_pixels);
        let capacity = tiling.capacity();
        let params_buf = params_buffer(ctx);
        let states = storage_buffer(ctx, "states", capacity * 64);
        let log_sums = storage_buffer(ctx, "log sums", capacity * 4);
        let bind = bind_group(
            ctx,
            "lyapunov",
            &self.layout,
            &[&params_buf, &states, &log_sums],
        );
        let dispatch = |pipeline: &wgpu::ComputePipeline, params: &GpuParams| {
            ctx.queue
                .write_buffer(&params_buf, 0, bytemuck::bytes_of(params));
            dispatch_and_wait(ctx, pipeline, &bind, params.count)
        };

        let tiles = tiling.count();
        monitor.start("gpu", tiles as u64 * total_steps as u64);
        let mut field = Field::new(grid.width, grid.height, 0.0);
        let base = GpuParams {
            interval: spec.renorm_steps(),
            total_steps,
            twin_eps: match spec.method {
                Method::Twin { eps } => eps as f32,
                Method::Tangent => 0.0,
            },
            ..GpuParams::new(&spec.params, spec.stepping.dt).with_grid(&grid)
        };
        let t_end = total_steps as f64 * spec.stepping.dt;
        for (row0, rows) in tiling.tiles() {
            let pixels = rows * grid.width;
            let mut params = GpuParams {
                row0,
                rows,
                count: pixels,
                ..base
            };
            dispatch(init, &params)?;
            let mut step0 = 0;
            while step0 < total_steps {
                monitor.check()?;
                let steps = match trace {
                    Some(_) => params.interval.min(total_steps - step0),
                    None => (STEPS_PER_DISPATCH / STEP_COST / pixels as u64)
                        .clamp(1, (total_steps - step0) as u64) as u32,
                };
                params.step0 = step0;
                params.steps = steps;
                dispatch(advance, &params)?;
                step0 += steps;
                monitor.advance(steps as u64);
                if let Some(trace) = trace.as_deref_mut() {
                    let log_sum = read_f32s(ctx, &log_sums, 1)?[0];
                    let t = step0 as f64 * spec.stepping.dt;
                    trace.t.push(t);
                    trace.ftle.push(log_sum as f64 / t);
                }
            }
            let sums = read_f32s(ctx, &log_sums, pixels as u64)?;
            let start = row0 as usize * grid.width as usize;
            for (out, log_sum) in field.data[start..start + pixels as usize]
                .iter_mut()
                .zip(sums)
            {
                *out = (log_sum as f64 / t_end) as f32;
            }
        }
        field.mirror_below(rows_needed);
        monitor.finish();
        Ok(field)
    }
}

/// The Jacobian d(rate)/d(state) that the shader's dual numbers give at each of `states`
/// (row-major 4x4), for checking against the CPU's.
pub fn jacobians(ctx: &GpuContext, p: &Params, states: &[State]) -> Result<Vec<[[f64; 4]; 4]>> {
    let module = shader_module(ctx, "lyapunov.wgsl", LYAPUNOV_WGSL);
    let pipeline = compute_pipeline(
        ctx,
        &module,
        None,
        "jacobian_columns",
        p.losses.kinds(),
        &[],
    );
    let params = GpuParams {
        count: states.len() as u32,
        ..GpuParams::new(p, 0.01)
    };
    let params_buf = params_buffer(ctx);
    ctx.queue
        .write_buffer(&params_buf, 0, bytemuck::bytes_of(&params));
    let bytes = states.len() as u64 * 64;
    let buf = storage_buffer(ctx, "jacobians", bytes);
    // Each state in the first vec4 of its 4-vec4 block.
    let input: Vec<f32> = states
        .iter()
        .flat_map(|s| {
            let mut block = [0f32; 16];
            for (b, v) in block.iter_mut().zip(s.to_array()) {
                *b = v as f32;
            }
            block
        })
        .collect();
    ctx.queue
        .write_buffer(&buf, 0, bytemuck::cast_slice(&input));
    let layout = pipeline.get_bind_group_layout(0);
    let bind = bind_group(ctx, "jacobian_columns", &layout, &[&params_buf, &buf]);
    dispatch_and_wait(ctx, &pipeline, &bind, params.count)?;
    let floats = read_f32s(ctx, &buf, bytes / 4)?;
    // Column j of state i is floats[16 i + 4 j ..][..4].
    Ok(floats
        .chunks_exact(16)
        .map(|m| std::array::from_fn(|r| std::array::from_fn(|c| m[4 * c + r] as f64)))
        .collect())
}
