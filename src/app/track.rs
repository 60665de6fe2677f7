//! `track`: the positions of both masses in every frame of a film of the pendulum, as the
//! CSV that `fit` and `forecast` read, with how each row was obtained and its uncertainty.

use std::path::PathBuf;

use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::fit::bridge::Bridged;
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::render::Outputs;
use crate::track::file::{DIGEST_FRAMES, Digest};
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
    /// None where the lower mass was never measured: no length from what was not seen.
    pub r2_px: Option<f64>,
    pub pixels_per_metre: f64,
    /// The lower arm's length this scale gives (m); None where the lower mass was never
    /// measured.
    pub l2: Option<f64>,
    /// Which way is up: from the pendulum at rest, or the picture's.
    pub up: track::Up,
    /// Still blobs set aside (lamps, reflections of them, fixed marks), px.
    pub still: Vec<(f64, f64)>,
    /// The last still frame's time before free motion (s), where the film shows the
    /// pendulum held and let go; and the stretch from the end of its rest to then, when
    /// it was lifted by hand (where a rest was seen).
    pub release: Option<f64>,
    pub lift: Option<(f64, f64)>,
    /// The marker at the pivot the masses were measured from, where the film shows one.
    pub pivot_marker: Option<track::PivotMarker>,
    pub codec: String,
    pub width: u32,
    pub height: u32,
    pub duration: f64,
    /// The film's own frame rate ([`crate::video::Probe::frame_rate`]).
    pub frame_rate: f64,
    /// Frames read and tracked a second of processing (decoding included).
    pub processing_frames_per_second: f64,
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
    let engine = check_job(job, engine)?;
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
    let region = region_within(job.region, width, height)?;
    let (blobs, times, digest, sampled) = markers_of(&mut decoder, job.markers, region, monitor)?;
    let mut tracked = track::track(&blobs, &times, job.scale, job.markers, &|rows, g| {
        crate::fit::pendulum::scale_from_motion(rows, g, monitor)
    })?;
    let bridged = match (&job.bridge, engine) {
        (Some(sources), Some(engine)) => Some(crate::fit::bridge::bridge(
            &mut tracked,
            sources,
            engine,
            monitor,
        )?),
        _ => None,
    };
    let seconds = started.elapsed().as_secs_f64();
    let n = tracked.rows.len() as f64;
    let share =
        |f: &dyn Fn(&TrackRow) -> bool| tracked.rows.iter().filter(|r| f(r)).count() as f64 / n;
    let measured = |m: Option<track::Mark>| m.is_some_and(|m| !m.bridged);
    let both = share(&|r| measured(r.m1) && measured(r.m2));
    let mut notices = notices_of(&decoder.probe, both);
    let second = second_colour_note(job.markers, both, &sampled, width as usize, region);
    notices.extend(second);
    let mut files = Outputs::new();
    let film = track::file::Film {
        digest: Some(digest),
        ..track::file::Film::of(&decoder.probe)
    };
    files.write(&job.output, |w| {
        track::file::write(w, &tracked, &film, command)
    })?;
    files.commit(monitor)?;
    let g = tracked.geometry;
    let lower_seen = tracked.rows.iter().any(|r| measured(r.m2));
    Ok(TrackSummary {
        frames: tracked.rows.len(),
        seen1: share(&|r| measured(r.m1)),
        seen2: share(&|r| measured(r.m2)),
        bridged,
        both,
        pivot_px: g.pivot,
        r1_px: g.r1,
        r2_px: lower_seen.then_some(g.r2),
        pixels_per_metre: tracked.pixels_per_metre,
        l2: lower_seen.then_some(g.r2 / tracked.pixels_per_metre),
        up: tracked.up,
        still: tracked.still.clone(),
        release: tracked.release,
        lift: tracked.lift(),
        pivot_marker: tracked.pivot_marker,
        codec: decoder.probe.codec.clone(),
        width,
        height,
        duration: times.last().copied().unwrap_or(0.0),
        frame_rate: decoder.probe.frame_rate(),
        processing_frames_per_second: n / seconds,
        output: job.output.clone(),
        files: vec![job.output.clone()],
        notices,
    })
}

/// One colour given and both masses measured in under half the frames: the second sticker
/// the film shows (in the `sampled` frames, `width` pixels wide), named, where it shows one.
fn second_colour_note(
    markers: track::Markers,
    both: f64,
    sampled: &[Vec<u8>],
    width: usize,
    region: Option<(usize, usize, usize, usize)>,
) -> Option<String> {
    let track::Markers::Colour(given) = markers else {
        return None;
    };
    if both >= 0.5 {
        return None;
    }
    let other = track::colours::second_colour(sampled, width, region, given)?;
    let given = track::colours::colour_name(given);
    Some(format!(
        "note: with one colour both masses were measured in {:.0} % of the frames; the film shows a {other} sticker too: for a sticker of each colour, the upper mass's first, [[markers={given},{other}]] (or {other},{given})",
        100.0 * both
    ))
}

/// The job's values, its film and its output, before any work; the engine where it bridges.
fn check_job<'e>(job: &TrackJob, engine: Option<&'e Engine>) -> Result<Option<&'e Engine>> {
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
    Ok(engine)
}

/// The region to look in, as pixel bounds, checked against the film's size.
fn region_within(
    region: Option<(u32, u32, u32, u32)>,
    width: u32,
    height: u32,
) -> Result<Option<(usize, usize, usize, usize)>> {
    let Some((x0, y0, x1, y1)) = region else {
        return Ok(None);
    };
    if !(x0 < x1 && y0 < y1 && x1 <= width && y1 <= height) {
        return Err(Error::invalid(
            "region",
            format!(
                "{x0},{y0},{x1},{y1} must be X0,Y0,X1,Y1 with X0 < X1 <= {width} and Y0 < Y1 <= {height} (the film's size)"
            ),
        ));
    }
    Ok(Some((x0 as usize, y0 as usize, x1 as usize, y1 as usize)))
}

/// Every frame's marker blobs and its time, frame by frame (the progress bar's units), the
/// film's digest (its first frames as read), and, where one colour was given, a few frames
/// spread over the film (to look for a second sticker in).
#[allow(clippy::type_complexity)]
fn markers_of(
    decoder: &mut Decoder,
    markers: Markers,
    region: Option<(usize, usize, usize, usize)>,
    monitor: &Monitor,
) -> Result<(Vec<Vec<track::Blob>>, Vec<f64>, Digest, Vec<Vec<u8>>)> {
    let width = decoder.probe.width as usize;
    let total = decoder.probe.times.len();
    monitor.start("track", total as u64);
    let mut frame = Vec::new();
    let mut scratch = track::detect::Scratch::default();
    let (mut blobs, mut times) = (Vec::with_capacity(total), Vec::with_capacity(total));
    let mut digest = Digest::start(markers.channels() as u8);
    let mut sampled = Vec::new();
    while let Some(t) = decoder
        .next_frame(&mut frame)
        .map_err(|e| e.as_input("video"))?
    {
        monitor.check()?;
        if times.len() < DIGEST_FRAMES {
            digest.add(&frame);
        }
        blobs.push(markers.find(&frame, width, region, &mut scratch));
        let every = (total / track::colours::SAMPLED_FRAMES).max(1);
        if matches!(markers, Markers::Colour(_)) && times.len() % every == every / 2 {
            sampled.push(frame.clone());
        }
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
    Ok((blobs, times, digest, sampled))
}

/// What the film's reading says: repeated timestamps, masses measured too rarely.
fn notices_of(probe: &crate::video::Probe, both: f64) -> Vec<String> {
    let mut notices = Vec::new();
    if probe.repeated > 0 {
        notices.push(format!(
            "note: {} of the film's {} frames repeat another's timestamp (its container's rounding): each took its place in time order",
            probe.repeated,
            probe.times.len()
        ));
    }
    if both < 0.5 {
        notices.push(format!(
            "note: both masses were measured in {:.0} % of the frames only: is the region, the markers' kind or the scale right?",
            100.0 * both
        ));
    }
    notices
}
