//! `chaoscope zoom`: a film from one view of a map's plane to another, or through several,
//! the width shrinking geometrically (a constant zoom speed). Every frame is the map of its
//! view, computed with the precision its pixel step needs: f32 while f32 resolves the step,
//! then f64 (on a GPU that has it, else on the CPU), and refused where even f64 cannot.
//!
//! Frames are numbered PNGs, each carrying the single map's command that makes it alone: a
//! run keeps the frames an earlier run of the same zoom finished (resume), `tile` shares the
//! frames out between tasks, and a run without `tile` encodes the film once every frame is
//! there, with `frames.csv` (each frame's view, precision, place and unresolved share).

use std::cell::RefCell;
use std::path::PathBuf;
use std::time::Instant;

use super::film::{FilmSpec, Format};
use super::frames::{self, FrameSet, Frames, TABLE, text};
use super::map::{Judged, MapJob, check_in_memory, compute_planned, computed_spec};
use crate::engine::{Backend, Engine, MapKernels};
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::plan::MapPlan;
use crate::render::{self, MapPicture};
use crate::spec::{Grid, Precision};

mod views;
use views::grid_of_view;
pub use views::{Target, grids};

/// A zoom to make.
#[derive(Clone, Debug, PartialEq)]
pub struct ZoomJob<S> {
    /// The first frame's map: its spec (its grid is the first view), picture, colours,
    /// sub-samples and `show_unresolved`; its other files are not used.
    pub map: MapJob<S>,
    /// The views after the first, in order; the last is the film's end.
    pub to: Vec<Target>,
    pub frames: u32,
    /// The film: MP4 (or APNG), its rate and quality.
    pub film: FilmSpec,
    /// The frames' directory (frame_0000.png ...) and frames.csv.
    pub output: PathBuf,
    /// Make only frames k with k % COUNT == INDEX (no film): `(INDEX, COUNT)`.
    pub tile: Option<(u32, u32)>,
    /// Judge every frame (the share of its pixels not resolved, in frames.csv); implied by
    /// the map's `show_unresolved`.
    pub verdict: bool,
}

impl<S> ZoomJob<S> {
    pub fn wants_verdict(&self) -> bool {
        self.verdict || self.map.files.show_unresolved
    }
}

/// What a film may be.
pub const FILM_FORMATS: &[Format] = &[Format::Mp4, Format::Apng];
/// The film's name in the output folder when no other is named.
pub const FILM: &str = "zoom.mp4";

/// One frame as planned: its view, its grid and where and how precisely it runs.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FramePlan {
    pub frame: u32,
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub height: f64,
    /// The step between neighbouring starts along x (a pixel's, or a sub-sample's).
    pub step: f64,
    pub precision: &'static str,
    pub on_gpu: bool,
    #[serde(skip)]
    pub grid: Grid,
}

/// Where the precision changes: the first frame in f64 after frames in f32.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Switch {
    pub frame: u32,
    pub width: f64,
    /// The first f64 frame's step along x, and the finest step f32 resolves there.
    pub step: f64,
    pub f32_finest: f64,
    pub on_gpu: bool,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ZoomSummary {
    pub frames: u32,
    /// Frames computed by this run, and kept from an earlier one.
    pub made: u32,
    pub kept: u32,
    pub tile: Option<(u32, u32)>,
    pub switch: Option<Switch>,
    /// The colours' fixed range (the quantity's unit) where its colours span one, and
    /// where it came from.
    pub range: Option<(f32, f32)>,
    pub range_from: &'static str,
    /// The mean share of unresolved pixels over the frames (with the verdict), and the
    /// largest.
    pub unresolved_mean: Option<f64>,
    pub unresolved_max: Option<f64>,
    pub compute_seconds: f64,
    /// Reading the frames back and encoding them (None: a tile makes no film).
    pub encode_seconds: Option<f64>,
    pub output: PathBuf,
    pub film: Option<PathBuf>,
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
    /// What the axes vary, and every frame as planned.
    pub axes: [&'static str; 2],
    pub plans: Vec<FramePlan>,
}

/// A zoom's checks that need neither an engine nor every frame's map: the first map, each
/// view it goes to within what the map allows, and every frame's starts told apart by f64.
/// A frame between two views lies within the box of both (its corners move on straight
/// lines from one view's to the other's), so the views decide where the map's limits hold;
/// the explorer checks its zooms by this alone. Returns the frames' grids.
pub fn check<S: MapKernels + MapPicture>(job: &ZoomJob<S>) -> Result<Vec<Grid>> {
    let spec = &job.map.spec;
    check_in_memory(spec, job.wants_verdict(), job.map.samples)?;
    job.map
        .spec
        .check_picture(&job.map.picture, job.map.colour_range)?;
    let grids = grids(spec.grid(), &job.to, job.frames)?;
    // Each view the film passes through within what the map allows, named by its own values
    // (the frames between views then lie within the first view and these).
    for v in &job.to {
        let at = grid_of_view(spec.grid(), *v);
        check_in_memory(&spec.on_grid(at), false, 1).map_err(|e| match e {
            Error::InvalidSpec { field, reason } => Error::invalid(
                "to",
                format!(
                    "{},{},{} reaches past what the map allows ({field}): {reason}",
                    v.x, v.y, v.width
                ),
            ),
            e => e,
        })?;
    }
    let end = job.to.last().expect("checked: a view to go to");
    let aspect =
        (spec.grid().y.range.max - spec.grid().y.range.min) / Target::of(spec.grid()).width;
    for (k, g) in grids.iter().enumerate() {
        let fine = *computed_spec(&spec.on_grid(*g), job.map.samples).grid();
        if fine.beyond_f64() {
            // The widest the last view may be: each axis's f64 step limit, in widths.
            let x = fine.x.finest_step(f64::EPSILON) * fine.width as f64;
            let y = fine.y.finest_step(f64::EPSILON) * fine.height as f64 / aspect;
            return Err(Error::invalid(
                "to",
                format!(
                    "a width of {:e} is deeper than f64 resolves: from frame {k} on, neighbouring starts ({:.1e} apart) would share their numbers; on this grid a zoom ends at a width of {:.1e} or more",
                    end.width,
                    fine.x_step(),
                    x.max(y) * 1.01
                ),
            ));
        }
    }
    Ok(grids)
}

/// Every frame planned on `engine` as its map is ([`crate::plan::MapPlan`]: its path, its
/// checks on that path, the verdict's finer maps), before any work ([`check`] first, then
/// each frame's map against the map's limits), with what frames.csv says of each.
pub fn plan<S: MapKernels + MapPicture>(
    job: &ZoomJob<S>,
    engine: &Engine,
) -> Result<Vec<(FramePlan, MapPlan<S>)>> {
    let spec = &job.map.spec;
    let verdict = job.wants_verdict();
    let grids = check(job)?;
    grids
        .iter()
        .enumerate()
        .map(|(k, g)| {
            let fine = computed_spec(&spec.on_grid(*g), job.map.samples);
            if k > 0 {
                check_in_memory(&spec.on_grid(*g), verdict, job.map.samples).map_err(
                    |e| match e {
                        Error::InvalidSpec { field, reason } => Error::invalid(
                            "to",
                            format!("frame {k} leaves what the map allows ({field}): {reason}"),
                        ),
                        e => e,
                    },
                )?;
            }
            let map = engine.plan(&fine, verdict)?;
            let path = map.info.path;
            let frame = FramePlan {
                frame: k as u32,
                x: g.x.range.mid(),
                y: g.y.range.mid(),
                width: g.x.range.max - g.x.range.min,
                height: g.y.range.max - g.y.range.min,
                step: fine.grid().x_step(),
                precision: path.precision().name(),
                on_gpu: path.on_gpu(),
                grid: *g,
            };
            Ok((frame, map))
        })
        .collect()
}

/// Where the plan turns from f32 to f64, if it does.
pub fn switch(plans: &[FramePlan]) -> Option<Switch> {
    let f32 = Precision::F32.name();
    let k = plans.iter().position(|p| p.precision != f32)?;
    (k > 0 && plans[0].precision == f32).then(|| {
        let p = &plans[k];
        Switch {
            frame: p.frame,
            width: p.width,
            step: p.step,
            f32_finest: p.grid.x.finest_step(f32::EPSILON as f64),
            on_gpu: p.on_gpu,
        }
    })
}

/// The text a zoom's frame carries besides its map's: the zoom's command, the colours'
/// fixed range, the frame's unresolved share (with the verdict) and its precision.
const ZOOM_KEY: &str = "chaoscope:zoom";
const RANGE_KEY: &str = "chaoscope:zoom-range";
const UNRESOLVED_KEY: &str = "chaoscope:unresolved";
const PRECISION_KEY: &str = "chaoscope:precision";

fn parse_range(s: &str) -> Option<(f32, f32)> {
    let (lo, hi) = s.split_once(':')?;
    Some((lo.parse().ok()?, hi.parse().ok()?))
}

/// A zoom's frames: each the map of its planned view, in one colour range.
struct ZoomFrames<'a, S> {
    job: &'a ZoomJob<S>,
    plans: &'a [FramePlan],
    /// Each frame's map as planned ([`plan`]).
    maps: &'a [MapPlan<S>],
    engine: &'a Engine,
    /// The zoom's command, carried by every frame.
    command: &'a str,
    frame_command: &'a dyn Fn(&MapJob<S>) -> String,
    range: Option<(f32, f32)>,
    verdict: bool,
    /// Frame 0, where it was made to find the colours' range.
    first: RefCell<Option<Judged>>,
}

impl<S: MapKernels + MapPicture> ZoomFrames<'_, S> {
    /// Frame `k`'s map, as planned.
    fn compute(&self, k: u32, this: &MapJob<S>, monitor: &Monitor) -> Result<Judged> {
        let map = self.maps[k as usize].clone();
        compute_planned(&this.spec, map, self.engine, this.samples, monitor)
    }

    fn job(&self, k: u32) -> MapJob<S> {
        let plan = &self.plans[k as usize];
        MapJob {
            spec: self.job.map.spec.on_grid(plan.grid),
            backend: if plan.on_gpu {
                Backend::Gpu
            } else {
                Backend::Cpu
            },
            colour_range: self.range,
            ..self.job.map.clone()
        }
    }

    /// The colours' range, fixed for every frame (the frames would flicker else): given, or
    /// frame 0's own (read back from its PNG, whose command is then checked with it, or
    /// computed, that frame kept for the run); returns where it came from.
    fn fix_range(&mut self, set: &FrameSet, monitor: &Monitor) -> Result<&'static str> {
        let job = self.job;
        Ok(match (job.map.spec.ranged(), job.map.colour_range) {
            (false, _) => {
                self.range = None;
                "fixed by the quantity"
            }
            (true, Some(_)) => "given",
            (true, None) => {
                let read = set
                    .read(0)?
                    .and_then(|png| text(&png, RANGE_KEY).and_then(parse_range));
                self.range = match read {
                    Some(r) => Some(r),
                    None => {
                        let first = self.job(0);
                        let made = self.compute(0, &first, &monitor.quiet())?;
                        let drawn = first.spec.draw(&made.made.0, &first.picture, None, None)?;
                        *self.first.get_mut() = Some(made);
                        Some(
                            drawn
                                .range
                                .expect("a ranged quantity's picture has a range"),
                        )
                    }
                };
                "frame 0"
            }
        })
    }
}

impl<S: MapKernels + MapPicture> Frames for ZoomFrames<'_, S> {
    fn command(&self, k: u32) -> String {
        (self.frame_command)(&self.job(k))
    }

    /// A frame without the judgement this run asks for is made again.
    fn keep(&self, _k: u32, png: &render::Png, _monitor: &Monitor) -> Result<bool> {
        Ok(!self.verdict || text(png, UNRESOLVED_KEY).is_some())
    }

    fn make(&self, k: u32, monitor: &Monitor) -> Result<frames::Made> {
        let this = self.job(k);
        let computed = match (k, self.first.take()) {
            (0, Some(m)) => m,
            _ => self.compute(k, &this, monitor)?,
        };
        let (field, mask) = &computed.made;
        let shown = mask.as_deref().filter(|_| this.files.show_unresolved);
        let drawn = this.spec.draw(field, &this.picture, self.range, shown)?;
        let mut text = drawn.picture.metadata();
        text.extend(drawn.text);
        text.push((ZOOM_KEY.into(), self.command.to_string()));
        text.push((
            PRECISION_KEY.into(),
            computed.info.path.precision().name().into(),
        ));
        if let Some((lo, hi)) = self.range {
            text.push((RANGE_KEY.into(), format!("{lo}:{hi}")));
        }
        if let Some(mask) = mask {
            let unresolved = 1.0 - crate::verdict::fraction(mask);
            text.push((UNRESOLVED_KEY.into(), format!("{unresolved}")));
        }
        Ok(frames::Made {
            picture: drawn.picture,
            info: computed.info,
            text,
        })
    }
}

/// Runs the zoom on `engine`: this task's frames that are not already there, then (without
/// a tile) the film and frames.csv. `command` reproduces the zoom (it goes into the film
/// and every frame); `frame_command` the single map of one frame (it goes into the frame and
/// identifies it when a zoom resumes).
pub fn run<S: MapKernels + MapPicture>(
    job: &ZoomJob<S>,
    at: &crate::app::Running,
    frame_command: &dyn Fn(&MapJob<S>) -> String,
) -> Result<ZoomSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    let set = FrameSet::new(
        "zoom",
        &job.output,
        job.frames,
        job.tile,
        &job.film,
        FILM_FORMATS,
    )?;
    let (plans, maps): (Vec<FramePlan>, Vec<MapPlan<S>>) = plan(job, engine)?.into_iter().unzip();
    set.check()?;
    let mut notices = engine.notices();
    let switch = switch(&plans);
    if let Some(s) = &switch {
        let grid = &plans[s.frame as usize].grid;
        notices.push(crate::plan::f64_notice(
            grid,
            s.on_gpu,
            Some((s.frame, s.width)),
        ));
    }
    let verdict = job.wants_verdict();
    let started = Instant::now();
    let mut frames = ZoomFrames {
        job,
        plans: &plans,
        maps: &maps,
        engine,
        command: &command,
        frame_command,
        range: job.map.colour_range,
        verdict,
        first: RefCell::new(None),
    };
    let range_from = frames.fix_range(&set, monitor)?;
    let run = set.make(&frames, monitor)?;
    notices.extend(run.damaged);
    let mut summary = ZoomSummary {
        frames: job.frames,
        made: run.made,
        kept: run.kept,
        tile: job.tile,
        switch,
        range: frames.range,
        range_from,
        unresolved_mean: None,
        unresolved_max: None,
        compute_seconds: started.elapsed().as_secs_f64(),
        encode_seconds: None,
        output: job.output.clone(),
        film: None,
        files: run.files,
        notices,
        axes: [
            job.map.spec.grid().x.var.name(),
            job.map.spec.grid().y.var.name(),
        ],
        plans: Vec::new(),
    };
    if job.tile.is_none() {
        let encoding = Instant::now();
        let mut unresolved = Vec::new();
        set.encode(
            &command,
            &engine.info(),
            "x,y,width,height,step,precision,place,unresolved",
            |k, png| {
                let p = &plans[k as usize];
                let u = text(png, UNRESOLVED_KEY).and_then(|s| s.parse::<f64>().ok());
                unresolved.extend(u);
                format!(
                    "{},{},{:e},{:e},{:e},{},{},{}",
                    p.x,
                    p.y,
                    p.width,
                    p.height,
                    p.step,
                    p.precision,
                    if p.on_gpu { "gpu" } else { "cpu" },
                    u.map(|u| u.to_string()).unwrap_or_default()
                )
            },
            monitor,
        )?;
        summary.encode_seconds = Some(encoding.elapsed().as_secs_f64());
        if verdict {
            summary.unresolved_mean =
                Some(unresolved.iter().sum::<f64>() / unresolved.len() as f64);
            summary.unresolved_max = unresolved.iter().copied().reduce(f64::max);
        }
        summary.film = Some(job.film.path.clone());
        summary
            .files
            .extend([job.film.path.clone(), job.output.join(TABLE)]);
    }
    summary.plans = plans;
    Ok(summary)
}
