//! `flip`: a flip-time map as a PNG, optionally with the raw times as .npy.

use std::path::PathBuf;
use std::time::Instant;

use super::{MapOutputs, check_finer, write_map};
use crate::engine::Backend;
use crate::error::Result;
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
        super::check_tile(self.tile, &self.files)?;
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
    let (field, mask) =
        super::flip_and_verdict(&engine, &job.spec, job.files.wants_verdict(), monitor)?;
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

/// `job` into its Zarr store at `path` ([`super::store::fill_store`]).
fn run_store(
    job: &FlipJob,
    path: &std::path::Path,
    command: String,
    monitor: &Monitor,
) -> Result<FlipSummary> {
    use super::store::{StoreFill, fill_store, missing_note};
    let started = Instant::now();
    let (engine, info, mut notices) =
        super::map_engine(job.backend, job.spec.precision, &job.spec.grid)?;
    if info.backend == "gpu" {
        job.spec.integrator.validate(Precision::F32)?;
    }
    let grid = job.spec.grid;
    let finer_of = |spec: &FlipSpec| verdict::finer_flip(spec, engine.has_f64());
    let verdict = job.files.wants_verdict();
    if verdict
        && engine
            .map_info(&grid, finer_of(&job.spec).precision)
            .backend
            == "gpu"
    {
        check_finer(finer_of(&job.spec).integrator.validate(Precision::F32))?;
    }
    let fill = StoreFill {
        path,
        grid,
        command,
        tile: job.tile,
        symmetric: job.spec.use_symmetry,
        verdict,
        quantity: ("flip time", "s"),
    };
    let filled = fill_store(
        &fill,
        monitor,
        |rows, monitor| {
            let spec = FlipSpec {
                band: Some(rows),
                ..job.spec
            };
            super::flip_and_verdict(&engine, &spec, verdict, monitor)
        },
        f32::is_finite,
    )?;
    notices.extend(missing_note(&filled, path));
    let share = |n: usize| n as f64 / filled.pixels.max(1) as f64;
    Ok(FlipSummary {
        width: grid.width,
        height: grid.height,
        place: info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        flipped: share(filled.counted),
        nan: filled.nan,
        resolved: verdict.then(|| share(filled.resolved)),
        rule: verdict::flip_rule_short(&job.spec, &finer_of(&job.spec)),
        t_max: job.spec.stepping.t_max,
        output: path.to_path_buf(),
        files: vec![path.to_path_buf()],
        notices,
    })
}
