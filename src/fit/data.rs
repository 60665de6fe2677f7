//! Tracked positions from a camera: reading them, finding the pivot and the arm lengths,
//! angles, velocities and energies with error bars (the lab report's analysis, section 3).

use std::path::Path;

use nalgebra::{DMatrix, DVector};

use super::lsq::{Fit, least_squares};
use crate::error::{Error, Result};
pub use crate::track::file::{PixelScale, RELEASE, TrackedRow};

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
}

/// The columns a tracked file may name, beside the positions x1, y1, x2, y2: the time `t`
/// (s) or the `frame` number, and a pivot `x0`, `y0` that moves (positions are taken
/// relative to it, row by row).
const COLUMNS: [&str; 8] = ["t", "frame", "x0", "y0", "x1", "y1", "x2", "y2"];

/// Reads a CSV with a header naming t, x1, y1, x2, y2 (any order, other columns ignored);
/// lines starting with # are comments; a byte-order mark, `;` or tab separators and decimal
/// commas (with those separators) as spreadsheets and Tracker write them. `units` says how
/// its numbers become seconds and metres: a `frame` column at a frame rate instead of `t`,
/// pixels instead of metres; a pivot column pair `x0`, `y0` moves the origin row by row.
/// Where the header names `seen1` and `seen2` (as `track` writes them), only the rows in
/// which both masses were `measured` are read: a mass hidden in a frame has no position to
/// fit. Errors name the line. A scale from the motion ([`PixelScale::FromMotion`]) is
/// applied by [`crate::fit::pendulum::tracked_model`]: the rows here are then in pixels,
/// y up.
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
    let (mut header_line, mut header) = lines
        .next()
        .ok_or_else(|| bad(path, 1, "no header line (t,x1,y1,x2,y2)".into()))?;
    // Spreadsheets in much of the world separate by `;` (or tabs) and write decimal commas.
    let separator_of = |line: &str| match (line.contains(';'), line.contains('\t')) {
        (true, _) => ';',
        (false, true) => '\t',
        _ => ',',
    };
    let split = |line: &str| -> Vec<String> {
        line.split(separator_of(line))
            .map(|c| c.trim().to_string())
            .collect()
    };
    // Tracker's export of two point masses together: a line of the tracks' names over
    // `t x y x y` (the upper mass's track first).
    let tracker = !split(header).iter().any(|n| n == "t" || n == "frame")
        && lines.peek().is_some_and(|(_, next)| {
            let names = split(next);
            names.first().is_some_and(|n| n == "t")
                && names.iter().filter(|n| *n == "x").count() >= 2
                && names.iter().filter(|n| *n == "y").count() >= 2
        });
    if tracker {
        (header_line, header) = lines.next().expect("the line peeked");
    }
    let separator = separator_of(header);
    let mut names = split(header);
    if tracker {
        // The first x and y are the first track's (the upper mass), the next the second's.
        for (name, numbered) in [("x", ["x1", "x2"]), ("y", ["y1", "y2"])] {
            for (k, column) in names.iter_mut().filter(|n| *n == name).take(2).enumerate() {
                *column = numbered[k].to_string();
            }
        }
    }
    let find = |name: &str| names.iter().position(|n| n == name);
    let column = |name: &str| {
        find(name).ok_or_else(|| {
            bad(
                path,
                header_line,
                format!("the header has no column `{name}` (needs t, x1, y1, x2, y2)"),
            )
        })
    };
    let time = match (find("t"), find("frame"), units.frame_rate) {
        (Some(t), _, None) => t,
        (_, Some(frame), Some(_)) => frame,
        (None, Some(_), None) => {
            return Err(Error::invalid(
                "frame_rate",
                format!(
                    "{} numbers its rows by `frame`, with no `t`: give the frame rate (frames a second) to make them times",
                    path.display()
                ),
            ));
        }
        (Some(_), None, Some(_)) => {
            return Err(Error::invalid(
                "frame_rate",
                format!(
                    "{} has times (`t`, s) and no `frame` column: a frame rate is for a file that numbers its rows by frame; leave it out",
                    path.display()
                ),
            ));
        }
        (None, _, _) => column("t")?,
    };
    // A column named twice would be read from its first copy silently. Only the columns
    // read are looked at, each name once (a header of 200,000 names costs one pass).
    let mut first: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (k, name) in names.iter().enumerate() {
        if !COLUMNS.contains(&name.as_str()) {
            continue;
        }
        if let Some(&j) = first.get(name.as_str()) {
            return Err(bad(
                path,
                header_line,
                format!(
                    "the header names `{name}` twice (columns {} and {})",
                    j + 1,
                    k + 1
                ),
            ));
        }
        first.insert(name.as_str(), k);
    }
    let cols = [
        time,
        column("x1")?,
        column("y1")?,
        column("x2")?,
        column("y2")?,
    ];
    let pivot = match (find("x0"), find("y0")) {
        (Some(x), Some(y)) => Some([x, y]),
        (None, None) => None,
        _ => {
            return Err(bad(
                path,
                header_line,
                "a moving pivot takes both columns `x0` and `y0`".into(),
            ));
        }
    };
    // Pixels count y down; metres here count it up.
    let (scale, flip) = match units.pixels_per_metre {
        None => (1.0, 1.0),
        Some(PixelScale::PerMetre(p)) => (1.0 / p, -1.0),
        Some(PixelScale::FromMotion) => (1.0, -1.0),
    };
    let seen: Vec<usize> = ["seen1", "seen2"]
        .iter()
        .filter_map(|s| names.iter().position(|n| n == s))
        .collect();
    let mut frames = Vec::new();
    let decimal_comma = separator != ',';
    for (n, line) in lines {
        let cells: Vec<String> = line
            .split(separator)
            .map(|c| match decimal_comma {
                true => c.trim().replace(',', "."),
                false => c.trim().to_string(),
            })
            .collect();
        // Tracker leaves a step that was not marked empty: no position to fit.
        if tracker
            && cols
                .iter()
                .any(|&c| cells.get(c).is_none_or(|c| c.is_empty()))
        {
            continue;
        }
        // A row of more or fewer fields than the header has its values under other columns'
        // names (a decimal comma, a cell left out).
        if !tracker && cells.len() != names.len() {
            return Err(bad(
                path,
                n,
                format!(
                    "{} fields where the header has {}",
                    cells.len(),
                    names.len()
                ),
            ));
        }
        if seen.iter().any(|&c| cells[c] != "measured") {
            continue;
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
                        format!("`{cell}` in column `{}` is not a number", names[c]),
                    )
                })
        };
        let mut v = [0.0; 5];
        for (k, &c) in cols.iter().enumerate() {
            v[k] = number(c)?;
        }
        let origin = match pivot {
            Some([x, y]) => [number(x)?, number(y)?],
            None => [0.0, 0.0],
        };
        if let Some(rate) = units.frame_rate {
            v[0] /= rate;
        }
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
                    v[k], names[cols[k]]
                ),
            ));
        }
        if v[0].abs() > MAX_TIME {
            return Err(bad(
                path,
                n,
                format!(
                    "time {:e} s is beyond {MAX_TIME:e} s: are the times in seconds?",
                    v[0]
                ),
            ));
        }
        if let Some(prev) = frames.last().map(|f: &TrackedRow| f.t)
            && v[0] <= prev
        {
            return Err(bad(
                path,
                n,
                format!("time {} does not increase (previous row: {prev})", v[0]),
            ));
        }
        // Tracked frames come from a camera: steps below a microsecond are a unit mistake,
        // and their velocities and energies overflow.
        if let Some(prev) = frames.last().map(|f: &TrackedRow| f.t)
            && v[0] - prev < MIN_TIME_STEP
        {
            return Err(bad(
                path,
                n,
                format!(
                    "time step {:e} s from the previous row is below {MIN_TIME_STEP:e} s: are the times in seconds?",
                    v[0] - prev
                ),
            ));
        }
        frames.push(TrackedRow {
            t: v[0],
            x1: v[1],
            y1: v[2],
            x2: v[3],
            y2: v[4],
        });
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

/// The pivot from a least-squares circle through the upper-mass positions: an algebraic
/// (Kasa) fit to start, then the geometric fit of |p - c| - r, with standard errors.
pub struct Pivot {
    pub x: f64,
    pub y: f64,
    pub radius: f64,
    pub errors: [f64; 3],
    pub rms_residual: f64,
}

pub fn fit_pivot(frames: &[TrackedRow]) -> Result<Pivot> {
    let n = frames.len();
    // x^2 + y^2 + D x + E y + F = 0, linear in (D, E, F).
    let a = DMatrix::from_fn(n, 3, |i, j| match j {
        0 => frames[i].x1,
        1 => frames[i].y1,
        _ => 1.0,
    });
    let b = DVector::from_fn(n, |i, _| -(frames[i].x1.powi(2) + frames[i].y1.powi(2)));
    let sol = a
        .svd(true, true)
        .solve(&b, 1e-12)
        .map_err(|e| Error::invalid("file", format!("circle fit: {e}")))?;
    let (cx, cy) = (-sol[0] / 2.0, -sol[1] / 2.0);
    let r = (cx * cx + cy * cy - sol[2]).max(0.0).sqrt();
    let residuals = |p: &DVector<f64>| {
        let r = DVector::from_fn(n, |i, _| {
            ((frames[i].x1 - p[0]).powi(2) + (frames[i].y1 - p[1]).powi(2)).sqrt() - p[2]
        });
        let j = DMatrix::from_fn(n, 3, |i, k| {
            let d = ((frames[i].x1 - p[0]).powi(2) + (frames[i].y1 - p[1]).powi(2)).sqrt();
            match k {
                0 => -(frames[i].x1 - p[0]) / d,
                1 => -(frames[i].y1 - p[1]) / d,
                _ => -1.0,
            }
        });
        (r, j)
    };
    let fit = least_squares(residuals, DVector::from_vec(vec![cx, cy, r]), 100);
    // The upper mass swings on an arc around the pivot: positions that span only a sliver of
    // a circle (or a line) give no pivot, only a far-away guess. Ask for an arc that the
    // radius does not dwarf: a bounding box whose diagonal is at least 1/20 of it.
    let (x, y) = (frames.iter().map(|f| f.x1), frames.iter().map(|f| f.y1));
    let extent = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        hi - lo
    };
    let spread = extent(&mut x.clone()).hypot(extent(&mut y.clone()));
    if !(fit.params[2].is_finite() && spread >= 0.05 * fit.params[2]) {
        return Err(Error::invalid(
            "file",
            format!(
                "the upper mass's positions span {spread:.3} m, too little of a circle (radius {:.3} m) to locate the pivot: they must swing through an arc",
                fit.params[2]
            ),
        ));
    }
    Ok(Pivot {
        x: fit.params[0],
        y: fit.params[1],
        radius: fit.params[2],
        errors: [fit.errors[0], fit.errors[1], fit.errors[2]],
        rms_residual: (fit.chi2 / n as f64).sqrt(),
    })
}

/// The report's method: the point of a grid (step `step` m, within `half` m of `around`)
/// whose distances to all upper-mass positions have the least variance.
pub fn grid_pivot(frames: &[TrackedRow], around: (f64, f64), half: f64, step: f64) -> (f64, f64) {
    let k = (half / step).round() as i64;
    let mut best = (f64::INFINITY, around);
    for i in -k..=k {
        for j in -k..=k {
            let (x, y) = (around.0 + i as f64 * step, around.1 + j as f64 * step);
            let d: Vec<f64> = frames
                .iter()
                .map(|f| ((f.x1 - x).powi(2) + (f.y1 - y).powi(2)).sqrt())
                .collect();
            let mean = d.iter().sum::<f64>() / d.len() as f64;
            let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / d.len() as f64;
            if var < best.0 {
                best = (var, (x, y));
            }
        }
    }
    best.1
}

/// Mean and its standard error, and the standard deviation.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Estimate {
    pub value: f64,
    pub error: f64,
    pub spread: f64,
}

pub fn estimate(values: &[f64]) -> Estimate {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    Estimate {
        value: mean,
        error: (var / n).sqrt(),
        spread: var.sqrt(),
    }
}

/// Arm lengths from the distances pivot - mass 1 and mass 1 - mass 2.
pub fn arm_lengths(frames: &[TrackedRow], pivot: (f64, f64)) -> (Estimate, Estimate) {
    let d1: Vec<f64> = frames
        .iter()
        .map(|f| ((f.x1 - pivot.0).powi(2) + (f.y1 - pivot.1).powi(2)).sqrt())
        .collect();
    let d2: Vec<f64> = frames
        .iter()
        .map(|f| ((f.x2 - f.x1).powi(2) + (f.y2 - f.y1).powi(2)).sqrt())
        .collect();
    (estimate(&d1), estimate(&d2))
}

/// Angles from the downward vertical (rad), unwrapped along the run.
pub fn angles(frames: &[TrackedRow], pivot: (f64, f64)) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(frames.len());
    for f in frames {
        let mut a = (
            (f.x1 - pivot.0).atan2(-(f.y1 - pivot.1)),
            (f.x2 - f.x1).atan2(-(f.y2 - f.y1)),
        );
        if let Some(prev) = out.last() {
            let unwrap = |x: f64, p: f64| {
                x + std::f64::consts::TAU * ((p - x) / std::f64::consts::TAU).round()
            };
            a = (unwrap(a.0, prev.0), unwrap(a.1, prev.1));
        }
        out.push(a);
    }
    out
}

/// Central differences (x(t+) - x(t-)) / (t+ - t-) at the interior rows, as the report.
pub fn central_differences(t: &[f64], x: &[f64]) -> Vec<f64> {
    (1..t.len() - 1)
        .map(|i| (x[i + 1] - x[i - 1]) / (t[i + 1] - t[i - 1]))
        .collect()
}

/// Energy (J) at the interior rows, zero with both masses hanging at rest, and its error
/// by propagation (the report's equation 23): dE = dv sqrt(m1^2 v1^2 + m2^2 v2^2).
pub struct Energies {
    pub t: Vec<f64>,
    pub e: Vec<f64>,
    pub de: Vec<f64>,
}

pub fn energies(
    frames: &[TrackedRow],
    pivot: (f64, f64),
    masses: (f64, f64),
    lengths: (f64, f64),
    g: f64,
    dv: f64,
) -> Energies {
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let col = |f: fn(&TrackedRow) -> f64| -> Vec<f64> { frames.iter().map(f).collect() };
    let (vx1, vy1) = (
        central_differences(&t, &col(|f| f.x1)),
        central_differences(&t, &col(|f| f.y1)),
    );
    let (vx2, vy2) = (
        central_differences(&t, &col(|f| f.x2)),
        central_differences(&t, &col(|f| f.y2)),
    );
    let (m1, m2) = masses;
    let (l1, l2) = lengths;
    let mut out = Energies {
        t: Vec::new(),
        e: Vec::new(),
        de: Vec::new(),
    };
    for i in 1..frames.len() - 1 {
        let f = &frames[i];
        let (v1sq, v2sq) = (
            vx1[i - 1].powi(2) + vy1[i - 1].powi(2),
            vx2[i - 1].powi(2) + vy2[i - 1].powi(2),
        );
        let kinetic = 0.5 * m1 * v1sq + 0.5 * m2 * v2sq;
        let potential = g * (m1 * (f.y1 - pivot.1 + l1) + m2 * (f.y2 - pivot.1 + l1 + l2));
        out.t.push(f.t);
        out.e.push(kinetic + potential);
        out.de.push(dv * (m1 * m1 * v1sq + m2 * m2 * v2sq).sqrt());
    }
    out
}

/// The two decay laws of section 2.4, fitted to E(t) with weights 1/dE^2:
/// exponential E = a exp(b t) (viscous losses) and E = a (b t + d)^-2 (pure quadratic drag;
/// a, b, d are degenerate - only a/d^2 and b/d matter - so d is fixed at 1).
pub struct DecayFits {
    pub exponential: Fit,
    pub inverse_square: Fit,
}

pub fn fit_decay(en: &Energies) -> DecayFits {
    let n = en.t.len();
    // Errors of zero (a mass at rest at the bottom) would get infinite weight.
    let floor = en.de.iter().copied().fold(0.0, f64::max) * 0.05 + 1e-6;
    let sigma: Vec<f64> = en.de.iter().map(|d| d.max(floor)).collect();
    let e0 = en.e.iter().copied().fold(0.0, f64::max).max(1e-6);
    let exponential = least_squares(
        |p: &DVector<f64>| {
            let r = DVector::from_fn(n, |i, _| {
                (en.e[i] - p[0] * (p[1] * en.t[i]).exp()) / sigma[i]
            });
            let j = DMatrix::from_fn(n, 2, |i, k| {
                let ex = (p[1] * en.t[i]).exp();
                -(if k == 0 { ex } else { p[0] * en.t[i] * ex }) / sigma[i]
            });
            (r, j)
        },
        DVector::from_vec(vec![e0, -0.02]),
        200,
    );
    let inverse_square = least_squares(
        |p: &DVector<f64>| {
            let r = DVector::from_fn(n, |i, _| {
                (en.e[i] - p[0] * (p[1] * en.t[i] + 1.0).powi(-2)) / sigma[i]
            });
            let j = DMatrix::from_fn(n, 2, |i, k| {
                let u = p[1] * en.t[i] + 1.0;
                -(if k == 0 {
                    u.powi(-2)
                } else {
                    -2.0 * p[0] * en.t[i] * u.powi(-3)
                }) / sigma[i]
            });
            (r, j)
        },
        DVector::from_vec(vec![e0, 0.01]),
        200,
    );
    DecayFits {
        exponential,
        inverse_square,
    }
}
