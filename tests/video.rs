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
        .args("-v error -select_streams v:0 -count_frames -show_entries stream=codec_name,pix_fmt,width,height,nb_read_frames,duration:format_tags=comment -of json".split(' '))
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
        .args("--size 64x42 --t-max 4 --backend cpu --crf 10".split(' '))
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
        .args("traces --theta1 2 --theta2 2 --runs 2 --exposure 0.5".split(' '))
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
        .args("-frames:v 90 -vf settb=1/600,setpts='(N/30+floor(N/3)/60)/TB' -fps_mode passthrough -c:v libx265 -x265-params log-level=error -crf 22 -video_track_timescale 600".split(' '))
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

/// A point on the flip-time map's boundary (found by zooming on the steepest pixel near the
/// centre, level by level, to 2e-8 wide): a zoom there keeps detail to the end.
const EDGE: &str = "-1.6892315177083337,0.7416354402083335";

/// The flags of a small zoom's map: 16:9 pixels over a 16:9 window of the angle plane.
const SMALL_MAP: [&str; 7] = [
    "flip",
    "--size",
    "96x54",
    "--theta2=-1.7671458676442586:1.7671458676442586",
    "--t-max",
    "8",
    "--json",
];

/// A zoom from the whole plane to 1e-7: its first frame is the `flip` map its PNG names (bit
/// for bit, and in the film after the colour conversion); frames run in f32 exactly while the
/// step between starts is at least 16 f32 ulps of pi, then in f64; ffprobe sees the film.
#[test]
fn a_zoom_starts_at_the_flip_map_and_turns_to_f64_where_f32_stops_resolving() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("zoom");
    let s = common::summary(
        chaoscope()
            .args([
                "zoom",
                &format!("--to={EDGE},1e-7"),
                "--frames",
                "10",
                "--crf",
                "10",
            ])
            .arg("--output")
            .arg(&out)
            .args(SMALL_MAP)
            .output()
            .unwrap(),
    );
    assert_eq!(
        (s["frames"].as_u64(), s["made"].as_u64()),
        (Some(10), Some(10))
    );
    // The first frame's own command, run as it stands, makes the same picture.
    let first = out.join("frame_0000.png");
    let command = common::png_text(&first, "chaoscope:command");
    let words: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(&words[..2], ["chaoscope", "flip"], "{command}");
    let flip = dir.path().join("flip.png");
    chaoscope()
        .args(&words[1..])
        .arg("--output")
        .arg(&flip)
        .assert()
        .success();
    assert_eq!(read_png(&first).unwrap().rgb, read_png(&flip).unwrap().rgb);
    let (codec, pix, w, h, frames, duration, comment) = ffprobe(&out.join("zoom.mp4"));
    assert_eq!(
        (codec.as_str(), pix.as_str(), w, h, frames),
        ("h264", "yuv420p", 96, 54, 10)
    );
    assert!((duration - 10.0 / 30.0).abs() < 1e-3, "{duration}");
    assert!(
        comment.starts_with("chaoscope zoom --to -1.6892315177083337"),
        "{comment}"
    );
    // The film's first frame is the flip map after yuv420p: H.264 at crf 10 costs a flip
    // map's detail about 1.2 levels on average (tests above); 2 levels at most.
    let mut decoder = Decoder::open(&out.join("zoom.mp4"), Pixels::Rgb).unwrap();
    let mut frame = Vec::new();
    decoder.next_frame(&mut frame).unwrap().unwrap();
    let flat = through_yuv420p(&flip);
    let mean = flat
        .iter()
        .zip(&frame)
        .map(|(&a, &b)| (a as i32 - b as i32).unsigned_abs() as f64)
        .sum::<f64>()
        / flat.len() as f64;
    assert!(mean <= 2.0, "mean difference {mean:.2} levels");
    // f32 resolves a step between starts down to 16 of its ulps of the largest angle, pi
    // (where the arms flip): ulp(pi) = 2 f32::EPSILON.
    let f32_finest = 16.0 * 2.0 * f32::EPSILON as f64;
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut precisions = Vec::new();
    for line in csv.lines().skip(2) {
        let cells: Vec<&str> = line.split(',').collect();
        let step: f64 = cells[5].parse().unwrap();
        let expected = if step >= f32_finest { "f32" } else { "f64" };
        assert_eq!(cells[6], expected, "{line}");
        precisions.push(cells[6].to_string());
        let frame = out.join(format!("frame_{:04}.png", cells[0].parse::<u32>().unwrap()));
        assert_eq!(common::png_text(&frame, "chaoscope:precision"), expected);
    }
    let switch = precisions.iter().position(|p| p == "f64").unwrap();
    assert!(switch > 0 && precisions.len() == 10);
    assert_eq!(s["switch"]["frame"].as_u64(), Some(switch as u64));
}

/// A zoom killed mid-run and run again, and a zoom made in three tiles then encoded, give
/// the frames of a zoom run once, byte for byte (each frame its own pure function of the
/// command: nothing of the run that made it is in it).
#[test]
fn a_killed_zoom_resumes_to_the_same_frames_and_tiles_add_up() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let zoom = |out: &Path| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_chaoscope"));
        c.args(["zoom", &format!("--to={EDGE},1e-5"), "--frames", "12"])
            .arg("--output")
            .arg(out)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir());
        c
    };
    let map = ["flip", "--size", "128x72", "--t-max", "12", "--json"];
    let whole = dir.path().join("whole");
    common::summary(zoom(&whole).args(map).output().unwrap());
    let frames = |d: &Path| -> Vec<Vec<u8>> {
        (0..12)
            .map(|k| std::fs::read(d.join(format!("frame_{k:04}.png"))).unwrap())
            .collect()
    };
    let expected = frames(&whole);
    let table = std::fs::read(whole.join("frames.csv")).unwrap();

    let killed = dir.path().join("killed");
    let mut child = zoom(&killed)
        .args(map)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while !killed.join("frame_0002.png").exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the zoom ended before it was killed"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let left = (0..12)
        .filter(|k| killed.join(format!("frame_{k:04}.png")).exists())
        .count();
    assert!(left < 12, "the kill came after the last frame");
    let s = common::summary(zoom(&killed).args(map).output().unwrap());
    assert_eq!(s["kept"].as_u64(), Some(left as u64));
    assert_eq!(frames(&killed), expected);
    assert_eq!(std::fs::read(killed.join("frames.csv")).unwrap(), table);

    let tiles = dir.path().join("tiles");
    for tile in ["0/3", "1/3", "2/3"] {
        let s = common::summary(
            zoom(&tiles)
                .args(["--tile", tile])
                .args(map)
                .output()
                .unwrap(),
        );
        assert_eq!((s["made"].as_u64(), s["film"].as_str()), (Some(4), None));
    }
    assert!(!tiles.join("zoom.mp4").exists());
    let s = common::summary(zoom(&tiles).args(map).output().unwrap());
    assert_eq!(
        (s["made"].as_u64(), s["kept"].as_u64()),
        (Some(0), Some(12))
    );
    assert_eq!(frames(&tiles), expected);
    assert!(tiles.join("zoom.mp4").exists());

    // Damaged frames are made again, not kept: one cut short, one whose pixels changed
    // under its own text.
    let cut = tiles.join("frame_0002.png");
    std::fs::write(&cut, &expected[2][..expected[2].len() / 2]).unwrap();
    let changed = tiles.join("frame_0005.png");
    let mut png = read_png(&changed).unwrap();
    png.rgb[0] ^= 0xff;
    chaoscope::render::write_png(&changed, (png.width, png.height), &png.rgb, &png.text).unwrap();
    let s = common::summary(zoom(&tiles).args(map).output().unwrap());
    assert_eq!(
        (s["made"].as_u64(), s["kept"].as_u64()),
        (Some(2), Some(10))
    );
    let notices = s["notices"].to_string();
    assert!(
        notices.contains("frame_0002.png, frame_0005.png"),
        "{notices}"
    );
    assert_eq!(frames(&tiles), expected);
}

/// What a zoom cannot do exits 2 naming the flag, and writes nothing: past f64's resolution
/// (naming the end width), a view without its width, one frame, a GIF, a tile out of range,
/// the map's own files, a single start instead of a plane.
#[test]
fn a_zoom_refuses_what_it_cannot_do() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("zoom");
    let to = format!("--to={EDGE},1e-6");
    let frame0 = out.join("frame_0000.png").display().to_string();
    let cases: &[(&[&str], &str)] = &[
        (
            &["--to=0.5,0.5,1e-15", "flip", "--size", "64"],
            "--to: a width of 1e-15",
        ),
        (&["--to=0.5,0.5", "flip"], "--to"),
        (&[&to, "--frames", "1", "flip"], "--frames"),
        (&[&to, "--film", "x.gif", "flip"], "--film"),
        (&[&to, "--tile", "3/3", "flip"], "--tile"),
        (&[&to, "--film", &frame0, "flip"], "--film"),
        (&[&to, "flip", "--data", "x.npy"], "--data"),
        (&[&to, "flip", "--output", "x.png"], "--output"),
        (
            &[&to, "lyapunov", "--theta1", "0.5", "--theta2", "0.5"],
            "--theta1",
        ),
        (&[&to, "lyapunov", "--spectrum", "s.csv"], "--spectrum"),
    ];
    for (args, flag) in cases {
        let o = chaoscope()
            .arg("zoom")
            .arg("--output")
            .arg(&out)
            .args(*args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?} should name {flag}: {err}");
    }
    assert!(!out.exists(), "nothing written");
}

/// The process ids of `parent`'s children named `name` (from /proc).
fn children_named(parent: u32, name: &str) -> Vec<u32> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // pid (comm) state ppid ...: the name may hold spaces, so split after its ')'.
        let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let ppid = stat[close + 1..].split_whitespace().nth(1);
        if &stat[open + 1..close] == name && ppid == Some(&parent.to_string()) {
            found.push(pid);
        }
    }
    found
}

/// Whether process `pid` has ended (gone, or a zombie nobody has reaped yet).
fn ended(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => {
            stat.rfind(')')
                .and_then(|k| stat[k + 1..].split_whitespace().next())
                == Some("Z")
        }
    }
}

/// One Ctrl-C stops a film while its FFmpeg has stalled (stopped here by SIGSTOP, as a full
/// disk or a slow network drive stalls it): the run, blocked writing frames to it, ends
/// within seconds as interrupted (exit 130), FFmpeg is gone, and no film or temporary file
/// is left.
#[cfg(unix)]
#[test]
fn one_ctrl_c_stops_a_film_whose_ffmpeg_stalled() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = dir.path().join("t.mp4");
    // 3 MB frames: a stalled FFmpeg's pipe fills with the first.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_chaoscope"))
        .args(["traces", "--theta1", "2", "--theta2", "2.5", "--runs", "2"])
        .args("--exposure 60 --fps 30 --size 1001 --backend cpu".split(' '))
        .arg("--output")
        .arg(dir.path().join("t.png"))
        .arg("--film")
        .arg(&film)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    let ffmpeg = loop {
        if let Some(&pid) = children_named(child.id(), "ffmpeg").first() {
            break pid;
        }
        assert!(child.try_wait().unwrap().is_none(), "ended before its film");
        assert!(started.elapsed().as_secs() < 60, "no FFmpeg after 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let signal = |sig: &str, pid: u32| {
        std::process::Command::new("kill")
            .args([sig, &pid.to_string()])
            .status()
            .unwrap()
    };
    assert!(signal("-STOP", ffmpeg).success());
    // Long enough for the pipe to fill and the run to block on it.
    std::thread::sleep(std::time::Duration::from_secs(1));
    assert!(signal("-INT", child.id()).success());
    let asked = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        // The kill is immediate and the run's blocked write then fails; 5 s leaves room for
        // a loaded machine's scheduler.
        if asked.elapsed().as_secs() >= 5 {
            let _ = signal("-KILL", ffmpeg);
            let _ = child.kill();
            panic!("still running 5 s after one Ctrl-C");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(130), "{status}");
    assert!(ended(ffmpeg), "FFmpeg {ffmpeg} outlived the run");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

/// A film cut short (its index counts frames whose bytes are gone) or joined from pieces
/// without new timestamps (every time twice) is refused as the bad input it is (exit 2,
/// naming what is wrong), not tracked in part or with times misassigned.
#[test]
fn a_film_cut_short_or_joined_is_refused() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let whole =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/test_film.mp4")).unwrap();
    let half = dir.path().join("half.mp4");
    std::fs::write(&half, &whole[..whole.len() / 2]).unwrap();
    let piece = dir.path().join("piece.ts");
    let made = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/test_film.mp4"))
        .args("-t 2 -c copy -bsf:v h264_mp4toannexb -f mpegts".split(' '))
        .arg(&piece)
        .status()
        .unwrap();
    assert!(made.success());
    let piece = std::fs::read(&piece).unwrap();
    let joined = dir.path().join("joined.ts");
    std::fs::write(&joined, [piece.clone(), piece].concat()).unwrap();
    for (film, says) in [(&half, "cut short"), (&joined, "timestamps repeat")] {
        let out = chaoscope()
            .arg("track")
            .arg(film)
            .args(["--l1", "0.3", "--output"])
            .arg(dir.path().join("t.csv"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {err}", film.display());
        assert!(err.contains(says), "{err}");
        assert!(!dir.path().join("t.csv").exists());
    }
}

/// The track records its film's first frames (a digest), and `forecast --video` draws only on
/// that film: another take of the same size, frames and length (here the same film mirrored)
/// is refused before any work, naming the option; before, only size, frames and length were
/// compared, and it was drawn on.
#[test]
fn a_forecast_is_drawn_only_on_the_film_it_was_tracked_from() {
    if !common::ffmpeg() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let film = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/test_film.mp4");
    let csv = dir.path().join("t.csv");
    chaoscope()
        .arg("track")
        .arg(&film)
        .args(["--l1", "0.30", "--output"])
        .arg(&csv)
        .assert()
        .success();
    assert!(
        std::fs::read_to_string(&csv)
            .unwrap()
            .contains("# film_digest = ")
    );
    let other = dir.path().join("other.mp4");
    let made = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(&film)
        .args("-vf hflip -fps_mode passthrough -c:v libx264 -crf 18 -pix_fmt yuv420p".split(' '))
        .arg(&other)
        .status()
        .unwrap();
    assert!(made.success());
    let out = chaoscope()
        .arg("forecast")
        .arg(&csv)
        .args([
            "--preset",
            "lab",
            "--window",
            "0.8:2.3",
            "--members",
            "100",
            "--video",
        ])
        .arg(&other)
        .arg("--output")
        .arg(dir.path().join("f"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--video") && err.contains("first 3 frames"),
        "{err}"
    );
    assert!(!dir.path().join("f").exists());
}
