//! Films in and out through FFmpeg, the field's standard: its command-line programs in a
//! pipe (raw frames over stdin and stdout), as matplotlib's animation writers and
//! imageio-ffmpeg do. No video codec is written here, and none is linked: the programs are
//! found on the PATH when a film is asked for, so every other command runs without them
//! (ARCHITECTURE.md, "Video", says why this route and not the libraries' bindings).

mod decode;
mod encode;

pub use decode::{Decoder, Pixels, Probe, probe};
pub use encode::{Mp4, write_mp4};

use std::io::Read;
use std::process::{Child, Command, Stdio};

use crate::error::{Error, Result};

/// What a user runs to get FFmpeg on Debian (the error names it).
pub const INSTALL: &str = "apt-get install ffmpeg";

/// The most of a program's error output kept for the message (its last lines matter).
const STDERR_CAP: u64 = 64 << 10;

/// `program` (ffmpeg, ffprobe) with `args`, its stdin, stdout and stderr as given, in a
/// process group of its own: Ctrl-C at the terminal reaches chaoscope, which stops it, and
/// not FFmpeg, which would otherwise end the film mid-frame before chaoscope can say why.
fn spawn(
    program: &'static str,
    what: &'static str,
    args: &[std::ffi::OsString],
    stdin: Stdio,
    stdout: Stdio,
) -> Result<Child> {
    let mut c = Command::new(program);
    c.args(args)
        .stdin(stdin)
        .stdout(stdout)
        .stderr(Stdio::piped());
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        c.process_group(0);
    }
    c.spawn().map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => Error::MissingTool {
            tool: program,
            what,
        },
        _ => Error::Io(e),
    })
}

/// `words` as a program's arguments.
fn args(words: &[&str]) -> Vec<std::ffi::OsString> {
    words.iter().map(std::ffi::OsString::from).collect()
}

/// The containers a film is read from: phones' and cameras' (MP4, MOV), MKV and WebM, AVI,
/// MPEG (program and transport streams), FLV, Ogg, ASF, MXF, NUT, DV, elementary H.264 and
/// HEVC, IVF (AV1, VP9), Y4M and GIF. Playlists and scripts (HLS, DASH, concat, image
/// sequences) are left out: they name other files, which FFmpeg would then read.
const CONTAINERS: &str =
    "mov,matroska,avi,mpegts,mpeg,flv,ogg,asf,mxf,nut,dv,h264,hevc,m4v,ivf,yuv4mpegpipe,gif";

/// FFmpeg's input options that let it read the named file alone: local files only (no
/// network, pipe or nested protocol), through [`CONTAINERS`] only.
fn input_options() -> Vec<std::ffi::OsString> {
    args(&[
        "-protocol_whitelist",
        "file",
        "-format_whitelist",
        CONTAINERS,
    ])
}

/// `path` as FFmpeg's programs must be handed it to read or write that file and no other: an
/// absolute `file:` URL. Given as written, a name that begins with a protocol (`concat:`,
/// `subfile,,...:`, `data:`, `pipe:`, `tee:`) is read as a URL naming other files, one
/// that begins with `-` as an option; `file:` followed by an absolute path is taken as the
/// path, byte for byte (FFmpeg decodes no `%` escapes in it and ends it at no `?` or `#`).
fn file_url(path: &std::path::Path) -> Result<std::ffi::OsString> {
    let absolute = std::path::absolute(path).map_err(|e| Error::File {
        path: path.to_path_buf(),
        source: e,
    })?;
    let mut url = std::ffi::OsString::from("file:");
    url.push(absolute.as_os_str());
    Ok(url)
}

/// That `program` (ffmpeg, ffprobe) runs here, checked before the work that needs it:
/// else [`Error::MissingTool`] naming `what` needs it.
pub fn require(program: &'static str, what: &'static str) -> Result<()> {
    let status = spawn(
        program,
        what,
        &args(&["-hide_banner", "-version"]),
        Stdio::null(),
        Stdio::null(),
    )?
    .wait()?;
    match status.success() {
        true => Ok(()),
        false => Err(Error::MissingTool {
            tool: program,
            what,
        }),
    }
}

/// Collects a child's error output on a thread of its own (so that a chatty program never
/// blocks on a full pipe), at most [`STDERR_CAP`] bytes.
fn drain_stderr(child: &mut Child) -> std::thread::JoinHandle<String> {
    let stderr = child.stderr.take();
    std::thread::spawn(move || {
        let mut text = String::new();
        if let Some(e) = stderr {
            let _ = e.take(STDERR_CAP).read_to_string(&mut text);
        }
        text
    })
}

/// The error of a program that failed: its last lines of error output.
fn failed(program: &str, path: &std::path::Path, stderr: &str) -> Error {
    let tail: Vec<&str> = stderr.lines().rev().take(4).collect();
    let tail: Vec<&str> = tail.into_iter().rev().collect();
    Error::format(path, format!("{program} failed: {}", tail.join(" / ")))
}
