//! Drives `shaders/indicators.wgsl`: maps of the chaos indicators beyond the largest exponent
//! inside the tiled loop of `tiled.rs`, every pixel integrating the whole run (an alignment
//! index's pixel stops once it falls below its threshold).

use super::context::{GpuContext, read_buffer};
use super::layout::{Real, Run, RunParams, TileParams, read_reals, with_real};
use super::pipeline::{MapBuffers, Variants, dispatch_and_wait, kernel_module, layouts};
use super::shaders::Kernel;
use super::tiled::{TileWork, Tiling, catch_up, map_tiles, max_pixels, time_loop};
use crate::error::Result;
use crate::field::Field;
use crate::measure::Runs;
use crate::monitor::Monitor;
use crate::spec::{LyapunovSpec, Precision};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A value below this is the kernel's "left the numbers" (-3e38): NaN.
pub const LEFT_BELOW: f64 = -1e38;

/// The entries every measure's kernel starts with.
const INIT: &str = "indicator_init";

pub struct IndicatorKernel {
    precision: Precision,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// (init, advance) of each advance entry asked for so far, its pipelines compiled on
    /// first use.
    entries: Mutex<HashMap<&'static str, Arc<Variants>>>,
    layout: wgpu::BindGroupLayout,
}

impl IndicatorKernel {
    /// The kernel in `precision` (f64 needs a context with f64).
    pub fn with_precision(ctx: &GpuContext, precision: Precision) -> Self {
        let module = kernel_module(ctx, Kernel::Indicators, precision);
        let (layout, pipeline_layout) = layouts(ctx, "indicators", &[false, false]);
        IndicatorKernel {
            precision,
            module,
            pipeline_layout,
            entries: Mutex::default(),
            layout,
        }
    }

    /// The (init, `advance`) pipelines' variants.
    fn variants(&self, advance: &'static str) -> Arc<Variants> {
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        let made = entries.entry(advance).or_insert_with(|| {
            Arc::new(Variants::new(
                self.module.clone(),
                self.pipeline_layout.clone(),
                &[INIT, advance],
                None,
            ))
        });
        made.clone()
    }

    /// The map of `spec`'s indicator (its quantity's unit).
    pub fn run(&self, ctx: &GpuContext, spec: &LyapunovSpec, monitor: &Monitor) -> Result<Field> {
        with_real!(self.precision, R => self.run_in::<R>(ctx, spec, monitor, None))
    }

    /// All four exponents of `spec`'s grid (1/s, in Gram-Schmidt order: the first the largest, the others not sorted per pixel), from
    /// one run of the spectrum kernel; `spec`'s indicator must be an exponent or their sum.
    pub fn spectrum(
        &self,
        ctx: &GpuContext,
        spec: &LyapunovSpec,
        monitor: &Monitor,
    ) -> Result<[Field; 4]> {
        let mut layers: [Vec<f64>; 4] = Default::default();
        with_real!(self.precision, R => self.run_in::<R>(ctx, spec, monitor, Some(&mut layers)))?;
        let t_end = spec.stepping.steps() as f64 * spec.stepping.dt;
        let span = spec.row_span();
        Ok(layers.map(|sums| {
            let mut field = Field {
                width: spec.grid.width,
                height: span.field_rows(&spec.grid),
                data: sums.into_iter().map(|s| (s / t_end) as f32).collect(),
            };
            field
                .data
                .resize(field.width as usize * field.height as usize, 0.0);
            if span.whole {
                field.mirror_below(span.count);
            }
            field
        }))
    }

    /// The tiled loop; `layers`, if given, receives each pixel's four log sums in tile order.
    fn run_in<R: Real>(
        &self,
        ctx: &GpuContext,
        spec: &LyapunovSpec,
        monitor: &Monitor,
        mut layers: Option<&mut [Vec<f64>; 4]>,
    ) -> Result<Field> {
        use std::mem::size_of;
        let indicator = spec.indicator;
        let measure = indicator.measure();
        let Runs::Indicators(gpu) = measure.runs(indicator) else {
            unreachable!("the divergence kernel's map is gpu::lyapunov's")
        };
        let adaptive = spec.integrator.tolerances();
        let advance = match (adaptive, gpu.adaptive) {
            (None, _) => gpu.entry,
            (Some(_), Some(entry)) => entry,
            (Some(_), None) => {
                return Err(crate::Error::invalid(
                    "integrator",
                    format!("the {} steps with rk4 only", indicator.title()),
                ));
            }
        };
        let (rtol, atol) = adaptive.unwrap_or_default();
        let total_steps = spec.stepping.steps();
        let base = R::Params::of(&spec.params, spec.stepping.dt)
            .over(&spec.grid, &spec.params)
            .with_run(Run {
                interval: spec.renorm_steps(),
                total_steps,
                setting: gpu.setting,
                measure: gpu.measure,
                rtol,
                atol,
                ..Run::default()
            });
        let variants = self.variants(advance);
        let [init, advance] = variants.map_pair(ctx, &spec.params, &spec.grid, false);
        let slot = size_of::<R::IndicatorSlot>() as u64;
        let value_bytes = size_of::<R>() as u64;
        let tiling = Tiling::new(
            spec.grid.width,
            spec.row_span(),
            max_pixels(ctx, slot, slot + value_bytes),
        );
        let capacity = tiling.capacity();
        let MapBuffers {
            params: params_buf,
            slots: states,
            values,
            bind,
        } = MapBuffers::new(
            ctx,
            "indicators",
            &self.layout,
            size_of::<R::Params>() as u64,
            capacity,
            (slot, value_bytes),
        );
        let dispatch = |pipeline: &wgpu::ComputePipeline, params: &R::Params| {
            ctx.queue
                .write_buffer(&params_buf, 0, bytemuck::bytes_of(params));
            dispatch_and_wait(ctx, pipeline, &bind, params.count())
        };
        let cost = gpu.cost;
        // The adaptive kernel's dispatches count renormalisation windows, each about
        // `interval` steps of DP54's six rates.
        let interval = spec.renorm_steps();
        let (units, unit_cost) = match adaptive {
            Some(_) => (total_steps.div_ceil(interval), cost * 2 * interval as u64),
            None => (total_steps, cost),
        };
        let t_end = total_steps as f64 * spec.stepping.dt;
        let finish = |raw: f64| -> f32 {
            match raw < LEFT_BELOW {
                true => f32::NAN,
                false => measure.finish(indicator, raw, t_end),
            }
        };
        let grid = spec.grid;
        map_tiles(&grid, &tiling, total_steps, monitor, |row0, rows, later| {
            let pixels = rows * grid.width;
            let mut params = base;
            params.set_tile(row0, rows, pixels);
            dispatch(init, &params)?;
            let work = TileWork::new(units, pixels, unit_cost, later);
            // The adaptive spectrum's pixels keep their own place in their slot's clock
            // (shaders/indicators.wgsl).
            let clocks = || -> Result<Vec<[f64; 4]>> {
                let bytes = read_buffer(ctx, &states, pixels as u64 * slot)?;
                let slots = bytemuck::pod_collect_to_vec::<u8, R::IndicatorSlot>(&bytes);
                Ok(slots.iter().map(R::slot_clock).collect())
            };
            time_loop(work, monitor, |step0, steps, active| {
                params.set_steps(step0, steps, pixels);
                dispatch(advance, &params)?;
                if adaptive.is_some() && step0 + steps == units {
                    catch_up(units, monitor, clocks, || dispatch(advance, &params))?;
                }
                Ok(active)
            })?;
            let raw = read_reals::<R>(&read_buffer(ctx, &values, pixels as u64 * value_bytes)?);
            if let Some(layers) = layers.as_deref_mut() {
                let bytes = read_buffer(ctx, &states, pixels as u64 * slot)?;
                for s in bytemuck::pod_collect_to_vec::<u8, R::IndicatorSlot>(&bytes) {
                    for (layer, sum) in layers.iter_mut().zip(R::slot_sums(&s)) {
                        layer.push(sum);
                    }
                }
            }
            Ok(raw.into_iter().map(finish).collect())
        })
    }
}
