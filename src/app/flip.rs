//! `flip`: a flip-time map as a PNG, optionally with the raw times as .npy.

use std::path::PathBuf;
use std::time::Instant;

use super::{MapOutputs, check_finer, write_map};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::{self, PictureSpec};
use crate::spec::{FlipSpec, Precision};
use crate::verdict;

#[derive(Clone, Debug, PartialEq)]
pub struct FlipJob {
    pub spec: FlipSpec,
    pub backend: Backend,
    pub picture: PictureSpec,
    /// The PNG, the raw flip times (s; inf = never), the verdict.
    pub files: MapOutputs,
    /// With a .zarr store: compute only part `index` of `count` of it.
    pub tile: Option<(u32, u32)>,
}

impl FlipJob {
    pub fn validate(&self) -> Result<()> {
        self.spec.validate()?;
        self.files.validate()?;
        if self.files.wants_verdict() {
            check_finer(verdict::finer_flip(&self.spec, true).validate())?;
        }
        if let Some((index, count)) = self.tile {
            if self.files.store().is_none() {
                return Err(Error::invalid(
                    "tile",
                    "needs a store to fill: --data MAP.zarr",
                ));
            }
            if count == 0 || index >= count {
                return Err(Error::invalid(
                    "tile",
                    format!("{index}/{count}: INDEX/COUNT with 0 <= INDEX < COUNT"),
                ));
            }
        }
        Ok(())
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct FlipSummary {
    pub width: u32,
    pub height: u32,
    /// Where it ran: the adapter's name or "the CPU".
    pub place: String,
    pub seconds: f64,
    /// Fraction of the pixels that flipped within t-max.
    pub flipped: f64,
    /// Pixels whose state became infinite or NaN before flipping (NaN in the data).
    pub nan: usize,
    /// The fraction of the pixels resolved, when the verdict was asked for.
    pub resolved: Option<f64>,
    /// How the verdict's finer map differs, in a few words.
    pub rule: String,
    pub t_max: f64,
    pub output: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

/// Runs `job`; `command` (the line that reproduces it) goes into the PNG.
pub fn run(job: &FlipJob, command: String, monitor: &Monitor) -> Result<FlipSummary> {
    job.validate()?;
    if let Some(store) = job.files.store() {
        return run_store(job, store, command, monitor);
    }
    let started = Instant::now();
    let (engine, info, notices) =
        super::map_engine(job.backend, job.spec.precision, &job.spec.grid)?;
    if info.backend == "gpu" {
        job.spec.integrator.validate(Precision::F32)?;
    }
    let finer = verdict::finer_flip(&job.spec, engine.has_f64());
    if job.files.wants_verdict() && engine.map_info(&finer.grid, finer.precision).backend == "gpu" {
        check_finer(finer.integrator.validate(Precision::F32))?;
    }
    let field = engine.flip_map(&job.spec, monitor)?;
    let mask = if job.files.wants_verdict() {
        let finer = engine.flip_map(&finer, monitor)?;
        Some(verdict::grid_mask(
            &job.spec.grid,
            &field,
            &finer,
            verdict::flip_times_agree,
        ))
    } else {
        None
    };
    let shown = mask.as_deref().filter(|_| job.files.show_unresolved);
    let picture = render::flip_picture(&field, &job.spec, &job.picture, shown)?;
    let meta = render::provenance(command, &info);
    let rule = shown
        .map(|_| {
            (
                "chaoscope:resolved-rule".to_string(),
                verdict::flip_rule(&job.spec, &finer),
            )
        })
        .into_iter()
        .collect();
    write_map(
        &picture,
        meta,
        rule,
        &job.files,
        &field,
        mask.as_deref(),
        monitor,
    )?;
    let flipped = field.data.iter().filter(|t| t.is_finite()).count();
    Ok(FlipSummary {
        width: field.width,
        height: field.height,
        place: info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        flipped: flipped as f64 / field.data.len() as f64,
        nan: field.data.iter().filter(|t| t.is_nan()).count(),
        resolved: mask.as_deref().map(verdict::fraction),
        rule: verdict::flip_rule_short(&job.spec, &finer),
        t_max: job.spec.stepping.t_max,
        output: job.files.output.clone(),
        files: job.files.files(),
        notices,
    })
}

/// `job` into its Zarr store at `path`, unit by unit (memory holds one), skipping the units
/// already written: a failed or pre-empted task is simply run again.
fn run_store(
    job: &FlipJob,
    path: &std::path::Path,
    command: String,
    monitor: &Monitor,
) -> Result<FlipSummary> {
    use crate::render::store::{self, MapStore, StoreInfo};
    let started = Instant::now();
    let (engine, info, mut notices) =
        super::map_engine(job.backend, job.spec.precision, &job.spec.grid)?;
    if info.backend == "gpu" {
        job.spec.integrator.validate(Precision::F32)?;
    }
    let (index, count) = job.tile.unwrap_or((0, 1));
    let grid = job.spec.grid;
    let ours = StoreInfo {
        command,
        version: env!("CARGO_PKG_VERSION").to_string(),
        tiles: count,
        mirrored: store::pairs_mirrored(&grid, job.spec.use_symmetry),
        resolved: job.files.wants_verdict(),
    };
    let store = MapStore::create_or_open("data", path, &grid, &ours, ("flip time", "s"))?;
    let all = store::units(grid.height, store.chunk_rows, store.info.mirrored);
    let mut todo = Vec::new();
    for unit in store::task_units(&all, index, count) {
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
    let (mut pixels, mut flipped, mut nan, mut resolved) = (0usize, 0usize, 0usize, 0usize);
    let finer_of = |spec: &FlipSpec| verdict::finer_flip(spec, engine.has_f64());
    if store.info.resolved
        && engine
            .map_info(&grid, finer_of(&job.spec).precision)
            .backend
            == "gpu"
    {
        check_finer(finer_of(&job.spec).integrator.validate(Precision::F32))?;
    }
    for unit in &todo {
        monitor.check()?;
        // A chunk that is its own mirror image (the middle one, on a symmetric grid):
        // its top half, the rest reflected, as a whole map does.
        let (first, rows) = store.chunk_span(unit.chunk);
        let own_mirror = store.info.mirrored && unit.mirror.is_none();
        let integrated = if own_mirror { rows.div_ceil(2) } else { rows };
        let spec = FlipSpec {
            band: Some((first, integrated)),
            ..job.spec
        };
        let band = |spec: &FlipSpec| -> Result<crate::field::Field> {
            let top = engine.flip_map(spec, &monitor.quiet())?;
            if !own_mirror {
                return Ok(top);
            }
            let mut whole = crate::field::Field::new(top.width, rows, 0.0);
            whole.data[..top.data.len()].copy_from_slice(&top.data);
            whole.mirror_below(integrated);
            Ok(whole)
        };
        let field = band(&spec)?;
        let mask = if store.info.resolved {
            let finer = band(&finer_of(&spec))?;
            Some(verdict::grid_mask(
                &grid,
                &field,
                &finer,
                verdict::flip_times_agree,
            ))
        } else {
            None
        };
        if let Some(m) = &mask {
            resolved +=
                m.iter().filter(|&&v| v == 1).count() * (1 + unit.mirror.is_some() as usize);
        }
        store.write_unit(*unit, &field, mask.as_deref())?;
        let copies = 1 + unit.mirror.is_some() as usize;
        pixels += field.data.len() * copies;
        flipped += field.data.iter().filter(|t| t.is_finite()).count() * copies;
        nan += field.data.iter().filter(|t| t.is_nan()).count() * copies;
        monitor.advance(rows_of(unit));
    }
    monitor.finish();
    let missing = store.missing()?.len();
    if missing > 0 {
        notices.push(format!(
            "note: {missing} of the store's {} chunks are still to be computed (`chaoscope status {}`)",
            store.chunks(),
            path.display()
        ));
    }
    Ok(FlipSummary {
        width: grid.width,
        height: grid.height,
        place: info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        flipped: flipped as f64 / pixels.max(1) as f64,
        nan,
        resolved: store
            .info
            .resolved
            .then(|| resolved as f64 / pixels.max(1) as f64),
        rule: verdict::flip_rule_short(&job.spec, &finer_of(&job.spec)),
        t_max: job.spec.stepping.t_max,
        output: path.to_path_buf(),
        files: vec![path.to_path_buf()],
        notices,
    })
}
