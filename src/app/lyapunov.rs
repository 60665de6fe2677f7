//! `lyapunov`: a divergence-family map (the FTLE or another chaos indicator) as PNG and
//! .npy, or the convergence of one start's indicator as CSV (`t,ftle` for the FTLE).

use std::io::Write;
use std::path::PathBuf;

use super::check_output;
use crate::cpu;
use crate::engine::{Backend, MapKernels};
use crate::error::Error;
use crate::error::Result;
use crate::measure::Runs;
use crate::model::State;
use crate::spec::{self, LyapunovSpec, MapSpec};

use super::map::MapSummary;

pub use crate::quantity::CHAOTIC_FTLE;

/// A divergence map to make: the one map job ([`super::map`]) over a [`LyapunovSpec`]; its
/// colours span `colour_range` (1/s), by default 0 to the map's 99.5th percentile
/// ([`crate::measure::FTLE_RANGE`]).
pub type LyapunovMapJob = super::map::MapJob<LyapunovSpec>;

pub use super::map::run as run_map;

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
    /// The indicator's quantity (its name in words).
    pub quantity: &'static str,
    /// Its value at t-max (an alignment index's where it fell below the threshold).
    pub value: f64,
    /// The exponent at t-max (1/s), for the FTLE.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ftle: Option<f64>,
    pub output: Option<PathBuf>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run_point(
    job: &LyapunovPointJob,
    at: &super::Running,
    stdout: &mut dyn Write,
) -> Result<LyapunovPointSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    job.spec.validate_run()?;
    spec::validate_start(&job.start)?;
    if let Some(path) = &job.output {
        check_output("output", path, "csv")?;
    }
    let indicator = job.spec.indicator;
    let measure = indicator.measure();
    let on_engine = measure.runs(indicator) == Runs::Divergence;
    if !on_engine && job.backend == Backend::Gpu {
        return Err(Error::invalid(
            "backend",
            format!(
                "a single start's {} runs on the CPU (f64); leave out [[backend=gpu]]",
                indicator.title()
            ),
        ));
    }
    let mut notices: Vec<String> = engine.notices();
    let path = engine.map_info(&job.spec.grid, job.spec.precision).path;
    notices.extend(job.spec.notices(path));
    // (t, the columns at t) at every renormalisation, and the map's value at t-max.
    let header = measure.columns(indicator);
    let (rows, value) = match on_engine {
        true => {
            let trace = engine.ftle_convergence(&job.spec, job.start, monitor)?;
            let rows = trace.t.iter().zip(&trace.ftle).map(|(&t, &l)| (t, vec![l]));
            (rows.collect(), trace.last())
        }
        false => {
            let mut rows = Vec::new();
            let value = cpu::indicator_run(&job.spec, job.start, Some(monitor), &mut |t, row| {
                rows.push((t, row.to_vec()))
            })?;
            (rows, value)
        }
    };
    if value.is_nan() {
        notices.push(format!(
            "warning: the {} is NaN: the state left the numbers (a smaller time step may help)",
            indicator.title()
        ));
    }
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(w, "# {command}")?;
        writeln!(w, "t,{}", header.join(","))?;
        for (t, row) in &rows {
            let row: Vec<String> = row.iter().map(|x| x.to_string()).collect();
            writeln!(w, "{t},{}", row.join(","))?;
        }
        Ok(())
    };
    super::write_text(job.output.as_deref(), stdout, monitor, write)?;
    Ok(LyapunovPointSummary {
        t_max: job.spec.stepping.t_max,
        quantity: job.spec.quantity().name,
        value,
        ftle: on_engine.then_some(value),
        output: job.output.clone(),
        files: job.output.iter().cloned().collect(),
        notices,
    })
}

/// `job`'s map (an exponent of the spectrum, or their sum) drawn from one run of the four
/// tangent vectors, with all four exponents (1/s, in Gram-Schmidt order) written to `spectrum` as
/// float32 of shape (4, height, width). No verdict and no store: they hold one quantity.
pub fn run_spectrum(
    job: &LyapunovMapJob,
    at: &super::Running,
    spectrum: &std::path::Path,
) -> Result<MapSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    use crate::render::MapPicture;
    let started = std::time::Instant::now();
    let spec = &job.spec;
    let measure = spec.indicator.measure();
    // Its map is read off the four layers (an empty run asks whether it is).
    let empty: [crate::field::Field; 4] =
        std::array::from_fn(|_| crate::field::Field::new(0, 0, 0.0));
    let refused = [
        (
            measure.of_spectrum(spec.indicator, &empty).is_none(),
            "is for the indicators exponent and exponent-sum",
        ),
        (
            job.files.store().is_some() || job.tile.is_some(),
            "writes a .npy beside a map; a Zarr store holds one quantity (leave out [[spectrum]])",
        ),
        (
            job.files.wants_verdict(),
            "has no verdict: leave out [[resolved]] and [[show_unresolved]], or [[spectrum]]",
        ),
    ];
    if let Some((_, why)) = refused.into_iter().find(|r| r.0) {
        return Err(Error::invalid("spectrum", why));
    }
    spec.check_picture(&job.picture, job.colour_range)?;
    super::map::validate(spec, &job.files, job.tile)?;
    check_output("spectrum", spectrum, "npy")?;
    let mut named = job.files.named();
    named.push(("spectrum", spectrum));
    super::checks::check_distinct(&named, &[])?;
    let crate::plan::MapPlan { info, notices, .. } = engine.plan(spec, false)?;
    let layers = engine.spectrum(spec, monitor)?;
    let field = measure
        .of_spectrum(spec.indicator, &layers)
        .expect("checked above: the spectrum's measure");
    let drawn = spec.draw(&field, &job.picture, job.colour_range, None)?;
    super::map::write_map(
        &drawn.picture,
        crate::render::provenance(command, &info),
        drawn.text,
        &job.files,
        &field,
        None,
        monitor,
    )?;
    let (width, height) = (spec.grid.width, spec.grid.height);
    let data: Vec<f32> = layers.iter().flat_map(|l| l.data.iter().copied()).collect();
    crate::render::write_npy_shaped(spectrum, &[4, height as u64, width as u64], &data)?;
    let mut files = job.files.files();
    files.push(spectrum.to_path_buf());
    Ok(MapSummary {
        quantity: spec.quantity(),
        width,
        height,
        place: info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        counted: field.data.iter().filter(|&&x| spec.counted(x)).count() as f64
            / field.data.len().max(1) as f64,
        nan: field.data.iter().filter(|x| x.is_nan()).count(),
        resolved: None,
        rule: String::new(),
        t_max: spec.stepping.t_max,
        mirrored: spec.mirrors() && spec.grid.point_symmetric(),
        range: drawn.range,
        output: job.files.output.clone(),
        files,
        notices,
    })
}
