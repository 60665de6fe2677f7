//! [`AtomicStore`]: zarrs' filesystem store with every write a temporary file renamed into
//! place, so a killed writer leaves no half-written chunk.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use zarrs::filesystem::FilesystemStore;
use zarrs::storage::{
    Bytes, ListableStorageTraits, MaybeBytesIterator, OffsetBytesIterator, ReadableStorageTraits,
    StorageError, StoreKey, StoreKeys, StoreKeysPrefixes, StorePrefix, WritableStorageTraits,
    byte_range::ByteRangeIterator,
};

/// The filesystem store, but every `set` goes to a temporary file renamed into place.
pub struct AtomicStore {
    inner: FilesystemStore,
    root: PathBuf,
}

static TEMPORARY: AtomicU64 = AtomicU64::new(0);

impl AtomicStore {
    pub(super) fn new(root: &Path) -> Result<Self> {
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

/// A chunk file at most: a chunk holds 2^18 pixels (1 MiB of f32, `CHUNK_PIXELS`), or one
/// row where a row is wider (65536 pixels at most), and a 4-byte checksum.
const CHUNK_CAP: u64 = 4 << 20;

impl AtomicStore {
    /// That the file of `key` is one to read: a regular file (a FIFO or device put in a store
    /// would block or never end) no larger than its kind may be; nothing there is fine (a
    /// chunk not written yet).
    fn readable(&self, key: &StoreKey) -> std::result::Result<(), StorageError> {
        let path = self.root.join(key.as_str());
        let cap = match key.as_str().ends_with("zarr.json") {
            true => crate::input::METADATA_CAP,
            false => CHUNK_CAP,
        };
        match std::fs::metadata(&path) {
            Ok(m) if !m.is_file() => Err(StorageError::Other(format!(
                "{}: not a regular file; only a regular file is read",
                path.display()
            ))),
            Ok(m) if m.len() > cap => Err(StorageError::Other(format!(
                "{}: {}",
                path.display(),
                crate::input::too_large(m.len(), cap)
            ))),
            _ => Ok(()),
        }
    }
}

impl ReadableStorageTraits for AtomicStore {
    fn get_partial_many<'a>(
        &'a self,
        key: &StoreKey,
        byte_ranges: ByteRangeIterator<'a>,
    ) -> std::result::Result<MaybeBytesIterator<'a>, StorageError> {
        self.readable(key)?;
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
        // A directory where the chunk belongs (a damaged store) is cleared, so the chunk is
        // rewritten rather than failing for ever.
        if path.is_dir() {
            std::fs::remove_dir_all(&path).ok();
        }
        crate::render::files::replaceable(&path)
            .map_err(|why| StorageError::Other(format!("{}: {why}", path.display())))?;
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
