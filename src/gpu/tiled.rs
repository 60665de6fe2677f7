//! The one loop every map kernel runs: the grid cut into tiles of whole rows that fit the
//! device, each tile's time loop cut into dispatches of bounded work, the values read back
//! into a [`Field`] and the mirrored half filled in.

use super::context::GpuContext;
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::Grid;

/// Pendulum-steps per dispatch: about 0.1 s on lavapipe (~1.5e8 steps/s), far less on a real
/// GPU, so no dispatch holds the device long enough to trip a driver watchdog.
pub const STEPS_PER_DISPATCH: u64 = 1 << 24;

/// A grid cut into tiles of whole rows that fit the device: at most `max_pixels` pixels each.
pub struct Tiling {
    pub width: u32,
    pub height: u32,
    pub tile_rows: u32,
}

impl Tiling {
    pub fn new(width: u32, height: u32, max_pixels: u64) -> Self {
        let tile_rows = (max_pixels / width as u64).clamp(1, height as u64) as u32;
        Tiling {
            width,
            height,
            tile_rows,
        }
    }

    /// Pixels of the largest tile (what the buffers must hold).
    pub fn capacity(&self) -> u64 {
        self.tile_rows as u64 * self.width as u64
    }

    pub fn count(&self) -> u32 {
        self.height.div_ceil(self.tile_rows)
    }

    /// (first row, rows) of each tile, top to bottom.
    pub fn tiles(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.count()).map(|t| {
            let row0 = t * self.tile_rows;
            (row0, self.tile_rows.min(self.height - row0))
        })
    }
}

/// Most pixels a tile may hold when each pixel needs `largest` bytes in its largest binding
/// and `total` bytes in all buffers together (the sizes of the layout's storage mirrors).
pub fn max_pixels(ctx: &GpuContext, largest: u64, total: u64) -> u64 {
    (ctx.max_binding() / largest).min(ctx.limits.max_buffer_size / total)
}

/// The map of `grid` whose top `rows` rows are computed tile by tile by `tile(row0, rows)`
/// (the values of those rows, row-major); the rest is mirrored from them. Progress counts
/// `steps` a tile.
pub fn map_tiles(
    grid: &Grid,
    tiling: &Tiling,
    steps: u32,
    monitor: &Monitor,
    mut tile: impl FnMut(u32, u32) -> Result<Vec<f32>>,
) -> Result<Field> {
    monitor.start("gpu", tiling.count() as u64 * steps as u64);
    let mut field = Field::new(grid.width, grid.height, 0.0);
    for (row0, rows) in tiling.tiles() {
        let values = tile(row0, rows)?;
        let start = row0 as usize * grid.width as usize;
        field.data[start..start + values.len()].copy_from_slice(&values);
    }
    field.mirror_below(tiling.height);
    monitor.finish();
    Ok(field)
}

/// A tile's time loop: `dispatch(step0, steps, active)` advances the `active` pixels by
/// `steps` steps from `step0` and returns how many are still active, until `total` steps are
/// done or none is. Each dispatch holds at most STEPS_PER_DISPATCH / `cost` pendulum-steps
/// (`cost`: plain steps a step costs), and at most `max_steps` steps when given.
pub fn time_loop(
    total: u32,
    mut active: u32,
    cost: u64,
    max_steps: Option<u32>,
    monitor: &Monitor,
    mut dispatch: impl FnMut(u32, u32, u32) -> Result<u32>,
) -> Result<()> {
    let mut step0 = 0;
    while step0 < total && active > 0 {
        monitor.check()?;
        let bounded = (STEPS_PER_DISPATCH / cost / active as u64).max(1);
        let steps = bounded
            .min(max_steps.unwrap_or(u32::MAX) as u64)
            .min((total - step0) as u64) as u32;
        active = dispatch(step0, steps, active)?;
        step0 += steps;
        monitor.advance(steps as u64);
    }
    monitor.advance((total - step0) as u64);
    Ok(())
}
