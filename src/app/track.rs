//! `track`: the positions of both masses in every frame of a film of the pendulum, as the
//! CSV that `fit` and `forecast` read, with how each row was obtained and its uncertainty.

use std::io::Write;
use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::monitor::Monitor;
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
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TrackSummary {
    pub frames: usize,
    /// The share of frames in which each mass was measured, and both.
    pub seen1: f64,
    pub seen2: f64,
    pub both: f64,
    /// The pivot (px, x right, y down), the arms (px) and the scale (px per metre).
    pub pivot_px: (f64, f64),
    pub r1_px: f64,
    pub r2_px: f64,
    pub pixels_per_metre: f64,
    /// The lower arm's length this scale gives (m).
    pub l2: f64,
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

pub fn run(job: &TrackJob, command: &str, monitor: &Monitor) -> Result<TrackSummary> {
    match job.scale {
        Scale::UpperArm(l1) => super::check_within("l1", l1, 1e-4, 1e4)?,
        Scale::PixelsPerMetre(p) => super::check_within("pixels_per_metre", p, 1e-3, 1e9)?,
    }
    if !job.video.exists() {
        return Err(Error::Missing {
            field: "video",
            path: job.video.clone(),
        });
    }
    super::check_output("output", &job.output, "csv")?;
    super::checks::check_distinct(&[("output", &job.output)], &[("video", &job.video)])?;
    let started = std::time::Instant::now();
    let mut decoder = Decoder::open(
        &job.video,
        match job.markers.channels() {
            1 => Pixels::Gray,
            _ => Pixels::Rgb,
        },
    )?;
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
    while let Some(t) = decoder.next_frame(&mut frame)? {
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
    let tracked = track::track(&blobs, &times, job.scale)?;
    let seconds = started.elapsed().as_secs_f64();
    let n = tracked.rows.len() as f64;
    let share =
        |f: &dyn Fn(&TrackRow) -> bool| tracked.rows.iter().filter(|r| f(r)).count() as f64 / n;
    let mut notices = Vec::new();
    let both = share(&|r| r.m1.is_some() && r.m2.is_some());
    if both < 0.5 {
        notices.push(format!(
            "note: both masses were measured in {:.0} % of the frames only: is the region, the markers' kind or the scale right?",
            100.0 * both
        ));
    }
    let mut files = Outputs::new();
    files.write(&job.output, |w| write_csv(w, &tracked, command))?;
    files.commit(monitor)?;
    let g = tracked.geometry;
    Ok(TrackSummary {
        frames: tracked.rows.len(),
        seen1: share(&|r| r.m1.is_some()),
        seen2: share(&|r| r.m2.is_some()),
        both,
        pivot_px: g.pivot,
        r1_px: g.r1,
        r2_px: g.r2,
        pixels_per_metre: tracked.pixels_per_metre,
        l2: g.r2 / tracked.pixels_per_metre,
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

/// The CSV: t (s), x1 y1 x2 y2 (m, origin at the pivot, y up), seen1 seen2 (`measured` or
/// `hidden`: a hidden mass's cells are empty), sx1 sy1 sx2 sy2 (each position's standard
/// error from the sensor's noise, m) and streak1 streak2 (the distance moved during the
/// exposure, m).
fn write_csv(w: &mut impl Write, t: &track::Tracked, command: &str) -> Result<()> {
    let g = t.geometry;
    writeln!(w, "# {command}")?;
    writeln!(
        w,
        "# pivot at ({:.3}, {:.3}) px, upper arm {:.3} px, lower arm {:.3} px, {:.4} px per metre; t from the film's first frame",
        g.pivot.0, g.pivot.1, g.r1, g.r2, t.pixels_per_metre
    )?;
    writeln!(
        w,
        "t,x1,y1,x2,y2,seen1,seen2,sx1,sy1,sx2,sy2,streak1,streak2"
    )?;
    for r in &t.rows {
        let pos = |m: Option<track::Mark>| match m {
            Some(m) => format!("{:.6},{:.6}", m.x, m.y),
            None => ",".into(),
        };
        let seen = |m: Option<track::Mark>| if m.is_some() { "measured" } else { "hidden" };
        let err = |m: Option<track::Mark>| match m {
            Some(m) => format!("{:.2e},{:.2e}", m.sx, m.sy),
            None => ",".into(),
        };
        let streak =
            |m: Option<track::Mark>| m.map_or(String::new(), |m| format!("{:.5}", m.streak));
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
