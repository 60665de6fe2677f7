//! [`SweepStore`]: a sweep's frames as one 3-D array.

use super::atomic::AtomicStore;
use super::identity::check_same;
use super::{
    StoreInfo, checksummed, chunk_rows, first_chunk_rows, padded, store_error, write_axes,
    write_coordinate, write_group,
};
use crate::error::Result;
use crate::field::Field;
use crate::spec::Grid;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use zarrs::array::{Array, ArrayBuilder, ArraySubset, CodecOptions, data_type};
use zarrs::group::Group;
use zarrs::storage::ReadableStorageTraits;

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
                identity: a.get("chaoscope:identity").cloned().unwrap_or_default(),
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
        write_axes(&store, path, grid)?;
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
        .dimension_names({
            let [y, x] = super::dims(grid);
            ["frame", y, x].into()
        })
        .attributes(attributes)
        .bytes_to_bytes_codecs(checksummed())
        .build(store.clone(), "/map")
        .map_err(|e| err(&e))?;
        map.store_metadata().map_err(|e| err(&e))?;
        let mut attributes = serde_json::Map::new();
        attributes.insert("chaoscope:command".into(), info.command.clone().into());
        attributes.insert("chaoscope:version".into(), info.version.clone().into());
        attributes.insert("chaoscope:varied".into(), param_name.into());
        attributes.insert("chaoscope:identity".into(), info.identity.clone());
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
