//! Drives `shaders/trajectory.wgsl`: ensembles of pendulums, one invocation each, keeping
//! every `stride`-th state.

use super::context::{GpuContext, read_buffer};
use super::layout::{Real, Run, RunParams, read_reals, with_real};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, kernel_module, layouts, params_buffer_of,
    storage_buffer,
};
use super::shaders::Kernel;
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::spec::Precision;

pub struct TrajectoryKernel {
    precision: Precision,
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl TrajectoryKernel {
    /// The f32 kernel.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_precision(ctx, Precision::F32)
    }

    /// The kernel in `precision` (f64 needs a context with `GpuContext::has_f64`).
    pub fn with_precision(ctx: &GpuContext, precision: Precision) -> Self {
        let module = kernel_module(ctx, Kernel::Trajectory, precision);
        let (layout, pipeline_layout) = layouts(ctx, "trajectory", &[false]);
        TrajectoryKernel {
            precision,
            pipelines: Variants::new(module, pipeline_layout, &["trajectory"], None),
            layout,
        }
    }

    /// One run per start, integrated over `steps` steps of `dt` in the kernel's precision,
    /// keeping the start and every `stride`-th state (`steps` a multiple of `stride`).
    pub fn run(
        &self,
        ctx: &GpuContext,
        p: &Params,
        starts: &[State],
        dt: f64,
        steps: u32,
        stride: u32,
    ) -> Result<Vec<Vec<State>>> {
        with_real!(self.precision, R => self.run_in::<R>(ctx, p, starts, dt, steps, stride))
    }

    fn run_in<R: Real>(
        &self,
        ctx: &GpuContext,
        p: &Params,
        starts: &[State],
        dt: f64,
        steps: u32,
        stride: u32,
    ) -> Result<Vec<Vec<State>>> {
        assert!(
            stride >= 1 && steps.is_multiple_of(stride),
            "steps a multiple of the stride"
        );
        let per_run = (steps / stride) as u64 + 1;
        // A state is four floats of the kernel's precision.
        let state_bytes = 4 * std::mem::size_of::<R>() as u64;
        let bytes = starts.len() as u64 * per_run * state_bytes;
        if bytes > ctx.max_binding() {
            return Err(Error::invalid(
                "t_max",
                format!(
                    "{} runs of {steps} steps do not fit one GPU buffer; use the CPU backend, fewer runs or a shorter run",
                    starts.len()
                ),
            ));
        }
        let [pipeline] = self.pipelines.get(ctx, p.losses.kinds(), false, false) else {
            unreachable!("one entry point")
        };
        let count = starts.len() as u32;
        let params = R::Params::of(p, dt).with_run(Run {
            steps,
            interval: stride,
            count,
            ..Run::default()
        });
        let params = bytemuck::bytes_of(&params);
        let params_buf = params_buffer_of(ctx, params.len() as u64);
        ctx.queue.write_buffer(&params_buf, 0, params);
        let states = storage_buffer(ctx, "trajectory states", bytes);
        for (i, s) in starts.iter().enumerate() {
            let at = i as u64 * per_run * state_bytes;
            let v = s.to_array().map(R::from_f64);
            ctx.queue
                .write_buffer(&states, at, bytemuck::cast_slice(&v));
        }
        let bind = bind_group(ctx, "trajectory", &self.layout, &[&params_buf, &states]);
        dispatch_and_wait(ctx, pipeline, &bind, count)?;
        let values = read_reals::<R>(&read_buffer(ctx, &states, bytes)?);
        let all: Vec<State> = values
            .chunks_exact(4)
            .map(|v| State::from_array(std::array::from_fn(|i| v[i])))
            .collect();
        Ok(all.chunks(per_run as usize).map(|c| c.to_vec()).collect())
    }
}
