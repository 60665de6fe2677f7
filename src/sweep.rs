//! `chaoscope sweep`: one map per frame while a physical parameter changes, or a zoom into a
//! point of the map; numbered PNGs plus an animated PNG. Frames that already exist (from an
//! interrupted run of the same sweep) are kept, so running the command again resumes it.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};

use crate::cli::{GridArgs, flip_command_line, flip_picture, lyapunov_picture, png_metadata};
use crate::cpu;
use crate::engine::{self, Backend, RunInfo};
use crate::error::{Error, Result};
use crate::gpu::{FlipTimeKernel, LyapunovKernel};
use crate::model::Params;
use crate::monitor::Monitor;
use crate::render;
use crate::spec::{FlipSpec, Grid, LyapunovSpec, Method, Range, Stepping};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MapKind {
    Flip,
    Lyapunov,
}

/// The parameters a sweep can vary. Ratios keep the denominator and change the numerator;
/// `mass` scales both masses (the motion does not change: a check of the pipeline).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Param {
    M1,
    M2,
    L1,
    L2,
    G,
    MassRatio,
    LengthRatio,
    Mass,
    Omega1,
    Omega2,
    /// Both joints' viscous damping (N m s).
    Damping,
}

const PARAM_NAMES: &str = "m1, m2, l1, l2, g, m2/m1, l2/l1, mass, omega1, omega2, damping";

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vary {
    pub param: Param,
    pub from: f64,
    pub to: f64,
}

fn parse_vary(s: &str) -> std::result::Result<Vary, String> {
    let (name, range) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}` must be PARAM=FROM:TO, e.g. m2/m1=0.5:2"))?;
    let param = match name.trim() {
        "m1" => Param::M1,
        "m2" => Param::M2,
        "l1" => Param::L1,
        "l2" => Param::L2,
        "g" => Param::G,
        "m2/m1" => Param::MassRatio,
        "l2/l1" => Param::LengthRatio,
        "mass" => Param::Mass,
        "omega1" => Param::Omega1,
        "omega2" => Param::Omega2,
        "damping" => Param::Damping,
        other => return Err(format!("`{other}` is not one of {PARAM_NAMES}")),
    };
    let (a, b) = range
        .split_once(':')
        .ok_or_else(|| format!("`{range}` must be FROM:TO"))?;
    Ok(Vary {
        param,
        from: crate::cli::parse_number(a)?,
        to: crate::cli::parse_number(b)?,
    })
}

fn parse_point(s: &str) -> std::result::Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("`{s}` must be THETA1,THETA2"))?;
    Ok((crate::cli::parse_number(a)?, crate::cli::parse_number(b)?))
}

#[derive(Args, Debug, Clone)]
pub struct SweepArgs {
    /// Which map each frame shows.
    #[arg(long, value_enum, default_value = "flip")]
    pub map: MapKind,
    /// PARAM=FROM:TO, PARAM one of m1, m2, l1, l2, g, m2/m1, l2/l1, mass, omega1, omega2,
    /// damping (both joints, N m s).
    #[arg(long, value_parser = parse_vary, allow_hyphen_values = true)]
    pub vary: Option<Vary>,
    /// Zoom towards THETA1,THETA2 (rad), which stays fixed in the picture.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true, requires = "zoom")]
    pub zoom_to: Option<(f64, f64)>,
    /// Total magnification of the last frame over the first.
    #[arg(long, value_parser = crate::cli::parse_number, requires = "zoom_to")]
    pub zoom: Option<f64>,
    /// Number of frames.
    #[arg(long, default_value = "24")]
    pub frames: u32,
    /// Frames per second of the animation.
    #[arg(long, default_value = "8", value_parser = crate::cli::parse_number)]
    pub fps: f64,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Simulated time (s) of every frame.
    #[arg(long, default_value = "20", value_parser = crate::cli::parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    /// Lyapunov frames: renormalisation interval (s).
    #[arg(long, default_value = "0.1", value_parser = crate::cli::parse_number)]
    pub renorm: f64,
    /// Lyapunov frames: top of the colour range (1/s), the same for every frame.
    #[arg(long, default_value = "2", value_parser = crate::cli::parse_number)]
    pub ftle_max: f64,
    /// Directory for frame_0000.png ... and animation.png (APNG).
    #[arg(long, default_value = "out/sweep")]
    pub output: PathBuf,
}

/// Smallest angle step between pixels that f32 still resolves near |theta| = pi: 16 ulp of
/// pi (ulp = 2.4e-7), so neighbouring pixels start from distinct f32 angles with room for
/// the arithmetic that forms them.
pub const F32_MIN_PIXEL_STEP: f64 = 16.0 * 2.384185791015625e-7;

/// One frame's parameters, grid and whether it needs f64.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub params: Params,
    pub grid: Grid,
    pub needs_f64: bool,
}

/// The frames of a sweep, validated; errors name the flag.
pub fn frames(args: &SweepArgs) -> Result<Vec<Frame>> {
    if args.frames == 0 || args.frames > 100_000 {
        return Err(Error::invalid("--frames", "must be between 1 and 100000"));
    }
    if !(args.fps.is_finite() && args.fps > 0.0 && args.fps <= 100.0) {
        return Err(Error::invalid("--fps", "must be in (0, 100]"));
    }
    if args.vary.is_none() && args.zoom.is_none() {
        return Err(Error::invalid(
            "--vary",
            "a sweep needs --vary PARAM=FROM:TO or --zoom-to THETA1,THETA2 --zoom FACTOR",
        ));
    }
    let base_params = args.grid.physical.params()?;
    let base_grid = args.grid.grid();
    let n = args.frames;
    let mut out = Vec::with_capacity(n as usize);
    for k in 0..n {
        let s = if n == 1 {
            0.0
        } else {
            k as f64 / (n - 1) as f64
        };
        let mut p = base_params;
        let mut g = base_grid;
        if let Some(v) = args.vary {
            let x = v.from + (v.to - v.from) * s;
            match v.param {
                Param::M1 => p.m1 = x,
                Param::M2 => p.m2 = x,
                Param::L1 => p.l1 = x,
                Param::L2 => p.l2 = x,
                Param::G => p.g = x,
                Param::MassRatio => p.m2 = x * p.m1,
                Param::LengthRatio => p.l2 = x * p.l1,
                Param::Mass => {
                    p.m1 *= x;
                    p.m2 *= x;
                }
                Param::Omega1 => g.omega1 = x,
                Param::Omega2 => g.omega2 = x,
                Param::Damping => {
                    p.losses.joint1 = x;
                    p.losses.joint2 = x;
                }
            }
            crate::spec::validate_params(&p)
                .map_err(|e| Error::invalid("--vary", format!("at frame {k}: {e}")))?;
        }
        if let (Some((t1, t2)), Some(factor)) = (args.zoom_to, args.zoom) {
            if !(factor.is_finite() && factor >= 1.0) {
                return Err(Error::invalid("--zoom", "must be a magnification >= 1"));
            }
            if !(base_grid.theta1.min..=base_grid.theta1.max).contains(&t1)
                || !(base_grid.theta2.min..=base_grid.theta2.max).contains(&t2)
            {
                return Err(Error::invalid(
                    "--zoom-to",
                    "must lie inside the --theta1 and --theta2 ranges",
                ));
            }
            // The point keeps its place in the picture while the window shrinks.
            let scale = factor.powf(-s);
            let shrink = |r: Range, c: f64| Range {
                min: c + (r.min - c) * scale,
                max: c + (r.max - c) * scale,
            };
            g.theta1 = shrink(base_grid.theta1, t1);
            g.theta2 = shrink(base_grid.theta2, t2);
        }
        let needs_f64 = g.theta1_step().min(g.theta2_step()) < F32_MIN_PIXEL_STEP;
        out.push(Frame {
            params: p,
            grid: g,
            needs_f64,
        });
    }
    Ok(out)
}

enum Kernels {
    // Boxed: a context with its kernels is large beside the CPU variant.
    Gpu(
        Box<(
            crate::gpu::GpuContext,
            Option<FlipTimeKernel>,
            Option<LyapunovKernel>,
        )>,
    ),
    Cpu,
}

fn frame_path(dir: &Path, k: u32) -> PathBuf {
    dir.join(format!("frame_{k:04}.png"))
}

pub fn run(args: &SweepArgs, monitor: &Monitor) -> Result<()> {
    let frames = frames(args)?;
    for f in &frames {
        crate::spec::validate_grid(&f.grid)?;
    }
    if args.map == MapKind::Lyapunov {
        lyapunov_spec(
            args,
            &frames[0],
            Stepping {
                dt: args.grid.dt,
                t_max: args.t_max,
            },
        )
        .validate()?;
    }
    let stepping = Stepping {
        dt: args.grid.dt,
        t_max: args.t_max,
    };
    crate::spec::validate_stepping(&stepping)?;
    if !(args.ftle_max.is_finite() && args.ftle_max > 0.0) {
        return Err(Error::invalid("--ftle-max", "must be > 0"));
    }
    let (ctx, notice) = engine::resolve(args.grid.backend)?;
    if let Some(n) = notice {
        eprintln!("{n}");
    }
    let kernels = match ctx {
        Some(ctx) => {
            let flip = (args.map == MapKind::Flip).then(|| FlipTimeKernel::new(&ctx));
            let lyap =
                (args.map == MapKind::Lyapunov).then(|| LyapunovKernel::new(&ctx, Method::Tangent));
            Kernels::Gpu(Box::new((ctx, flip, lyap)))
        }
        None => Kernels::Cpu,
    };
    if let (Kernels::Gpu(..), Some(k)) = (&kernels, frames.iter().position(|f| f.needs_f64)) {
        eprintln!(
            "note: from frame {k} on the pixel step is below {F32_MIN_PIXEL_STEP:.1e} rad, finer than f32 resolves near pi; those frames run on the CPU in f64"
        );
    }
    std::fs::create_dir_all(&args.output)?;
    monitor.start("frames", frames.len() as u64);
    let quiet = monitor.quiet();
    let mut skipped = 0;
    let mut size = None;
    for (k, frame) in frames.iter().enumerate() {
        monitor.check()?;
        let path = frame_path(&args.output, k as u32);
        let on_gpu = matches!(kernels, Kernels::Gpu(..)) && !frame.needs_f64;
        let command = frame_command(args, frame, stepping, on_gpu);
        if path.exists() {
            // Resume: keep a finished frame of the same sweep; refuse to mix sweeps.
            let old = render::read_png(&path)?;
            let same = old
                .text
                .iter()
                .any(|(key, text)| key == "chaoscope:command" && *text == command);
            if !same {
                return Err(Error::invalid(
                    "--output",
                    format!(
                        "{} holds frames of a different sweep; choose another directory",
                        args.output.display()
                    ),
                ));
            }
            skipped += 1;
        } else {
            let (picture, info) = render_frame(args, frame, stepping, &kernels, &quiet)?;
            let mut meta = png_metadata(command, &info);
            meta.push(("chaoscope:frame".into(), format!("{k} of {}", frames.len())));
            render::write_png(&path, picture.width, picture.height, &picture.rgb, &meta)?;
        }
        monitor.advance(1);
    }
    monitor.finish();
    // The animation from the frame files (including those of an earlier, interrupted run).
    let mut rgb = Vec::with_capacity(frames.len());
    for k in 0..frames.len() {
        let png = render::read_png(&frame_path(&args.output, k as u32))?;
        size.get_or_insert((png.width, png.height));
        rgb.push(png.rgb);
    }
    let (w, h) = size.expect("at least one frame");
    let delay_ms = (1000.0 / args.fps).round() as u16;
    let animation = args.output.join("animation.png");
    render::write_apng(&animation, w, h, &rgb, delay_ms, &[])?;
    eprintln!(
        "{} frames ({} kept from an earlier run) in {} -> {}",
        frames.len(),
        skipped,
        args.output.display(),
        animation.display()
    );
    Ok(())
}

fn flip_spec(frame: &Frame, stepping: Stepping) -> FlipSpec {
    FlipSpec::new(frame.params, frame.grid, stepping)
}

fn lyapunov_spec(args: &SweepArgs, frame: &Frame, stepping: Stepping) -> LyapunovSpec {
    LyapunovSpec {
        params: frame.params,
        grid: frame.grid,
        stepping,
        method: Method::Tangent,
        renorm: args.renorm,
        use_symmetry: true,
    }
}

/// The command that reproduces one frame as a single map; it identifies the frame when a
/// sweep resumes.
fn frame_command(args: &SweepArgs, frame: &Frame, stepping: Stepping, on_gpu: bool) -> String {
    let backend = if on_gpu { Backend::Gpu } else { Backend::Cpu };
    let flags = args.grid.picture.flags();
    match args.map {
        MapKind::Flip => flip_command_line(&flip_spec(frame, stepping), backend) + &flags,
        MapKind::Lyapunov => {
            crate::cli::lyapunov_command_line(&lyapunov_spec(args, frame, stepping), None, backend)
                + &flags
        }
    }
}

/// Renders one frame, on the GPU unless it needs f64.
fn render_frame(
    args: &SweepArgs,
    frame: &Frame,
    stepping: Stepping,
    kernels: &Kernels,
    monitor: &Monitor,
) -> Result<(crate::cli::Picture, RunInfo)> {
    let gpu = match kernels {
        Kernels::Gpu(k) if !frame.needs_f64 => Some((&k.0, &k.1, &k.2)),
        _ => None,
    };
    let info = RunInfo {
        backend: if gpu.is_some() { "gpu" } else { "cpu" },
        adapter: gpu.map(|(ctx, ..)| ctx.adapter_name()),
        notice: None,
    };
    let picture = match args.map {
        MapKind::Flip => {
            let spec = flip_spec(frame, stepping);
            let field = match gpu {
                Some((ctx, Some(k), _)) => k.run(ctx, &spec, monitor)?,
                _ => cpu::flip_map(&spec, monitor)?,
            };
            flip_picture(&field, &spec, &args.grid.picture)?
        }
        MapKind::Lyapunov => {
            let spec = lyapunov_spec(args, frame, stepping);
            let field = match gpu {
                Some((ctx, _, Some(k))) => k.run(ctx, &spec, monitor)?,
                _ => cpu::ftle_map(&spec, monitor)?,
            };
            lyapunov_picture(
                &field,
                &spec,
                (0.0, args.ftle_max as f32),
                &args.grid.picture,
            )?
        }
    };
    Ok((picture, info))
}
