//! The one path of every map, whichever quantity it measures: checked once, planned once on
//! the engine (with its verdict's finer map), computed with its verdict or filled into a store
//! band by band. `flip` and `lyapunov` are two front doors of it: they add their picture and
//! their summary.

use std::path::Path;

use super::store::{Filled, StoreFill, fill_store, missing_note};
use super::{MapOutputs, check_finer, check_tile, map_and_verdict, map_engine};
use crate::engine::{Backend, MapKernels, RunInfo};
use crate::error::Result;
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::MapSpec;
use crate::verdict;

/// Everything checked before any work: the spec, the files, the verdict's finer map, the tile.
pub fn validate(spec: &impl MapSpec, files: &MapOutputs, tile: Option<(u32, u32)>) -> Result<()> {
    spec.validate()?;
    files.validate()?;
    if files.wants_verdict() {
        check_finer(verdict::finer(spec, true).validate())?;
    }
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

/// `spec`'s map on `backend` and, with `verdict`, its mask.
pub fn make<S: MapKernels>(
    spec: &S,
    backend: Backend,
    verdict: bool,
    monitor: &Monitor,
) -> Result<Made<(Field, Option<Vec<u8>>)>> {
    let (engine, info, notices) = map_engine(backend, spec, verdict)?;
    let finer = verdict::finer(spec, engine.has_f64());
    let made = map_and_verdict(&engine, spec, verdict, monitor)?;
    Ok(Made {
        made,
        info,
        notices,
        rule: verdict::rule_short(spec, &finer),
        rule_in_full: verdict::rule(spec, &finer),
    })
}

/// `spec`'s map into its Zarr store at `path` ([`fill_store`]): this task's part of it
/// (`tile`), band by band, with the verdict's mask when asked.
pub fn make_store<S: MapKernels>(
    spec: &S,
    backend: Backend,
    path: &Path,
    command: String,
    tile: Option<(u32, u32)>,
    verdict: bool,
    monitor: &Monitor,
) -> Result<Made<Filled>> {
    let (engine, info, mut notices) = map_engine(backend, spec, verdict)?;
    let finer = verdict::finer(spec, engine.has_f64());
    let quantity = spec.quantity();
    let fill = StoreFill {
        path,
        grid: *spec.grid(),
        command,
        tile,
        symmetric: spec.mirrors(),
        verdict,
        quantity: (quantity.name, quantity.unit),
    };
    let filled = fill_store(
        &fill,
        monitor,
        |rows, monitor| map_and_verdict(&engine, &spec.with_band(rows), verdict, monitor),
        quantity.counted,
    )?;
    notices.extend(missing_note(&filled, path));
    Ok(Made {
        made: filled,
        info,
        notices,
        rule: verdict::rule_short(spec, &finer),
        rule_in_full: verdict::rule(spec, &finer),
    })
}
