//! `status` and `render`: what a Zarr store of a map still lacks, and its picture, made from
//! the store in bounded memory (one chunk band and the picture at a time).

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::engine::RunInfo;
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::render::store::{self, MapStore};
use crate::render::{self, Outputs, PictureSpec};
use crate::spec::{FlipSpec, Grid};

/// The command a store was made by (to be parsed back into its job by the command line).
pub fn store_command(path: &Path) -> Result<String> {
    Ok(MapStore::open(path)?.info.command)
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
    pub spec: FlipSpec,
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
    let grid = job.spec.grid;
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
    let spec = FlipSpec {
        grid: Grid {
            width: w,
            height: h,
            ..grid
        },
        ..job.spec
    };
    let picture = render::flip_picture(&small, &spec, &job.picture, None)?;
    let info = RunInfo {
        backend: "zarr store",
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
