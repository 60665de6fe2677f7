//! The lab report's pictures: long-exposure light trails of releases from "the same" start
//! (`traces`, figures 7-9) and phase portraits (`phase`, figures 3, 4, 18, 19).

use std::path::PathBuf;

use clap::Args;

use crate::cli::{PhysicalArgs, StartArgs, check_extension, parse_number, png_metadata};
use crate::cpu;
use crate::engine::{self, Backend, RunInfo};
use crate::error::{Error, Result};
use crate::gpu;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::render::{self, Bobs, Colormap, Film, View};
use crate::spec::{self, Stepping};

/// How far apart the releases start: an angle (rad) or a position error of the bobs
/// (`5mm`, `0.5cm`, `0.005m`), as the report quotes its release accuracy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spread {
    Radians(f64),
    Metres(f64),
}

fn parse_spread(s: &str) -> std::result::Result<Spread, String> {
    let t = s.trim();
    for (suffix, factor) in [("mm", 1e-3), ("cm", 1e-2), ("m", 1.0)] {
        if let Some(v) = t.strip_suffix(suffix) {
            return v
                .trim()
                .parse::<f64>()
                .map(|v| Spread::Metres(v * factor))
                .map_err(|_| format!("`{s}` is not a length"));
        }
    }
    parse_number(t.strip_suffix("rad").unwrap_or(t)).map(Spread::Radians)
}

/// The releases: `runs` starts around `start`, evenly on a circle of radius `spread` in the
/// (theta1, theta2) plane (a position error e moves arm i by e / l_i). Deterministic, so a
/// picture can be made again; with spread 0 all starts are identical.
pub fn releases(p: &Params, start: State, runs: u32, spread: Spread) -> Vec<State> {
    let (d1, d2) = match spread {
        Spread::Radians(r) => (r, r),
        Spread::Metres(e) => (e / p.l1, e / p.l2),
    };
    (0..runs)
        .map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / runs as f64;
            State {
                theta1: start.theta1 + d1 * phi.cos(),
                theta2: start.theta2 + d2 * phi.sin(),
                ..start
            }
        })
        .collect()
}

/// Trajectories of all `starts` on the chosen backend (GPU: one invocation per run).
pub fn ensemble(
    p: &Params,
    starts: &[State],
    stepping: Stepping,
    backend: Backend,
) -> Result<(Vec<Vec<State>>, RunInfo)> {
    let steps = stepping.steps();
    let (ctx, notice) = engine::resolve(backend)?;
    match ctx {
        Some(ctx) => {
            let runs = gpu::trajectories(&ctx, p, starts, stepping.dt, steps)?;
            let info = RunInfo {
                backend: "gpu",
                adapter: Some(ctx.adapter_name()),
                notice,
            };
            Ok((runs, info))
        }
        None => {
            use rayon::prelude::*;
            let runs = starts
                .par_iter()
                .map(|s| cpu::trajectory(p, *s, stepping.dt, steps))
                .collect();
            let info = RunInfo {
                backend: "cpu",
                adapter: None,
                notice,
            };
            Ok((runs, info))
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct TracesArgs {
    /// The release (nominal start) of every run.
    #[command(flatten)]
    pub start: StartArgs,
    /// Number of releases.
    #[arg(long, default_value = "3")]
    pub runs: u32,
    /// Distance between releases: rad (0.01) or a position error (5mm, the report's).
    #[arg(long, default_value = "5mm", value_parser = parse_spread)]
    pub spread: Spread,
    /// Exposure time (s): the report's photographs were 3.2 s.
    #[arg(long, default_value = "3.2", value_parser = parse_number, allow_hyphen_values = true)]
    pub exposure: f64,
    /// RK4 time step (s); small, so the trails are smooth.
    #[arg(long, default_value = "0.001", value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    /// Picture side (px).
    #[arg(long, default_value = "1024")]
    pub size: u32,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    /// PNG to write.
    #[arg(long, default_value = "out/traces.png")]
    pub output: PathBuf,
    /// Also an animated GIF of the pendulums swinging and parting.
    #[arg(long)]
    pub gif: Option<PathBuf>,
    /// Lower-bob positions as float32 .npy, shape (runs, samples, 4): x1, y1, x2, y2 (m).
    #[arg(long)]
    pub data: Option<PathBuf>,
}

/// Colour of run k of n: evenly spaced hues of the cyclic sinebow map.
fn run_color(k: usize, n: usize) -> [u8; 3] {
    let g = Colormap::Sinebow.gradient();
    let [r, gg, b, _] = g.at((k as f32 + 0.5) / n as f32).to_rgba8();
    [r, gg, b]
}

pub fn traces(args: &TracesArgs, monitor: &Monitor) -> Result<()> {
    let p = args.physical.params()?;
    let stepping = Stepping {
        dt: args.dt,
        t_max: args.exposure,
    };
    // The exposure is this command's t-max: name it as the user wrote it.
    spec::validate_stepping(&stepping).map_err(|e| match e {
        Error::InvalidSpec {
            flag: "--t-max",
            reason,
        } => Error::invalid("--exposure", reason),
        e => e,
    })?;
    if !(1..=100_000).contains(&args.runs) {
        return Err(Error::invalid("--runs", "must be between 1 and 100000"));
    }
    if !(16..=8192).contains(&args.size) {
        return Err(Error::invalid("--size", "must be between 16 and 8192 px"));
    }
    let spread_ok = match args.spread {
        Spread::Radians(r) | Spread::Metres(r) => r.is_finite() && (0.0..=1.0).contains(&r),
    };
    if !spread_ok {
        return Err(Error::invalid(
            "--spread",
            "must be between 0 and 1 (rad, or m with a unit)",
        ));
    }
    check_extension("--output", &args.output, "png")?;
    if let Some(g) = &args.gif {
        check_extension("--gif", g, "gif")?;
    }
    if let Some(d) = &args.data {
        check_extension("--data", d, "npy")?;
    }
    let start = args.start.state()?;
    monitor.check()?;
    let starts = releases(&p, start, args.runs, args.spread);
    let (runs, info) = ensemble(&p, &starts, stepping, args.backend)?;
    if let Some(n) = &info.notice {
        eprintln!("{n}");
    }
    let positions: Vec<Vec<Bobs>> = runs
        .iter()
        .map(|r| {
            r.iter()
                .map(|s| {
                    let q = p.positions(s);
                    (q.x1, q.y1, q.x2, q.y2)
                })
                .collect()
        })
        .collect();
    let view = View {
        size: args.size,
        reach: 1.08 * (p.l1 + p.l2),
    };
    let n = positions.len();
    let colors: Vec<[u8; 3]> = (0..n).map(|k| run_color(k, n)).collect();
    let speed = reference_speed(&positions, args.dt);
    let mut film = Film::new(view);
    expose(&mut film, &positions, &colors, args.dt, 0, usize::MAX);
    let rgb = develop(&film, speed, &positions, &colors, None, n)?;
    let command = format!(
        "chaoscope traces {} --runs {} --spread {} --exposure {} --dt {} --size {} {}",
        args.start.flags(),
        args.runs,
        match args.spread {
            Spread::Radians(r) => format!("{r}"),
            Spread::Metres(m) => format!("{m}m"),
        },
        args.exposure,
        args.dt,
        args.size,
        crate::physics_args::flags(&p)
    );
    let meta = png_metadata(command, &info);
    render::write_png(&args.output, args.size, args.size, &rgb, &meta)?;
    if let Some(path) = &args.data {
        let samples = positions[0].len();
        let flat: Vec<f32> = positions
            .iter()
            .flatten()
            .flat_map(|q| [q.0 as f32, q.1 as f32, q.2 as f32, q.3 as f32])
            .collect();
        render::write_npy_shaped(path, &[n as u64, samples as u64, 4], &flat)?;
    }
    if let Some(path) = &args.gif {
        write_gif(path, &p, &positions, &colors, speed, args, monitor)?;
    }
    eprintln!(
        "{} releases over {} s on {} -> {}",
        n,
        args.exposure,
        info.adapter.as_deref().unwrap_or("the CPU"),
        args.output.display()
    );
    Ok(())
}

/// Exposes the lower bobs' trails between samples `from` and `to` (exclusive) onto `film`.
fn expose(
    film: &mut Film,
    positions: &[Vec<Bobs>],
    colors: &[[u8; 3]],
    dt: f64,
    from: usize,
    to: usize,
) {
    for (run, color) in positions.iter().zip(colors) {
        let c = color.map(|v| v as f32 / 255.0);
        let to = run.len().min(to);
        if to > from + 1 {
            for w in run[from..to].windows(2) {
                film.expose_segment((w[0].2, w[0].3), (w[1].2, w[1].3), dt, c);
            }
        }
    }
}

/// Develops `film` (half brightness at `speed`, see `reference_speed`) and draws the arms of
/// the first `arms` runs: at the start, grey and faint, for the photograph (`sample` None);
/// at `sample`, in each run's colour, for an animation frame.
fn develop(
    film: &Film,
    speed: f64,
    positions: &[Vec<Bobs>],
    colors: &[[u8; 3]],
    sample: Option<usize>,
    arms: usize,
) -> Result<Vec<u8>> {
    let mut rgb = film.develop(speed);
    let drawn: Vec<_> = positions
        .iter()
        .zip(colors)
        .take(arms)
        .map(|(run, c)| match sample {
            None => (run[0], [200, 200, 200]),
            Some(k) => (run[k.min(run.len() - 1)], *c),
        })
        .collect();
    let alpha = if sample.is_none() { 0.25 } else { 0.85 };
    let radius = (film.view.size / 120).max(2) as i32;
    render::draw_arms(&mut rgb, film.view, &drawn, alpha, radius)?;
    Ok(rgb)
}

/// Twice the median speed (m/s) of the lower bob over all runs: a bob crossing a pixel at
/// that speed develops to half brightness, so typical stretches show clearly and the slow
/// turning points saturate, as on the photographs.
fn reference_speed(positions: &[Vec<Bobs>], dt: f64) -> f64 {
    let mut speeds: Vec<f64> = positions
        .iter()
        .flat_map(|run| {
            run.windows(2)
                .map(|w| ((w[1].2 - w[0].2).powi(2) + (w[1].3 - w[0].3).powi(2)).sqrt() / dt)
        })
        .collect();
    if speeds.is_empty() {
        return 1.0;
    }
    let mid = speeds.len() / 2;
    let (_, median, _) = speeds.select_nth_unstable_by(mid, f64::total_cmp);
    (2.0 * *median).max(1e-3)
}

fn write_gif(
    path: &std::path::Path,
    p: &Params,
    positions: &[Vec<Bobs>],
    colors: &[[u8; 3]],
    speed: f64,
    args: &TracesArgs,
    monitor: &Monitor,
) -> Result<()> {
    const FPS: f64 = 25.0;
    let view = View {
        size: args.size.min(480),
        reach: 1.08 * (p.l1 + p.l2),
    };
    let samples = positions[0].len();
    let frames = ((args.exposure * FPS).round() as usize).max(1);
    monitor.start("gif", frames as u64);
    let mut rgb = Vec::with_capacity(frames);
    // One film, exposed a frame's worth further each time.
    let mut film = Film::new(view);
    let mut exposed = 0;
    for f in 1..=frames {
        monitor.check()?;
        let upto = ((f as f64 / frames as f64) * (samples - 1) as f64).round() as usize + 1;
        expose(&mut film, positions, colors, args.dt, exposed, upto);
        exposed = upto - 1;
        // Arms of at most 50 runs, or the picture is all arms.
        rgb.push(develop(
            &film,
            speed,
            positions,
            colors,
            Some(upto - 1),
            positions.len().min(50),
        )?);
        monitor.advance(1);
    }
    monitor.finish();
    render::write_gif(
        path,
        view.size,
        view.size,
        &rgb,
        (100.0 / FPS).round() as u16,
    )
}

#[derive(Args, Debug, Clone)]
pub struct PhaseArgs {
    /// Start angle of the upper arm (rad); ignored with --single.
    #[arg(long, default_value = "2", value_parser = parse_number, allow_hyphen_values = true)]
    pub theta1: f64,
    /// Start angle of the lower arm (rad).
    #[arg(long, default_value = "2", value_parser = parse_number, allow_hyphen_values = true)]
    pub theta2: f64,
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
    /// Number of runs (starts spread as for `traces`); their time densities add up.
    #[arg(long, default_value = "1")]
    pub runs: u32,
    #[arg(long, default_value = "0.01", value_parser = parse_spread)]
    pub spread: Spread,
    /// Simulated time (s).
    #[arg(long, default_value = "60", value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    #[arg(long, default_value = "0.005", value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    /// Side of each panel (px).
    #[arg(long, default_value = "600")]
    pub size: u32,
    /// The single pendulum (length l1): libration and rotation orbits and the separatrix
    /// that divides them, the report's figure 4.
    #[arg(long)]
    pub single: bool,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    #[arg(long, value_enum)]
    pub colormap: Option<Colormap>,
    /// PNG to write.
    #[arg(long, default_value = "out/phase.png")]
    pub output: PathBuf,
}

/// Time spent (s) per cell of a (theta, omega) grid: theta wrapped to (-pi, pi] along x,
/// omega from `w_max` (top) to `-w_max` along y. Each step's time is spread along the segment
/// between its end points (at most half a cell apart), so fast stretches draw lines, not dots.
pub fn phase_density(
    runs: &[Vec<(f64, f64)>],
    dt: f64,
    size: u32,
    w_max: f64,
) -> crate::field::Field {
    use std::f64::consts::PI;
    let mut field = crate::field::Field::new(size, size, 0.0);
    let n = size as f64;
    let to_cell = |theta: f64, omega: f64| {
        let t = (theta + PI).rem_euclid(2.0 * PI) - PI;
        (
            (t + PI) / (2.0 * PI) * n,
            (w_max - omega) / (2.0 * w_max) * n,
        )
    };
    for run in runs {
        for w in run.windows(2) {
            let (a, b) = (to_cell(w[0].0, w[0].1), to_cell(w[1].0, w[1].1));
            // A step across the theta = +-pi seam: deposit at its start only.
            let seam = (b.0 - a.0).abs() > n / 2.0;
            let length = if seam {
                0.0
            } else {
                ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt()
            };
            let k = (2.0 * length).ceil().max(1.0) as usize;
            for i in 0..k {
                let s = if seam {
                    0.0
                } else {
                    (i as f64 + 0.5) / k as f64
                };
                let (col, row) = (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1));
                if (0.0..n).contains(&col) && (0.0..n).contains(&row) {
                    field.data[(row.floor() * n + col.floor()) as usize] += (dt / k as f64) as f32;
                }
            }
        }
    }
    field
}

/// A density panel: log of the time per cell over three decades below the maximum,
/// cells never visited in the background colour; framed with axes.
fn phase_panel(
    field: &crate::field::Field,
    w_max: f64,
    colormap: Colormap,
    title: String,
    subtitle: String,
    labels: (&str, &str),
    overlay: impl FnOnce(&mut [u8]) -> Result<()>,
) -> Result<render::Annotated> {
    let max = field
        .data
        .iter()
        .copied()
        .fold(0.0f32, f32::max)
        .max(f32::MIN_POSITIVE);
    let table = render::ftle_table(colormap);
    let decades = 3.0f32;
    let mut rgb = Vec::with_capacity(field.data.len() * 3);
    for &v in &field.data {
        let c = if v > 0.0 {
            let u = (1.0 + (v / max).log10() / decades).clamp(0.0, 1.0);
            // Visited cells start a little above the background.
            table[((0.08 + 0.92 * u) * (table.len() - 1) as f32).round() as usize]
        } else {
            table[0]
        };
        rgb.extend_from_slice(&c);
    }
    overlay(&mut rgb)?;
    let ticks = (0..=3)
        .map(|k| {
            let frac = 0.08 + 0.92 * (k as f64 / 3.0);
            (frac, format!("{:.0e}", max as f64 * 10f64.powi(k - 3)))
        })
        .collect();
    render::annotate(
        &rgb,
        field.width,
        field.height,
        &render::Annotation {
            title,
            subtitle,
            x: render::Axis {
                label: labels.0.into(),
                min: -std::f64::consts::PI,
                max: std::f64::consts::PI,
                decimal: false,
            },
            y: render::Axis {
                label: labels.1.into(),
                min: -w_max,
                max: w_max,
                decimal: true,
            },
            bar: render::ColorBar {
                colors: table[(0.08 * (table.len() - 1) as f32) as usize..].to_vec(),
                ticks,
                label: "time per cell (s)".into(),
                swatch: None,
            },
        },
    )
}

/// Panels side by side (same height).
fn side_by_side(panels: &[render::Annotated]) -> (Vec<u8>, u32, u32) {
    let height = panels.iter().map(|p| p.height).max().unwrap_or(0);
    let width: u32 = panels.iter().map(|p| p.width).sum();
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    let mut x0 = 0;
    for p in panels {
        for row in 0..p.height {
            let src = &p.rgb[(row * p.width * 3) as usize..((row + 1) * p.width * 3) as usize];
            let at = ((row * width + x0) * 3) as usize;
            rgb[at..at + src.len()].copy_from_slice(src);
        }
        x0 += p.width;
    }
    (rgb, width, height)
}

/// A bound on |omega| to show: the largest reached, with a margin, at least 1 rad/s.
fn omega_extent(values: impl Iterator<Item = f64>) -> f64 {
    (1.08 * values.fold(0.0f64, |m, w| m.max(w.abs()))).max(1.0)
}

pub fn phase(args: &PhaseArgs, monitor: &Monitor) -> Result<()> {
    let p = args.physical.params()?;
    let stepping = Stepping {
        dt: args.dt,
        t_max: args.t_max,
    };
    spec::validate_stepping(&stepping)?;
    if !(1..=100_000).contains(&args.runs) {
        return Err(Error::invalid("--runs", "must be between 1 and 100000"));
    }
    if !(32..=4096).contains(&args.size) {
        return Err(Error::invalid("--size", "must be between 32 and 4096 px"));
    }
    check_extension("--output", &args.output, "png")?;
    let colormap = args.colormap.unwrap_or(Colormap::Inferno);
    monitor.check()?;
    let (rgb, width, height, command, info) = if args.single {
        single_pendulum_portrait(&p, args, colormap)?
    } else {
        let start = State {
            theta1: args.theta1,
            omega1: args.omega1,
            theta2: args.theta2,
            omega2: args.omega2,
        };
        spec::validate_start(&start)?;
        let starts = releases(&p, start, args.runs, args.spread);
        let (runs, info) = ensemble(&p, &starts, stepping, args.backend)?;
        if let Some(n) = &info.notice {
            eprintln!("{n}");
        }
        let states = || runs.iter().flatten();
        let arm_runs = |arm: usize| -> Vec<Vec<(f64, f64)>> {
            runs.iter()
                .map(|r| {
                    r.iter()
                        .map(|s| {
                            if arm == 0 {
                                (s.theta1, s.omega1)
                            } else {
                                (s.theta2, s.omega2)
                            }
                        })
                        .collect()
                })
                .collect()
        };
        let subtitle = format!(
            "{} run(s) from θ ({}, {}) rad, ω ({}, {}) rad/s · {} s · m {} / {} kg · l {} / {} m",
            args.runs,
            args.theta1,
            args.theta2,
            args.omega1,
            args.omega2,
            args.t_max,
            p.m1,
            p.m2,
            p.l1,
            p.l2
        );
        let mut panels = Vec::new();
        for arm in 0..2 {
            let pick = |s: &State| {
                if arm == 0 {
                    (s.theta1, s.omega1)
                } else {
                    (s.theta2, s.omega2)
                }
            };
            let w_max = omega_extent(states().map(|s| pick(s).1));
            let field = phase_density(&arm_runs(arm), args.dt, args.size, w_max);
            let (title, labels) = if arm == 0 {
                ("Upper arm: ω1 (rad/s) against θ1", ("θ1 (rad)", "ω1"))
            } else {
                ("Lower arm: ω2 (rad/s) against θ2", ("θ2 (rad)", "ω2"))
            };
            panels.push(phase_panel(
                &field,
                w_max,
                colormap,
                title.into(),
                subtitle.clone(),
                labels,
                |_| Ok(()),
            )?);
        }
        let (rgb, w, h) = side_by_side(&panels);
        let command = format!(
            "chaoscope phase --theta1 {} --theta2 {} --omega1 {} --omega2 {} --runs {} --t-max {} --dt {} --size {} {}",
            args.theta1,
            args.theta2,
            args.omega1,
            args.omega2,
            args.runs,
            args.t_max,
            args.dt,
            args.size,
            crate::physics_args::flags(&p)
        );
        (rgb, w, h, command, info)
    };
    let meta = png_metadata(command, &info);
    render::write_png(&args.output, width, height, &rgb, &meta)?;
    eprintln!("phase portrait -> {}", args.output.display());
    Ok(())
}

/// theta'' = -(g/l) sin theta, RK4, from (theta, omega), `steps` steps of `dt`.
pub fn single_pendulum(
    g_over_l: f64,
    theta: f64,
    omega: f64,
    dt: f64,
    steps: u32,
) -> Vec<(f64, f64)> {
    let f = |(t, w): (f64, f64)| (w, -g_over_l * t.sin());
    let mut y = (theta, omega);
    let mut out = Vec::with_capacity(steps as usize + 1);
    out.push(y);
    for _ in 0..steps {
        let k1 = f(y);
        let k2 = f((y.0 + 0.5 * dt * k1.0, y.1 + 0.5 * dt * k1.1));
        let k3 = f((y.0 + 0.5 * dt * k2.0, y.1 + 0.5 * dt * k2.1));
        let k4 = f((y.0 + dt * k3.0, y.1 + dt * k3.1));
        y = (
            y.0 + dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            y.1 + dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        );
        out.push(y);
    }
    out
}

type Rendered = (Vec<u8>, u32, u32, String, RunInfo);

/// The single pendulum's phase portrait: librations from rest at 12 amplitudes, rotations at
/// 6 speeds above the separatrix, each over one period's worth of time at least, and the
/// separatrix omega = +-2 sqrt(g/l) cos(theta/2) drawn over them.
fn single_pendulum_portrait(p: &Params, args: &PhaseArgs, colormap: Colormap) -> Result<Rendered> {
    use std::f64::consts::PI;
    let k = p.g / p.l1;
    let w0 = k.sqrt();
    let w_sep = 2.0 * w0;
    let w_max = 1.6 * w_sep;
    let steps = Stepping {
        dt: args.dt,
        t_max: args.t_max,
    }
    .steps();
    let mut orbits: Vec<(f64, f64)> = (1..=12).map(|i| (i as f64 * PI / 13.0, 0.0)).collect();
    orbits.extend((1..=6).map(|i| (0.0, w_sep * (1.0 + 0.08 * i as f64))));
    orbits.extend((1..=6).map(|i| (0.0, -w_sep * (1.0 + 0.08 * i as f64))));
    let runs: Vec<Vec<(f64, f64)>> = orbits
        .iter()
        .map(|&(t, w)| single_pendulum(k, t, w, args.dt, steps))
        .collect();
    let field = phase_density(&runs, args.dt, args.size, w_max);
    let size = args.size;
    let panel = phase_panel(
        &field,
        w_max,
        colormap,
        "Single pendulum: ω (rad/s) against θ, and the separatrix".into(),
        format!(
            "l {} m · g {} m/s² · separatrix ω = ±2 √(g/l) cos(θ/2), |ω| ≤ {:.2} rad/s",
            p.l1, p.g, w_sep
        ),
        ("θ (rad)", "ω"),
        |rgb| {
            use plotters::prelude::*;
            let root = BitMapBackend::with_buffer(rgb, (size, size)).into_drawing_area();
            let to_px = |t: f64, w: f64| {
                (
                    ((t + PI) / (2.0 * PI) * size as f64).round() as i32,
                    ((w_max - w) / (2.0 * w_max) * size as f64).round() as i32,
                )
            };
            for sign in [1.0, -1.0] {
                let curve: Vec<_> = (0..=400)
                    .map(|i| {
                        let t = -PI + 2.0 * PI * i as f64 / 400.0;
                        to_px(t, sign * w_sep * (t / 2.0).cos())
                    })
                    .collect();
                root.draw(&PathElement::new(
                    curve,
                    RGBColor(120, 220, 255).stroke_width(2),
                ))
                .map_err(|e| Error::Io(std::io::Error::other(format!("{e:?}"))))?;
            }
            root.present()
                .map_err(|e| Error::Io(std::io::Error::other(format!("{e:?}"))))?;
            Ok(())
        },
    )?;
    let command = format!(
        "chaoscope phase --single --t-max {} --dt {} --size {} --l1 {} --g {}",
        args.t_max, args.dt, args.size, p.l1, p.g
    );
    let info = RunInfo {
        backend: "cpu",
        adapter: None,
        notice: None,
    };
    Ok((panel.rgb, panel.width, panel.height, command, info))
}
