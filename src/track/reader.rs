//! The reader of a tracked file: `track`'s CSV, a spreadsheet's or Tracker's export, as rows
//! in seconds and metres (y up). `fit`, `forecast` and the bridge read through it.

use std::path::Path;

use super::file::{PixelScale, RELEASE, TrackedRow};
use crate::error::{Error, Result};

/// Smallest time step (s) between tracked rows.
const MIN_TIME_STEP: f64 = 1e-6;

/// Times beyond this many seconds (eleven days) are a unit mistake for a tracked pendulum
/// (issue 25's audit: times of 1e300 s were fitted and reported as nonsense).
const MAX_TIME: f64 = 1e6;

/// Positions beyond this many metres are a unit mistake (arms are at most 1e4 m, as --l1
/// allows); 1e300 m overflowed the fit's energies into NaN arm lengths.
const MAX_POSITION: f64 = 1e4;

fn bad(path: &Path, line: usize, what: String) -> Error {
    Error::invalid("file", format!("{}:{line}: {what}", path.display()))
}

/// How a tracked file's numbers become seconds and metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Units {
    /// Positions in pixels as images count them (x right, y down), this many to a metre, or
    /// the scale the motion implies under gravity; None: metres, y up.
    pub pixels_per_metre: Option<PixelScale>,
    /// Rows numbered by a `frame` column, this many frames a second; None: a `t` column in
    /// seconds.
    pub frame_rate: Option<f64>,
    /// Read the rows before the release as well, where `track` found one (its file says
    /// `# release = T`): the rest and the lift by hand are not free motion.
    pub before_release: bool,
    /// Pixels whose y runs up (Tracker's own frame, and plots'), not down as images count it.
    pub y_up: bool,
}

/// The columns a tracked file may name, beside the positions x1, y1, x2, y2: the time `t`
/// (s) or the `frame` number, and a pivot `x0`, `y0` that moves (positions are taken
/// relative to it, row by row).
const COLUMNS: [&str; 8] = ["t", "frame", "x0", "y0", "x1", "y1", "x2", "y2"];

/// What the header says: where each value stands and how the lines are written.
struct Header {
    line: usize,
    names: Vec<String>,
    separator: char,
    /// Tracker's export of two point masses: unmarked steps are skipped, rows may be short.
    tracker: bool,
    /// The time (or frame) and x1, y1, x2, y2.
    cols: [usize; 5],
    /// A moving pivot's x0, y0.
    pivot: Option<[usize; 2]>,
    /// `track`'s seen1, seen2: only rows where both masses were measured are read.
    seen: Vec<usize>,
}

/// Spreadsheets in much of the world separate by `;` (or tabs) and write decimal commas.
fn separator_of(line: &str) -> char {
    match (line.contains(';'), line.contains('\t')) {
        (true, _) => ';',
        (false, true) => '\t',
        _ => ',',
    }
}

fn split(line: &str) -> Vec<String> {
    line.split(separator_of(line))
        .map(|c| c.trim().to_string())
        .collect()
}

/// Whether `names` is Tracker's header of two point masses: `t`, then x and y twice or more
/// (the upper mass's track first).
fn tracker_columns(names: &[String]) -> bool {
    names.first().is_some_and(|n| n == "t")
        && names.iter().filter(|n| *n == "x").count() >= 2
        && names.iter().filter(|n| *n == "y").count() >= 2
}

impl Header {
    /// The header among `lines` (comments and blank lines gone), which it leaves at the
    /// first data row.
    fn read<'a>(
        lines: &mut std::iter::Peekable<impl Iterator<Item = (usize, &'a str)>>,
        path: &Path,
        units: &Units,
    ) -> Result<Header> {
        let (mut line, mut header) = lines
            .next()
            .ok_or_else(|| bad(path, 1, "no header line (t,x1,y1,x2,y2)".into()))?;
        // Tracker's export of two point masses together: a line of the tracks' names over
        // `t x y x y`, or that line alone.
        let first = split(header);
        let numbered = first.iter().any(|n| n == "x1");
        let named_above = !first.iter().any(|n| n == "t" || n == "frame")
            && lines
                .peek()
                .is_some_and(|(_, next)| tracker_columns(&split(next)));
        if named_above {
            (line, header) = lines.next().expect("the line peeked");
        }
        let tracker = named_above || (!numbered && tracker_columns(&first));
        let mut names = split(header);
        if tracker {
            // The first x and y are the first track's (the upper mass), the next the second's.
            for (name, numbered) in [("x", ["x1", "x2"]), ("y", ["y1", "y2"])] {
                for (k, column) in names.iter_mut().filter(|n| *n == name).take(2).enumerate() {
                    *column = numbered[k].to_string();
                }
            }
        }
        let mut h = Header {
            line,
            separator: separator_of(header),
            tracker,
            cols: [0; 5],
            pivot: None,
            seen: Vec::new(),
            names,
        };
        h.check_names(path)?;
        h.cols = [
            h.time(path, units)?,
            h.column(path, "x1")?,
            h.column(path, "y1")?,
            h.column(path, "x2")?,
            h.column(path, "y2")?,
        ];
        h.pivot = match (h.find("x0"), h.find("y0")) {
            (Some(x), Some(y)) => Some([x, y]),
            (None, None) => None,
            _ => {
                return Err(bad(
                    path,
                    line,
                    "a moving pivot takes both columns `x0` and `y0`".into(),
                ));
            }
        };
        h.seen = ["seen1", "seen2"]
            .iter()
            .filter_map(|s| h.find(s))
            .collect();
        Ok(h)
    }

    fn find(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    fn column(&self, path: &Path, name: &str) -> Result<usize> {
        self.find(name).ok_or_else(|| {
            bad(
                path,
                self.line,
                format!("the header has no column `{name}` (needs t, x1, y1, x2, y2)"),
            )
        })
    }

    /// The time's column: `t` in seconds, or `frame` where a frame rate is given.
    fn time(&self, path: &Path, units: &Units) -> Result<usize> {
        match (self.find("t"), self.find("frame"), units.frame_rate) {
            (Some(t), _, None) => Ok(t),
            (_, Some(frame), Some(_)) => Ok(frame),
            (None, Some(_), None) => Err(Error::invalid(
                "frame_rate",
                format!(
                    "{} numbers its rows by `frame`, with no `t`: give the frame rate (frames a second) to make them times",
                    path.display()
                ),
            )),
            (Some(_), None, Some(_)) => Err(Error::invalid(
                "frame_rate",
                format!(
                    "{} has times (`t`, s) and no `frame` column: a frame rate is for a file that numbers its rows by frame; leave it out",
                    path.display()
                ),
            )),
            (None, _, _) => self.column(path, "t"),
        }
    }

    /// A column named twice would be read from its first copy silently. Only the columns
    /// read are looked at, each name once (a header of 200,000 names costs one pass).
    fn check_names(&self, path: &Path) -> Result<()> {
        let mut first: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        for (k, name) in self.names.iter().enumerate() {
            if !COLUMNS.contains(&name.as_str()) {
                continue;
            }
            if let Some(&j) = first.get(name.as_str()) {
                return Err(bad(
                    path,
                    self.line,
                    format!(
                        "the header names `{name}` twice (columns {} and {})",
                        j + 1,
                        k + 1
                    ),
                ));
            }
            first.insert(name.as_str(), k);
        }
        Ok(())
    }

    /// Line `n`'s row in seconds and metres (y up), None where it holds no position to fit
    /// (a step Tracker left unmarked, a mass `track` did not see).
    fn row(&self, n: usize, line: &str, path: &Path, units: &Units) -> Result<Option<TrackedRow>> {
        let decimal_comma = self.separator != ',';
        let cells: Vec<String> = line
            .split(self.separator)
            .map(|c| match decimal_comma {
                true => c.trim().replace(',', "."),
                false => c.trim().to_string(),
            })
            .collect();
        if self.tracker
            && self
                .cols
                .iter()
                .any(|&c| cells.get(c).is_none_or(|c| c.is_empty()))
        {
            return Ok(None);
        }
        // A row of more or fewer fields than the header has its values under other columns'
        // names (a decimal comma, a cell left out).
        if !self.tracker && cells.len() != self.names.len() {
            return Err(bad(
                path,
                n,
                format!(
                    "{} fields where the header has {}",
                    cells.len(),
                    self.names.len()
                ),
            ));
        }
        if self.seen.iter().any(|&c| cells[c] != "measured") {
            return Ok(None);
        }
        let number = |c: usize| -> Result<f64> {
            let cell = &cells[c];
            cell.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    bad(
                        path,
                        n,
                        format!("`{cell}` in column `{}` is not a number", self.names[c]),
                    )
                })
        };
        let mut v = [0.0; 5];
        for (k, &c) in self.cols.iter().enumerate() {
            v[k] = number(c)?;
        }
        let origin = match self.pivot {
            Some([x, y]) => [number(x)?, number(y)?],
            None => [0.0, 0.0],
        };
        if let Some(rate) = units.frame_rate {
            v[0] /= rate;
        }
        // Pixels count y down (unless the file's run up); metres here count it up.
        let down = if units.y_up { 1.0 } else { -1.0 };
        let (scale, flip) = match units.pixels_per_metre {
            None => (1.0, 1.0),
            Some(PixelScale::PerMetre(p)) => (1.0 / p, down),
            Some(PixelScale::FromMotion) => (1.0, down),
        };
        for (k, x) in v.iter_mut().enumerate().skip(1) {
            let along = match k % 2 {
                1 => *x - origin[0],
                _ => flip * (*x - origin[1]),
            };
            *x = along * scale;
        }
        if let Some(k) = (1..5).find(|&k| v[k].abs() > MAX_POSITION) {
            return Err(bad(
                path,
                n,
                format!(
                    "{:e} m in column `{}` is beyond {MAX_POSITION:e} m from the origin: are the positions in metres?",
                    v[k], self.names[self.cols[k]]
                ),
            ));
        }
        Ok(Some(TrackedRow {
            t: v[0],
            x1: v[1],
            y1: v[2],
            x2: v[3],
            y2: v[4],
        }))
    }
}

/// A row's time: within the times a tracked pendulum has, after the previous row's by a
/// camera's step at least (steps below a microsecond are a unit mistake, and their velocities
/// and energies overflow).
fn check_time(t: f64, previous: Option<f64>, n: usize, path: &Path) -> Result<()> {
    if t.abs() > MAX_TIME {
        return Err(bad(
            path,
            n,
            format!("time {t:e} s is beyond {MAX_TIME:e} s: are the times in seconds?"),
        ));
    }
    let Some(prev) = previous else {
        return Ok(());
    };
    if t <= prev {
        return Err(bad(
            path,
            n,
            format!("time {t} does not increase (previous row: {prev})"),
        ));
    }
    if t - prev < MIN_TIME_STEP {
        return Err(bad(
            path,
            n,
            format!(
                "time step {:e} s from the previous row is below {MIN_TIME_STEP:e} s: are the times in seconds?",
                t - prev
            ),
        ));
    }
    Ok(())
}

/// Reads a CSV with a header naming t, x1, y1, x2, y2 (any order, other columns ignored);
/// lines starting with # are comments; a byte-order mark, `;` or tab separators and decimal
/// commas (with those separators) as spreadsheets and Tracker write them; Tracker's header of
/// two point masses (`t,x,y,x,y`, with or without the tracks' names above it). `units` says
/// how its numbers become seconds and metres: a `frame` column at a frame rate instead of
/// `t`, pixels instead of metres; a pivot column pair `x0`, `y0` moves the origin row by
/// row. Where the header names `seen1` and `seen2` (as `track` writes them), only the rows in
/// which both masses were `measured` are read: a mass hidden in a frame has no position to
/// fit. Errors name the line. A scale from the motion ([`PixelScale::FromMotion`]) is
/// applied by `fit::pendulum::tracked_model`: the rows here are then in pixels, y up.
pub fn read_frames(path: &Path, units: &Units) -> Result<Vec<TrackedRow>> {
    let text = crate::input::read_text("file", path, crate::input::CSV_CAP)?;
    // A byte-order mark (as some spreadsheets write) is not part of the first column's name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .peekable();
    let header = Header::read(&mut lines, path, units)?;
    let mut frames: Vec<TrackedRow> = Vec::new();
    for (n, line) in lines {
        let Some(row) = header.row(n, line, path, units)? else {
            continue;
        };
        check_time(row.t, frames.last().map(|f| f.t), n, path)?;
        frames.push(row);
    }
    // Free motion only: before the release `track` saw the rest and the hand.
    let release = crate::input::comment_values(text)
        .into_iter()
        .find(|(k, _)| *k == RELEASE)
        .and_then(|(_, v)| v.first().copied());
    if let (Some(release), false) = (release, units.before_release) {
        frames.retain(|f| f.t >= release - 1e-9);
    }
    if frames.len() < 5 {
        return Err(bad(
            path,
            text.lines().count(),
            format!("{} data rows; at least 5 are needed", frames.len()),
        ));
    }
    Ok(frames)
}
