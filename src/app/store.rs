//! `status` and `render`: what a Zarr store of a map still lacks, and its picture, made from
//! the store in bounded memory (one chunk band and the picture at a time).

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::engine::{Path as RunPath, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::render::MapPicture;
use crate::render::store::{self, MapStore};
use crate::render::{self, Outputs, PictureSpec};
use crate::spec::{AnyMap, Grid, MapSpec};

/// The map a store holds (from its identity, as data, checked like any spec) and the command
/// that made it. The command is shown, never parsed: it may name files, and a store may come
/// from anyone.
pub fn stored_map(path: &Path) -> Result<(String, AnyMap)> {
    map_of(&MapStore::open(path)?)
}

/// The map `store` holds ([`stored_map`]), checked against its arrays.
fn map_of(store: &MapStore) -> Result<(String, AnyMap)> {
    let path = store.path();
    let info = store.info.clone();
    let bad = |why: String| Error::Format(format!("{}: {why}", path.display()));
    let map = info
        .identity
        .get("map")
        .cloned()
        .ok_or_else(|| bad("records no map (chaoscope:identity); start a new store".into()))?;
    let map: AnyMap = serde_json::from_value(map).map_err(|e| {
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
    pub spec: AnyMap,
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
