//! Frames out of any film FFmpeg reads (MP4 and MOV from phones and cameras, H.264, HEVC,
//! AV1), one at a time over a pipe, each with its time from the container: phones record at a
//! variable frame rate, so a frame's time is its timestamp, never its index over a rate.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Stdio;

use crate::error::{Error, Result};

/// The most of ffprobe's report read: about 200 bytes a frame, so some 300,000 frames
/// (almost three hours at 30 frames a second).
const PROBE_CAP: u64 = 64 << 20;

/// What a film holds: its picture size as shown (a phone's rotation applied) and the time
/// of every frame (s, from the first), in the order shown.
#[derive(Clone, Debug)]
pub struct Probe {
    pub codec: String,
    pub width: u32,
    pub height: u32,
    pub times: Vec<f64>,
    /// Frames whose timestamp repeats another's (at most [`REPEATS_TOLERATED`] of them).
    pub repeated: usize,
}

impl Probe {
    /// The film's frame rate: one over the median step between its frames, taken as the
    /// standard rate it is within a thousandth of (a container's timestamps in milliseconds
    /// make 60 frames a second read as 59.998; NTSC's 30000/1001 stays itself). A film of one
    /// frame: 30.
    pub fn frame_rate(&self) -> f64 {
        let mut steps: Vec<f64> = self.times.windows(2).map(|w| w[1] - w[0]).collect();
        if steps.is_empty() {
            return 30.0;
        }
        let mid = steps.len() / 2;
        let rate = 1.0 / *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
        const STANDARD: [f64; 22] = [
            24000.0 / 1001.0,
            24.0,
            25.0,
            30000.0 / 1001.0,
            30.0,
            48.0,
            50.0,
            60000.0 / 1001.0,
            60.0,
            90.0,
            100.0,
            120000.0 / 1001.0,
            120.0,
            200.0,
            240.0,
            250.0,
            300.0,
            400.0,
            480.0,
            500.0,
            960.0,
            1000.0,
        ];
        STANDARD
            .iter()
            .copied()
            .min_by(|a, b| (a / rate - 1.0).abs().total_cmp(&(b / rate - 1.0).abs()))
            .filter(|s| (s / rate - 1.0).abs() < 1e-3)
            .unwrap_or(rate)
    }
}

/// The share of frames whose timestamps may repeat another's before the film is refused.
pub const REPEATS_TOLERATED: f64 = 0.1;

/// The film at `path` as [`Probe`] tells it (ffprobe reads the container, decoding nothing).
pub fn probe(path: &Path) -> Result<Probe> {
    let (_, _) = crate::input::open_regular(path).map_err(|e| Error::File {
        path: path.to_path_buf(),
        source: e,
    })?;
    let mut args = super::args(&["-v", "error"]);
    args.extend(super::input_options());
    args.extend(super::args(&[
        "-select_streams",
        "v:0",
        "-show_entries",
        "stream=codec_name,width,height,nb_frames:stream_side_data=rotation:packet=pts_time",
        "-of",
        "json=c=1",
    ]));
    args.push(super::file_url(path)?);
    let mut child = super::spawn(
        "ffprobe",
        "reading a film",
        &args,
        Stdio::null(),
        Stdio::piped(),
    )?;
    let stderr = super::drain_stderr(&mut child);
    let mut text = String::new();
    child
        .stdout
        .take()
        .expect("piped")
        .take(PROBE_CAP)
        .read_to_string(&mut text)
        .map_err(|e| Error::format(path, e))?;
    let status = child.wait()?;
    let stderr = stderr.join().unwrap_or_default();
    if !status.success() {
        return Err(super::failed("ffprobe", path, &stderr));
    }
    parse_probe(path, &text)
}

fn parse_probe(path: &Path, text: &str) -> Result<Probe> {
    let bad = |why: &str| Error::format(path, format!("not a film FFmpeg can read: {why}"));
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|_| bad("ffprobe's report was cut or unreadable"))?;
    let stream = v["streams"]
        .as_array()
        .and_then(|s| s.first())
        .ok_or_else(|| bad("no video stream"))?;
    let dim = |key: &str| {
        stream[key]
            .as_u64()
            .and_then(|d| u32::try_from(d).ok())
            .filter(|&d| d > 0)
            .ok_or_else(|| bad("no picture size"))
    };
    let (mut width, mut height) = (dim("width")?, dim("height")?);
    let rotation = stream["side_data_list"]
        .as_array()
        .into_iter()
        .flatten()
        .find_map(|d| d["rotation"].as_f64())
        .unwrap_or(0.0);
    // FFmpeg turns the frames upright as it decodes them (its autorotate).
    if (rotation.abs() - 90.0).abs() < 1.0 {
        (width, height) = (height, width);
    }
    let mut times: Vec<f64> = v["packets"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|p| p["pts_time"].as_str()?.parse().ok())
        .collect();
    // Packets come in decoding order; frames are shown in the order of their timestamps.
    times.sort_by(f64::total_cmp);
    let first = *times.first().ok_or_else(|| bad("no frames"))?;
    // A container that counts its frames (MP4, MOV) and holds fewer was cut short: its
    // index lists pictures whose bytes are gone.
    let counted = stream["nb_frames"]
        .as_str()
        .and_then(|n| n.parse::<usize>().ok());
    if let Some(counted) = counted.filter(|&n| n > times.len()) {
        return Err(Error::format(
            path,
            format!(
                "its container counts {counted} frames but only {} are there: the film is cut short or damaged",
                times.len()
            ),
        ));
    }
    // Frames at one time: pieces joined without new timestamps (MPEG-TS segments cat'ed
    // together: every time twice), whose frames no time can be given to. A few repeats are
    // a muxer's rounding (a variable-rate MOV with B-frames): those frames take their
    // places in time order, and the probe counts them.
    let repeated = times.windows(2).filter(|w| w[1] <= w[0]).count();
    if repeated as f64 > REPEATS_TOLERATED * times.len() as f64 {
        return Err(Error::format(
            path,
            format!(
                "{repeated} of its {} frames' timestamps repeat another's: pieces joined without new timestamps? Re-encode it (ffmpeg -i FILM -c:v libx264 NEW.mp4) to give every frame its own time",
                times.len()
            ),
        ));
    }
    for t in &mut times {
        *t -= first;
    }
    Ok(Probe {
        codec: stream["codec_name"].as_str().unwrap_or("?").to_string(),
        width,
        height,
        times,
        repeated,
    })
}

/// The pixels each frame is handed over as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixels {
    /// One byte a pixel (luma).
    Gray,
    /// Three bytes a pixel.
    Rgb,
}

impl Pixels {
    fn bytes(self) -> usize {
        match self {
            Pixels::Gray => 1,
            Pixels::Rgb => 3,
        }
    }
    fn ffmpeg(self) -> &'static str {
        match self {
            Pixels::Gray => "gray",
            Pixels::Rgb => "rgb24",
        }
    }
}

/// A film's frames in the order shown, one at a time.
pub struct Decoder {
    child: super::Program,
    stderr: Option<std::thread::JoinHandle<String>>,
    path: PathBuf,
    pub probe: Probe,
    pub pixels: Pixels,
    next: usize,
}

impl Decoder {
    pub fn open(path: &Path, pixels: Pixels) -> Result<Decoder> {
        let probe = probe(path)?;
        let mut args = super::args(&["-hide_banner", "-v", "error", "-nostdin"]);
        args.extend(super::input_options());
        args.push("-i".into());
        args.push(super::file_url(path)?);
        args.extend(super::args(&[
            "-map",
            "0:v:0",
            "-fps_mode",
            "passthrough",
            "-f",
            "rawvideo",
            "-pix_fmt",
            pixels.ffmpeg(),
            "pipe:1",
        ]));
        let mut child = super::spawn(
            "ffmpeg",
            "reading a film",
            &args,
            Stdio::null(),
            Stdio::piped(),
        )?;
        let stderr = Some(super::drain_stderr(&mut child));
        Ok(Decoder {
            child,
            stderr,
            path: path.to_path_buf(),
            probe,
            pixels,
            next: 0,
        })
    }

    /// The next frame's time (s) and pixels into `frame` (row after row from the top), or
    /// None after the last.
    pub fn next_frame(&mut self, frame: &mut Vec<u8>) -> Result<Option<f64>> {
        let bytes = self.probe.width as usize * self.probe.height as usize * self.pixels.bytes();
        frame.resize(bytes, 0);
        let stdout = self.child.stdout.as_mut().expect("piped");
        let mut got = 0;
        while got < bytes {
            match stdout.read(&mut frame[got..]) {
                Ok(0) => break,
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::format(&self.path, e)),
            }
        }
        let listed = self.probe.times.len();
        if got == 0 {
            let status = self.child.wait()?;
            let stderr = self
                .stderr
                .take()
                .and_then(|h| h.join().ok())
                .unwrap_or_default();
            if !status.success() {
                return Err(super::failed("ffmpeg", &self.path, &stderr));
            }
            // Every frame the container lists must decode: a film cut short or damaged
            // lists frames whose pictures are gone.
            if self.next < listed {
                return Err(Error::format(
                    &self.path,
                    format!(
                        "only {} of the {listed} frames its container lists decode: the film is cut short or damaged",
                        self.next
                    ),
                ));
            }
            return Ok(None);
        }
        if got < bytes {
            return Err(Error::format(
                &self.path,
                format!(
                    "frame {} of {listed} was cut short: the film is damaged",
                    self.next + 1
                ),
            ));
        }
        let k = self.next;
        self.next += 1;
        // Each frame takes its own timestamp; a frame beyond them has no time.
        match self.probe.times.get(k) {
            Some(&t) => Ok(Some(t)),
            None => Err(Error::format(
                &self.path,
                format!(
                    "more frames decode than the {listed} timestamps its container lists: no time can be given to them"
                ),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_probe_turns_a_phones_portrait_film_upright_and_sorts_its_times() {
        let text = r#"{"packets":[{"pts_time":"1.000000"},{"pts_time":"1.066667"},{"pts_time":"1.033333"}],
            "streams":[{"codec_name":"hevc","width":1920,"height":1080,
            "side_data_list":[{"rotation":-90}]}]}"#;
        let p = parse_probe(Path::new("x.mov"), text).unwrap();
        assert_eq!((p.codec.as_str(), p.width, p.height), ("hevc", 1080, 1920));
        assert_eq!(p.repeated, 0);
        let expected = [0.0, 0.033333, 0.066667];
        for (t, e) in p.times.iter().zip(expected) {
            assert!((t - e).abs() < 1e-9, "{:?}", p.times);
        }
        assert!(parse_probe(Path::new("x"), r#"{"streams":[]}"#).is_err());
    }
}
