//! `lyapunov`: a divergence (FTLE) map as PNG and .npy, or the convergence of one start's
//! exponent as CSV `t,ftle`.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use super::{MapOutputs, check_output, map, write_map};
use crate::engine::{Backend, Engine, MapKernels};
use crate::error::Result;
use crate::model::State;
use crate::monitor::Monitor;
use crate::render::{self, Colormap, PictureSpec};
use crate::spec::{self, LyapunovSpec, MapSpec};
use crate::verdict;

pub use crate::quantity::CHAOTIC_FTLE;

#[derive(Clone, Debug, PartialEq)]
pub struct LyapunovMapJob {
    pub spec: LyapunovSpec,
    pub backend: Backend,
    pub picture: PictureSpec,
    /// The PNG, the raw exponents (1/s), the verdict.
    pub files: MapOutputs,
    /// With a .zarr store: compute only part `index` of `count` of it.
    pub tile: Option<(u32, u32)>,
    /// The colours' range (1/s, low, high); None: 0 to the map's 99.5th percentile
    /// ([`render::ftle_range`]).
    pub colour_range: Option<(f32, f32)>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct LyapunovMapSummary {
    pub width: u32,
    pub height: u32,
    pub place: String,
    pub seconds: f64,
    /// Fraction of the pixels whose exponent exceeds [`CHAOTIC_FTLE`].
    pub chaotic: f64,
    /// Pixels whose exponent is NaN (the integration left the numbers).
    pub nan: usize,
    /// The fraction of the pixels resolved, when the verdict was asked for.
    pub resolved: Option<f64>,
    /// How the verdict's finer map differs, in a few words.
    pub rule: String,
    pub t_max: f64,
    /// The colour range (1/s).
    pub range: (f32, f32),
    pub output: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run_map(
    job: &LyapunovMapJob,
    command: String,
    monitor: &Monitor,
) -> Result<LyapunovMapSummary> {
    map::validate(&job.spec, &job.files, job.tile)?;
    if let Some((lo, hi)) = job.colour_range
        && !(lo.is_finite() && hi.is_finite() && lo < hi)
    {
        return Err(crate::error::Error::invalid(
            "colour_range",
            format!("{lo}:{hi} must be LOW:HIGH with LOW < HIGH (1/s)"),
        ));
    }
    let started = Instant::now();
    let verdict = job.files.wants_verdict();
    if let Some(path) = job.files.store() {
        let made = map::make_store(
            &job.spec,
            job.backend,
            path,
            command,
            job.tile,
            verdict,
            monitor,
        )?;
        let filled = &made.made;
        let share = |n: usize| n as f64 / filled.pixels.max(1) as f64;
        let grid = job.spec.grid;
        return Ok(LyapunovMapSummary {
            width: grid.width,
            height: grid.height,
            place: made.info.place().to_string(),
            seconds: started.elapsed().as_secs_f64(),
            chaotic: share(filled.counted),
            nan: filled.nan,
            resolved: verdict.then(|| share(filled.resolved)),
            rule: made.rule,
            t_max: job.spec.stepping.t_max,
            range: (f32::NAN, f32::NAN),
            output: path.to_path_buf(),
            files: vec![path.to_path_buf()],
            notices: made.notices,
        });
    }
    let made = map::make(&job.spec, job.backend, verdict, monitor)?;
    let (field, mask) = &made.made;
    let range = job
        .colour_range
        .unwrap_or_else(|| render::ftle_range(field));
    let shown = mask.as_deref().filter(|_| job.files.show_unresolved);
    let picture = render::lyapunov_picture(field, &job.spec, range, &job.picture, shown)?;
    let colour_range = (
        "chaoscope:colour-range".into(),
        format!(
            "FTLE {} .. {} 1/s, {}, linear (low = regular)",
            range.0,
            range.1,
            job.picture.colormap.unwrap_or(Colormap::Magma).name()
        ),
    );
    let mut extra = vec![colour_range];
    if shown.is_some() {
        extra.push(("chaoscope:resolved-rule".into(), made.rule_in_full.clone()));
    }
    write_map(
        &picture,
        render::provenance(command, &made.info),
        extra,
        &job.files,
        field,
        mask.as_deref(),
        monitor,
    )?;
    let chaotic = field
        .data
        .iter()
        .filter(|&&x| (job.spec.quantity().counted)(x))
        .count();
    Ok(LyapunovMapSummary {
        width: field.width,
        height: field.height,
        place: made.info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        chaotic: chaotic as f64 / field.data.len() as f64,
        nan: field.data.iter().filter(|x| x.is_nan()).count(),
        resolved: mask.as_deref().map(verdict::fraction),
        rule: made.rule,
        t_max: job.spec.stepping.t_max,
        range,
        output: job.files.output.clone(),
        files: job.files.files(),
        notices: made.notices,
    })
}

/// The convergence of one start's exponent. `spec.grid` is not used.
#[derive(Clone, Debug, PartialEq)]
pub struct LyapunovPointJob {
    pub spec: LyapunovSpec,
    pub start: State,
    pub backend: Backend,
    /// The CSV; None writes to the `stdout` given to [`run_point`].
    pub output: Option<PathBuf>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct LyapunovPointSummary {
    pub t_max: f64,
    /// The exponent at t-max (1/s).
    pub ftle: f64,
    pub output: Option<PathBuf>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run_point(
    job: &LyapunovPointJob,
    command: String,
    monitor: &Monitor,
    stdout: &mut dyn Write,
) -> Result<LyapunovPointSummary> {
    job.spec.validate_run()?;
    spec::validate_start(&job.start)?;
    if let Some(path) = &job.output {
        check_output("output", path, "csv")?;
    }
    let engine = Engine::new(job.backend)?;
    let mut notices: Vec<String> = engine.notices();
    let path = engine.map_info(&job.spec.grid, job.spec.precision).path;
    notices.extend(job.spec.notices(path));
    let trace = engine.ftle_convergence(&job.spec, job.start, monitor)?;
    if trace.last().is_nan() {
        notices.push(
            "warning: the exponent is NaN: the state left the numbers (a smaller time step may help)"
                .into(),
        );
    }
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(w, "# {command}")?;
        writeln!(w, "t,ftle")?;
        for (t, l) in trace.t.iter().zip(&trace.ftle) {
            writeln!(w, "{t},{l}")?;
        }
        Ok(())
    };
    super::write_text(job.output.as_deref(), stdout, monitor, write)?;
    Ok(LyapunovPointSummary {
        t_max: job.spec.stepping.t_max,
        ftle: trace.last(),
        output: job.output.clone(),
        files: job.output.iter().cloned().collect(),
        notices,
    })
}
