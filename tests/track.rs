//! `track` measured against films with a known truth (src/track/synth.rs): markers rendered
//! from the model's trajectory with blur, noise, a lamp, a reflection and a table's edge,
//! encoded as H.264 by FFmpeg, read back by the tracker.

mod common;

use std::path::Path;

use chaoscope::model::State;
use chaoscope::params::Preset;
use chaoscope::track::synth::{Scene, Score, calibration, film, score};
use common::chaoscope;

/// The lab's pendulum released high (it flips), as the report's runs were.
fn release() -> State {
    State {
        theta1: 2.0,
        omega1: 0.0,
        theta2: 2.6,
        omega2: 0.0,
    }
}

/// A tracked row: t and each mass's place in pixels (None: hidden).
type Row = (f64, [Option<(f64, f64)>; 2]);

/// Runs `chaoscope track` on `video` and reads its CSV back into pixels (through the
/// summary's scale and pivot).
fn tracked(video: &Path, extra: &[&str]) -> (Vec<Row>, serde_json::Value) {
    let csv = video.with_extension("csv");
    let o = chaoscope()
        .arg("track")
        .arg(video)
        .args(["--l1", "0.30", "--json", "--output"])
        .arg(&csv)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = common::summary(o);
    let px = to_pixels(&s);
    // Read back by the library's reader of track's CSV (it checks the header, and that a
    // hidden mass has no position).
    let rows = chaoscope::track::read_rows(&csv)
        .unwrap()
        .into_iter()
        .map(|(t, a, b)| (t, [px(a.map(|m| m.at())), px(b.map(|m| m.at()))]))
        .collect();
    (rows, s)
}

/// Metres of track's CSV back to the film's pixels, by the summary's pivot, scale and up.
fn to_pixels(s: &serde_json::Value) -> impl Fn(Option<(f64, f64)>) -> Option<(f64, f64)> + use<> {
    let f = |v: &serde_json::Value| v.as_f64().unwrap();
    let ppm = f(&s["pixels_per_metre"]);
    let (cx, cy) = (f(&s["pivot_px"][0]), f(&s["pivot_px"][1]));
    let (ux, uy) = (f(&s["up"]["direction"][0]), f(&s["up"]["direction"][1]));
    // The world's right in the picture: up turned a quarter clockwise as seen.
    move |m| m.map(|(x, y)| (cx + ppm * (-x * uy + y * ux), cy + ppm * (x * ux + y * uy)))
}

/// Renders `frames` frames of `scene` (the lab pendulum from `start`), tracks the film and
/// scores the rows against the truth (times checked against the frames' own).
fn tracked_scene(
    name: &str,
    scene: &Scene,
    start: State,
    frames: usize,
) -> (Score, serde_json::Value) {
    let (sc, s, _) = scored(name, scene, start, frames, &[]);
    // Every test: at least 99 % of the masses in view measured (the target).
    clean(name, &sc, 0.99);
    (sc, s)
}

/// No mass named for the other, no distractor followed, none placed where it was hidden,
/// and at least `found` of the masses in view measured.
fn clean(name: &str, sc: &Score, found: f64) {
    assert_eq!(
        (sc.swaps, sc.astray, sc.invented),
        (0, 0, 0),
        "{name}: {sc:?}"
    );
    assert!(sc.found >= found, "{name}: {sc:?}");
}

/// Red and green stickers (the upper mass, the lower), as `--markers red,green` names them.
const RED_GREEN: [[u8; 3]; 2] = [[0xe0, 0x20, 0x20], [0x20, 0xa0, 0x40]];

/// [`tracked_scene`] with `extra` flags and no assertion: the score, the summary, and the
/// share of the measured coordinates within 1.96 of their stated standard errors of the
/// truth (in metres: the scenes' scale is the lab's l1, given as --l1).
fn scored(
    name: &str,
    scene: &Scene,
    start: State,
    frames: usize,
    extra: &[&str],
) -> (Score, serde_json::Value, f64) {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join(format!("{name}.mp4"));
    // crf 14: the sensor's noise kept (a phone's film of a dark room is no cleaner).
    let truth = film(scene, &Preset::Lab.params(), start, frames, 14, &video).unwrap();
    let (rows, s) = tracked(&video, extra);
    let measured = chaoscope::track::read_rows(&video.with_extension("csv")).unwrap();
    let calibration = calibration(&measured, &truth);
    for ((t, _), truth) in rows.iter().zip(&truth) {
        assert!(
            (t - truth.t).abs() < 1e-4,
            "{name}: row at {t} s for frame at {} s",
            truth.t
        );
    }
    let positions: Vec<[Option<(f64, f64)>; 2]> = rows.iter().map(|r| r.1).collect();
    let sc = score(&positions, &truth);
    eprintln!("{name}: {sc:?}, within 1.96 stated sigma {calibration:.3}");
    (sc, s, calibration)
}

/// A phone held upright over a board lit from one side: a red sticker on the upper mass, a
/// green one on the lower, 60 frames a second at 1/120 s, the camera rolled 2.5 degrees,
/// the pendulum hanging still for a second first. Told apart by colour: both found in
/// every frame, none swapped, the roll found; the stated errors hold (the share within
/// 1.96 sigma near 95 %: 85-99.5 % on some 1 000 coordinates, whose binomial scatter is
/// under 1 %, the rest for how the film's own arms estimate the errors). A colour the film
/// does not show, or the colours in the wrong order, is refused naming --markers.
#[test]
fn markers_of_two_colours_are_told_apart_by_colour() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        fps: 60.0,
        shutter: 1.0 / 120.0,
        roll: 2.5f64.to_radians(),
        // Hanging still long enough to give the up; released between two frames'
        // exposures, not inside one.
        rest: 1.01,
        stickers: Some(RED_GREEN),
        marker_sigma: 3.0,
        ..Scene::lab(360, 640, p.l1 + p.l2)
    };
    let (sc, s, calibration) = scored(
        "stickers",
        &scene,
        release(),
        240,
        &["--markers", "red,green"],
    );
    // The target for two colours.
    clean("stickers", &sc, 0.98);
    // The roll from a second's rest: the line of two markers 180 px long, each to some
    // 0.05 px, gives its angle to 0.03 degrees; 0.1 leaves room for the chroma's blur.
    let tilt = s["up"]["tilt_degrees"].as_f64().unwrap();
    assert!((tilt - 2.5).abs() < 0.1, "{s}");
    assert!((0.85..=0.995).contains(&calibration), "{calibration}");
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("stickers.mp4");
    film(&scene, &p, release(), 120, 18, &video).unwrap();
    for (markers, says) in [
        (
            "blue,green",
            "no marker of colour 2040e0 (the upper one) found",
        ),
        ("green,red", "are the colours in order"),
    ] {
        let o = chaoscope()
            .arg("track")
            .arg(&video)
            .args(["--l1", "0.3", "--markers", markers, "--output"])
            .arg(dir.path().join("t.csv"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{markers}: {err}");
        assert!(
            err.contains("--markers") && err.contains(says),
            "{markers}: {err}"
        );
    }
}

/// A marker on the pivot, the picture wandering by 1.2 px (a stand or tripod that creeps):
/// red, green and blue stickers (the upper mass, the lower, the pivot), 60 frames a second,
/// the pendulum hanging still, lifted by a hand that comes into the picture and let go.
/// Measured from the pivot's marker, the masses are where the pendulum put them (0.5 px
/// RMS, as a blurred marker's target; 0.20 measured); measured from a fixed pivot the
/// wander stays in them (1.2 px measured), at least twice that. The hand is
/// neither mass, the release is found within a frame, and the stated errors hold (with the
/// pivot marker's own in them: as for two colours, 85-99.5 %).
#[test]
fn a_marker_on_the_pivot_takes_out_the_pictures_wander() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        fps: 60.0,
        shutter: 1.0 / 120.0,
        rest: 1.0,
        lift: 0.8,
        hand: true,
        wander: 1.2,
        stickers: Some(RED_GREEN),
        pivot_marker: Some([0x20, 0x40, 0xe0]),
        marker_sigma: 3.0,
        ..Scene::lab(640, 360, p.l1 + p.l2)
    };
    let (sc, s, calibration) = scored(
        "pivot",
        &scene,
        release(),
        240,
        &["--markers", "red,green,blue"],
    );
    clean("pivot", &sc, 0.98);
    assert!(sc.rms <= 0.5, "{sc:?}");
    assert!(s["pivot_marker"]["seen"].as_f64().unwrap() >= 0.98, "{s}");
    let found = s["release"].as_f64().unwrap();
    assert!((found - 1.8).abs() <= 1.0 / 60.0 + 1e-6, "{s}");
    assert!((0.85..=0.995).contains(&calibration), "{calibration}");
    let (fixed, s, _) = scored("fixed", &scene, release(), 240, &["--markers", "red,green"]);
    assert!(s["pivot_marker"].is_null(), "{s}");
    assert!(fixed.rms >= 2.0 * sc.rms, "{fixed:?} against {sc:?}");
}

/// A second reflection of the whole pendulum (a glossy board): both LEDs again at a fixed
/// offset, a quarter as bright, at 1/60 s. The upper marker's copy keeps a fixed distance
/// from it, which once passed for the lower arm; now the lower arm is the pendulum's, the
/// lower mass is found in at least 95 % of the frames (the target: where a
/// streak runs into its copy's, the frame may be left out), none swapped or invented.
#[test]
fn a_reflection_moving_with_the_pendulum_is_not_a_mass() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        shutter: 1.0 / 60.0,
        ghost: Some(((20.0, 12.0), 0.25)),
        ..Scene::lab(640, 360, p.l1 + p.l2)
    };
    let (sc, s, _) = scored("ghost", &scene, release(), 150, &[]);
    assert_eq!((sc.swaps, sc.invented), (0, 0), "{sc:?}");
    assert!(sc.found >= 0.95, "{sc:?}");
    // The lower arm within 2 mm of the truth (a pixel at this scale is 1.4 mm).
    let l2 = s["l2"].as_f64().unwrap();
    assert!((l2 - p.l2).abs() < 2e-3, "{s}");
}

/// The lab's scene at 1280 x 720, 30 frames a second, LEDs of 2.5 px under noise of 2
/// levels, the pendulum flipping: sharp markers (1/2000 s) are measured to 0.2 px RMS (the
/// target; the centroid's noise alone is some 0.03 px), the pivot and arms found to a
/// fraction of a pixel.
#[test]
fn sharp_markers_are_measured_to_a_fifth_of_a_pixel() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene::lab(1280, 720, p.l1 + p.l2);
    let (sc, s) = tracked_scene("sharp", &scene, release(), 90);
    assert!(sc.rms <= 0.2, "{sc:?}");
    let (px, py) = (
        s["pivot_px"][0].as_f64().unwrap(),
        s["pivot_px"][1].as_f64().unwrap(),
    );
    // Within 0.1 px: the circle is fitted to 90 positions of 0.05 px each.
    assert!(
        (px - scene.pivot.0).abs() < 0.1 && (py - scene.pivot.1).abs() < 0.1,
        "{s}"
    );
    // --l1 0.30 sets the scale; the lower arm then comes out at the lab's 0.195 m within
    // 0.1 px of 71 px.
    assert!(
        (s["l2"].as_f64().unwrap() - p.l2).abs() < 0.1 / scene.pixels_per_metre,
        "{s}"
    );
    // The film's own rate, exactly, beside the processing speed.
    assert_eq!(s["frame_rate"].as_f64(), Some(scene.fps), "{s}");
    assert!(s["processing_frames_per_second"].as_f64().unwrap() > 0.0);
}

/// A 1/60 s exposure smears the fast lower marker into a streak many pixels long: its
/// centroid is still the mean position over the exposure, to 0.5 px RMS (the target).
#[test]
fn blurred_markers_are_measured_as_streaks() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        shutter: 1.0 / 60.0,
        ..Scene::lab(1280, 720, p.l1 + p.l2)
    };
    let (sc, _) = tracked_scene("blurred", &scene, release(), 90);
    assert!(sc.rms <= 0.5, "{sc:?}");
}

/// A lamp in the picture and a reflection of the lower marker (in a pane: marker-sized,
/// moving, at 40 % brightness) are never followed; the lamp is reported as set aside.
#[test]
fn a_lamp_and_a_reflection_are_not_followed() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        lamp: Some((470.0, 120.0)),
        // The reflection crosses the pendulum's own half of the picture.
        reflection: Some(380.0),
        ..Scene::lab(640, 360, p.l1 + p.l2)
    };
    let (_, s) = tracked_scene("distractors", &scene, release(), 150);
    let still = s["still"].as_array().unwrap();
    assert_eq!(still.len(), 1, "{s}");
    let lamp = (still[0][0].as_f64().unwrap(), still[0][1].as_f64().unwrap());
    assert!(
        (lamp.0 - 470.0).abs() < 0.5 && (lamp.1 - 120.0).abs() < 0.5,
        "{s}"
    );
}

/// A table's edge hides the lower mass (and at times the upper) for whole stretches: those
/// rows say `hidden` and carry no position, and `fit` reads only the rows measured.
#[test]
fn a_hidden_mass_is_reported_hidden_never_placed() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        table: Some(262.0),
        ..Scene::lab(640, 360, p.l1 + p.l2)
    };
    let (sc, s) = tracked_scene("occluded", &scene, release(), 150);
    // The lower mass is behind the table for a good share of the film.
    assert!(s["seen2"].as_f64().unwrap() < 0.85, "{s} {sc:?}");
}

/// `--bridge`: where the table hides a mass, the model fitted to the rows measured on each
/// side places it, marked `bridged`, with its standard errors; measured rows stay as they
/// were, and `fit` reads only them. Against the exposures' mean positions the bridged places
/// err by their stated errors: z = error / sqrt(stated^2 + the tracker's 0.06 px) has an RMS
/// near 1 where the errors are honest; 2 allows the tracking errors' correlation from frame
/// to frame (the rods' long-run ratio, up to 1.5 on these films) and the few places that
/// decide an RMS; every place within 5 of its errors, and within half a pixel in RMS (the
/// target for a blurred marker's measurement).
#[test]
fn hidden_masses_are_bridged_by_the_model_when_asked() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("bridge.mp4");
    let p = Preset::Lab.params();
    let scene = Scene {
        table: Some(262.0),
        ..Scene::lab(640, 360, p.l1 + p.l2)
    };
    let start = State::at_rest(-1.4, 1.2);
    let truth = film(&scene, &p, start, 150, 18, &video).unwrap();
    let (plain, before) = tracked(&video, &[]);
    let csv = video.with_extension("csv");
    let o = chaoscope()
        .arg("track")
        .arg(&video)
        .args([
            "--l1", "0.30", "--bridge", "--preset", "lab", "--json", "--output",
        ])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = common::summary(o);
    // The measured rows are the same either way (read_rows reads only those).
    let measured: Vec<Row> = {
        let px = to_pixels(&s);
        chaoscope::track::read_rows(&csv)
            .unwrap()
            .into_iter()
            .map(|(t, a, b)| (t, [px(a.map(|m| m.at())), px(b.map(|m| m.at()))]))
            .collect()
    };
    assert_eq!(measured, plain);
    assert_eq!(s["seen2"], before["seen2"]);
    let bridged = &s["bridged"];
    assert!(bridged["gaps"].as_u64().unwrap() >= 4, "{s}");
    // Each bridged place against the truth, in pixels.
    let text = std::fs::read_to_string(&csv).unwrap();
    let (ppm, cx, cy) = (
        s["pixels_per_metre"].as_f64().unwrap(),
        s["pivot_px"][0].as_f64().unwrap(),
        s["pivot_px"][1].as_f64().unwrap(),
    );
    let (mut z, mut err) = (Vec::new(), Vec::new());
    for (line, truth) in text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .zip(&truth)
    {
        let c: Vec<&str> = line.split(',').collect();
        for m in 0..2 {
            if c[5 + m] != "bridged" {
                continue;
            }
            // Only where the mass was hidden (wholly, or partly: the tracker leaves a marker
            // cut by the edge unnamed), and with no streak (nothing was measured).
            assert_ne!(
                [truth.seen1, truth.seen2][m],
                Some(true),
                "bridged in view: {line}"
            );
            assert_eq!(c[11 + m], "", "{line}");
            let v = |k: usize| c[k].parse::<f64>().unwrap();
            let at = (cx + v(1 + 2 * m) * ppm, cy - v(2 + 2 * m) * ppm);
            let want = [truth.m1, truth.m2][m];
            for (e, sd) in [(at.0 - want.0, v(7 + 2 * m)), (at.1 - want.1, v(8 + 2 * m))] {
                err.push(e);
                z.push(e / (sd * ppm).hypot(0.06));
            }
        }
    }
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let worst = z.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    eprintln!(
        "bridged {} places: error RMS {:.3} px, z RMS {:.2}, worst {worst:.2}; {}",
        err.len() / 2,
        rms(&err),
        rms(&z),
        bridged
    );
    assert_eq!(err.len() / 2, bridged["places"].as_u64().unwrap() as usize);
    assert!(err.len() >= 2 * 40, "{bridged}");
    assert!(rms(&z) < 2.0 && worst < 5.0 && rms(&err) < 0.5);
}

/// The picture's up need not be the world's: a camera rolled by 0.05 rad (2.86 degrees)
/// films the pendulum hanging still for 1.5 s before its release. Up is found from the rest
/// (the pivot straight above both markers) to within 0.1 degree: the pivot is found to some
/// 0.1 px and the lower marker at rest lies 180 px below it (0.03 degree a tenth of a
/// pixel), and the positions come out in the world's frame, to 0.2 px of the truth's
/// (what the sharp markers are measured to, and the up's error over the arms' 180 px).
/// Without a rest, the picture's up is taken, and the summary says so.
#[test]
fn up_is_found_from_the_pendulum_at_rest() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let p = Preset::Lab.params();
    let start = State::at_rest(-1.4, 1.2);
    for rest in [1.5, 0.0] {
        let scene = Scene {
            roll: 0.05,
            rest,
            ..Scene::lab(640, 360, p.l1 + p.l2)
        };
        let video = dir.path().join(format!("rolled{rest}.mp4"));
        let truth = film(&scene, &p, start, 150, 18, &video).unwrap();
        let (_, s) = tracked(&video, &[]);
        let up = &s["up"];
        let tilt = up["tilt_degrees"].as_f64().unwrap();
        if rest == 0.0 {
            assert!(up["rest"].is_null() && tilt == 0.0, "{up}");
            continue;
        }
        let seen = up["rest"][1].as_f64().unwrap() - up["rest"][0].as_f64().unwrap();
        assert!(seen > 1.0 && seen < 1.5 + 1e-6, "{up}");
        assert!((tilt - 0.05f64.to_degrees()).abs() < 0.1, "{up}");
        let rows = chaoscope::track::read_rows(&video.with_extension("csv")).unwrap();
        let (mut sq, mut n) = (0.0, 0);
        for ((_, a, b), t) in rows.iter().zip(&truth) {
            for (m, want) in [
                (a, [t.metres[0], t.metres[1]]),
                (b, [t.metres[2], t.metres[3]]),
            ] {
                if let Some(chaoscope::track::Measured { x, y, .. }) = m {
                    sq += (x - want[0]).powi(2) + (y - want[1]).powi(2);
                    n += 1;
                }
            }
        }
        let rms = (sq / n as f64).sqrt() * scene.pixels_per_metre;
        eprintln!("rolled: up {up}, positions {rms:.3} px RMS over {n}");
        assert!(n > 280 && rms < 0.2, "{rms} px over {n}");
    }
}

/// From the camera to the model: a film of a release the fit can follow, tracked, then
/// fitted by `fit`: the arm lengths within three of their stated errors, the state at the
/// fit's start within 1e-3 rad and 0.01 rad/s of the truth's (ten times what 45 rows of
/// positions to 0.05 px at 110 px give), and the model agreeing with the track to the end.
#[test]
fn a_tracked_film_is_fitted_back_to_its_truth() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("fit.mp4");
    let p = Preset::Lab.params();
    let scene = Scene::lab(640, 360, p.l1 + p.l2);
    let start = State::at_rest(-1.4, 1.2);
    film(&scene, &p, start, 120, 14, &video).unwrap();
    tracked(&video, &[]);
    let out = dir.path().join("fit");
    chaoscope()
        .arg("fit")
        .arg(video.with_extension("csv"))
        // The film is of the lab's apparatus: 4 s at 30 frames a second are too few to find
        // its moments from the motion.
        .args([
            "--preset", "lab", "--start", "0.8", "--window", "1.5", "--output",
        ])
        .arg(&out)
        .assert()
        .success();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for (arm, truth) in [("l1", p.l1), ("l2", p.l2)] {
        let fitted = &s["arm_lengths"][arm];
        let (v, e) = (
            fitted["value"].as_f64().unwrap(),
            fitted["error"].as_f64().unwrap(),
        );
        assert!((v - truth).abs() < 3.0 * e, "{arm}: {v} ± {e} for {truth}");
    }
    let t0 = s["model"]["t0"].as_f64().unwrap();
    let truth = *chaoscope::cpu::trajectory(&p, start, 1e-4, (t0 / 1e-4).round() as u32)
        .last()
        .unwrap();
    let fitted: Vec<f64> = s["model"]["state"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let want = [truth.theta1, truth.omega1, truth.theta2, truth.omega2];
    for (k, (f, w)) in fitted.iter().zip(want).enumerate() {
        let tol = if k % 2 == 0 { 1e-3 } else { 1e-2 };
        assert!((f - w).abs() < tol, "state {k}: {f} for {w}");
    }
    let agrees_until = s["model"]["agrees_until"].as_f64().unwrap();
    assert!(agrees_until > 3.9, "{}", s["model"]);
}

/// From the camera to the forecast and back onto the footage: the repository's test film
/// tracked, forecast from a window of its track, and the forecast drawn on the film: an MP4
/// of the film's every frame, the fitted model's arms (blue) over the window and the 90 %
/// bands (orange) after it, nothing drawn before the window but the markers' rings.
#[test]
fn the_forecast_is_drawn_back_onto_the_film() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/test_film.mp4");
    let csv = dir.path().join("track.csv");
    chaoscope()
        .arg("track")
        .arg(&film)
        .args(["--l1", "0.30", "--output"])
        .arg(&csv)
        .assert()
        .success();
    let out = dir.path().join("forecast");
    chaoscope()
        .arg("forecast")
        .arg(&csv)
        .args("--window 0.8:2.3 --members 300 --candidates 1024".split(' '))
        .args(["--preset", "lab", "--backend", "cpu", "--video"])
        .arg(&film)
        .arg("--output")
        .arg(&out)
        .assert()
        .success();
    let overlay = out.join("overlay.mp4");
    let mut decoder =
        chaoscope::video::Decoder::open(&overlay, chaoscope::video::Pixels::Rgb).unwrap();
    assert_eq!(
        (
            decoder.probe.codec.as_str(),
            decoder.probe.width,
            decoder.probe.height
        ),
        ("h264", 1280, 720)
    );
    assert_eq!(decoder.probe.times.len(), 300);
    // At the film's own rate, not the mean step's rounding of it.
    assert_eq!(decoder.probe.frame_rate(), 30.0);
    // Pixels of the model's colours (within the film's compression of them), below the
    // caption's lines (written in the same colours, they end 120 px down). The arms alone
    // are some 360 px long and 3 px wide with two dots of 6 px: over 1,000 pixels, so more
    // than 300 is a drawn model and fewer than 50 none (a ring's or a glyph's fringe).
    let near = |rgb: &[u8], c: [i32; 3]| {
        rgb[130 * 1280 * 3..]
            .chunks_exact(3)
            .filter(|p| (0..3).all(|k| (p[k] as i32 - c[k]).abs() < 40))
            .count()
    };
    let (mut frame, mut k) = (Vec::new(), 0);
    while let Some(t) = decoder.next_frame(&mut frame).unwrap() {
        let (fitted, band) = (near(&frame, [60, 200, 255]), near(&frame, [255, 150, 40]));
        if t < 0.7 {
            assert!(fitted + band < 50, "frame {k} at {t} s: {fitted} {band}");
        } else if (0.9..2.2).contains(&t) {
            assert!(
                fitted > 300 && band < 50,
                "frame {k} at {t} s: {fitted} {band}"
            );
        } else if t > 2.4 {
            assert!(
                band > 300 && fitted < 50,
                "frame {k} at {t} s: {fitted} {band}"
            );
        }
        k += 1;
    }
    assert_eq!(k, 300);

    // Another film (the same, cut near 5 s): refused before any forecast
    // work, naming both films, and nothing written.
    let other = dir.path().join("other.mp4");
    let made = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&film)
        .args(["-t", "5", "-c", "copy"])
        .arg(&other)
        .status()
        .unwrap();
    assert!(made.success());
    let refused = dir.path().join("refused");
    let o = chaoscope()
        .arg("forecast")
        .arg(&csv)
        .args(["--window", "0.8:2.3", "--preset", "lab", "--video"])
        .arg(&other)
        .arg("--output")
        .arg(&refused)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--video")
            && err.matches(" frames over ").count() == 2
            && err.contains("300 frames over 9.967 s"),
        "{err}"
    );
    assert!(!refused.exists());
}

/// `track` without a length: the scale from the swing itself. A film of 10 s at 60 frames a
/// second of a pendulum with rods (no drag, light joint damping): the pixels per metre the
/// motion implies under g at the film's own frame times within 2 % of the scene's (the
/// time-scale check's error at this rate and length is under 1 %, examples/identify_coverage).
#[test]
fn the_scale_is_found_from_the_swing() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("swing.mp4");
    let mut p = chaoscope::model::Params {
        m1: 0.2,
        m2: 0.1,
        l1: 0.3,
        l2: 0.2,
        rod1: 0.1,
        rod2: 0.05,
        ..Default::default()
    };
    (p.losses.joint1, p.losses.joint2) = (1e-4, 1e-5);
    let scene = Scene {
        fps: 60.0,
        ..Scene::lab(480, 270, p.l1 + p.l2)
    };
    film(&scene, &p, State::at_rest(2.0, 2.5), 600, 14, &video).unwrap();
    let csv = dir.path().join("swing.csv");
    let o = chaoscope()
        .arg("track")
        .arg(&video)
        .args(["--pixels-per-metre", "motion", "--json", "--output"])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = common::summary(o);
    let found = s["pixels_per_metre"].as_f64().unwrap();
    assert!(
        (found / scene.pixels_per_metre - 1.0).abs() < 0.02,
        "{found} px/m against the scene's {}",
        scene.pixels_per_metre
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.lines()
            .next()
            .unwrap()
            .contains("--pixels-per-metre motion"),
        "{text:.200}"
    );
}

/// A film made as the guide recommends: the pendulum hanging still for 1.2 s, lifted by
/// a hand that comes into the picture for a second (eased up, then held), let go at 2.2 s,
/// the hand pulled away. `track` finds the release
/// within a frame (the target) and the lift, writes it into the CSV, and `fit` and
/// `forecast` read the free motion from there unless told to read it all.
#[test]
fn the_release_is_found_and_the_free_motion_read_from_it() {
    if !common::ffmpeg() {
        return;
    }
    let p = Preset::Lab.params();
    let scene = Scene {
        fps: 60.0,
        shutter: 1.0 / 250.0,
        rest: 1.2,
        lift: 1.0,
        hand: true,
        ..Scene::lab(640, 360, p.l1 + p.l2)
    };
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("release.mp4");
    film(&scene, &p, release(), 200, 18, &video).unwrap();
    let (_, s) = tracked(&video, &[]);
    let found = s["release"].as_f64().unwrap();
    assert!((found - 2.2).abs() <= 1.0 / 60.0 + 1e-6, "{s}");
    // The lift begins where the rest ends: the rest is the run of still frames before it,
    // which the lift's first eased steps (a pixel or less) may lengthen by a few frames.
    let lift = &s["lift"];
    assert!((lift[0].as_f64().unwrap() - 1.2).abs() < 0.1, "{s}");
    let csv = video.with_extension("csv");
    let read = |before_release| {
        let units = chaoscope::fit::data::Units {
            before_release,
            ..Default::default()
        };
        chaoscope::fit::read_frames(&csv, &units).unwrap()
    };
    assert!(read(false)[0].t >= found - 1e-9);
    assert_eq!(read(true)[0].t, 0.0);
}

/// `--markers red` on a film of a red and a green sticker finds the masses in no frame; the
/// note names the green one it saw and the flag that tracks both (the README's own film).
#[test]
fn one_colour_on_a_two_colour_film_names_the_second() {
    use predicates::prelude::*;
    let film = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/own_film.mp4");
    let dir = tempfile::tempdir().unwrap();
    for (given, other) in [("red", "green"), ("green", "red")] {
        chaoscope()
            .arg("track")
            .arg(&film)
            .args(["--markers", given, "--l1", "0.3", "--output"])
            .arg(dir.path().join(format!("{given}.csv")))
            .assert()
            .success()
            .stderr(predicate::str::contains(format!(
                "the film shows a {other} sticker too"
            )))
            .stderr(predicate::str::contains(format!(
                "--markers {given},{other}"
            )));
    }
}
