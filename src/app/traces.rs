//! `traces`: the lab report's long-exposure light trails of releases from "the same" start
//! (figures 7-9), and an animated GIF of the pendulums swinging and parting.

use std::path::{Path, PathBuf};

use super::{check_count, check_output};
use crate::engine::{Backend, Engine};
use crate::error::Result;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::render::{self, Bobs, Colormap, Film, Outputs, View};
use crate::spec::{self, Spread, Stepping, releases};

#[derive(Clone, Debug, PartialEq)]
pub struct TracesJob {
    pub params: Params,
    /// The release (nominal start) of every run.
    pub start: State,
    pub runs: u32,
    pub spread: Spread,
    /// t_max is the exposure time (s).
    pub stepping: Stepping,
    /// Picture side (px).
    pub size: u32,
    pub backend: Backend,
    pub output: PathBuf,
    /// An animated GIF of the pendulums.
    pub gif: Option<PathBuf>,
    /// Lower-bob positions as float32 .npy, shape (runs, samples, 4): x1, y1, x2, y2 (m).
    pub data: Option<PathBuf>,
}

impl TracesJob {
    pub fn validate(&self) -> Result<()> {
        spec::validate_params(&self.params)?;
        spec::validate_stepping(&self.stepping)?;
        spec::validate_stability(&self.params, &self.stepping)?;
        spec::validate_start(&self.start)?;
        let s = &self.start;
        spec::validate_speeds(&self.params, &self.stepping, s.omega1, s.omega2)?;
        check_count("runs", self.runs as u64, 1, 100_000)?;
        check_count("size", self.size as u64, 16, 8192)?;
        self.spread.validate()?;
        check_output("output", &self.output, "png")?;
        if let Some(g) = &self.gif {
            check_output("gif", g, "gif")?;
        }
        if let Some(d) = &self.data {
            check_output("data", d, "npy")?;
        }
        Ok(())
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TracesSummary {
    pub runs: usize,
    pub exposure: f64,
    pub place: String,
    pub output: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

/// Colour of run k of n: evenly spaced hues of the cyclic sinebow map.
fn run_color(k: usize, n: usize) -> [u8; 3] {
    let g = Colormap::Sinebow.gradient();
    let [r, gg, b, _] = g.at((k as f32 + 0.5) / n as f32).to_rgba8();
    [r, gg, b]
}

pub fn run(job: &TracesJob, command: String, monitor: &Monitor) -> Result<TracesSummary> {
    job.validate()?;
    monitor.check()?;
    let p = &job.params;
    let engine = Engine::new(job.backend)?;
    let notices: Vec<String> = engine.notices();
    let info = engine.info();
    let starts = releases(p, job.start, job.runs, job.spread);
    let runs = engine.ensemble(
        p,
        &starts,
        job.stepping.dt,
        job.stepping.steps(),
        1,
        monitor,
    )?;
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
        size: job.size,
        reach: 1.08 * (p.l1 + p.l2),
    };
    let n = positions.len();
    let colors: Vec<[u8; 3]> = (0..n).map(|k| run_color(k, n)).collect();
    let dt = job.stepping.dt;
    let speed = reference_speed(&positions, dt);
    let mut film = Film::new(view);
    expose(&mut film, &positions, &colors, dt, 0, usize::MAX);
    let rgb = develop(&film, speed, &positions, &colors, None, n)?;
    let meta = render::provenance(command, &info);
    let mut files = Outputs::new();
    files.png(&job.output, job.size, job.size, &rgb, &meta)?;
    if let Some(path) = &job.data {
        let samples = positions[0].len();
        let flat: Vec<f32> = positions
            .iter()
            .flatten()
            .flat_map(|q| [q.0 as f32, q.1 as f32, q.2 as f32, q.3 as f32])
            .collect();
        files.npy_shaped(path, &[n as u64, samples as u64, 4], &flat)?;
    }
    if let Some(path) = &job.gif {
        write_gif(&mut files, path, job, &positions, &colors, speed, monitor)?;
    }
    files.commit(monitor)?;
    Ok(TracesSummary {
        runs: n,
        exposure: job.stepping.t_max,
        place: info.place().to_string(),
        output: job.output.clone(),
        files: [Some(job.output.clone()), job.data.clone(), job.gif.clone()]
            .into_iter()
            .flatten()
            .collect(),
        notices,
    })
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
    files: &mut Outputs,
    path: &Path,
    job: &TracesJob,
    positions: &[Vec<Bobs>],
    colors: &[[u8; 3]],
    speed: f64,
    monitor: &Monitor,
) -> Result<()> {
    const FPS: f64 = 25.0;
    let p = &job.params;
    let view = View {
        size: job.size.min(480),
        reach: 1.08 * (p.l1 + p.l2),
    };
    let samples = positions[0].len();
    let frames = ((job.stepping.t_max * FPS).round() as usize).max(1);
    monitor.start("gif", frames as u64);
    let mut rgb = Vec::with_capacity(frames);
    // One film, exposed a frame's worth further each time.
    let mut film = Film::new(view);
    let mut exposed = 0;
    for f in 1..=frames {
        monitor.check()?;
        let upto = ((f as f64 / frames as f64) * (samples - 1) as f64).round() as usize + 1;
        expose(&mut film, positions, colors, job.stepping.dt, exposed, upto);
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
    files.gif(
        path,
        view.size,
        view.size,
        &rgb,
        (100.0 / FPS).round() as u16,
    )
}
