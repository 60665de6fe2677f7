//! Atomic writes of PNG, .npy, GIF, MP4 and text files, one file or a set: each is written to a
//! temporary file beside its destination (created with the user's umask) and renamed into
//! place only when every file of the set is complete, so no half-written or half-updated
//! output is left behind, not even on a second Ctrl-C ([`remove_pending`]).

use std::borrow::Cow;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;

/// Temporary files being written, for removal when the process is stopped hard.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file still being written: for a signal handler that is about to
/// exit the process.
pub fn remove_pending() {
    if let Ok(pending) = PENDING.lock() {
        for path in pending.iter() {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// A temporary file, listed in PENDING while it exists.
struct Staged {
    tmp: tempfile::NamedTempFile,
    path: PathBuf,
}

impl Staged {
    fn new(dir: &Path) -> std::io::Result<Self> {
        // Mode 0666 at creation, so the user's umask applies (tempfile's default is 0600,
        // which the rename would keep).
        #[allow(unused_mut)]
        let mut builder = tempfile::Builder::new();
        builder.prefix(".chaoscope-");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder.tempfile_in(dir)?;
        let path = tmp.path().to_path_buf();
        PENDING.lock().expect("pending list").push(path.clone());
        Ok(Staged { tmp, path })
    }

    fn persist(self, to: &Path) -> std::io::Result<()> {
        // Checked again at the last moment: a FIFO or device made since the run's check must
        // not be renamed over either.
        replaceable(to)
            .map_err(|why| std::io::Error::new(std::io::ErrorKind::InvalidInput, why))?;
        // Drop (which forgets the path) runs when `self` goes out of scope; the file is
        // renamed through a borrow of it.
        std::fs::rename(self.tmp.path(), to)
    }
}

fn forget(path: &Path) {
    if let Ok(mut pending) = PENDING.lock() {
        pending.retain(|p| p != path);
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        // The NamedTempFile removes the file itself (unless persisted).
        forget(&self.path);
    }
}

/// An error about the file at `path`.
fn file_error(path: &Path, e: std::io::Error) -> Error {
    Error::File {
        path: path.to_path_buf(),
        source: e,
    }
}

/// Files written as a set: staged one by one, renamed into place together by
/// [`Outputs::commit`]; dropped uncommitted, they leave nothing.
#[derive(Default)]
pub struct Outputs {
    staged: Vec<(Staged, PathBuf)>,
}

impl Outputs {
    /// `value` as pretty JSON into `path` (a summary.json) among these outputs.
    pub fn write_json(&mut self, path: &std::path::Path, value: &serde_json::Value) -> Result<()> {
        let text = serde_json::to_string_pretty(value).map_err(|e| Error::format(path, e))?;
        self.write(path, |w| {
            use std::io::Write;
            writeln!(w, "{text}")?;
            Ok(())
        })
    }

    pub fn new() -> Self {
        Outputs::default()
    }

    /// Stages `path`, written by `write`.
    pub fn write(
        &mut self,
        path: &Path,
        write: impl FnOnce(&mut BufWriter<&std::fs::File>) -> Result<()>,
    ) -> Result<()> {
        self.stage(path, |staged| {
            let mut w = BufWriter::new(staged.tmp.as_file());
            write(&mut w)?;
            w.flush().map_err(|e| file_error(path, e))
        })
    }

    /// Stages `path`, written by another program: `write` is given the temporary file's
    /// path (created empty, with the user's umask), which the program overwrites in place.
    pub fn write_by(&mut self, path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        self.stage(path, |staged| write(&staged.path))
    }

    fn stage(&mut self, path: &Path, write: impl FnOnce(&Staged) -> Result<()>) -> Result<()> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        replaceable(path).map_err(|why| {
            file_error(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, why),
            )
        })?;
        std::fs::create_dir_all(dir).map_err(|e| file_error(dir, e))?;
        let staged = Staged::new(dir).map_err(|e| file_error(dir, e))?;
        write(&staged).map_err(|e| match e {
            Error::Io(e) => file_error(path, e),
            e => e,
        })?;
        self.staged.push((staged, path.to_path_buf()));
        Ok(())
    }

    /// An 8-bit RGB PNG with tEXt chunks (keyword, text).
    pub fn png(
        &mut self,
        path: &Path,
        width: u32,
        height: u32,
        rgb: &[u8],
        text: &[(String, String)],
    ) -> Result<()> {
        self.write(path, |w| {
            encode_png(w, path, (width, height), 1, None, text, |_| {
                Ok(Cow::Borrowed(rgb))
            })
        })
    }

    /// An animated PNG (APNG, lossless) of `count` RGB frames of `size`, made one at a time
    /// by `frame(k)`, `delay_ms` per frame, looping forever; viewers without APNG support
    /// show the first frame.
    pub fn apng(
        &mut self,
        path: &Path,
        size: (u32, u32),
        count: usize,
        delay_ms: u16,
        text: &[(String, String)],
        mut frame: impl FnMut(usize) -> Result<Vec<u8>>,
    ) -> Result<()> {
        self.write(path, |w| {
            encode_png(w, path, size, count, Some(delay_ms), text, |k| {
                frame(k).map(Cow::Owned)
            })
        })
    }

    /// float32 array of shape (height, width), C order, row 0 = top of the image.
    pub fn npy(&mut self, path: &Path, field: &Field) -> Result<()> {
        self.npy_shaped(
            path,
            &[field.height as u64, field.width as u64],
            &field.data,
        )
    }

    /// A uint8 mask of shape (height, width), C order (1 = resolved).
    pub fn mask(&mut self, path: &Path, width: u32, height: u32, mask: &[u8]) -> Result<()> {
        self.npy_shaped(path, &[height as u64, width as u64], mask)
    }

    /// An array of any `shape` (float32, uint8...), C order.
    pub fn npy_shaped<T: npyz::AutoSerialize + Copy>(
        &mut self,
        path: &Path,
        shape: &[u64],
        data: &[T],
    ) -> Result<()> {
        use npyz::WriterBuilder;
        self.write(path, |w| {
            let mut npy = npyz::WriteOptions::new()
                .default_dtype()
                .shape(shape)
                .writer(w)
                .begin_nd()?;
            npy.extend(data.iter().copied())?;
            npy.finish()?;
            Ok(())
        })
    }

    /// An animated GIF of `count` equally sized RGB frames made one at a time by `frame(k)`
    /// (memory of one frame), each quantised to its own 256-colour palette, `delay_cs`
    /// hundredths of a second per frame, looping forever.
    pub fn gif_from(
        &mut self,
        path: &Path,
        (width, height): (u32, u32),
        count: usize,
        delay_cs: u16,
        mut frame: impl FnMut(usize) -> Result<Vec<u8>>,
    ) -> Result<()> {
        let gif_err = |e: gif::EncodingError| match e {
            gif::EncodingError::Io(e) => file_error(path, e),
            e => Error::format(path, e),
        };
        let (w, h) = (
            u16::try_from(width)
                .map_err(|_| Error::invalid("size", "GIF frames are at most 65535 pixels wide"))?,
            u16::try_from(height)
                .map_err(|_| Error::invalid("size", "GIF frames are at most 65535 pixels high"))?,
        );
        self.write(path, |out| {
            let mut encoder = gif::Encoder::new(out, w, h, &[]).map_err(gif_err)?;
            encoder.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;
            for k in 0..count {
                // Speed 10: NeuQuant's usual trade of palette quality for time.
                let mut frame = gif::Frame::from_rgb_speed(w, h, &frame(k)?, 10);
                frame.delay = delay_cs;
                encoder.write_frame(&frame).map_err(gif_err)?;
            }
            Ok(())
        })
    }

    /// Renames every staged file into place, unless the user asked to stop: then nothing is.
    pub fn commit(self, monitor: &Monitor) -> Result<()> {
        monitor.check()?;
        self.commit_now()
    }

    fn commit_now(self) -> Result<()> {
        for (staged, path) in self.staged {
            staged.persist(&path).map_err(|e| file_error(&path, e))?;
        }
        Ok(())
    }
}

/// Writes `path` atomically (a set of one).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&std::fs::File>) -> Result<()>,
) -> Result<()> {
    let mut set = Outputs::new();
    set.write(path, write)?;
    set.commit_now()
}

/// Whether an output may take the place of what is at `path`: nothing yet, a regular file,
/// or a link to one or to nothing (the rename replaces the link itself). A directory, a
/// device node (/dev/null), a FIFO or a socket, or a link to one, is never replaced: run as
/// root, a rename over /dev/null would replace the system's device with a PNG.
pub fn replaceable(path: &Path) -> std::result::Result<(), String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) if m.is_dir() => Err("is a directory".into()),
        Ok(_) => Err(
            "is not a regular file (a device, FIFO or socket): only a regular file is replaced"
                .into(),
        ),
        // Nothing there, or a dangling link.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e.to_string()),
    }
}

/// That `path` can be written: its nearest existing ancestor is a directory that takes
/// files (the rest is made when the file is written), and `path` is not a directory.
/// Checked before any work, creating nothing; the error names `field`.
pub fn check_writable(field: &'static str, path: &Path) -> Result<()> {
    let mut dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    while !dir.exists() {
        dir = match dir.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
    }
    let problem = if let Err(why) = replaceable(path) {
        Some(why)
    } else if !dir.is_dir() {
        Some(format!("{} is not a directory", dir.display()))
    } else {
        Staged::new(dir)
            .err()
            .map(|e| format!("cannot write in {}: {e}", dir.display()))
    };
    match problem {
        Some(p) => Err(Error::invalid(field, format!("{}: {p}", path.display()))),
        None => Ok(()),
    }
}

/// An 8-bit RGB PNG with tEXt chunks (keyword, text).
pub fn write_png(
    path: &Path,
    size: (u32, u32),
    rgb: &[u8],
    text: &[(String, String)],
) -> Result<()> {
    let mut set = Outputs::new();
    set.png(path, size.0, size.1, rgb, text)?;
    set.commit_now()
}

/// An 8-bit RGB PNG with tEXt chunks, in memory (the explorer's tiles and views), encoded
/// as [`write_png`] encodes files.
pub fn png_bytes(
    width: u32,
    height: u32,
    rgb: &[u8],
    text: &[(String, String)],
) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    encode_png(
        &mut out,
        Path::new("(memory)"),
        (width, height),
        1,
        None,
        text,
        |_| Ok(Cow::Borrowed(rgb)),
    )?;
    Ok(out)
}

/// RGB frames as a PNG into `w`, animated (APNG, `delay_ms` a frame, looping) when
/// `delay_ms` is given; `path` names the file in errors.
fn encode_png<'a>(
    w: &mut impl Write,
    path: &Path,
    (width, height): (u32, u32),
    count: usize,
    delay_ms: Option<u16>,
    text: &[(String, String)],
    mut frame: impl FnMut(usize) -> Result<Cow<'a, [u8]>>,
) -> Result<()> {
    let png_err = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => file_error(path, e),
        e => Error::format(path, e),
    };
    {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        if let Some(delay) = delay_ms {
            encoder.set_animated(count as u32, 0).map_err(png_err)?;
            encoder.set_frame_delay(delay, 1000).map_err(png_err)?;
        }
        for (key, value) in text {
            encoder
                .add_text_chunk(key.clone(), value.clone())
                .map_err(png_err)?;
        }
        let mut writer = encoder.write_header().map_err(png_err)?;
        for k in 0..count {
            writer.write_image_data(&frame(k)?).map_err(png_err)?;
        }
        writer.finish().map_err(png_err)
    }
}

/// float32 array of shape (height, width), C order, row 0 = top of the image.
pub fn write_npy(path: &Path, field: &Field) -> Result<()> {
    let mut set = Outputs::new();
    set.npy(path, field)?;
    set.commit_now()
}

/// float32 array of any `shape`, C order.
pub fn write_npy_shaped(path: &Path, shape: &[u64], data: &[f32]) -> Result<()> {
    let mut set = Outputs::new();
    set.npy_shaped(path, shape, data)?;
    set.commit_now()
}

/// A decoded 8-bit RGB PNG: width, height, pixels and its tEXt chunks.
pub struct Png {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    pub text: Vec<(String, String)>,
}

/// The PNG at `path`, a regular file of at most [`crate::input::PNG_CAP`] bytes.
pub fn read_png(path: &Path) -> Result<Png> {
    let cap = crate::input::PNG_CAP;
    let err = |e: png::DecodingError| Error::format(path, e);
    let (file, len) = crate::input::open_regular(path).map_err(|e| file_error(path, e))?;
    if len > cap {
        return Err(Error::format(path, crate::input::too_large(len, cap)));
    }
    use std::io::Read;
    let file = std::io::BufReader::new(file.take(cap));
    let mut reader = png::Decoder::new(file).read_info().map_err(err)?;
    let mut rgb = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let frame = reader.next_frame(&mut rgb).map_err(err)?;
    if frame.color_type != png::ColorType::Rgb || frame.bit_depth != png::BitDepth::Eight {
        return Err(Error::format(path, "not an 8-bit RGB PNG"));
    }
    rgb.truncate(frame.buffer_size());
    let text = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    Ok(Png {
        width: frame.width,
        height: frame.height,
        rgb,
        text,
    })
}
