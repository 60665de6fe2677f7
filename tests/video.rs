//! Films through FFmpeg: every animated output as an MP4 that browsers and slide programs
//! play (H.264, yuv420p), checked by ffprobe and by decoding its frames back.

mod common;

use std::path::Path;

use chaoscope::render::read_png;
use chaoscope::video::{Decoder, Pixels, probe};
use common::chaoscope;

/// ffprobe's view of a film's first video stream: codec, pixel format, width, height,
/// frames counted by decoding, duration (s), and the container's comment.
fn ffprobe(path: &Path) -> (String, String, u32, u32, u64, f64, String) {
    let o = std::process::Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-select_streams",
            "v:0",
            "-count_frames",
            "-show_entries",
            "stream=codec_name,pix_fmt,width,height,nb_read_frames,duration:format_tags=comment",
            "-of",
            "json",
        ])
        .arg(path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let s = &v["streams"][0];
    let text = |x: &serde_json::Value| x.as_str().unwrap_or("").to_string();
    (
        text(&s["codec_name"]),
        text(&s["pix_fmt"]),
        s["width"].as_u64().unwrap() as u32,
        s["height"].as_u64().unwrap() as u32,
        text(&s["nb_read_frames"]).parse().unwrap(),
        text(&s["duration"]).parse().unwrap(),
        text(&v["format"]["tags"]["comment"]),
    )
}

/// A sweep's MP4: H.264 in yuv420p, one film frame per map at the asked rate, the command
/// that makes it in its comment, and its frames the maps' PNGs after the colour conversion.
#[test]
fn a_sweep_films_its_frames_as_an_mp4() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (out, film) = (dir.path().join("sweep"), dir.path().join("sweep.mp4"));
    chaoscope()
        .args(["sweep", "--vary", "g=5:15", "--frames", "6", "--fps", "12"])
        .args([
            "--size",
            "64x42",
            "--t-max",
            "4",
            "--backend",
            "cpu",
            "--crf",
            "10",
        ])
        .arg("--output")
        .arg(&out)
        .arg("--film")
        .arg(&film)
        .assert()
        .success();
    let (codec, pix, w, h, frames, duration, comment) = ffprobe(&film);
    assert_eq!((codec.as_str(), pix.as_str()), ("h264", "yuv420p"));
    assert_eq!((w, h, frames), (64, 42, 6));
    // 6 frames at 12 a second (the container's clock ticks in 1/12800 s or finer).
    assert!((duration - 0.5).abs() < 1e-3, "{duration}");
    assert!(
        comment.starts_with("chaoscope sweep --map flip --vary g=5:15 --frames 6 --fps 12")
            && comment.ends_with("--crf 10"),
        "{comment}"
    );
    assert!(
        !out.join("animation.png").exists(),
        "the film replaces the APNG"
    );
    // Decoded back, each frame is its PNG after the conversion to yuv420p (halved chroma
    // costs a map whose colours change from pixel to pixel some 4 levels by itself): the
    // mean absolute difference at most 2 levels of 255, what H.264 at crf 10 costs a flip
    // map's fractal detail (measured 1.2 on a 256 x 256 map; crf 18 costs 2.6 there and
    // 1.7 at 1024 x 576).
    let mut decoder = Decoder::open(&film, Pixels::Rgb).unwrap();
    assert_eq!((decoder.probe.width, decoder.probe.height), (64, 42));
    let mut frame = Vec::new();
    let mut k = 0;
    while let Some(t) = decoder.next_frame(&mut frame).unwrap() {
        assert!((t - k as f64 / 12.0).abs() < 1e-3, "frame {k} at {t} s");
        let png = through_yuv420p(&out.join(format!("frame_{k:04}.png")));
        let sum: u64 = png
            .iter()
            .zip(&frame)
            .map(|(&a, &b)| (a as i32 - b as i32).unsigned_abs() as u64)
            .sum();
        let mean = sum as f64 / png.len() as f64;
        assert!(mean <= 2.0, "frame {k}: mean difference {mean:.2} levels");
        k += 1;
    }
    assert_eq!(k, 6);
}

/// The RGB of the PNG at `path` after FFmpeg's conversion to yuv420p and back, no codec.
fn through_yuv420p(path: &Path) -> Vec<u8> {
    let run = |args: &[&str], input: &[u8]| {
        use std::io::Write;
        let mut c = std::process::Command::new("ffmpeg")
            .args(["-v", "error"])
            .args(args)
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        c.stdin.take().unwrap().write_all(input).unwrap();
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success());
        o.stdout
    };
    let png = std::fs::read(path).unwrap();
    let size = {
        let p = read_png(path).unwrap();
        format!("{}x{}", p.width, p.height)
    };
    let yuv = run(
        &["-i", "-", "-f", "rawvideo", "-pix_fmt", "yuv420p", "-"],
        &png,
    );
    let args = [
        "-f", "rawvideo", "-pix_fmt", "yuv420p", "-s", &size, "-i", "-",
    ];
    run(
        &[&args[..], &["-f", "rawvideo", "-pix_fmt", "rgb24", "-"]].concat(),
        &yuv,
    )
}

/// `traces --film x.mp4`: the trails growing for the exposure in real time at the asked rate;
/// `--gif` still makes a GIF.
#[test]
fn traces_film_the_trails_growing() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = dir.path().join("t.mp4");
    let base = [
        "traces",
        "--theta1",
        "2",
        "--theta2",
        "2.5",
        "--runs",
        "5",
        "--exposure",
        "1.5",
        "--size",
        "101",
        "--backend",
        "cpu",
    ];
    chaoscope()
        .args(base)
        .args(["--fps", "20", "--output"])
        .arg(dir.path().join("t.png"))
        .arg("--film")
        .arg(&film)
        .assert()
        .success();
    let (codec, pix, w, h, frames, _, comment) = ffprobe(&film);
    assert_eq!(
        (codec.as_str(), pix.as_str(), w, h, frames),
        ("h264", "yuv420p", 102, 102, 30)
    );
    assert!(comment.contains("--fps 20 --crf 18"), "{comment}");
    let p = probe(&film).unwrap();
    assert_eq!(p.times.len(), 30);
    // The film's last frame holds every trail; its first, the first 1/20 s only.
    let mut decoder = Decoder::open(&film, Pixels::Gray).unwrap();
    let (mut frame, mut lit) = (Vec::new(), Vec::new());
    while decoder.next_frame(&mut frame).unwrap().is_some() {
        lit.push(frame.iter().filter(|&&v| v > 40).count());
    }
    // The arms are drawn in every frame; the trails add to them, a little every frame.
    assert!(
        lit[29] > 2 * lit[0],
        "lit pixels {} then {}",
        lit[0],
        lit[29]
    );
    let gif = dir.path().join("t.gif");
    chaoscope()
        .args(base)
        .arg("--output")
        .arg(dir.path().join("t2.png"))
        .arg("--gif")
        .arg(&gif)
        .assert()
        .success();
    assert_eq!(&std::fs::read(&gif).unwrap()[..6], b"GIF89a");
}

/// Bad film settings are refused before any work, naming the flag and the allowed range; a
/// film asked for without FFmpeg is refused naming what to install, and leaves no file.
#[test]
fn film_settings_are_checked_and_a_missing_ffmpeg_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = [
        "sweep", "--vary", "g=5:15", "--frames", "2", "--size", "16", "--t-max", "1",
    ];
    for (extra, flag, says) in [
        (&["--film", "x.avi"][..], "--film", ".png or .mp4"),
        (&["--film", "x.mp4", "--crf", "52"][..], "--crf", "0..=51"),
        (&["--film", "x.mp4", "--fps", "300"][..], "--fps", "240"),
        (&["--fps", "150"][..], "--fps", "at most 100 for an APNG"),
    ] {
        let o = chaoscope()
            .current_dir(dir.path())
            .args(sweep)
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(
            stderr.contains(flag) && stderr.contains(says),
            "{extra:?}: {stderr}"
        );
    }
    // PATH without FFmpeg (the tests' binary is run by its full path).
    let film = dir.path().join("t.mp4");
    let o = chaoscope()
        .env("PATH", dir.path())
        .args([
            "traces",
            "--theta1",
            "2",
            "--theta2",
            "2",
            "--runs",
            "2",
            "--exposure",
            "0.5",
        ])
        .args(["--size", "32", "--backend", "cpu", "--output"])
        .arg(dir.path().join("t.png"))
        .arg("--film")
        .arg(&film)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("needs ffmpeg") && stderr.contains("apt-get install ffmpeg"),
        "{stderr}"
    );
    assert!(
        !film.exists() && !dir.path().join("t.png").exists(),
        "nothing half made"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
}

/// A phone's film: HEVC in a QuickTime (.mov) container at a variable frame rate. The
/// decoder hands over every frame once, each at its own timestamp (a phone's rotation
/// metadata is read by `probe`, checked in src/video/decode.rs), and `track` reads it as it
/// reads an MP4.
#[test]
fn a_phones_hevc_mov_decodes_upright_with_its_own_times() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/test_film.mp4");
    let mov = dir.path().join("phone.mov");
    // Frames 0-89 re-timed to a variable rate (every third step 1/20 s, else 1/30 s), HEVC.
    let o = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(&film)
        .args([
            "-frames:v",
            "90",
            "-vf",
            "settb=1/600,setpts='(N/30+floor(N/3)/60)/TB'",
            "-fps_mode",
            "passthrough",
            "-c:v",
            "libx265",
            "-x265-params",
            "log-level=error",
            "-crf",
            "22",
            "-video_track_timescale",
            "600",
        ])
        .arg(&mov)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = probe(&mov).unwrap();
    assert_eq!(p.codec, "hevc");
    assert_eq!(p.times.len(), 90);
    // The steps between frames vary (FFmpeg's muxer rounds the ones written, so only their
    // variety is checked): frame times are the container's, not an index over a rate.
    let steps: Vec<f64> = p.times.windows(2).map(|w| w[1] - w[0]).collect();
    let odd = steps
        .iter()
        .filter(|&&s| (s - 1.0 / 30.0).abs() > 0.01)
        .count();
    assert!(
        odd >= 10,
        "{odd} of {} steps other than 1/30 s",
        steps.len()
    );
    let mut decoder = Decoder::open(&mov, Pixels::Gray).unwrap();
    assert_eq!((decoder.probe.width, decoder.probe.height), (1280, 720));
    let mut frame = Vec::new();
    let mut times = Vec::new();
    while let Some(t) = decoder.next_frame(&mut frame).unwrap() {
        assert_eq!(frame.len(), 1280 * 720);
        times.push(t);
    }
    // Each frame once (no frame repeated to fill a constant rate), at its own time.
    assert_eq!(times, p.times);
    let csv = dir.path().join("phone.csv");
    let o = chaoscope()
        .arg("track")
        .arg(&mov)
        .args(["--l1", "0.30", "--json", "--output"])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = common::summary(o);
    assert_eq!(s["frames"], 90);
    assert!(s["both"].as_f64().unwrap() >= 0.99, "{s}");
}
