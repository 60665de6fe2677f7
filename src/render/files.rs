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
    encode_png(path, width, height, &[rgb], None, text)
}

/// RGB frames as a PNG, animated (APNG, `delay_ms` a frame, looping) when `delay_ms` is given.
fn encode_png(
    path: &Path,
    width: u32,
    height: u32,
    frames: &[&[u8]],
    delay_ms: Option<u16>,
    text: &[(String, String)],
) -> Result<()> {
    let png_err = |e: png::EncodingError| Error::format(path, e);
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        if let Some(delay) = delay_ms {
            encoder
                .set_animated(frames.len() as u32, 0)
                .map_err(png_err)?;
            encoder.set_frame_delay(delay, 1000).map_err(png_err)?;
        }
        for (key, value) in text {
            encoder
                .add_text_chunk(key.clone(), value.clone())
                .map_err(png_err)?;
        }
        let mut writer = encoder.write_header().map_err(png_err)?;
        for frame in frames {
            writer.write_image_data(frame).map_err(png_err)?;
        }
        writer.finish().map_err(png_err)
    })
}

/// float32 array of shape (height, width), C order, row 0 = top of the image.
pub fn write_npy(path: &Path, field: &Field) -> Result<()> {
    write_npy_shaped(
        path,
        &[field.height as u64, field.width as u64],
        &field.data,
    )
}

/// float32 array of any `shape`, C order.
pub fn write_npy_shaped(path: &Path, shape: &[u64], data: &[f32]) -> Result<()> {
    use npyz::WriterBuilder;
    write_atomic(path, |w| {
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

/// A decoded 8-bit RGB PNG: width, height, pixels and its tEXt chunks.
pub struct Png {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    pub text: Vec<(String, String)>,
}

pub fn read_png(path: &Path) -> Result<Png> {
    let err = |e: png::DecodingError| Error::format(path, e);
    let file = std::io::BufReader::new(std::fs::File::open(path)?);
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

/// An animated PNG (APNG, lossless) of equally sized RGB frames, `delay_ms` per frame,
/// looping forever; viewers without APNG support show the first frame.
pub fn write_apng(
    path: &Path,
    width: u32,
    height: u32,
    frames: &[Vec<u8>],
    delay_ms: u16,
    text: &[(String, String)],
) -> Result<()> {
    let frames: Vec<&[u8]> = frames.iter().map(Vec::as_slice).collect();
    encode_png(path, width, height, &frames, Some(delay_ms), text)
}

/// An animated GIF of equally sized RGB frames (each quantised to its own 256-colour
/// palette), `delay_cs` hundredths of a second per frame, looping forever.
pub fn write_gif(
    path: &Path,
    width: u32,
    height: u32,
    frames: &[Vec<u8>],
    delay_cs: u16,
) -> Result<()> {
    let gif_err = |e: gif::EncodingError| Error::format(path, e);
    let (w, h) = (
        u16::try_from(width)
            .map_err(|_| Error::invalid("size", "GIF frames are at most 65535 pixels wide"))?,
        u16::try_from(height)
            .map_err(|_| Error::invalid("size", "GIF frames are at most 65535 pixels high"))?,
    );
    write_atomic(path, |out| {
        let mut encoder = gif::Encoder::new(out, w, h, &[]).map_err(gif_err)?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(gif_err)?;
        for rgb in frames {
            // Speed 10: NeuQuant's usual trade of palette quality for time.
            let mut frame = gif::Frame::from_rgb_speed(w, h, rgb, 10);
            frame.delay = delay_cs;
            encoder.write_frame(&frame).map_err(gif_err)?;
        }
        Ok(())
    })
}
