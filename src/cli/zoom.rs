//! `chaoscope zoom`: the zoom's own flags, then the map of its first frame as `flip` or
//! `lyapunov` would make it (`chaoscope zoom --to X,Y,W flip --size 1920x1080`).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::flip::FlipArgs;
use super::lyapunov::{LyapunovArgs, LyapunovJob};
use super::parse::{not_a_flag, parse_number, parse_tile, parse_u32};
use super::{command_line, json, say};
use crate::app::film::FilmSpec;
use crate::app::map::MapJob;
use crate::app::zoom::{self, Target, ZoomJob};
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::spec::ZOOM;

#[derive(Args, Debug, Clone)]
pub struct ZoomArgs {
    /// The view to zoom to: X,Y,WIDTH (its centre on the map's axes, `pi` understood, and its
    /// width along x; the height keeps the first view's proportions). Given more than once:
    /// the views the film passes through, in order, the last its end.
    #[arg(long = "to", required = true, value_parser = parse_view, allow_hyphen_values = true)]
    pub to: Vec<Target>,
    /// Frames in the film (2 to 100000).
    #[arg(long, default_value_t = ZOOM.frames, value_parser = parse_u32, allow_hyphen_values = true)]
    pub frames: u32,
    /// Frames a second.
    #[arg(long, default_value_t = ZOOM.fps, value_parser = parse_number, allow_hyphen_values = true)]
    pub fps: f64,
    /// The film's quality: H.264's constant rate factor, 0 (lossless) to 51 (18 looks
    /// lossless; each 6 more halves the file).
    #[arg(long, default_value_t = ZOOM.crf, value_parser = parse_u32, allow_hyphen_values = true)]
    pub crf: u32,
    /// The film: .mp4 (H.264, through FFmpeg) or .png (APNG) [default: OUTPUT/zoom.mp4].
    #[arg(long)]
    pub film: Option<PathBuf>,
    /// Directory for frame_0000.png ... and frames.csv (each frame's view, precision, place
    /// and unresolved share). Frames of the same zoom already there are kept: a run resumes.
    #[arg(long, default_value = ZOOM.output)]
    pub output: PathBuf,
    /// Make only part INDEX of COUNT of the frames (frames k with k % COUNT == INDEX) and no
    /// film, e.g. --tile $SLURM_ARRAY_TASK_ID/8; the same command without --tile then encodes
    /// the film from them.
    #[arg(long, value_parser = parse_tile)]
    pub tile: Option<(u32, u32)>,
    /// Judge every frame: the share of its pixels the verdict cannot resolve, in frames.csv
    /// (the map's --show-unresolved also paints them grey). Costs two to three maps a frame.
    #[arg(long)]
    pub verdict: bool,
    #[command(subcommand)]
    pub map: ZoomMap,
}

/// The map every frame shows, with its flags (its plane is the first view).
#[derive(Subcommand, Debug, Clone)]
pub enum ZoomMap {
    /// Flip-time or flip-kind frames, every flag as `chaoscope flip` has it.
    Flip(FlipArgs),
    /// Divergence or indicator frames, every flag as `chaoscope lyapunov` has it.
    Lyapunov(LyapunovArgs),
}

/// `X,Y,WIDTH`.
pub fn parse_view(s: &str) -> std::result::Result<Target, String> {
    not_a_flag(s)?;
    let parts: Vec<&str> = s.split(',').collect();
    let [x, y, width] = parts[..] else {
        return Err(format!("`{s}` must be X,Y,WIDTH"));
    };
    Ok(Target {
        x: parse_number(x)?,
        y: parse_number(y)?,
        width: parse_number(width)?,
    })
}

/// The map's flags that have no place in a zoom (its frames are the zoom's files).
fn not_in_a_zoom(
    output: &Option<PathBuf>,
    data: &Option<PathBuf>,
    tile: Option<(u32, u32)>,
    resolved: &Option<PathBuf>,
) -> Result<()> {
    for (given, field, instead) in [
        (
            output.is_some(),
            "output",
            "zoom's --output DIR before the map's name",
        ),
        (
            data.is_some(),
            "data",
            "the frames' PNGs in zoom's --output DIR",
        ),
        (
            tile.is_some(),
            "tile",
            "zoom's --tile INDEX/COUNT, over frames",
        ),
        (
            resolved.is_some(),
            "resolved",
            "zoom's --verdict (each frame's share in frames.csv)",
        ),
    ] {
        if given {
            return Err(Error::invalid(
                field,
                format!("is the map's own file; a zoom's frames take {instead}"),
            ));
        }
    }
    Ok(())
}

impl ZoomArgs {
    fn job_of<S>(&self, map: MapJob<S>) -> ZoomJob<S> {
        ZoomJob {
            map,
            to: self.to.clone(),
            frames: self.frames,
            film: FilmSpec {
                path: self
                    .film
                    .clone()
                    .unwrap_or_else(|| self.output.join(zoom::FILM)),
                fps: self.fps,
                crf: self.crf,
            },
            output: self.output.clone(),
            tile: self.tile,
            verdict: self.verdict,
        }
    }
}

pub fn run(args: &ZoomArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let s = match &args.map {
        ZoomMap::Flip(map) => {
            not_in_a_zoom(&map.output, &map.data, map.tile, &map.verdict.resolved)?;
            let (engine, job) =
                super::args::engine_then(map.precision, map.backend, |f32| map.job_on(f32))?;
            let job = args.job_of(job);
            let command = command_line::zoom(&job, &command_line::flip(&job.map));
            let at = crate::app::Running::new(&engine, command, monitor);
            zoom::run(&job, &at, &command_line::flip)?
        }
        ZoomMap::Lyapunov(map) => {
            not_in_a_zoom(&map.output, &map.data, map.tile, &map.verdict.resolved)?;
            if map.spectrum.is_some() {
                return Err(Error::invalid(
                    "spectrum",
                    "is a map's own file; a zoom's frames show one exponent or indicator each",
                ));
            }
            let (engine, job) =
                super::args::engine_then(map.precision, map.backend(), |f32| map.job_on(f32))?;
            let LyapunovJob::Map(mapjob) = job else {
                return Err(Error::invalid(
                    "theta1",
                    "a zoom needs a plane: ranges (or --x and --y), not a single start",
                ));
            };
            let job = args.job_of(mapjob);
            let command = command_line::zoom(&job, &command_line::lyapunov_map(&job.map));
            let at = crate::app::Running::new(&engine, command, monitor);
            zoom::run(&job, &at, &command_line::lyapunov_map)?
        }
    };
    say("zoom", &s.notices);
    let precision = match &s.switch {
        Some(w) => format!(
            "f32 for frames 0-{}, f64 from frame {} (width {:.3e}) on the {}",
            w.frame - 1,
            w.frame,
            w.width,
            if w.on_gpu { "GPU" } else { "CPU" }
        ),
        None => "one precision throughout".into(),
    };
    let unresolved = s
        .unresolved_mean
        .zip(s.unresolved_max)
        .map(|(mean, max)| {
            format!(
                "; unresolved {:.2} % a frame on average, {:.2} % at most",
                100.0 * mean,
                100.0 * max
            )
        })
        .unwrap_or_default();
    let range = s
        .range
        .map(|(lo, hi)| format!("; colours {lo}:{hi} ({}), every frame", s.range_from))
        .unwrap_or_default();
    eprintln!(
        "{} frames ({} made, {} kept from an earlier run) in {:.1} s; {precision}{range}{unresolved}",
        s.frames, s.made, s.kept, s.compute_seconds
    );
    match (&s.film, s.encode_seconds, s.tile) {
        (Some(film), Some(secs), _) => eprintln!(
            "encoded in {secs:.1} s -> {} ({} and frames.csv in {})",
            film.display(),
            crate::app::frames::frame_name(0),
            s.output.display()
        ),
        (_, _, Some((index, count))) => eprintln!(
            "tile {index}/{count} done in {}; the same command without --tile encodes the film once every tile is",
            s.output.display()
        ),
        _ => {}
    }
    json(&s)
}
