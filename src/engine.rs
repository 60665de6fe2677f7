//! Chooses the path a run takes: the GPU when an adapter exists, else the CPU.

use crate::cpu;
use crate::error::{Error, Result};
use crate::field::Field;
use crate::gpu::{FlipTimeKernel, GpuContext, LyapunovKernel};
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, LyapunovSpec};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The GPU when an adapter exists, else the CPU (with a one-line notice).
    Auto,
    /// The GPU; fails when there is no adapter.
    Gpu,
    /// The f64 CPU reference, on all cores.
    Cpu,
}

/// Which path ran, for the user and the PNG metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    pub backend: &'static str,
    pub adapter: Option<String>,
    /// Said once to the user, e.g. that auto fell back to the CPU.
    pub notice: Option<String>,
}

impl RunInfo {
    fn cpu(notice: Option<String>) -> Self {
        RunInfo {
            backend: "cpu",
            adapter: None,
            notice,
        }
    }
}

/// A GPU context for `backend`, or None for the CPU path, with the notice to give.
pub fn resolve(backend: Backend) -> Result<(Option<GpuContext>, Option<String>)> {
    match backend {
        Backend::Cpu => Ok((None, None)),
        Backend::Gpu => Ok((Some(GpuContext::new()?), None)),
        Backend::Auto => match GpuContext::new() {
            Ok(ctx) => Ok((Some(ctx), None)),
            Err(Error::NoAdapter) => Ok((
                None,
                Some("note: no GPU adapter found (install a Vulkan driver, e.g. mesa-vulkan-drivers); running on the CPU".into()),
            )),
            Err(e) => Err(e),
        },
    }
}

/// The flip-time map of `spec` on the chosen backend.
pub fn flip_map(spec: &FlipSpec, backend: Backend, monitor: &Monitor) -> Result<(Field, RunInfo)> {
    spec.validate()?;
    let (ctx, notice) = resolve(backend)?;
    match ctx {
        Some(ctx) => {
            let field = FlipTimeKernel::new(&ctx).run(&ctx, spec, monitor)?;
            let info = RunInfo {
                backend: "gpu",
                adapter: Some(ctx.adapter_name()),
                notice,
            };
            Ok((field, info))
        }
        None => Ok((cpu::flip_map(spec, monitor)?, RunInfo::cpu(notice))),
    }
}

/// The divergence (FTLE) map of `spec` on the chosen backend.
pub fn lyapunov_map(
    spec: &LyapunovSpec,
    backend: Backend,
    monitor: &Monitor,
) -> Result<(Field, RunInfo)> {
    spec.validate()?;
    let (ctx, notice) = resolve(backend)?;
    match ctx {
        Some(ctx) => {
            let field = LyapunovKernel::new(&ctx, spec.method).run(&ctx, spec, monitor)?;
            let info = RunInfo {
                backend: "gpu",
                adapter: Some(ctx.adapter_name()),
                notice,
            };
            Ok((field, info))
        }
        None => Ok((cpu::ftle_map(spec, monitor)?, RunInfo::cpu(notice))),
    }
}
