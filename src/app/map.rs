//! The one path of every map, whichever quantity it measures: one job, checked once, planned
//! once on the engine (with its verdict's finer map), computed with its verdict or filled into
//! a store band by band, drawn as its quantity draws it, summed up in one summary. `flip` and
//! `lyapunov` are two front doors of it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::check_output;
use crate::engine::{Backend, Engine, MapKernels, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::plan::{MapPlan, check_verdict};
use crate::quantity::Quantity;
use crate::render::store::{Filled, StoreFill, fill_store, missing_note};
use crate::render::{self, MapPicture, Outputs, Picture, PictureSpec, check_writable};
use crate::spec::{Grid, MapSpec};
use crate::verdict;

/// A map to make, whatever it measures.
#[derive(Clone, Debug, PartialEq)]
pub struct MapJob<S> {
    pub spec: S,
    pub backend: Backend,
    pub picture: PictureSpec,
    /// The PNG, the raw values (the quantity's unit), the verdict.
    pub files: MapOutputs,
    /// With a .zarr store: compute only part `index` of `count` of it.
    pub tile: Option<(u32, u32)>,
    /// The colours' range (low, high, the quantity's unit) where its colours span one; None:
    /// the quantity's default for the map.
    pub colour_range: Option<(f32, f32)>,
    /// Sub-samples a side of every pixel ([`super::supersample`]); 1: the pixel's centre.
    pub samples: u32,
}

/// What a map run did, whatever it measured.
#[derive(Clone, Debug)]
pub struct MapSummary {
    pub quantity: &'static Quantity,
    pub width: u32,
    pub height: u32,
    /// Where it ran: the adapter's name or "the CPU".
    pub place: String,
    pub seconds: f64,
    /// The share of the pixels the quantity counts (flipped, chaotic), under its key.
    pub counted: f64,
    /// Pixels whose state left the numbers (NaN in the data).
    pub nan: usize,
    /// The fraction of the pixels resolved, when the verdict was asked for.
    pub resolved: Option<f64>,
    /// How the verdict's finer map differs, in a few words.
    pub rule: String,
    pub t_max: f64,
    /// Whether half the map is the other half mirrored (a point-symmetric plane).
    pub mirrored: bool,
    /// The colour range, where the quantity's colours span one (NaN for a store: no picture).
    pub range: Option<(f32, f32)>,
    pub output: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

impl serde::Serialize for MapSummary {
    fn serialize<Se: serde::Serializer>(&self, s: Se) -> std::result::Result<Se::Ok, Se::Error> {
        use serde::ser::SerializeStruct;
        let mut m = s.serialize_struct("MapSummary", 14 + self.range.is_some() as usize)?;
        m.serialize_field("quantity", self.quantity.name)?;
        m.serialize_field("width", &self.width)?;
        m.serialize_field("height", &self.height)?;
        m.serialize_field("place", &self.place)?;
        m.serialize_field("seconds", &self.seconds)?;
        m.serialize_field(self.quantity.counted_as, &self.counted)?;
        m.serialize_field("nan", &self.nan)?;
        m.serialize_field("resolved", &self.resolved)?;
        m.serialize_field("rule", &self.rule)?;
        m.serialize_field("t_max", &self.t_max)?;
        m.serialize_field("mirrored", &self.mirrored)?;
        if let Some(range) = &self.range {
            m.serialize_field("range", range)?;
        }
        m.serialize_field("output", &self.output)?;
        m.serialize_field("files", &self.files)?;
        m.serialize_field("notices", &self.notices)?;
        m.end()
    }
}

/// Runs `job` on the `engine` its door lends: its map (and verdict) into files, or its part
/// of a store; `command` (the line that reproduces it) goes into the PNG or the store.
pub fn run<S: MapKernels + MapPicture>(job: &MapJob<S>, at: &super::Running) -> Result<MapSummary> {
    let (engine, monitor, command) = (at.engine, at.monitor, at.command.clone());
    job.spec.check_picture(&job.picture, job.colour_range)?;
    validate(&job.spec, &job.files, job.tile)?;
    validate_samples(&job.spec, job.samples, job.files.store().is_some())?;
    let started = Instant::now();
    let verdict = job.files.wants_verdict();
    let summary = |info: &RunInfo, counted: usize, nan: usize, pixels: usize| MapSummary {
        quantity: job.spec.quantity(),
        width: job.spec.grid().width,
        height: job.spec.grid().height,
        place: info.place().to_string(),
        seconds: started.elapsed().as_secs_f64(),
        counted: counted as f64 / pixels.max(1) as f64,
        nan,
        resolved: None,
        rule: String::new(),
        t_max: job.spec.stepping().t_max,
        mirrored: job.spec.mirrors() && job.spec.grid().point_symmetric(),
        range: None,
        output: job.files.output.clone(),
        files: job.files.files(),
        notices: Vec::new(),
    };
    if let Some(store) = job.files.store() {
        let made = make_store(
            &job.spec, engine, store, command, job.tile, verdict, monitor,
        )?;
        let filled = &made.made;
        return Ok(MapSummary {
            resolved: verdict.then(|| filled.resolved as f64 / filled.pixels.max(1) as f64),
            rule: made.rule,
            range: job.spec.ranged().then_some((f32::NAN, f32::NAN)),
            output: store.to_path_buf(),
            files: vec![store.to_path_buf()],
            notices: made.notices,
            ..summary(&made.info, filled.counted, filled.nan, filled.pixels)
        });
    }
    let made = compute(&job.spec, engine, verdict, job.samples, monitor)?;
    let (field, mask) = &made.made;
    let shown = mask.as_deref().filter(|_| job.files.show_unresolved);
    let drawn = job
        .spec
        .draw(field, &job.picture, job.colour_range, shown)?;
    let mut text = drawn.text;
    if shown.is_some() {
        text.push(("chaoscope:resolved-rule".into(), made.rule_in_full.clone()));
    }
    write_map(
        &drawn.picture,
        render::provenance(command, &made.info),
        text,
        &job.files,
        field,
        mask.as_deref(),
        monitor,
    )?;
    let counted = field.data.iter().filter(|&&x| job.spec.counted(x)).count();
    let nan = field.data.iter().filter(|x| x.is_nan()).count();
    Ok(MapSummary {
        resolved: mask.as_deref().map(verdict::fraction),
        rule: made.rule,
        range: drawn.range,
        notices: made.notices,
        ..summary(&made.info, counted, nan, field.data.len())
    })
}

/// A map made with, where asked, its verdict's mask (1 where a pixel is resolved).
pub type Judged = Made<(Field, Option<Vec<u8>>)>;

/// `spec`'s map (with `verdict`, its mask) in memory, as `run` makes it for a PNG or .npy:
/// `samples` x `samples` sub-samples a pixel when more than 1 ([`super::supersample`]).
/// Unchecked: [`run`] checks the job first, a library caller [`check_in_memory`].
pub fn compute<S: MapKernels>(
    spec: &S,
    engine: &Engine,
    verdict: bool,
    samples: u32,
    monitor: &Monitor,
) -> Result<Judged> {
    let plan = engine.plan(&computed_spec(spec, samples), verdict)?;
    compute_planned(spec, plan, engine, samples, monitor)
}

/// The map `spec`'s pixels are computed as: itself, or with `samples` x `samples` starts a
/// pixel.
pub fn computed_spec<S: MapSpec>(spec: &S, samples: u32) -> S {
    let g = spec.grid();
    spec.on_grid(Grid {
        width: g.width * samples,
        height: g.height * samples,
        ..*g
    })
}

/// [`compute`] of a map already planned on `engine` (its [`computed_spec`]'s plan), reduced
/// to `spec`'s pixels.
pub fn compute_planned<S: MapKernels>(
    spec: &S,
    plan: MapPlan<S>,
    engine: &Engine,
    samples: u32,
    monitor: &Monitor,
) -> Result<Judged> {
    let made = engine.planned_map(&plan, monitor)?;
    let made = Made::of(plan, made);
    if samples == 1 {
        return Ok(made);
    }
    let (field, mask) = &made.made;
    let reduced = super::supersample::reduce_map(spec.quantity(), field, mask.as_deref(), samples);
    Ok(Made {
        made: reduced,
        ..made
    })
}

/// What [`run`] checks of a map made in memory (no files): the spec, the verdict's step and
/// finer map, the sub-samples.
pub fn check_in_memory<S: MapSpec>(spec: &S, verdict: bool, samples: u32) -> Result<()> {
    spec.validate()?;
    check_verdict(spec, verdict)?;
    validate_samples(spec, samples, false)
}

/// Everything checked before any work: the spec, the files, the verdict's finer map, the tile.
/// `--samples`: within range, and for maps drawn whole (a store is filled band by band).
fn validate_samples<S: MapSpec>(spec: &S, samples: u32, store: bool) -> Result<()> {
    let max = super::supersample::MAX_SAMPLES;
    if !(1..=max).contains(&samples) {
        return Err(Error::invalid(
            "samples",
            format!("{} must be between 1 and {max}", samples),
        ));
    }
    if samples > 1 {
        if store {
            return Err(Error::invalid(
                "samples",
                "is for maps drawn whole (PNG, .npy); a .zarr store is filled band by band at one start a pixel",
            ));
        }
        let g = spec.grid();
        spec.on_grid(Grid {
            width: g.width.saturating_mul(samples),
            height: g.height.saturating_mul(samples),
            ..*g
        })
        .validate()
        .map_err(|e| match e {
            Error::InvalidSpec {
                field: "size",
                reason,
            } => Error::invalid(
                "samples",
                format!("{} x {} sub-samples a pixel: {reason}", samples, samples),
            ),
            e => e,
        })?;
    }
    Ok(())
}

pub fn validate(spec: &impl MapSpec, files: &MapOutputs, tile: Option<(u32, u32)>) -> Result<()> {
    match files.store() {
        // A store's run holds one band at a time: its memory is a band's, not the map's.
        Some(_) => {
            let g = spec.grid();
            let rows = crate::render::store::chunk_rows(g.width, g.height);
            spec.with_band((0, rows)).validate()?;
        }
        None => spec.validate()?,
    }
    files.validate()?;
    check_verdict(spec, files.wants_verdict())?;
    check_tile(tile, files)
}

/// A map as computed: its values, the verdict's mask, the path it took, the notices to give,
/// and the verdict's rule (in a few words and in full).
pub struct Made<T> {
    pub made: T,
    pub info: RunInfo,
    pub notices: Vec<String>,
    pub rule: String,
    pub rule_in_full: String,
}

impl<T> Made<T> {
    fn of<S>(plan: MapPlan<S>, made: T) -> Self {
        Made {
            made,
            info: plan.info,
            notices: plan.notices,
            rule: plan.rule,
            rule_in_full: plan.rule_in_full,
        }
    }
}

/// `spec`'s map into its Zarr store at `path` ([`fill_store`]): this task's part of it
/// (`tile`), band by band, with the verdict's mask when asked.
pub fn make_store<S: MapKernels>(
    spec: &S,
    engine: &Engine,
    path: &Path,
    command: String,
    tile: Option<(u32, u32)>,
    verdict: bool,
    monitor: &Monitor,
) -> Result<Made<Filled>> {
    let mut plan = engine.plan(spec, verdict)?;
    let quantity = spec.quantity();
    let backend = engine.asked();
    let fill = StoreFill {
        path,
        grid: *spec.grid(),
        command,
        tile,
        symmetric: spec.mirrors(),
        verdict,
        quantity: (quantity.name, quantity.unit),
        identity: serde_json::json!({ "map": spec.any(), "backend": backend.name() }),
    };
    let filled = fill_store(
        &fill,
        monitor,
        |rows, monitor| engine.planned_map(&plan.with_band(rows), monitor),
        |x| spec.counted(x),
    )?;
    plan.notices.extend(missing_note(&filled, path));
    Ok(Made::of(plan, filled))
}

/// Where a map's files go, and whether it carries the verdict ([`crate::verdict`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MapOutputs {
    /// The PNG.
    pub output: PathBuf,
    /// The raw values as float32 .npy, shape (height, width).
    pub data: Option<PathBuf>,
    /// The verdict as uint8 .npy, the layout of `data`: 1 resolved.
    pub resolved: Option<PathBuf>,
    /// Draw the pixels the verdict cannot resolve in grey.
    pub show_unresolved: bool,
}

impl MapOutputs {
    /// The Zarr store the map goes to (`data` ending in .zarr), if so.
    pub fn store(&self) -> Option<&Path> {
        self.data
            .as_deref()
            .filter(|p| p.extension().is_some_and(|e| e == "zarr"))
    }

    /// Every path the right kind and writable, before any work.
    pub fn validate(&self) -> Result<()> {
        if self.resolved.is_some() && self.resolved == self.data && self.store().is_none() {
            return Err(Error::invalid(
                "resolved",
                "is the [[data]] file: the mask would overwrite the map; give it its own .npy",
            ));
        }
        if let Some(store) = self.store() {
            if self.resolved.as_ref().is_some_and(|r| r != store) {
                return Err(Error::invalid(
                    "resolved",
                    "with a .zarr store the verdict goes into the store (its array `resolved`): give the store's path",
                ));
            }
            if self.show_unresolved {
                return Err(Error::invalid(
                    "show_unresolved",
                    "a .zarr store has no picture to paint (its verdict is the array `resolved`)",
                ));
            }
            // A store is a directory: a file (or device, FIFO) there is not one to open.
            if store.exists() && !store.is_dir() {
                return Err(Error::invalid(
                    "data",
                    format!(
                        "{} is not a directory, so not a Zarr store: give a new path or a store",
                        store.display()
                    ),
                ));
            }
            let parent = store.parent().filter(|p| !p.as_os_str().is_empty());
            return check_writable("data", &parent.unwrap_or(Path::new(".")).join(".probe"));
        }
        check_output("output", &self.output, "png")?;
        if let Some(data) = &self.data {
            check_output("data", data, "npy")?;
        }
        if let Some(path) = &self.resolved {
            check_output("resolved", path, "npy")?;
        }
        super::checks::check_distinct(&self.named(), &[])
    }

    /// Each file a run writes, with its field.
    pub fn named(&self) -> Vec<(&'static str, &Path)> {
        [
            Some(("output", self.output.as_path())),
            self.data.as_deref().map(|p| ("data", p)),
            self.resolved.as_deref().map(|p| ("resolved", p)),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// Whether the map is made a second time for the verdict.
    pub fn wants_verdict(&self) -> bool {
        self.resolved.is_some() || self.show_unresolved
    }

    /// The files a run writes.
    pub fn files(&self) -> Vec<PathBuf> {
        self.named()
            .into_iter()
            .map(|(_, p)| p.to_path_buf())
            .collect()
    }
}

/// `--tile INDEX/COUNT` only into a store, and in range.
pub fn check_tile(tile: Option<(u32, u32)>, files: &MapOutputs) -> Result<()> {
    if let Some((index, count)) = tile {
        if files.store().is_none() {
            return Err(Error::invalid(
                "tile",
                "needs a store to fill: [[data=MAP.zarr]]",
            ));
        }
        if count == 0 || index >= count {
            return Err(Error::invalid(
                "tile",
                format!("{index}/{count}: INDEX/COUNT with 0 <= INDEX < COUNT"),
            ));
        }
    }
    Ok(())
}

/// A map's files, as a set: the picture as PNG with its provenance, where the map sits in it
/// and `extra` text, the raw values as .npy and the verdict's `mask` as .npy when asked.
pub fn write_map(
    picture: &Picture,
    provenance: Vec<(String, String)>,
    extra: Vec<(String, String)>,
    to: &MapOutputs,
    field: &Field,
    mask: Option<&[u8]>,
    monitor: &Monitor,
) -> Result<()> {
    let mut meta = provenance;
    meta.extend(picture.metadata());
    meta.extend(extra);
    let mut files = Outputs::new();
    files.png(
        &to.output,
        picture.width,
        picture.height,
        &picture.rgb,
        &meta,
    )?;
    if let Some(data) = &to.data {
        files.npy(data, field)?;
    }
    if let (Some(path), Some(mask)) = (&to.resolved, mask) {
        files.mask(path, field.width, field.height, mask)?;
    }
    files.commit(monitor)
}
