//! `chaoscope sweep`.

use std::path::PathBuf;

use clap::Args;

use super::args::{GridArgs, PhysicalArgs, PictureArgs, StepArgs, backend_parser};
use super::parse::{one_of, parse_number, parse_point, parse_tile, parse_u32, parse_vary};
use super::{command_line, json, say};
use crate::app::film::FilmSpec;
use crate::app::frames::TABLE;
use crate::app::sweep::{self, MapKind, SweepJob, Vary};
use crate::engine::Backend;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::Var;

#[derive(Args, Debug, Clone)]
#[command(mut_arg("t_max", |a| a.default_value("20")))]
pub struct SweepArgs {
    /// Which map each frame shows: flip (times), flip-kind (which arm flips first and which
    /// way) or lyapunov.
    #[arg(long, default_value = "flip", value_parser = one_of(MapKind::all(), MapKind::name))]
    pub map: MapKind,
    /// PARAM=FROM:TO, PARAM one of m1, m2, l1, l2, g, m2/m1, l2/l1, mass, omega1, omega2,
    /// damping (both joints, N m s).
    #[arg(long, value_parser = parse_vary, allow_hyphen_values = true)]
    pub vary: Option<Vary>,
    /// Sweep's zoom, moved to `chaoscope zoom`: refused with the zoom that does it.
    #[arg(long, hide = true, value_parser = parse_point, allow_hyphen_values = true)]
    pub zoom_to: Option<(f64, f64)>,
    /// Sweep's zoom's magnification, moved to `chaoscope zoom`.
    #[arg(long, hide = true, value_parser = parse_number, allow_hyphen_values = true)]
    pub zoom: Option<f64>,
    /// Number of frames.
    #[arg(long, default_value = "24", value_parser = parse_u32, allow_hyphen_values = true)]
    pub frames: u32,
    /// Frames per second of the animation.
    #[arg(long, default_value = "8", value_parser = parse_number, allow_hyphen_values = true)]
    pub fps: f64,
    /// The animation's file, its format by its extension: .png (APNG, lossless) or .mp4
    /// (H.264, through FFmpeg) [default: OUTPUT/animation.png].
    #[arg(long)]
    pub film: Option<PathBuf>,
    /// An MP4's quality: H.264's constant rate factor, 0 (lossless) to 51 (18 looks
    /// lossless; each 6 more halves the file).
    #[arg(long, default_value = "18", value_parser = parse_u32, allow_hyphen_values = true)]
    pub crf: u32,
    #[command(flatten)]
    pub grid: GridArgs,
    #[command(flatten)]
    pub step: StepArgs,
    /// Lyapunov frames: renormalisation interval (s).
    #[arg(long, default_value = "0.1", value_parser = parse_number, allow_hyphen_values = true)]
    pub renorm: f64,
    /// Lyapunov frames: top of the colour range (1/s), the same for every frame.
    #[arg(long, default_value = "2", value_parser = parse_number, allow_hyphen_values = true)]
    pub ftle_max: f64,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// auto, gpu or cpu (f64).
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    #[command(flatten)]
    pub picture: PictureArgs,
    /// Directory for frame_0000.png ... and animation.png (APNG) unless --film names another.
    #[arg(long, default_value = "out/sweep")]
    pub output: PathBuf,
    /// The frames' maps also as one Zarr v3 store SWEEP.zarr: an array (frame, theta2,
    /// theta1) with the varied parameter as the frame coordinate (--vary sweeps).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Make only part INDEX of COUNT of the frames (frames k with k % COUNT == INDEX) and no
    /// animation, e.g. --tile $SLURM_ARRAY_TASK_ID/8; the same command without --tile then
    /// makes the animation from them.
    #[arg(long, value_parser = parse_tile)]
    pub tile: Option<(u32, u32)>,
}

impl SweepArgs {
    pub fn job(&self) -> Result<SweepJob> {
        let grid = self.grid.grid()?;
        if let Some((x, y)) = self.zoom_to {
            // The zoom's last view: the grid's width over the magnification.
            let width = (grid.x.range.max - grid.x.range.min) / self.zoom.unwrap_or(1.0);
            return Err(crate::Error::invalid(
                "zoom_to",
                format!(
                    "sweep no longer zooms: `chaoscope zoom --to {x},{y},{width:e} --frames {} flip ...` (the map's flags after it) films that zoom, the first frame the whole plane, in f64 where f32 runs out, resumable",
                    self.frames
                ),
            ));
        }
        if self.zoom.is_some() {
            return Err(crate::Error::invalid(
                "zoom",
                "sweep no longer zooms: `chaoscope zoom --to X,Y,WIDTH` films a zoom",
            ));
        }
        let Some(vary) = self.vary else {
            return Err(crate::Error::invalid(
                "vary",
                "a sweep needs a parameter to vary, PARAM=FROM:TO (a zoom into a point is `chaoscope zoom --to`)",
            ));
        };
        let sources = self.physical.sources();
        if let Some(var) = vary.param.var() {
            crate::spec::check_along(&sources, &[("vary", var)])?;
            let plane = &self.grid.plane;
            for (given, field, v) in [
                (plane.omega1.is_some(), "omega1", Var::Omega1),
                (plane.omega2.is_some(), "omega2", Var::Omega2),
            ] {
                if given && var == v {
                    return Err(crate::Error::invalid(
                        field,
                        format!(
                            "{field} varies in the sweep, which sets it: leave one of them out"
                        ),
                    ));
                }
            }
        }
        Ok(SweepJob {
            map: self.map,
            vary,
            frames: self.frames,
            film: FilmSpec {
                path: self
                    .film
                    .clone()
                    .unwrap_or_else(|| self.output.join(sweep::ANIMATION)),
                fps: self.fps,
                crf: self.crf,
            },
            params: crate::spec::resolve_on(&sources, &grid)?,
            grid,
            stepping: self.step.stepping(),
            renorm: self.renorm,
            ftle_max: self.ftle_max,
            backend: self.backend,
            picture: self.picture.spec(),
            output: self.output.clone(),
            data: self.data.clone(),
            tile: self.tile,
        })
    }
}

pub fn run(args: &SweepArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job()?;
    let engine = super::args::lent_engine(None, job.backend)?;
    let s = sweep::run(
        &job,
        &crate::app::Running::new(&engine, command_line::sweep(&job), monitor),
        &command_line::frame,
    )?;
    say("sweep", &s.notices);
    let made = format!(
        "{} frames ({} made, {} kept from an earlier run) in {}",
        s.frames,
        s.made,
        s.kept,
        s.output.display()
    );
    match (&s.animation, s.tile) {
        (Some(film), _) => eprintln!("{made} -> {} and {TABLE}", film.display()),
        (None, Some((index, count))) => eprintln!(
            "{made}: tile {index}/{count} done; the same command without --tile makes the animation once every tile is"
        ),
        (None, None) => eprintln!("{made}"),
    }
    json(&s)
}
