//! Drives `shaders/trajectory.wgsl`: one pendulum, every state kept.

use wgpu::util::DeviceExt;

use super::context::{GpuContext, read_buffer};
use super::layout::{GpuParams, TRAJECTORY_WGSL, shader_source};
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
    let bytes = (steps as u64 + 1) * 16;
    if bytes > ctx.max_binding() {
        return Err(Error::invalid(
            "--t-max",
            format!("{steps} steps do not fit one GPU buffer; use --backend cpu or fewer steps"),
        ));
    }
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("trajectory.wgsl"),
        source: wgpu::ShaderSource::Wgsl(shader_source(TRAJECTORY_WGSL).into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("trajectory"),
        layout: None,
        module: &module,
        entry_point: Some("trajectory"),
        compilation_options: Default::default(),
        cache: None,
    });
    let params = GpuParams {
        steps,
        ..GpuParams::new(p, dt)
    };
    let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("params"),
        contents: bytemuck::bytes_of(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let states = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("trajectory states"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let s = start.to_array().map(|v| v as f32);
    ctx.queue.write_buffer(&states, 0, bytemuck::cast_slice(&s));
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("trajectory"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: states.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("trajectory"),
    });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("trajectory"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let out = read_buffer(ctx, &states, bytes)?;
    Ok(out
        .chunks_exact(16)
        .map(|c| {
            let v: [f32; 4] = std::array::from_fn(|i| {
                f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().expect("4 bytes"))
            });
            State::from_array(v.map(f64::from))
        })
        .collect())
}
