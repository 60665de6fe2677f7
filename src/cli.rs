//! The command line: clap flags -> validated specs -> runs -> files.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use crate::engine::{self, Backend, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::render::{self, Annotation, Axis, ColorBar, Colormap, FlipColors};
use crate::spec::{self, FlipSpec, Grid, LyapunovSpec, Method, Range, Stepping};
use crate::{cpu, gpu};

#[derive(Parser, Debug)]
#[command(
    name = "chaoscope",
    version,
    about = "Chaos in the double pendulum, millions of pendulums at once"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Flip-time map: time until either arm first flips over, for a grid of starts.
    Flip(FlipArgs),
    /// Divergence map: the largest finite-time Lyapunov exponent (1/s) of every start; with
    /// single angles (--theta1 A --theta2 B), its convergence over time as CSV `t,ftle`.
    Lyapunov(LyapunovArgs),
    /// One trajectory as CSV: t,theta1,omega1,theta2,omega2,x1,y1,x2,y2,energy,dissipated
    /// (after a `#` line with the command that reproduces it).
    Trajectory(TrajectoryArgs),
    /// Frames of a map while a parameter changes (--vary) or zooming into a point (--zoom-to),
    /// as numbered PNGs and an animated PNG; an interrupted sweep resumes where it stopped.
    Sweep(crate::sweep::SweepArgs),
    /// Long-exposure light trails of the lower bob for releases from "the same" start.
    Traces(crate::views::TracesArgs),
    /// Phase portraits, omega against theta of each arm, as time-density images; --single for
    /// the single pendulum with its separatrix.
    Phase(crate::views::PhaseArgs),
    /// Fit the model to a camera's tracked positions: pivot, arm lengths, energies and their
    /// decay, the state and damping by a GPU ensemble search; plots and summary.json.
    Fit(crate::fit::FitArgs),
    /// GPU adapters found, the one chosen, its limits and features.
    Info,
    /// Throughput of the GPU and CPU paths on FLIP-512, optionally beside the peers.
    Bench(crate::bench::BenchArgs),
}

pub use crate::physics_args::PhysicalArgs;

/// How a map becomes a picture.
#[derive(Args, Debug, Clone, Default)]
pub struct PictureArgs {
    /// Frame the map with theta axes (ticks at multiples of pi), a colour bar with units and
    /// a title. Without it the PNG is the bare map, one pixel a pendulum.
    #[arg(long)]
    pub annotate: bool,
    /// Colour map (default: inferno for flip times, magma for exponents).
    #[arg(long, value_enum)]
    pub colormap: Option<Colormap>,
}

impl PictureArgs {
    /// The flags as they appear in a reproducing command line.
    pub fn flags(&self) -> String {
        let mut out = String::new();
        if self.annotate {
            out.push_str(" --annotate");
        }
        if let Some(c) = self.colormap {
            out.push_str(&format!(" --colormap {}", c.name()));
        }
        out
    }
}

/// The grid of starts and the physics, shared by the map commands.
#[derive(Args, Debug, Clone)]
pub struct GridArgs {
    /// Grid size: N (square) or WxH, one pendulum per pixel.
    #[arg(long, default_value = "512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// theta1 range along x, MIN:MAX in rad (`pi` is understood: -pi:pi).
    #[arg(long, default_value = "-pi:pi", value_parser = parse_range, allow_hyphen_values = true)]
    pub theta1: Range,
    /// theta2 range along y (top = MAX), MIN:MAX in rad.
    #[arg(long, default_value = "-pi:pi", value_parser = parse_range, allow_hyphen_values = true)]
    pub theta2: Range,
    /// Initial angular velocity of the upper arm (rad/s), the same for every pixel.
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    /// Initial angular velocity of the lower arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
    /// RK4 time step (s).
    #[arg(long, default_value = "0.01", value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    #[command(flatten)]
    pub picture: PictureArgs,
}

impl GridArgs {
    pub fn grid(&self) -> Grid {
        let (width, height) = self.size;
        Grid {
            width,
            height,
            theta1: self.theta1,
            theta2: self.theta2,
            omega1: self.omega1,
            omega2: self.omega2,
        }
    }

    /// The flip map of these flags up to `t_max`.
    pub fn flip_spec(&self, t_max: f64) -> Result<FlipSpec> {
        let stepping = Stepping { dt: self.dt, t_max };
        Ok(FlipSpec::new(
            self.physical.params()?,
            self.grid(),
            stepping,
        ))
    }
}

#[derive(Args, Debug, Clone)]
pub struct FlipArgs {
    #[command(flatten)]
    pub grid: GridArgs,
    /// Simulated time (s); pixels that have not flipped by then are "never".
    #[arg(long, default_value = "30", value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    /// PNG to write.
    #[arg(long, default_value = "out/flip.png")]
    pub output: PathBuf,
    /// Raw flip times (s) as float32 .npy, shape (height, width), row 0 = top, inf = never.
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Benchmarking: integrate every pixel for every step (no early exit, no skipped starts,
    /// no mirrored half).
    #[arg(long)]
    pub full: bool,
    /// Integrate both halves of a point-symmetric grid (theta ranges centred on 0, released
    /// from rest) instead of mirroring the top half: the same map, twice the work.
    #[arg(long)]
    pub no_symmetry: bool,
}

impl FlipArgs {
    pub fn spec(&self) -> Result<FlipSpec> {
        Ok(FlipSpec {
            early_exit: !self.full,
            use_symmetry: !(self.full || self.no_symmetry),
            ..self.grid.flip_spec(self.t_max)?
        })
    }
}

/// An angle flag of `lyapunov`: a range of the map, or the single start of a convergence run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Angles {
    Range(Range),
    Point(f64),
}

fn parse_angles(s: &str) -> std::result::Result<Angles, String> {
    if s.contains(':') {
        parse_range(s).map(Angles::Range)
    } else {
        parse_number(s).map(Angles::Point)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Tangent (variational) equations by dual numbers: works in f32.
    Tangent,
    /// A second trajectory --eps away, renormalised back to --eps.
    Twin,
}

#[derive(Args, Debug, Clone)]
pub struct LyapunovArgs {
    /// Grid size: N (square) or WxH, one pendulum per pixel.
    #[arg(long, default_value = "512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// theta1 range along x, MIN:MAX in rad; or one angle for a single-point convergence run.
    #[arg(long, default_value = "-pi:pi", value_parser = parse_angles, allow_hyphen_values = true)]
    pub theta1: Angles,
    /// theta2 range along y (top = MAX), MIN:MAX in rad; or one angle.
    #[arg(long, default_value = "-pi:pi", value_parser = parse_angles, allow_hyphen_values = true)]
    pub theta2: Angles,
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
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
    #[arg(long, value_enum, default_value = "tangent")]
    pub method: MethodArg,
    /// Twin separation (Euclidean in theta1, omega1, theta2, omega2), for --method twin.
    #[arg(long, default_value = "1e-8", value_parser = parse_number, allow_hyphen_values = true)]
    pub eps: f64,
    /// Integrate both halves of a point-symmetric grid with the tangent method instead of
    /// mirroring the top half: the same map, twice the work.
    #[arg(long)]
    pub no_symmetry: bool,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// Default: auto for a map, cpu (f64) for a single point.
    #[arg(long, value_enum)]
    pub backend: Option<Backend>,
    /// PNG for a map (default out/lyapunov.png); CSV for a single point (default stdout).
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Raw exponents (1/s) as float32 .npy, shape (height, width), row 0 = top.
    #[arg(long)]
    pub data: Option<PathBuf>,
    #[command(flatten)]
    pub picture: PictureArgs,
}

/// One start: both angles required, angular velocities 0 unless given.
#[derive(Args, Debug, Clone)]
pub struct StartArgs {
    /// Initial upper-arm angle (rad).
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub theta1: f64,
    /// Initial lower-arm angle (rad).
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub theta2: f64,
    /// Initial angular velocity of the upper arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    /// Initial angular velocity of the lower arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
}

impl StartArgs {
    /// The start, every component finite (else an error naming the flag).
    pub fn state(&self) -> Result<State> {
        let s = State {
            theta1: self.theta1,
            omega1: self.omega1,
            theta2: self.theta2,
            omega2: self.omega2,
        };
        spec::validate_start(&s)?;
        Ok(s)
    }

    /// The flags as they appear in a reproducing command line.
    pub fn flags(&self) -> String {
        format!(
            "--theta1 {} --theta2 {} --omega1 {} --omega2 {}",
            self.theta1, self.theta2, self.omega1, self.omega2
        )
    }
}

#[derive(Args, Debug, Clone)]
pub struct TrajectoryArgs {
    #[command(flatten)]
    pub start: StartArgs,
    #[arg(long, default_value = "10", value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    #[arg(long, default_value = "0.01", value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    /// Output interval (s), a multiple of dt; default every step.
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub every: Option<f64>,
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Backend,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// CSV to write; standard output if absent.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

/// A number, or a multiple or fraction of pi: `1.5`, `-pi`, `pi/2`, `2pi`, `-0.5*pi`, `3pi/4`.
pub fn parse_number(s: &str) -> std::result::Result<f64, String> {
    let t = s.trim().to_ascii_lowercase();
    if let Some(i) = t.find("pi") {
        let (head, tail) = (&t[..i], &t[i + 2..]);
        let head = head.trim_end_matches('*');
        let factor = match head {
            "" | "+" => 1.0,
            "-" => -1.0,
            h => h
                .parse::<f64>()
                .map_err(|_| format!("`{s}` is not a number"))?,
        };
        let divisor = match tail {
            "" => 1.0,
            d => d
                .strip_prefix('/')
                .and_then(|d| d.parse::<f64>().ok())
                .ok_or_else(|| format!("`{s}` is not a number"))?,
        };
        Ok(factor * std::f64::consts::PI / divisor)
    } else {
        t.parse::<f64>()
            .map_err(|_| format!("`{s}` is not a number"))
    }
}

pub fn parse_range(s: &str) -> std::result::Result<Range, String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("`{s}` must be MIN:MAX, e.g. -pi:pi"))?;
    Ok(Range {
        min: parse_number(a)?,
        max: parse_number(b)?,
    })
}

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let side = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("`{s}` must be N or WxH with whole numbers"))
    };
    match s.split_once(['x', 'X']) {
        Some((w, h)) => Ok((side(w)?, side(h)?)),
        None => side(s).map(|n| (n, n)),
    }
}

/// The command that reproduces a flip map, for the PNG metadata.
pub fn flip_command_line(spec: &FlipSpec, backend: Backend) -> String {
    let (g, p, s) = (&spec.grid, &spec.params, &spec.stepping);
    let backend = backend_name(backend);
    format!(
        "chaoscope flip --size {}x{} --theta1 {}:{} --theta2 {}:{} --omega1 {} --omega2 {} --t-max {} --dt {} {} --backend {}{}",
        g.width,
        g.height,
        g.theta1.min,
        g.theta1.max,
        g.theta2.min,
        g.theta2.max,
        g.omega1,
        g.omega2,
        s.t_max,
        s.dt,
        crate::physics_args::flags(p),
        backend,
        if spec.early_exit { "" } else { " --full" }
    )
}

/// A rendered map: bare (one pixel a pendulum) or annotated, with where the map sits.
pub struct Picture {
    pub rgb: Vec<u8>,
    pub width: u32,
    pub height: u32,
    /// (x, y, width, height) of the map inside an annotated picture.
    pub map: Option<(u32, u32, u32, u32)>,
}

impl Picture {
    fn metadata(&self) -> Vec<(String, String)> {
        match self.map {
            Some((x, y, w, h)) => vec![(
                "chaoscope:map-region".into(),
                format!("{w}x{h} map at x {x}, y {y} (top left); the rest is annotation"),
            )],
            None => Vec::new(),
        }
    }
}

fn frame(
    field: &Field,
    rgb: Vec<u8>,
    annotate: bool,
    a: impl FnOnce() -> Annotation,
) -> Result<Picture> {
    if !annotate {
        return Ok(Picture {
            rgb,
            width: field.width,
            height: field.height,
            map: None,
        });
    }
    let out = render::annotate(&rgb, field.width, field.height, &a())?;
    Ok(Picture {
        rgb: out.rgb,
        width: out.width,
        height: out.height,
        map: Some((out.map_x, out.map_y, field.width, field.height)),
    })
}

fn axes(grid: &Grid) -> (Axis, Axis) {
    (
        Axis {
            label: "θ1 (rad)".into(),
            min: grid.theta1.min,
            max: grid.theta1.max,
            decimal: false,
        },
        Axis {
            label: "θ2".into(),
            min: grid.theta2.min,
            max: grid.theta2.max,
            decimal: false,
        },
    )
}

fn physics_line(p: &Params, grid: &Grid) -> String {
    let mut line = format!(
        "m1 {} kg · m2 {} kg · l1 {} m · l2 {} m · g {} m/s² · ω0 ({}, {}) rad/s",
        p.m1, p.m2, p.l1, p.l2, p.g, grid.omega1, grid.omega2
    );
    if p.rod1 != 0.0 || p.rod2 != 0.0 {
        line += &format!(" · rods {}/{} kg", p.rod1, p.rod2);
    }
    let l = &p.losses;
    if l.joint1 != 0.0 || l.joint2 != 0.0 {
        line += &format!(" · damping {}/{} N m s", l.joint1, l.joint2);
    }
    if l.has_drag() {
        line += " · air drag";
    }
    if l.has_bearings() {
        line += " · bearing friction";
    }
    line
}

/// The flip map as a picture (`--annotate`, `--colormap`).
pub fn flip_picture(field: &Field, spec: &FlipSpec, picture: &PictureArgs) -> Result<Picture> {
    let colors = FlipColors {
        t_lo: (spec.params.l1 / spec.params.g).sqrt(),
        t_max: spec.stepping.t_max,
        colormap: picture.colormap.unwrap_or(Colormap::Inferno),
    };
    let rgb = render::flip_colors(field, colors);
    frame(field, rgb, picture.annotate, || {
        let (x, y) = axes(&spec.grid);
        let (colors_, ticks) = colors.bar();
        Annotation {
            title: "Time until an arm first flips over".into(),
            subtitle: format!(
                "{} · RK4 dt {} s",
                physics_line(&spec.params, &spec.grid),
                spec.stepping.dt
            ),
            x,
            y,
            bar: ColorBar {
                colors: colors_,
                ticks,
                label: "flip time (s)".into(),
                swatch: Some((render::NEVER_RGB, format!("> {} s", spec.stepping.t_max))),
            },
        }
    })
}

/// The divergence map as a picture, coloured over `range` (1/s).
pub fn lyapunov_picture(
    field: &Field,
    spec: &LyapunovSpec,
    range: (f32, f32),
    picture: &PictureArgs,
) -> Result<Picture> {
    let colormap = picture.colormap.unwrap_or(Colormap::Magma);
    let rgb = render::ftle_colors(field, range, colormap);
    frame(field, rgb, picture.annotate, || {
        let (x, y) = axes(&spec.grid);
        let (lo, hi) = (range.0 as f64, range.1 as f64);
        let ticks = render::decimal_ticks(lo, hi)
            .into_iter()
            .map(|(v, l)| ((v - lo) / (hi - lo), l))
            .collect();
        Annotation {
            title: format!(
                "Largest finite-time Lyapunov exponent over {} s",
                spec.stepping.t_max
            ),
            subtitle: format!(
                "{} · RK4 dt {} s · renormalised every {} s",
                physics_line(&spec.params, &spec.grid),
                spec.stepping.dt,
                spec.renorm
            ),
            x,
            y,
            bar: ColorBar {
                colors: render::ftle_table(colormap),
                ticks,
                label: "FTLE (1/s)".into(),
                swatch: None,
            },
        }
    })
}

/// The command that reproduces a divergence map or convergence run.
pub fn lyapunov_command_line(
    spec: &LyapunovSpec,
    point: Option<State>,
    backend: Backend,
) -> String {
    let (g, p, s) = (&spec.grid, &spec.params, &spec.stepping);
    let where_ = match point {
        Some(a) => format!(
            "--theta1 {} --theta2 {} --omega1 {} --omega2 {}",
            a.theta1, a.theta2, a.omega1, a.omega2
        ),
        None => format!(
            "--size {}x{} --theta1 {}:{} --theta2 {}:{} --omega1 {} --omega2 {}",
            g.width,
            g.height,
            g.theta1.min,
            g.theta1.max,
            g.theta2.min,
            g.theta2.max,
            g.omega1,
            g.omega2
        ),
    };
    let method = match spec.method {
        Method::Tangent => "--method tangent".to_string(),
        Method::Twin { eps } => format!("--method twin --eps {eps}"),
    };
    format!(
        "chaoscope lyapunov {where_} --t-max {} --dt {} --renorm {} {method} {} --backend {}",
        s.t_max,
        s.dt,
        spec.renorm,
        crate::physics_args::flags(p),
        backend_name(backend)
    )
}

fn backend_name(backend: Backend) -> &'static str {
    match backend {
        Backend::Auto => "auto",
        Backend::Gpu => "gpu",
        Backend::Cpu => "cpu",
    }
}

/// PNG text chunks that let an image be reproduced from itself.
pub fn png_metadata(command: String, info: &RunInfo) -> Vec<(String, String)> {
    vec![
        (
            "Software".into(),
            format!("chaoscope {}", env!("CARGO_PKG_VERSION")),
        ),
        ("chaoscope:command".into(), command),
        ("chaoscope:backend".into(), info.backend.into()),
        (
            "chaoscope:adapter".into(),
            info.adapter
                .clone()
                .unwrap_or_else(|| "none (CPU f64)".into()),
        ),
    ]
}

fn flip(args: &FlipArgs, monitor: &Monitor) -> Result<()> {
    let spec = args.spec()?;
    spec.validate()?;
    check_extension("--output", &args.output, "png")?;
    if let Some(data) = &args.data {
        check_extension("--data", data, "npy")?;
    }
    let started = std::time::Instant::now();
    let (field, info) = engine::flip_map(&spec, args.grid.backend, monitor)?;
    if let Some(notice) = &info.notice {
        eprintln!("{notice}");
    }
    let picture = flip_picture(&field, &spec, &args.grid.picture)?;
    let command = flip_command_line(&spec, args.grid.backend) + &args.grid.picture.flags();
    let mut meta = png_metadata(command, &info);
    meta.extend(picture.metadata());
    render::write_png(
        &args.output,
        picture.width,
        picture.height,
        &picture.rgb,
        &meta,
    )?;
    if let Some(data) = &args.data {
        render::write_npy(data, &field)?;
    }
    let flipped = field.data.iter().filter(|t| t.is_finite()).count();
    eprintln!(
        "{}x{} on {} in {:.2} s: {:.1} % flipped within {} s -> {}",
        field.width,
        field.height,
        info.adapter.as_deref().unwrap_or("the CPU"),
        started.elapsed().as_secs_f64(),
        100.0 * flipped as f64 / field.data.len() as f64,
        spec.stepping.t_max,
        args.output.display()
    );
    Ok(())
}

fn lyapunov(args: &LyapunovArgs, monitor: &Monitor) -> Result<()> {
    let method = match args.method {
        MethodArg::Tangent => Method::Tangent,
        MethodArg::Twin => Method::Twin { eps: args.eps },
    };
    let (width, height) = args.size;
    let point = match (args.theta1, args.theta2) {
        (Angles::Point(a), Angles::Point(b)) => Some((a, b)),
        (Angles::Range(_), Angles::Range(_)) => None,
        (Angles::Point(_), Angles::Range(_)) => {
            return Err(Error::invalid(
                "--theta2",
                "must be one angle too when --theta1 is one angle (a single-point run)",
            ));
        }
        (Angles::Range(_), Angles::Point(_)) => {
            return Err(Error::invalid(
                "--theta1",
                "must be one angle too when --theta2 is one angle (a single-point run)",
            ));
        }
    };
    let range = |a: Angles| match a {
        Angles::Range(r) => r,
        Angles::Point(x) => Range {
            min: x - 1e-3,
            max: x + 1e-3,
        },
    };
    let spec = LyapunovSpec {
        params: args.physical.params()?,
        grid: Grid {
            width,
            height,
            theta1: range(args.theta1),
            theta2: range(args.theta2),
            omega1: args.omega1,
            omega2: args.omega2,
        },
        stepping: Stepping {
            dt: args.dt,
            t_max: args.t_max,
        },
        method,
        renorm: args.renorm,
        use_symmetry: !args.no_symmetry,
    };
    match point {
        Some((theta1, theta2)) => {
            let start = State {
                theta1,
                omega1: args.omega1,
                theta2,
                omega2: args.omega2,
            };
            lyapunov_point(args, &spec, start, monitor)
        }
        None => lyapunov_map(args, &spec, monitor),
    }
}

fn lyapunov_point(
    args: &LyapunovArgs,
    spec: &LyapunovSpec,
    start: State,
    monitor: &Monitor,
) -> Result<()> {
    spec.validate_run()?;
    spec::validate_start(&start)?;
    if let Some(path) = &args.output {
        check_extension("--output", path, "csv")?;
    }
    if args.data.is_some() {
        return Err(Error::invalid(
            "--data",
            "is for maps; a single-point run writes its CSV to --output",
        ));
    }
    let backend = args.backend.unwrap_or(Backend::Cpu);
    let trace = match engine::resolve(backend)? {
        (Some(ctx), _) => {
            // A one-pixel grid whose centre is the start (the point's ranges are start +- 1e-3).
            let one = LyapunovSpec {
                grid: Grid {
                    width: 1,
                    height: 1,
                    ..spec.grid
                },
                ..*spec
            };
            twin_notice(spec);
            gpu::LyapunovKernel::new(&ctx, spec.method).convergence(&ctx, &one, monitor)?
        }
        (None, notice) => {
            if let Some(n) = notice {
                eprintln!("{n}");
            }
            cpu::ftle(spec, start)
        }
    };
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(w, "t,ftle")?;
        for (t, l) in trace.t.iter().zip(&trace.ftle) {
            writeln!(w, "{t},{l}")?;
        }
        Ok(())
    };
    match &args.output {
        Some(path) => {
            render::write_atomic(path, |w| write(w))?;
            eprintln!(
                "FTLE at {} s: {:.4} /s -> {}",
                spec.stepping.t_max,
                trace.last(),
                path.display()
            );
            Ok(())
        }
        None => write(&mut std::io::stdout().lock()),
    }
}

/// f32 cannot resolve a twin separation much below 1e-6 of the state: say so once.
fn twin_notice(spec: &LyapunovSpec) {
    if let Method::Twin { eps } = spec.method
        && eps < 1e-4
    {
        eprintln!(
            "note: --eps {eps} is close to f32 round-off on the GPU (~1e-7 of the state): the twin reads noise; use --method tangent, a larger --eps, or --backend cpu"
        );
    }
}

fn lyapunov_map(args: &LyapunovArgs, spec: &LyapunovSpec, monitor: &Monitor) -> Result<()> {
    spec.validate()?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/lyapunov.png"));
    check_extension("--output", &output, "png")?;
    if let Some(data) = &args.data {
        check_extension("--data", data, "npy")?;
    }
    let backend = args.backend.unwrap_or(Backend::Auto);
    if backend != Backend::Cpu {
        twin_notice(spec);
    }
    let started = std::time::Instant::now();
    let (field, info) = engine::lyapunov_map(spec, backend, monitor)?;
    if let Some(notice) = &info.notice {
        eprintln!("{notice}");
    }
    let range = render::ftle_range(&field);
    let picture = lyapunov_picture(&field, spec, range, &args.picture)?;
    let command = lyapunov_command_line(spec, None, backend) + &args.picture.flags();
    let mut meta = png_metadata(command, &info);
    meta.extend(picture.metadata());
    meta.push((
        "chaoscope:colour-range".into(),
        format!(
            "FTLE {} .. {} 1/s, {}, linear (low = regular)",
            range.0,
            range.1,
            args.picture.colormap.unwrap_or(Colormap::Magma).name()
        ),
    ));
    render::write_png(&output, picture.width, picture.height, &picture.rgb, &meta)?;
    if let Some(data) = &args.data {
        render::write_npy(data, &field)?;
    }
    let chaotic = field.data.iter().filter(|&&x| x > CHAOTIC_FTLE).count();
    eprintln!(
        "{}x{} on {} in {:.2} s: {:.1} % chaotic (FTLE > {CHAOTIC_FTLE} /s at {} s), colour range {:.2}..{:.2} /s -> {}",
        field.width,
        field.height,
        info.adapter.as_deref().unwrap_or("the CPU"),
        started.elapsed().as_secs_f64(),
        100.0 * chaotic as f64 / field.data.len() as f64,
        spec.stepping.t_max,
        range.0,
        range.1,
        output.display()
    );
    Ok(())
}

/// Exponent (1/s) above which the summary counts a pixel as chaotic: regular orbits stay
/// below ln(1 + K t) / t, about 0.27 /s at 20 s (tests/lyapunov.rs).
pub const CHAOTIC_FTLE: f32 = 0.5;

/// `path` must end in `.ext`, else an error naming `flag`.
pub fn check_extension(flag: &'static str, path: &Path, ext: &str) -> Result<()> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case(ext) => Ok(()),
        _ => Err(Error::invalid(
            flag,
            format!("{} must end in .{ext}", path.display()),
        )),
    }
}

/// Output stride in steps for `every` seconds, which must be a whole multiple of dt.
pub fn output_stride(every: Option<f64>, dt: f64) -> Result<u32> {
    let Some(every) = every else { return Ok(1) };
    let k = every / dt;
    let n = k.round();
    if !(every.is_finite() && every > 0.0) || n < 1.0 || (k - n).abs() > 1e-9 * n {
        return Err(Error::invalid(
            "--every",
            format!("{every} s must be a positive whole multiple of --dt {dt} s"),
        ));
    }
    Ok(n as u32)
}

fn trajectory(args: &TrajectoryArgs) -> Result<()> {
    let params = args.physical.params()?;
    let stepping = Stepping {
        dt: args.dt,
        t_max: args.t_max,
    };
    spec::validate_stepping(&stepping)?;
    let stride = output_stride(args.every, args.dt)?;
    let start = args.start.state()?;
    let steps = stepping.steps();
    let (states, dissipated) = match engine::resolve(args.backend)? {
        (Some(ctx), _) => {
            let states = gpu::trajectory(&ctx, &params, start, args.dt, steps)?;
            let work = cpu::dissipated_along(&params, &states, args.dt);
            (states, work)
        }
        (None, notice) => {
            if let Some(n) = notice {
                eprintln!("{n}");
            }
            cpu::trajectory_with_work(&params, start, args.dt, steps)
        }
    };
    let write = |w: &mut dyn Write| -> Result<()> {
        writeln!(
            w,
            "# chaoscope trajectory {} --t-max {} --dt {} {} --backend {}",
            args.start.flags(),
            args.t_max,
            args.dt,
            crate::physics_args::flags(&params),
            backend_name(args.backend)
        )?;
        writeln!(
            w,
            "t,theta1,omega1,theta2,omega2,x1,y1,x2,y2,energy,dissipated"
        )?;
        for (k, s) in states.iter().enumerate().step_by(stride as usize) {
            let pos = params.positions(s);
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{}",
                k as f64 * args.dt,
                s.theta1,
                s.omega1,
                s.theta2,
                s.omega2,
                pos.x1,
                pos.y1,
                pos.x2,
                pos.y2,
                params.energy(s),
                dissipated[k]
            )?;
        }
        Ok(())
    };
    match &args.output {
        Some(path) => render::write_atomic(path, |w| write(w)),
        None => write(&mut std::io::stdout().lock()),
    }
}

fn info() -> Result<()> {
    let adapters = gpu::list_adapters();
    println!("adapters found: {}", adapters.len());
    for a in &adapters {
        let i = a.get_info();
        println!(
            "  - {} ({:?}, {:?}, driver {} {})",
            i.name, i.backend, i.device_type, i.driver, i.driver_info
        );
    }
    match gpu::GpuContext::new() {
        Ok(ctx) => {
            println!("chosen: {}", ctx.adapter_name());
            let l = &ctx.limits;
            println!(
                "  max_storage_buffer_binding_size: {} MiB",
                l.max_storage_buffer_binding_size >> 20
            );
            println!("  max_buffer_size: {} MiB", l.max_buffer_size >> 20);
            println!(
                "  max_compute_workgroups_per_dimension: {}",
                l.max_compute_workgroups_per_dimension
            );
            println!(
                "  max_compute_invocations_per_workgroup: {}",
                l.max_compute_invocations_per_workgroup
            );
            let f = ctx.adapter_features;
            println!(
                "  adapter supports SHADER_F64: {}",
                f.contains(wgpu::Features::SHADER_F64)
            );
            println!("  adapter features: {f:?}");
        }
        Err(e) => println!("chosen: none ({e}); maps run on the CPU"),
    }
    Ok(())
}

/// Runs a parsed command. Invalid values exit 2 (like clap's own errors), other failures 1.
pub fn run(cli: Cli, monitor: &Monitor) -> ExitCode {
    let result = match &cli.command {
        Command::Flip(args) => flip(args, monitor),
        Command::Lyapunov(args) => lyapunov(args, monitor),
        Command::Trajectory(args) => trajectory(args),
        Command::Sweep(args) => crate::sweep::run(args, monitor),
        Command::Traces(args) => crate::views::traces(args, monitor),
        Command::Phase(args) => crate::views::phase(args, monitor),
        Command::Fit(args) => crate::fit::run(args),
        Command::Info => info(),
        Command::Bench(args) => crate::bench::run(args, monitor),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            match e {
                Error::InvalidSpec { .. } => ExitCode::from(2),
                Error::Interrupted => ExitCode::from(130),
                _ => ExitCode::FAILURE,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn numbers_with_pi() {
        assert_eq!(parse_number("-pi").unwrap(), -PI);
        assert_eq!(parse_number("pi/2").unwrap(), PI / 2.0);
        assert_eq!(parse_number("3pi/4").unwrap(), 3.0 * PI / 4.0);
        assert_eq!(parse_number("-0.5*pi").unwrap(), -0.5 * PI);
        assert_eq!(parse_number("-3").unwrap(), -3.0);
        assert!(parse_number("pie").is_err());
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("64").unwrap(), (64, 64));
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("64x").is_err());
    }
}
