//! Whether the identified moments' stated errors hold on films: `cargo run --release
//! --example film_identify_coverage -- [FILMS] [DIR]` films FILMS (20) seeded compound
//! pendulums (bars with bobs, 50 g to 5 kg, a heavy upper arm, released high) as a phone
//! sees red and green stickers on a lit board (src/track/synth.rs: 640 x 360 at 60 frames a
//! second for 12 s, H.264), tracks each (`chaoscope track`'s job), reads the track as `fit`
//! does and identifies the pendulum from its motion alone; then counts how often the truth
//! lies inside each moment's 95 % interval (1.96 standard errors). Writes the films and
//! tracks into DIR (out/film-coverage).

use chaoscope::app::track::{TrackJob, run as track};
use chaoscope::fit::identify::MOMENTS;
use chaoscope::fit::pendulum::tracked_model;
use chaoscope::model::{Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::track::synth::{Scene, film};
use chaoscope::track::{Markers, Scale};
use rand::{Rng, SeedableRng};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let films: usize = args.first().map_or(Ok(20), |s| s.parse())?;
    let dir = std::path::PathBuf::from(args.get(1).map_or("out/film-coverage", String::as_str));
    std::fs::create_dir_all(&dir)?;
    let quiet = Monitor::hidden();
    let mut inside = [0usize; 4];
    let mut identified = 0;
    for seed in 0..films as u64 {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1000 + seed);
        let scale = 10f64.powf(rng.random_range(-1.3..0.7));
        let mut p = Params {
            m1: scale * rng.random_range(0.01..0.1),
            m2: scale * rng.random_range(0.001..0.02),
            l1: rng.random_range(0.15..0.3),
            l2: rng.random_range(0.12..0.25),
            g: 9.81,
            rod1: scale * rng.random_range(0.1..0.3),
            rod2: scale * rng.random_range(0.02..0.05),
            ..Params::default()
        };
        let k = p.inertia();
        // Light joint damping: an e-fold of the swing in tens of seconds.
        (p.losses.joint1, p.losses.joint2) = (2e-3 * k.a, 2e-3 * k.b);
        let start = State::at_rest(rng.random_range(1.6..2.6), rng.random_range(1.5..3.0));
        let scene = Scene {
            fps: 60.0,
            shutter: 1.0 / 120.0,
            stickers: Some([[0xe0, 0x20, 0x20], [0x20, 0xa0, 0x40]]),
            seed: seed + 1,
            ..Scene::lab(640, 360, p.l1 + p.l2)
        };
        let video = dir.join(format!("film{seed}.mp4"));
        film(&scene, &p, start, 720, 23, &video)?;
        let csv = video.with_extension("csv");
        track(
            &TrackJob {
                video: video.clone(),
                output: csv.clone(),
                markers: Markers::Colours {
                    upper: [0xe0, 0x20, 0x20],
                    lower: [0x20, 0xa0, 0x40],
                    pivot: None,
                },
                scale: Scale::UpperArm(p.l1),
                region: None,
                bridge: None,
            },
            None,
            "film_identify_coverage",
            &quiet,
        )?;
        let units = Default::default();
        let rows = chaoscope::fit::read_frames(&csv, &units)?;
        let tracked = tracked_model(&rows, &Default::default(), &units, &quiet)?;
        let truth = [k.a / k.p, k.b / k.p, k.c / k.p, k.q / k.p];
        match &tracked.identified {
            Ok(id) => {
                identified += 1;
                for (j, hit) in inside.iter_mut().enumerate() {
                    *hit += ((id.values[j] - truth[j]).abs() <= 1.96 * id.errors[j]) as usize;
                }
                println!(
                    "film {seed}: masses x{scale:.2}: {}; misfit {:.1e} {:.1e}",
                    (0..4)
                        .map(|j| format!(
                            "{} {:+.2} sd (rel. error {:.1e})",
                            MOMENTS[j],
                            (id.values[j] - truth[j]) / id.errors[j],
                            id.errors[j] / truth[j]
                        ))
                        .collect::<Vec<_>>()
                        .join(", "),
                    id.misfit[0],
                    id.misfit[1]
                );
            }
            Err(e) => println!("film {seed}: not identified: {e}"),
        }
    }
    println!("\n{identified} of {films} identified; the truth inside the 95 % interval:");
    for j in 0..4 {
        println!(
            "  {}: {} of {identified} ({:.0} %)",
            MOMENTS[j],
            inside[j],
            100.0 * inside[j] as f64 / identified.max(1) as f64
        );
    }
    Ok(())
}
