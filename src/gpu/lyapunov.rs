//! Drives `shaders/lyapunov.wgsl`: divergence maps inside the tiled loop of `tiled.rs`, every
//! pixel integrating the whole run; and single-start convergence runs.

use super::context::{GpuContext, read_f32s};
use super::layout::{GpuLyapunovSlot, GpuParams, LYAPUNOV_BYTES_PER_PIXEL, LYAPUNOV_WGSL};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, layouts, params_buffer, shader_module, storage_buffer,
};
use super::tiled::{Tiling, map_tiles, max_pixels, time_loop};
use crate::error::Result;
use crate::field::{Convergence, Field};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{LyapunovSpec, Method};

/// A tangent step costs about this many plain steps (BENCH.md), so dispatches hold fewer.
const STEP_COST: u64 = 3;

const SLOT_BYTES: u64 = std::mem::size_of::<GpuLyapunovSlot>() as u64;

pub struct LyapunovKernel {
    /// (init, advance) of the method per kind of loss.
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl LyapunovKernel {
    /// Compiles the entry points of `method` only (lavapipe compiles each pipeline anew).
    pub fn new(ctx: &GpuContext, method: Method) -> Self {
        let module = shader_module(ctx, "lyapunov.wgsl", LYAPUNOV_WGSL);
        let (layout, pipeline_layout) = layouts(ctx, "lyapunov", &[false, false]);
        let entries: &'static [&'static str] = match method {
            Method::Tangent => &["tangent_init", "tangent_advance"],
            Method::Twin { .. } => &["twin_init", "twin_advance"],
        };
        let kernel = LyapunovKernel {
            pipelines: Variants::new(module, pipeline_layout, entries, None),
            layout,
        };
        kernel.pipelines.get(ctx, 0, false);
        kernel
    }

    /// The FTLE map of `spec` (1/s at t-max).
    pub fn run(&self, ctx: &GpuContext, spec: &LyapunovSpec, monitor: &Monitor) -> Result<Field> {
        let max = max_pixels(ctx, SLOT_BYTES, LYAPUNOV_BYTES_PER_PIXEL);
        self.run_tiled(ctx, spec, monitor, max)
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
        let [init, advance] = self.pipelines.get(ctx, spec.params.losses.kinds(), false) else {
            unreachable!("two entry points")
        };
        let total_steps = spec.stepping.steps();
        let tiling = Tiling::new(grid.width, spec.rows_to_integrate(), max_pixels);
        let capacity = tiling.capacity();
        let params_buf = params_buffer(ctx);
        let states = storage_buffer(ctx, "states", capacity * SLOT_BYTES);
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
        // A convergence run reads the log sum back after every renormalisation.
        let max_steps = trace.is_some().then_some(base.interval);
        map_tiles(&grid, &tiling, total_steps, monitor, |row0, rows, later| {
            let pixels = rows * grid.width;
            let mut params = GpuParams {
                row0,
                rows,
                count: pixels,
                ..base
            };
            dispatch(init, &params)?;
            time_loop(
                total_steps,
                pixels,
                pixels,
                STEP_COST,
                max_steps,
                later,
                monitor,
                |step0, steps, active| {
                    params.step0 = step0;
                    params.steps = steps;
                    dispatch(advance, &params)?;
                    if let Some(trace) = trace.as_deref_mut() {
                        let log_sum = read_f32s(ctx, &log_sums, 1)?[0];
                        let t = (step0 + steps) as f64 * spec.stepping.dt;
                        trace.t.push(t);
                        trace.ftle.push(log_sum as f64 / t);
                    }
                    Ok(active)
                },
            )?;
            let sums = read_f32s(ctx, &log_sums, pixels as u64)?;
            Ok(sums
                .into_iter()
                .map(|log_sum| (log_sum as f64 / t_end) as f32)
                .collect())
        })
    }
}

/// The shader's dual-number Jacobians d(rate)/d(state), for checking against the CPU's.
pub struct JacobianKernel {
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl JacobianKernel {
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(ctx, "lyapunov.wgsl", LYAPUNOV_WGSL);
        let (layout, pipeline_layout) = layouts(ctx, "jacobian", &[false, false]);
        JacobianKernel {
            pipelines: Variants::new(module, pipeline_layout, &["jacobian_columns"], None),
            layout,
        }
    }

    /// The Jacobian at each of `states` (row-major 4x4).
    pub fn run(
        &self,
        ctx: &GpuContext,
        p: &Params,
        states: &[State],
    ) -> Result<Vec<[[f64; 4]; 4]>> {
        let [pipeline] = self.pipelines.get(ctx, p.losses.kinds(), false) else {
            unreachable!("one entry point")
        };
        let params = GpuParams {
            count: states.len() as u32,
            ..GpuParams::new(p, 0.01)
        };
        let params_buf = params_buffer(ctx);
        ctx.queue
            .write_buffer(&params_buf, 0, bytemuck::bytes_of(&params));
        // Each state in the first vec4 of its slot; the columns come back in the slot.
        let slots: Vec<GpuLyapunovSlot> = states
            .iter()
            .map(|s| {
                let mut slot = GpuLyapunovSlot::default();
                slot.a.y = s.to_array().map(|v| v as f32);
                slot
            })
            .collect();
        let bytes = states.len() as u64 * SLOT_BYTES;
        let buf = storage_buffer(ctx, "jacobians", bytes);
        ctx.queue
            .write_buffer(&buf, 0, bytemuck::cast_slice(&slots));
        let unused = storage_buffer(ctx, "unused", 4);
        let bind = bind_group(
            ctx,
            "jacobian_columns",
            &self.layout,
            &[&params_buf, &buf, &unused],
        );
        dispatch_and_wait(ctx, pipeline, &bind, params.count)?;
        let floats = read_f32s(ctx, &buf, bytes / 4)?;
        // Column j of state i is floats[16 i + 4 j ..][..4].
        Ok(floats
            .chunks_exact(16)
            .map(|m| std::array::from_fn(|r| std::array::from_fn(|c| m[4 * c + r] as f64)))
            .collect())
    }
}
