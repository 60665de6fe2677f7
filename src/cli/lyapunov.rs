//! `chaoscope lyapunov`: a divergence map, or with single angles a convergence run.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::args::{PhysicalArgs, PictureArgs, VerdictArgs, backend_parser};
use super::parse::{
    Angles, one_of, parse_angles, parse_number, parse_range, parse_size, parse_tile,
};
use super::{command_line, json, say};
use crate::app::MapOutputs;
use crate::app::lyapunov::{self, CHAOTIC_FTLE, LyapunovMapJob, LyapunovPointJob};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::model::State;
use crate::monitor::Monitor;
use crate::quantity::FTLE;
use crate::spec::{Grid, Integrator, LyapunovSpec, Method, Precision, Range, Stepping};

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
    /// theta1 range along x, MIN:MAX in rad; or one angle for a single-point convergence run.
    #[arg(long, default_value = "-pi:pi", value_parser = parse_angles, allow_hyphen_values = true)]
    pub theta1: Angles,
    /// theta2 range along y (top = MAX), MIN:MAX in rad; or one angle.
    #[arg(long, default_value = "-pi:pi", value_parser = parse_angles, allow_hyphen_values = true)]
    pub theta2: Angles,
    /// Initial angular velocity of the upper arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    /// Initial angular velocity of the lower arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
    /// Simulated time (s); the exponent is the mean log stretch rate over [0, t-max].
    #[arg(long, default_value = "20", value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    /// RK4 time step (s).
    #[arg(long, default_value = "0.01", value_parser = parse_number, allow_hyphen_values = true)]
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
    /// The colours' range LOW:HIGH (1/s) [default: 0 to the map's 99.5th percentile].
    #[arg(long, value_parser = parse_range, allow_hyphen_values = true)]
    pub colour_range: Option<Range>,
}

/// What the flags ask for: a map or a convergence run.
#[derive(Clone, Debug, PartialEq)]
pub enum LyapunovJob {
    Map(LyapunovMapJob),
    Point(LyapunovPointJob),
}

impl LyapunovArgs {
    /// The integrator the flags ask for (tolerances only with dp54).
    fn integrator(&self) -> Result<Integrator> {
        let gpu_f32 = self.precision.unwrap_or_default() == Precision::F32
            && self.backend != Some(Backend::Cpu);
        super::flip::integrator_of(&self.integrator, self.rtol, self.atol, gpu_f32)
    }

    /// The map the flags ask for over `grid` (`--accurate` expanded by the spec).
    fn spec(&self, grid: Grid) -> Result<LyapunovSpec> {
        if self.accurate && self.method == MethodArg::Twin {
            return Err(Error::invalid(
                "accurate",
                "steps the tangent method with dp54; --method twin has fixed steps only",
            ));
        }
        let integrator = match self.accurate {
            true => Integrator::Rk4,
            false => self.integrator()?,
        };
        let spec = LyapunovSpec {
            params: self.physical.sources().resolve()?,
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
            integrator,
        };
        Ok(if self.accurate { spec.accurate() } else { spec })
    }

    pub fn job(&self) -> Result<LyapunovJob> {
        let (width, height) = self.size;
        match (self.theta1, self.theta2) {
            (Angles::Range(theta1), Angles::Range(theta2)) => {
                super::args::no_picture_with_a_store(self.data.as_deref(), self.output.as_deref())?;
                let grid = Grid {
                    width,
                    height,
                    theta1,
                    theta2,
                    omega1: self.omega1,
                    omega2: self.omega2,
                };
                Ok(LyapunovJob::Map(LyapunovMapJob {
                    spec: self.spec(grid)?,
                    backend: self.backend.unwrap_or(Backend::Auto),
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
                }))
            }
            (Angles::Point(theta1), Angles::Point(theta2)) => {
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
                    omega1: self.omega1,
                    theta2,
                    omega2: self.omega2,
                };
                // A convergence run has no grid: the start's own, one pixel.
                let around = |x: f64| Range {
                    min: x - 1e-3,
                    max: x + 1e-3,
                };
                let grid = Grid {
                    width: 1,
                    height: 1,
                    theta1: around(theta1),
                    theta2: around(theta2),
                    omega1: self.omega1,
                    omega2: self.omega2,
                };
                Ok(LyapunovJob::Point(LyapunovPointJob {
                    spec: self.spec(grid)?,
                    start,
                    backend: self.backend.unwrap_or(Backend::Cpu),
                    output: self.output.clone(),
                }))
            }
            (Angles::Point(_), Angles::Range(_)) => Err(Error::invalid(
                "theta2",
                "must be one angle too when --theta1 is one angle (a single-point run)",
            )),
            (Angles::Range(_), Angles::Point(_)) => Err(Error::invalid(
                "theta1",
                "must be one angle too when --theta2 is one angle (a single-point run)",
            )),
        }
    }
}

pub fn run(args: &LyapunovArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    match args.job()? {
        LyapunovJob::Map(job) => {
            super::args::f32_on_the_cpu(args.precision, job.backend);
            let s = lyapunov::run_map(&job, command_line::lyapunov_map(&job), monitor)?;
            say(&s.notices);
            eprintln!(
                "{}x{} on {} in {:.2} s: {:.1} % chaotic (FTLE > {CHAOTIC_FTLE} /s at {} s){}{}{} -> {}",
                s.width,
                s.height,
                s.place,
                s.seconds,
                100.0 * s.counted,
                s.t_max,
                super::flip::nan_note(s.nan),
                super::flip::resolved_note(
                    s.resolved,
                    &format!("the same map {} within {}", s.rule, FTLE.tolerance)
                ),
                match s.range {
                    // A store has no picture, so no colour range.
                    Some((lo, hi)) if !lo.is_nan() => format!(", colour range {lo:.2}..{hi:.2} /s"),
                    _ => String::new(),
                },
                s.output.display()
            );
            json(&s)
        }
        LyapunovJob::Point(job) => {
            super::args::f32_on_the_cpu(args.precision, job.backend);
            let command = command_line::lyapunov_point(&job);
            let s = lyapunov::run_point(&job, command, monitor, &mut std::io::stdout().lock())?;
            say(&s.notices);
            if let Some(path) = &s.output {
                eprintln!(
                    "FTLE at {} s: {:.4} /s -> {}",
                    s.t_max,
                    s.ftle,
                    path.display()
                );
            }
            json(&s)
        }
    }
}
