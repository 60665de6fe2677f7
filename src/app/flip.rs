//! `flip`: a flip-time map as a PNG, optionally with the raw times as .npy.

use std::path::PathBuf;
use std::time::Instant;

use super::{MapOutputs, map, write_map};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::{self, PictureSpec};
use crate::spec::{FlipMeasure, FlipSpec, MapSpec};
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
        if self.spec.measure == FlipMeasure::Kind && self.picture.colormap.is_some() {
            return Err(Error::invalid(
                "colormap",
                "the flip kind has a colour a class of its own; leave out --colormap",
            ));
        }
        map::validate(&self.spec, &self.files, self.tile)
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
    let started = Instant::now();
    let verdict = job.files.wants_verdict();
    if let Some(store) = job.files.store() {
        let made = map::make_store(
            &job.spec,
            job.backend,
            store,
            command,
            job.tile,
            verdict,
            monitor,
        )?;
        let filled = &made.made;
        let share = |n: usize| n as f64 / filled.pixels.max(1) as f64;
        let grid = job.spec.grid;
        return Ok(FlipSummary {
            width: grid.width,
            height: grid.height,
            place: made.info.place().to_string(),
            seconds: started.elapsed().as_secs_f64(),
            flipped: share(filled.counted),
            nan: filled.nan,
            resolved: verdict.then(|| share(filled.resolved)),
            rule: made.rule,
            t_max: job.spec.stepping.t_max,
            output: store.to_path_buf(),
            files: vec![store.to_path_buf()],
            notices: made.notices,
        });
    }
    let made = map::make(&job.spec, job.backend, verdict, monitor)?;
    let (field, mask) = &made.made;
    let shown = mask.as_deref().filter(|_| job.files.show_unresolved);
    let picture = render::flip_picture(field, &job.spec, &job.picture, shown)?;
    let meta = render::provenance(command, &made.info);
    let rule = shown
        .map(|_| {
            (
                "chaoscope:resolved-rule".to_string(),
                made.rule_in_full.clone(),
            )
        })
        .into_iter()
        .collect();
    write_map(
        &picture,
        meta,
        rule,
        &job.files,
        field,
        mask.as_deref(),
        monitor,
    )?;
    let flipped = field
        .data
        .iter()
        .filter(|&&t| (job.spec.quantity().counted)(t))
        .count();
    Ok(FlipSummary {
        width: field.width,
        height: field.height,
        place: made.info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        flipped: flipped as f64 / field.data.len() as f64,
        nan: field.data.iter().filter(|t| t.is_nan()).count(),
        resolved: mask.as_deref().map(verdict::fraction),
        rule: made.rule,
        t_max: job.spec.stepping.t_max,
        output: job.files.output.clone(),
        files: job.files.files(),
        notices: made.notices,
    })
}
