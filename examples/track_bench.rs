//! The tracker's benchmark (BENCH.md, "Tracking"): test films with a known truth
//! (src/track/synth.rs) at 1280 x 720 and 1920 x 1080, 30 frames a second, sharp (1/2000 s)
//! and blurred (1/60 s), with a lamp and a reflection, and with a table's edge hiding the
//! masses; a phone's portrait film of red and green stickers on a lit board; a reflection
//! that moves with the pendulum; a marker on the pivot with the picture wandering; three
//! stickers and a hand that lifts the pendulum and lets it go. Each tracked as `chaoscope track` does (decoding included)
//! and scored against its truth, with the share of its errors within 1.96 of the stated
//! standard errors. Prints a Markdown table.
//!
//!     cargo run --release --example track_bench -- [FRAMES] [DIR] [FILM]
//!
//! FILM: only the films whose name holds it (e.g. `stickers`).

use std::time::Instant;

use chaoscope::app::track::{TrackJob, run};
use chaoscope::model::State;
use chaoscope::monitor::Monitor;
use chaoscope::params::Preset;
use chaoscope::track::synth::{Scene, film, score};
use chaoscope::track::{Markers, Scale};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: usize = args.first().map_or(Ok(300), |s| s.parse())?;
    let dir = std::path::PathBuf::from(args.get(1).map_or("out/track-bench", String::as_str));
    std::fs::create_dir_all(&dir)?;
    let p = Preset::Lab.params();
    let release = State {
        theta1: 2.0,
        omega1: 0.0,
        theta2: 2.6,
        omega2: 0.0,
    };
    println!(
        "| film | Mbit/s | RMS error (px) | found | invented | swaps | astray | within 1.96 stated sigma | release found (true) | frames/s |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut cases: Vec<(String, Scene, Markers)> = Vec::new();
    for (w, h) in [(1280u32, 720u32), (1920, 1080)] {
        let lab = Scene::lab(w, h, p.l1 + p.l2);
        let s = w as f64 / 1280.0;
        let named =
            |name: &str, scene: Scene| (format!("{w} x {h}, {name}"), scene, Markers::Bright);
        cases.extend([
            named("sharp, 1/2000 s", lab.clone()),
            named(
                "blurred, 1/60 s",
                Scene {
                    shutter: 1.0 / 60.0,
                    ..lab.clone()
                },
            ),
            named(
                "lamp and reflection",
                Scene {
                    lamp: Some((940.0 * s, 240.0 * s)),
                    reflection: Some(760.0 * s),
                    ..lab.clone()
                },
            ),
            named(
                "table edge",
                Scene {
                    table: Some(524.0 * s),
                    ..lab.clone()
                },
            ),
        ]);
    }
    // A phone held upright: red and green stickers of 6 px on a textured board lit from
    // one side, 60 frames a second at 1/120 s, the camera rolled 2.5 degrees, the
    // pendulum hanging still for the first 1.5 s.
    let stickers = [[0xe0, 0x20, 0x20], [0x20, 0xa0, 0x40]];
    cases.push((
        "1080 x 1920, red and green stickers, 60 frames/s, rolled".into(),
        Scene {
            fps: 60.0,
            shutter: 1.0 / 120.0,
            roll: 2.5f64.to_radians(),
            rest: 1.5,
            stickers: Some(stickers),
            marker_sigma: 6.0,
            ..Scene::lab(1080, 1920, p.l1 + p.l2)
        },
        Markers::Colours {
            upper: stickers[0],
            lower: stickers[1],
            pivot: None,
        },
    ));
    // A second reflection of the whole pendulum (a glossy board): both LEDs again, 47 px
    // off, a quarter as bright, at 1/60 s.
    cases.push((
        "1280 x 720, reflection moving with the pendulum, 1/60 s".into(),
        Scene {
            shutter: 1.0 / 60.0,
            ghost: Some(((40.0, 25.0), 0.25)),
            ..Scene::lab(1280, 720, p.l1 + p.l2)
        },
        Markers::Bright,
    ));
    // A marker on the axle, the picture wandering by a pixel (a tripod that creeps).
    cases.push((
        "1280 x 720, pivot marker, the picture wandering 1 px".into(),
        Scene {
            pivot_marker: Some([255; 3]),
            wander: 1.0,
            ..Scene::lab(1280, 720, p.l1 + p.l2)
        },
        Markers::Bright,
    ));
    // A teacher's film: red, green and blue (pivot) stickers, 60 frames a second, the
    // pendulum hanging still, then lifted by a hand that comes into the picture and lets
    // go, the stand creeping by half a pixel.
    cases.push((
        "1280 x 720, three stickers, a hand lifts and releases, 60 frames/s".into(),
        Scene {
            fps: 60.0,
            shutter: 1.0 / 120.0,
            rest: 1.5,
            lift: 1.0,
            hand: true,
            wander: 0.5,
            stickers: Some(stickers),
            pivot_marker: Some([0x20, 0x40, 0xe0]),
            marker_sigma: 5.0,
            ..Scene::lab(1280, 720, p.l1 + p.l2)
        },
        Markers::Colours {
            upper: stickers[0],
            lower: stickers[1],
            pivot: Some([0x20, 0x40, 0xe0]),
        },
    ));
    let only = args.get(2);
    for (name, scene, markers) in cases {
        if only.is_some_and(|only| !name.contains(only.as_str())) {
            continue;
        }
        let video = dir.join(format!(
            "{}.mp4",
            name.split(',')
                .take(2)
                .collect::<String>()
                .replace([' ', '/'], "-")
        ));
        // crf 18: some 10-30 Mbit/s with the sensor's noise, what phones record 1080p at.
        let truth = film(&scene, &p, release, frames, 18, &video)?;
        let mbits =
            std::fs::metadata(&video)?.len() as f64 * 8.0 / 1e6 / (frames as f64 / scene.fps);
        let job = TrackJob {
            video: video.clone(),
            output: video.with_extension("csv"),
            markers,
            scale: Scale::UpperArm(p.l1),
            region: None,
            bridge: None,
        };
        let started = Instant::now();
        let summary = run(&job, None, "track_bench", &Monitor::hidden())?;
        let fps = summary.frames as f64 / started.elapsed().as_secs_f64();
        let rows = chaoscope::track::read_rows(&job.output)?;
        let placed = chaoscope::track::file::header_of(&job.output, "file")?.placement;
        let px = |m: Option<chaoscope::track::Measured>| m.map(|m| placed.pixels(m.x, m.y));
        let found: Vec<[Option<(f64, f64)>; 2]> = rows.iter().map(|r| [px(r.1), px(r.2)]).collect();
        let sc = score(&found, &truth);
        let calibration = chaoscope::track::synth::calibration(&rows, &truth);
        println!(
            "| {name} | {mbits:.0} | {:.3} | {:.2} % | {} | {} | {} | {:.1} % | {} | {fps:.0} |",
            sc.rms,
            100.0 * sc.found,
            sc.invented,
            sc.swaps,
            sc.astray,
            100.0 * calibration,
            match (scene.rest > 0.0, summary.release) {
                (false, None) => "none, none shown".to_string(),
                (true, Some(t)) => format!("{t:.3} s ({:.3} s)", scene.rest + scene.lift),
                (true, None) => format!("not found ({:.3} s)", scene.rest + scene.lift),
                (false, Some(t)) => format!("{t:.3} s where none was shown"),
            },
        );
    }
    Ok(())
}
