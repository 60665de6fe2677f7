//! `chaoscope track`.

use std::path::PathBuf;

use clap::Args;

use super::args::preset_parser;
use super::parse::parse_number;
use super::{command_line, json, say};
use crate::app::track::{self, TrackJob};
use crate::engine::Backend;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::params::{ParamSources, Preset};
use crate::track::{Markers, Scale};

#[derive(Args, Debug, Clone)]
pub struct TrackArgs {
    /// The film of the pendulum (MP4, MOV...: any FFmpeg reads), its markers in view.
    pub video: PathBuf,
    /// The CSV to write: t, x1, y1, x2, y2 (s, m; origin at the pivot, y up), as `fit` and
    /// `forecast` read it, with how each row was obtained and its uncertainty.
    #[arg(long, default_value = "out/track.csv")]
    pub output: PathBuf,
    /// The upper arm's length (m), pivot to the upper marker: the scale.
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true, required_unless_present = "pixels_per_metre", conflicts_with = "pixels_per_metre")]
    pub l1: Option<f64>,
    /// The scale in pixels per metre, instead of --l1; `motion`: the scale the swing implies
    /// under g (9.81 m/s^2) at the film's own frame times (a rigid pendulum's motion fixes
    /// l1/g in seconds: some 8 s of swinging at 60 frames a second or more).
    #[arg(long, value_parser = super::args::parse_pixel_scale, allow_hyphen_values = true)]
    pub pixels_per_metre: Option<crate::fit::data::PixelScale>,
    /// What the markers look like: bright (lights on a dark background), one colour for
    /// both (stickers on a lighter or other-coloured board), or two as UPPER,LOWER (the
    /// upper mass's first), or three as UPPER,LOWER,PIVOT with a marker on the pivot. A
    /// colour as RRGGBB (e.g. ff2020) or a name: red, orange, yellow, green, cyan, blue,
    /// purple, magenta, pink. What counts is the hue, so a sticker in shade or under a
    /// lighting gradient is still found; colours must differ in hue by more than 60 degrees.
    /// A marker that stays at the pivot (of its own colour, or like the masses') is found
    /// by itself: the masses are then measured from it frame by frame, so that a camera or
    /// stand that creeps moves nothing.
    #[arg(long, default_value = "bright", value_parser = Markers::parse)]
    pub markers: Markers,
    /// Look only within X0,Y0,X1,Y1 (pixels from the top left corner).
    #[arg(long, value_parser = parse_region)]
    pub region: Option<(u32, u32, u32, u32)>,
    /// Bridge gaps where a mass is hidden (up to 1 s, with 5 rows measured on each side) by
    /// the model fitted to the half second of measured rows on each side: those places
    /// are marked `bridged` with the model's standard errors, and `fit` and `forecast` read
    /// only the measured rows.
    #[arg(long)]
    pub bridge: bool,
    /// The model that bridges: a named set of parameters [default: lab, unless --params is
    /// given]; the arms' lengths come from the track.
    #[arg(long, value_parser = preset_parser(), requires = "bridge")]
    pub preset: Option<Preset>,
    /// The model that bridges, from a TOML parameter file (as `--params` elsewhere).
    #[arg(long, requires = "bridge")]
    pub params: Option<PathBuf>,
}

fn parse_region(s: &str) -> std::result::Result<(u32, u32, u32, u32), String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("{s}: X0,Y0,X1,Y1 in whole pixels"))?;
    match v[..] {
        [x0, y0, x1, y1] => Ok((x0, y0, x1, y1)),
        _ => Err(format!("{s}: X0,Y0,X1,Y1 in whole pixels")),
    }
}

impl TrackArgs {
    pub fn job(&self) -> Result<TrackJob> {
        Ok(TrackJob {
            video: self.video.clone(),
            output: self.output.clone(),
            markers: self.markers,
            scale: Scale::asked(self.l1, self.pixels_per_metre)?,
            region: self.region,
            bridge: self.bridge.then(|| ParamSources {
                preset: self.preset,
                params: self.params.clone(),
                ..ParamSources::default()
            }),
        })
    }
}

pub fn run(args: &TrackArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job()?;
    // Only bridging integrates the model.
    let engine = match job.bridge {
        Some(_) => Some(super::args::lent_engine(None, Backend::Auto)?),
        None => None,
    };
    let s = track::run(&job, engine.as_ref(), &command_line::track(&job), monitor)?;
    say("track", &s.notices);
    eprintln!(
        "{} frames ({} {}x{}, {:.1} s at {} frames a second), tracked at {:.0} frames a second of processing: upper mass measured in {:.1} %, lower in {:.1} %; pivot ({:.1}, {:.1}) px, {:.1} px per metre, {}; up {}; {} still blobs set aside -> {}",
        s.frames,
        s.codec,
        s.width,
        s.height,
        s.duration,
        match s.frame_rate.fract() {
            0.0 => format!("{:.0}", s.frame_rate),
            _ => format!("{:.3}", s.frame_rate),
        },
        s.processing_frames_per_second,
        100.0 * s.seen1,
        100.0 * s.seen2,
        s.pivot_px.0,
        s.pivot_px.1,
        s.pixels_per_metre,
        match s.l2 {
            Some(l2) => format!("lower arm {l2:.4} m"),
            None => "the lower mass never measured: no lower arm".into(),
        },
        match s.up.rest {
            Some((a, b)) => format!(
                "from the rest at {a:.1}..{b:.1} s ({:+.2} degrees from the picture's)",
                s.up.tilt_degrees
            ),
            None => "the picture's (no rest seen)".into(),
        },
        s.still.len(),
        s.output.display()
    );
    if let Some(p) = &s.pivot_marker {
        eprintln!(
            "positions taken from the pivot's marker at ({:.1}, {:.1}) px, measured in {:.1} % of the frames; it wandered {:.2} px RMS",
            p.place.0,
            p.place.1,
            100.0 * p.seen,
            p.wander
        );
    }
    match s.release {
        Some(t) => eprintln!(
            "released at {t:.3} s (the last still frame before it swings){}: fit and forecast read the free motion from there",
            match s.lift {
                Some((a, b)) => format!(", lifted {a:.2}..{b:.2} s"),
                None => String::new(),
            }
        ),
        None => eprintln!("no release seen: the film shows the pendulum swinging from its start"),
    }
    if let Some(b) = &s.bridged {
        eprintln!(
            "bridged {} gap(s) by the model ({} places), {} left open{}",
            b.gaps,
            b.places,
            b.left_open.len(),
            b.left_open
                .iter()
                .map(|(a, b, why)| format!("\n  {a:.3}..{b:.3} s: {why}"))
                .collect::<String>()
        );
    }
    json(&s)
}
