//! `traces`: the lab report's long-exposure light trails of releases from "the same" start
//! (figures 7-9), and an animated GIF of the pendulums swinging and parting.

use std::path::PathBuf;

use super::film::{self, FilmSpec, Format};
use super::{check_count, check_output};
use crate::engine::{Backend, Engine};
use crate::error::Result;
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::render::{self, Bobs, Canvas, Colormap, Film, Outputs};
use crate::spec::{self, EnsembleSpec, Precision, Spread, Stepping, releases};

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
    /// The GPU's precision (the CPU is always f64).
    pub precision: Precision,
    pub output: PathBuf,
    /// The film of the trails growing and the pendulums swinging (GIF, APNG or MP4).
    pub film: Option<FilmSpec>,
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
        if let Some(film) = &self.film {
            film.validate("film", FILM_FORMATS)?;
        }
        if let Some(d) = &self.data {
            check_output("data", d, "npy")?;
        }
        let named = [
            Some(("output", self.output.as_path())),
            self.film.as_ref().map(|f| ("film", f.path.as_path())),
            self.data.as_deref().map(|p| ("data", p)),
        ];
        super::checks::check_distinct(&named.into_iter().flatten().collect::<Vec<_>>(), &[])
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

pub fn run(job: &TracesJob, at: &super::Running) -> Result<TracesSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    job.validate()?;
    monitor.check()?;
    let p = &job.params;
    let notices: Vec<String> = engine.notices();
    let info = engine.info();
    let starts = releases(p, job.start, job.runs, job.spread);
    let n = starts.len();
    let colors: Vec<[u8; 3]> = (0..n).map(|k| run_color(k, n)).collect();
    let meta = render::provenance(command, &info);
    let mut files = Outputs::new();
    let ensemble = EnsembleSpec::new(*p, &starts, job.stepping.dt, job.stepping.steps());
    if engine.ensemble_chunk(&ensemble) >= n {
        all_at_once(job, engine, &ensemble, &colors, &meta, &mut files, monitor)?;
    } else {
        streamed(job, engine, &ensemble, &colors, &meta, &mut files, monitor)?;
    }
    files.commit(monitor)?;
    Ok(TracesSummary {
        runs: n,
        exposure: job.stepping.t_max,
        place: info.place().to_string(),
        output: job.output.clone(),
        files: [
            Some(job.output.clone()),
            job.data.clone(),
            job.film.as_ref().map(|f| f.path.clone()),
        ]
        .into_iter()
        .flatten()
        .collect(),
        notices,
    })
}

/// Positions as the .npy holds them: x1, y1, x2, y2 in f32, sample after sample.
fn flat(positions: &[Bobs]) -> impl Iterator<Item = f32> + '_ {
    positions
        .iter()
        .flat_map(|q| [q.0 as f32, q.1 as f32, q.2 as f32, q.3 as f32])
}

fn bobs(p: &crate::model::Params, s: &State) -> Bobs {
    let q = p.positions(s);
    (q.x1, q.y1, q.x2, q.y2)
}

fn canvas(job: &TracesJob, size: u32) -> Canvas {
    Canvas {
        size,
        reach: 1.08 * (job.params.l1 + job.params.l2),
    }
}

/// What the film may be.
pub const FILM_FORMATS: &[Format] = &[Format::Gif, Format::Apng, Format::Mp4];

/// The film's frames: the exposure in real time; frame f (from 1) shows the samples before
/// `upto(f)`.
fn film_frames(job: &TracesJob, film: &FilmSpec) -> usize {
    ((job.stepping.t_max * film.fps).round() as usize).max(1)
}

/// The film's canvas: the picture's, at most 480 pixels a side in a GIF or an APNG (their
/// size grows with every pixel of every frame) and 720 in an MP4.
fn film_canvas(job: &TracesJob, film: &FilmSpec) -> Canvas {
    let most = match film.format("film", FILM_FORMATS) {
        Ok(Format::Mp4) => 720,
        _ => 480,
    };
    canvas(job, job.size.min(most))
}

fn upto(f: usize, frames: usize, samples: usize) -> usize {
    ((f as f64 / frames as f64) * (samples - 1) as f64).round() as usize + 1
}

/// Every run in memory at once (an ensemble that fits one chunk).
fn all_at_once(
    job: &TracesJob,
    engine: &Engine,
    ensemble: &EnsembleSpec,
    colors: &[[u8; 3]],
    meta: &[(String, String)],
    files: &mut Outputs,
    monitor: &Monitor,
) -> Result<()> {
    let (p, dt) = (&ensemble.params, ensemble.dt);
    let runs = engine.ensemble_all(ensemble, monitor)?;
    let positions: Vec<Vec<Bobs>> = runs
        .iter()
        .map(|r| r.iter().map(|s| bobs(p, s)).collect())
        .collect();
    let n = positions.len();
    let speed = reference_speed(&positions, dt);
    let mut film = Film::new(canvas(job, job.size));
    expose(&mut film, &positions, colors, dt, 0, usize::MAX);
    let rgb = develop(&film, speed, &positions, colors, None, n)?;
    files.png(&job.output, job.size, job.size, &rgb, meta)?;
    if let Some(path) = &job.data {
        let samples = positions[0].len();
        let data: Vec<f32> = positions.iter().flat_map(|run| flat(run)).collect();
        files.npy_shaped(path, &[n as u64, samples as u64, 4], &data)?;
    }
    if let Some(spec) = &job.film {
        let gcanvas = film_canvas(job, spec);
        let (frames, samples) = (film_frames(job, spec), positions[0].len());
        // One film, exposed a frame's worth further each time, each frame encoded as made.
        let mut film = Film::new(gcanvas);
        let mut exposed = 0;
        write_film(files, spec, gcanvas, frames, meta, monitor, |k| {
            let upto = upto(k + 1, frames, samples);
            expose(&mut film, &positions, colors, dt, exposed, upto);
            exposed = upto - 1;
            // Arms of at most 50 runs, or the picture is all arms.
            develop(&film, speed, &positions, colors, Some(upto - 1), n.min(50))
        })?;
    }
    Ok(())
}

/// Runs in chunks, none kept: memory holds one chunk, the films and the GIF's per-frame
/// films, whatever the number of runs. Two passes: the first finds the bin of a
/// histogram that holds the median lower-bob speed, the second exposes the films, writes
/// the .npy as it goes and keeps the speeds in that bin, from which the median comes out
/// exactly as from all the speeds at once.
fn streamed(
    job: &TracesJob,
    engine: &Engine,
    ensemble: &EnsembleSpec,
    colors: &[[u8; 3]],
    meta: &[(String, String)],
    files: &mut Outputs,
    monitor: &Monitor,
) -> Result<()> {
    let (p, dt, steps) = (&ensemble.params, ensemble.dt, ensemble.steps);
    let (n, samples) = (ensemble.starts.len(), steps as usize + 1);
    let (gcanvas, frames) = match &job.film {
        Some(f) => (film_canvas(job, f), film_frames(job, f)),
        None => (canvas(job, 16), 0),
    };
    if job.film.is_some() {
        let film_bytes = (gcanvas.size as u64).pow(2) * 12;
        spec::check_memory("film", frames as u64 * film_bytes, "the film's exposures")?;
    }
    // Log-spaced speed bins over 1e-9 .. 1e9 m/s.
    const BINS: usize = 1 << 16;
    let bin = |v: f64| {
        let u = (v.max(1e-9).log10() + 9.0) / 18.0 * BINS as f64;
        if u.is_nan() {
            0
        } else {
            u.clamp(0.0, (BINS - 1) as f64) as usize
        }
    };
    let speeds = |pos: &[Bobs]| -> Vec<f64> {
        pos.windows(2)
            .map(|w| ((w[1].2 - w[0].2).powi(2) + (w[1].3 - w[0].3).powi(2)).sqrt() / dt)
            .collect()
    };
    let mut histogram = vec![0u64; BINS];
    engine.ensemble(ensemble, monitor, |_, runs| {
        for run in &runs.into_states() {
            let pos: Vec<Bobs> = run.iter().map(|s| bobs(p, s)).collect();
            for v in speeds(&pos) {
                histogram[bin(v)] += 1;
            }
        }
        Ok(())
    })?;
    // The median's rank among all speeds (as select_nth_unstable at len / 2), and its bin.
    let total: u64 = histogram.iter().sum();
    let mid = total / 2;
    let (mut median_bin, mut before) = (0, 0);
    for (b, &count) in histogram.iter().enumerate() {
        if before + count > mid {
            median_bin = b;
            break;
        }
        before += count;
    }
    let mut film = Film::new(canvas(job, job.size));
    let mut increments: Vec<Film> = match job.film {
        Some(_) => (0..frames).map(|_| Film::new(gcanvas)).collect(),
        None => Vec::new(),
    };
    let arms_shown = n.min(50);
    let mut arms: Vec<Vec<Bobs>> = Vec::new();
    let mut candidates = Vec::new();
    let mut second_pass = |sink: &mut dyn FnMut(&[f32]) -> Result<()>| {
        engine.ensemble(ensemble, monitor, |first, runs| {
            for (j, run) in runs.into_states().iter().enumerate() {
                let k = first + j;
                let pos: Vec<Bobs> = run.iter().map(|s| bobs(p, s)).collect();
                candidates.extend(speeds(&pos).into_iter().filter(|&v| bin(v) == median_bin));
                let (one, color) = (std::slice::from_ref(&pos), &colors[k..=k]);
                expose(&mut film, one, color, dt, 0, usize::MAX);
                let mut exposed = 0;
                for (f, increment) in increments.iter_mut().enumerate() {
                    let upto = upto(f + 1, frames, samples);
                    expose(increment, one, color, dt, exposed, upto);
                    exposed = upto - 1;
                }
                if k < arms_shown && !increments.is_empty() {
                    arms.push(
                        (1..=frames)
                            .map(|f| pos[upto(f, frames, samples) - 1])
                            .collect(),
                    );
                }
                sink(&flat(&pos).collect::<Vec<_>>())?;
            }
            Ok(())
        })
    };
    match &job.data {
        Some(path) => files.write(path, |w| {
            use npyz::WriterBuilder;
            let mut npy = npyz::WriteOptions::new()
                .default_dtype()
                .shape(&[n as u64, samples as u64, 4])
                .writer(w)
                .begin_nd()?;
            second_pass(&mut |flat| {
                npy.extend(flat.iter().copied())?;
                Ok(())
            })?;
            npy.finish()?;
            Ok(())
        })?,
        None => second_pass(&mut |_| Ok(()))?,
    }
    let speed = if candidates.is_empty() {
        1.0
    } else {
        let rank = (mid - before) as usize;
        let (_, median, _) = candidates.select_nth_unstable_by(rank, f64::total_cmp);
        (2.0 * *median).max(1e-3)
    };
    // The photograph: trails, and every run's arms at its release, grey and faint.
    let released: Vec<Vec<Bobs>> = ensemble.starts.iter().map(|s| vec![bobs(p, s)]).collect();
    let rgb = develop(&film, speed, &released, colors, None, n)?;
    files.png(&job.output, job.size, job.size, &rgb, meta)?;
    if let Some(spec) = &job.film {
        let mut shown = Film::new(gcanvas);
        write_film(files, spec, gcanvas, frames, meta, monitor, |f| {
            shown.add(&increments[f]);
            develop(&shown, speed, &arms, colors, Some(f), arms_shown)
        })?;
    }
    Ok(())
}

/// Stages the film `spec` asks for: `frames` frames of `canvas`, each made by `frame(k)`,
/// with progress and Ctrl-C between frames.
fn write_film(
    files: &mut Outputs,
    spec: &FilmSpec,
    canvas: Canvas,
    frames: usize,
    meta: &[(String, String)],
    monitor: &Monitor,
    mut frame: impl FnMut(usize) -> Result<Vec<u8>>,
) -> Result<()> {
    monitor.start("film", frames as u64);
    let format = spec.format("film", FILM_FORMATS)?;
    film::write(
        files,
        spec,
        format,
        (canvas.size, canvas.size),
        frames,
        meta,
        |k| {
            monitor.check()?;
            let rgb = frame(k)?;
            monitor.advance(1);
            Ok(rgb)
        },
    )?;
    monitor.finish();
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
    let radius = (film.canvas.size / 120).max(2) as i32;
    render::draw_arms(&mut rgb, film.canvas, &drawn, alpha, radius)?;
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
