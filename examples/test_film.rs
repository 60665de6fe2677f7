//! A test film with a known truth (src/track/synth.rs): the lab pendulum's two LEDs rendered
//! from the model's trajectory, encoded as H.264 by FFmpeg, and the truth as CSV beside it
//! (t, the markers' mean positions over each exposure in px and in m, whether each was in
//! view). `scripts/test-films` makes the repository's film and the tracker's benchmark.
//!
//!     cargo run --release --example test_film -- OUT.mp4 [WIDTHxHEIGHT] [FRAMES] [options]
//!
//! options: --shutter S (s, default 1/2000), --lamp X,Y, --reflection X (a pane's column),
//! --table Y (the table's edge, px row), --roll A (the camera's roll, rad), --rest S (s
//! hanging still before the release), --lift S (s lifted by hand after the rest), --hand
//! (a hand comes in during the rest, holds the lower mass through the lift and is pulled
//! away at the release), --seed N, --crf Q, --theta1 A --theta2 B, --fps F (frames a
//! second, default 30), --params FILE.toml (the pendulum filmed, default the lab preset;
//! its markers at the middle joint and the lower arm's end), --stickers C1,C2[,C3]
//! (coloured stickers on a lit, textured board instead of LEDs in the dark: the upper and
//! the lower one's colours and the pivot's, as `track --markers` takes them),
//! --pivot-marker (an LED on the axle), --wander PX (the picture wanders by this much, the
//! pivot's marker with it), --marker-sigma PX (a marker's size, default 2.5), --ghost
//! DX,DY,SHARE (both markers again, shifted by DX,DY px at SHARE of their brightness: a
//! reflection that moves with the pendulum).

use std::io::Write;

use chaoscope::model::State;
use chaoscope::params::Preset;
use chaoscope::track::synth::{Scene, film};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = std::path::PathBuf::from(
        args.first()
            .ok_or("usage: test_film OUT.mp4 [WxH] [FRAMES] [options]")?,
    );
    let positional: Vec<&String> = args[1..]
        .iter()
        .take_while(|a| !a.starts_with("--"))
        .collect();
    let (w, h) = match positional.first() {
        Some(s) => {
            let (w, h) = s.split_once('x').ok_or("size as WIDTHxHEIGHT")?;
            (w.parse()?, h.parse()?)
        }
        None => (1280, 720),
    };
    let frames: usize = positional.get(1).map_or(Ok(300), |s| s.parse())?;
    let option = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|k| args.get(k + 1))
            .cloned()
    };
    let number = |name: &str| option(name).map(|v| v.parse::<f64>()).transpose();
    let p = match option("--params") {
        Some(file) => chaoscope::params::ParamSources {
            params: Some(file.into()),
            ..Default::default()
        }
        .resolve()?,
        None => Preset::Lab.params(),
    };
    let mut scene = Scene::lab(w, h, p.l1 + p.l2);
    if let Some(f) = number("--fps")? {
        scene.fps = f;
    }
    if let Some(s) = number("--shutter")? {
        scene.shutter = s;
    }
    if let Some(v) = option("--lamp") {
        let (x, y) = v.split_once(',').ok_or("--lamp X,Y")?;
        scene.lamp = Some((x.parse()?, y.parse()?));
    }
    scene.reflection = number("--reflection")?;
    if let Some(v) = option("--ghost") {
        let v: Vec<f64> = v.split(',').map(str::parse).collect::<Result<_, _>>()?;
        let [dx, dy, share] = v[..] else {
            return Err("--ghost DX,DY,SHARE".into());
        };
        scene.ghost = Some(((dx, dy), share));
    }
    scene.table = number("--table")?;
    scene.roll = number("--roll")?.unwrap_or(0.0);
    scene.rest = number("--rest")?.unwrap_or(0.0);
    scene.lift = number("--lift")?.unwrap_or(0.0);
    if let Some(m) = option("--stickers") {
        scene.stickers = Some(match chaoscope::track::Markers::parse(&m)? {
            chaoscope::track::Markers::Colours {
                upper,
                lower,
                pivot,
            } => {
                scene.pivot_marker = pivot.or(scene.pivot_marker);
                [upper, lower]
            }
            chaoscope::track::Markers::Colour(c) => [c, c],
            chaoscope::track::Markers::Bright => return Err("--stickers C1,C2".into()),
        });
    }
    if args.iter().any(|a| a == "--pivot-marker") {
        scene.pivot_marker = scene.pivot_marker.or(Some([255; 3]));
    }
    scene.wander = number("--wander")?.unwrap_or(0.0);
    scene.hand = args.iter().any(|a| a == "--hand");
    if let Some(s) = number("--marker-sigma")? {
        scene.marker_sigma = s;
    }
    if let Some(s) = number("--seed")? {
        scene.seed = s as u64;
    }
    let crf = number("--crf")?.map_or(18, |c| c as u32);
    let start = State {
        theta1: number("--theta1")?.unwrap_or(2.0),
        omega1: 0.0,
        theta2: number("--theta2")?.unwrap_or(2.6),
        omega2: 0.0,
    };
    let truth = film(&scene, &p, start, frames, crf, &out)?;
    let mut csv = std::io::BufWriter::new(std::fs::File::create(out.with_extension("truth.csv"))?);
    writeln!(
        csv,
        "# the truth of {}: the markers' mean positions over each exposure (px as the picture would show them had it not wandered; its wander in shift_x, shift_y)",
        out.display()
    )?;
    writeln!(
        csv,
        "t,px1,py1,px2,py2,x1,y1,x2,y2,seen1,seen2,shift_x,shift_y"
    )?;
    let seen = |s: Option<bool>| match s {
        Some(true) => "in_view",
        Some(false) => "hidden",
        None => "partly",
    };
    for r in &truth {
        let m = r.metres;
        writeln!(
            csv,
            "{:.6},{:.4},{:.4},{:.4},{:.4},{:.6},{:.6},{:.6},{:.6},{},{},{:.4},{:.4}",
            r.t,
            r.m1.0,
            r.m1.1,
            r.m2.0,
            r.m2.1,
            m[0],
            m[1],
            m[2],
            m[3],
            seen(r.seen1),
            seen(r.seen2),
            r.shift.0,
            r.shift.1
        )?;
    }
    csv.flush()?;
    eprintln!("{} frames of {w}x{h} -> {}", truth.len(), out.display());
    Ok(())
}
