//! `chaoscope sweep`: one map per frame while a physical parameter changes (a zoom into a
//! point is `chaoscope zoom`); numbered PNGs plus an animated PNG. Frames that already exist (from an
//! interrupted run of the same sweep) are kept, so running the command again resumes it.

use std::path::PathBuf;

use super::film::{FilmSpec, Format};
use super::frames::{FrameSet, Frames, Made, TABLE};
use crate::engine::{Backend, Engine, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::model::Params;
use crate::monitor::Monitor;
use crate::render::store::SweepStore;
use crate::render::{self, MapPicture, Picture, PictureSpec};
use crate::spec::{self, AnyMap, FlipMeasure, FlipSpec, Grid, LyapunovSpec, MapSpec, Stepping};

pub use crate::spec::MapKind;

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

impl Param {
    /// Every parameter with its name.
    pub const NAMES: [(Param, &'static str); 11] = [
        (Param::M1, "m1"),
        (Param::M2, "m2"),
        (Param::L1, "l1"),
        (Param::L2, "l2"),
        (Param::G, "g"),
        (Param::MassRatio, "m2/m1"),
        (Param::LengthRatio, "l2/l1"),
        (Param::Mass, "mass"),
        (Param::Omega1, "omega1"),
        (Param::Omega2, "omega2"),
        (Param::Damping, "damping"),
    ];

    /// The plane's variable it is (all but `mass`, which scales both masses).
    pub fn var(self) -> Option<crate::spec::Var> {
        use crate::spec::Var;
        Some(match self {
            Param::M1 => Var::M1,
            Param::M2 => Var::M2,
            Param::L1 => Var::L1,
            Param::L2 => Var::L2,
            Param::G => Var::G,
            Param::MassRatio => Var::MassRatio,
            Param::LengthRatio => Var::LengthRatio,
            Param::Omega1 => Var::Omega1,
            Param::Omega2 => Var::Omega2,
            Param::Damping => Var::Damping,
            Param::Mass => return None,
        })
    }

    /// The parameter's unit, for a store's coordinate.
    pub fn unit(self) -> &'static str {
        match self {
            Param::M1 | Param::M2 => "kg",
            Param::L1 | Param::L2 => "m",
            Param::G => "m/s^2",
            Param::MassRatio | Param::LengthRatio | Param::Mass => "1",
            Param::Omega1 | Param::Omega2 => "rad/s",
            Param::Damping => "N m s",
        }
    }

    pub fn name(self) -> &'static str {
        Param::NAMES
            .iter()
            .find(|(p, _)| *p == self)
            .map(|(_, n)| *n)
            .expect("every parameter has a name")
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vary {
    pub param: Param,
    pub from: f64,
    pub to: f64,
}

impl Vary {
    /// The parameter's value at `progress` (0 the first frame, 1 the last).
    pub fn at(&self, progress: f64) -> f64 {
        self.from + (self.to - self.from) * progress
    }
}

/// How far frame `k` of `n` is through the sweep, 0 to 1 (0 for a single frame).
fn progress(k: usize, n: usize) -> f64 {
    match n {
        0 | 1 => 0.0,
        _ => k as f64 / (n - 1) as f64,
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct SweepJob {
    pub map: MapKind,
    pub vary: Vary,
    pub frames: u32,
    /// The animation: its file (APNG, MP4), rate and quality.
    pub film: FilmSpec,
    /// The first frame's parameters and grid.
    pub params: Params,
    pub grid: Grid,
    pub stepping: Stepping,
    /// Lyapunov frames: renormalisation interval (s) and top of the colour range (1/s).
    pub renorm: f64,
    pub ftle_max: f64,
    pub backend: Backend,
    pub picture: PictureSpec,
    /// Directory for frame_0000.png ... and animation.png.
    pub output: PathBuf,
    /// The frames' maps also as one Zarr store (frame, theta2, theta1).
    pub data: Option<PathBuf>,
    /// Make only frames k with k % COUNT == INDEX (no film): `(INDEX, COUNT)`.
    pub tile: Option<(u32, u32)>,
}

/// One frame's parameters and grid.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub params: Params,
    pub grid: Grid,
}

/// The frames of a sweep, validated; errors name the job's field.
pub fn frames(args: &SweepJob) -> Result<Vec<Frame>> {
    if args.frames == 0 || args.frames > 100_000 {
        return Err(Error::invalid("frames", "must be between 1 and 100000"));
    }
    // A parameter along an axis is the pixel's own: a sweep of it would change nothing.
    if let Some(var) = args.vary.param.var()
        && [args.grid.x.var, args.grid.y.var]
            .iter()
            .any(|a| a.overlaps(var))
    {
        return Err(Error::invalid(
            "vary",
            format!(
                "{} lies along an axis of the map: sweep another parameter",
                var.name()
            ),
        ));
    }
    spec::validate_params(&args.params)?;
    let base_params = args.params;
    let base_grid = args.grid;
    let n = args.frames;
    let mut out = Vec::with_capacity(n as usize);
    for k in 0..n {
        let s = progress(k as usize, n as usize);
        let mut p = base_params;
        let mut g = base_grid;
        let v = args.vary;
        let x = v.at(s);
        match v.param.var() {
            Some(var) => var.set(x, &mut p, &mut g.fixed),
            None => {
                p.m1 *= x;
                p.m2 *= x;
            }
        }
        spec::validate_params(&p)
            .map_err(|e| Error::invalid("vary", format!("at frame {k}: {e}")))?;
        out.push(Frame { params: p, grid: g });
    }
    Ok(out)
}

/// The animation's name in the output folder when no other file is named.
pub const ANIMATION: &str = "animation.png";

/// What a sweep's animation may be: an APNG (lossless) or an MP4.
pub const FILM_FORMATS: &[Format] = &[Format::Apng, Format::Mp4];

#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepSummary {
    pub frames: usize,
    /// Frames computed by this run, and kept from an earlier, interrupted run of the same
    /// sweep.
    pub made: u32,
    pub kept: u32,
    pub tile: Option<(u32, u32)>,
    pub output: PathBuf,
    /// The animation (None: a tile makes none).
    pub animation: Option<PathBuf>,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

/// A sweep's frames: each the map of its frame's physics, on the path the engine picks.
struct SweepFrames<'a> {
    job: &'a SweepJob,
    frames: &'a [Frame],
    engine: &'a Engine,
    frame_command: &'a dyn Fn(&AnyMap, Backend, &PictureSpec) -> String,
    store: Option<SweepStore>,
}

impl SweepFrames<'_> {
    fn map(&self, k: u32) -> AnyMap {
        frame_map(self.job, &self.frames[k as usize])
    }

    fn info(&self, map: &AnyMap) -> RunInfo {
        self.engine.map_info(map.grid(), map.precision())
    }

    /// Frame `k`'s map into the store, if there is one.
    fn store(&self, k: u32, field: &Field) -> Result<()> {
        match &self.store {
            Some(s) => s.write_frame(k, field),
            None => Ok(()),
        }
    }
}

impl Frames for SweepFrames<'_> {
    fn command(&self, k: u32) -> String {
        let map = self.map(k);
        let on = match self.info(&map).path.on_gpu() {
            true => Backend::Gpu,
            false => Backend::Cpu,
        };
        (self.frame_command)(&map, on, &self.job.picture)
    }

    /// A frame whose picture is there but not its store's map: the map once more.
    fn keep(&self, k: u32, _png: &render::Png, monitor: &Monitor) -> Result<bool> {
        if let Some(s) = &self.store
            && !s.has_frame(k)?
        {
            let field = frame_field(&self.map(k), self.engine, monitor)?;
            s.write_frame(k, &field)?;
        }
        Ok(true)
    }

    fn make(&self, k: u32, monitor: &Monitor) -> Result<Made> {
        let map = self.map(k);
        let field = frame_field(&map, self.engine, monitor)?;
        self.store(k, &field)?;
        Ok(Made {
            picture: frame_picture(self.job, &map, &field)?,
            info: self.info(&map),
            text: Vec::new(),
        })
    }
}

/// Runs the sweep; `command` reproduces the whole sweep (it goes into the animation),
/// `frame_command` the single map of one frame on one backend (it goes into the frame and
/// identifies it when a sweep resumes).
pub fn run(
    job: &SweepJob,
    at: &super::Running,
    frame_command: &dyn Fn(&AnyMap, Backend, &PictureSpec) -> String,
) -> Result<SweepSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    // The plane as given, before any frame: its own errors name its own fields (--x),
    // not the varied parameter.
    spec::validate_grid(&job.grid)?;
    let frames = frames(job)?;
    let set = FrameSet::new(
        "sweep",
        &job.output,
        frames.len() as u32,
        job.tile,
        &job.film,
        FILM_FORMATS,
    )?;
    if job.tile.is_some() && job.data.is_some() {
        return Err(Error::invalid(
            "tile",
            "a sweep's store is written by one task: leave out the tile or the data store",
        ));
    }
    check_frames(job, &frames)?;
    set.check()?;
    if let Some(data) = &job.data {
        super::check_extension("data", data, "zarr")?;
    }
    // Every frame has the first's grid (a sweep varies the physics or the fixed start): the
    // first frame's plan says what all of them will (the engine, f64 where f32 runs out, the
    // measure's own notes), in the words a single map uses.
    let mut notices = match frame_map(job, &frames[0]) {
        AnyMap::Flip(spec) => engine.plan(&spec, false)?.notices,
        AnyMap::Lyapunov(spec) => engine.plan(&spec, false)?.notices,
    };
    let n = frames.len();
    let values: Vec<f64> = (0..n).map(|k| job.vary.at(progress(k, n))).collect();
    let store = open_store(job, &frames, &values, &command)?;
    let sweep = SweepFrames {
        job,
        frames: &frames,
        engine,
        frame_command,
        store,
    };
    let run = set.make(&sweep, monitor)?;
    notices.extend(run.damaged);
    let mut summary = SweepSummary {
        frames: n,
        made: run.made,
        kept: run.kept,
        tile: job.tile,
        output: job.output.clone(),
        animation: None,
        files: run.files,
        notices,
    };
    if job.tile.is_none() {
        set.encode(
            &command,
            &engine.info(),
            &format!("{},precision,place", job.vary.param.name()),
            |k, _| {
                let path = sweep.info(&sweep.map(k)).path;
                let place = if path.on_gpu() { "gpu" } else { "cpu" };
                format!("{},{},{place}", values[k as usize], path.precision().name())
            },
            monitor,
        )?;
        summary.animation = Some(job.film.path.clone());
        summary
            .files
            .extend([job.film.path.clone(), job.output.join(TABLE)]);
    }
    summary.files.extend(job.data.clone());
    Ok(summary)
}

/// Every frame's checks: the stepping once, each frame's plane, stability and grid (an
/// impossible frame is the varied range's fault, named `vary`), the divergence map's own.
fn check_frames(job: &SweepJob, frames: &[Frame]) -> Result<()> {
    spec::validate_stepping(&job.stepping)?;
    for (k, f) in frames.iter().enumerate() {
        let checked = spec::validate_grid(&f.grid)
            .and_then(|()| spec::validate_stability(&f.params, &job.stepping))
            .and_then(|()| spec::validate_plane(&f.params, &f.grid, &job.stepping));
        if let Err(Error::InvalidSpec { field, reason }) = checked {
            return Err(Error::invalid(
                "vary",
                format!(
                    "at frame {k} ({} = {:e}): {field}: {reason}",
                    job.vary.param.name(),
                    job.vary.at(progress(k, frames.len()))
                ),
            ));
        }
        checked?;
    }
    if let AnyMap::Lyapunov(spec) = frame_map(job, &frames[0]) {
        spec.validate()?;
    }
    if !(job.ftle_max.is_finite() && job.ftle_max > 0.0) {
        return Err(Error::invalid("ftle_max", "must be > 0"));
    }
    Ok(())
}

/// The sweep's Zarr store, when asked for: made, or opened to resume; the varied
/// parameter's `values` its frame coordinate.
fn open_store(
    job: &SweepJob,
    frames: &[Frame],
    values: &[f64],
    command: &str,
) -> Result<Option<SweepStore>> {
    Ok(match &job.data {
        Some(path) => {
            let info = crate::render::store::StoreInfo {
                command: command.to_string(),
                version: env!("CARGO_PKG_VERSION").to_string(),
                tiles: 1,
                mirrored: false,
                resolved: false,
                identity: serde_json::json!({
                    "frames": frames.iter().map(|f| frame_map(job, f)).collect::<Vec<_>>(),
                    "backend": job.backend.name(),
                }),
            };
            let quantity = frame_map(job, &frames[0]).quantity();
            let map = (quantity.name, quantity.unit);
            let vary = job.vary.param;
            Some(SweepStore::create_or_open(
                path,
                &frames[0].grid,
                &info,
                (vary.name(), vary.unit(), values),
                map,
            )?)
        }
        None => None,
    })
}

fn lyapunov_spec(job: &SweepJob, frame: &Frame) -> LyapunovSpec {
    LyapunovSpec {
        renorm: job.renorm,
        ..LyapunovSpec::new(frame.params, frame.grid, job.stepping)
    }
}

fn frame_map(job: &SweepJob, frame: &Frame) -> AnyMap {
    match job.map {
        MapKind::FLIP_TIME => AnyMap::Flip(FlipSpec::new(frame.params, frame.grid, job.stepping)),
        MapKind::FLIP_KIND => AnyMap::Flip(FlipSpec {
            measure: FlipMeasure::Kind,
            ..FlipSpec::new(frame.params, frame.grid, job.stepping)
        }),
        kind => AnyMap::Lyapunov(LyapunovSpec {
            indicator: kind
                .entry()
                .indicator
                .expect("every map but the flip maps is of the divergence family"),
            ..lyapunov_spec(job, frame)
        }),
    }
}

/// One frame's map, planned as every map is ([`Engine::plan`]: the checks of its path).
fn frame_field(map: &AnyMap, engine: &Engine, monitor: &Monitor) -> Result<Field> {
    let (field, _) = match map {
        AnyMap::Flip(spec) => engine.planned_map(&engine.plan(spec, false)?, monitor)?,
        AnyMap::Lyapunov(spec) => engine.planned_map(&engine.plan(spec, false)?, monitor)?,
    };
    Ok(field)
}

/// One frame's picture.
fn frame_picture(job: &SweepJob, map: &AnyMap, field: &Field) -> Result<Picture> {
    // One colour range for every frame of the FTLE (--ftle-max); the other indicators take
    // their own default range per frame.
    let range = (job.map == MapKind::FTLE).then_some((0.0, job.ftle_max as f32));
    Ok(map.draw(field, &job.picture, range, None)?.picture)
}
