//! `chaoscope flip`.

use crate::app::Running;
use std::path::PathBuf;

use clap::Args;

use super::args::{
    GridArgs, PhysicalArgs, PictureArgs, SampleArgs, StepArgs, VerdictArgs, backend_parser,
};
use super::parse::{one_of, parse_number, parse_tile};
use super::{command_line, json, say};
use crate::app::MapOutputs;
use crate::app::flip::{self, FlipJob};
use crate::engine::Backend;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::{FlipMeasure, FlipSpec, Integrator, MapSpec, Precision, SteppingAsked};

#[derive(Args, Debug, Clone)]
pub struct FlipArgs {
    /// What the map shows of each start's first flip: time (s) or kind (which arm flips first
    /// and which way, a colour a class with a legend; --data then holds the class codes: 0
    /// never, 1 upper arm past +pi, 2 upper past -pi, 3 lower past +pi, 4 lower past -pi, NaN
    /// where the state left the numbers; rk4 only).
    #[arg(long, default_value = "time", value_parser = one_of(&FlipMeasure::ALL, FlipMeasure::name))]
    pub colour_by: FlipMeasure,
    #[command(flatten)]
    pub grid: GridArgs,
    #[command(flatten)]
    pub step: StepArgs,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// auto: the GPU when an adapter exists, else the CPU (with a notice); gpu; cpu (f64).
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    #[command(flatten)]
    pub picture: PictureArgs,
    /// PNG to write [default: out/flip.png; none with a .zarr store: `chaoscope render`
    /// makes it].
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Raw flip times (s) as float32 .npy, shape (height, width), row 0 = top, inf = never;
    /// or a Zarr v3 store MAP.zarr (written chunk by chunk, resumable, shared by --tile tasks).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Compute only part INDEX of COUNT of a .zarr store's map (whole chunks; tasks on
    /// different machines fill one store), e.g. --tile $SLURM_ARRAY_TASK_ID/4.
    #[arg(long, value_parser = parse_tile)]
    pub tile: Option<(u32, u32)>,
    #[command(flatten)]
    pub verdict: VerdictArgs,
    #[command(flatten)]
    pub sampling: SampleArgs,
    /// Benchmarking: integrate every pixel for every step (no early exit, no skipped starts,
    /// no mirrored half).
    #[arg(long)]
    pub full: bool,
    /// Integrate both halves of a point-symmetric grid (theta ranges centred on 0, released
    /// from rest) instead of mirroring the top half: the same map, twice the work.
    #[arg(long)]
    pub no_symmetry: bool,
    /// The GPU's floating-point precision: f32 (fastest) or f64 (an adapter with f64, e.g.
    /// lavapipe; elsewhere auto runs f64 on the CPU). The CPU is always f64.
    /// [default: f32]
    #[arg(long, value_parser = one_of(&Precision::ALL, Precision::name))]
    pub precision: Option<Precision>,
    /// How each pendulum is stepped: rk4 (fixed --dt), dp54 (Dormand-Prince 5(4): every
    /// pendulum takes its own steps to --rtol/--atol; --dt is then its first and largest step)
    /// or dop853 (Dormand-Prince 8(5,3), the same way: fewer, longer steps at tight tolerances).
    #[arg(long, default_value = "rk4", value_parser = clap::builder::PossibleValuesParser::new(Integrator::NAMES))]
    pub integrator: String,
    /// dp54's and dop853's relative tolerance per step [default: 1e-5 in f32 on the GPU, else 1e-9; 1e-5
    /// is the least f32 allows].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// dp54's and dop853's absolute tolerance per step (rad, rad/s) [default: as --rtol].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// The recommended settings for a map right on >= 99.5 % of its pixels: --precision f64
    /// --integrator dp54 --rtol 1e-9 --atol 1e-9 --dt 0.05 (the PNG records those flags).
    #[arg(long, conflicts_with_all = ["precision", "integrator", "rtol", "atol", "dt"])]
    pub accurate: bool,
}

impl FlipArgs {
    /// The map the flags ask for (`--accurate` expanded by the spec), its defaults those of
    /// an f32 GPU path when `gpu_f32`.
    fn spec(&self, gpu_f32: bool) -> Result<FlipSpec> {
        let asked = SteppingAsked {
            precision: self.precision.unwrap_or_default(),
            integrator: &self.integrator,
            rtol: self.rtol,
            atol: self.atol,
            accurate: self.accurate,
            gpu_f32,
        };
        let grid = self.grid.grid()?;
        asked.flip(FlipSpec {
            measure: self.colour_by,
            early_exit: !self.full,
            use_symmetry: !(self.full || self.no_symmetry),
            ..FlipSpec::new(
                crate::spec::resolve_on(&self.physical.sources(), &grid)?,
                grid,
                self.step.stepping(),
            )
        })
    }

    /// The job of a command line read without running it: its defaults those of the path
    /// the flags name (the GPU unless `--backend cpu`). A run takes [`FlipArgs::job_on`].
    pub fn job(&self) -> Result<FlipJob> {
        let named_f32_gpu =
            self.precision.unwrap_or_default() == Precision::F32 && self.backend != Backend::Cpu;
        self.job_on(named_f32_gpu)
    }

    /// The job, its defaults that depend on the path those of an f32 GPU path when `gpu_f32`
    /// (the lent engine's answer, [`Engine::computes_in_f32`]).
    pub fn job_on(&self, gpu_f32: bool) -> Result<FlipJob> {
        let spec = self.spec(gpu_f32)?;
        super::args::no_picture_with_a_store(self.data.as_deref(), self.output.as_deref())?;
        Ok(FlipJob {
            spec,
            backend: self.backend,
            picture: self.picture.spec(),
            files: MapOutputs {
                output: self
                    .output
                    .clone()
                    .unwrap_or_else(|| PathBuf::from("out/flip.png")),
                data: self.data.clone(),
                resolved: self.verdict.resolved.clone(),
                show_unresolved: self.verdict.show_unresolved,
            },
            tile: self.tile,
            colour_range: None,
            samples: self.sampling.samples,
        })
    }
}

/// ", X % resolved (rule)" when the verdict was asked for.
pub fn resolved_note(resolved: Option<f64>, rule: &str) -> String {
    resolved
        .map(|f| format!(", {:.1} % resolved ({rule})", 100.0 * f))
        .unwrap_or_default()
}

/// ", N pixels NaN (...)" when there are any.
pub fn nan_note(nan: usize) -> String {
    if nan == 0 {
        String::new()
    } else {
        format!(", {nan} pixels NaN (the integration left the numbers; green in the PNG)")
    }
}

pub fn run(args: &FlipArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let (engine, job) =
        super::args::engine_then(args.precision, args.backend, |f32| args.job_on(f32))?;
    let at = Running::new(&engine, command_line::flip(&job), monitor);
    let s = flip::run(&job, &at)?;
    say("flip", &s.notices);
    eprintln!(
        "{}x{} on {} in {:.2} s: {:.1} % flipped within {} s{}{} -> {}",
        s.width,
        s.height,
        s.place,
        s.seconds,
        100.0 * s.counted,
        s.t_max,
        nan_note(s.nan),
        resolved_note(
            s.resolved,
            &format!(
                "the same map {} within {}",
                s.rule,
                job.spec.quantity().vouch_tolerance()
            )
        ),
        s.output.display()
    );
    json(&s)
}
