//! `chaoscope boundary`.

use crate::app::Running;
use std::path::PathBuf;

use clap::Args;

use super::args::{PhysicalArgs, PlaneArgs, StepArgs, backend_parser};
use super::parse::{one_of, parse_range, parse_u32};
use super::{command_line, json, say};
use crate::app::boundary::{self, BoundaryClass, BoundaryJob};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::measure::IndicatorAsked;
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, LyapunovSpec, Precision};

#[derive(Args, Debug, Clone)]
#[command(mut_arg("t_max", |a| a.default_value("20")))]
pub struct BoundaryArgs {
    /// The outcome whose boundary is measured: flip-kind (which arm flips first and which
    /// way, or never), flipped (within --t-max or not) or chaotic (by --indicator's rule).
    #[arg(long, default_value = "flip-kind", value_parser = one_of(&BoundaryClass::ALL, BoundaryClass::name))]
    pub class: BoundaryClass,
    /// Pairs of starts drawn at each eps (rounded up to whole rows of 256); each pair costs
    /// two pendulums and the verdict's finer runs (six maps' work for flip-kind).
    #[arg(long, default_value = "20000", value_parser = parse_u32, allow_hyphen_values = true)]
    pub pairs: u32,
    /// Smallest and largest perturbation, MIN:MAX as fractions of the plane's width or height
    /// (0 < MIN < MAX <= 0.25).
    #[arg(long, default_value = "1e-5:1e-1", value_parser = parse_range, allow_hyphen_values = true)]
    pub eps: crate::spec::Range,
    /// Perturbation sizes, evenly spaced in log between the two (3 to 40).
    #[arg(long, default_value = "9", value_parser = parse_u32, allow_hyphen_values = true)]
    pub levels: u32,
    /// The chaotic class's indicator, by its rule (the measures' list:
    /// `measure::classifying`) [default: megno].
    #[arg(long, help = classifying_help(), value_parser = clap::builder::PossibleValuesParser::new(crate::measure::classifying().into_iter().map(|(name, _)| name)))]
    pub indicator: Option<String>,
    /// The chaotic class's renormalisation interval (s).
    #[arg(long, value_parser = super::parse::parse_number, allow_hyphen_values = true)]
    pub renorm: Option<f64>,
    /// Seed of the starts (the same seed draws the same starts on every machine and path).
    #[arg(long, default_value = "1", value_parser = parse_u32, allow_hyphen_values = true)]
    pub seed: u32,
    #[command(flatten)]
    pub plane: PlaneArgs,
    #[command(flatten)]
    pub step: StepArgs,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// f32 or f64 (the default: perturbations down to 1e-5 of the plane need it).
    #[arg(long, default_value = "f64", value_parser = one_of(&Precision::ALL, Precision::name))]
    pub precision: Precision,
    /// auto, gpu or cpu (f64).
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    /// The log-log plot of f(eps) with the fit (PNG).
    #[arg(long, default_value = "out/boundary.png")]
    pub output: PathBuf,
    /// The counts at each eps as CSV: eps,pairs,resolved,uncertain,fraction.
    #[arg(long)]
    pub data: Option<PathBuf>,
}

/// `--indicator`'s help, from the measures.
fn classifying_help() -> String {
    let rules: Vec<String> = crate::measure::classifying()
        .into_iter()
        .map(|(name, rule)| format!("{name} ({rule})"))
        .collect();
    format!(
        "The chaotic class's indicator, a start chaotic by its rule: {} [default: megno]",
        rules.join(", ")
    )
}

impl BoundaryArgs {
    pub fn job(&self) -> Result<BoundaryJob> {
        let chaotic = self.class == BoundaryClass::Chaotic;
        for (flag, given) in [
            ("indicator", self.indicator.is_some()),
            ("renorm", self.renorm.is_some()),
        ] {
            if given && !chaotic {
                return Err(Error::invalid(flag, "is for --class chaotic"));
            }
        }
        let spec = FlipSpec {
            precision: self.precision,
            ..{
                let grid = self.plane.grid((1, 1))?;
                FlipSpec::new(
                    crate::spec::resolve_on(&self.physical.sources(), &grid)?,
                    grid,
                    self.step.stepping(),
                )
            }
        };
        Ok(BoundaryJob {
            spec,
            divergence: LyapunovSpec {
                renorm: self.renorm.unwrap_or(0.1),
                use_symmetry: false,
                precision: self.precision,
                // Clap took one of the classifying names: options take their defaults.
                indicator: IndicatorAsked::named(self.indicator.as_deref().unwrap_or("megno"))
                    .indicator()?,
                ..LyapunovSpec::new(spec.params, spec.grid, spec.stepping)
            },
            class: self.class,
            pairs: self.pairs,
            eps: (self.eps.min, self.eps.max),
            levels: self.levels,
            seed: self.seed,
            backend: self.backend,
            output: self.output.clone(),
            data: self.data.clone(),
        })
    }
}

pub fn run(args: &BoundaryArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job()?;
    let engine = super::args::lent_engine(None, job.backend)?;
    let at = Running::new(&engine, command_line::boundary(&job), monitor);
    let s = boundary::run(&job, &at)?;
    say("boundary", &s.notices);
    for l in &s.levels {
        eprintln!(
            "eps {:.2e}: {} of {} resolved pairs differ (f = {:.3e})",
            l.eps,
            l.uncertain,
            l.resolved,
            l.fraction()
        );
    }
    match &s.fit {
        Some(f) => eprintln!(
            "{} boundary over {} s on {} in {:.1} s: alpha = {:.3} +- {:.3}, D = 2 - alpha = {:.3} (fitted over eps {:.1e}..{:.1e}, {} levels, reduced chi2 {:.2}); {} pairs left out unresolved -> {}",
            s.class,
            s.t_max,
            s.place,
            s.seconds,
            f.alpha,
            f.alpha_se,
            f.dimension(),
            f.eps_range.0,
            f.eps_range.1,
            f.levels,
            f.reduced_chi2,
            s.unresolved,
            job.output.display()
        ),
        None => eprintln!(
            "too few uncertain pairs to fit alpha (at least {} at three eps): widen --eps or draw more --pairs -> {}",
            crate::boundary::MIN_UNCERTAIN,
            job.output.display()
        ),
    }
    json(&s)
}
