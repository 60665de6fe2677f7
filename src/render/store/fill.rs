//! Filling a Zarr store of a map, unit by unit: one band of rows in memory at a time, the
//! units already written skipped, so that a task that stopped resumes and tasks share a map.

use std::path::Path;

use super::{MapStore, StoreInfo, Unit, pairs_mirrored, task_units, units};
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::Grid;

/// A map job into a store: which store, the grid, the command, which part.
pub struct StoreFill<'a> {
    pub path: &'a Path,
    pub grid: Grid,
    pub command: String,
    pub tile: Option<(u32, u32)>,
    /// Whether the map may pair mirrored chunks (its own `use_symmetry`).
    pub symmetric: bool,
    pub verdict: bool,
    /// The map's (name, unit), for the array's attributes.
    pub quantity: (&'a str, &'a str),
    /// The map's settings as data ([`StoreInfo::identity`]).
    pub identity: serde_json::Value,
}

/// What a fill computed: pixels written, the counts `count` found in them, resolved pixels.
pub struct Filled {
    pub pixels: usize,
    pub counted: usize,
    pub nan: usize,
    pub resolved: usize,
    pub missing: usize,
    pub chunks: u32,
}

/// Fills this task's part of the store: unit by unit (memory holds one band), skipping the
/// units already written. `band((first, rows), monitor)` computes rows of the map and, with
/// the verdict, its mask; `count` counts the pixels the summary reports (flipped, chaotic).
pub fn fill_store(
    fill: &StoreFill,
    monitor: &Monitor,
    band: impl Fn((u32, u32), &Monitor) -> Result<(Field, Option<Vec<u8>>)>,
    count: impl Fn(f32) -> bool,
) -> Result<Filled> {
    let (index, tasks) = fill.tile.unwrap_or((0, 1));
    let grid = fill.grid;
    let ours = StoreInfo {
        command: fill.command.clone(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        tiles: tasks,
        mirrored: pairs_mirrored(&grid, fill.symmetric),
        resolved: fill.verdict,
        identity: fill.identity.clone(),
    };
    let store = MapStore::create_or_open("data", fill.path, &grid, &ours, fill.quantity)?;
    let all = units(grid.height, store.chunk_rows, store.info.mirrored);
    let mut todo = Vec::new();
    for unit in task_units(&all, index, tasks) {
        let written = store.is_written(unit.chunk)?
            && unit.mirror.map_or(Ok(true), |m| store.is_written(m))?;
        if !written {
            todo.push(unit);
        }
    }
    let rows_of = |u: &Unit| {
        let r = store.chunk_span(u.chunk).1 as u64;
        r * (1 + u.mirror.is_some() as u64)
    };
    monitor.start("rows", todo.iter().map(rows_of).sum());
    let mut filled = Filled {
        pixels: 0,
        counted: 0,
        nan: 0,
        resolved: 0,
        missing: 0,
        chunks: store.chunks(),
    };
    for unit in &todo {
        monitor.check()?;
        // A chunk that is its own mirror image (the middle one, on a symmetric grid): its
        // top half, the rest reflected, as a whole map does.
        let (first, rows) = store.chunk_span(unit.chunk);
        let own_mirror = store.info.mirrored && unit.mirror.is_none();
        let integrated = if own_mirror { rows.div_ceil(2) } else { rows };
        let (top, mask) = band((first, integrated), &monitor.quiet())?;
        let (field, mask) = if own_mirror {
            let (width, rows, top_rows) = (top.width as usize, rows as usize, integrated as usize);
            let field = Field {
                width: top.width,
                height: rows as u32,
                data: reflected(top.data, width, rows, top_rows),
            };
            (field, mask.map(|m| reflected(m, width, rows, top_rows)))
        } else {
            (top, mask)
        };
        let copies = 1 + unit.mirror.is_some() as usize;
        if let Some(m) = &mask {
            filled.resolved += m.iter().filter(|&&v| v == 1).count() * copies;
        }
        store.write_unit(*unit, &field, mask.as_deref())?;
        filled.pixels += field.data.len() * copies;
        filled.counted += field.data.iter().filter(|&&v| count(v)).count() * copies;
        filled.nan += field.data.iter().filter(|v| v.is_nan()).count() * copies;
        monitor.advance(rows_of(unit));
    }
    monitor.finish();
    filled.missing = store.missing()?.len();
    Ok(filled)
}

/// The `top` rows of a band of `rows` rows, the rest filled by point reflection (a band that
/// is its own mirror image).
fn reflected<T: Copy + Default>(
    mut values: Vec<T>,
    width: usize,
    rows: usize,
    top: usize,
) -> Vec<T> {
    values.resize(width * rows, T::default());
    crate::field::mirror_below(&mut values, width, top);
    values
}

/// The notes after a fill: nothing was left to do here, or chunks are still missing.
pub fn missing_note(filled: &Filled, path: &Path) -> Vec<String> {
    let mut out = Vec::new();
    if filled.pixels == 0 {
        out.push("note: nothing left to compute in this part of the store (the figures below count none)".into());
    }
    if filled.missing > 0 {
        out.push(format!(
            "note: {} of the store's {} chunks are still to be computed (`chaoscope status {}`)",
            filled.missing,
            filled.chunks,
            path.display()
        ));
    }
    out
}
