//! From the camera to the forecast, replicated (issue 37's coverage target): 16 test films of
//! the lab pendulum from nearby releases (src/track/synth.rs, 640 x 360, 10 s at 30 frames a
//! second), each tracked, fitted on a window and forecast as `chaoscope forecast` does; the
//! truth's share inside the model's 90 % band after the window and before the spread
//! horizon, the truth taken relative to the pivot (and, beside it, where the picture puts the
//! markers: see the scoring below). Prints one line per film and the pooled share; writes
//! into DIR each film (filmK.mp4), its track (filmK.csv), the exposures' mean positions
//! (film_truthK.csv: t, x1, y1, x2, y2 in px), the forecast (forecastK/) and the truth beside
//! its band (truthK.csv: t, coordinate, truth, p05, median, p95, the truth in the picture;
//! m).
//!
//!     cargo run --release --example track_coverage -- [FILMS] [DIR] [FIRST] [CRF]

use chaoscope::app::forecast::{ForecastJob, run as forecast};
use chaoscope::app::track::{TrackJob, run as track};
use chaoscope::engine::{Backend, Engine};
use chaoscope::forecast::outcome::ForecastSettings;
use chaoscope::model::State;
use chaoscope::monitor::Monitor;
use chaoscope::params::{ParamSources, Preset};
use chaoscope::spec::Precision;
use chaoscope::track::synth::{Scene, film};
use chaoscope::track::{Markers, Scale};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let films: usize = args.first().map_or(Ok(16), |s| s.parse())?;
    let dir = std::path::PathBuf::from(args.get(1).map_or("out/track-coverage", String::as_str));
    // Another set of films (FIRST .. FIRST + FILMS: the same releases, other noise), and
    // the encoder's quality (CRF 0 is lossless: the tracker's errors without the codec's).
    let first: usize = args.get(2).map_or(Ok(0), |s| s.parse())?;
    let crf: u32 = args.get(3).map_or(Ok(18), |s| s.parse())?;
    std::fs::create_dir_all(&dir)?;
    let p = Preset::Lab.params();
    let engine = Engine::in_precision(Backend::Auto, Precision::F32)?;
    let quiet = Monitor::hidden();
    let (mut inside, mut inside_picture, mut counted) = (0usize, 0usize, 0usize);
    let mut shares = Vec::new();
    for k in first..first + films {
        // Sixteen releases; films past the sixteenth repeat them under other noise.
        let release = (k % 16) as f64;
        let start = State {
            theta1: -1.4 - 0.02 * release,
            omega1: 0.0,
            theta2: 1.2 + 0.03 * release,
            omega2: 0.0,
        };
        let scene = Scene {
            seed: k as u64 + 1,
            ..Scene::lab(640, 360, p.l1 + p.l2)
        };
        let video = dir.join(format!("film{k}.mp4"));
        let truth_rows = film(&scene, &p, start, 300, crf, &video)?;
        let csv = video.with_extension("csv");
        // The exposures' mean positions (px) beside the tracked ones, as the films' tests
        // compare them: the tracker's own error, apart from the forecast's.
        std::fs::write(
            dir.join(format!("film_truth{k}.csv")),
            truth_rows
                .iter()
                .map(|r| format!("{},{},{},{},{}\n", r.t, r.m1.0, r.m1.1, r.m2.0, r.m2.1))
                .collect::<String>(),
        )?;
        let tracked = track(
            &TrackJob {
                video: video.clone(),
                output: csv.clone(),
                markers: Markers::Bright,
                scale: Scale::UpperArm(p.l1),
                region: None,
                bridge: None,
            },
            None,
            "track_coverage",
            &quiet,
        )?;
        let out = dir.join(format!("forecast{k}"));
        let job = ForecastJob {
            file: csv,
            output: out.clone(),
            units: Default::default(),
            settings: ForecastSettings {
                window: Some((0.8, 2.3)),
                members: 10_000,
                seed: k as u64 + 1,
                tolerance: Some(0.03),
                tracking_error: std::env::var("TRACKING_ERROR")
                    .ok()
                    .and_then(|v| v.parse().ok()),
                candidates: 65_536,
                // The model is the truth here: no model error to measure.
                held_out: 0,
                ahead: None,
                in_sample: false,
            },
            params: ParamSources {
                preset: Some(Preset::Lab),
                ..ParamSources::default()
            },
            backend: Backend::Auto,
            precision: Precision::F32,
            video: None,
        };
        let s = forecast(
            &job,
            &chaoscope::app::Running::new(&engine, "track_coverage".into(), &quiet),
        )?;
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json"))?)?;
        let pivot = (
            summary["pivot"][0].as_f64().unwrap_or(0.0),
            summary["pivot"][1].as_f64().unwrap_or(0.0),
        );
        let text = std::fs::read_to_string(out.join("bands.csv"))?;
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
            .map(|l| {
                l.split(',')
                    .map(|v| v.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        let end = rows.last().map_or(0.0, |r| r[0]);
        let until = s.spread_horizon.unwrap_or(end);
        let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let dt = 1e-4;
        let truth = chaoscope::cpu::positions(&p, start, dt, (end / dt).ceil() as u32 + 1, &times);
        // The truth in the track's metres (its scale, y up). The forecast's positions are
        // relative to the pivot: the track's origin is the centre of the upper marker's
        // circle, and the window's fit places the pivot near it (the summary's fit values).
        // The truth is scored relative to the scene's pivot, placed where the fit puts the
        // pivot: the pendulum's own positions. H.264 moves every marker in the picture by
        // the same fraction of a pixel (0.018, 0.026 px at CRF 18 against none at CRF 0 on
        // the same frames), and the pivot found from the markers moves with them, so that
        // the positions relative to it hold; the marker's place in the picture, before the
        // encoder moved it (its distance from the track's origin), is scored beside.
        let ppm = tracked.pixels_per_metre;
        let in_track = |x: f64, y: f64| {
            let (px, py) = scene.to_pixels(x, y);
            (
                (px - tracked.pivot_px.0) / ppm,
                (tracked.pivot_px.1 - py) / ppm,
            )
        };
        let offset = in_track(0.0, 0.0);
        let fitted = &summary["fit"]["values"];
        let fit_pivot = (
            fitted[6].as_f64().unwrap_or(0.0),
            fitted[7].as_f64().unwrap_or(0.0),
        );
        let (mut n_in, mut n_in_picture, mut n) = (0, 0, 0);
        let mut dump = String::from("t,c,truth,p05,median,p95,in_picture\n");
        for (r, q) in rows.iter().zip(&truth) {
            let (m1, m2) = (in_track(q.x1, q.y1), in_track(q.x2, q.y2));
            let in_picture = [
                m1.0 - pivot.0,
                m1.1 - pivot.1,
                m2.0 - pivot.0,
                m2.1 - pivot.1,
            ];
            let from_pivot = [
                m1.0 - offset.0 + fit_pivot.0,
                m1.1 - offset.1 + fit_pivot.1,
                m2.0 - offset.0 + fit_pivot.0,
                m2.1 - offset.1 + fit_pivot.1,
            ];
            // Scored after the window and before the spread horizon; written throughout.
            let scored = r[0] > s.window.1 + 1e-9 && r[0] < until;
            for c in 0..4 {
                let (x, seen) = (from_pivot[c], in_picture[c]);
                let (lo, median, hi) = (r[1 + 10 * c], r[1 + 10 * c + 2], r[1 + 10 * c + 4]);
                dump += &format!("{},{c},{x},{lo},{median},{hi},{seen}\n", r[0]);
                if scored {
                    n += 1;
                    n_in += (lo..=hi).contains(&x) as usize;
                    n_in_picture += (lo..=hi).contains(&seen) as usize;
                }
            }
        }
        std::fs::write(dir.join(format!("truth{k}.csv")), dump)?;
        inside += n_in;
        shares.push(n_in as f64 / n.max(1) as f64);
        inside_picture += n_in_picture;
        counted += n;
        println!(
            "film {k}: release ({:.2}, {:.2}); the tracker's pivot off by ({:.3}, {:.3}) mm, its scale by {:.1e}; spread horizon {}; coverage {:.1} % of {n} ({:.1} % where the picture puts the markers)",
            start.theta1,
            start.theta2,
            1e3 * offset.0,
            1e3 * offset.1,
            scene.pixels_per_metre / ppm - 1.0,
            s.spread_horizon
                .map_or("beyond the film".into(), |h| format!("{h:.2} s")),
            100.0 * n_in as f64 / n.max(1) as f64,
            100.0 * n_in_picture as f64 / n.max(1) as f64
        );
    }
    println!(
        "pooled: the truth inside the model's 90 % band {:.1} % of {counted} coordinates ({:.1} % where the picture puts the markers); mean of the films' {:.1} %",
        100.0 * inside as f64 / counted.max(1) as f64,
        100.0 * inside_picture as f64 / counted.max(1) as f64,
        100.0 * shares.iter().sum::<f64>() / shares.len().max(1) as f64
    );
    Ok(())
}
