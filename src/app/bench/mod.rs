//! `chaoscope bench`: FLIP-512 throughput of both paths, side by side with the peers of
//! `../shared/peers` in one run (same machine, same moment, interleaved repetitions).
//!
//! Timing: the device and pipelines are made, and the kernels compiled, before the clock
//! starts (a warm-up run on a small grid), as the peers exclude their JIT compile. The timed
//! part is everything else: buffer set-up, all dispatches, and the read-back of the times.

mod accuracy;
mod forecast;
mod indicators;
mod peers;

pub use self::accuracy::ftle_accuracy_size;
use self::accuracy::{
    accurate_problem, accurate_reference, accurate_samples, ftle_accuracy_paths,
    ftle_accuracy_samples, ftle_reference,
};
use self::peers::{PeerRun, run_peer};

use std::path::PathBuf;
use std::time::Instant;

use crate::cpu;
use crate::error::{Error, Result};
use crate::field::Field;
use crate::gpu::{FlipTimeKernel, GpuContext, LyapunovKernel};
use crate::model::Params;
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Grid, Integrator, LyapunovSpec, Method, Precision, Stepping};

#[derive(Debug, Clone, PartialEq)]
pub struct BenchJob {
    /// Grid side (FLIP-512: 512).
    pub size: u32,
    /// Grid side for the CPU rows (steps per second do not depend on it; the f64 CPU path
    /// is slow enough that 512 would dominate the run).
    pub cpu_size: u32,
    pub t_max: f64,
    pub dt: f64,
    /// Repetitions of every configuration, interleaved; the median is reported.
    pub repeat: u32,
    /// Skip the CPU rows.
    pub no_cpu: bool,
    /// Skip the divergence-map (FTLE) rows.
    pub no_ftle: bool,
    /// Directory of the peer scripts (e.g. ../shared/peers); no peers are run without it.
    pub peers: Option<PathBuf>,
    /// Python with the peers' requirements installed.
    pub python: String,
    /// Peers to run, as SCRIPT[:ARCH] (e.g. taichi:vulkan, numba), in f32.
    pub peer: Vec<String>,
    /// Grid side of the "accurate map" rows (0: none) and their simulated time (s).
    pub accurate_size: u32,
    pub accurate_t_max: f64,
    /// Grid side of the chaos indicators' rows (0: none); with `peers`, the Numba
    /// indicators peer runs them too.
    pub indicator_size: u32,
    /// Members of the forecast row (an ensemble of tracked data over 6 s; 0: none).
    pub forecast_members: usize,
}

/// One row of the report: the median of the repetitions of one path and mode.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    pub path: String,
    pub mode: &'static str,
    pub wall_s: f64,
    /// NaN (null in JSON) for adaptive steps, which have no fixed count.
    pub steps_per_s: f64,
    /// "accurate" rows: the fraction of pixels matching the converged reference.
    pub right: Option<f64>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct BenchReport {
    pub adapter: String,
    pub rows: Vec<Row>,
    /// Same-run comparisons, one sentence each.
    pub ratios: Vec<String>,
    /// Peers that failed, and why.
    pub notices: Vec<String>,
}

/// One measured run.
#[derive(Clone, Debug)]
struct Sample {
    name: String,
    mode: &'static str,
    wall_s: f64,
    pendulum_steps: f64,
    right: Option<f64>,
}

/// Pendulum-steps the benchmark's problem needs, as the peers count them: every pixel up to
/// its flip step, or all steps (skipped starts count in full, as the peers integrate them).
/// The GPU rows: the peers' two modes, early exit and every step, as the peers define them
/// (`early-all`, `full`: every pixel integrated, the raw throughput) and with the mirrored
/// half of the symmetric grid (`early`: the map as users get it, `full-half`).
/// `full-plane`: the (m2/m1, l2/l1) parameter plane at a fixed start, every pixel every
/// step: against `full`, what per-pixel parameters cost the kernel (issue 22).
const MODES: [&str; 5] = ["early", "early-all", "full", "full-half", "full-plane"];

/// The f64 kernel's rows: the map as users get it, and every pixel every step.
const MODES_F64: [&str; 2] = ["early", "full"];

fn problem_steps(field: &Field, spec: &FlipSpec) -> f64 {
    let steps = spec.stepping.steps() as f64;
    if !spec.early_exit {
        return field.data.len() as f64 * steps;
    }
    field
        .data
        .iter()
        .map(|&t| {
            if t.is_finite() {
                (t as f64 / spec.stepping.dt).ceil().min(steps)
            } else {
                steps
            }
        })
        .sum()
}

/// The FLIP-512 problem; `mode` is one of `MODES`.
fn spec(size: u32, args: &BenchJob, mode: &str) -> FlipSpec {
    let grid = match mode {
        "full-plane" => Grid {
            x: crate::spec::Axis::new(crate::spec::Var::MassRatio, 0.5, 2.0),
            y: crate::spec::Axis::new(crate::spec::Var::LengthRatio, 0.5, 2.0),
            fixed: crate::model::State::at_rest(2.0, 2.0),
            ..Grid::square(size)
        },
        _ => Grid::square(size),
    };
    FlipSpec {
        early_exit: mode.starts_with("early"),
        use_symmetry: mode == "early" || mode == "full-half",
        ..FlipSpec::new(
            Params::default(),
            grid,
            Stepping {
                dt: args.dt,
                t_max: args.t_max,
            },
        )
    }
}

/// The divergence-map benchmark: the FLIP-512 grid and time, tangent method.
fn ftle_spec(size: u32, args: &BenchJob) -> LyapunovSpec {
    let stepping = Stepping {
        dt: args.dt,
        t_max: args.t_max,
    };
    LyapunovSpec {
        use_symmetry: false,
        ..LyapunovSpec::new(Params::default(), Grid::square(size), stepping)
    }
}

/// One FTLE map on the GPU at `size` and on the CPU at half `cpu_size` (scaled), as rows
/// of mode "ftle": every pixel runs every step, counted as pendulum-steps.
fn ftle_samples(
    args: &BenchJob,
    ctx: &GpuContext,
    kernel: &LyapunovKernel,
    quiet: &Monitor,
) -> Result<Vec<Sample>> {
    let mut out = Vec::new();
    let s = ftle_spec(args.size, args);
    let t0 = Instant::now();
    kernel.run(ctx, &s, quiet)?;
    out.push(Sample {
        name: format!("chaoscope gpu f32 ({})", ctx.info.name),
        mode: "ftle",
        wall_s: t0.elapsed().as_secs_f64(),
        pendulum_steps: s.grid.pixels() as f64 * s.stepping.steps() as f64,
        right: None,
    });
    if !args.no_cpu {
        let n = (args.cpu_size / 2).max(1);
        let s = ftle_spec(n, args);
        let t0 = Instant::now();
        cpu::ftle_map(&s, quiet)?;
        let scale = (args.size as f64 / n as f64).powi(2);
        out.push(Sample {
            name: format!("chaoscope cpu f64 (n={n})"),
            mode: "ftle",
            wall_s: t0.elapsed().as_secs_f64() * scale,
            pendulum_steps: s.grid.pixels() as f64 * s.stepping.steps() as f64 * scale,
            right: None,
        });
    }
    Ok(out)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

pub fn run(args: &BenchJob, monitor: &Monitor) -> Result<BenchReport> {
    if args.accurate_size > 0 {
        accurate_problem(args, Precision::F32, Integrator::Rk4, args.dt)
            .validate()
            .map_err(|e| match e {
                Error::InvalidSpec { field, reason } => Error::invalid(
                    match field {
                        "t_max" => "accurate_t_max",
                        "size" => "accurate_size",
                        other => other,
                    },
                    reason,
                ),
                e => e,
            })?;
    }
    let quiet = Monitor::hidden();
    let ctx = GpuContext::new()?;
    let kernel = FlipTimeKernel::new(&ctx);
    for mode in MODES {
        kernel.run(&ctx, &spec(32, args, mode), &quiet)?; // warm-up: shader compile
    }
    // The f64 kernel where the adapter has f64: the map as users get it and every step.
    let kernel64 = ctx
        .has_f64()
        .then(|| FlipTimeKernel::with_precision(&ctx, Precision::F64));
    if let Some(k) = &kernel64 {
        for mode in MODES_F64 {
            k.run(&ctx, &spec(32, args, mode), &quiet)?;
        }
    }
    let lyapunov = LyapunovKernel::new(&ctx, Method::Tangent);
    lyapunov.run(&ctx, &ftle_spec(32, args), &quiet)?;
    // The accurate-map rows run through an engine (the paths users get), on a GPU with f64.
    let accurate = if args.accurate_size > 0 && ctx.has_f64() {
        let engine = crate::engine::Engine::on_gpu(GpuContext::new()?);
        let small = BenchJob {
            accurate_size: 16,
            accurate_t_max: 1.0,
            peers: None,
            ..args.clone()
        };
        accurate_samples(
            &small,
            &engine,
            &accurate_reference(&small, &quiet)?,
            &quiet,
            &mut Vec::new(),
        )?;
        Some((engine, accurate_reference(args, monitor)?))
    } else {
        None
    };
    // The accurate divergence-map rows, on the same engine, with the FTLE rows.
    let ftle_reference = match &accurate {
        Some((engine, _)) if !args.no_ftle => {
            for (_, spec) in ftle_accuracy_paths(args) {
                let small = LyapunovSpec {
                    grid: Grid::square(8),
                    stepping: Stepping {
                        t_max: 0.2,
                        ..spec.stepping
                    },
                    ..spec
                };
                engine.map(&small, &quiet)?;
            }
            Some(ftle_reference(args, monitor)?)
        }
        _ => None,
    };
    // The indicators' rows go through an engine on the GPU (the path users get).
    let indicator_engine = match args.indicator_size {
        0 => None,
        _ => {
            let engine = crate::engine::Engine::on_gpu(GpuContext::new()?);
            indicators::warm_up(args, &engine, &quiet)?;
            Some(engine)
        }
    };
    // The forecast's row on the GPU engine, its fit and pipelines made before the clock.
    let forecast_run = match args.forecast_members {
        0 => None,
        members => {
            let engine = crate::engine::Engine::on_gpu(GpuContext::new()?);
            let fit = forecast::prepare(&engine, &quiet)?;
            forecast::sample(&fit, members.min(64), &engine, &quiet)?;
            Some((engine, fit, members))
        }
    };
    let mut samples: Vec<Sample> = Vec::new();
    let mut notices = Vec::new();
    monitor.start("bench", args.repeat as u64);
    for _ in 0..args.repeat {
        monitor.check()?;
        for mode in MODES {
            let s = spec(args.size, args, mode);
            let t0 = Instant::now();
            let field = kernel.run(&ctx, &s, &quiet)?;
            let wall_s = t0.elapsed().as_secs_f64();
            samples.push(Sample {
                name: format!("chaoscope gpu f32 ({})", ctx.info.name),
                mode,
                wall_s,
                pendulum_steps: problem_steps(&field, &s),
                right: None,
            });
        }
        for mode in kernel64.iter().flat_map(|_| MODES_F64) {
            let k = kernel64.as_ref().expect("f64 kernel");
            let s = spec(args.size, args, mode);
            let t0 = Instant::now();
            let field = k.run(&ctx, &s, &quiet)?;
            samples.push(Sample {
                name: format!("chaoscope gpu f64 ({})", ctx.info.name),
                mode,
                wall_s: t0.elapsed().as_secs_f64(),
                pendulum_steps: problem_steps(&field, &s),
                right: None,
            });
        }
        for early in [true, false] {
            let mode = if early { "early" } else { "full" };
            if !args.no_cpu {
                let s = spec(args.cpu_size, args, mode);
                let t0 = Instant::now();
                let field = cpu::flip_map(&s, &quiet)?;
                let wall_s = t0.elapsed().as_secs_f64();
                let scale = (args.size as f64 / args.cpu_size as f64).powi(2);
                samples.push(Sample {
                    name: format!("chaoscope cpu f64 (n={})", args.cpu_size),
                    mode,
                    wall_s: wall_s * scale,
                    pendulum_steps: problem_steps(&field, &s) * scale,
                    right: None,
                });
            }
            if !early && !args.no_ftle {
                samples.extend(ftle_samples(args, &ctx, &lyapunov, &quiet)?);
            }
            if !early && let Some((engine, reference)) = &accurate {
                samples.extend(accurate_samples(
                    args,
                    engine,
                    reference,
                    &quiet,
                    &mut notices,
                )?);
            }
            if !early && let (Some((engine, _)), Some(reference)) = (&accurate, &ftle_reference) {
                samples.extend(ftle_accuracy_samples(args, engine, reference, &quiet)?);
            }
            if !early && let Some((engine, fit, members)) = &forecast_run {
                samples.push(forecast::sample(fit, *members, engine, &quiet)?);
            }
            if !early && let Some(engine) = &indicator_engine {
                samples.extend(indicators::samples(args, engine, &quiet, &mut notices)?);
            }
            if let Some(dir) = &args.peers {
                for peer in &args.peer {
                    match run_peer(args, dir, peer, &PeerRun::flip512(args, !early)) {
                        Ok(s) => samples.push(s),
                        Err(e) => notices.push(format!("peer {peer}: {e}")),
                    }
                }
            }
        }
        monitor.advance(1);
    }
    monitor.finish();
    let mut names: Vec<(String, &str)> = samples.iter().map(|s| (s.name.clone(), s.mode)).collect();
    names.sort();
    names.dedup();
    let mut rows = Vec::new();
    for (name, mode) in names {
        let mine: Vec<&Sample> = samples
            .iter()
            .filter(|s| s.name == name && s.mode == mode)
            .collect();
        let wall = median(mine.iter().map(|s| s.wall_s).collect());
        let steps = mine[0].pendulum_steps;
        rows.push(Row {
            path: name,
            mode,
            wall_s: wall,
            steps_per_s: steps / wall,
            right: mine[0].right,
        });
    }
    let mut ratios = ratios(&rows);
    ratios.extend(indicators::ratios(&rows));
    Ok(BenchReport {
        adapter: ctx.adapter_name(),
        rows,
        ratios,
        notices,
    })
}

/// The same-run comparisons: a tangent step against a plain one, and each GPU mode against
/// the fastest peer in the same mode.
fn ratios(rows: &[Row]) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(f) = rows.iter().find(|r| r.mode == "forecast") {
        out.push(format!(
            "forecast: the ensemble of [[forecast_members]] over 6 s past a fit window (draws, runs with their own damping, bands, FTLE) takes {:.2} s on {} ({:.3e} pendulum-steps/s)",
            f.wall_s, f.path, f.steps_per_s
        ));
    }
    let gpu_rate = |mode: &str| {
        rows.iter()
            .find(|r| r.path.starts_with("chaoscope gpu f32") && r.mode == mode)
            .map(|r| r.steps_per_s)
    };
    let f64_rate = rows
        .iter()
        .find(|r| r.path.starts_with("chaoscope gpu f64") && r.mode == "full")
        .map(|r| r.steps_per_s);
    if let (Some(full), Some(f64_full)) = (gpu_rate("full"), f64_rate) {
        out.push(format!(
            "f64: the GPU's f64 kernel runs {:.2}x the f32 kernel's pendulum-steps/s (every step)",
            f64_full / full
        ));
    }
    if let (Some(full), Some(plane)) = (gpu_rate("full"), gpu_rate("full-plane")) {
        out.push(format!(
            "plane: a parameter plane (m2/m1, l2/l1) costs {:.2}x the (theta1, theta2) map of the same size and time on the GPU (every pixel every step)",
            full / plane
        ));
    }
    if let (Some(full), Some(ftle)) = (gpu_rate("full"), gpu_rate("ftle")) {
        out.push(format!(
            "ftle: a tangent step (state + variational equations) costs {:.2} plain RK4 steps on the GPU",
            full / ftle
        ));
    }
    // "NAME is right on X % of the pixels (f32 RK4: Y %) in Zx the f32 RK4 map's time" for
    // the row of `mode` starting with `path`, against that mode's f32 RK4 row.
    let against_f32 = |mode: &str, path: &str, what: &str| {
        let row = |p: &str| {
            rows.iter()
                .find(|r| r.mode == mode && r.path.starts_with(p))
        };
        let (a, f32_map) = (row(path)?, row("chaoscope gpu f32 rk4")?);
        let percent = |r: &Row| 100.0 * r.right.unwrap_or(f64::NAN);
        Some((
            a,
            format!(
                "{what} on {:.2} % of the pixels (f32 RK4: {:.2} %) in {:.2}x the f32 RK4 map's time",
                percent(a),
                percent(f32_map),
                a.wall_s / f32_map.wall_s
            ),
        ))
    };
    if let Some((a, line)) = against_f32(
        "accurate",
        "chaoscope [[accurate]]",
        "accurate map: [[accurate]] is right",
    ) {
        out.push(line);
        let right = a.right.unwrap_or(0.0);
        let peer = rows
            .iter()
            .filter(|r| {
                r.mode == "accurate"
                    && r.path.starts_with("peer")
                    && r.right.is_some_and(|p| p >= right.min(0.995))
            })
            .min_by(|x, y| x.wall_s.total_cmp(&y.wall_s));
        match peer {
            Some(p) => out.push(format!(
                "accurate map: the fastest peer as right ({}, {:.2} %) takes {:.1}x [[accurate]]'s time",
                p.path,
                100.0 * p.right.unwrap_or(f64::NAN),
                p.wall_s / a.wall_s
            )),
            None => out.push("accurate map: no peer run reached 99.5 % of the pixels".into()),
        }
    }
    if let Some((_, line)) = against_f32(
        "accurate-ftle",
        "chaoscope lyapunov [[accurate]]",
        "accurate divergence map: lyapunov [[accurate]] agrees with the converged map",
    ) {
        out.push(line);
    }
    for (mode, peer_mode) in [
        ("early", "early"),
        ("early-all", "early"),
        ("full", "full"),
        ("full-half", "full"),
    ] {
        let ours = rows
            .iter()
            .find(|r| r.path.starts_with("chaoscope gpu f32") && r.mode == mode);
        let best_peer = rows
            .iter()
            .filter(|r| r.path.starts_with("peer") && r.mode == peer_mode && r.wall_s.is_finite())
            .min_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
        if let (Some(o), Some(p)) = (ours, best_peer) {
            out.push(format!(
                "{mode}: chaoscope gpu takes {:.3} of the time of the fastest peer ({}), {:.2}x its pendulum-steps/s",
                o.wall_s / p.wall_s,
                p.path,
                o.steps_per_s / p.steps_per_s
            ));
        }
    }
    out
}
