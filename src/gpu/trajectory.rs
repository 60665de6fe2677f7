//! Drives `shaders/trajectory.wgsl`: ensembles of pendulums, one invocation each, keeping
//! every `stride`-th state.

use super::context::{GpuContext, read_buffer};
use super::layout::{GpuParams, GpuParams64, TRAJECTORY_WGSL, shader_source, shader_source_f64};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, layouts, module_of, params_buffer_of, storage_buffer,
};
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
        let source = match precision {
            Precision::F32 => shader_source(TRAJECTORY_WGSL),
            Precision::F64 => shader_source_f64(TRAJECTORY_WGSL),
        };
        let module = module_of(ctx, "trajectory.wgsl", source);
        let (layout, pipeline_layout) = layouts(ctx, "trajectory", &[false]);
        TrajectoryKernel {
            precision,
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
        // A state is four floats of the kernel's precision.
        let state_bytes = match self.precision {
            Precision::F32 => 16,
            Precision::F64 => 32,
        };
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
        let [pipeline] = self.pipelines.get(ctx, p.losses.kinds(), false) else {
            unreachable!("one entry point")
        };
        let count = starts.len() as u32;
        let params: Vec<u8> = match self.precision {
            Precision::F32 => bytemuck::bytes_of(&GpuParams {
                steps,
                interval: stride,
                count,
                ..GpuParams::new(p, dt)
            })
            .to_vec(),
            Precision::F64 => bytemuck::bytes_of(&GpuParams64 {
                steps,
                interval: stride,
                count,
                ..GpuParams64::new(p, dt)
            })
            .to_vec(),
        };
        let params_buf = params_buffer_of(ctx, params.len() as u64);
        ctx.queue.write_buffer(&params_buf, 0, &params);
        let states = storage_buffer(ctx, "trajectory states", bytes);
        for (i, s) in starts.iter().enumerate() {
            let at = i as u64 * per_run * state_bytes;
            match self.precision {
                Precision::F32 => {
                    let v = s.to_array().map(|v| v as f32);
                    ctx.queue
                        .write_buffer(&states, at, bytemuck::cast_slice(&v));
                }
                Precision::F64 => {
                    let v = s.to_array();
                    ctx.queue
                        .write_buffer(&states, at, bytemuck::cast_slice(&v));
                }
            }
        }
        let bind = bind_group(ctx, "trajectory", &self.layout, &[&params_buf, &states]);
        dispatch_and_wait(ctx, pipeline, &bind, count)?;
        let raw = read_buffer(ctx, &states, bytes)?;
        let values: Vec<f64> = match self.precision {
            Precision::F32 => bytemuck::pod_collect_to_vec::<u8, f32>(&raw)
                .into_iter()
                .map(f64::from)
                .collect(),
            Precision::F64 => bytemuck::pod_collect_to_vec::<u8, f64>(&raw),
        };
        let all: Vec<State> = values
            .chunks_exact(4)
            .map(|v| State::from_array(std::array::from_fn(|i| v[i])))
            .collect();
        Ok(all.chunks(per_run as usize).map(|c| c.to_vec()).collect())
    }
}
