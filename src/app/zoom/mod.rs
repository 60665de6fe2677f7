//! `chaoscope zoom`: a film from one view of a map's plane to another, or through several,
//! the width shrinking geometrically (a constant zoom speed). Every frame is the map of its
//! view, computed with the precision its pixel step needs: f32 while f32 resolves the step,
//! then f64 (on a GPU that has it, else on the CPU), and refused where even f64 cannot.
//!
//! Frames are numbered PNGs, each carrying the single map's command that makes it alone: a
//! run keeps the frames an earlier run of the same zoom finished (resume), `tile` shares the
//! frames out between tasks, and a run without `tile` encodes the film once every frame is
//! there, with `frames.csv` (each frame's view, precision, place and unresolved share).

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use super::film::{FilmSpec, Format, frame_name};
use super::map::{MapJob, check_in_memory, compute};
use crate::engine::{Backend, Engine, MapKernels};
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::{self, MapPicture, Outputs};
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
/// The frames' table's name in the output folder.
pub const TABLE: &str = "frames.csv";

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

/// The grid a frame's map is computed on: `samples` x `samples` starts a pixel.
fn computed_grid(grid: &Grid, samples: u32) -> Grid {
    Grid {
        width: grid.width * samples,
        height: grid.height * samples,
        ..*grid
    }
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
        let fine = computed_grid(g, job.map.samples);
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

/// Every frame planned on `engine`, checked as its map would be, before any work ([`check`],
/// then each frame's map against the map's limits and the path it runs on).
pub fn plan<S: MapKernels + MapPicture>(
    job: &ZoomJob<S>,
    engine: &Engine,
) -> Result<Vec<FramePlan>> {
    let spec = &job.map.spec;
    let verdict = job.wants_verdict();
    let grids = check(job)?;
    grids
        .iter()
        .enumerate()
        .map(|(k, g)| {
            let fine = computed_grid(g, job.map.samples);
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
            let path = engine.map_info(&fine, spec.precision()).path;
            Ok(FramePlan {
                frame: k as u32,
                x: g.x.range.mid(),
                y: g.y.range.mid(),
                width: g.x.range.max - g.x.range.min,
                height: g.y.range.max - g.y.range.min,
                step: fine.x_step(),
                precision: path.precision().name(),
                on_gpu: path.on_gpu(),
                grid: *g,
            })
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

/// Whether frame `k` is this task's.
fn mine(tile: Option<(u32, u32)>, k: u32) -> bool {
    tile.is_none_or(|(index, count)| k % count == index)
}

/// The text a frame's PNG carries besides its provenance.
const ZOOM_KEY: &str = "chaoscope:zoom";
const FRAME_KEY: &str = "chaoscope:frame";
const RANGE_KEY: &str = "chaoscope:zoom-range";
const UNRESOLVED_KEY: &str = "chaoscope:unresolved";
const COMMAND_KEY: &str = "chaoscope:command";
/// The precision the frame ran in (f32 or f64).
const PRECISION_KEY: &str = "chaoscope:precision";
/// The frame's pixels' digest ([`digest`]), so that a frame changed since it was written is
/// made again rather than kept.
const PIXELS_KEY: &str = "chaoscope:pixels";

/// A frame's pixels as 16 hex digits: FNV-1a over its bytes (stable across Rust versions and
/// machines, which a resume needs; a checksum against damage, not against intent).
fn digest(rgb: &[u8]) -> String {
    let hash = rgb.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("{hash:016x}")
}

fn text<'a>(png: &'a render::Png, key: &str) -> Option<&'a str> {
    png.text
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

fn parse_range(s: &str) -> Option<(f32, f32)> {
    let (lo, hi) = s.split_once(':')?;
    Some((lo.parse().ok()?, hi.parse().ok()?))
}

/// Runs the zoom on `engine`: this task's frames that are not already there, then (without
/// a tile) the film and frames.csv. `command` reproduces the zoom (it goes into the film
/// and every frame); `frame_command` the single map of one frame (it goes into the frame and
/// identifies it when a zoom resumes).
pub fn run<S: MapKernels + MapPicture>(
    job: &ZoomJob<S>,
    engine: &Engine,
    command: String,
    frame_command: &dyn Fn(&MapJob<S>) -> String,
    monitor: &Monitor,
) -> Result<ZoomSummary> {
    if let Some((index, count)) = job.tile
        && (count == 0 || index >= count)
    {
        return Err(Error::invalid(
            "tile",
            format!("{index}/{count}: INDEX/COUNT with 0 <= INDEX < COUNT"),
        ));
    }
    let plans = plan(job, engine)?;
    let n = plans.len() as u32;
    let mut names: Vec<String> = (0..n).map(frame_name).collect();
    names.push(TABLE.into());
    // A tile writes frames alone; the whole zoom its film too, which is none of them.
    let film = [("film", job.film.path.as_path())];
    let also: &[_] = match job.tile {
        None => &film,
        Some(_) => &[],
    };
    super::checks::check_directory("output", &job.output, &names, also, &[])?;
    if job.tile.is_none() {
        job.film.validate("film", FILM_FORMATS)?;
    }
    let mut notices = engine.notices();
    let switch = switch(&plans);
    if let Some(s) = &switch {
        notices.push(format!(
            "note: from frame {} on (width {:.3e}) the step between starts, {:.1e}, is finer than f32 resolves ({:.1e} there): those frames run in f64 on the {}",
            s.frame,
            s.width,
            s.step,
            s.f32_finest,
            if s.on_gpu { "GPU" } else { "CPU" }
        ));
    }
    std::fs::create_dir_all(&job.output)?;
    let verdict = job.wants_verdict();
    let quiet = monitor.quiet();
    let started = Instant::now();
    let frame_job = |k: usize, range: Option<(f32, f32)>| MapJob {
        spec: job.map.spec.on_grid(plans[k].grid),
        backend: if plans[k].on_gpu {
            Backend::Gpu
        } else {
            Backend::Cpu
        },
        colour_range: range,
        ..job.map.clone()
    };
    // A frame of this zoom already there (its own command and, with the verdict, its
    // judgement), read back; another zoom's is refused.
    let damaged = std::cell::RefCell::new(std::collections::BTreeSet::new());
    let kept = |k: usize, range: Option<(f32, f32)>| -> Result<Option<render::Png>> {
        let path = job.output.join(frame_name(k as u32));
        if !path.exists() {
            return Ok(None);
        }
        // A frame cut short or otherwise unreadable as a PNG (a run killed as the disk
        // filled, a bad copy), or whose pixels are no longer those it was written with, is
        // made again (said in a notice); anything but a file there is refused when written.
        let png = match render::read_png(&path) {
            Ok(png) => png,
            Err(Error::Format(_)) => {
                damaged.borrow_mut().insert(k);
                return Ok(None);
            }
            Err(e) => return Err(e),
        };
        if text(&png, PIXELS_KEY).is_some_and(|d| d != digest(&png.rgb)) {
            damaged.borrow_mut().insert(k);
            return Ok(None);
        }
        let range = range.or_else(|| text(&png, RANGE_KEY).and_then(parse_range));
        if text(&png, COMMAND_KEY) != Some(frame_command(&frame_job(k, range)).as_str()) {
            return Err(Error::invalid(
                "output",
                format!(
                    "{} holds frames of a different zoom; choose another directory",
                    job.output.display()
                ),
            ));
        }
        Ok((!verdict || text(&png, UNRESOLVED_KEY).is_some()).then_some(png))
    };
    // The colours' range: fixed for every frame (the frames would flicker else): given, or
    // frame 0's own (read back from its PNG, or computed).
    let ranged = job.map.spec.ranged();
    let mut first: Option<super::map::Made<(crate::field::Field, Option<Vec<u8>>)>> = None;
    let (range, range_from) = match (ranged, job.map.colour_range) {
        (false, _) => (None, "fixed by the quantity"),
        (true, Some(r)) => (Some(r), "given"),
        (true, None) => {
            let read = kept(0, None)?.and_then(|png| text(&png, RANGE_KEY).and_then(parse_range));
            let range = match read {
                Some(r) => r,
                None => {
                    let made = compute(
                        &frame_job(0, None).spec,
                        engine,
                        verdict,
                        job.map.samples,
                        &quiet,
                    )?;
                    let drawn = job.map.spec.on_grid(plans[0].grid).draw(
                        &made.made.0,
                        &job.map.picture,
                        None,
                        None,
                    )?;
                    first = Some(made);
                    drawn
                        .range
                        .expect("a ranged quantity's picture has a range")
                }
            };
            (Some(range), "frame 0")
        }
    };
    let todo: Vec<usize> = (0..plans.len())
        .filter(|&k| mine(job.tile, k as u32))
        .collect();
    monitor.start("frames", todo.len() as u64);
    let (mut made, mut kept_count) = (0, 0);
    for &k in &todo {
        monitor.check()?;
        if kept(k, range)?.is_some() {
            kept_count += 1;
            monitor.advance(1);
            continue;
        }
        let this = frame_job(k, range);
        let computed = match (k, first.take()) {
            (0, Some(m)) => m,
            _ => compute(&this.spec, engine, verdict, this.samples, &quiet)?,
        };
        let (field, mask) = &computed.made;
        let shown = mask.as_deref().filter(|_| this.files.show_unresolved);
        let drawn = this.spec.draw(field, &this.picture, range, shown)?;
        let mut meta = render::provenance(frame_command(&this), &computed.info);
        meta.extend(drawn.picture.metadata());
        meta.extend(drawn.text);
        meta.push((ZOOM_KEY.into(), command.clone()));
        meta.push((FRAME_KEY.into(), format!("{k} of {n}")));
        meta.push((
            PRECISION_KEY.into(),
            computed.info.path.precision().name().into(),
        ));
        if let Some((lo, hi)) = range {
            meta.push((RANGE_KEY.into(), format!("{lo}:{hi}")));
        }
        if let Some(mask) = mask {
            let unresolved = 1.0 - crate::verdict::fraction(mask);
            meta.push((UNRESOLVED_KEY.into(), format!("{unresolved}")));
        }
        let picture = &drawn.picture;
        meta.push((PIXELS_KEY.into(), digest(&picture.rgb)));
        render::write_png(
            &job.output.join(frame_name(k as u32)),
            picture.width,
            picture.height,
            &picture.rgb,
            &meta,
        )?;
        made += 1;
        monitor.advance(1);
    }
    monitor.finish();
    let damaged = damaged.into_inner();
    if !damaged.is_empty() {
        let names: Vec<String> = damaged.iter().map(|&k| frame_name(k as u32)).collect();
        notices.push(format!(
            "{} frames were damaged (unreadable, or their pixels changed since they were written) and were made again: {}",
            damaged.len(),
            names.join(", ")
        ));
    }
    let compute_seconds = started.elapsed().as_secs_f64();
    let mut summary = ZoomSummary {
        frames: n,
        made,
        kept: kept_count,
        tile: job.tile,
        switch,
        range,
        range_from,
        unresolved_mean: None,
        unresolved_max: None,
        compute_seconds,
        encode_seconds: None,
        output: job.output.clone(),
        film: None,
        files: todo
            .iter()
            .map(|&k| job.output.join(frame_name(k as u32)))
            .collect(),
        notices,
        axes: [
            job.map.spec.grid().x.var.name(),
            job.map.spec.grid().y.var.name(),
        ],
        plans: Vec::new(),
    };
    if job.tile.is_some() {
        summary.plans = plans;
        return Ok(summary);
    }
    let encoding = Instant::now();
    let unresolved = encode(job, &plans, &command, engine, monitor)?;
    summary.encode_seconds = Some(encoding.elapsed().as_secs_f64());
    if verdict {
        summary.unresolved_mean = Some(unresolved.iter().sum::<f64>() / unresolved.len() as f64);
        summary.unresolved_max = unresolved.iter().copied().reduce(f64::max);
    }
    summary.plans = plans;
    summary.film = Some(job.film.path.clone());
    summary
        .files
        .extend([job.film.path.clone(), job.output.join(TABLE)]);
    Ok(summary)
}

/// The film from the frame files, read one at a time, and frames.csv beside it; returns
/// each frame's share of unresolved pixels (empty without the verdict).
fn encode<S>(
    job: &ZoomJob<S>,
    plans: &[FramePlan],
    command: &str,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Vec<f64>> {
    let path = |k: usize| job.output.join(frame_name(k as u32));
    let first = render::read_png(&path(0))?;
    let size = (first.width, first.height);
    drop(first);
    let mut unresolved: Vec<Option<f64>> = Vec::with_capacity(plans.len());
    let mut files = Outputs::new();
    monitor.start("film", plans.len() as u64);
    super::film::write(
        &mut files,
        &job.film,
        job.film.format("film", FILM_FORMATS)?,
        size,
        plans.len(),
        &render::provenance(command.to_string(), &engine.info()),
        |k| {
            monitor.check()?;
            let png = render::read_png(&path(k))?;
            if (png.width, png.height) != size {
                return Err(Error::format(
                    &path(k),
                    "a frame of another size than frame 0",
                ));
            }
            unresolved.push(text(&png, UNRESOLVED_KEY).and_then(|s| s.parse().ok()));
            monitor.advance(1);
            Ok(png.rgb)
        },
    )?;
    monitor.finish();
    files.write(&job.output.join(TABLE), |w| {
        writeln!(w, "# {command}")?;
        writeln!(w, "frame,x,y,width,height,step,precision,place,unresolved")?;
        for (p, u) in plans.iter().zip(&unresolved) {
            writeln!(
                w,
                "{},{},{},{:e},{:e},{:e},{},{},{}",
                p.frame,
                p.x,
                p.y,
                p.width,
                p.height,
                p.step,
                p.precision,
                if p.on_gpu { "gpu" } else { "cpu" },
                u.map(|u| u.to_string()).unwrap_or_default()
            )?;
        }
        Ok(())
    })?;
    files.commit(monitor)?;
    Ok(unresolved.into_iter().flatten().collect())
}
