//! `track --bridge`: the places of masses hidden in gaps of a track filled with the model's,
//! fitted as `forecast` fits it to the rows measured around each gap, with the fit's errors;
//! a gap the model cannot join stays hidden, and is named.

use crate::engine::Engine;
use crate::error::Result;
use crate::fit::TrackedRow;
use crate::fit::window::{TrackRows, fit_window};
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::track::{Mark, TrackRow, Tracked};

/// What `--bridge` did: gaps (runs of frames with a mass hidden) bridged by the model, the
/// masses' places filled, and the gaps left open (first and last hidden frame, s) with why.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Bridged {
    pub gaps: usize,
    pub places: usize,
    pub left_open: Vec<(f64, f64, String)>,
}

/// Measured rows the model is fitted to on each side of a gap (s): half a second is some
/// 15 frames of a phone's film a side, enough for the state, short enough that the model
/// holds over the window (the lab pendulum's Lyapunov time is about a second).
const BRIDGE_MARGIN: f64 = 0.5;
/// The fewest rows with both masses measured on each side of a gap: a gap at the film's
/// ends, or between others, has no orbit to join and is left open.
const BRIDGE_ROWS: usize = 5;
/// The longest gap bridged (s): over a Lyapunov time the orbits that fit both sides part
/// and the model's place means little.
const BRIDGE_LONGEST: f64 = 1.0;
/// How far a bridge's fit may stray from the rows it was fitted to, in tracking errors
/// (the rods' RMS): fits that found the orbit stray by 0.4-1.6 of them on the test films,
/// those that missed it by a hundred or more.
const STRAYS: f64 = 3.0;
/// Candidates of each bridge fit's search (the window is short, the guess near).
const BRIDGE_CANDIDATES: usize = 4096;

/// Fills the places of masses hidden in gaps of `tracked` with the model's: for each gap
/// (a run of frames in which a mass is hidden), the model (`sources`, the arms from the
/// track) fitted as `forecast` fits it to the rows measured within [`BRIDGE_MARGIN`] of the
/// gap, its positions at the hidden frames and their standard errors from the fit's
/// covariance. Gaps too long, at the film's ends or without enough rows around them stay
/// hidden, and are named.
pub fn bridge(
    tracked: &mut Tracked,
    sources: &ParamSources,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Bridged> {
    let frames = measured_rows(&tracked.rows);
    let gaps = gaps_of(&tracked.rows);
    let mut out = Bridged::default();
    if gaps.is_empty() {
        return Ok(out);
    }
    if frames.len() < 2 * BRIDGE_ROWS {
        let rows = &tracked.rows;
        out.left_open = gaps
            .iter()
            .map(|g| {
                (
                    rows[g.start].t,
                    rows[g.end - 1].t,
                    "too few rows measured in the whole film".into(),
                )
            })
            .collect();
        return Ok(out);
    }
    let units = Default::default();
    let model = crate::fit::pendulum::tracked_model(&frames, sources, &units, monitor)?;
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let nested = monitor.quiet();
    let filler = Filler {
        t: &t,
        rows: TrackRows {
            t: &t,
            data: &model.measured,
            angles: &model.angles,
        },
        params: &model.params,
        // The model's frame is `tracked_model`'s pivot's; the CSV's is the tracker's.
        origin: (model.pivot.x, model.pivot.y),
        frame: frame_interval(&tracked.rows),
        engine,
        monitor: &nested,
    };
    monitor.start("bridge", gaps.len() as u64);
    for gap in gaps {
        monitor.check()?;
        let (ta, tb) = (tracked.rows[gap.start].t, tracked.rows[gap.end - 1].t);
        let (ppm, g) = (tracked.pixels_per_metre, tracked.geometry);
        match filler.fill(&mut tracked.rows[gap], ppm, g.pivot)? {
            Ok(places) => {
                out.places += places;
                out.gaps += 1;
            }
            Err(why) => out.left_open.push((ta, tb, why)),
        }
        monitor.advance(1);
    }
    monitor.finish();
    Ok(out)
}

/// The rows with both masses measured, as positions to fit.
fn measured_rows(rows: &[TrackRow]) -> Vec<TrackedRow> {
    rows.iter()
        .filter_map(|r| match (r.m1, r.m2) {
            (Some(a), Some(b)) => Some(TrackedRow {
                t: r.t,
                x1: a.x,
                y1: a.y,
                x2: b.x,
                y2: b.y,
            }),
            _ => None,
        })
        .collect()
}

/// The gaps: runs of rows without both masses.
fn gaps_of(rows: &[TrackRow]) -> Vec<std::ops::Range<usize>> {
    let both = |r: &TrackRow| r.m1.is_some() && r.m2.is_some();
    let mut gaps = Vec::new();
    let mut k = 0;
    while k < rows.len() {
        if both(&rows[k]) {
            k += 1;
            continue;
        }
        let first = k;
        while k < rows.len() && !both(&rows[k]) {
            k += 1;
        }
        gaps.push(first..k);
    }
    gaps
}

/// The film's frame interval: the median step between rows.
fn frame_interval(rows: &[TrackRow]) -> f64 {
    let mut steps: Vec<f64> = rows.windows(2).map(|w| w[1].t - w[0].t).collect();
    crate::stats::median(&mut steps).unwrap_or(f64::NAN)
}

/// What fills one gap: the measured rows, the model and where its frame lies in the CSV's.
struct Filler<'a> {
    t: &'a [f64],
    rows: TrackRows<'a>,
    params: &'a crate::model::Params,
    origin: (f64, f64),
    frame: f64,
    engine: &'a Engine,
    monitor: &'a Monitor,
}

impl Filler<'_> {
    /// Fills the hidden places of `gap` (its rows) with the model's, the pivot at `pivot_px`
    /// and `ppm` pixels a metre: the places filled, or why the gap stays open.
    fn fill(
        &self,
        gap: &mut [TrackRow],
        ppm: f64,
        pivot_px: (f64, f64),
    ) -> Result<std::result::Result<usize, String>> {
        let (ta, tb) = (gap[0].t, gap[gap.len() - 1].t);
        let t = self.t;
        let near = |lo: f64, hi: f64| t.iter().filter(|&&x| x >= lo && x <= hi).count();
        let (before, after) = (near(ta - BRIDGE_MARGIN, ta), near(tb, tb + BRIDGE_MARGIN));
        if tb - ta > BRIDGE_LONGEST {
            return Ok(Err(format!("longer than {BRIDGE_LONGEST} s")));
        }
        if before < BRIDGE_ROWS || after < BRIDGE_ROWS {
            return Ok(Err(format!(
                "{before} rows measured in the {BRIDGE_MARGIN} s before it and {after} after (needs {BRIDGE_ROWS} each)"
            )));
        }
        // The fit's state is the first row's, its search's guess of the velocities from the
        // rows either side: the window starts at the first row whose neighbours are the
        // frames next to it.
        let first = t
            .windows(3)
            .find(|w| w[1] >= ta - BRIDGE_MARGIN && w[1] < ta && w[2] - w[0] < 2.5 * self.frame)
            .map_or(ta - BRIDGE_MARGIN, |w| w[1]);
        let window = (first, tb + BRIDGE_MARGIN);
        let fit = match fit_window(
            &self.rows,
            self.params,
            window,
            BRIDGE_CANDIDATES,
            None,
            self.engine,
            self.monitor,
        ) {
            Ok(fit) => fit,
            Err(e) => return Ok(Err(format!("the model's fit failed: {e}"))),
        };
        // A fit that strays from the rows it was fitted to by more than the tracking errors
        // allow has not found the orbit through them (a search's miss in a chaotic window
        // with gaps of its own): its places would be guesses.
        if fit.tracking_error > STRAYS * fit.correlation.rms {
            return Ok(Err(format!(
                "the model does not follow the rows around it ({:.2} mm from them, the tracking errors {:.2} mm)",
                1e3 * fit.tracking_error,
                1e3 * fit.correlation.rms
            )));
        }
        let at: Vec<f64> = gap.iter().map(|r| r.t).collect();
        let places = fit.positions(&at);
        let errors = fit.position_errors(&at);
        let mut filled = 0;
        for ((row, p), e) in gap.iter_mut().zip(places).zip(errors) {
            let mark = |c: usize| {
                let (x, y) = (p[c] + self.origin.0, p[c + 1] + self.origin.1);
                Mark {
                    x,
                    y,
                    sx: e[c],
                    sy: e[c + 1],
                    streak: f64::NAN,
                    px: (pivot_px.0 + x * ppm, pivot_px.1 - y * ppm),
                    bridged: true,
                }
            };
            for (c, m) in [(0, &mut row.m1), (2, &mut row.m2)] {
                if m.is_none() {
                    *m = Some(mark(c));
                    filled += 1;
                }
            }
        }
        Ok(Ok(filled))
    }
}
