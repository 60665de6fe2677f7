//! `phase`: phase portraits, omega against theta of each arm, as time-density images
//! (figures 3, 18, 19 of the lab report); or the single pendulum with its separatrix (figure 4).

use std::path::PathBuf;

use super::{check_count, check_output};
use crate::engine::{Backend, Engine, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::render::{self, Colormap, Outputs};
use crate::spec::{self, EnsembleSpec, Precision, Spread, Stepping, releases};

#[derive(Clone, Debug, PartialEq)]
pub struct PhaseJob {
    pub params: Params,
    /// The start of the double pendulum (not used with `single`).
    pub start: State,
    /// Runs (starts spread as for traces); their time densities add up.
    pub runs: u32,
    pub spread: Spread,
    pub stepping: Stepping,
    /// Side of each panel (px).
    pub size: u32,
    /// The single pendulum (length l1) instead of the double.
    pub single: bool,
    pub backend: Backend,
    /// The GPU's precision (the CPU is always f64).
    pub precision: Precision,
    /// Default inferno.
    pub colormap: Option<Colormap>,
    pub output: PathBuf,
}

impl PhaseJob {
    pub fn validate(&self) -> Result<()> {
        spec::validate_params(&self.params)?;
        spec::validate_stepping(&self.stepping)?;
        if !self.single {
            spec::validate_stability(&self.params, &self.stepping)?;
        }
        check_count("runs", self.runs as u64, 1, 100_000)?;
        check_count("size", self.size as u64, 32, 4096)?;
        self.spread.validate()?;
        check_output("output", &self.output, "png")?;
        if !self.single {
            spec::validate_start(&self.start)?;
            let s = &self.start;
            spec::validate_speeds(&self.params, &self.stepping, s.omega1, s.omega2)?;
        }
        Ok(())
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PhaseSummary {
    pub output: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run(job: &PhaseJob, at: &super::Running) -> Result<PhaseSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    job.validate()?;
    let colormap = job.colormap.unwrap_or(Colormap::Inferno);
    monitor.check()?;
    let (rgb, width, height, info, notices) = if job.single {
        let (rgb, w, h) = single_pendulum_portrait(job, colormap)?;
        (rgb, w, h, RunInfo::CPU, Vec::new())
    } else {
        let notices: Vec<String> = engine.notices();
        let (rgb, w, h) = double_pendulum_portraits(job, engine, colormap, monitor)?;
        (rgb, w, h, engine.info(), notices)
    };
    let meta = render::provenance(command, &info);
    let mut files = Outputs::new();
    files.png(&job.output, width, height, &rgb, &meta)?;
    files.commit(monitor)?;
    Ok(PhaseSummary {
        output: job.output.clone(),
        files: vec![job.output.clone()],
        notices,
    })
}

fn double_pendulum_portraits(
    job: &PhaseJob,
    engine: &Engine,
    colormap: Colormap,
    monitor: &Monitor,
) -> Result<(Vec<u8>, u32, u32)> {
    let p = &job.params;
    let starts = releases(p, job.start, job.runs, job.spread);
    let (dt, steps) = (job.stepping.dt, job.stepping.steps());
    let pick = |arm: usize, s: &State| {
        if arm == 0 {
            (s.theta1, s.omega1)
        } else {
            (s.theta2, s.omega2)
        }
    };
    // Streamed, so memory holds one chunk of runs however many there are: a first pass finds
    // each arm's largest |omega| (the panels' scale), a second adds the densities up. With
    // a single chunk the runs are kept from the first pass instead of integrated again.
    let ensemble = EnsembleSpec::new(*p, &starts, dt, steps);
    let single = engine.ensemble_chunk(&ensemble) >= starts.len();
    let mut peak = [0.0f64; 2];
    let mut kept = Vec::new();
    engine.ensemble(&ensemble, monitor, |_, chunk| {
        let runs = chunk.into_states();
        for (arm, peak) in peak.iter_mut().enumerate() {
            let w = runs.iter().flatten().map(|s| pick(arm, s).1.abs());
            *peak = w.fold(*peak, f64::max);
        }
        if single {
            kept = runs;
        }
        Ok(())
    })?;
    let w_max = peak.map(|w| omega_extent(std::iter::once(w)));
    let mut fields = [0, 1].map(|_| Field::new(job.size, job.size, 0.0));
    let mut add = |runs: Vec<Vec<State>>| {
        for (arm, field) in fields.iter_mut().enumerate() {
            let arm_runs: Vec<Vec<(f64, f64)>> = runs
                .iter()
                .map(|r| r.iter().map(|s| pick(arm, s)).collect())
                .collect();
            add_phase_density(field, &arm_runs, dt, w_max[arm]);
        }
        Ok(())
    };
    if single {
        add(kept)?;
    } else {
        engine.ensemble(&ensemble, monitor, |_, runs| add(runs.into_states()))?;
    }
    let s = &job.start;
    let subtitle = format!(
        "{} run(s) from θ ({}, {}) rad, ω ({}, {}) rad/s · {} s · m {} / {} kg · l {} / {} m",
        job.runs,
        s.theta1,
        s.theta2,
        s.omega1,
        s.omega2,
        job.stepping.t_max,
        p.m1,
        p.m2,
        p.l1,
        p.l2
    );
    let mut panels = Vec::new();
    for (arm, field) in fields.iter().enumerate() {
        let w_max = w_max[arm];
        let (title, labels) = if arm == 0 {
            ("Upper arm: ω1 (rad/s) against θ1", ("θ1 (rad)", "ω1"))
        } else {
            ("Lower arm: ω2 (rad/s) against θ2", ("θ2 (rad)", "ω2"))
        };
        panels.push(phase_panel(
            field,
            w_max,
            colormap,
            title.into(),
            subtitle.clone(),
            labels,
            |_| Ok(()),
        )?);
    }
    Ok(side_by_side(&panels))
}

/// Time spent (s) per cell of a (theta, omega) grid: theta wrapped to (-pi, pi] along x,
/// omega from `w_max` (top) to `-w_max` along y. Each step's time is spread along the segment
/// between its end points (at most half a cell apart), so fast stretches draw lines, not dots.
pub fn phase_density(runs: &[Vec<(f64, f64)>], dt: f64, size: u32, w_max: f64) -> Field {
    let mut field = Field::new(size, size, 0.0);
    add_phase_density(&mut field, runs, dt, w_max);
    field
}

/// Adds the time `runs` spend per cell to `field` (as [`phase_density`]), run by run.
pub fn add_phase_density(field: &mut Field, runs: &[Vec<(f64, f64)>], dt: f64, w_max: f64) {
    use std::f64::consts::PI;
    let n = field.width as f64;
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
}

/// A density panel: log of the time per cell over three decades below the maximum,
/// cells never visited in the background colour; framed with axes.
fn phase_panel(
    field: &Field,
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

/// The single pendulum's phase portrait: librations from rest at 12 amplitudes, rotations at
/// 6 speeds above the separatrix, each over one period's worth of time at least, and the
/// separatrix omega = +-2 sqrt(g/l) cos(theta/2) drawn over them.
fn single_pendulum_portrait(job: &PhaseJob, colormap: Colormap) -> Result<(Vec<u8>, u32, u32)> {
    use std::f64::consts::PI;
    let p: &Params = &job.params;
    let k = p.g / p.l1;
    let w0 = k.sqrt();
    let w_sep = 2.0 * w0;
    let w_max = 1.6 * w_sep;
    let steps = job.stepping.steps();
    let dt = job.stepping.dt;
    let mut orbits: Vec<(f64, f64)> = (1..=12).map(|i| (i as f64 * PI / 13.0, 0.0)).collect();
    orbits.extend((1..=6).map(|i| (0.0, w_sep * (1.0 + 0.08 * i as f64))));
    orbits.extend((1..=6).map(|i| (0.0, -w_sep * (1.0 + 0.08 * i as f64))));
    let runs: Vec<Vec<(f64, f64)>> = orbits
        .iter()
        .map(|&(t, w)| single_pendulum(k, t, w, dt, steps))
        .collect();
    let field = phase_density(&runs, dt, job.size, w_max);
    let size = job.size;
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
                .map_err(Error::plot)?;
            }
            root.present().map_err(Error::plot)?;
            Ok(())
        },
    )?;
    Ok((panel.rgb, panel.width, panel.height))
}
