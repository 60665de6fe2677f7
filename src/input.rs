//! Every file the program reads goes through here: it must be a regular file (a FIFO, a
//! device such as /dev/zero, a socket or a directory is refused before a byte is read) no
//! larger than a cap that fits its format, and the read itself stops at the cap, so neither
//! a file that grows while it is read nor a sparse file of terabytes can take the memory.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};

/// A CSV of tracked positions: an hour filmed at 1000 frames a second is 3.6 million rows of
/// about 60 bytes (216 MB).
pub const CSV_CAP: u64 = 256 << 20;
/// A TOML file of parameters: a dozen keys.
pub const TOML_CAP: u64 = 64 << 10;
/// A PNG read back (a sweep's frames): the decoder itself takes at most 64 MiB of pixels;
/// stored (uncompressed) blocks and text chunks add little to that.
pub const PNG_CAP: u64 = 80 << 20;
/// A Zarr store's metadata document (zarr.json): a few kilobytes of JSON.
pub const METADATA_CAP: u64 = 1 << 20;

/// Opens `path` for reading if it is a regular file (through links), without blocking on a
/// FIFO: opened non-blocking, then asked what it is. Its size is returned with it.
pub fn open_regular(path: &Path) -> std::io::Result<(File, u64)> {
    use std::os::unix::fs::OpenOptionsExt;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, FIFO or socket)"
        };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("is {kind}; only a regular file is read"),
        ));
    }
    Ok((file, meta.len()))
}

/// The bytes of the regular file `path`, at most `cap` of them; an error naming `field`, the
/// file and the cap otherwise.
pub fn read_bounded(field: &'static str, path: &Path, cap: u64) -> Result<Vec<u8>> {
    let refuse = |why: String| Error::invalid(field, format!("{}: {why}", path.display()));
    let (file, len) = open_regular(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => Error::Missing {
            field,
            path: path.to_path_buf(),
        },
        _ => refuse(e.to_string()),
    })?;
    if len > cap {
        return Err(refuse(too_large(len, cap)));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // One byte past the cap tells a file that grew while it was read.
    file.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| refuse(format!("cannot read: {e}")))?;
    if bytes.len() as u64 > cap {
        return Err(refuse(too_large(bytes.len() as u64, cap)));
    }
    Ok(bytes)
}

/// The text of the regular file `path` (UTF-8), at most `cap` bytes, as [`read_bounded`].
pub fn read_text(field: &'static str, path: &Path, cap: u64) -> Result<String> {
    let bytes = read_bounded(field, path, cap)?;
    String::from_utf8(bytes).map_err(|e| {
        Error::invalid(
            field,
            format!(
                "{}: not UTF-8 text (byte {} is not)",
                path.display(),
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// "10.0 GiB is larger than the 256.0 MiB this file may have".
pub(crate) fn too_large(len: u64, cap: u64) -> String {
    format!(
        "{} is larger than the {} this file may have",
        bytes(len),
        bytes(cap)
    )
}

/// `n` bytes in words: "64 KiB", "256 MiB", "10 GiB".
pub fn bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 30 => format!("{:.1} GiB", n as f64 / (1u64 << 30) as f64),
        n if n >= 1 << 20 => format!("{:.1} MiB", n as f64 / (1u64 << 20) as f64),
        n if n >= 1 << 10 => format!("{:.1} KiB", n as f64 / 1024.0),
        n => format!("{n} bytes"),
    }
}

/// The `# key = value` comments of `text` (before its header): each key's numbers.
pub fn comment_values(text: &str) -> Vec<(&str, Vec<f64>)> {
    text.lines()
        .take_while(|l| l.starts_with('#'))
        .filter_map(|l| {
            let (key, value) = l[1..].trim_start().split_once(" = ")?;
            let key = key.trim();
            key.chars()
                .all(|c| c.is_ascii_lowercase() || c == '_')
                .then(|| {
                    let numbers = value
                        .split_whitespace()
                        .map_while(|w| w.parse::<f64>().ok())
                        .collect();
                    (key, numbers)
                })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_within_the_cap_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let small = dir.path().join("small.csv");
        std::fs::write(&small, "t,x1\n").unwrap();
        assert_eq!(read_text("file", &small, 5).unwrap(), "t,x1\n");
        let e = read_text("file", &small, 4).unwrap_err().to_string();
        assert!(e.contains("5 bytes") && e.contains("4 bytes"), "{e}");
        let e = read_bounded("file", dir.path(), 100)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a directory"), "{e}");
        let e = read_bounded("params", Path::new("/dev/zero"), 100)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("not a regular file") && e.contains("params"),
            "{e}"
        );
    }
}
