//! Drives `shaders/positions.wgsl`: the bobs' positions of an ensemble at given times, each
//! run with the same parameters or its own joint damping. Only the positions come back.

use super::context::{GpuContext, read_buffer_with};
use super::layout::{GpuBandTime, Real, Run, RunParams, TileParams, with_real};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, kernel_module, layouts, params_buffer_of,
    storage_buffer,
};
use super::shaders::Kernel;
use super::tiled::{STEPS_PER_DISPATCH, STEPS_PER_INVOCATION};
use super::trajectory::{damped_pipeline, damping_buffer, pendulums_buffer};
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::spec::{EnsembleSpec, Precision};

pub struct PositionsKernel {
    precision: Precision,
    pipelines: Variants,
    layout: wgpu::BindGroupLayout,
}

impl PositionsKernel {
    /// The kernel in `precision` (f64 needs a context with `GpuContext::has_f64`).
    pub fn with_precision(ctx: &GpuContext, precision: Precision) -> Self {
        let module = kernel_module(ctx, Kernel::Positions, precision);
        let (layout, pipeline_layout) = layouts(ctx, "positions", &[false, true, true, false]);
        PositionsKernel {
            precision,
            pipelines: Variants::new(module, pipeline_layout, &["positions"], None),
            layout,
        }
    }

    /// The positions (x1, y1, x2, y2) of the runs of `spec` (which keeps positions at given
    /// times) integrated in the kernel's precision, handed to `f` where they are read back,
    /// time-major: time j, coordinate c, run i of n at (4 j + c) n + i. Progress (runs) and
    /// Ctrl-C between dispatches.
    pub fn run_with<T>(
        &self,
        ctx: &GpuContext,
        spec: &EnsembleSpec,
        monitor: &Monitor,
        f: impl FnOnce(&[f32]) -> T,
    ) -> Result<T> {
        with_real!(self.precision, R => self.run_in::<R, T>(ctx, spec, monitor, f))
    }

    fn run_in<R: Real, T>(
        &self,
        ctx: &GpuContext,
        spec: &EnsembleSpec,
        monitor: &Monitor,
        f: impl FnOnce(&[f32]) -> T,
    ) -> Result<T> {
        let (p, starts, damping, dt, steps) =
            (&spec.params, spec.starts, spec.damping, spec.dt, spec.steps);
        let times = spec.times();
        if let Some(d) = damping {
            assert_eq!(d.len(), starts.len(), "one damping pair per start");
        }
        assert!(steps >= 1 && !times.is_empty(), "a step and a time");
        // Four f32 coordinates a run and time.
        let bytes = starts.len() as u64 * times.len() as u64 * 16;
        if bytes > ctx.max_binding() {
            return Err(Error::invalid(
                "members",
                format!(
                    "{} runs at {} times do not fit one GPU buffer; use the CPU backend, fewer runs or fewer times",
                    starts.len(),
                    times.len()
                ),
            ));
        }
        let pipeline = damped_pipeline(&self.pipelines, ctx, p, damping.is_some());
        let count = starts.len() as u32;
        let mut params = R::Params::of(p, dt).with_run(Run {
            steps,
            count,
            ..Run::default()
        });
        let params_buf = params_buffer_of(ctx, std::mem::size_of_val(&params) as u64);
        let states_buf = pendulums_buffer::<R>(ctx, "positions states", starts);
        let damping_buf = damping_buffer::<R>(ctx, p, damping);
        let band: Vec<GpuBandTime> = times
            .iter()
            .map(|&t| GpuBandTime::at(t, dt, steps))
            .collect();
        let times_buf = storage_buffer(
            ctx,
            "positions times",
            std::mem::size_of_val(band.as_slice()) as u64,
        );
        ctx.queue
            .write_buffer(&times_buf, 0, bytemuck::cast_slice(&band));
        let out = storage_buffer(ctx, "positions", bytes);
        let bind = bind_group(
            ctx,
            "positions",
            &self.layout,
            &[&params_buf, &states_buf, &damping_buf, &times_buf, &out],
        );
        // Spans of steps within lavapipe's loop limit, each in dispatches of at most
        // STEPS_PER_DISPATCH pendulum-steps (a driver's watchdog), all writing into the one
        // buffer read back at the end.
        for (step0, span, first_time) in spans(&band, steps) {
            let per_dispatch = (STEPS_PER_DISPATCH / span as u64).clamp(1, u32::MAX as u64) as u32;
            let last = step0 + span == steps;
            let mut first = 0;
            while first < count {
                monitor.check()?;
                let rows = per_dispatch.min(count - first);
                params.set_tile(first, rows, count);
                params.set_steps(step0, span, count);
                params.set_interval(first_time);
                ctx.queue
                    .write_buffer(&params_buf, 0, bytemuck::bytes_of(&params));
                dispatch_and_wait(ctx, pipeline, &bind, rows)?;
                if last {
                    monitor.advance(rows as u64);
                }
                first += rows;
            }
        }
        read_buffer_with(ctx, &out, bytes, |b| match bytemuck::try_cast_slice(b) {
            Ok(v) => f(v),
            // A mapping not aligned to 4 bytes (wgpu promises 8): one copy.
            Err(_) => f(&bytemuck::pod_collect_to_vec::<u8, f32>(b)),
        })
    }
}

/// The dispatches' spans of steps: (first step, steps, index of the first time placed in
/// it), each with at most half of [`STEPS_PER_INVOCATION`] steps and as many times (a span
/// holds at least one step).
fn spans(times: &[GpuBandTime], steps: u32) -> Vec<(u32, u32, u32)> {
    let half = STEPS_PER_INVOCATION / 2;
    let (mut out, mut step0, mut j) = (Vec::new(), 0u32, 0usize);
    while step0 < steps {
        let mut end = (step0 + half).min(steps);
        if let Some(t) = times.get(j + half as usize) {
            end = end.min(t.step.max(step0 + 1));
        }
        out.push((step0, end - step0, j as u32));
        j += times[j..].partition_point(|t| t.step < end);
        step0 = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spans cover the steps in order, each time lies in its span, and no span asks an
    /// invocation for more than half the loop limit of steps or of times.
    #[test]
    fn spans_cover_every_step_and_time_within_the_loop_limit() {
        let half = STEPS_PER_INVOCATION / 2;
        for (steps, times) in [(1, 1), (100_000, 50), (1_000, 40_000), (70_000, 70_000)] {
            let band: Vec<GpuBandTime> = (0..times)
                .map(|j| GpuBandTime::at(j as f64 / times as f64, 1.0 / steps as f64, steps))
                .collect();
            let spans = spans(&band, steps);
            let mut next = 0;
            for (k, &(step0, span, first)) in spans.iter().enumerate() {
                assert_eq!(step0, next, "spans follow each other");
                assert!(span >= 1 && span <= half, "{span} steps");
                let last = spans.get(k + 1).map_or(times, |s| s.2 as usize);
                let placed = &band[first as usize..last];
                assert!(placed.len() <= half as usize, "{} times", placed.len());
                assert!(
                    placed
                        .iter()
                        .all(|t| t.step >= step0 && t.step < step0 + span)
                );
                next = step0 + span;
            }
            assert_eq!(next, steps);
        }
    }
}
