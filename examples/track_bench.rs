//! The tracker's benchmark (BENCH.md, "Tracking"): test films with a known truth
//! (src/track/synth.rs) at 1280 x 720 and 1920 x 1080, 30 frames a second, sharp (1/2000 s)
//! and blurred (1/60 s), with a lamp and a reflection, and with a table's edge hiding the
//! masses; each tracked as `chaoscope track` does (decoding included) and scored against its
//! truth. Prints a Markdown table. `scripts/track-bench` runs it.
//!
//!     cargo run --release --example track_bench -- [FRAMES] [DIR]

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
    println!("| film | Mbit/s | RMS error (px) | found | invented | swaps | astray | frames/s |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for (w, h) in [(1280u32, 720u32), (1920, 1080)] {
        let lab = Scene::lab(w, h, p.l1 + p.l2);
        let s = w as f64 / 1280.0;
        let cases = [
            ("sharp, 1/2000 s", lab.clone()),
            (
                "blurred, 1/60 s",
                Scene {
                    shutter: 1.0 / 60.0,
                    ..lab.clone()
                },
            ),
            (
                "lamp and reflection",
                Scene {
                    lamp: Some((940.0 * s, 240.0 * s)),
                    reflection: Some(760.0 * s),
                    ..lab.clone()
                },
            ),
            (
                "table edge",
                Scene {
                    table: Some(524.0 * s),
                    ..lab.clone()
                },
            ),
        ];
        for (name, scene) in cases {
            let video = dir.join(format!(
                "{w}x{h}-{}.mp4",
                name.split(',').next().unwrap().replace(' ', "-")
            ));
            // crf 18: some 10-30 Mbit/s with the sensor's noise, what phones record 1080p at.
            let truth = film(&scene, &p, release, frames, 18, &video)?;
            let mbits =
                std::fs::metadata(&video)?.len() as f64 * 8.0 / 1e6 / (frames as f64 / scene.fps);
            let job = TrackJob {
                video: video.clone(),
                output: video.with_extension("csv"),
                markers: Markers::Bright,
                scale: Scale::UpperArm(p.l1),
                region: None,
                bridge: None,
            };
            let started = Instant::now();
            let summary = run(&job, None, "track_bench", &Monitor::hidden())?;
            let fps = summary.frames as f64 / started.elapsed().as_secs_f64();
            let rows = chaoscope::track::read_rows(&job.output)?;
            let ppm = summary.pixels_per_metre;
            let (cx, cy) = summary.pivot_px;
            let px = |m: Option<(f64, f64)>| m.map(|(x, y)| (cx + x * ppm, cy - y * ppm));
            let found: Vec<[Option<(f64, f64)>; 2]> =
                rows.iter().map(|r| [px(r.1), px(r.2)]).collect();
            let sc = score(&found, &truth);
            println!(
                "| {w} x {h}, {name} | {mbits:.0} | {:.3} | {:.2} % | {} | {} | {} | {:.0} |",
                sc.rms,
                100.0 * sc.found,
                sc.invented,
                sc.swaps,
                sc.astray,
                fps
            );
        }
    }
    Ok(())
}
