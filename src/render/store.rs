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
use std::sync::atomic::{AtomicU64, Ordering};

use zarrs::array::{Array, ArrayBuilder, ArrayError, ArraySubset, CodecOptions, data_type};
use zarrs::filesystem::FilesystemStore;
use zarrs::group::{Group, GroupBuilder};
use zarrs::storage::{
    Bytes, ListableStorageTraits, MaybeBytesIterator, OffsetBytesIterator, ReadableStorageTraits,
    StorageError, StoreKey, StoreKeys, StoreKeysPrefixes, StorePrefix, WritableStorageTraits,
    byte_range::ByteRangeIterator,
};

use crate::error::{Error, Result};
use crate::field::Field;
use crate::spec::Grid;

/// Pixels a chunk holds at most (1 MiB of f32): small enough that a 2048-wide map has 16
/// chunks to share among tasks, large enough to keep a GPU busy.
const CHUNK_PIXELS: u64 = 1 << 18;

/// The filesystem store, but every `set` goes to a temporary file renamed into place.
pub struct AtomicStore {
    inner: FilesystemStore,
    root: PathBuf,
}

static TEMPORARY: AtomicU64 = AtomicU64::new(0);

impl AtomicStore {
    fn new(root: &Path) -> Result<Self> {
        std::fs::create_dir_all(root).map_err(|source| Error::File {
            path: root.to_path_buf(),
            source,
        })?;
        let inner = FilesystemStore::new(root).map_err(|e| Error::format(root, e))?;
        Ok(AtomicStore {
            inner,
            root: root.to_path_buf(),
        })
    }
}

impl ReadableStorageTraits for AtomicStore {
    fn get_partial_many<'a>(
        &'a self,
        key: &StoreKey,
        byte_ranges: ByteRangeIterator<'a>,
    ) -> std::result::Result<MaybeBytesIterator<'a>, StorageError> {
        self.inner.get_partial_many(key, byte_ranges)
    }

    fn size_key(&self, key: &StoreKey) -> std::result::Result<Option<u64>, StorageError> {
        self.inner.size_key(key)
    }

    fn supports_get_partial(&self) -> bool {
        self.inner.supports_get_partial()
    }
}

impl WritableStorageTraits for AtomicStore {
    fn set(&self, key: &StoreKey, value: Bytes) -> std::result::Result<(), StorageError> {
        let path = self.root.join(key.as_str());
        let dir = path.parent().unwrap_or(&self.root);
        std::fs::create_dir_all(dir)?;
        // Unique per process and write: two tasks writing the same chunk at once each
        // rename a whole file of their own (the same values), the last one stays.
        let name = format!(
            ".{}.tmp-{}-{}",
            path.file_name().and_then(|n| n.to_str()).unwrap_or("chunk"),
            std::process::id(),
            TEMPORARY.fetch_add(1, Ordering::Relaxed)
        );
        let temporary = dir.join(name);
        let written =
            std::fs::write(&temporary, &value).and_then(|()| std::fs::rename(&temporary, &path));
        if written.is_err() {
            std::fs::remove_file(&temporary).ok();
        }
        Ok(written?)
    }

    fn set_partial_many(
        &self,
        _key: &StoreKey,
        _offset_values: OffsetBytesIterator,
    ) -> std::result::Result<(), StorageError> {
        Err(StorageError::Unsupported(
            "partial writes (every chunk is written whole)".into(),
        ))
    }

    fn erase(&self, key: &StoreKey) -> std::result::Result<(), StorageError> {
        self.inner.erase(key)
    }

    fn erase_prefix(&self, prefix: &StorePrefix) -> std::result::Result<(), StorageError> {
        self.inner.erase_prefix(prefix)
    }

    fn supports_set_partial(&self) -> bool {
        false
    }
}

impl ListableStorageTraits for AtomicStore {
    fn list(&self) -> std::result::Result<StoreKeys, StorageError> {
        self.inner.list()
    }

    fn list_prefix(&self, prefix: &StorePrefix) -> std::result::Result<StoreKeys, StorageError> {
        self.inner.list_prefix(prefix)
    }

    fn list_dir(
        &self,
        prefix: &StorePrefix,
    ) -> std::result::Result<StoreKeysPrefixes, StorageError> {
        self.inner.list_dir(prefix)
    }

    fn size_prefix(&self, prefix: &StorePrefix) -> std::result::Result<u64, StorageError> {
        self.inner.size_prefix(prefix)
    }
}

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

fn store_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::format(path, e)
}

/// Bands of whole chunks computed together: a chunk, or a chunk and its mirror image through
/// the map's centre (computed once and written twice, as a whole map mirrors its top half).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Unit {
    pub chunk: u32,
    pub mirror: Option<u32>,
}

/// The units of a map of `height` rows in chunks of `chunk_rows` (the last may be shorter);
/// with `mirrored`, chunk c pairs with chunk C - 1 - c (then `height` is a multiple of
/// `chunk_rows`, so the pairs are exact images). Task `i` of `n` takes units i, i + n, ...
pub fn units(height: u32, chunk_rows: u32, mirrored: bool) -> Vec<Unit> {
    let chunks = height.div_ceil(chunk_rows);
    if !mirrored {
        return (0..chunks)
            .map(|chunk| Unit {
                chunk,
                mirror: None,
            })
            .collect();
    }
    (0..chunks.div_ceil(2))
        .map(|chunk| {
            let other = chunks - 1 - chunk;
            Unit {
                chunk,
                mirror: (other != chunk).then_some(other),
            }
        })
        .collect()
}

/// Whether the map of `grid` pairs mirrored chunks (a point-symmetric grid integrated with
/// its symmetry, in whole pairs of chunks).
pub fn pairs_mirrored(grid: &Grid, use_symmetry: bool) -> bool {
    use_symmetry
        && grid.point_symmetric()
        && grid
            .height
            .is_multiple_of(chunk_rows(grid.width, grid.height))
}

/// The units of task `index` of `tasks`, in an order spread over the map (bit-reversed), so
/// that the first units done foretell the rest's cost for the progress estimate.
pub fn task_units(all: &[Unit], index: u32, tasks: u32) -> Vec<Unit> {
    let mine: Vec<Unit> = all
        .iter()
        .copied()
        .skip(index as usize)
        .step_by(tasks as usize)
        .collect();
    let bits = mine.len().next_power_of_two().trailing_zeros();
    if bits == 0 {
        return mine;
    }
    let mut order: Vec<usize> = (0..mine.len()).collect();
    order.sort_by_key(|&k| k.reverse_bits() >> (usize::BITS - bits));
    order.into_iter().map(|k| mine[k]).collect()
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
            if (store.width, store.height) != (grid.width, grid.height) {
                return Err(Error::invalid(
                    field,
                    format!(
                        "{} holds a {}x{} map",
                        path.display(),
                        store.width,
                        store.height
                    ),
                ));
            }
            return Ok(store);
        }
        let store = Arc::new(AtomicStore::new(path)?);
        let err = |e: &dyn std::fmt::Display| store_error(path, e);
        let (w, h) = (grid.width as u64, grid.height as u64);
        let rows = chunk_rows(grid.width, grid.height) as u64;
        write_angles(&store, path, grid)?;
        let mut attributes = serde_json::Map::new();
        attributes.insert("units".into(), units.into());
        attributes.insert("long_name".into(), name.into());
        let map = ArrayBuilder::new(vec![h, w], vec![rows, w], data_type::float32(), f32::NAN)
            .dimension_names(["theta2", "theta1"].into())
            .attributes(attributes)
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
                    .dimension_names(["theta2", "theta1"].into())
                    .attributes(attributes)
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
        };
        let map = Array::open(store.clone(), "/map").map_err(|e| err(&e))?;
        let resolved = match info.resolved {
            true => Some(Array::open(store.clone(), "/resolved").map_err(|e| err(&e))?),
            false => None,
        };
        let shape = map.shape().to_vec();
        let (height, width) = (shape[0] as u32, shape[1] as u32);
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

    pub fn chunks(&self) -> u32 {
        self.height.div_ceil(self.chunk_rows)
    }

    /// (first row, rows) of chunk `c`.
    pub fn chunk_span(&self, c: u32) -> (u32, u32) {
        let first = c * self.chunk_rows;
        (first, self.chunk_rows.min(self.height - first))
    }

    /// Whether chunk `c` is written (its files exist: they are complete), the verdict's too
    /// where the store holds one.
    pub fn is_written(&self, c: u32) -> Result<bool> {
        for array in std::iter::once(&self.map).chain(&self.resolved) {
            let key = array.chunk_key(&[c as u64, 0]);
            let there = self
                .store
                .size_key(&key)
                .map_err(|e| store_error(&self.path, e))?
                .is_some();
            if !there {
                return Ok(false);
            }
        }
        Ok(true)
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
            .map_err(|e| store_error(&self.path, e))
    }

    /// Rows `first..first + rows` of the map (NaN where not written).
    pub fn read_rows(&self, first: u32, rows: u32) -> Result<Vec<f32>> {
        let subset = ArraySubset::new_with_ranges(&[
            first as u64..(first + rows) as u64,
            0..self.width as u64,
        ]);
        self.map
            .retrieve_array_subset::<Vec<f32>>(&subset)
            .map_err(|e| store_error(&self.path, e))
    }
}

/// A sweep's store: the maps of its frames as one 3-D array `map` (frame, theta2, theta1),
/// chunks of one frame's row band, the varied parameter as the coordinate array of the frame
/// dimension (named after it), the angles as for a single map.
pub struct SweepStore {
    path: PathBuf,
    store: Arc<AtomicStore>,
    map: Array<AtomicStore>,
    width: u32,
    height: u32,
    chunk_rows: u32,
}

impl SweepStore {
    /// Opens the sweep store at `path` made by `info.command`, or makes it: `frames` frames of
    /// maps over `grid`, `param` (its name, unit, and value per frame), the map's (name, unit).
    pub fn create_or_open(
        path: &Path,
        grid: &Grid,
        info: &StoreInfo,
        param: (&str, &str, &[f64]),
        (name, units): (&str, &str),
    ) -> Result<Self> {
        let err = |e: &dyn std::fmt::Display| store_error(path, e);
        if path.join("zarr.json").is_file() {
            let store = Arc::new(AtomicStore::new(path)?);
            let group = Group::open(store.clone(), "/").map_err(|e| err(&e))?;
            let a = group.attributes();
            let text = |key: &str| a.get(key).and_then(|v| v.as_str()).map(str::to_string);
            let theirs = StoreInfo {
                command: text("chaoscope:command").unwrap_or_default(),
                version: text("chaoscope:version").unwrap_or_default(),
                ..info.clone()
            };
            check_same("data", path, &theirs, info)?;
            return Self::open(path, store);
        }
        let store = Arc::new(AtomicStore::new(path)?);
        let (w, h, f) = (grid.width as u64, grid.height as u64, param.2.len() as u64);
        let rows = chunk_rows(grid.width, grid.height) as u64;
        let (param_name, param_units, values) = param;
        // An array name may not hold a slash: m2/m1 is stored as m2_over_m1.
        let param_array = param_name.replace('/', "_over_");
        write_angles(&store, path, grid)?;
        let mut attributes = serde_json::Map::new();
        attributes.insert("units".into(), param_units.into());
        write_coordinate(&store, path, (&param_array, "frame"), values, attributes)?;
        let mut attributes = serde_json::Map::new();
        attributes.insert("units".into(), units.into());
        attributes.insert("long_name".into(), name.into());
        // CF's way of naming a non-dimension coordinate (xarray reads it so).
        attributes.insert("coordinates".into(), param_array.clone().into());
        let map = ArrayBuilder::new(
            vec![f, h, w],
            vec![1, rows, w],
            data_type::float32(),
            f32::NAN,
        )
        .dimension_names(["frame", "theta2", "theta1"].into())
        .attributes(attributes)
        .build(store.clone(), "/map")
        .map_err(|e| err(&e))?;
        map.store_metadata().map_err(|e| err(&e))?;
        let mut attributes = serde_json::Map::new();
        attributes.insert("chaoscope:command".into(), info.command.clone().into());
        attributes.insert("chaoscope:version".into(), info.version.clone().into());
        attributes.insert("chaoscope:varied".into(), param_name.into());
        write_group(&store, path, attributes)?;
        Self::open(path, store)
    }

    fn open(path: &Path, store: Arc<AtomicStore>) -> Result<Self> {
        let map = Array::open(store.clone(), "/map").map_err(|e| store_error(path, e))?;
        let shape = map.shape().to_vec();
        Ok(SweepStore {
            path: path.to_path_buf(),
            chunk_rows: first_chunk_rows(&map, 1).map_err(|e| store_error(path, e))?,
            store,
            width: shape[2] as u32,
            height: shape[1] as u32,
            map,
        })
    }

    fn chunks(&self) -> u32 {
        self.height.div_ceil(self.chunk_rows)
    }

    /// Whether every chunk of frame `k` is written.
    pub fn has_frame(&self, k: u32) -> Result<bool> {
        for c in 0..self.chunks() {
            let key = self.map.chunk_key(&[k as u64, c as u64, 0]);
            let there = self
                .store
                .size_key(&key)
                .map_err(|e| store_error(&self.path, e))?;
            if there.is_none() {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Frame `k`'s map (NaN where not written).
    pub fn read_frame(&self, k: u32) -> Result<Vec<f32>> {
        let subset = ArraySubset::new_with_ranges(&[
            k as u64..k as u64 + 1,
            0..self.height as u64,
            0..self.width as u64,
        ]);
        self.map
            .retrieve_array_subset::<Vec<f32>>(&subset)
            .map_err(|e| store_error(&self.path, e))
    }

    /// Opens an existing sweep store.
    pub fn open_existing(path: &Path) -> Result<Self> {
        Self::open(path, Arc::new(AtomicStore::new(path)?))
    }

    /// Writes frame `k`'s map.
    pub fn write_frame(&self, k: u32, field: &Field) -> Result<()> {
        let options = CodecOptions::default().with_store_empty_chunks(true);
        let band = (self.chunk_rows * self.width) as usize;
        for (c, values) in field.data.chunks(band).enumerate() {
            self.map
                .store_chunk_opt(
                    &[k as u64, c as u64, 0],
                    padded(values, band, f32::NAN),
                    &options,
                )
                .map_err(|e| store_error(&self.path, e))?;
        }
        Ok(())
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

/// The angle coordinates of `grid`'s pixel centres, `theta1` and `theta2`.
fn write_angles(store: &Arc<AtomicStore>, path: &Path, grid: &Grid) -> Result<()> {
    for (axis, values) in [
        (
            "theta1",
            (0..grid.width)
                .map(|c| grid.theta1_at(c))
                .collect::<Vec<f64>>(),
        ),
        (
            "theta2",
            (0..grid.height).map(|r| grid.theta2_at(r)).collect(),
        ),
    ] {
        let mut attributes = serde_json::Map::new();
        attributes.insert("units".into(), "rad".into());
        attributes.insert(
            "long_name".into(),
            format!("{axis} at the pixel centres").into(),
        );
        write_coordinate(store, path, (axis, axis), &values, attributes)?;
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

/// `theirs` (a store's) and `ours` made by the same command and version, else an error naming
/// `field` and what differs.
fn check_same(
    field: &'static str,
    path: &Path,
    theirs: &StoreInfo,
    ours: &StoreInfo,
) -> Result<()> {
    if theirs.version != ours.version {
        return Err(Error::invalid(
            field,
            format!(
                "{} was made by chaoscope {}, this is {}: start a new store",
                path.display(),
                theirs.version,
                ours.version
            ),
        ));
    }
    if theirs.resolved != ours.resolved {
        return Err(Error::invalid(
            field,
            format!(
                "{} was made {} the verdict (--resolved): ask for it {}",
                path.display(),
                if theirs.resolved { "with" } else { "without" },
                if theirs.resolved {
                    "too"
                } else {
                    "in a new store"
                }
            ),
        ));
    }
    if theirs.command != ours.command {
        let flags = |c: &str| -> Vec<String> {
            let words: Vec<&str> = c.split_whitespace().collect();
            let mut out = Vec::new();
            let mut k = 0;
            while k < words.len() {
                if words[k].starts_with("--") {
                    let mut flag = words[k].to_string();
                    while k + 1 < words.len() && !words[k + 1].starts_with("--") {
                        k += 1;
                        flag = format!("{flag} {}", words[k]);
                    }
                    out.push(flag);
                } else {
                    out.push(words[k].to_string());
                }
                k += 1;
            }
            out
        };
        let (a, b) = (flags(&theirs.command), flags(&ours.command));
        let only = |x: &[String], y: &[String]| {
            x.iter()
                .filter(|f| !y.contains(f))
                .cloned()
                .collect::<Vec<_>>()
                .join(" ")
        };
        return Err(Error::invalid(
            field,
            format!(
                "{} was made by another command: it has `{}` where this one has `{}` (its command: {})",
                path.display(),
                only(&a, &b),
                only(&b, &a),
                theirs.command
            ),
        ));
    }
    Ok(())
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
