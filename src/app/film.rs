//! An animated output in the format its file's extension names: APNG (`.png`, lossless),
//! GIF (`.gif`) or MP4 (`.mp4`, H.264 through FFmpeg: what browsers, slide programs and
//! journals take). Frames are made one at a time and handed on as made.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::render::Outputs;
use crate::video::Mp4;

/// The formats a film may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Apng,
    Gif,
    Mp4,
}

impl Format {
    fn extension(self) -> &'static str {
        match self {
            Format::Apng => "png",
            Format::Gif => "gif",
            Format::Mp4 => "mp4",
        }
    }
}

/// Where a film goes and how fast and well it plays.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSpec {
    pub path: PathBuf,
    /// Frames a second.
    pub fps: f64,
    /// The MP4's H.264 constant rate factor ([`Mp4::crf`]).
    pub crf: u32,
}

impl FilmSpec {
    /// Its format, one of `allowed`, by the file's extension; else an error naming `field`.
    pub fn format(&self, field: &'static str, allowed: &[Format]) -> Result<Format> {
        let ext = self.path.extension().and_then(|e| e.to_str()).unwrap_or("");
        allowed
            .iter()
            .copied()
            .find(|f| ext.eq_ignore_ascii_case(f.extension()))
            .ok_or_else(|| {
                let names: Vec<String> = allowed
                    .iter()
                    .map(|f| format!(".{}", f.extension()))
                    .collect();
                Error::invalid(
                    field,
                    format!("{} must end in {}", self.path.display(), names.join(" or ")),
                )
            })
    }

    /// That the film can be made: its format one of `allowed`, its rate and quality in
    /// range (the APNG's and GIF's delays are whole milliseconds and hundredths), its file
    /// writable. Errors name `field`, `fps` and `crf`.
    pub fn validate(&self, field: &'static str, allowed: &[Format]) -> Result<()> {
        let format = self.format(field, allowed)?;
        Mp4 {
            fps: self.fps,
            crf: self.crf,
        }
        .validate()?;
        if format != Format::Mp4 && self.fps > 100.0 {
            return Err(Error::invalid(
                "fps",
                format!(
                    "{} must be at most 100 for an APNG or a GIF (.mp4 takes up to 240)",
                    self.fps
                ),
            ));
        }
        crate::render::check_writable(field, &self.path)?;
        match format {
            Format::Mp4 => crate::video::require("ffmpeg", "an MP4"),
            _ => Ok(()),
        }
    }
}

/// Stages the film of `count` RGB frames of `size`, made by `frame(k)`, in `files`; `meta`
/// (the provenance) goes into its text chunks, or the MP4's comment (the command).
pub fn write(
    files: &mut Outputs,
    film: &FilmSpec,
    format: Format,
    size: (u32, u32),
    count: usize,
    meta: &[(String, String)],
    frame: impl FnMut(usize) -> Result<Vec<u8>>,
) -> Result<()> {
    let path: &Path = &film.path;
    match format {
        Format::Apng => {
            let delay_ms = (1000.0 / film.fps).round().min(65535.0) as u16;
            files.apng(path, size, count, delay_ms, meta, frame)
        }
        Format::Gif => {
            let delay_cs = (100.0 / film.fps).round().clamp(1.0, 65535.0) as u16;
            files.gif_from(path, size, count, delay_cs, frame)
        }
        Format::Mp4 => {
            let command = meta
                .iter()
                .find(|(k, _)| k == "chaoscope:command")
                .map_or("", |(_, v)| v.as_str());
            crate::video::write_mp4(
                files,
                path,
                size,
                Mp4 {
                    fps: film.fps,
                    crf: film.crf,
                },
                command,
                count,
                frame,
            )
        }
    }
}
