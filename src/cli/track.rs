//! `chaoscope track`.

use std::path::PathBuf;

use clap::Args;

use super::parse::parse_number;
use super::{command_line, json, say};
use crate::app::track::{self, TrackJob};
use crate::error::Result;
use crate::monitor::Monitor;
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
    /// The scale in pixels per metre, instead of --l1.
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub pixels_per_metre: Option<f64>,
    /// What the markers look like: bright (lights on a dark background) or a colour as
    /// RRGGBB (coloured markers on a lighter or other-coloured background, e.g. ff2020).
    #[arg(long, default_value = "bright", value_parser = Markers::parse)]
    pub markers: Markers,
    /// Look only within X0,Y0,X1,Y1 (pixels from the top left corner).
    #[arg(long, value_parser = parse_region)]
    pub region: Option<(u32, u32, u32, u32)>,
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
    pub fn job(&self) -> TrackJob {
        TrackJob {
            video: self.video.clone(),
            output: self.output.clone(),
            markers: self.markers,
            scale: match (self.l1, self.pixels_per_metre) {
                (Some(l1), _) => Scale::UpperArm(l1),
                (None, Some(p)) => Scale::PixelsPerMetre(p),
                // clap requires one of them.
                (None, None) => Scale::UpperArm(f64::NAN),
            },
            region: self.region,
        }
    }
}

pub fn run(args: &TrackArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job();
    let s = track::run(&job, &command_line::track(&job), monitor)?;
    say("track", &s.notices);
    eprintln!(
        "{} frames ({} {}x{}, {:.1} s) at {:.0} frames/s: upper mass measured in {:.1} %, lower in {:.1} %; pivot ({:.1}, {:.1}) px, {:.1} px per metre, lower arm {:.4} m; {} still blobs set aside -> {}",
        s.frames,
        s.codec,
        s.width,
        s.height,
        s.duration,
        s.frames_per_second,
        100.0 * s.seen1,
        100.0 * s.seen2,
        s.pivot_px.0,
        s.pivot_px.1,
        s.pixels_per_metre,
        s.l2,
        s.still.len(),
        s.output.display()
    );
    json(&s)
}
