//! `status` and `render`: what a Zarr store of a map still lacks, and its picture, made from
//! the store in bounded memory (one chunk band and the picture at a time).

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::sweep::FrameMap;
use crate::engine::{Path as RunPath, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::render::MapPicture;
use crate::render::store::{self, MapStore};
use crate::render::{self, Outputs, PictureSpec};
use crate::spec::{Grid, MapSpec};

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
    /// The map's settings as data ([`store::StoreInfo::identity`]).
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
    let ours = store::StoreInfo {
        command: fill.command.clone(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        tiles: tasks,
        mirrored: store::pairs_mirrored(&grid, fill.symmetric),
        resolved: fill.verdict,
        identity: fill.identity.clone(),
    };
    let store = MapStore::create_or_open("data", fill.path, &grid, &ours, fill.quantity)?;
    let all = store::units(grid.height, store.chunk_rows, store.info.mirrored);
    let mut todo = Vec::new();
    for unit in store::task_units(&all, index, tasks) {
        let written = store.is_written(unit.chunk)?
            && unit.mirror.map_or(Ok(true), |m| store.is_written(m))?;
        if !written {
            todo.push(unit);
        }
    }
    let rows_of = |u: &store::Unit| {
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

/// The map a store holds (from its identity, as data, checked like any spec) and the command
/// that made it. The command is shown, never parsed: it may name files, and a store may come
/// from anyone.
pub fn stored_map(path: &Path) -> Result<(String, FrameMap)> {
    map_of(&MapStore::open(path)?)
}

/// The map `store` holds ([`stored_map`]), checked against its arrays.
fn map_of(store: &MapStore) -> Result<(String, FrameMap)> {
    let path = store.path();
    let info = store.info.clone();
    let bad = |why: String| Error::Format(format!("{}: {why}", path.display()));
    let map = info
        .identity
        .get("map")
        .cloned()
        .ok_or_else(|| bad("records no map (chaoscope:identity); start a new store".into()))?;
    let map: FrameMap = serde_json::from_value(map).map_err(|e| {
        bad(format!(
            "its recorded map (chaoscope:identity) is not one: {e}"
        ))
    })?;
    // Checked as a store's task holds it: a band at a time (a 65536^2 map is no whole-map
    // memory check's business here).
    let band = |g: &Grid| (0, store::chunk_rows(g.width, g.height));
    // Refused as the flag would be, saying the value is the store's, not this command's.
    let runnable = |checked: Result<()>| {
        checked.map_err(|e| match e {
            Error::InvalidSpec { field, reason } => Error::invalid(
                field,
                format!(
                    "in {}'s recorded map (chaoscope:identity): {reason}; start a new store",
                    path.display()
                ),
            ),
            e => e,
        })
    };
    runnable(map.with_band(band(map.grid())).validate())?;
    let (grid, mirrors) = (*map.grid(), map.mirrors());
    // The arrays as the recorded map makes them, and its mirrored chunks as it pairs them.
    if (grid.width, grid.height) != (store.width, store.height) {
        return Err(bad(format!(
            "its map is {}x{} but its arrays are {}x{}: start a new store",
            grid.width, grid.height, store.width, store.height
        )));
    }
    if info.mirrored != store::pairs_mirrored(&grid, mirrors) {
        return Err(bad(format!(
            "chaoscope:mirrored says {}, which its map does not: start a new store",
            info.mirrored
        )));
    }
    Ok((info.command, map))
}

#[derive(Clone, Debug, PartialEq)]
pub struct StatusJob {
    pub store: PathBuf,
    /// Count the tasks in this many (default: what the store was made for).
    pub tiles: Option<u32>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct StatusSummary {
    pub store: PathBuf,
    pub command: String,
    pub width: u32,
    pub height: u32,
    pub chunks: u32,
    pub written: u32,
    /// (first row, rows) of each chunk not written yet.
    pub missing: Vec<(u32, u32)>,
    /// The tasks count, and the indices of the `--tile INDEX/COUNT` runs that would fill
    /// the missing chunks.
    pub tiles: u32,
    pub tiles_to_run: Vec<u32>,
    pub complete: bool,
}

pub fn status(job: &StatusJob) -> Result<StatusSummary> {
    let s = MapStore::open(&job.store)?;
    // The recorded map checked against the arrays first: the units follow from both.
    map_of(&s)?;
    let tiles = job.tiles.unwrap_or(s.info.tiles).max(1);
    let missing = s.missing()?;
    let units = store::units(s.height, s.chunk_rows, s.info.mirrored);
    let mut tiles_to_run: Vec<u32> = units
        .iter()
        .enumerate()
        .filter(|(_, u)| {
            missing.contains(&u.chunk) || u.mirror.is_some_and(|m| missing.contains(&m))
        })
        .map(|(k, _)| k as u32 % tiles)
        .collect();
    tiles_to_run.sort_unstable();
    tiles_to_run.dedup();
    Ok(StatusSummary {
        store: job.store.clone(),
        command: s.info.command.clone(),
        width: s.width,
        height: s.height,
        chunks: s.chunks(),
        written: s.chunks() - missing.len() as u32,
        missing: missing.iter().map(|&c| s.chunk_span(c)).collect(),
        tiles,
        tiles_to_run,
        complete: missing.is_empty(),
    })
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderJob {
    pub store: PathBuf,
    /// The map's spec, from the store's command.
    pub spec: FrameMap,
    pub picture: PictureSpec,
    pub output: PathBuf,
    /// The picture's larger side at most (every n-th pixel each way); None: full size.
    pub max_size: Option<u32>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderSummary {
    pub width: u32,
    pub height: u32,
    /// Every `step`-th pixel of the map each way.
    pub step: u32,
    pub seconds: f64,
    pub output: PathBuf,
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn render(job: &RenderJob, command: String, monitor: &Monitor) -> Result<RenderSummary> {
    super::check_output("output", &job.output, "png")?;
    if job.max_size == Some(0) {
        return Err(Error::invalid("max_size", "must be at least 1"));
    }
    let started = Instant::now();
    let s = MapStore::open(&job.store)?;
    let grid = *job.spec.grid();
    if (s.width, s.height) != (grid.width, grid.height) {
        return Err(Error::Format(format!(
            "{}: the map is {}x{} but its command says {}x{}",
            job.store.display(),
            s.width,
            s.height,
            grid.width,
            grid.height
        )));
    }
    let largest = grid.width.max(grid.height);
    let step = job.max_size.map_or(1, |m| largest.div_ceil(m));
    let (w, h) = (grid.width.div_ceil(step), grid.height.div_ceil(step));
    // The picture's values (4 B a pixel), its colours (3 B) and the PNG encoder's copy (3 B),
    // and a band of the store, against what this process may still take (its address-space
    // limit and its cgroup's too): refused here, not aborted by a failed allocation.
    let need = 10 * w as u64 * h as u64 + 4 * grid.width as u64 * s.chunk_rows as u64;
    let have = crate::spec::available_memory();
    if need > have {
        let fits = ((have / 10) as f64).sqrt() as u64;
        return Err(Error::invalid(
            "max_size",
            format!(
                "a {w}x{h} picture needs about {} MiB but only {} MiB of memory are available to this process: render it at most {fits} pixels on its larger side",
                need >> 20,
                have >> 20
            ),
        ));
    }
    // Every step-th pixel from the first, read one chunk band at a time.
    let mut small = Field::new(w, h, f32::NAN);
    monitor.start("rows", s.chunks() as u64);
    for c in 0..s.chunks() {
        monitor.check()?;
        let (first, rows) = s.chunk_span(c);
        let wanted: Vec<u32> = (first..first + rows).filter(|r| r % step == 0).collect();
        if !wanted.is_empty() {
            let band = s.read_rows(first, rows)?;
            for r in wanted {
                let row = &band[((r - first) * grid.width) as usize..][..grid.width as usize];
                let out = (r / step * w) as usize;
                for (k, v) in row.iter().step_by(step as usize).enumerate() {
                    small.data[out + k] = *v;
                }
            }
        }
        monitor.advance(1);
    }
    monitor.finish();
    let mut notices = Vec::new();
    let missing = s.missing()?.len();
    if missing > 0 {
        notices.push(format!(
            "note: {missing} of {} chunks are not computed yet (NaN, drawn green): `chaoscope status {}`",
            s.chunks(),
            job.store.display()
        ));
    }
    let grid = Grid {
        width: w,
        height: h,
        ..grid
    };
    let picture = job
        .spec
        .on_grid(grid)
        .draw(&small, &job.picture, None, None)?
        .picture;
    let info = RunInfo {
        path: RunPath::Store,
        adapter: None,
    };
    let mut meta = render::provenance(command, &info);
    meta.extend(picture.metadata());
    meta.push((
        "chaoscope:rendered".into(),
        format!(
            "from {}, every {step}th pixel each way",
            job.store.display()
        ),
    ));
    let mut files = Outputs::new();
    files.png(
        &job.output,
        picture.width,
        picture.height,
        &picture.rgb,
        &meta,
    )?;
    files.commit(monitor)?;
    Ok(RenderSummary {
        width: picture.width,
        height: picture.height,
        step,
        seconds: started.elapsed().as_secs_f64(),
        output: job.output.clone(),
        files: vec![job.output.clone()],
        notices,
    })
}
