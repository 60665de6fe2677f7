//! Drives `shaders/trajectory.wgsl`: ensembles of pendulums, one invocation each, keeping
//! every `stride`-th state, each with the same parameters or its own joint damping.

use super::context::{GpuContext, read_buffer_with};
use super::layout::{Real, Run, RunParams, mass_scale, with_real};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, kernel_module, layouts, params_buffer_of,
    storage_buffer,
};
use super::shaders::Kernel;
use crate::error::{Error, Result};
use crate::model::{KeptRuns, Params, State};
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
        let (layout, pipeline_layout) = layouts(ctx, "trajectory", &[false, true]);
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
        self.run_damped_with(ctx, p, starts, None, dt, steps, stride, |kept| {
            kept.to_runs()
        })
    }

    /// As [`TrajectoryKernel::run`], run i with joint damping `damping[i]` (N m s at the pivot
    /// and the middle joint) in place of `p`'s when given (one pair per start), the kept states
    /// handed to `f` where they are read back, in the kernel's precision (no copy or
    /// conversion on the host).
    #[allow(clippy::too_many_arguments)]
    pub fn run_damped_with<T>(
        &self,
        ctx: &GpuContext,
        p: &Params,
        starts: &[State],
        damping: Option<&[(f64, f64)]>,
        dt: f64,
        steps: u32,
        stride: u32,
        f: impl FnOnce(KeptRuns<'_>) -> T,
    ) -> Result<T> {
        with_real!(self.precision, R => self.run_in::<R, T>(ctx, p, starts, damping, dt, steps, stride, f))
    }

    #[allow(clippy::too_many_arguments)]
    fn run_in<R: Real, T>(
        &self,
        ctx: &GpuContext,
        p: &Params,
        starts: &[State],
        damping: Option<&[(f64, f64)]>,
        dt: f64,
        steps: u32,
        stride: u32,
        f: impl FnOnce(KeptRuns<'_>) -> T,
    ) -> Result<T> {
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
        // Per-run damping: the joint-damping loss compiled in whatever `p`'s is.
        let losses = p.losses.kinds() | damping.is_some() as u32;
        let [pipeline] = self.pipelines.get(ctx, losses, false, damping.is_some()) else {
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
        // The starts written straight into the buffer as it is made: one copy, where a write
        // per start cost wgpu a staging round each (a tenth of a forecast's time on lavapipe).
        let states = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("trajectory states"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: true,
        });
        {
            let mut view = states
                .get_mapped_range_mut(..)
                .map_err(|e| Error::Gpu(format!("map range: {e}")))?;
            let size = state_bytes as usize;
            for (i, s) in starts.iter().enumerate() {
                let at = i * per_run as usize * size;
                let v = s.to_array().map(R::from_f64);
                view.slice(at..at + size)
                    .copy_from_slice(bytemuck::cast_slice(&v));
            }
        }
        states.unmap();
        // Two reals a run (a vec2<real>), or one unused pair when the runs share `p`'s;
        // scaled as the parameters' torques are (`GpuParams::new`).
        let scale = mass_scale(p);
        let pairs: Vec<R> = match damping {
            Some(d) => d
                .iter()
                .flat_map(|&(a, b)| [R::from_f64(a * scale), R::from_f64(b * scale)])
                .collect(),
            None => vec![R::from_f64(0.0); 2],
        };
        let damping_buf = storage_buffer(
            ctx,
            "trajectory damping",
            (pairs.len() * std::mem::size_of::<R>()) as u64,
        );
        ctx.queue
            .write_buffer(&damping_buf, 0, bytemuck::cast_slice(&pairs));
        let bind = bind_group(
            ctx,
            "trajectory",
            &self.layout,
            &[&params_buf, &states, &damping_buf],
        );
        dispatch_and_wait(ctx, pipeline, &bind, count)?;
        let per_run = per_run as usize;
        read_buffer_with(ctx, &states, bytes, |b| {
            match bytemuck::try_cast_slice::<u8, R>(b) {
                Ok(v) => f(KeptRuns {
                    reals: R::reals(v),
                    per_run,
                }),
                // A mapping not aligned to the real's size (wgpu promises 8 bytes): one copy.
                Err(_) => f(KeptRuns {
                    reals: R::reals(&bytemuck::pod_collect_to_vec::<u8, R>(b)),
                    per_run,
                }),
            }
        })
    }
}
