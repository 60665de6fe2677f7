//! `chaoscope bench`: FLIP-512 throughput of both paths, side by side with the peers of
//! `../shared/peers` in one run (same machine, same moment, interleaved repetitions).
//!
//! Timing: the device and pipelines are made, and the kernels compiled, before the clock
//! starts (a warm-up run on a small grid), as the peers exclude their JIT compile. The timed
//! part is everything else: buffer set-up, all dispatches, and the read-back of the times.

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use clap::Args;

use crate::cpu;
use crate::error::{Error, Result};
use crate::field::Field;
use crate::gpu::{FlipTimeKernel, GpuContext, LyapunovKernel};
use crate::model::Params;
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Grid, LyapunovSpec, Method, Stepping};

#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// Grid side (FLIP-512: 512).
    #[arg(long, default_value = "512")]
    pub size: u32,
    /// Grid side for the CPU rows (steps per second do not depend on it; the f64 CPU path
    /// is slow enough that 512 would dominate the run).
    #[arg(long, default_value = "256")]
    pub cpu_size: u32,
    #[arg(long, default_value = "20")]
    pub t_max: f64,
    #[arg(long, default_value = "0.01")]
    pub dt: f64,
    /// Repetitions of every configuration, interleaved; the median is reported.
    #[arg(long, default_value = "3")]
    pub repeat: u32,
    /// Skip the CPU rows.
    #[arg(long)]
    pub no_cpu: bool,
    /// Skip the divergence-map (FTLE) rows.
    #[arg(long)]
    pub no_ftle: bool,
    /// Directory of the peer scripts (e.g. ../shared/peers); no peers are run without it.
    #[arg(long)]
    pub peers: Option<PathBuf>,
    /// Python with the peers' requirements installed.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Peers to run, as SCRIPT[:ARCH] (e.g. taichi:vulkan, numba), in f32.
    #[arg(long, default_values = ["taichi:vulkan", "numba"])]
    pub peer: Vec<String>,
}

/// One measured run.
#[derive(Clone, Debug)]
struct Sample {
    name: String,
    mode: &'static str,
    wall_s: f64,
    pendulum_steps: f64,
}

/// Pendulum-steps the benchmark's problem needs, as the peers count them: every pixel up to
/// its flip step, or all steps (skipped starts count in full, as the peers integrate them).
/// The GPU rows: the peers' two modes, early exit and every step, as the peers define them
/// (`early-all`, `full`: every pixel integrated, the raw throughput) and with the mirrored
/// half of the symmetric grid (`early`: the map as users get it, `full-half`).
const MODES: [&str; 4] = ["early", "early-all", "full", "full-half"];

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
fn spec(size: u32, args: &BenchArgs, mode: &str) -> FlipSpec {
    FlipSpec {
        early_exit: mode.starts_with("early"),
        use_symmetry: mode == "early" || mode == "full-half",
        ..FlipSpec::new(
            Params::default(),
            Grid::square(size),
            Stepping {
                dt: args.dt,
                t_max: args.t_max,
            },
        )
    }
}

/// The divergence-map benchmark: the FLIP-512 grid and time, tangent method.
fn ftle_spec(size: u32, args: &BenchArgs) -> LyapunovSpec {
    LyapunovSpec {
        params: Params::default(),
        grid: Grid::square(size),
        stepping: Stepping {
            dt: args.dt,
            t_max: args.t_max,
        },
        method: Method::Tangent,
        renorm: 0.1,
        use_symmetry: false,
    }
}

/// One FTLE map on the GPU at `size` and on the CPU at half `cpu_size` (scaled), as rows
/// of mode "ftle": every pixel runs every step, counted as pendulum-steps.
fn ftle_samples(
    args: &BenchArgs,
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
        });
    }
    Ok(out)
}

fn run_peer(args: &BenchArgs, dir: &PathBuf, peer: &str, full: bool) -> Result<Sample> {
    let (script, arch) = peer
        .split_once(':')
        .map_or((peer, None), |(s, a)| (s, Some(a)));
    let mut cmd = Command::new(&args.python);
    cmd.current_dir(dir).arg(format!("{script}_peer.py"));
    if let Some(arch) = arch {
        cmd.args(["--arch", arch]);
    }
    cmd.args([
        "--n",
        &args.size.to_string(),
        "--t-max",
        &args.t_max.to_string(),
        "--dt",
        &args.dt.to_string(),
        "--f32",
    ]);
    if full {
        cmd.arg("--full");
    }
    let out = cmd.output()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .ok_or_else(|| {
            Error::Io(std::io::Error::other(format!(
                "peer {peer} printed no result: {}",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            )))
        })?;
    let field = |key: &str| -> f64 {
        line.split(&format!("\"{key}\": "))
            .nth(1)
            .and_then(|r| r.split([',', '}']).next())
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(f64::NAN)
    };
    Ok(Sample {
        name: format!("peer {peer} f32"),
        mode: if full { "full" } else { "early" },
        wall_s: field("wall_s"),
        pendulum_steps: field("pendulum_steps"),
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

pub fn run(args: &BenchArgs, monitor: &Monitor) -> Result<()> {
    let quiet = Monitor::hidden();
    let ctx = GpuContext::new()?;
    let kernel = FlipTimeKernel::new(&ctx);
    for mode in MODES {
        kernel.run(&ctx, &spec(32, args, mode), &quiet)?; // warm-up: shader compile
    }
    let lyapunov = LyapunovKernel::new(&ctx, Method::Tangent);
    lyapunov.run(&ctx, &ftle_spec(32, args), &quiet)?;
    eprintln!("GPU: {}", ctx.adapter_name());
    let mut samples: Vec<Sample> = Vec::new();
    for rep in 0..args.repeat {
        monitor.check()?;
        eprintln!("repetition {}/{}", rep + 1, args.repeat);
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
                });
            }
            if !early && !args.no_ftle {
                samples.extend(ftle_samples(args, &ctx, &lyapunov, &quiet)?);
            }
            if let Some(dir) = &args.peers {
                for peer in &args.peer {
                    match run_peer(args, dir, peer, !early) {
                        Ok(s) => samples.push(s),
                        Err(e) => eprintln!("peer {peer}: {e}"),
                    }
                }
            }
        }
    }
    println!(
        "FLIP-{} (RK4, dt {}, t_max {} s): medians of {} interleaved runs; cpu rows scaled from n={}",
        args.size, args.dt, args.t_max, args.repeat, args.cpu_size
    );
    println!(
        "pendulum-steps as the peers count them: early-all and full integrate every pixel; early \
         and full-half integrate the top half of the symmetric grid and mirror it"
    );
    println!(
        "{:<44} {:>9} {:>10} {:>16}",
        "path", "mode", "wall s", "pendulum-steps/s"
    );
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
        println!("{name:<44} {mode:>9} {wall:>10.3} {:>16.3e}", steps / wall);
        rows.push((name, mode, wall, steps / wall));
    }
    let gpu_rate = |mode: &str| {
        rows.iter()
            .find(|r| r.0.starts_with("chaoscope gpu") && r.1 == mode)
            .map(|r| r.3)
    };
    if let (Some(full), Some(ftle)) = (gpu_rate("full"), gpu_rate("ftle")) {
        println!(
            "ftle: a tangent step (state + variational equations) costs {:.2} plain RK4 steps on the GPU",
            full / ftle
        );
    }
    for (mode, peer_mode) in [
        ("early", "early"),
        ("early-all", "early"),
        ("full", "full"),
        ("full-half", "full"),
    ] {
        let ours = rows
            .iter()
            .find(|r| r.0.starts_with("chaoscope gpu") && r.1 == mode);
        let best_peer = rows
            .iter()
            .filter(|r| r.0.starts_with("peer") && r.1 == peer_mode && r.2.is_finite())
            .min_by(|a, b| a.2.total_cmp(&b.2));
        if let (Some(o), Some(p)) = (ours, best_peer) {
            println!(
                "{mode}: chaoscope gpu takes {:.3} of the time of the fastest peer ({}), {:.2}x its pendulum-steps/s",
                o.2 / p.2,
                p.0,
                o.3 / p.3
            );
        }
    }
    Ok(())
}
