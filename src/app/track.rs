//! `track`: the positions of both masses in every frame of a film of the pendulum, as the
//! CSV that `fit` and `forecast` read, with how each row was obtained and its uncertainty.

use std::path::PathBuf;

use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::fit::TrackedRow;
use crate::fit::window::{TrackRows, fit_window};
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::render::Outputs;
use crate::track::{self, Markers, Scale, TrackRow};
use crate::video::{Decoder, Pixels};

#[derive(Clone, Debug, PartialEq)]
pub struct TrackJob {
    pub video: PathBuf,
    /// The CSV to write.
    pub output: PathBuf,
    pub markers: Markers,
    pub scale: Scale,
    /// The part of the picture to look in (px: x0, y0, x1, y1; None: all of it).
    pub region: Option<(u32, u32, u32, u32)>,
    /// Gaps where a mass is hidden bridged by this model fitted to the measured rows around
    /// each (the lab preset unless a preset or file is given; the arms from the track);
    /// None: hidden masses stay hidden.
    pub bridge: Option<ParamSources>,
}

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

#[derive(Clone, Debug, serde::Serialize)]
pub struct TrackSummary {
    pub frames: usize,
    /// The share of frames in which each mass was measured, and both.
    pub seen1: f64,
    pub seen2: f64,
    pub both: f64,
    /// What `--bridge` filled in (None: not asked).
    pub bridged: Option<Bridged>,
    /// The pivot (px, x right, y down), the arms (px) and the scale (px per metre).
    pub pivot_px: (f64, f64),
    pub r1_px: f64,
    pub r2_px: f64,
    pub pixels_per_metre: f64,
    /// The lower arm's length this scale gives (m).
    pub l2: f64,
    /// Which way is up: from the pendulum at rest, or the picture's.
    pub up: track::Up,
    /// Still blobs set aside (lamps, reflections of them, fixed marks), px.
    pub still: Vec<(f64, f64)>,
    pub codec: String,
    pub width: u32,
    pub height: u32,
    pub duration: f64,
    /// Frames read and tracked a second (decoding included).
    pub frames_per_second: f64,
    pub output: PathBuf,
    pub files: Vec<PathBuf>,
    pub notices: Vec<String>,
}

pub fn run(
    job: &TrackJob,
    engine: Option<&Engine>,
    command: &str,
    monitor: &Monitor,
) -> Result<TrackSummary> {
    match job.scale {
        Scale::UpperArm(l1) => super::check_within("l1", l1, 1e-4, 1e4)?,
        Scale::PixelsPerMetre(p) => super::check_within("pixels_per_metre", p, 1e-3, 1e9)?,
        Scale::FromMotion(g) => super::check_within("g", g, 1e-6, 1e6)?,
    }
    if !job.video.exists() {
        return Err(Error::Missing {
            field: "video",
            path: job.video.clone(),
        });
    }
    super::check_output("output", &job.output, "csv")?;
    let engine = match (&job.bridge, engine) {
        (Some(sources), Some(engine)) => {
            super::checks::check_damping_not_given(sources)?;
            Some(engine)
        }
        (Some(_), None) => unreachable!("a door that bridges lends an engine"),
        (None, _) => None,
    };
    super::checks::check_distinct(&[("output", &job.output)], &[("video", &job.video)])?;
    let started = std::time::Instant::now();
    let mut decoder = Decoder::open(
        &job.video,
        match job.markers.channels() {
            1 => Pixels::Gray,
            _ => Pixels::Rgb,
        },
    )
    .map_err(|e| e.as_input("video"))?;
    let (width, height) = (decoder.probe.width, decoder.probe.height);
    let region = match job.region {
        Some((x0, y0, x1, y1)) => {
            if !(x0 < x1 && y0 < y1 && x1 <= width && y1 <= height) {
                return Err(Error::invalid(
                    "region",
                    format!(
                        "{x0},{y0},{x1},{y1} must be X0,Y0,X1,Y1 with X0 < X1 <= {width} and Y0 < Y1 <= {height} (the film's size)"
                    ),
                ));
            }
            Some((x0 as usize, y0 as usize, x1 as usize, y1 as usize))
        }
        None => None,
    };
    let total = decoder.probe.times.len();
    monitor.start("track", total as u64);
    let (mut frame, mut score) = (Vec::new(), Vec::new());
    let mut scratch = track::detect::Scratch::default();
    let (mut blobs, mut times) = (Vec::with_capacity(total), Vec::with_capacity(total));
    while let Some(t) = decoder
        .next_frame(&mut frame)
        .map_err(|e| e.as_input("video"))?
    {
        monitor.check()?;
        job.markers.score(&frame, &mut score);
        blobs.push(track::detect::blobs(
            &score,
            width as usize,
            region,
            &mut scratch,
        ));
        times.push(t);
        monitor.advance(1);
    }
    monitor.finish();
    if blobs.len() < 10 {
        return Err(Error::invalid(
            "video",
            format!("{} frames: tracking needs at least 10", blobs.len()),
        ));
    }
    let mut tracked = track::track(&blobs, &times, job.scale)?;
    let bridged = match (&job.bridge, engine) {
        (Some(sources), Some(engine)) => Some(bridge(&mut tracked, sources, engine, monitor)?),
        _ => None,
    };
    let seconds = started.elapsed().as_secs_f64();
    let n = tracked.rows.len() as f64;
    let share =
        |f: &dyn Fn(&TrackRow) -> bool| tracked.rows.iter().filter(|r| f(r)).count() as f64 / n;
    let measured = |m: Option<track::Mark>| m.is_some_and(|m| !m.bridged);
    let mut notices = Vec::new();
    if decoder.probe.repeated > 0 {
        notices.push(format!(
            "note: {} of the film's {} frames repeat another's timestamp (its container's rounding): each took its place in time order",
            decoder.probe.repeated, total
        ));
    }
    let both = share(&|r| measured(r.m1) && measured(r.m2));
    if both < 0.5 {
        notices.push(format!(
            "note: both masses were measured in {:.0} % of the frames only: is the region, the markers' kind or the scale right?",
            100.0 * both
        ));
    }
    let mut files = Outputs::new();
    let film = track::file::Film::of(&decoder.probe);
    files.write(&job.output, |w| {
        track::file::write(w, &tracked, &film, command)
    })?;
    files.commit(monitor)?;
    let g = tracked.geometry;
    Ok(TrackSummary {
        frames: tracked.rows.len(),
        seen1: share(&|r| measured(r.m1)),
        seen2: share(&|r| measured(r.m2)),
        bridged,
        both,
        pivot_px: g.pivot,
        r1_px: g.r1,
        r2_px: g.r2,
        pixels_per_metre: tracked.pixels_per_metre,
        l2: g.r2 / tracked.pixels_per_metre,
        up: tracked.up,
        still: tracked.still.clone(),
        codec: decoder.probe.codec.clone(),
        width,
        height,
        duration: times.last().copied().unwrap_or(0.0),
        frames_per_second: n / seconds,
        output: job.output.clone(),
        files: vec![job.output.clone()],
        notices,
    })
}

/// Fills the places of masses hidden in gaps of `tracked` with the model's: for each gap
/// (a run of frames in which a mass is hidden), the model (`sources`, the arms from the
/// track) fitted as `forecast` fits it to the rows measured within [`BRIDGE_MARGIN`] of the
/// gap, its positions at the hidden frames and their standard errors from the fit's
/// covariance. Gaps too long, at the film's ends or without enough rows around them stay
/// hidden, and are named.
fn bridge(
    tracked: &mut track::Tracked,
    sources: &ParamSources,
    engine: &Engine,
    monitor: &Monitor,
) -> Result<Bridged> {
    let rows = &tracked.rows;
    let both = |r: &TrackRow| r.m1.is_some() && r.m2.is_some();
    let frames: Vec<TrackedRow> = rows
        .iter()
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
        .collect();
    // The gaps: runs of rows without both masses.
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
    let mut out = Bridged::default();
    if gaps.is_empty() {
        return Ok(out);
    }
    if frames.len() < 2 * BRIDGE_ROWS {
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
    let model = crate::fit::pendulum::tracked_model(&frames, sources, &Default::default())?;
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let track_rows = TrackRows {
        t: &t,
        data: &model.measured,
        angles: &model.angles,
    };
    let nested = monitor.quiet();
    monitor.start("bridge", gaps.len() as u64);
    let ppm = tracked.pixels_per_metre;
    let g = tracked.geometry;
    // The model's frame is `tracked_model`'s pivot's; the CSV's is the tracker's.
    let origin = (model.pivot.x, model.pivot.y);
    // The film's frame interval: the median step between rows.
    let frame = {
        let mut steps: Vec<f64> = tracked.rows.windows(2).map(|w| w[1].t - w[0].t).collect();
        let mid = steps.len() / 2;
        *steps.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    for gap in gaps {
        monitor.check()?;
        let (ta, tb) = (tracked.rows[gap.start].t, tracked.rows[gap.end - 1].t);
        let near = |lo: f64, hi: f64| t.iter().filter(|&&x| x >= lo && x <= hi).count();
        let (before, after) = (near(ta - BRIDGE_MARGIN, ta), near(tb, tb + BRIDGE_MARGIN));
        let why = if tb - ta > BRIDGE_LONGEST {
            Some(format!("longer than {BRIDGE_LONGEST} s"))
        } else if before < BRIDGE_ROWS || after < BRIDGE_ROWS {
            Some(format!(
                "{before} rows measured in the {BRIDGE_MARGIN} s before it and {after} after (needs {BRIDGE_ROWS} each)"
            ))
        } else {
            None
        };
        if let Some(why) = why {
            out.left_open.push((ta, tb, why));
            monitor.advance(1);
            continue;
        }
        // The fit's state is the first row's, its search's guess of the velocities from the
        // rows either side: the window starts at the first row whose neighbours are the
        // frames next to it.
        let first = t
            .windows(3)
            .find(|w| w[1] >= ta - BRIDGE_MARGIN && w[1] < ta && w[2] - w[0] < 2.5 * frame)
            .map_or(ta - BRIDGE_MARGIN, |w| w[1]);
        let window = (first, tb + BRIDGE_MARGIN);
        let fit = match fit_window(
            &track_rows,
            &model.params,
            window,
            BRIDGE_CANDIDATES,
            engine,
            &nested,
        ) {
            Ok(fit) => fit,
            Err(e) => {
                out.left_open
                    .push((ta, tb, format!("the model's fit failed: {e}")));
                monitor.advance(1);
                continue;
            }
        };
        // A fit that strays from the rows it was fitted to by more than the tracking errors
        // allow has not found the orbit through them (a search's miss in a chaotic window
        // with gaps of its own): its places would be guesses.
        if fit.tracking_error > STRAYS * fit.correlation.rms {
            out.left_open.push((
                ta,
                tb,
                format!(
                    "the model does not follow the rows around it ({:.2} mm from them, the tracking errors {:.2} mm)",
                    1e3 * fit.tracking_error,
                    1e3 * fit.correlation.rms
                ),
            ));
            monitor.advance(1);
            continue;
        }
        let at: Vec<f64> = tracked.rows[gap.clone()].iter().map(|r| r.t).collect();
        let places = fit.positions(&at);
        let errors = fit.position_errors(&at);
        for ((row, p), e) in tracked.rows[gap.clone()].iter_mut().zip(places).zip(errors) {
            let mark = |c: usize| {
                let (x, y) = (p[c] + origin.0, p[c + 1] + origin.1);
                track::Mark {
                    x,
                    y,
                    sx: e[c],
                    sy: e[c + 1],
                    streak: f64::NAN,
                    px: (g.pivot.0 + x * ppm, g.pivot.1 - y * ppm),
                    bridged: true,
                }
            };
            for (c, m) in [(0, &mut row.m1), (2, &mut row.m2)] {
                if m.is_none() {
                    *m = Some(mark(c));
                    out.places += 1;
                }
            }
        }
        out.gaps += 1;
        monitor.advance(1);
    }
    monitor.finish();
    Ok(out)
}
