//! The zoom's benchmark (BENCH.md, "Zooms"): a flip-time zoom of FRAMES frames at WxH over six
//! decades of width (the whole 16:9 window of the angle plane, 2 pi wide, to 6.3e-6) into a
//! point of the boundary, run as `chaoscope zoom` runs it (the release binary, which must be
//! built). Reports the frames' compute and the encoding (reading the PNGs back and H.264),
//! the peak memory of chaoscope and of its children (ffmpeg), the frame where f64 takes over,
//! the single map's time of frame 0 (`chaoscope flip` run from frame 0's own command) and how
//! far the film's first frame is from that map after the colour conversion to yuv420p.
//!
//!     cargo build --release && cargo run --release --example zoom_bench -- [FRAMES] [WxH] [T_MAX]

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use chaoscope::render::read_png;
use chaoscope::video::{Decoder, Pixels};

/// A point on the flip-time map's boundary (found by zooming on the steepest pixel near the
/// centre, level by level).
const EDGE: (f64, f64) = (-1.68923151770833, 0.74163544020833);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: u32 = args.first().map_or(Ok(300), |s| s.parse())?;
    let size = args.get(1).map_or("1920x1080", String::as_str).to_string();
    let t_max = args.get(2).map_or("10", String::as_str).to_string();
    let bin = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/release/chaoscope");
    let dir = std::path::PathBuf::from("out/zoom-bench");
    // ZOOM_BENCH_KEEP=1: keep the frames of an earlier run (the zoom then only encodes).
    if std::env::var_os("ZOOM_BENCH_KEEP").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    std::fs::create_dir_all(&dir)?;
    let end = 2.0 * std::f64::consts::PI * 1e-6;
    let zoom_args = [
        "zoom".to_string(),
        format!("--to={},{},{end}", EDGE.0, EDGE.1),
        "--frames".into(),
        frames.to_string(),
        "--output".into(),
        dir.join("frames").display().to_string(),
        "--json".into(),
        "flip".into(),
        "--size".into(),
        size.clone(),
        "--theta2=-9pi/16:9pi/16".into(),
        "--t-max".into(),
        t_max.clone(),
    ];
    eprintln!("chaoscope {}", zoom_args.join(" "));
    let started = Instant::now();
    let mut child = Command::new(&bin)
        .args(&zoom_args)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()?;
    // chaoscope's own high-water mark, read while it runs (the last read is within 50 ms of
    // its end, and the mark only rises).
    // The summary (every frame's plan) outgrows a pipe's buffer: read it as it comes.
    let mut stdout = child.stdout.take().ok_or("no stdout")?;
    let reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut text).map(|_| text)
    });
    let status = format!("/proc/{}/status", child.id());
    let mut peak_kb = 0u64;
    while child.try_wait()?.is_none() {
        if let Ok(text) = std::fs::read_to_string(&status)
            && let Some(line) = text.lines().find(|l| l.starts_with("VmHWM:"))
        {
            let kb: u64 = line.split_whitespace().nth(1).unwrap_or("0").parse()?;
            peak_kb = peak_kb.max(kb);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let exit = child.wait()?;
    let wall = started.elapsed().as_secs_f64();
    let stdout = reader.join().map_err(|_| "the reader panicked")??;
    if !exit.success() {
        return Err("the zoom failed".into());
    }
    // The largest of the children waited for: chaoscope or the ffmpeg it ran.
    let children_kb = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage);
        usage.ru_maxrss as u64
    };
    let s: serde_json::Value = serde_json::from_slice(&stdout)?;
    let compute = s["compute_seconds"].as_f64().unwrap_or(f64::NAN);
    let encode = s["encode_seconds"].as_f64().unwrap_or(f64::NAN);

    // Frame 0 alone, from its own command.
    let first = dir.join("frames/frame_0000.png");
    let png = read_png(&first)?;
    let command = png
        .text
        .iter()
        .find(|(k, _)| k == "chaoscope:command")
        .map(|(_, v)| v.clone())
        .ok_or("frame 0 has no command")?;
    let flip = dir.join("flip.png");
    let single = Instant::now();
    let ran = Command::new(&bin)
        .args(command.split_whitespace().skip(1))
        .arg("--output")
        .arg(&flip)
        .stderr(Stdio::null())
        .status()?;
    let single = single.elapsed().as_secs_f64();
    if !ran.success() {
        return Err("frame 0's command failed".into());
    }
    let map = read_png(&flip)?;
    let same = map.rgb == png.rgb;
    let mut decoder = Decoder::open(&dir.join("frames/zoom.mp4"), Pixels::Rgb)?;
    let mut film = Vec::new();
    decoder.next_frame(&mut film)?.ok_or("an empty film")?;
    let flat = through_yuv420p(&flip, map.width, map.height)?;
    let mad = flat
        .iter()
        .zip(&film)
        .map(|(&a, &b)| (a as i32 - b as i32).unsigned_abs() as f64)
        .sum::<f64>()
        / flat.len() as f64;

    let n = frames as f64;
    println!(
        "| frames | size | t-max | compute s | frames/s | encode s | encode / compute | peak MB (chaoscope) | peak MB (ffmpeg or chaoscope) | f64 from frame | frame 0 alone s |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    println!(
        "| {frames} | {size} | {t_max} | {compute:.0} | {:.3} | {encode:.1} | {:.1} % | {:.0} | {:.0} | {} (width {}) | {single:.2} |",
        n / compute,
        100.0 * encode / compute,
        peak_kb as f64 / 1024.0,
        children_kb as f64 / 1024.0,
        s["switch"]["frame"],
        s["switch"]["width"]
            .as_f64()
            .map_or("-".into(), |w| format!("{w:.2e}")),
    );
    println!();
    println!(
        "- wall {wall:.0} s; frame 0 is `chaoscope flip` of its own command pixel for pixel: {same}"
    );
    println!(
        "- the film's first frame against that map after the conversion to yuv420p: mean absolute difference {mad:.2} levels of 255"
    );
    if let Some(sw) = s["switch"].as_object() {
        println!(
            "- f64 from frame {}: its step between starts {:.2e}, f32's finest there {:.2e}",
            sw["frame"],
            sw["step"].as_f64().unwrap_or(f64::NAN),
            sw["f32_finest"].as_f64().unwrap_or(f64::NAN)
        );
    }
    Ok(())
}

/// The RGB of the PNG at `path` after FFmpeg's conversion to yuv420p and back, no codec.
fn through_yuv420p(
    path: &Path,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    let run = |args: &[&str], input: Vec<u8>| -> Result<Vec<u8>, Box<dyn std::error::Error>> {
        let mut c = Command::new("ffmpeg")
            .args(["-v", "error"])
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()?;
        let mut stdin = c.stdin.take().ok_or("no stdin")?;
        let writer = std::thread::spawn(move || stdin.write_all(&input));
        let o = c.wait_with_output()?;
        writer.join().map_err(|_| "the writer panicked")??;
        Ok(o.stdout)
    };
    let size = format!("{width}x{height}");
    let yuv = run(
        &["-i", "-", "-f", "rawvideo", "-pix_fmt", "yuv420p", "-"],
        std::fs::read(path)?,
    )?;
    run(
        &[
            "-f", "rawvideo", "-pix_fmt", "yuv420p", "-s", &size, "-i", "-", "-f", "rawvideo",
            "-pix_fmt", "rgb24", "-",
        ],
        yuv,
    )
}
