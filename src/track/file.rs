//! The tracked CSV, written by `track` and read by `forecast --video` (where the positions
//! lie in the film, and which film they came from) and by the tests (the measured rows):
//! its one owner. The comments above the header carry the placement and the film as
//! `# key = value` lines (numbers, then an optional remark in parentheses); `fit` and
//! `forecast` read the rows as any positions file (the fit room's reader), skipping them.
//!
//! ```text
//! # chaoscope track film.mp4 --l1 0.3
//! # pivot_px = 640.040 324.040
//! # arms_px = 200.018 159.991
//! # pixels_per_metre = 1998.5234
//! # up = 0.000000000 -1.000000000 (the picture's: ...)
//! # film_px = 1280 720
//! # film_frames = 600
//! # film_seconds = 5.990000 (the last frame's time from the first)
//! t,x1,y1,x2,y2,seen1,seen2,sx1,sy1,sx2,sy2,streak1,streak2
//! ```

use std::io::Write;
use std::path::Path;

use super::{Mark, Tracked};
use crate::error::{Error, Result};

/// One row of tracked data (a camera frame's): time (s) and positions (m) of both masses, y up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackedRow {
    pub t: f64,
    pub x1: f64,
    pub y1: f64,
    pub x2: f64,
    pub y2: f64,
}

/// The key of a tracked file's `# release = T` comment: where free motion begins (s).
pub const RELEASE: &str = "release";

/// The metre scale of positions in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PixelScale {
    PerMetre(f64),
    /// From the motion: a rigid pendulum's swing fixes l1/g in seconds, so at the file's
    /// frame rate and the stated g its upper arm's length in metres (src/fit/identify).
    FromMotion,
}

/// The columns' names.
pub const HEADER: &str = "t,x1,y1,x2,y2,seen1,seen2,sx1,sy1,sx2,sy2,streak1,streak2";

/// Where a tracked file's positions lie in its film's picture: the pivot (px), the scale
/// (px per metre) and the world's up in the picture (a unit vector, px axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub pivot: (f64, f64),
    pub pixels_per_metre: f64,
    pub up: (f64, f64),
}

impl Placement {
    /// Metres (x along the world's right, y up, from the pivot) to the picture's pixels.
    pub fn pixels(&self, x: f64, y: f64) -> (f64, f64) {
        let ((cx, cy), ppm, (ux, uy)) = (self.pivot, self.pixels_per_metre, self.up);
        // The world's right in the picture: up turned a quarter clockwise as seen.
        (cx + ppm * (-x * uy + y * ux), cy + ppm * (x * ux + y * uy))
    }
}

/// The film a track was made from: its picture size (px), its frames, the last frame's time
/// from the first (s), and what its first frames hold ([`Digest`]; None in a file tracked
/// before digests were recorded).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub seconds: f64,
    pub digest: Option<Digest>,
}

/// The identity of a film's pictures: FNV-1a (64 bits) of its first [`DIGEST_FRAMES`]
/// frames as decoded, at `bytes_per_pixel` (1: luma, 3: RGB, as the track read them). Two
/// takes of one scene with the same size, frames and length differ here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Digest {
    pub value: u64,
    pub bytes_per_pixel: u8,
}

/// Frames a [`Digest`] covers.
pub const DIGEST_FRAMES: usize = 3;

impl Digest {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    /// The digest of no frames yet.
    pub fn start(bytes_per_pixel: u8) -> Digest {
        Digest {
            value: Self::OFFSET,
            bytes_per_pixel,
        }
    }

    /// Adds a frame's bytes.
    pub fn add(&mut self, frame: &[u8]) {
        for &b in frame {
            self.value = (self.value ^ b as u64).wrapping_mul(Self::PRIME);
        }
    }

    /// The digest of the film at `path`, read as the track read it.
    pub fn of_film(path: &Path, bytes_per_pixel: u8) -> Result<Digest> {
        use crate::video::{Decoder, Pixels};
        let pixels = match bytes_per_pixel {
            1 => Pixels::Gray,
            _ => Pixels::Rgb,
        };
        let mut decoder = Decoder::open(path, pixels)?;
        let (mut digest, mut frame) = (Digest::start(bytes_per_pixel), Vec::new());
        for _ in 0..DIGEST_FRAMES {
            if decoder.next_frame(&mut frame)?.is_none() {
                break;
            }
            digest.add(&frame);
        }
        Ok(digest)
    }
}

impl Film {
    pub fn of(probe: &crate::video::Probe) -> Film {
        Film {
            width: probe.width,
            height: probe.height,
            frames: probe.times.len(),
            seconds: probe.times.last().copied().unwrap_or(0.0),
            digest: None,
        }
    }

    fn describe(&self) -> String {
        format!(
            "{} x {} px, {} frames over {:.3} s",
            self.width, self.height, self.frames, self.seconds
        )
    }

    /// That the film at `path` (probed as `other`, about to be drawn on) is this one: its
    /// size and frames the same, its length within a millisecond (the containers' timestamps
    /// are exact to far less), and its first frames the same where this film's digest is
    /// known. Else an error naming `field` and both films.
    pub fn check_film(&self, other: &Film, path: &Path, field: &'static str) -> Result<()> {
        self.check(other, field)?;
        let Some(digest) = self.digest else {
            return Ok(());
        };
        let theirs =
            Digest::of_film(path, digest.bytes_per_pixel).map_err(|e| e.as_input(field))?;
        match theirs == digest {
            true => Ok(()),
            false => Err(Error::invalid(
                field,
                format!(
                    "the film's first {DIGEST_FRAMES} frames are not those the track was made from (another take of the same size and length?): draw on the film it was tracked from"
                ),
            )),
        }
    }

    fn check(&self, other: &Film, field: &'static str) -> Result<()> {
        let same = self.width == other.width
            && self.height == other.height
            && self.frames == other.frames
            && (self.seconds - other.seconds).abs() < 1e-3;
        match same {
            true => Ok(()),
            false => Err(Error::invalid(
                field,
                format!(
                    "the film is {}, but the track was made from a film of {}: draw on the film it was tracked from",
                    other.describe(),
                    self.describe()
                ),
            )),
        }
    }
}

/// What a tracked file's comments say: the placement, and the film (None in a file tracked
/// before films were recorded).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Header {
    pub placement: Placement,
    pub film: Option<Film>,
    /// Where free motion begins (s), where `track` saw the pendulum let go.
    pub release: Option<f64>,
}

/// Writes `t`, tracked from `film` by `command`, as the tracked CSV.
pub fn write(w: &mut impl Write, t: &Tracked, film: &Film, command: &str) -> Result<()> {
    let g = t.geometry;
    writeln!(w, "# {command}")?;
    writeln!(w, "# pivot_px = {:.3} {:.3}", g.pivot.0, g.pivot.1)?;
    writeln!(w, "# arms_px = {:.3} {:.3}", g.r1, g.r2)?;
    writeln!(w, "# pixels_per_metre = {:.4}", t.pixels_per_metre)?;
    writeln!(
        w,
        "# up = {:.9} {:.9} ({})",
        t.up.direction.0,
        t.up.direction.1,
        match t.up.rest {
            Some((a, b)) => format!(
                "from the pendulum at rest {a:.3}..{b:.3} s, {:.3} degrees counter-clockwise from the picture's",
                t.up.tilt_degrees
            ),
            None => "the picture's: the film never shows the pendulum hanging at rest".into(),
        }
    )?;
    if let Some(release) = t.release {
        writeln!(
            w,
            "# {} = {release:.6} (s: the last still frame before the pendulum swings; fit and forecast read from it)",
            RELEASE
        )?;
    }
    writeln!(w, "# film_px = {} {}", film.width, film.height)?;
    writeln!(w, "# film_frames = {}", film.frames)?;
    writeln!(
        w,
        "# film_seconds = {:.6} (the last frame's time from the first; t counts from the first)",
        film.seconds
    )?;
    if let Some(d) = film.digest {
        writeln!(
            w,
            "# film_digest = {} {} {} (FNV-1a of the first {DIGEST_FRAMES} frames as decoded: its two 32-bit halves, and bytes a pixel)",
            d.value >> 32,
            d.value & 0xffff_ffff,
            d.bytes_per_pixel
        )?;
    }
    writeln!(w, "{HEADER}")?;
    for r in &t.rows {
        let pos = |m: Option<Mark>| match m {
            Some(m) => format!("{:.6},{:.6}", m.x, m.y),
            None => ",".into(),
        };
        let seen = |m: Option<Mark>| match m {
            Some(m) if m.bridged => "bridged",
            Some(_) => "measured",
            None => "hidden",
        };
        let err = |m: Option<Mark>| match m {
            Some(m) => format!("{:.2e},{:.2e}", m.sx, m.sy),
            None => ",".into(),
        };
        let streak = |m: Option<Mark>| match m {
            Some(m) if !m.bridged => format!("{:.5}", m.streak),
            _ => String::new(),
        };
        writeln!(
            w,
            "{:.6},{},{},{},{},{},{},{},{}",
            r.t,
            pos(r.m1),
            pos(r.m2),
            seen(r.m1),
            seen(r.m2),
            err(r.m1),
            err(r.m2),
            streak(r.m1),
            streak(r.m2)
        )?;
    }
    Ok(())
}

/// What `text`'s comments say (None: it is no tracked file, or says nothing of where it
/// lies in its film). A file tracked by an earlier version states its placement in prose
/// ("# pivot at (X, Y) px, ..., P px per metre", "# up in the picture (X, Y): ...") and no
/// film; that is read too.
pub fn read_header(text: &str) -> Option<Header> {
    let values = crate::input::comment_values(text);
    let get = |key: &str, n: usize| -> Option<Vec<f64>> {
        values
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.clone())
            .filter(|v| v.len() == n && v.iter().all(|x| x.is_finite()))
    };
    let unit = |v: &[f64]| ((v[0].hypot(v[1]) - 1.0).abs() < 1e-6).then_some((v[0], v[1]));
    let placement = match (get("pivot_px", 2), get("pixels_per_metre", 1)) {
        (Some(p), Some(s)) if s[0] > 0.0 => Placement {
            pivot: (p[0], p[1]),
            pixels_per_metre: s[0],
            up: match get("up", 2) {
                Some(u) => unit(&u)?,
                None => (0.0, -1.0),
            },
        },
        _ => earlier_placement(text)?,
    };
    let film = match (
        get("film_px", 2),
        get("film_frames", 1),
        get("film_seconds", 1),
    ) {
        (Some(px), Some(n), Some(s)) if px.iter().chain(&n).all(|&x| x >= 0.0) => Some(Film {
            width: px[0] as u32,
            height: px[1] as u32,
            frames: n[0] as usize,
            seconds: s[0],
            digest: get("film_digest", 3)
                .filter(|d| d[..2].iter().all(|&h| (0.0..=u32::MAX as f64).contains(&h)))
                .filter(|d| d[2] == 1.0 || d[2] == 3.0)
                .map(|d| Digest {
                    value: (d[0] as u64) << 32 | d[1] as u64,
                    bytes_per_pixel: d[2] as u8,
                }),
        }),
        _ => None,
    };
    Some(Header {
        placement,
        film,
        release: get(RELEASE, 1).map(|v| v[0]),
    })
}

/// The placement in prose, as earlier versions wrote it.
fn earlier_placement(text: &str) -> Option<Placement> {
    let numbers = |start: &str| -> Option<Vec<f64>> {
        let line = text.lines().find(|l| l.starts_with(start))?;
        Some(
            line[start.len()..]
                .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
                .filter_map(|w| w.parse().ok())
                .collect(),
        )
    };
    let up = match numbers("# up in the picture (").as_deref() {
        Some(&[x, y, ..]) if (x.hypot(y) - 1.0).abs() < 1e-6 => (x, y),
        Some(_) => return None,
        None => (0.0, -1.0),
    };
    match numbers("# pivot at (")?[..] {
        [x, y, _, _, ppm, ..] if ppm > 0.0 => Some(Placement {
            pivot: (x, y),
            pixels_per_metre: ppm,
            up,
        }),
        _ => None,
    }
}

/// The [`Header`] of the tracked file at `path`; an error naming `field` where it says
/// nothing of where it lies in its film.
pub fn header_of(path: &Path, field: &'static str) -> Result<Header> {
    let text = crate::input::read_text("file", path, crate::input::CSV_CAP)?;
    read_header(&text).ok_or_else(|| {
        Error::invalid(
            field,
            "the tracked file says nothing of where it lies in the film: draw on the film a CSV that `track` wrote",
        )
    })
}

/// A mass's measured place in a tracked CSV (m) and its stated standard errors (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    pub x: f64,
    pub y: f64,
    pub sx: f64,
    pub sy: f64,
}

impl Measured {
    pub fn at(&self) -> (f64, f64) {
        (self.x, self.y)
    }
}

/// A row of a tracked CSV: its time (s) and the upper and lower mass as measured, None
/// where it was not.
pub type CsvRow = (f64, Option<Measured>, Option<Measured>);

/// Reads back the measured positions of a tracked CSV (its header and `seen` columns): a
/// mass hidden, or placed by the model (`bridged`), is None.
pub fn read_rows(path: &Path) -> Result<Vec<CsvRow>> {
    let text = crate::input::read_text("file", path, crate::input::CSV_CAP)?;
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let bad = |what: &str| Error::format(path, format!("not a CSV that track wrote: {what}"));
    if lines.next() != Some(HEADER) {
        return Err(bad("its header"));
    }
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            if c.len() != 13 {
                return Err(bad("a row of other than 13 fields"));
            }
            let at = |k: usize, seen: &str| -> Result<Option<Measured>> {
                match seen {
                    "measured" => {
                        let v = |s: &str| s.parse::<f64>().map_err(|_| bad("a position"));
                        // x, y at k and k + 1; their errors 6 columns on.
                        Ok(Some(Measured {
                            x: v(c[k])?,
                            y: v(c[k + 1])?,
                            sx: v(c[k + 6])?,
                            sy: v(c[k + 7])?,
                        }))
                    }
                    // Not seen: no position, not even a guessed one.
                    "hidden" if c[k].is_empty() && c[k + 1].is_empty() => Ok(None),
                    "bridged" => Ok(None),
                    _ => Err(bad("a seen cell, or a hidden mass's position")),
                }
            };
            let t = c[0].parse::<f64>().map_err(|_| bad("a time"))?;
            Ok((t, at(1, c[5])?, at(3, c[6])?))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::{Geometry, TrackRow, Up};

    /// What `write` writes, `read_header` and `read_rows` read back: the placement, the film
    /// and the measured rows (a hidden or bridged mass as None); a file in the earlier prose
    /// is read too.
    #[test]
    fn the_tracked_file_reads_back_what_was_written() {
        let mark = |x: f64, bridged: bool| Mark {
            x,
            y: -0.25,
            sx: 1e-5,
            sy: 2e-5,
            streak: 0.001,
            px: (0.0, 0.0),
            bridged,
        };
        let tracked = Tracked {
            rows: vec![
                TrackRow {
                    t: 0.0,
                    m1: Some(mark(0.1, false)),
                    m2: Some(mark(0.2, false)),
                },
                TrackRow {
                    t: 0.033333,
                    m1: Some(mark(0.11, false)),
                    m2: None,
                },
                TrackRow {
                    t: 0.066667,
                    m1: Some(mark(0.12, true)),
                    m2: Some(mark(0.22, false)),
                },
            ],
            geometry: Geometry {
                pivot: (640.04, 324.04),
                r1: 200.018,
                r2: 159.991,
            },
            pixels_per_metre: 1998.5234,
            up: Up {
                direction: (0.6, -0.8),
                tilt_degrees: 36.87,
                rest: Some((0.0, 1.0)),
            },
            still: Vec::new(),
            release: None,
            pivot_marker: None,
        };
        let film = Film {
            width: 1280,
            height: 720,
            frames: 3,
            seconds: 0.066667,
            // The digest's high half and low half both full: read back to the bit.
            digest: Some(Digest {
                value: 0xfedc_ba98_7654_3210,
                bytes_per_pixel: 3,
            }),
        };
        let mut text = Vec::new();
        write(&mut text, &tracked, &film, "chaoscope track 'a b.mp4'").unwrap();
        let text = String::from_utf8(text).unwrap();
        let header = read_header(&text).expect("a header");
        assert_eq!(header.film, Some(film));
        assert_eq!(header.placement.pivot, (640.04, 324.04));
        assert_eq!(header.placement.pixels_per_metre, 1998.5234);
        assert_eq!(header.placement.up, (0.6, -0.8));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        std::fs::write(&path, &text).unwrap();
        type Places = (f64, Option<(f64, f64)>, Option<(f64, f64)>);
        let rows: Vec<Places> = read_rows(&path)
            .unwrap()
            .into_iter()
            .map(|(t, a, b)| (t, a.map(|m| m.at()), b.map(|m| m.at())))
            .collect();
        assert_eq!(
            rows,
            vec![
                (0.0, Some((0.1, -0.25)), Some((0.2, -0.25))),
                (0.033333, Some((0.11, -0.25)), None),
                (0.066667, None, Some((0.22, -0.25))),
            ]
        );
        let earlier = "# chaoscope track x.mp4\n# pivot at (640.012, 323.950) px, upper arm 218.160 px, lower arm 141.810 px, 727.2000 px per metre; t from the film's first frame\nt,x1\n";
        let h = read_header(earlier).unwrap();
        assert_eq!(
            (h.placement.pivot, h.placement.pixels_per_metre, h.film),
            ((640.012, 323.95), 727.2, None)
        );
        assert!(read_header("t,x1,y1,x2,y2\n0,1,2,3,4\n").is_none());
        // One metre right of the pivot and one up, in the picture's frame.
        let placed = h.placement;
        assert_eq!(placed.pixels(1.0, 1.0), (640.012 + 727.2, 323.95 - 727.2));
        // A camera turned a quarter counter-clockwise: the world's up points left in the
        // picture, and its right points up.
        let turned =
            format!("{earlier}# up in the picture (-1.000000000, 0.000000000): from the rest\n");
        let placed = read_header(&turned).unwrap().placement;
        assert_eq!(placed.up, (-1.0, 0.0));
        assert_eq!(placed.pixels(1.0, 0.0), (640.012, 323.95 - 727.2));
        assert_eq!(placed.pixels(0.0, 1.0), (640.012 - 727.2, 323.95));
    }
}
