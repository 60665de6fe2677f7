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
    FlipMeasure, FlipSpec, Grid, Integrator, LyapunovSpec, MapSpec, Method, Precision, Range,
    Stepping,
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

/// The path a run takes: a type, so that what depends on it (the f32 tolerance floor, the
/// words in the PNG and the summary) is decided once, from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The f64 CPU reference.
    Cpu,
    /// A GPU kernel in this precision.
    Gpu(Precision),
    /// Read back from a Zarr store (`render`).
    Store,
}

impl Path {
    /// The path in the PNG metadata's words: "cpu", "gpu", "gpu f64", "zarr store".
    pub fn name(self) -> &'static str {
        match self {
            Path::Cpu => "cpu",
            Path::Gpu(precision) => precision.gpu_path_name(),
            Path::Store => "zarr store",
        }
    }

    pub fn on_gpu(self) -> bool {
        matches!(self, Path::Gpu(_))
    }

    /// The precision the arithmetic runs in (the CPU's, and a store's maps', is f64).
    pub fn precision(self) -> Precision {
        match self {
            Path::Gpu(precision) => precision,
            Path::Cpu | Path::Store => Precision::F64,
        }
    }
}

/// Which path a run took, for the user and the PNG metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    pub path: Path,
    pub adapter: Option<String>,
}

impl RunInfo {
    pub const CPU: RunInfo = RunInfo {
        path: Path::Cpu,
        adapter: None,
    };

    /// The path in the PNG metadata's words ([`Path::name`]).
    pub fn backend(&self) -> &'static str {
        self.path.name()
    }

    /// Where it ran, in words: the adapter's name or "the CPU".
    pub fn place(&self) -> &str {
        self.adapter.as_deref().unwrap_or("the CPU")
    }
}

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

    /// The path `spec`'s map takes, and the checks that depend on it, made once: the
    /// tolerances must be within what that path's precision can follow (an f32 kernel's
    /// error estimate is round-off below [`crate::spec::MIN_TOLERANCE_F32`]).
    pub fn plan(&self, spec: &impl MapSpec) -> Result<RunInfo> {
        let info = self.map_info(spec.grid(), spec.precision());
        spec.validate_in(info.path.precision())?;
        Ok(info)
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
                    .run(&k.ctx, p, &[start], stepping.dt, steps, 1)?
                    .remove(0);
                let work = cpu::dissipated_along(p, &states, stepping.dt);
                Ok((states, work))
            }
            None => cpu::trajectory_with_work(p, start, stepping.dt, steps, monitor),
        }
    }

    /// Trajectories of all `starts` over `steps` steps of `dt`, keeping the start and every
    /// `stride`-th state (GPU: one invocation per run; CPU: runs in parallel), all at once.
    pub fn ensemble(
        &self,
        p: &Params,
        starts: &[State],
        dt: f64,
        steps: u32,
        stride: u32,
        monitor: &Monitor,
    ) -> Result<Vec<Vec<State>>> {
        let mut runs = Vec::with_capacity(starts.len());
        self.ensemble_each(p, starts, dt, steps, stride, monitor, |_, chunk| {
            runs.extend(chunk);
            Ok(())
        })?;
        Ok(runs)
    }

    /// Runs per chunk of an ensemble: at most a dispatch's worth of pendulum-steps (on the
    /// CPU a sixteenth, ~0.1 s) and [`ENSEMBLE_CHUNK_STATES`] kept states, at least one run.
    pub fn ensemble_chunk(&self, runs: usize, steps: u32, stride: u32) -> usize {
        self.chunk_of(runs, steps, (steps / stride.max(1) + 1) as u64)
    }

    /// Runs per chunk of runs of `steps` steps that keep `kept` states (or sets of four
    /// f32 positions, as large as an f32 state) each.
    fn chunk_of(&self, runs: usize, steps: u32, kept: u64) -> usize {
        let budget = if self.gpu.is_some() {
            STEPS_PER_DISPATCH
        } else {
            STEPS_PER_DISPATCH / 16
        };
        let by_work = budget / steps.max(1) as u64;
        let by_memory = ENSEMBLE_CHUNK_STATES / kept.max(1);
        by_work.min(by_memory).clamp(1, runs.max(1) as u64) as usize
    }

    /// The bobs' positions (x1, y1, x2, y2) of one run per start at `times` (s from the
    /// start, ascending, within `steps` steps of `dt`), run i with joint damping `damping[i]`
    /// (N m s at the pivot and the middle joint) in place of `p`'s when given (GPU: one
    /// invocation per run, `shaders/positions.wgsl`; CPU: `cpu::positions`, runs in
    /// parallel). Each chunk of runs is handed to `each` in order, with the index of its
    /// first run, its positions time-major: time j, coordinate c, run i of the chunk's n at
    /// (4 j + c) n + i. Progress and Ctrl-C between chunks.
    #[allow(clippy::too_many_arguments)]
    pub fn ensemble_positions_each(
        &self,
        p: &Params,
        starts: &[State],
        damping: Option<&[(f64, f64)]>,
        dt: f64,
        steps: u32,
        times: &[f64],
        monitor: &Monitor,
        mut each: impl FnMut(usize, &[f32]) -> Result<()>,
    ) -> Result<()> {
        // The GPU kernel splits its dispatches itself and reads back once: chunks by memory.
        let work = if self.gpu.is_some() { 1 } else { steps };
        let per_chunk = self.chunk_of(starts.len(), work, times.len() as u64);
        monitor.start("runs", starts.len() as u64);
        for (k, chunk) in starts.chunks(per_chunk).enumerate() {
            monitor.check()?;
            let first = k * per_chunk;
            let pairs = damping.map(|d| &d[first..first + chunk.len()]);
            match &self.gpu {
                Some(g) => g.positions(self.precision).run_with(
                    &g.ctx,
                    p,
                    chunk,
                    pairs,
                    dt,
                    steps,
                    times,
                    monitor,
                    |v| each(first, v),
                )??,
                None => {
                    let runs: Vec<Vec<Positions>> = chunk
                        .par_iter()
                        .enumerate()
                        .map(|(i, s)| {
                            let mut q = *p;
                            if let Some(d) = pairs {
                                (q.losses.joint1, q.losses.joint2) = d[i];
                            }
                            cpu::positions(&q, *s, dt, steps, times)
                        })
                        .collect();
                    let n = chunk.len();
                    let mut v = vec![0f32; 4 * times.len() * n];
                    v.par_chunks_mut(4 * n).enumerate().for_each(|(j, v)| {
                        for (i, run) in runs.iter().enumerate() {
                            let q = run[j];
                            for (c, x) in [q.x1, q.y1, q.x2, q.y2].into_iter().enumerate() {
                                v[c * n + i] = x as f32;
                            }
                        }
                    });
                    each(first, &v)?;
                    // The GPU kernel counts its runs as its dispatches finish.
                    monitor.advance(chunk.len() as u64);
                }
            };
        }
        monitor.finish();
        Ok(())
    }

    /// As [`Engine::ensemble`], handing each chunk of runs (in order, with the index of its
    /// first run) to `each` as it is done: memory holds one chunk, whatever the number of
    /// runs. Progress and Ctrl-C between chunks.
    #[allow(clippy::too_many_arguments)]
    pub fn ensemble_each(
        &self,
        p: &Params,
        starts: &[State],
        dt: f64,
        steps: u32,
        stride: u32,
        monitor: &Monitor,
        each: impl FnMut(usize, Vec<Vec<State>>) -> Result<()>,
    ) -> Result<()> {
        self.ensemble_damped_each(p, starts, None, dt, steps, stride, monitor, each)
    }

    /// As [`Engine::ensemble_each`], run i with joint damping `damping[i]` (N m s at the
    /// pivot and the middle joint, one pair per start) in place of `p`'s when given.
    #[allow(clippy::too_many_arguments)]
    pub fn ensemble_damped_each(
        &self,
        p: &Params,
        starts: &[State],
        damping: Option<&[(f64, f64)]>,
        dt: f64,
        steps: u32,
        stride: u32,
        monitor: &Monitor,
        mut each: impl FnMut(usize, Vec<Vec<State>>) -> Result<()>,
    ) -> Result<()> {
        let per_chunk = self.ensemble_chunk(starts.len(), steps, stride);
        monitor.start("runs", starts.len() as u64);
        for (k, chunk) in starts.chunks(per_chunk).enumerate() {
            monitor.check()?;
            let first = k * per_chunk;
            let pairs = damping.map(|d| &d[first..first + chunk.len()]);
            match &self.gpu {
                Some(g) => each(
                    first,
                    g.trajectory(self.precision)
                        .run_damped(&g.ctx, p, chunk, pairs, dt, steps, stride)?,
                )?,
                None => {
                    let runs = chunk
                        .par_iter()
                        .enumerate()
                        .map(|(i, s)| {
                            let mut q = *p;
                            if let Some(d) = pairs {
                                (q.losses.joint1, q.losses.joint2) = d[i];
                            }
                            let run = cpu::trajectory(&q, *s, dt, steps);
                            run.into_iter().step_by(stride as usize).collect()
                        })
                        .collect();
                    each(first, runs)?
                }
            };
            monitor.advance(chunk.len() as u64);
        }
        monitor.finish();
        Ok(())
    }
}

/// Most states an ensemble chunk keeps (32 bytes each on the host, 16 in the GPU buffer):
/// 128 MiB, within every device's storage binding.
pub const ENSEMBLE_CHUNK_STATES: u64 = 1 << 22;
