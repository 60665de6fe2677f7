//! Drives `shaders/trajectory.wgsl`: ensembles of pendulums, one invocation each, keeping
//! every `stride`-th state, each with the same parameters or its own joint damping.

use super::context::{GpuContext, read_buffer_with};
use super::layout::{Real, Run, RunParams, TileParams, mass_scale, with_real};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, kernel_module, layouts, params_buffer_of,
    storage_buffer,
};
use super::shaders::Kernel;
use super::tiled::STEPS_PER_INVOCATION;
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::spec::{EnsembleSpec, Precision};

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
        let (layout, pipeline_layout) = layouts(ctx, "trajectory", &[false, true, false]);
        TrajectoryKernel {
            precision,
            pipelines: Variants::new(module, pipeline_layout, &["trajectory"], None),
            layout,
        }
    }

    /// The runs of `spec` (which keeps every n-th state) integrated in the kernel's
    /// precision, each run's start and kept states converted where they are read back.
    pub fn run(&self, ctx: &GpuContext, spec: &EnsembleSpec) -> Result<Vec<Vec<State>>> {
        with_real!(self.precision, R => self.run_in::<R>(ctx, spec))
    }

    fn run_in<R: Real>(&self, ctx: &GpuContext, spec: &EnsembleSpec) -> Result<Vec<Vec<State>>> {
        let (p, starts, damping, dt, steps) =
            (&spec.params, spec.starts, spec.damping, spec.dt, spec.steps);
        let stride = spec.stride();
        if let Some(d) = damping {
            assert_eq!(d.len(), starts.len(), "one damping pair per start");
        }
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
        let pipeline = damped_pipeline(&self.pipelines, ctx, p, damping.is_some());
        let count = starts.len() as u32;
        let mut params = R::Params::of(p, dt).with_run(Run {
            interval: stride,
            count,
            total_steps: steps,
            ..Run::default()
        });
        let params_buf = params_buffer_of(ctx, std::mem::size_of_val(&params) as u64);
        let states = starts_buffer::<R>(ctx, "trajectory states", starts, per_run as usize, bytes)?;
        let damping_buf = damping_buffer::<R>(ctx, p, damping);
        let carried = pendulums_buffer::<R>(ctx, "trajectory carried", starts);
        let bind = bind_group(
            ctx,
            "trajectory",
            &self.layout,
            &[&params_buf, &states, &damping_buf, &carried],
        );
        // Spans of steps within lavapipe's loop limit (the engine keeps a chunk's runs within
        // a dispatch's pendulum-steps).
        for step0 in (0..steps).step_by(STEPS_PER_INVOCATION as usize) {
            params.set_steps(step0, STEPS_PER_INVOCATION.min(steps - step0), count);
            ctx.queue
                .write_buffer(&params_buf, 0, bytemuck::bytes_of(&params));
            dispatch_and_wait(ctx, pipeline, &bind, count)?;
        }
        let per_run = per_run as usize;
        let runs = |v: &[R]| -> Vec<Vec<State>> {
            v.chunks_exact(4 * per_run)
                .map(|run| {
                    run.chunks_exact(4)
                        .map(|s| State::from_array(std::array::from_fn(|i| s[i].to_f64())))
                        .collect()
                })
                .collect()
        };
        read_buffer_with(ctx, &states, bytes, |b| {
            match bytemuck::try_cast_slice::<u8, R>(b) {
                Ok(v) => runs(v),
                // A mapping not aligned to the real's size (wgpu promises 8 bytes): one copy.
                Err(_) => runs(&bytemuck::pod_collect_to_vec::<u8, R>(b)),
            }
        })
    }
}

/// A storage buffer of `bytes` (read back too) with start i written at state i `every`, as
/// it is made: one copy, where a write per start cost wgpu a staging round each (a tenth of
/// a forecast's time on lavapipe).
fn starts_buffer<R: Real>(
    ctx: &GpuContext,
    label: &str,
    starts: &[State],
    every: usize,
    bytes: u64,
) -> Result<wgpu::Buffer> {
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: true,
    });
    {
        let mut view = buffer
            .get_mapped_range_mut(..)
            .map_err(|e| Error::Gpu(format!("map range: {e}")))?;
        // A state is four reals.
        let size = 4 * std::mem::size_of::<R>();
        for (i, s) in starts.iter().enumerate() {
            let at = i * every * size;
            let v = s.to_array().map(R::from_f64);
            view.slice(at..at + size)
                .copy_from_slice(bytemuck::cast_slice(&v));
        }
    }
    buffer.unmap();
    Ok(buffer)
}

/// The runs' joint damping, two reals a run (a vec2<real>), or one unused pair when the runs
/// share `p`'s; scaled as the parameters' torques are (`GpuParams::new`).
pub(super) fn damping_buffer<R: Real>(
    ctx: &GpuContext,
    p: &Params,
    damping: Option<&[(f64, f64)]>,
) -> wgpu::Buffer {
    let scale = mass_scale(p);
    let pairs: Vec<R> = match damping {
        Some(d) => d
            .iter()
            .flat_map(|&(a, b)| [R::from_f64(a * scale), R::from_f64(b * scale)])
            .collect(),
        None => vec![R::from_f64(0.0); 2],
    };
    let buffer = storage_buffer(
        ctx,
        "damping",
        (pairs.len() * std::mem::size_of::<R>()) as u64,
    );
    ctx.queue
        .write_buffer(&buffer, 0, bytemuck::cast_slice(&pairs));
    buffer
}

/// A storage buffer of the runs' `Pendulum`s (shaders/common.wgsl): each start with the cos
/// and sin of its angles (in f64, then the kernel's precision).
pub(super) fn pendulums_buffer<R: Real>(
    ctx: &GpuContext,
    label: &str,
    starts: &[State],
) -> wgpu::Buffer {
    let pendulums: Vec<R> = starts
        .iter()
        .flat_map(|s| {
            let (s1, c1) = s.theta1.sin_cos();
            let (s2, c2) = s.theta2.sin_cos();
            let y = s.to_array();
            [y[0], y[1], y[2], y[3], c1, s1, c2, s2].map(R::from_f64)
        })
        .collect();
    let buffer = storage_buffer(
        ctx,
        label,
        std::mem::size_of_val(pendulums.as_slice()) as u64,
    );
    ctx.queue
        .write_buffer(&buffer, 0, bytemuck::cast_slice(&pendulums));
    buffer
}

/// The one entry point's pipeline for runs of `p`, each with its own joint damping when
/// `per_run`: then the joint-damping loss is compiled in whatever `p`'s is.
pub(super) fn damped_pipeline<'a>(
    pipelines: &'a Variants,
    ctx: &GpuContext,
    p: &Params,
    per_run: bool,
) -> &'a wgpu::ComputePipeline {
    let losses = p.losses.kinds() | per_run as u32;
    let [pipeline] = pipelines.get(ctx, losses, false, per_run) else {
        unreachable!("one entry point")
    };
    pipeline
}
