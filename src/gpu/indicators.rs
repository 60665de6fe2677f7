//! Drives `shaders/indicators.wgsl`: maps of the chaos indicators beyond the largest exponent
//! inside the tiled loop of `tiled.rs`, every pixel integrating the whole run (an alignment
//! index's pixel stops once it falls below its threshold).

use super::context::{GpuContext, read_buffer};
use super::layout::{NEVER, Real, Run, RunParams, TileParams, read_reals, with_real};
use super::pipeline::{
    Variants, bind_group, dispatch_and_wait, kernel_module, layouts, params_buffer_of,
    storage_buffer,
};
use super::shaders::Kernel;
use super::tiled::{Tiling, map_tiles, max_pixels, time_loop};
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::{Alignment, Indicator, LyapunovSpec, Precision};

/// A tangent step costs about this many plain steps (as `lyapunov.rs`), per vector.
const TANGENT_COST: u64 = 3;

/// A value below this is the kernel's "left the numbers" (-3e38): NaN.
const LEFT_BELOW: f64 = -1e38;

/// The (init, advance) entries of each indicator family, in the order of [`entry_of`].
const FAMILIES: [[&str; 2]; 8] = [
    ["indicator_init", "spectrum_advance"],
    ["indicator_init", "sali_advance"],
    ["indicator_init", "gali2_advance"],
    ["indicator_init", "gali3_advance"],
    ["indicator_init", "gali4_advance"],
    ["indicator_init", "growth_advance"],
    ["indicator_init", "descriptor_advance"],
    // The spectrum with DP54 steps (its windows as the dispatches' units).
    ["indicator_init", "spectrum_adaptive"],
];

/// The kernel's entry for `indicator` (an index into [`FAMILIES`]) and the value it writes
/// (`params.measure`).
fn entry_of(indicator: Indicator) -> (usize, u32) {
    let alignment = |index: Alignment| match index {
        Alignment::Sali => 1,
        Alignment::Gali(k) => k as usize,
    };
    match indicator {
        Indicator::Ftle => (0, 0),
        Indicator::Exponent(k) => (0, k as u32 - 1),
        Indicator::ExponentSum => (0, 4),
        Indicator::Alignment { index, .. } => (alignment(index), 0),
        Indicator::AlignmentTime { index, .. } => (alignment(index), 1),
        Indicator::Megno => (5, 0),
        Indicator::Fli => (5, 1),
        Indicator::Descriptor { .. } => (6, 0),
    }
}

pub struct IndicatorKernel {
    precision: Precision,
    /// (init, advance) of each family, compiled on first use.
    families: Vec<Variants>,
    layout: wgpu::BindGroupLayout,
}

impl IndicatorKernel {
    /// The kernel in `precision` (f64 needs a context with f64).
    pub fn with_precision(ctx: &GpuContext, precision: Precision) -> Self {
        let module = kernel_module(ctx, Kernel::Indicators, precision);
        let (layout, pipeline_layout) = layouts(ctx, "indicators", &[false, false]);
        let families = FAMILIES
            .iter()
            .map(|entries| Variants::new(module.clone(), pipeline_layout.clone(), entries, None))
            .collect();
        IndicatorKernel {
            precision,
            families,
            layout,
        }
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
        assert!(
            entry_of(spec.indicator).0 == 0,
            "the spectrum comes from the spectrum kernel"
        );
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
        let (family, measure) = entry_of(indicator);
        let adaptive = spec.integrator.tolerances();
        let family = match adaptive {
            Some(_) if family == 0 => 7,
            Some(_) => {
                return Err(crate::Error::invalid(
                    "integrator",
                    "only the spectrum steps with dp54",
                ));
            }
            None => family,
        };
        let (rtol, atol) = adaptive.unwrap_or_default();
        let total_steps = spec.stepping.steps();
        let base = R::Params::of(&spec.params, spec.stepping.dt)
            .over(&spec.grid, &spec.params)
            .with_run(Run {
                interval: spec.renorm_steps(),
                total_steps,
                setting: match indicator {
                    Indicator::Descriptor { p } => p,
                    other => other.threshold().unwrap_or(0.0),
                },
                measure,
                rtol,
                atol,
                ..Run::default()
            });
        let [init, advance] = self.families[family].get(
            ctx,
            spec.params.losses.kinds(),
            false,
            spec.grid.varies_params(),
        ) else {
            unreachable!("two entry points")
        };
        let slot = size_of::<R::IndicatorSlot>() as u64;
        let value_bytes = size_of::<R>() as u64;
        let tiling = Tiling::new(
            spec.grid.width,
            spec.row_span(),
            max_pixels(ctx, slot, slot + value_bytes),
        );
        let capacity = tiling.capacity();
        let params_buf = params_buffer_of(ctx, size_of::<R::Params>() as u64);
        let states = storage_buffer(ctx, "indicator states", capacity * slot);
        let values = storage_buffer(ctx, "indicator values", capacity * value_bytes);
        let bind = bind_group(
            ctx,
            "indicators",
            &self.layout,
            &[&params_buf, &states, &values],
        );
        let dispatch = |pipeline: &wgpu::ComputePipeline, params: &R::Params| {
            ctx.queue
                .write_buffer(&params_buf, 0, bytemuck::bytes_of(params));
            dispatch_and_wait(ctx, pipeline, &bind, params.count())
        };
        // Tangent vectors cost a tangent step each; a descriptor two plain steps.
        let cost = match indicator.vectors() {
            0 => 2,
            n => TANGENT_COST * n as u64,
        };
        // The adaptive kernel's dispatches count renormalisation windows, each about
        // `interval` steps of DP54's six rates.
        let interval = spec.renorm_steps();
        let (units, unit_cost) = match adaptive {
            Some(_) => (total_steps.div_ceil(interval), cost * 2 * interval as u64),
            None => (total_steps, cost),
        };
        let t_end = total_steps as f64 * spec.stepping.dt;
        let finish = |raw: f64| -> f32 {
            if raw < LEFT_BELOW {
                return f32::NAN;
            }
            match indicator {
                Indicator::Ftle | Indicator::Exponent(_) | Indicator::ExponentSum => {
                    (raw / t_end) as f32
                }
                Indicator::AlignmentTime { .. } if raw == NEVER as f64 => f32::INFINITY,
                _ => raw as f32,
            }
        };
        let grid = spec.grid;
        map_tiles(&grid, &tiling, total_steps, monitor, |row0, rows, later| {
            let pixels = rows * grid.width;
            let mut params = base;
            params.set_tile(row0, rows, pixels);
            dispatch(init, &params)?;
            time_loop(
                units,
                pixels,
                pixels,
                unit_cost,
                None,
                later,
                monitor,
                |step0, steps, active| {
                    params.set_steps(step0, steps, pixels);
                    dispatch(advance, &params)?;
                    Ok(active)
                },
            )?;
            let raw = read_reals::<R>(&read_buffer(ctx, &values, pixels as u64 * value_bytes)?);
            if let Some(layers) = layers.as_deref_mut() {
                // IndicatorSlot: y, u, four vectors, then the four log sums.
                let slots = read_reals::<R>(&read_buffer(ctx, &states, pixels as u64 * slot)?);
                for sums in slots.chunks_exact(32).map(|s| &s[24..28]) {
                    for (layer, &sum) in layers.iter_mut().zip(sums) {
                        layer.push(sum);
                    }
                }
            }
            Ok(raw.into_iter().map(finish).collect())
        })
    }
}
