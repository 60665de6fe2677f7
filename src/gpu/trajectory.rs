//! Drives `shaders/trajectory.wgsl`: one pendulum, every state kept.

use super::context::{GpuContext, read_f32s};
use super::layout::{GpuParams, TRAJECTORY_WGSL};
use super::pipeline::{
    bind_group, compute_pipeline, dispatch_and_wait, params_buffer, shader_module, storage_buffer,
};
use crate::error::{Error, Result};
use crate::model::{Params, State};

/// States at t = 0, dt, ... steps * dt, integrated in f32 on the GPU.
pub fn trajectory(
    ctx: &GpuContext,
    p: &Params,
    start: State,
    dt: f64,
    steps: u32,
) -> Result<Vec<State>> {
    Ok(trajectories(ctx, p, &[start], dt, steps)?.remove(0))
}

/// One trajectory per start, one GPU invocation each (an ensemble of pendulums).
pub fn trajectories(
    ctx: &GpuContext,
    p: &Params,
    starts: &[State],
    dt: f64,
    steps: u32,
) -> Result<Vec<Vec<State>>> {
    strided_trajectories(ctx, p, starts, dt, steps, 1)
}

/// As `trajectories`, keeping every `stride`-th state (steps must be a multiple of it).
pub fn strided_trajectories(
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
    let bytes = starts.len() as u64 * per_run * 16;
    if bytes > ctx.max_binding() {
        return Err(Error::invalid(
            "--t-max",
            format!(
                "{} runs of {steps} steps do not fit one GPU buffer; use --backend cpu, fewer runs or fewer steps",
                starts.len()
            ),
        ));
    }
    let module = shader_module(ctx, "trajectory.wgsl", TRAJECTORY_WGSL);
    let pipeline = compute_pipeline(ctx, &module, None, "trajectory", p.losses.kinds(), &[]);
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
        ctx.queue
            .write_buffer(&states, i as u64 * per_run * 16, bytemuck::cast_slice(&v));
    }
    let layout = pipeline.get_bind_group_layout(0);
    let bind = bind_group(ctx, "trajectory", &layout, &[&params_buf, &states]);
    dispatch_and_wait(ctx, &pipeline, &bind, starts.len() as u32)?;
    let all: Vec<State> = read_f32s(ctx, &states, bytes / 4)?
        .chunks_exact(4)
        .map(|v| State::from_array(std::array::from_fn(|i| v[i] as f64)))
        .collect();
    Ok(all.chunks(per_run as usize).map(|c| c.to_vec()).collect())
}
