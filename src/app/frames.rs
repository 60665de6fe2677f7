//! A film of maps, made one way whatever varies between its frames (a sweep's parameter,
//! a zoom's view): numbered PNGs in one folder, each carrying the single map's command that
//! makes it alone. A run keeps the frames an earlier run of the same film finished (resume),
//! makes a damaged frame again, refuses a folder of another film's frames, shares the frames
//! out between tasks (`tile`), and encodes the film and the frames' table from the PNGs.

use std::cell::RefCell;
use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::film::{FilmSpec, Format};
use crate::engine::RunInfo;
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::{self, Outputs, Picture};

/// Frame `k`'s file in a film's folder of frames: the name each run resumes by and encodes
/// from.
pub fn frame_name(k: u32) -> String {
    format!("frame_{k:04}.png")
}

/// The frames' table's name in the folder.
pub const TABLE: &str = "frames.csv";

/// The text a frame's PNG carries besides its map's own: which frame of how many, and its
/// pixels' digest ([`digest`]), so that a frame changed since it was written is made again
/// rather than kept.
const FRAME_KEY: &str = "chaoscope:frame";
const PIXELS_KEY: &str = "chaoscope:pixels";
const COMMAND_KEY: &str = "chaoscope:command";

/// A frame's pixels as 16 hex digits: FNV-1a over its bytes (stable across Rust versions and
/// machines, which a resume needs; a checksum against damage, not against intent).
fn digest(rgb: &[u8]) -> String {
    let hash = rgb.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// The PNG text chunk `key`, if the frame has it.
pub fn text<'a>(png: &'a render::Png, key: &str) -> Option<&'a str> {
    png.text
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

/// One frame as made: its picture, the path that ran it, and the text it carries besides its
/// provenance.
pub struct Made {
    pub picture: Picture,
    pub info: RunInfo,
    pub text: Vec<(String, String)>,
}

/// What a film's frames are: how each is named by its command and made. The rest of a run
/// (resume, damage, tiles, the film and the table) is [`FrameSet`]'s.
pub trait Frames {
    /// Frame `k`'s own command: it makes that frame alone, goes into its PNG and tells this
    /// film's frames from another's when a run resumes.
    fn command(&self, k: u32) -> String;
    /// Whether frame `k`, found finished with this film's command, may be kept as it is (it
    /// may lack what this run asks for besides, such as a judgement); it may finish what
    /// the picture does not hold (a data store's frame).
    fn keep(&self, _k: u32, _png: &render::Png, _monitor: &Monitor) -> Result<bool> {
        Ok(true)
    }
    /// Frame `k` made.
    fn make(&self, k: u32, monitor: &Monitor) -> Result<Made>;
}

/// One film's folder of frames.
pub struct FrameSet<'a> {
    /// What the film is, in the refusal of a folder of another's frames ("sweep", "zoom").
    pub of: &'static str,
    pub output: &'a Path,
    pub count: u32,
    /// Make only frames k with k % COUNT == INDEX (no film): `(INDEX, COUNT)`.
    pub tile: Option<(u32, u32)>,
    /// The film the frames make, and the formats it may take.
    film: &'a FilmSpec,
    formats: &'static [Format],
    damaged: RefCell<BTreeSet<u32>>,
}

/// What a run of a frame set did.
pub struct Run {
    pub made: u32,
    pub kept: u32,
    /// This task's frames' files.
    pub files: Vec<PathBuf>,
    /// A notice naming the frames found damaged and made again, if any were.
    pub damaged: Option<String>,
}

impl<'a> FrameSet<'a> {
    /// The set, its tile checked (errors name `tile`).
    pub fn new(
        of: &'static str,
        output: &'a Path,
        count: u32,
        tile: Option<(u32, u32)>,
        film: &'a FilmSpec,
        formats: &'static [Format],
    ) -> Result<Self> {
        if let Some((index, count)) = tile
            && (count == 0 || index >= count)
        {
            return Err(Error::invalid(
                "tile",
                format!("{index}/{count}: INDEX/COUNT with 0 <= INDEX < COUNT"),
            ));
        }
        Ok(FrameSet {
            of,
            output,
            count,
            tile,
            film,
            formats,
            damaged: RefCell::new(BTreeSet::new()),
        })
    }

    pub fn path(&self, k: u32) -> PathBuf {
        self.output.join(frame_name(k))
    }

    /// That the folder takes the frames and the table (errors name `output`) and, for a
    /// whole run, that the film can be made into its file (`film`), which is none of them: in
    /// the folder under a name of its own (its default place) it is one of the folder's
    /// files, else one of the run's outputs beside them (through `./`, `..` and links alike).
    pub fn check(&self) -> Result<()> {
        let mut names: Vec<String> = (0..self.count).map(frame_name).collect();
        names.push(TABLE.into());
        let films = [("film", self.film.path.as_path())];
        let mut also: &[_] = &[];
        if self.tile.is_none() {
            let name = self.film.path.file_name().map(|n| n.to_string_lossy());
            match name {
                Some(name)
                    if self.film.path.parent() == Some(self.output)
                        && !names.iter().any(|n| *n == name) =>
                {
                    names.push(name.into_owned())
                }
                _ => also = &films,
            }
        }
        super::checks::check_directory("output", self.output, &names, also, &[])?;
        if self.tile.is_none() {
            self.film.validate("film", self.formats)?;
        }
        Ok(())
    }

    /// Frame `k`'s PNG as an earlier run left it, without judging whose it is: None where
    /// there is none, or where it is damaged (cut short, unreadable, its pixels changed since
    /// written: it is made again and said so). Anything but a file there is refused when
    /// written.
    pub fn read(&self, k: u32) -> Result<Option<render::Png>> {
        let path = self.path(k);
        if !path.exists() {
            return Ok(None);
        }
        let png = match render::read_png(&path) {
            Ok(png) => png,
            Err(Error::Format(_)) => {
                self.damaged.borrow_mut().insert(k);
                return Ok(None);
            }
            Err(e) => return Err(e),
        };
        if text(&png, PIXELS_KEY).is_some_and(|d| d != digest(&png.rgb)) {
            self.damaged.borrow_mut().insert(k);
            return Ok(None);
        }
        Ok(Some(png))
    }

    /// Frame `k` of this film, finished by an earlier run, to keep; a frame of another film
    /// is refused (naming `output`).
    pub fn kept(
        &self,
        k: u32,
        frames: &dyn Frames,
        monitor: &Monitor,
    ) -> Result<Option<render::Png>> {
        let Some(png) = self.read(k)? else {
            return Ok(None);
        };
        if text(&png, COMMAND_KEY) != Some(frames.command(k).as_str()) {
            return Err(Error::invalid(
                "output",
                format!(
                    "{} holds frames of a different {}; choose another directory",
                    self.output.display(),
                    self.of
                ),
            ));
        }
        Ok(frames.keep(k, &png, monitor)?.then_some(png))
    }

    /// This task's frames: each kept or made and written.
    pub fn make(&self, frames: &dyn Frames, monitor: &Monitor) -> Result<Run> {
        std::fs::create_dir_all(self.output)?;
        let todo: Vec<u32> = (0..self.count)
            .filter(|&k| self.tile.is_none_or(|(index, count)| k % count == index))
            .collect();
        let quiet = monitor.quiet();
        monitor.start("frames", todo.len() as u64);
        let (mut made, mut kept) = (0, 0);
        for &k in &todo {
            monitor.check()?;
            if self.kept(k, frames, &quiet)?.is_some() {
                kept += 1;
                monitor.advance(1);
                continue;
            }
            let frame = frames.make(k, &quiet)?;
            let picture = &frame.picture;
            let mut meta = render::provenance(frames.command(k), &frame.info);
            meta.extend(frame.text);
            meta.push((FRAME_KEY.into(), format!("{k} of {}", self.count)));
            meta.push((PIXELS_KEY.into(), digest(&picture.rgb)));
            let size = (picture.width, picture.height);
            render::write_png(&self.path(k), size, &picture.rgb, &meta)?;
            made += 1;
            monitor.advance(1);
        }
        monitor.finish();
        let damaged = self.damaged.borrow();
        let damaged = (!damaged.is_empty()).then(|| {
            let names: Vec<String> = damaged.iter().map(|&k| frame_name(k)).collect();
            format!(
                "{} frames were damaged (unreadable, or their pixels changed since they were written) and were made again: {}",
                damaged.len(),
                names.join(", ")
            )
        });
        Ok(Run {
            made,
            kept,
            files: todo.iter().map(|&k| self.path(k)).collect(),
            damaged,
        })
    }

    /// The film from the frame files (those of earlier runs included), read one at a time,
    /// and the frames' table beside it: `columns` its header, `row(k, frame)` frame k's line.
    /// `command` reproduces the whole film.
    pub fn encode(
        &self,
        command: &str,
        info: &RunInfo,
        columns: &str,
        mut row: impl FnMut(u32, &render::Png) -> String,
        monitor: &Monitor,
    ) -> Result<()> {
        let first = render::read_png(&self.path(0))?;
        let size = (first.width, first.height);
        drop(first);
        let mut rows = Vec::with_capacity(self.count as usize);
        let mut files = Outputs::new();
        monitor.start("film", u64::from(self.count));
        super::film::write(
            &mut files,
            self.film,
            self.film.format("film", self.formats)?,
            size,
            self.count as usize,
            &render::provenance(command.to_string(), info),
            |k| {
                monitor.check()?;
                let path = self.path(k as u32);
                let png = render::read_png(&path)?;
                if (png.width, png.height) != size {
                    return Err(Error::format(&path, "a frame of another size than frame 0"));
                }
                rows.push(row(k as u32, &png));
                monitor.advance(1);
                Ok(png.rgb)
            },
        )?;
        monitor.finish();
        files.write(&self.output.join(TABLE), |w| {
            writeln!(w, "# {command}")?;
            writeln!(w, "frame,{columns}")?;
            for (k, line) in rows.iter().enumerate() {
                writeln!(w, "{k},{line}")?;
            }
            Ok(())
        })?;
        files.commit(monitor)
    }
}
