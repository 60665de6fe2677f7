//! Zarr v3 stores of maps (written with zarrs), for maps larger than one machine: a group
//! holding the map as float32 (fill NaN = not computed yet) with dimension names (theta2,
//! theta1), the pixel-centre angles as coordinate arrays, and the provenance (the reproducing
//! command, the version) as attributes. Chunks are bands of whole rows, the GPU's tiles.
//!
//! Every file is written to a temporary name and renamed ([`AtomicStore`]), so independent
//! processes on different machines can fill one store without locking and a killed one
//! leaves no half-written chunk: a chunk file exists only once it is complete. The group's
//! own `zarr.json` is written last, so a store whose group exists is whole.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use zarrs::array::{Array, ArrayBuilder, ArrayError, ArraySubset, CodecOptions, data_type};
use zarrs::group::{Group, GroupBuilder};
use zarrs::storage::ReadableStorageTraits;

mod atomic;
mod fill;
mod identity;
mod sweep;
mod units;

pub use atomic::AtomicStore;
pub use fill::{Filled, StoreFill, fill_store, missing_note};
use identity::check_same;
pub use sweep::SweepStore;
pub use units::{Unit, pairs_mirrored, task_units, units};

use crate::error::{Error, Result};
use crate::field::Field;
use crate::spec::Grid;

/// Pixels a chunk holds at most (1 MiB of f32): small enough that a 2048-wide map has 16
/// chunks to share among tasks, large enough to keep a GPU busy.
const CHUNK_PIXELS: u64 = 1 << 18;

/// What a store holds, as its group's attributes say.
#[derive(Clone, Debug, PartialEq)]
pub struct StoreInfo {
    /// The command that makes the whole map (without `--tile` and output paths).
    pub command: String,
    pub version: String,
    /// The number of tasks the store was first made for (`--tile I/N`); status counts in it.
    pub tiles: u32,
    /// Whether mirrored chunks are computed together (see [`units`]).
    pub mirrored: bool,
    /// Whether the store holds the verdict as the array `resolved` (uint8: 1 resolved, 0
    /// not, 255 not computed yet).
    pub resolved: bool,
    /// What the store holds, as data (JSON: the map's spec and the backend asked for): its
    /// identity, compared field by field with a task's before it adds to it; `render` and
    /// `serve --store` read the map from it, never from the command (which may name files).
    pub identity: serde_json::Value,
}

/// A map's store: its group, the map array, the grid.
pub struct MapStore {
    path: PathBuf,
    store: Arc<AtomicStore>,
    map: Array<AtomicStore>,
    resolved: Option<Array<AtomicStore>>,
    pub info: StoreInfo,
    pub width: u32,
    pub height: u32,
    pub chunk_rows: u32,
}

/// Rows of a chunk of a map `width` pixels wide and `height` high.
pub fn chunk_rows(width: u32, height: u32) -> u32 {
    (CHUNK_PIXELS / width as u64).clamp(1, height as u64) as u32
}

/// Rows of a chunk along dimension `rows` (the first chunk's, which every chunk but a
/// shorter last one shares).
fn first_chunk_rows(array: &Array<AtomicStore>, rows: usize) -> Result<u32, ArrayError> {
    let origin = vec![0; array.dimensionality()];
    Ok(array.chunk_shape(&origin)?[rows].get() as u32)
}

/// The verdict array's fill value: a pixel not computed yet.
pub const NOT_COMPUTED: u8 = 255;

/// `values` followed by `fill` up to `len`: an edge chunk's data at the chunk's full shape.
fn padded<T: Copy>(values: &[T], len: usize, fill: T) -> Vec<T> {
    let mut out = values.to_vec();
    out.resize(len.max(values.len()), fill);
    out
}

/// The layout chaoscope writes, checked before any work: the array `name` 2-D (at most
/// 65536 a side), of `data_type`, in chunks of whole rows as [`chunk_rows`] makes them, little
/// endian, checksummed; `shape` its map's (height, width) where given. A mismatch is an error
/// naming the metadata field: a store's metadata may come from anywhere.
fn check_layout(
    path: &Path,
    name: &str,
    array: &Array<AtomicStore>,
    data_type: &str,
    shape: Option<(u32, u32)>,
) -> Result<(u32, u32)> {
    let wrong = |field: &str, what: String| {
        Error::Format(format!(
            "{}: the array `{name}` has {field} {what}: its metadata is not a chaoscope map's; start a new store",
            path.display()
        ))
    };
    let meta = serde_json::to_value(array.metadata()).unwrap_or_default();
    let dims: Vec<u64> = array.shape().to_vec();
    let side = 1..=(1u64 << 16);
    if dims.len() != 2 || !dims.iter().all(|d| side.contains(d)) {
        return Err(wrong(
            "shape",
            format!("{dims:?} (a map is 2-D, 1 to 65536 a side)"),
        ));
    }
    let (height, width) = (dims[0] as u32, dims[1] as u32);
    if let Some(expected) = shape
        && expected != (height, width)
    {
        return Err(wrong(
            "shape",
            format!("{dims:?}, not the map's {expected:?}"),
        ));
    }
    if meta["data_type"] != data_type {
        return Err(wrong(
            "data_type",
            format!("{} (not {data_type})", meta["data_type"]),
        ));
    }
    // A chunk not written reads as the fill value: NaN ("not computed"), never a number.
    if data_type == "float32" && meta["fill_value"] != "NaN" {
        return Err(wrong(
            "fill_value",
            format!("{} (not \"NaN\")", meta["fill_value"]),
        ));
    }
    let chunk = &meta["chunk_grid"]["configuration"]["chunk_shape"];
    let rows = chunk_rows(width, height) as u64;
    if *chunk != serde_json::json!([rows, width]) {
        return Err(wrong(
            "chunk_shape",
            format!("{chunk}, not [{rows}, {width}]"),
        ));
    }
    // A codec is named by a string or by its "name" (with a configuration).
    let codecs = &meta["codecs"];
    let named = |c: &serde_json::Value, name: &str| c == name || c["name"] == name;
    let endian = &codecs[0]["configuration"]["endian"];
    if !named(&codecs[0], "bytes") || !(endian.is_null() || *endian == "little") {
        return Err(wrong(
            "codecs",
            format!("{codecs} (bytes must be little endian)"),
        ));
    }
    if codecs
        .as_array()
        .is_none_or(|c| !c.iter().any(|c| named(c, "crc32c")))
    {
        return Err(wrong(
            "codecs",
            format!("{codecs}, without the crc32c checksum"),
        ));
    }
    Ok((height, width))
}

/// The checksum every chunk carries (Zarr v3's `crc32c` codec, which zarr-python reads), so
/// a damaged chunk does not decode instead of reading as numbers.
fn checksummed() -> Vec<Arc<dyn zarrs::array::BytesToBytesCodecTraits>> {
    vec![Arc::new(
        zarrs::array::codec::bytes_to_bytes::crc32c::Crc32cCodec::new(),
    )]
}

fn store_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::format(path, e)
}

impl MapStore {
    /// Opens the store at `path` made by `command`, or makes it (metadata only) for `grid`:
    /// the map array (`units`: its values' unit, `name`: what they are), the coordinates and
    /// the group. A store made by another command or version is refused, naming the flags
    /// that differ (as `field`).
    pub fn create_or_open(
        field: &'static str,
        path: &Path,
        grid: &Grid,
        info: &StoreInfo,
        (name, units): (&str, &str),
    ) -> Result<Self> {
        if path.join("zarr.json").is_file() {
            let store = Self::open(path)?;
            check_same(field, path, &store.info, info)?;
            if store.info.mirrored != info.mirrored {
                return Err(Error::invalid(
                    field,
                    format!(
                        "{} says chaoscope:mirrored {}, but its map's mirrored chunks are {}: its metadata was changed; start a new store",
                        path.display(),
                        store.info.mirrored,
                        if info.mirrored {
                            "paired"
                        } else {
                            "not paired"
                        }
                    ),
                ));
            }
            if (store.width, store.height) != (grid.width, grid.height) {
                return Err(Error::invalid(
                    field,
                    format!(
                        "{} holds a {}x{} map, not this run's {}x{}",
                        path.display(),
                        store.width,
                        store.height,
                        grid.width,
                        grid.height
                    ),
                ));
            }
            return Ok(store);
        }
        let store = Arc::new(AtomicStore::new(path)?);
        let err = |e: &dyn std::fmt::Display| store_error(path, e);
        let (w, h) = (grid.width as u64, grid.height as u64);
        let rows = chunk_rows(grid.width, grid.height) as u64;
        write_axes(&store, path, grid)?;
        let mut attributes = serde_json::Map::new();
        attributes.insert("units".into(), units.into());
        attributes.insert("long_name".into(), name.into());
        let map = ArrayBuilder::new(vec![h, w], vec![rows, w], data_type::float32(), f32::NAN)
            .dimension_names(dims(grid).into())
            .attributes(attributes)
            .bytes_to_bytes_codecs(checksummed())
            .build(store.clone(), "/map")
            .map_err(|e| err(&e))?;
        map.store_metadata().map_err(|e| err(&e))?;
        if info.resolved {
            let mut attributes = serde_json::Map::new();
            attributes.insert(
                "long_name".into(),
                "1 where the pixel is resolved, 0 where not, 255 not computed yet".into(),
            );
            let mask =
                ArrayBuilder::new(vec![h, w], vec![rows, w], data_type::uint8(), NOT_COMPUTED)
                    .dimension_names(dims(grid).into())
                    .attributes(attributes)
                    .bytes_to_bytes_codecs(checksummed())
                    .build(store.clone(), "/resolved")
                    .map_err(|e| err(&e))?;
            mask.store_metadata().map_err(|e| err(&e))?;
        }
        let mut attributes = serde_json::Map::new();
        attributes.insert("chaoscope:command".into(), info.command.clone().into());
        attributes.insert("chaoscope:version".into(), info.version.clone().into());
        attributes.insert("chaoscope:tiles".into(), info.tiles.into());
        attributes.insert("chaoscope:mirrored".into(), info.mirrored.into());
        attributes.insert("chaoscope:resolved".into(), info.resolved.into());
        attributes.insert("chaoscope:identity".into(), info.identity.clone());
        write_group(&store, path, attributes)?;
        Self::open(path)
    }

    /// Opens an existing store.
    pub fn open(path: &Path) -> Result<Self> {
        if !path.join("zarr.json").is_file() {
            return Err(Error::File {
                path: path.to_path_buf(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "no Zarr store here (no zarr.json)",
                ),
            });
        }
        let store = Arc::new(AtomicStore::new(path)?);
        let err = |e: &dyn std::fmt::Display| store_error(path, e);
        let group = Group::open(store.clone(), "/").map_err(|e| err(&e))?;
        let a = group.attributes();
        let text = |key: &str| a.get(key).and_then(|v| v.as_str()).map(str::to_string);
        let info = StoreInfo {
            command: text("chaoscope:command")
                .ok_or_else(|| err(&"not a chaoscope store (no chaoscope:command)"))?,
            version: text("chaoscope:version").unwrap_or_default(),
            tiles: a
                .get("chaoscope:tiles")
                .and_then(|v| v.as_u64())
                .unwrap_or(1) as u32,
            mirrored: a
                .get("chaoscope:mirrored")
                .and_then(|v| v.as_bool())
                .unwrap_or(false),
            resolved: a
                .get("chaoscope:resolved")
                .and_then(|v| v.as_bool())
                .unwrap_or(false),
            identity: a.get("chaoscope:identity").cloned().unwrap_or_default(),
        };
        let map = Array::open(store.clone(), "/map").map_err(|e| err(&e))?;
        let resolved = match info.resolved {
            true => Some(Array::open(store.clone(), "/resolved").map_err(|e| err(&e))?),
            false => None,
        };
        let (height, width) = check_layout(path, "map", &map, "float32", None)?;
        if let Some(r) = &resolved {
            check_layout(path, "resolved", r, "uint8", Some((height, width)))?;
        }
        Ok(MapStore {
            path: path.to_path_buf(),
            chunk_rows: first_chunk_rows(&map, 0).map_err(|e| err(&e))?,
            store,
            info,
            width,
            height,
            map,
            resolved,
        })
    }

    /// Where the store is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn chunks(&self) -> u32 {
        self.height.div_ceil(self.chunk_rows)
    }

    /// (first row, rows) of chunk `c`.
    pub fn chunk_span(&self, c: u32) -> (u32, u32) {
        let first = c * self.chunk_rows;
        (first, self.chunk_rows.min(self.height - first))
    }

    /// Whether chunk `c` is written: its files exist (they are complete when written by
    /// chaoscope) and decode, checksum and size, the verdict's too where the store holds one.
    /// A truncated, empty, oversized, garbled chunk, or a directory in its place, is not
    /// written: `status` lists it, a resume rewrites it.
    pub fn is_written(&self, c: u32) -> Result<bool> {
        let at = [c as u64, 0];
        for array in std::iter::once(&self.map).chain(&self.resolved) {
            let key = array.chunk_key(&at);
            match self.store.size_key(&key) {
                Ok(Some(_)) => {}
                Ok(None) | Err(_) => return Ok(false),
            }
        }
        let decodes = self.map.retrieve_chunk::<Vec<f32>>(&at).is_ok()
            && self
                .resolved
                .as_ref()
                .is_none_or(|r| r.retrieve_chunk::<Vec<u8>>(&at).is_ok());
        Ok(decodes)
    }

    /// The error for rows `first..first + rows` that do not read: the first damaged chunk
    /// among them, named with its rows (`status` gives the `--tile` that rewrites it).
    fn damaged(&self, first: u32, rows: u32, e: impl std::fmt::Display) -> Error {
        let chunks = first / self.chunk_rows..(first + rows).div_ceil(self.chunk_rows);
        match chunks
            .clone()
            .find(|&c| !self.is_written(c).unwrap_or(false))
        {
            Some(c) => {
                let (a, n) = self.chunk_span(c);
                Error::Format(format!(
                    "{}: chunk {c} (rows {a}..{}) is damaged ({e}): run `chaoscope status` on the store and the [[tile]] task it names again",
                    self.path.display(),
                    a + n
                ))
            }
            None => store_error(&self.path, e),
        }
    }

    /// The chunks not written yet.
    pub fn missing(&self) -> Result<Vec<u32>> {
        let mut out = Vec::new();
        for c in 0..self.chunks() {
            if !self.is_written(c)? {
                out.push(c);
            }
        }
        Ok(out)
    }

    /// Writes chunk `c` of `array` (its rows, row-major); the last chunk, when shorter,
    /// padded with the array's `fill` to the chunk's shape (Zarr's edge chunks are whole).
    fn write_chunk<T: zarrs::array::Element + Copy>(
        &self,
        array: &Array<AtomicStore>,
        c: u32,
        values: &[T],
        fill: T,
    ) -> Result<()> {
        // Every chunk gets its file, even one that happens to be all fill value (NaN:
        // blown-up runs), so that "written" always means "computed".
        let options = CodecOptions::default().with_store_empty_chunks(true);
        let whole = (self.chunk_rows * self.width) as usize;
        array
            .store_chunk_opt(&[c as u64, 0], padded(values, whole, fill), &options)
            .map_err(|e| store_error(&self.path, e))
    }

    /// Writes a unit's band: `field` holds chunk `unit.chunk`'s rows (and `mask` its verdict,
    /// where the store holds one); their mirror images, the same values in reverse order, go
    /// to `unit.mirror`. The verdict first: a chunk of the map marks the unit done.
    pub fn write_unit(&self, unit: Unit, field: &Field, mask: Option<&[u8]>) -> Result<()> {
        let chunks = std::iter::once(unit.chunk).chain(unit.mirror);
        if let (Some(array), Some(mask)) = (&self.resolved, mask) {
            for (k, c) in chunks.clone().enumerate() {
                let values: Vec<u8> = match k {
                    0 => mask.to_vec(),
                    _ => mask.iter().rev().copied().collect(),
                };
                self.write_chunk(array, c, &values, NOT_COMPUTED)?;
            }
        }
        for (k, c) in chunks.enumerate() {
            let values: Vec<f32> = match k {
                0 => field.data.clone(),
                _ => field.data.iter().rev().copied().collect(),
            };
            self.write_chunk(&self.map, c, &values, f32::NAN)?;
        }
        Ok(())
    }

    /// Rows `first..first + rows` of the verdict, if the store holds one.
    pub fn read_resolved(&self, first: u32, rows: u32) -> Result<Option<Vec<u8>>> {
        let Some(array) = &self.resolved else {
            return Ok(None);
        };
        let subset = ArraySubset::new_with_ranges(&[
            first as u64..(first + rows) as u64,
            0..self.width as u64,
        ]);
        array
            .retrieve_array_subset::<Vec<u8>>(&subset)
            .map(Some)
            .map_err(|e| self.damaged(first, rows, e))
    }

    /// Rows `first..first + rows` of the map (NaN where not written).
    pub fn read_rows(&self, first: u32, rows: u32) -> Result<Vec<f32>> {
        let subset = ArraySubset::new_with_ranges(&[
            first as u64..(first + rows) as u64,
            0..self.width as u64,
        ]);
        self.map
            .retrieve_array_subset::<Vec<f32>>(&subset)
            .map_err(|e| self.damaged(first, rows, e))
    }
}

/// A 1-D f64 coordinate array `/name` along dimension `dim`, written whole.
fn write_coordinate(
    store: &Arc<AtomicStore>,
    path: &Path,
    (name, dim): (&str, &str),
    values: &[f64],
    attributes: serde_json::Map<String, serde_json::Value>,
) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| store_error(path, e);
    let n = values.len() as u64;
    let array = ArrayBuilder::new(vec![n], vec![n], data_type::float64(), f64::NAN)
        .dimension_names([dim].into())
        .attributes(attributes)
        .build(store.clone(), &format!("/{name}"))
        .map_err(|e| err(&e))?;
    array.store_metadata().map_err(|e| err(&e))?;
    array.store_chunk(&[0], values).map_err(|e| err(&e))
}

/// A map's dimension names, (y, x): its axes' names as arrays ([`crate::spec::Var::key`]).
pub(crate) fn dims(grid: &Grid) -> [&'static str; 2] {
    [grid.y.var.key(), grid.x.var.key()]
}

/// The coordinates of `grid`'s pixel centres along its axes, named by what they vary
/// (`theta1` and `theta2` for today's plane), with their units.
fn write_axes(store: &Arc<AtomicStore>, path: &Path, grid: &Grid) -> Result<()> {
    for (axis, values) in [
        (
            grid.x,
            (0..grid.width).map(|c| grid.x_at(c)).collect::<Vec<f64>>(),
        ),
        (grid.y, (0..grid.height).map(|r| grid.y_at(r)).collect()),
    ] {
        let mut attributes = serde_json::Map::new();
        attributes.insert("units".into(), axis.var.unit().into());
        attributes.insert(
            "long_name".into(),
            format!("{} at the pixel centres", axis.var.name()).into(),
        );
        let key = axis.var.key();
        write_coordinate(store, path, (key, key), &values, attributes)?;
    }
    Ok(())
}

/// The root group with `attributes`: written last, it marks the store whole.
fn write_group(
    store: &Arc<AtomicStore>,
    path: &Path,
    attributes: serde_json::Map<String, serde_json::Value>,
) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| store_error(path, e);
    GroupBuilder::new()
        .attributes(attributes)
        .build(store.clone(), "/")
        .map_err(|e| err(&e))?
        .store_metadata()
        .map_err(|e| err(&e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_pair_mirrored_chunks_and_tasks_share_them() {
        let u = units(10, 2, true);
        assert_eq!(u.len(), 3);
        assert_eq!(
            u[0],
            Unit {
                chunk: 0,
                mirror: Some(4)
            }
        );
        assert_eq!(
            u[2],
            Unit {
                chunk: 2,
                mirror: None
            }
        );
        assert_eq!(units(5, 2, false).len(), 3);
        // Every unit exactly once over the tasks.
        let all = units(64, 1, true);
        let mut seen: Vec<Unit> = (0..3).flat_map(|i| task_units(&all, i, 3)).collect();
        seen.sort_by_key(|u| u.chunk);
        assert_eq!(seen, all);
    }
}
