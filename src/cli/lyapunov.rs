//! `chaoscope lyapunov`: a divergence map, or with single angles a convergence run.

use crate::app::Running;
use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::args::{PhysicalArgs, PictureArgs, PlaneArgs, SampleArgs, VerdictArgs, backend_parser};
use super::parse::{Angles, one_of, parse_number, parse_range, parse_size, parse_tile};
use super::{command_line, json, say};
use crate::app::MapOutputs;
use crate::app::lyapunov::{self, LyapunovMapJob, LyapunovPointJob};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::measure::IndicatorAsked;
use crate::model::State;
use crate::monitor::Monitor;
use crate::spec::MapSpec;
use crate::spec::{
    Grid, Indicator, Integrator, LyapunovSpec, Method, Precision, Range, Stepping, SteppingAsked,
};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Tangent (variational) equations by dual numbers: works in f32.
    Tangent,
    /// A second trajectory --eps away, renormalised back to --eps.
    Twin,
}

#[derive(Args, Debug, Clone)]
pub struct LyapunovArgs {
    /// Grid size: N (square) or WxH, one pendulum per pixel.
    #[arg(long, default_value = "512", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: (u32, u32),
    /// The map's plane; one angle in each of --theta1 and --theta2 (without --x and --y)
    /// makes a single-point convergence run instead.
    #[command(flatten)]
    pub plane: PlaneArgs,
    /// Simulated time (s); the exponent is the mean log stretch rate over [0, t-max].
    #[arg(long, default_value_t = Stepping::DIVERGENCE_T_MAX, value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    /// RK4 time step (s).
    #[arg(long, default_value_t = Stepping::DT, value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    /// Renormalisation interval (s), a multiple of dt.
    #[arg(long, default_value = "0.1", value_parser = parse_number, allow_hyphen_values = true)]
    pub renorm: f64,
    /// How the divergence of nearby starts is measured.
    #[arg(long, value_enum, default_value = "tangent")]
    pub method: MethodArg,
    /// Twin separation (Euclidean in theta1, omega1, theta2, omega2), for --method twin.
    #[arg(long, default_value = "1e-8", value_parser = parse_number, allow_hyphen_values = true)]
    pub eps: f64,
    /// Integrate both halves of a point-symmetric grid with the tangent method instead of
    /// mirroring the top half: the same map, twice the work.
    #[arg(long)]
    pub no_symmetry: bool,
    /// The GPU's precision, f32 or f64 (an adapter with f64); the CPU is always f64.
    /// [default: f32]
    #[arg(long, value_parser = one_of(&Precision::ALL, Precision::name))]
    pub precision: Option<Precision>,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// auto, gpu or cpu. Default: auto for a map, cpu (f64) for a single point.
    #[arg(long, value_parser = backend_parser())]
    pub backend: Option<Backend>,
    /// PNG for a map (default out/lyapunov.png); CSV for a single point (default stdout).
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Raw exponents (1/s) as float32 .npy, shape (height, width), row 0 = top; or a Zarr
    /// v3 store MAP.zarr (as for flip).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Compute only part INDEX of COUNT of a .zarr store's map (as for flip).
    #[arg(long, value_parser = parse_tile)]
    pub tile: Option<(u32, u32)>,
    #[command(flatten)]
    pub verdict: VerdictArgs,
    #[command(flatten)]
    pub sampling: SampleArgs,
    #[command(flatten)]
    pub picture: PictureArgs,
    /// How the state and the tangent vector are stepped: rk4 (fixed --dt) or dp54 (every
    /// pendulum its own steps to --rtol/--atol, at most --dt, landing on each
    /// renormalisation; the tangent method only).
    #[arg(long, default_value = "rk4", value_parser = clap::builder::PossibleValuesParser::new(["rk4", "dp54"]))]
    pub integrator: String,
    /// dp54's relative tolerance per step [default: 1e-5 in f32 on the GPU, else 1e-9].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// dp54's absolute tolerance per step [default: as --rtol].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// The recommended settings for a map whose exponents are right: --precision f64
    /// --integrator dp54 --rtol 1e-9 --atol 1e-9 and steps of at most 0.1 s that land on every
    /// renormalisation (the tangent method; the PNG records those flags).
    #[arg(long, conflicts_with_all = ["precision", "integrator", "rtol", "atol", "dt"])]
    pub accurate: bool,
    /// The colours' range LOW:HIGH in the indicator's unit [default: 0 to the map's 99.5th
    /// percentile for exponents, MEGNO and the FLI; --threshold's log10 to 0 for alignment
    /// indices; 0 to --t-max for their times; the 0.5th to 99.5th percentile otherwise].
    #[arg(long, value_parser = parse_range, allow_hyphen_values = true)]
    pub colour_range: Option<Range>,
    /// What to map of each start (the measures' list: `measure::about`).
    #[arg(long, default_value = "ftle", help = indicator_help(), value_parser = clap::builder::PossibleValuesParser::new(crate::measure::names()))]
    pub indicator: String,
    /// The indicators' options (`measure::options`): --exponent, --gali, --threshold...
    #[command(flatten)]
    pub options: super::args::IndicatorOptions,
    /// All four exponents (1/s, in Gram-Schmidt order, as --exponent) as float32 .npy of shape (4, height, width),
    /// from the same run as the map of --indicator exponent or exponent-sum.
    #[arg(long)]
    pub spectrum: Option<PathBuf>,
}

/// A unit as the summary line writes it ("/s" for 1/s; nothing for a plain number).
fn short_unit(unit: &str) -> &str {
    match unit {
        "1/s" => " /s",
        "s" => " s",
        _ => "",
    }
}

/// What the flags ask for: a map or a convergence run.
#[derive(Clone, Debug, PartialEq)]
pub enum LyapunovJob {
    Map(LyapunovMapJob),
    Point(LyapunovPointJob),
}

/// `--indicator`'s help, from the measures.
fn indicator_help() -> String {
    format!(
        "What to map of each start: {}",
        crate::measure::about(|field| super::names::flag("lyapunov", field))
    )
}

impl LyapunovArgs {
    /// The indicator the flags ask for ([`IndicatorAsked::indicator`]), its defaults those
    /// of an f32 GPU path when `gpu_f32`.
    fn indicator(&self, gpu_f32: bool) -> Result<Indicator> {
        IndicatorAsked {
            name: &self.indicator,
            options: &self.options.0,
            accurate: self.accurate,
            gpu_f32,
        }
        .indicator()
    }

    /// The map the flags ask for over `grid` (`--accurate` expanded by the spec).
    fn spec(&self, grid: Grid, gpu_f32: bool) -> Result<LyapunovSpec> {
        let asked = SteppingAsked {
            precision: self.precision.unwrap_or_default(),
            integrator: &self.integrator,
            rtol: self.rtol,
            atol: self.atol,
            accurate: self.accurate,
            gpu_f32,
        };
        asked.lyapunov(LyapunovSpec {
            params: crate::spec::resolve_on(&self.physical.sources(), &grid)?,
            grid,
            stepping: Stepping {
                dt: self.dt,
                t_max: self.t_max,
            },
            method: match self.method {
                MethodArg::Tangent => Method::Tangent,
                MethodArg::Twin => Method::Twin { eps: self.eps },
            },
            renorm: self.renorm,
            use_symmetry: !self.no_symmetry,
            precision: self.precision.unwrap_or_default(),
            band: None,
            integrator: Integrator::Rk4,
            indicator: self.indicator(gpu_f32)?,
        })
    }

    /// The backend the flags name: `--backend`, else auto for a map and the CPU for a
    /// single start's convergence run.
    pub fn backend(&self) -> Backend {
        let plane = &self.plane;
        let point = plane.x.or(plane.y).is_none()
            && matches!(plane.theta1, Some(Angles::Point(_)))
            && matches!(plane.theta2, Some(Angles::Point(_)));
        self.backend
            .unwrap_or(if point { Backend::Cpu } else { Backend::Auto })
    }

    /// The job of a command line read without running it: its defaults those of the path
    /// the flags name ([`LyapunovArgs::backend`]). A run takes [`LyapunovArgs::job_on`].
    pub fn job(&self) -> Result<LyapunovJob> {
        let named_f32_gpu =
            self.precision.unwrap_or_default() == Precision::F32 && self.backend() != Backend::Cpu;
        self.job_on(named_f32_gpu)
    }

    /// The job, its defaults that depend on the path those of an f32 GPU path when `gpu_f32`
    /// (the lent engine's answer, [`Engine::computes_in_f32`]).
    pub fn job_on(&self, gpu_f32: bool) -> Result<LyapunovJob> {
        let plane = &self.plane;
        let point = match (plane.x.or(plane.y), plane.theta1, plane.theta2) {
            (None, Some(Angles::Point(theta1)), Some(Angles::Point(theta2))) => {
                Some((theta1, theta2))
            }
            (None, Some(Angles::Point(_)), _) => {
                return Err(Error::invalid(
                    "theta2",
                    "must be one angle too when --theta1 is one angle (a single-point run)",
                ));
            }
            (None, _, Some(Angles::Point(_))) => {
                return Err(Error::invalid(
                    "theta1",
                    "must be one angle too when --theta2 is one angle (a single-point run)",
                ));
            }
            _ => None,
        };
        match point {
            None => {
                super::args::no_picture_with_a_store(self.data.as_deref(), self.output.as_deref())?;
                let grid = plane.grid(self.size)?;
                Ok(LyapunovJob::Map(LyapunovMapJob {
                    spec: self.spec(grid, gpu_f32)?,
                    backend: self.backend(),
                    picture: self.picture.spec(),
                    files: MapOutputs {
                        output: self
                            .output
                            .clone()
                            .unwrap_or_else(|| PathBuf::from("out/lyapunov.png")),
                        data: self.data.clone(),
                        resolved: self.verdict.resolved.clone(),
                        show_unresolved: self.verdict.show_unresolved,
                    },
                    tile: self.tile,
                    colour_range: self.colour_range.map(|r| (r.min as f32, r.max as f32)),
                    samples: self.sampling.samples,
                }))
            }
            Some((theta1, theta2)) => {
                if self.sampling.samples != 1 {
                    return Err(Error::invalid(
                        "samples",
                        "is for maps; a single-point run follows its one start",
                    ));
                }
                if self.spectrum.is_some() {
                    return Err(Error::invalid(
                        "spectrum",
                        "is for maps; a single start's running spectrum is its CSV (--indicator exponent)",
                    ));
                }
                if self.data.is_some() || self.tile.is_some() {
                    return Err(Error::invalid(
                        "data",
                        "is for maps; a single-point run writes its CSV to --output",
                    ));
                }
                if self.verdict.resolved.is_some() || self.verdict.show_unresolved {
                    return Err(Error::invalid(
                        "resolved",
                        "is for maps; a single-point run's convergence CSV shows its own",
                    ));
                }
                let start = State {
                    theta1,
                    omega1: plane.omega1.unwrap_or(0.0),
                    theta2,
                    omega2: plane.omega2.unwrap_or(0.0),
                };
                // A convergence run has no grid: the start's own, one pixel.
                let around = |x: f64| Range {
                    min: x - 1e-3,
                    max: x + 1e-3,
                };
                let grid = Grid::angles(
                    1,
                    1,
                    around(theta1),
                    around(theta2),
                    start.omega1,
                    start.omega2,
                );
                Ok(LyapunovJob::Point(LyapunovPointJob {
                    spec: self.spec(grid, gpu_f32)?,
                    start,
                    backend: self.backend(),
                    output: self.output.clone(),
                }))
            }
        }
    }
}

pub fn run(args: &LyapunovArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let (engine, job) =
        super::args::engine_then(args.precision, args.backend(), |f32| args.job_on(f32))?;
    match job {
        LyapunovJob::Map(job) => {
            let command = command_line::lyapunov_map(&job);
            let s = match &args.spectrum {
                Some(path) => {
                    let command = format!("{command} --spectrum {}", path.display());
                    lyapunov::run_spectrum(&job, &Running::new(&engine, command, monitor), path)?
                }
                None => lyapunov::run_map(&job, &Running::new(&engine, command, monitor))?,
            };
            say("lyapunov", &s.notices);
            let q = job.spec.quantity();
            eprintln!(
                "{}x{} on {} in {:.2} s: {:.1} % {} ({} at {} s){}{}{} -> {}",
                s.width,
                s.height,
                s.place,
                s.seconds,
                100.0 * s.counted,
                q.counted_as,
                job.spec.counted_rule(),
                s.t_max,
                super::flip::nan_note(s.nan),
                super::flip::resolved_note(
                    s.resolved,
                    &format!("the same map {} within {}", s.rule, q.vouch_tolerance())
                ),
                match s.range {
                    // A store has no picture, so no colour range.
                    Some((lo, hi)) if !lo.is_nan() => {
                        format!(", colour range {lo:.2}..{hi:.2}{}", short_unit(q.unit))
                    }
                    _ => String::new(),
                },
                s.output.display()
            );
            json(&s)
        }
        LyapunovJob::Point(job) => {
            let command = command_line::lyapunov_point(&job);
            let s = lyapunov::run_point(
                &job,
                &Running::new(&engine, command, monitor),
                &mut std::io::stdout().lock(),
            )?;
            say("lyapunov", &s.notices);
            if let Some(path) = &s.output {
                eprintln!(
                    "{} at {} s: {:.4} -> {}",
                    job.spec.indicator.title(),
                    s.t_max,
                    s.value,
                    path.display()
                );
            }
            json(&s)
        }
    }
}
