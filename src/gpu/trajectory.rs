//! Drives `shaders/trajectory.wgsl`: ensembles of pendulums, one invocation each, keeping
//! every `stride`-th state.

use super::context::{GpuContext, read_f32s};
use super::layout::{GpuParams, TRAJECTORY_WGSL};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, layouts, params_buffer, shader_module, storage_buffer,
};
use crate::error::{Error, Result};
use crate::model::{Params, State};

const STATE_BYTES: u64 = std::mem::size_of::<[f32; 4]>() as u64;

pub struct TrajectoryKernel {
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl TrajectoryKernel {
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(ctx, "trajectory.wgsl", TRAJECTORY_WGSL);
        let (layout, pipeline_layout) = layouts(ctx, "trajectory", &[false]);
        TrajectoryKernel {
            pipelines: Variants::new(module, pipeline_layout, &["trajectory"], None),
            layout,
        }
    }

    /// One run per start, integrated in f32 over `steps` steps of `dt`, keeping the start
    /// and every `stride`-th state (steps must be a multiple of it).
    pub fn run(
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
        let bytes = starts.len() as u64 * per_run * STATE_BYTES;
        if bytes > ctx.max_binding() {
            return Err(Error::invalid(
                "t_max",
                format!(
                    "{} runs of {steps} steps do not fit one GPU buffer; use the CPU backend, fewer runs or a shorter run",
                    starts.len()
                ),
            ));
        }
        let [pipeline] = self.pipelines.get(ctx, p.losses.kinds(), false) else {
            unreachable!("one entry point")
        };
        let params = GpuParams {
            steps,
            interval: stride,
            count: starts.len() as u32,
            ..GpuParams::new(p, dt)
        };
        let params_buf = params_buffer(ctx);
        ctx.queue
            .write_buffer(&params_buf, 0, bytemuck::bytes_of(&params));
        let states = storage_buffer(ctx, "trajectory states", bytes);
        for (i, s) in starts.iter().enumerate() {
            let v = s.to_array().map(|v| v as f32);
            ctx.queue.write_buffer(
                &states,
                i as u64 * per_run * STATE_BYTES,
                bytemuck::cast_slice(&v),
            );
        }
        let bind = bind_group(ctx, "trajectory", &self.layout, &[&params_buf, &states]);
        dispatch_and_wait(ctx, pipeline, &bind, starts.len() as u32)?;
        let all: Vec<State> = read_f32s(ctx, &states, bytes / 4)?
            .chunks_exact(4)
            .map(|v| State::from_array(std::array::from_fn(|i| v[i] as f64)))
            .collect();
        Ok(all.chunks(per_run as usize).map(|c| c.to_vec()).collect())
    }
}
