//! Atomic writes of PNG and .npy files.

use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, Result};
use crate::field::Field;

/// Writes `path` through a temporary file in the same directory, renamed into place only
/// when `write` has succeeded; on any error (or a panic) the temporary file is removed.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&std::fs::File>) -> Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)?;
    let tmp = tempfile::Builder::new()
        .prefix(".chaoscope-")
        .tempfile_in(dir)?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        write(&mut w)?;
        w.flush()?;
    }
    tmp.persist(path).map_err(|e| Error::Io(e.error))?;
    Ok(())
}

/// An 8-bit RGB PNG with tEXt chunks (keyword, text).
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
    text: &[(String, String)],
) -> Result<()> {
    let png_err = |e: png::EncodingError| Error::Io(std::io::Error::other(e));
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        for (key, value) in text {
            encoder
                .add_text_chunk(key.clone(), value.clone())
                .map_err(png_err)?;
        }
        let mut writer = encoder.write_header().map_err(png_err)?;
        writer.write_image_data(rgb).map_err(png_err)?;
        writer.finish().map_err(png_err)
    })
}

/// float32 array of shape (height, width), C order, row 0 = top of the image.
pub fn write_npy(path: &Path, field: &Field) -> Result<()> {
    use npyz::WriterBuilder;
    write_atomic(path, |w| {
        let mut npy = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[field.height as u64, field.width as u64])
            .writer(w)
            .begin_nd()?;
        npy.extend(field.data.iter().copied())?;
        npy.finish()?;
        Ok(())
    })
}
