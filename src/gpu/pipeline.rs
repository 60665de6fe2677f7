//! The wgpu boilerplate every kernel shares: modules, pipelines, bindings, one dispatch.

use super::context::GpuContext;
use super::layout::{MAX_WORKGROUPS, WORKGROUP_SIZE};
use super::shaders::{Kernel, source};
use crate::error::Result;
use crate::spec::Precision;

/// The module of `kernel` in `precision`.
pub fn kernel_module(ctx: &GpuContext, kernel: Kernel, precision: Precision) -> wgpu::ShaderModule {
    module_of(ctx, kernel.name(), source(kernel, precision))
}

/// A module of a full WGSL source (`shaders::source`).
pub fn module_of(ctx: &GpuContext, label: &str, source: String) -> wgpu::ShaderModule {
    ctx.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        })
}

/// A compute pipeline for `entry`; `layout` None derives the layout from the shader.
/// `losses` sets the shaders' `override LOSSES` (bits: joint damping, drag, bearings, see
/// `Losses::kinds`): the driver then compiles each kind of loss in or out entirely (a
/// runtime branch on a uniform cost lavapipe 2x even when off). `switches` sets further
/// boolean overrides of the shader.
pub fn compute_pipeline(
    ctx: &GpuContext,
    module: &wgpu::ShaderModule,
    layout: Option<&wgpu::PipelineLayout>,
    entry: &str,
    losses: u32,
    switches: &[(&str, bool)],
) -> wgpu::ComputePipeline {
    let mut constants = vec![("LOSSES", losses as f64)];
    constants.extend(switches.iter().map(|&(name, on)| (name, on as u8 as f64)));
    ctx.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout,
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            },
            cache: None,
        })
}

/// The pipelines of a kernel's entry points (setup, advance, ...), compiled on first use for
/// each `LOSSES` value, each value of the kernel's boolean `switch` override if it has one, and
/// with `PER_PIXEL` (shaders/common.wgsl: a plane with a parameter along an axis) on or off.
pub struct Variants {
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    entries: Vec<&'static str>,
    switch: Option<&'static str>,
    compiled: [std::sync::OnceLock<Vec<wgpu::ComputePipeline>>; 32],
}

impl Variants {
    pub fn new(
        module: wgpu::ShaderModule,
        layout: wgpu::PipelineLayout,
        entries: &[&'static str],
        switch: Option<&'static str>,
    ) -> Self {
        Variants {
            module,
            layout,
            entries: entries.to_vec(),
            switch,
            compiled: Default::default(),
        }
    }

    /// The pipelines of the entry points, in order, for `losses` (see `Losses::kinds`) with
    /// the switch `on` (ignored by kernels without one), for a grid whose pixels have their
    /// own parameters if `per_pixel`.
    pub fn get(
        &self,
        ctx: &GpuContext,
        losses: u32,
        on: bool,
        per_pixel: bool,
    ) -> &[wgpu::ComputePipeline] {
        let on = on && self.switch.is_some();
        let slot = (losses as usize & 7) | (on as usize) << 3 | (per_pixel as usize) << 4;
        self.compiled[slot].get_or_init(|| {
            let mut switches: Vec<(&str, bool)> =
                self.switch.map(|name| (name, on)).into_iter().collect();
            // Only set when on: kernels without a plane (trajectories) have no such override.
            if per_pixel {
                switches.push(("PER_PIXEL", true));
            }
            self.entries
                .iter()
                .map(|entry| {
                    compute_pipeline(
                        ctx,
                        &self.module,
                        Some(&self.layout),
                        entry,
                        losses,
                        &switches,
                    )
                })
                .collect()
        })
    }
}

impl Variants {
    /// The (setup, advance) pipelines of a map of `params` over `grid` (its losses, whether
    /// its pixels have their own parameters) with the switch `on`.
    pub fn map_pair(
        &self,
        ctx: &GpuContext,
        params: &crate::model::Params,
        grid: &crate::spec::Grid,
        on: bool,
    ) -> [&wgpu::ComputePipeline; 2] {
        match self.get(ctx, params.losses.kinds(), on, grid.varies_params()) {
            [init, advance] => [init, advance],
            _ => unreachable!("a map's kernel has two entry points"),
        }
    }
}

/// A map kernel's buffers for a tile of pixels, bound in the kernel's order: its params, each
/// pixel's slot and each pixel's value.
pub struct MapBuffers {
    pub params: wgpu::Buffer,
    pub slots: wgpu::Buffer,
    pub values: wgpu::Buffer,
    pub bind: wgpu::BindGroup,
}

impl MapBuffers {
    /// For `capacity` pixels of `slot` and `value` bytes each, params of `params_bytes`.
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        params_bytes: u64,
        capacity: u64,
        (slot, value): (u64, u64),
    ) -> Self {
        let params = params_buffer_of(ctx, params_bytes);
        let slots = storage_buffer(ctx, &format!("{label} slots"), capacity * slot);
        let values = storage_buffer(ctx, &format!("{label} values"), capacity * value);
        let bind = bind_group(ctx, label, layout, &[&params, &slots, &values]);
        MapBuffers {
            params,
            slots,
            values,
            bind,
        }
    }
}

/// A bind group layout of one uniform (binding 0) and storage buffers (1, 2, ...), each
/// read-only or not, and the pipeline layout holding it.
pub fn layouts(
    ctx: &GpuContext,
    label: &str,
    storage_read_only: &[bool],
) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout) {
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![entry(0, wgpu::BufferBindingType::Uniform)];
    for (i, &read_only) in storage_read_only.iter().enumerate() {
        entries.push(entry(
            i as u32 + 1,
            wgpu::BufferBindingType::Storage { read_only },
        ));
    }
    let group = ctx
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &entries,
        });
    let pipeline = ctx
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&group)],
            immediate_size: 0,
        });
    (group, pipeline)
}

/// A bind group of whole buffers at bindings 0, 1, 2, ...
pub fn bind_group(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A storage buffer that can be copied to and from.
pub fn storage_buffer(ctx: &GpuContext, label: &str, bytes: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A uniform buffer for the kernels' `Params`.
pub fn params_buffer(ctx: &GpuContext) -> wgpu::Buffer {
    params_buffer_of(ctx, std::mem::size_of::<super::layout::GpuParams>() as u64)
}

/// A uniform buffer of `bytes` for a kernel's params (f64 kernels' are larger).
pub fn params_buffer_of(ctx: &GpuContext, bytes: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("params"),
        // Uniform buffers come in multiples of 16 bytes.
        size: bytes.next_multiple_of(16),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Workgroup counts (x, y) covering `invocations`, within [`MAX_WORKGROUPS`] along x.
pub fn workgroups(invocations: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(WORKGROUP_SIZE).max(1);
    let x = groups.min(MAX_WORKGROUPS);
    (x, groups.div_ceil(x))
}

/// Records one dispatch of `invocations` invocations of `pipeline` into `encoder`.
pub fn record_dispatch(
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    invocations: u32,
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: None,
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    let (x, y) = workgroups(invocations);
    pass.dispatch_workgroups(x, y, 1);
}

/// Submits one dispatch and waits for it.
pub fn dispatch_and_wait(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    invocations: u32,
) -> Result<()> {
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    record_dispatch(&mut encoder, pipeline, bind_group, invocations);
    ctx.queue.submit([encoder.finish()]);
    ctx.wait()
}
