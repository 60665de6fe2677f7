//! `chaoscope boundary`: the uncertainty exponent of a flip map's class boundary, from seeded
//! pairs of starts eps apart at several eps, on the GPU where there is one
//! ([`crate::boundary`]).

use std::path::PathBuf;

use plotters::prelude::*;

use crate::boundary::{Fit, Level, count, eps_levels, fit, level_seed};
use crate::engine::MapKernels;
use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::Outputs;
use crate::render::chart::{self, err as plot_err};
use crate::spec::{FlipMeasure, FlipSpec, Grid, LyapunovSpec, MapSpec, Sampling};

/// What decides a start's outcome.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryClass {
    /// Which arm flips first and which way, or never (`flip --colour-by kind`'s classes).
    FlipKind,
    /// Whether it flips within t-max.
    Flipped,
    /// Chaotic or regular by a chaos indicator's rule ([`BoundaryJob::divergence`]: the
    /// FTLE above 0.5 /s, MEGNO above 4, the FLI above 5).
    Chaotic,
}

impl BoundaryClass {
    pub const ALL: [BoundaryClass; 3] = [
        BoundaryClass::FlipKind,
        BoundaryClass::Flipped,
        BoundaryClass::Chaotic,
    ];

    pub fn name(self) -> &'static str {
        match self {
            BoundaryClass::FlipKind => "flip-kind",
            BoundaryClass::Flipped => "flipped",
            BoundaryClass::Chaotic => "chaotic",
        }
    }
}

/// Most pairs a level may draw (the pairs of a level are one map of twice as many starts).
pub const MAX_PAIRS: u32 = 1 << 22;

/// Pairs side by side in one row of a level's map.
const PAIRS_A_ROW: u32 = 256;

#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryJob {
    /// The map whose class boundary is measured: its plane, physics and steps (its size is
    /// the pairs').
    pub spec: FlipSpec,
    pub class: BoundaryClass,
    /// The chaotic class's map (its indicator, renormalisation; the plane, physics and steps
    /// are `spec`'s).
    pub divergence: LyapunovSpec,
    /// Pairs drawn at each eps (rounded up to whole rows of 256).
    pub pairs: u32,
    /// The smallest and largest eps, fractions of the plane's width or height.
    pub eps: (f64, f64),
    pub levels: u32,
    pub seed: u32,
    pub backend: Backend,
    /// The log-log plot (PNG).
    pub output: PathBuf,
    /// The levels as CSV `eps,pairs,resolved,uncertain,fraction`.
    pub data: Option<PathBuf>,
}

#[derive(Debug, serde::Serialize)]
pub struct BoundarySummary {
    pub class: &'static str,
    pub t_max: f64,
    pub place: String,
    pub seconds: f64,
    pub levels: Vec<Level>,
    /// Pairs left out at all levels because an outcome was not resolved.
    pub unresolved: u64,
    pub fit: Option<Fit>,
    /// D = 2 - alpha and its standard error (alpha's).
    pub dimension: Option<(f64, f64)>,
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

impl BoundaryJob {
    /// The map of level `k`'s pairs at `eps`.
    pub fn level_spec(&self, k: u32, eps: f64) -> FlipSpec {
        let rows = self.pairs.div_ceil(PAIRS_A_ROW);
        let grid = Grid {
            width: 2 * PAIRS_A_ROW.min(self.pairs),
            height: rows,
            sampling: Sampling::Pairs {
                seed: level_seed(self.seed, k),
                eps,
            },
            ..self.spec.grid
        };
        FlipSpec {
            grid,
            measure: match self.class {
                BoundaryClass::FlipKind => FlipMeasure::Kind,
                BoundaryClass::Flipped | BoundaryClass::Chaotic => FlipMeasure::Time,
            },
            use_symmetry: false,
            ..self.spec
        }
    }

    /// The chaotic class's map of level `k`'s pairs.
    pub fn divergence_spec(&self, k: u32, eps: f64) -> LyapunovSpec {
        LyapunovSpec {
            params: self.spec.params,
            grid: self.level_spec(k, eps).grid,
            stepping: self.spec.stepping,
            precision: self.spec.precision,
            use_symmetry: false,
            ..self.divergence
        }
    }

    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_PAIRS).contains(&self.pairs) {
            return Err(Error::invalid(
                "pairs",
                format!("{} must be between 1 and {MAX_PAIRS}", self.pairs),
            ));
        }
        let (lo, hi) = self.eps;
        if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi && hi <= 0.25) {
            return Err(Error::invalid(
                "eps",
                format!("{lo}:{hi} must be MIN:MAX with 0 < MIN < MAX <= 0.25 (of the plane)"),
            ));
        }
        if !(3..=40).contains(&self.levels) {
            return Err(Error::invalid(
                "levels",
                format!(
                    "{} must be between 3 and 40 (a slope needs three points)",
                    self.levels
                ),
            ));
        }
        super::check_output("output", &self.output, "png")?;
        if let Some(d) = &self.data {
            super::check_output("data", d, "csv")?;
            super::checks::check_distinct(&[("output", &self.output), ("data", d)], &[])?;
        }
        for (k, eps) in eps_levels(lo, hi, self.levels).into_iter().enumerate() {
            match self.class {
                BoundaryClass::Chaotic => self.divergence_spec(k as u32, eps).validate()?,
                _ => self.level_spec(k as u32, eps).validate()?,
            }
        }
        Ok(())
    }
}

pub fn run(job: &BoundaryJob, at: &super::Running) -> Result<BoundarySummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    job.validate()?;
    let started = std::time::Instant::now();
    let all = eps_levels(job.eps.0, job.eps.1, job.levels);
    let (levels, info, mut notices) = match job.class {
        BoundaryClass::Chaotic => {
            let spec = |k, eps| job.divergence_spec(k, eps);
            measure(engine, &all, spec, |s, v| s.counted(v) as u32, monitor)?
        }
        BoundaryClass::FlipKind => {
            let spec = |k, eps| job.level_spec(k, eps);
            measure(engine, &all, spec, |_, v| v as u32, monitor)?
        }
        BoundaryClass::Flipped => {
            let spec = |k, eps| job.level_spec(k, eps);
            measure(engine, &all, spec, |_, v| v.is_finite() as u32, monitor)?
        }
    };
    // A level is one map of whole rows of pairs: the pairs asked for, rounded up.
    if let Some(l) = levels.first().filter(|l| l.pairs != job.pairs as u64) {
        notices.insert(
            0,
            format!(
                "note: {} pairs a level drawn for the {} asked (whole rows of {PAIRS_A_ROW})",
                l.pairs, job.pairs
            ),
        );
    }
    let fitted = fit(&levels);
    let mut out = Outputs::new();
    plot(&mut out, job, &levels, fitted.as_ref(), &command)?;
    if let Some(path) = &job.data {
        let mut csv = format!("# {command}\neps,pairs,resolved,uncertain,fraction\n");
        for l in &levels {
            csv += &format!(
                "{},{},{},{},{}\n",
                l.eps,
                l.pairs,
                l.resolved,
                l.uncertain,
                l.fraction()
            );
        }
        out.write(path, |w| {
            use std::io::Write;
            w.write_all(csv.as_bytes()).map_err(Error::Io)
        })?;
    }
    out.commit(monitor)?;
    Ok(BoundarySummary {
        class: job.class.name(),
        t_max: job.spec.stepping.t_max,
        place: info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        unresolved: levels.iter().map(|l| l.pairs - l.resolved).sum(),
        dimension: fitted.as_ref().map(|f| (f.dimension(), f.alpha_se)),
        levels,
        fit: fitted,
        files: std::iter::once(job.output.clone())
            .chain(job.data.clone())
            .collect(),
        notices,
    })
}

/// Each level's counts: its pairs' map and verdict (`spec(k, eps)`), each start's class by
/// `class` (NaN: none), pairs counted where both classes are resolved. The engine and its
/// notices are the finest level's (the one most likely to need f64).
fn measure<S: MapKernels>(
    engine: &Engine,
    all: &[f64],
    spec: impl Fn(u32, f64) -> S,
    class: impl Fn(&S, f32) -> u32,
    monitor: &Monitor,
) -> Result<(Vec<Level>, crate::engine::RunInfo, Vec<String>)> {
    let first = engine.plan(&spec(0, all[0]), true)?;
    let (info, notices) = (first.info, first.notices);
    let mut levels = Vec::new();
    for (k, &eps) in all.iter().enumerate() {
        monitor.check()?;
        let s = spec(k as u32, eps);
        let (field, mask) = engine.planned_map(&engine.plan(&s, true)?, monitor)?;
        let mask = mask.expect("asked for");
        let classes: Vec<[Option<u32>; 2]> = field
            .data
            .chunks_exact(2)
            .zip(mask.chunks_exact(2))
            .map(|(v, m)| {
                let of = |i: usize| (!v[i].is_nan() && m[i] == 1).then(|| class(&s, v[i]));
                [of(0), of(1)]
            })
            .collect();
        levels.push(count(eps, &classes));
    }
    Ok((levels, info, notices))
}

/// f(eps) on log-log axes with binomial error bars (grey: too few uncertain pairs to fit)
/// and the fitted line.
fn plot(
    out: &mut Outputs,
    job: &BoundaryJob,
    levels: &[Level],
    fitted: Option<&Fit>,
    command: &str,
) -> Result<()> {
    let title = match fitted {
        Some(f) => format!(
            "uncertainty exponent α = {:.3} ± {:.3}, boundary dimension D = 2 - α = {:.3}",
            f.alpha,
            f.alpha_se,
            f.dimension()
        ),
        None => "too few uncertain pairs to fit α (widen [[eps]] or draw more [[pairs]])".into(),
    };
    let shown: Vec<&Level> = levels.iter().filter(|l| l.uncertain > 0).collect();
    let (lo, hi) = (job.eps.0 / 1.5, job.eps.1 * 1.5);
    let f_min = shown
        .iter()
        .map(|l| l.fraction())
        .fold(1.0, f64::min)
        .max(1e-7)
        / 3.0;
    let text = [
        // tEXt is Latin-1: the Greek letters spelt out.
        ("Title".into(), title.replace('α', "alpha")),
        ("chaoscope:command".into(), command.into()),
    ];
    chart::plot(out, &job.output, (900, 640), &text, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(&title, ("sans-serif", 18))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((lo..hi).log_scale(), (f_min..1.0).log_scale())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("ε (fraction of the plane's width or height)")
            .y_desc(format!(
                "f(ε): share of resolved pairs of differing {}",
                match job.class {
                    BoundaryClass::FlipKind => "flip kind".to_string(),
                    BoundaryClass::Flipped => "flip within t-max".to_string(),
                    BoundaryClass::Chaotic => format!("chaos ({})", job.divergence.counted_rule()),
                }
            ))
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()
            .map_err(plot_err)?;
        let ink = RGBColor(30, 30, 30);
        for l in &shown {
            let f = l.fraction();
            let se = (f * (1.0 - f) / l.resolved.max(1) as f64).sqrt();
            let colour = if l.counts() {
                ink
            } else {
                RGBColor(160, 160, 160)
            };
            chart
                .draw_series(std::iter::once(ErrorBar::new_vertical(
                    l.eps,
                    (f - se).max(f_min),
                    f,
                    f + se,
                    colour.filled(),
                    8,
                )))
                .map_err(plot_err)?;
        }
        if let Some(fit) = fitted {
            let line = |e: f64| (fit.intercept + fit.alpha * e.ln()).exp();
            let (a, b) = fit.eps_range;
            chart
                .draw_series(LineSeries::new(
                    [(a, line(a)), (b, line(b))],
                    RGBColor(214, 39, 40).stroke_width(2),
                ))
                .map_err(plot_err)?;
        }
        Ok(())
    })
}
