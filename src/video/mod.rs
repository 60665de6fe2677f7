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
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// What a user runs to get FFmpeg on Debian (the error names it).
pub const INSTALL: &str = "apt-get install ffmpeg";

/// The most of a program's error output kept for the message (its last lines matter).
const STDERR_CAP: u64 = 64 << 10;

/// The FFmpeg programs running now, by process id (each leads its own process group), so
/// that an interruption can stop them wherever the run waits on them ([`stop_all`]).
static RUNNING: Mutex<Vec<u32>> = Mutex::new(Vec::new());

/// A running FFmpeg program: registered in [`RUNNING`] until reaped, and killed (its
/// process group) and reaped when dropped before it ended.
pub(crate) struct Program {
    child: Child,
    reaped: bool,
}

impl Program {
    fn wait(&mut self) -> std::io::Result<ExitStatus> {
        let status = self.child.wait();
        self.reaped = true;
        forget(self.child.id());
        status
    }
}

impl std::ops::Deref for Program {
    type Target = Child;
    fn deref(&self) -> &Child {
        &self.child
    }
}

impl std::ops::DerefMut for Program {
    fn deref_mut(&mut self) -> &mut Child {
        &mut self.child
    }
}

impl Drop for Program {
    fn drop(&mut self) {
        if !self.reaped {
            let _ = self.child.kill();
            let _ = self.wait();
        }
    }
}

fn forget(pid: u32) {
    if let Ok(mut running) = RUNNING.lock() {
        running.retain(|&p| p != pid);
    }
}

/// Stops every FFmpeg program running now (SIGKILL to its process group): on Ctrl-C, so that
/// a stalled encode or decode, on which the run may be blocked in a write or a read, ends at
/// once; the blocked call then fails and the run stops as interrupted.
pub fn stop_all() {
    #[cfg(unix)]
    if let Ok(running) = RUNNING.lock() {
        for &pid in running.iter() {
            if let Ok(group) = i32::try_from(pid) {
                // SAFETY: kill(2) on a process group this process started and has not reaped
                // (a reaped one is forgotten first), so its id cannot have been reused.
                unsafe {
                    libc::kill(-group, libc::SIGKILL);
                }
            }
        }
    }
}

/// `program` (ffmpeg, ffprobe) with `args`, its stdin, stdout and stderr as given, in a
/// process group of its own: Ctrl-C at the terminal reaches chaoscope, which stops it, and
/// not FFmpeg, which would otherwise end the film mid-frame before chaoscope can say why.
fn spawn(
    program: &'static str,
    what: &'static str,
    args: &[std::ffi::OsString],
    stdin: Stdio,
    stdout: Stdio,
) -> Result<Program> {
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
    // Registered while the lock is held, so that stop_all never misses a program started
    // as it runs.
    let mut running = RUNNING.lock().unwrap_or_else(|e| e.into_inner());
    let child = c.spawn().map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => Error::MissingTool {
            tool: program,
            what,
            install: INSTALL,
        },
        _ => Error::Io(e),
    })?;
    running.push(child.id());
    Ok(Program {
        child,
        reaped: false,
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
            install: INSTALL,
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
