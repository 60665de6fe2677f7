//! Drives `shaders/lyapunov.wgsl`: divergence maps inside the tiled loop of `tiled.rs`, every
//! pixel integrating the whole run; and single-start convergence runs.

use super::context::{GpuContext, read_buffer, read_f32s};
use super::layout::{
    GpuLyapunovSlot, GpuParams, Real, Run, RunParams, TileParams, read_reals, with_real,
};
use super::pipeline::{
    MapBuffers, Variants, bind_group, dispatch_and_wait, kernel_module, layouts, params_buffer,
    storage_buffer,
};
use super::shaders::Kernel;
use super::tiled::{TileWork, Tiling, catch_up, map_tiles, max_pixels, time_loop};
use crate::error::Result;
use crate::field::{Convergence, Field};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::{LyapunovSpec, Method, Precision};

/// A tangent step costs about this many plain steps (BENCH.md), so dispatches hold fewer.
pub const STEP_COST: u64 = 3;

const SLOT_BYTES: u64 = std::mem::size_of::<GpuLyapunovSlot>() as u64;

pub struct LyapunovKernel {
    precision: Precision,
    /// (init, advance) of the method per kind of loss.
    pipelines: Variants,
    /// The tangent method's (init, advance) with DP54 steps, compiled on first use.
    adaptive: Option<Variants>,
    layout: wgpu::BindGroupLayout,
}

/// A run that stalled leaves this log sum (shaders/lyapunov.wgsl STALLED_LOG_SUM, -3e38):
/// anything below it is read as NaN.
pub const STALLED_BELOW: f64 = -1e38;

/// Bytes per pixel of the slot and the log sum, and of the params, in `precision`.
fn sizes(precision: Precision) -> (u64, u64, u64) {
    use std::mem::size_of;
    with_real!(precision, R => (
        size_of::<<R as Real>::LyapunovSlot>() as u64,
        size_of::<R>() as u64,
        size_of::<<R as Real>::Params>() as u64,
    ))
}

impl LyapunovKernel {
    /// Compiles the entry points of `method` only (lavapipe compiles each pipeline anew).
    pub fn new(ctx: &GpuContext, method: Method) -> Self {
        Self::with_precision(ctx, method, Precision::F32)
    }

    /// The kernel of `method` in `precision` (f64 needs a context with f64).
    pub fn with_precision(ctx: &GpuContext, method: Method, precision: Precision) -> Self {
        let module = kernel_module(ctx, Kernel::Lyapunov, precision);
        let (layout, pipeline_layout) = layouts(ctx, "lyapunov", &[false, false]);
        let entries: &'static [&'static str] = match method {
            Method::Tangent => &["tangent_init", "tangent_advance"],
            Method::Twin { .. } => &["twin_init", "twin_advance"],
        };
        let adaptive = (method == Method::Tangent).then(|| {
            Variants::new(
                module.clone(),
                pipeline_layout.clone(),
                &["tangent_init", "tangent_adaptive"],
                None,
            )
        });
        let kernel = LyapunovKernel {
            precision,
            pipelines: Variants::new(module, pipeline_layout, entries, None),
            adaptive,
            layout,
        };
        kernel.pipelines.get(ctx, 0, false, false);
        kernel
    }

    /// The FTLE map of `spec` (1/s at t-max).
    pub fn run(&self, ctx: &GpuContext, spec: &LyapunovSpec, monitor: &Monitor) -> Result<Field> {
        let (slot, sum, _) = sizes(self.precision);
        let max = max_pixels(ctx, slot, slot + sum);
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
        trace: Option<&mut Convergence>,
    ) -> Result<Field> {
        with_real!(self.precision, R => self.integrate_in::<R>(ctx, spec, monitor, max_pixels, trace))
    }

    /// The tiled loop in the kernel's scalar `R`.
    fn integrate_in<R: Real>(
        &self,
        ctx: &GpuContext,
        spec: &LyapunovSpec,
        monitor: &Monitor,
        max_pixels: u64,
        mut trace: Option<&mut Convergence>,
    ) -> Result<Field> {
        let (rtol, atol) = spec.integrator.tolerances().unwrap_or_default();
        let base = R::Params::of(&spec.params, spec.stepping.dt)
            .over(&spec.grid, &spec.params)
            .with_run(Run {
                interval: spec.renorm_steps(),
                total_steps: spec.stepping.steps(),
                setting: match spec.method {
                    Method::Twin { eps } => eps,
                    Method::Tangent => 0.0,
                },
                rtol,
                atol,
                ..Run::default()
            });
        let sums = read_reals::<R>;
        let grid = spec.grid;
        let adaptive = spec.integrator.tolerances().is_some();
        let variants = match (&self.adaptive, adaptive) {
            (Some(adaptive), true) => adaptive,
            (None, true) => {
                return Err(crate::Error::invalid(
                    "integrator",
                    "adaptive steps need the tangent method",
                ));
            }
            (_, false) => &self.pipelines,
        };
        let [init, advance] = variants.map_pair(ctx, &spec.params, &spec.grid, false);
        let total_steps = spec.stepping.steps();
        let interval = spec.renorm_steps();
        // The adaptive kernel's dispatches count renormalisation windows, each about
        // `interval` steps of DP54's six rates.
        let (units, unit_cost) = match adaptive {
            true => (
                total_steps.div_ceil(interval),
                STEP_COST * 2 * interval as u64,
            ),
            false => (total_steps, STEP_COST),
        };
        let tiling = Tiling::new(grid.width, spec.row_span(), max_pixels);
        let capacity = tiling.capacity();
        let (slot, sum_bytes, params_bytes) = sizes(self.precision);
        let MapBuffers {
            params: params_buf,
            slots: states,
            values: log_sums,
            bind,
        } = MapBuffers::new(
            ctx,
            "lyapunov",
            &self.layout,
            params_bytes,
            capacity,
            (slot, sum_bytes),
        );
        let dispatch = |pipeline: &wgpu::ComputePipeline, params: &dyn TileParamsBytes| {
            ctx.queue.write_buffer(&params_buf, 0, params.bytes());
            dispatch_and_wait(ctx, pipeline, &bind, params.active())
        };
        let t_end = total_steps as f64 * spec.stepping.dt;
        // A convergence run reads the log sum back after every renormalisation.
        let max_steps = trace
            .is_some()
            .then_some(if adaptive { 1 } else { interval });
        map_tiles(&grid, &tiling, total_steps, monitor, |row0, rows, later| {
            let pixels = rows * grid.width;
            let mut params = base;
            params.set_tile(row0, rows, pixels);
            dispatch(init, &params)?;
            let work = TileWork {
                max_steps,
                ..TileWork::new(units, pixels, unit_cost, later)
            };
            // The adaptive tangent's pixels keep their own place (shaders/lyapunov.wgsl): its
            // clock, the last vec4 of the slot's four.
            let clocks = || -> Result<Vec<[f64; 4]>> {
                let all = sums(&read_buffer(ctx, &states, pixels as u64 * slot)?);
                Ok(all
                    .chunks_exact(16)
                    .map(|s| [s[12], s[13], s[14], s[15]])
                    .collect())
            };
            time_loop(work, monitor, |step0, steps, active| {
                params.set_steps(step0, steps, pixels);
                dispatch(advance, &params)?;
                // A convergence run reads every window's sum: its pixel there first.
                if adaptive && (trace.is_some() || step0 + steps == units) {
                    catch_up(step0 + steps, monitor, clocks, || {
                        dispatch(advance, &params)
                    })?;
                }
                if let Some(trace) = trace.as_deref_mut() {
                    let log_sum = sums(&read_buffer(ctx, &log_sums, sum_bytes)?)[0];
                    let done = match adaptive {
                        true => ((step0 + steps) * interval).min(total_steps),
                        false => step0 + steps,
                    };
                    let t = done as f64 * spec.stepping.dt;
                    trace.t.push(t);
                    trace.ftle.push(match log_sum < STALLED_BELOW {
                        true => f64::NAN,
                        false => log_sum / t,
                    });
                }
                Ok(active)
            })?;
            let all = sums(&read_buffer(ctx, &log_sums, pixels as u64 * sum_bytes)?);
            Ok(all
                .into_iter()
                .map(|log_sum| match log_sum < STALLED_BELOW {
                    true => f32::NAN,
                    false => (log_sum / t_end) as f32,
                })
                .collect())
        })
    }
}

/// Params as the bytes a dispatch writes, and how many invocations it runs.
trait TileParamsBytes {
    fn bytes(&self) -> &[u8];
    fn active(&self) -> u32;
}

impl<T: TileParams> TileParamsBytes for T {
    fn bytes(&self) -> &[u8] {
        bytemuck::bytes_of(self)
    }
    fn active(&self) -> u32 {
        self.count()
    }
}

/// The shader's dual-number Jacobians d(rate)/d(state), for checking against the CPU's.
pub struct JacobianKernel {
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl JacobianKernel {
    pub fn new(ctx: &GpuContext) -> Self {
        let module = kernel_module(ctx, Kernel::Lyapunov, Precision::F32);
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
        let [pipeline] = self.pipelines.get(ctx, p.losses.kinds(), false, false) else {
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
            .map(|s| GpuLyapunovSlot {
                y: s.to_array().map(|v| v as f32),
                ..Default::default()
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
