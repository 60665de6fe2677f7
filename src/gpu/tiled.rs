//! The one loop every map kernel runs: the grid cut into tiles of whole rows that fit the
//! device, each tile's time loop cut into dispatches of bounded work, the values read back
//! into a [`Field`] and the mirrored half filled in.

use super::context::GpuContext;
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::{Grid, RowSpan};

/// Pendulum-steps per dispatch: about 0.1 s on lavapipe (~1.5e8 steps/s), far less on a real
/// GPU, so no dispatch holds the device long enough to trip a driver watchdog.
pub const STEPS_PER_DISPATCH: u64 = 1 << 24;

/// Most steps (or step attempts) an invocation takes in one dispatch. lavapipe (llvmpipe)
/// ends all of an invocation's loops after 65535 iterations in all (its
/// LP_MAX_TGSI_LOOP_ITERATIONS) and goes on silently, which left the pixels of a dispatch
/// with few active ones short of the steps counted; half of it leaves room for a step's own
/// loops (bisections at a flip).
pub const STEPS_PER_INVOCATION: u32 = 1 << 15;

/// Step attempts an adaptive window kernel's invocation takes at most a dispatch (the tangent
/// and spectrum kernels): with at most [`STEPS_PER_INVOCATION`] windows' loop turns besides,
/// well within lavapipe's 65,535 loop iterations an invocation. A pixel the budget stops
/// goes on in the next dispatch from where it was ([`catch_up`] after the last).
pub const ATTEMPTS_PER_DISPATCH: u32 = 1 << 14;

/// Fewest steps a dispatch takes (its per-pixel bookkeeping, the active list, costs about
/// a step; spread over a few steps it would rival the steps themselves).
pub const MIN_STEPS: u64 = 16;

/// The rows `span` of a grid cut into tiles of whole rows that fit the device: at most
/// `max_pixels` pixels each.
pub struct Tiling {
    pub width: u32,
    pub span: RowSpan,
    /// Rows integrated (`span.count`).
    pub height: u32,
    pub tile_rows: u32,
}

impl Tiling {
    pub fn new(width: u32, span: RowSpan, max_pixels: u64) -> Self {
        let height = span.count;
        let tile_rows = (max_pixels / width as u64).clamp(1, height as u64) as u32;
        Tiling {
            width,
            span,
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

    /// (first row of the grid, rows) of each tile, top to bottom.
    pub fn tiles(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.count()).map(|t| {
            let row0 = t * self.tile_rows;
            (
                self.span.first + row0,
                self.tile_rows.min(self.height - row0),
            )
        })
    }
}

/// Most pixels a tile may hold when each pixel needs `largest` bytes in its largest binding
/// and `total` bytes in all buffers together (the sizes of the layout's storage mirrors).
pub fn max_pixels(ctx: &GpuContext, largest: u64, total: u64) -> u64 {
    (ctx.max_binding() / largest).min(ctx.limits.max_buffer_size / total)
}

/// The map of `grid` whose top `rows` rows are computed tile by tile by `tile(row0, rows,
/// later)` (the values of those rows, row-major; `later` is the number of pixels in the
/// tiles after it, for the progress estimate); the rest is mirrored from them. Progress
/// counts pendulum-steps ([`time_loop`] estimates what is left).
pub fn map_tiles(
    grid: &Grid,
    tiling: &Tiling,
    steps: u32,
    monitor: &Monitor,
    mut tile: impl FnMut(u32, u32, u64) -> Result<Vec<f32>>,
) -> Result<Field> {
    monitor.start(
        "gpu",
        tiling.height as u64 * tiling.width as u64 * steps as u64,
    );
    let span = tiling.span;
    let mut field = Field::new(grid.width, span.field_rows(grid), 0.0);
    for (row0, rows) in tiling.tiles() {
        let done = row0 - span.first;
        let later = (tiling.height - done - rows) as u64 * tiling.width as u64;
        let values = tile(row0, rows, later)?;
        let start = done as usize * grid.width as usize;
        field.data[start..start + values.len()].copy_from_slice(&values);
    }
    if span.whole {
        field.mirror_below(tiling.height);
    }
    monitor.finish();
    Ok(field)
}

/// After the dispatches of an adaptive window kernel up to window `target`: dispatches again
/// (`again`, the target unchanged) while `clocks` reads a pixel short of it and not stalled.
/// A clock is (the next step, attempts so far (-1: stalled), windows done, time into the
/// next); each round gives every such pixel [`ATTEMPTS_PER_DISPATCH`] more attempts and a
/// pixel stalls after 2^24 in all, so the rounds end. Ctrl-C between rounds.
pub fn catch_up(
    target: u32,
    monitor: &Monitor,
    mut clocks: impl FnMut() -> Result<Vec<[f64; 4]>>,
    mut again: impl FnMut() -> Result<()>,
) -> Result<()> {
    while clocks()?
        .iter()
        .any(|c| c[1] >= 0.0 && c[2] < target as f64)
    {
        monitor.check()?;
        again()?;
    }
    Ok(())
}

/// A tile's work for [`time_loop`].
#[derive(Clone, Copy, Debug)]
pub struct TileWork {
    /// Steps to take.
    pub total: u32,
    /// The tile's pixels, and those still active at the start.
    pub pixels: u32,
    pub active: u32,
    /// Plain steps a step costs.
    pub cost: u64,
    /// At most this many steps a dispatch, when given.
    pub max_steps: Option<u32>,
    /// Pixels of the tiles still to come.
    pub later: u64,
}

impl TileWork {
    /// `total` steps of `pixels` pixels, all active at the start, each step costing `cost`
    /// plain steps, no other bound on a dispatch's steps, `later` pixels still to come.
    pub fn new(total: u32, pixels: u32, cost: u64, later: u64) -> Self {
        TileWork {
            total,
            pixels,
            active: pixels,
            cost,
            max_steps: None,
            later,
        }
    }
}

/// A tile's time loop: `dispatch(step0, steps, active)` advances the `active` pixels by
/// `steps` steps from `step0` and returns how many are still active, until `work.total` steps
/// are done or none is. Each dispatch holds at most STEPS_PER_DISPATCH / `cost` pendulum-steps,
/// at most `max_steps` steps when given, and at most [`STEPS_PER_INVOCATION`] / `cost` steps
/// (a step's loop iterations are at most its cost).
///
/// Progress counts pendulum-steps. What is left is estimated from the work itself: the
/// still-active pixels run until they flip, at the rate at which they flipped over the last
/// quarter of the steps so far (survival exp(-h k) over the steps left; h = 0 when none
/// flipped), and the `later` pixels of the tiles still to come cost what this tile's pixels
/// cost on average.
pub fn time_loop(
    work: TileWork,
    monitor: &Monitor,
    mut dispatch: impl FnMut(u32, u32, u32) -> Result<u32>,
) -> Result<()> {
    let TileWork {
        total,
        pixels,
        mut active,
        cost,
        max_steps,
        later,
    } = work;
    let mut step0 = 0;
    let mut done = 0u64;
    let mut hazard = 0.0f64;
    // (step, active) after each dispatch, for the flip rate over a window.
    let mut history = vec![(0u32, active)];
    loop {
        let left = (total - step0) as f64;
        let per_active = if hazard > 0.0 {
            (1.0 - (-hazard * left).exp()) / hazard
        } else {
            left
        };
        let tile_left = active as f64 * per_active;
        let per_pixel = (done as f64 + tile_left) / pixels.max(1) as f64;
        let guess = tile_left + later as f64 * per_pixel;
        // A sample's estimate of the whole work, where there is one, within what must and
        // what can still come.
        let left = match monitor.estimated() {
            Some(whole) => {
                let most = active as f64 * left + later as f64 * total as f64;
                (whole - monitor.position() as f64).clamp(active as f64, most.max(active as f64))
            }
            None => guess,
        };
        monitor.expect(left as u64);
        if step0 >= total || active == 0 {
            break;
        }
        monitor.check()?;
        let bounded = (STEPS_PER_DISPATCH / cost / active as u64).max(MIN_STEPS / cost);
        let steps = bounded
            .min(max_steps.unwrap_or(u32::MAX) as u64)
            .min((STEPS_PER_INVOCATION as u64 / cost).max(1))
            .min((total - step0) as u64) as u32;
        let before = active;
        active = dispatch(step0, steps, active)?;
        step0 += steps;
        let work = before as u64 * steps as u64;
        done += work;
        monitor.advance(work);
        history.push((step0, active));
        // The latest point at least a quarter of the steps so far back (or the start).
        let (then, was) = *history
            .iter()
            .rev()
            .find(|(k, _)| *k <= step0 - step0 / 4)
            .unwrap_or(&history[0]);
        hazard = match (active, step0 - then) {
            (0, _) => f64::INFINITY,
            (_, 0) => 0.0,
            (_, window) => (was as f64 / active as f64).ln() / window as f64,
        };
    }
    Ok(())
}

/// An adaptive tile's loop: `dispatch(attempts, active)` gives each of the `active` pixels up
/// to `attempts` more step attempts and returns how many still run, until none does (each
/// pixel ends by itself: at t-max, at its flip, or stalled, within MAX_STEPS attempts).
///
/// Progress counts pendulum-attempts. Each pixel is first expected to take `guess` attempts
/// (t-max over the largest step); pixels still running past that are expected to need a
/// quarter of what they took so far, and the `later` pixels of the tiles still to come what
/// this tile's took on average.
pub fn adaptive_loop(
    pixels: u32,
    mut active: u32,
    guess: u32,
    later: u64,
    monitor: &Monitor,
    mut dispatch: impl FnMut(u32, u32) -> Result<u32>,
) -> Result<()> {
    // A DP54 attempt costs six evaluations of the rate where an RK4 step costs four.
    const COST: u64 = 2;
    let mut taken = 0u64;
    let mut done = 0u64;
    loop {
        let per_active = (guess as f64 - taken as f64)
            .max(0.25 * taken as f64)
            .max(1.0);
        let per_pixel = (done as f64 + active as f64 * per_active) / pixels.max(1) as f64;
        monitor.expect((active as f64 * per_active + later as f64 * per_pixel) as u64);
        if active == 0 {
            break;
        }
        monitor.check()?;
        let attempts = (STEPS_PER_DISPATCH / COST / active as u64)
            .clamp(MIN_STEPS, STEPS_PER_INVOCATION as u64);
        let before = active;
        active = dispatch(attempts as u32, active)?;
        taken += attempts;
        done += before as u64 * attempts;
        monitor.advance(before as u64 * attempts);
    }
    Ok(())
}
