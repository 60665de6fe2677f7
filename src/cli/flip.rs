//! `chaoscope flip`.

use std::path::PathBuf;

use clap::Args;

use super::args::{GridArgs, PhysicalArgs, PictureArgs, StepArgs, VerdictArgs, backend_parser};
use super::parse::one_of;
use super::{command_line, json, say};
use crate::app::MapOutputs;
use crate::app::flip::{self, FlipJob};
use crate::engine::Backend;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Precision};

#[derive(Args, Debug, Clone)]
pub struct FlipArgs {
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
    /// PNG to write.
    #[arg(long, default_value = "out/flip.png")]
    pub output: PathBuf,
    /// Raw flip times (s) as float32 .npy, shape (height, width), row 0 = top, inf = never.
    #[arg(long)]
    pub data: Option<PathBuf>,
    #[command(flatten)]
    pub verdict: VerdictArgs,
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
    #[arg(long, default_value = "f32", value_parser = one_of(&Precision::ALL, Precision::name))]
    pub precision: Precision,
}

impl FlipArgs {
    pub fn job(&self) -> Result<FlipJob> {
        Ok(FlipJob {
            spec: FlipSpec {
                early_exit: !self.full,
                use_symmetry: !(self.full || self.no_symmetry),
                precision: self.precision,
                ..FlipSpec::new(
                    self.physical.sources().resolve()?,
                    self.grid.grid(),
                    self.step.stepping(),
                )
            },
            backend: self.backend,
            picture: self.picture.spec(),
            files: MapOutputs {
                output: self.output.clone(),
                data: self.data.clone(),
                resolved: self.verdict.resolved.clone(),
                show_unresolved: self.verdict.show_unresolved,
            },
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
    let job = args.job()?;
    let s = flip::run(&job, command_line::flip(&job), monitor)?;
    say(&s.notices);
    eprintln!(
        "{}x{} on {} in {:.2} s: {:.1} % flipped within {} s{}{} -> {}",
        s.width,
        s.height,
        s.place,
        s.seconds,
        100.0 * s.flipped,
        s.t_max,
        nan_note(s.nan),
        resolved_note(
            s.resolved,
            "the same map at half the step within 1 % or 0.02 s"
        ),
        s.output.display()
    );
    json(&s)
}
