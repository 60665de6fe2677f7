//! The forecast drawn on the footage (`forecast --video`): the film's own frames with the
//! tracked markers ringed, the fitted model's arms over its window, then the ensemble's
//! 90 % band of each mass and its median arms, and the horizon named: where the model loses
//! the real pendulum, to be seen. Frames are decoded, drawn on and encoded one at a time.

use std::path::Path;

use plotters::prelude::*;

use crate::error::{Error, Result};
use crate::fit::TrackedRow;
use crate::forecast::outcome::Outcome;
use crate::monitor::Monitor;
use crate::render::Outputs;
use crate::track::file::Placement;
use crate::video::{Decoder, Mp4, Pixels};

/// What to draw: the tracked rows (m, from the fitted `pivot`), the forecast, the horizon.
pub struct Overlay<'a> {
    pub rows: &'a [TrackedRow],
    /// Where the track lies in the film (the tracked file's header).
    pub geometry: Placement,
    /// The fitted pivot (m, in the CSV's frame) the forecast's positions are relative to.
    pub pivot: (f64, f64),
    /// The roll (rad) the track was levelled by ([`crate::fit::level`]): turned back here.
    pub roll: f64,
    pub outcome: &'a Outcome,
    /// The forecast's headline horizon ([`crate::forecast::Forecast::headline`]), found once.
    pub headline: crate::forecast::Headline,
    /// The lower bob's spread (m) that ends the forecast's horizon.
    pub tolerance: f64,
}

/// Stages `path`, an MP4 of the frames of `video` with `overlay` drawn on them, at the
/// film's own rate ([`crate::video::Probe::frame_rate`]), `command` (which reproduces it)
/// in its metadata.
pub fn write(
    files: &mut Outputs,
    path: &Path,
    video: &Path,
    overlay: &Overlay,
    command: &str,
    monitor: &Monitor,
) -> Result<()> {
    let placement = overlay.geometry;
    let mut decoder = Decoder::open(video, Pixels::Rgb).map_err(|e| e.as_input("video"))?;
    let (w, h) = (decoder.probe.width, decoder.probe.height);
    let count = decoder.probe.times.len();
    let film = Mp4 {
        fps: decoder.probe.frame_rate().clamp(1.0, 240.0),
        crf: 18,
    };
    // Metres in the forecast's frame to the picture's pixels.
    let (px, py) = overlay.pivot;
    let (s, c) = overlay.roll.sin_cos();
    let at = move |x: f64, y: f64| -> (i32, i32) {
        let (x, y) = (x * c - y * s, y * c + x * s);
        let (u, v) = placement.pixels(x + px, y + py);
        (u.round() as i32, v.round() as i32)
    };
    crate::render::register_font();
    monitor.start("overlay", count as u64);
    let mut frame = Vec::new();
    let result = crate::video::write_mp4(files, path, (w, h), film, command, count, |_| {
        monitor.check()?;
        let t = decoder
            .next_frame(&mut frame)
            .map_err(|e| e.as_input("video"))?
            .ok_or_else(|| Error::format(video, "fewer frames than its timestamps"))?;
        draw(&mut frame, (w, h), t, overlay, &at).map_err(Error::plot)?;
        monitor.advance(1);
        Ok(std::mem::take(&mut frame))
    });
    monitor.finish();
    result
}

const TRACKED: RGBColor = RGBColor(255, 255, 255);
const FITTED: RGBColor = RGBColor(60, 200, 255);
const FORECAST: RGBColor = RGBColor(255, 150, 40);
const LOST: RGBColor = RGBColor(255, 70, 70);

fn draw(
    rgb: &mut [u8],
    (w, h): (u32, u32),
    t: f64,
    o: &Overlay,
    at: &dyn Fn(f64, f64) -> (i32, i32),
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let f = &o.outcome.forecast;
    let root = BitMapBackend::with_buffer(rgb, (w, h)).into_drawing_area();
    // Drawn for a 1280 x 720 frame, scaled by the narrower way, so that the captions (the
    // longest some 1,100 px at that size) fit a portrait phone film's width too.
    let scale = (h as f64 / 720.0).min(w as f64 / 1280.0);
    let px = |v: f64| (v * scale).round().max(1.0) as i32;
    // The model's band at the frame's time (the bands hold every tracked row's time).
    let k = f.times.partition_point(|&x| x < t - 1e-6);
    let band = (t >= f.t0 - 1e-6 && k < f.times.len() && (f.times[k] - t).abs() < 0.011)
        .then(|| &f.model[k]);
    if let Some(b) = band {
        let median = |c: usize| b[c][2];
        let forecasting = t > f.window_end;
        let colour = if forecasting { FORECAST } else { FITTED };
        if forecasting {
            // The 90 % band of each mass: the box between its 5 % and 95 % quantiles.
            for m in 0..2 {
                let (a, z) = (
                    at(b[2 * m][0], b[2 * m + 1][0]),
                    at(b[2 * m][4], b[2 * m + 1][4]),
                );
                root.draw(&Rectangle::new([a, z], colour.mix(0.35).filled()))?;
                root.draw(&Rectangle::new([a, z], colour.stroke_width(px(1.0) as u32)))?;
            }
        }
        let arm = [
            at(0.0, 0.0),
            at(median(0), median(1)),
            at(median(2), median(3)),
        ];
        root.draw(&PathElement::new(
            arm.to_vec(),
            colour.stroke_width(px(3.0) as u32),
        ))?;
        for p in &arm[1..] {
            root.draw(&Circle::new(*p, px(6.0), colour.filled()))?;
        }
    }
    // The tracked markers at this time, ringed.
    let row = o.rows.iter().find(|r| (r.t - t).abs() < 1e-6);
    if let Some(r) = row {
        for (x, y) in [(r.x1, r.y1), (r.x2, r.y2)] {
            let (x, y) = (x - o.pivot.0, y - o.pivot.1);
            root.draw(&Circle::new(
                at(x, y),
                px(11.0),
                TRACKED.stroke_width(px(2.0) as u32),
            ))?;
        }
    }
    captions(&root, (w, h), t, o)?;
    root.present()?;
    Ok(())
}

/// The captions over the frame at time `t`: the time, the stage (tracked, fitted, forecast),
/// and from their moments on the headline horizon and where the median left the track.
fn captions(
    root: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    (w, h): (u32, u32),
    t: f64,
    o: &Overlay,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let f = &o.outcome.forecast;
    // The captions: a line 3 % of the frame's height (legible on a projector, from a phone's
    // portrait film too), wrapped to the frame's width, each on a dark backdrop.
    let size = (0.03 * h as f64).max(11.0);
    let font: TextStyle = ("sans-serif", size).into_font().into();
    let (margin, step) = ((0.5 * size) as i32, (1.3 * size) as i32);
    let next = std::cell::Cell::new(margin);
    let text =
        |s: String, colour: RGBColor| -> std::result::Result<(), Box<dyn std::error::Error>> {
            let room = w.saturating_sub(2 * margin as u32 + 8);
            for piece in wrapped(&s, room, |p| {
                root.estimate_text_size(p, &font).map_or(0, |e| e.0)
            }) {
                let width = root.estimate_text_size(&piece, &font).map_or(0, |e| e.0) as i32;
                let (x, y) = (margin, next.get());
                root.draw(&Rectangle::new(
                    [(x - 4, y - 2), (x + width + 4, y + step - 2)],
                    BLACK.mix(0.6).filled(),
                ))?;
                root.draw(&Text::new(piece, (x, y), font.color(&colour)))?;
                next.set(y + step);
            }
            Ok(())
        };
    text(format!("t = {t:.2} s"), TRACKED)?;
    let stage = if t < f.t0 {
        ("tracked".to_string(), TRACKED)
    } else if t <= f.window_end {
        (
            format!("model fitted to {:.2}..{:.2} s", f.t0, f.window_end),
            FITTED,
        )
    } else {
        (
            format!(
                "forecast: 90 % band of each mass, from {:.2} s",
                f.window_end
            ),
            FORECAST,
        )
    };
    text(stage.0, stage.1)?;
    // The one horizon, from its moment on: where the members say the median leaves the
    // pendulum by the tolerance; then, where the track shows it did.
    if let Some(lead) = o.headline.lead
        && t >= f.window_end + lead
    {
        text(
            format!(
                "past the horizon ({:.2} s after the window): the forecast's median is expected over {:.1} mm from the pendulum",
                lead,
                1e3 * o.tolerance
            ),
            LOST,
        )?;
    }
    let scores = &o.outcome.scores;
    if let Some(lead) = scores
        .median_follows_for
        .filter(|_| !scores.followed_to_data_end)
        && t >= f.window_end + lead
    {
        text(
            format!(
                "from {:.2} s the median is over {:.1} mm from the track",
                f.window_end + lead,
                1e3 * o.tolerance
            ),
            FORECAST,
        )?;
    }
    Ok(())
}

/// `text` in lines no wider than `room` (as `width` measures them), cut between words; a
/// word wider than the room stands on its own line.
fn wrapped(text: &str, room: u32, width: impl Fn(&str) -> u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if width(&format!("{line} {word}")) <= room => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    #[test]
    fn captions_wrap_between_words_within_the_room() {
        // One unit a character: lines of at most 12.
        let lines = super::wrapped("past the horizon (0.42 s after the window)", 12, |s| {
            s.chars().count() as u32
        });
        assert_eq!(
            lines,
            ["past the", "horizon", "(0.42 s", "after the", "window)"]
        );
        assert!(lines.iter().all(|l| l.chars().count() <= 12));
        assert_eq!(
            super::wrapped("unbreakable-word", 4, |s| s.len() as u32),
            ["unbreakable-word"]
        );
    }
}
