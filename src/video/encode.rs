//! MP4 (H.264, yuv420p: what browsers, slide programs and journals play) from RGB frames made
//! one at a time and streamed into `ffmpeg`: memory holds one frame whatever the film's length.

use std::io::Write;
use std::path::Path;
use std::process::Stdio;

use crate::error::{Error, Result};
use crate::render::Outputs;

/// How a film is encoded: frames a second and H.264's constant rate factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mp4 {
    pub fps: f64,
    /// 0 (lossless) to 51; 18 is visually lossless for maps, 23 is x264's default.
    pub crf: u32,
}

impl Mp4 {
    /// `fps` in 0.02..=240 and `crf` in 0..=51, else an error naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(self.fps.is_finite() && (0.02..=240.0).contains(&self.fps)) {
            return Err(Error::invalid(
                "fps",
                format!("{} must be in [0.02, 240] frames a second", self.fps),
            ));
        }
        if self.crf > 51 {
            return Err(Error::invalid(
                "crf",
                format!(
                    "{} must be in 0..=51 (0 lossless, 18 visually lossless)",
                    self.crf
                ),
            ));
        }
        Ok(())
    }
}

/// Stages `path` in `files`: an MP4 of `count` RGB frames of `size`, made one at a time by
/// `frame(k)` (which checks for Ctrl-C), at `film`'s rate and quality, `comment` (the
/// command that reproduces it) in its metadata. An odd width or height is padded by one
/// black column or row (yuv420p halves the colour resolution).
pub fn write_mp4(
    files: &mut Outputs,
    path: &Path,
    (width, height): (u32, u32),
    film: Mp4,
    comment: &str,
    count: usize,
    mut frame: impl FnMut(usize) -> Result<Vec<u8>>,
) -> Result<()> {
    film.validate()?;
    files.write_by(path, |tmp| {
        let size = format!("{width}x{height}");
        let rate = format!("{}", film.fps);
        let crf = film.crf.to_string();
        let comment = format!("comment={comment}");
        // Raw frames come in over the pipe alone; the film goes out to the staged file alone.
        let mut args = super::args(&[
            "-hide_banner",
            "-loglevel",
            "error",
            "-y",
            "-protocol_whitelist",
            "pipe",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            &size,
            "-framerate",
            &rate,
            "-i",
            "pipe:0",
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-c:v",
            "libx264",
            "-crf",
            &crf,
            "-pix_fmt",
            "yuv420p",
            "-movflags",
            "+faststart",
            "-metadata",
            &comment,
            "-protocol_whitelist",
            "file",
            "-f",
            "mp4",
        ]);
        args.push(super::file_url(tmp)?);
        let mut child = super::spawn("ffmpeg", "an MP4", &args, Stdio::piped(), Stdio::null())?;
        let stderr = super::drain_stderr(&mut child);
        let mut stdin = child.stdin.take().expect("piped");
        let bytes = (width as usize) * (height as usize) * 3;
        let mut fed = Ok(());
        for k in 0..count {
            let rgb = match frame(k) {
                Ok(rgb) => rgb,
                Err(e) => {
                    fed = Err(e);
                    break;
                }
            };
            assert_eq!(rgb.len(), bytes, "frame {k}: RGB of {width}x{height}");
            if let Err(e) = stdin.write_all(&rgb) {
                // FFmpeg stopped reading: its own error output says why.
                fed = Err(Error::Io(e));
                break;
            }
        }
        drop(stdin);
        if fed.is_err() {
            let _ = child.kill();
        }
        let status = child.wait()?;
        let stderr = stderr.join().unwrap_or_default();
        match fed {
            Err(Error::Io(_)) | Ok(()) if !status.success() => {
                Err(super::failed("ffmpeg", path, &stderr))
            }
            other => other,
        }
    })
}
