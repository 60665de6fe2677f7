//! The one place that picks the CPU or the GPU, for every kind of run: maps, convergence
//! runs, trajectories and ensembles. An [`Engine`] is made once per command from the chosen
//! [`Backend`]; its GPU kernels are built on first use and kept.

use rayon::prelude::*;

use crate::cpu;
use crate::error::{Error, Result};
use crate::field::{Convergence, Field};
use crate::gpu::{GpuContext, Kernels, STEPS_PER_DISPATCH};
use crate::measure::Runs;
use crate::model::{Params, Positions, State};
use crate::monitor::Monitor;
use crate::spec::{
    Chunk, EnsembleSpec, FlipMeasure, FlipSpec, Grid, Integrator, Keep, LyapunovSpec, MapSpec,
    Method, Precision, Range, Stepping,
};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The GPU when an adapter exists, else the CPU (with a one-line notice).
    Auto,
    /// The GPU; fails when there is no adapter.
    Gpu,
    /// The f64 CPU reference, on all cores.
    Cpu,
}

impl Backend {
    pub const ALL: [Backend; 3] = [Backend::Auto, Backend::Gpu, Backend::Cpu];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}

pub use crate::field::{Path, RunInfo};

/// How each quantity's map runs on either path: the kernels' table, one impl a quantity.
pub trait MapKernels: MapSpec {
    /// The map on the GPU's kernel in `precision` (the engine has checked f64 is there).
    fn on_gpu(&self, k: &Kernels, precision: Precision, monitor: &Monitor) -> Result<Field>;
    /// The map by the f64 CPU twin.
    fn on_cpu(&self, monitor: &Monitor) -> Result<Field>;
    /// What to tell the user about this map on `path`, beyond its precision.
    fn notices(&self, _path: Path) -> Vec<String> {
        Vec::new()
    }
}

impl MapKernels for FlipSpec {
    fn on_gpu(&self, k: &Kernels, precision: Precision, monitor: &Monitor) -> Result<Field> {
        k.flip(precision).run(&k.ctx, self, monitor)
    }

    fn on_cpu(&self, monitor: &Monitor) -> Result<Field> {
        match (self.measure, self.integrator) {
            (FlipMeasure::Kind, _) => cpu::flip_kind_map(self, monitor),
            (FlipMeasure::Time, Integrator::Rk4) => cpu::flip_map(self, monitor),
            (FlipMeasure::Time, Integrator::Dp54 { .. } | Integrator::Dop853 { .. }) => {
                cpu::flip_map_adaptive(self, monitor)
            }
        }
    }
}

impl MapKernels for LyapunovSpec {
    fn on_gpu(&self, k: &Kernels, precision: Precision, monitor: &Monitor) -> Result<Field> {
        match self.indicator.measure().runs(self.indicator) {
            Runs::Divergence => k
                .lyapunov(self.method, precision)
                .run(&k.ctx, self, monitor),
            Runs::Indicators(_) => k.indicators(precision).run(&k.ctx, self, monitor),
        }
    }

    fn on_cpu(&self, monitor: &Monitor) -> Result<Field> {
        match self.indicator.measure().runs(self.indicator) {
            Runs::Divergence => cpu::ftle_map(self, monitor),
            Runs::Indicators(_) => cpu::indicator_map(self, monitor),
        }
    }

    /// What the measure tells of these physics (`Measure::notices`); f32 cannot resolve a
    /// twin separation much below 1e-6 of the state: say so.
    fn notices(&self, path: Path) -> Vec<String> {
        let told = self
            .indicator
            .measure()
            .notices(self.indicator, &self.params);
        if !told.is_empty() {
            return told;
        }
        match self.method {
            Method::Twin { eps } if eps < 1e-4 && path == Path::Gpu(Precision::F32) => {
                vec![format!(
                    "note: a twin separation of {eps} is close to f32 round-off on the GPU (~1e-7 of the state): the twin reads noise; use the tangent method, a larger separation, or the CPU"
                )]
            }
            _ => Vec::new(),
        }
    }
}

/// The chosen path: a GPU with its kernels, or the CPU.
pub struct Engine {
    gpu: Option<Kernels>,
    notice: Option<String>,
    /// The precision of trajectories and ensembles on the GPU (maps carry their own).
    precision: Precision,
    /// The backend it was made for (f64 asked of a GPU without it is an error only when the
    /// GPU itself was asked for).
    asked: Backend,
}

impl Engine {
    /// The engine for `backend`: `Auto` falls back to the CPU without an adapter (see
    /// [`Engine::notice`]), `Gpu` fails.
    pub fn new(backend: Backend) -> Result<Self> {
        let (gpu, notice) = match backend {
            Backend::Cpu => (None, None),
            Backend::Gpu => (Some(GpuContext::new()?), None),
            Backend::Auto => match GpuContext::new() {
                Ok(ctx) => (Some(ctx), None),
                Err(Error::NoAdapter) => (
                    None,
                    Some("note: no GPU adapter found (install a Vulkan driver, e.g. mesa-vulkan-drivers); running on the CPU".into()),
                ),
                Err(e) => return Err(e),
            },
        };
        Ok(Engine {
            gpu: gpu.map(Kernels::new),
            notice,
            precision: Precision::F32,
            asked: backend,
        })
    }

    /// The engine for `backend` whose trajectories and ensembles run in `precision`
    /// ([`Engine::with_precision`]): what a door makes and lends to a command that runs them.
    pub fn in_precision(backend: Backend, precision: Precision) -> Result<Self> {
        Engine::new(backend)?.with_precision(precision, backend)
    }

    /// The engine on an existing GPU context.
    pub fn on_gpu(ctx: GpuContext) -> Self {
        Engine {
            gpu: Some(Kernels::new(ctx)),
            notice: None,
            precision: Precision::F32,
            asked: Backend::Gpu,
        }
    }

    /// f64 asked of a GPU without it: an error naming `precision` when the GPU was asked
    /// for (`backend`), else the note to give, the work then running on the CPU in f64.
    pub fn check_f64(&self, precision: Precision, backend: Backend) -> Result<Option<String>> {
        match &self.gpu {
            Some(k) if precision == Precision::F64 && !k.ctx.has_f64() => {
                let reason = format!(
                    "f64: the GPU adapter {} has no f64 (SHADER_F64); use the CPU backend (f64) or auto",
                    k.ctx.adapter_name()
                );
                if backend == Backend::Gpu {
                    return Err(Error::invalid("precision", reason));
                }
                Ok(Some(format!("note: {reason}; it runs on the CPU in f64")))
            }
            _ => Ok(None),
        }
    }

    /// Trajectories and ensembles in `precision` on the GPU ([`Engine::check_f64`] decides
    /// what f64 on an adapter without it means).
    pub fn with_precision(mut self, precision: Precision, backend: Backend) -> Result<Self> {
        self.precision = precision;
        if let Some(note) = self.check_f64(precision, backend)? {
            self.notice = Some(note);
            self.gpu = None;
        }
        Ok(self)
    }

    /// The backend it was made for.
    pub fn asked(&self) -> Backend {
        self.asked
    }

    /// What to tell the user once about the choice (auto fell back to the CPU).
    pub fn notice(&self) -> Option<&str> {
        self.notice.as_deref()
    }

    /// The notice as the start of a run's list of notices.
    pub fn notices(&self) -> Vec<String> {
        self.notice.iter().cloned().collect()
    }

    /// Whether f64 maps run here without leaving the chosen path: on the CPU, or on a GPU
    /// with f64.
    pub fn has_f64(&self) -> bool {
        self.gpu.as_ref().is_none_or(|k| k.ctx.has_f64())
    }

    /// Whether a map asked for in `precision` runs in f32 arithmetic here (on a GPU): the
    /// defaults that depend on the path (f32's tolerance floor, the alignment threshold's)
    /// are read from it, by the door that lends this engine, never guessed from its flags.
    pub fn computes_in_f32(&self, precision: Precision) -> bool {
        self.gpu.is_some() && precision == Precision::F32
    }

    /// The GPU and its kernels, if this engine has one.
    pub fn gpu(&self) -> Option<&Kernels> {
        self.gpu.as_ref()
    }

    /// The path of single runs, trajectories and ensembles.
    pub fn info(&self) -> RunInfo {
        match &self.gpu {
            Some(k) => RunInfo {
                path: Path::Gpu(self.precision),
                adapter: Some(k.ctx.adapter_name()),
            },
            None => RunInfo::CPU,
        }
    }

    /// The GPU and the precision a map runs in: f64 when asked for or when the grid is finer
    /// than f32 resolves, if the adapter has f64; None for the CPU (f64).
    fn map_gpu(&self, grid: &Grid, precision: Precision) -> Option<(&Kernels, Precision)> {
        let k = self.gpu.as_ref()?;
        if precision == Precision::F32 && !grid.needs_f64() {
            Some((k, Precision::F32))
        } else if k.ctx.has_f64() {
            Some((k, Precision::F64))
        } else {
            None
        }
    }

    /// The path a map over `grid` asked for in `precision` takes.
    pub fn map_info(&self, grid: &Grid, precision: Precision) -> RunInfo {
        match self.map_gpu(grid, precision) {
            Some((k, precision)) => RunInfo {
                path: Path::Gpu(precision),
                adapter: Some(k.ctx.adapter_name()),
            },
            None => RunInfo::CPU,
        }
    }

    /// The map of a validated `spec`, whichever quantity it measures.
    pub fn map<S: MapKernels>(&self, spec: &S, monitor: &Monitor) -> Result<Field> {
        match self.map_gpu(spec.grid(), spec.precision()) {
            Some((k, precision)) => spec.on_gpu(k, precision, monitor),
            None => spec.on_cpu(monitor),
        }
    }

    /// All four Lyapunov exponents of a validated `spec` (an exponent or their sum), from one
    /// run of four tangent vectors a pixel.
    pub fn spectrum(&self, spec: &LyapunovSpec, monitor: &Monitor) -> Result<[Field; 4]> {
        match self.map_gpu(&spec.grid, spec.precision) {
            Some((k, precision)) => k.indicators(precision).spectrum(&k.ctx, spec, monitor),
            None => cpu::spectrum_map(spec, monitor),
        }
    }

    /// The running FTLE of one start (`spec`'s grid is not used).
    pub fn ftle_convergence(
        &self,
        spec: &LyapunovSpec,
        start: State,
        monitor: &Monitor,
    ) -> Result<Convergence> {
        match &self.gpu {
            Some(k) => {
                // A one-pixel grid whose centre is the start.
                let around = |x: f64| Range {
                    min: x - 1e-3,
                    max: x + 1e-3,
                };
                let one = LyapunovSpec {
                    grid: Grid::angles(
                        1,
                        1,
                        around(start.theta1),
                        around(start.theta2),
                        start.omega1,
                        start.omega2,
                    ),
                    ..*spec
                };
                let precision = match k.ctx.has_f64() {
                    true => spec.precision,
                    false => Precision::F32,
                };
                k.lyapunov(spec.method, precision)
                    .convergence(&k.ctx, &one, monitor)
            }
            None => cpu::ftle_monitored(spec, start, monitor),
        }
    }

    /// One trajectory: the state at every step and the work done by the losses so far.
    pub fn trajectory(
        &self,
        p: &Params,
        start: State,
        stepping: Stepping,
        monitor: &Monitor,
    ) -> Result<(Vec<State>, Vec<f64>)> {
        let steps = stepping.steps();
        match &self.gpu {
            Some(k) => {
                let states = k
                    .trajectory(self.precision)
                    .run(&k.ctx, &EnsembleSpec::new(*p, &[start], stepping.dt, steps))?
                    .remove(0);
                let work = cpu::dissipated_along(p, &states, stepping.dt);
                Ok((states, work))
            }
            None => cpu::trajectory_with_work(p, start, stepping.dt, steps, monitor),
        }
    }

    /// Every run of `spec` (which keeps states), all at once.
    pub fn ensemble_all(&self, spec: &EnsembleSpec, monitor: &Monitor) -> Result<Vec<Vec<State>>> {
        let mut runs = Vec::with_capacity(spec.starts.len());
        self.ensemble(spec, monitor, |_, chunk| {
            runs.extend(chunk.into_states());
            Ok(())
        })?;
        Ok(runs)
    }

    /// Runs per chunk of `spec`'s ensemble: at most a dispatch's worth of pendulum-steps (on
    /// the CPU a sixteenth, ~0.1 s) and [`ENSEMBLE_CHUNK_STATES`] kept states, at least one
    /// run. The GPU's positions kernel splits its dispatches itself and reads back once: its
    /// chunks are bounded by memory alone.
    pub fn ensemble_chunk(&self, spec: &EnsembleSpec) -> usize {
        let work = match (spec.keep, self.gpu.is_some()) {
            (Keep::At(_), true) => 1,
            _ => spec.steps,
        };
        let budget = if self.gpu.is_some() {
            STEPS_PER_DISPATCH
        } else {
            STEPS_PER_DISPATCH / 16
        };
        let by_work = budget / work.max(1) as u64;
        let by_memory = ENSEMBLE_CHUNK_STATES / spec.kept().max(1);
        by_work
            .min(by_memory)
            .clamp(1, spec.starts.len().max(1) as u64) as usize
    }

    /// The runs of `spec`, handed to `each` chunk by chunk (in order, with the index of the
    /// chunk's first run) in what the spec keeps: memory holds one chunk, whatever the number
    /// of runs. GPU: one invocation a run (`shaders/trajectory.wgsl`, `shaders/positions.wgsl`);
    /// CPU: runs in parallel. Progress (runs) and Ctrl-C between chunks.
    pub fn ensemble(
        &self,
        spec: &EnsembleSpec,
        monitor: &Monitor,
        mut each: impl FnMut(usize, Chunk<'_>) -> Result<()>,
    ) -> Result<()> {
        let per_chunk = self.ensemble_chunk(spec);
        let total = spec.starts.len();
        monitor.start("runs", total as u64);
        for first in (0..total).step_by(per_chunk.max(1)) {
            monitor.check()?;
            let chunk = spec.runs(first, per_chunk.min(total - first));
            let n = chunk.starts.len();
            match (&self.gpu, chunk.keep) {
                (Some(g), Keep::Every(_)) => {
                    let runs = g.trajectory(self.precision).run(&g.ctx, &chunk)?;
                    each(first, Chunk::States(runs))?;
                    monitor.advance(n as u64);
                }
                // The kernel counts its runs as its dispatches finish.
                (Some(g), Keep::At(_)) => {
                    g.positions(self.precision)
                        .run_with(&g.ctx, &chunk, monitor, |v| {
                            each(first, Chunk::Positions(v))
                        })??
                }
                (None, Keep::Every(stride)) => {
                    let runs = (0..n)
                        .into_par_iter()
                        .map(|i| {
                            let run = cpu::trajectory(
                                &chunk.params_of(i),
                                chunk.starts[i],
                                chunk.dt,
                                chunk.steps,
                            );
                            run.into_iter().step_by(stride as usize).collect()
                        })
                        .collect();
                    each(first, Chunk::States(runs))?;
                    monitor.advance(n as u64);
                }
                (None, Keep::At(times)) => {
                    let runs: Vec<Vec<Positions>> = (0..n)
                        .into_par_iter()
                        .map(|i| {
                            cpu::positions(
                                &chunk.params_of(i),
                                chunk.starts[i],
                                chunk.dt,
                                chunk.steps,
                                times,
                            )
                        })
                        .collect();
                    let mut v = vec![0f32; 4 * times.len() * n];
                    v.par_chunks_mut(4 * n).enumerate().for_each(|(j, v)| {
                        for (i, run) in runs.iter().enumerate() {
                            let q = run[j];
                            for (c, x) in [q.x1, q.y1, q.x2, q.y2].into_iter().enumerate() {
                                v[c * n + i] = x as f32;
                            }
                        }
                    });
                    each(first, Chunk::Positions(&v))?;
                    monitor.advance(n as u64);
                }
            }
        }
        monitor.finish();
        Ok(())
    }
}

/// Most states an ensemble chunk keeps (32 bytes each on the host, 16 in the GPU buffer):
/// 128 MiB, within every device's storage binding.
pub const ENSEMBLE_CHUNK_STATES: u64 = 1 << 22;
