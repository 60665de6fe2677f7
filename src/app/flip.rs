//! `flip`: a flip-time map as a PNG, optionally with the raw times as .npy.

use std::path::PathBuf;
use std::time::Instant;

use super::{MapOutputs, check_finer, write_map};
use crate::engine::{Backend, Engine};
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
}

impl FlipJob {
    pub fn validate(&self) -> Result<()> {
        self.spec.validate()?;
        self.files.validate()?;
        if self.files.wants_verdict() {
            check_finer(verdict::finer_flip(&self.spec, true).validate())?;
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
    let started = Instant::now();
    let engine = Engine::new(job.backend)?;
    let mut notices: Vec<String> = engine.notices();
    let info = engine.map_info(&job.spec.grid, job.spec.precision);
    notices.extend(super::precision_notices(
        &engine,
        job.backend,
        job.spec.precision,
        &job.spec.grid,
        &info,
    )?);
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
