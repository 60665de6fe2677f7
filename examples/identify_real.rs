//! The shared real recording's pendulum identified from its motion alone: `cargo run
//! --release --example identify_real -- FILE [FPS] [FIRST_S] [SECONDS]`, FILE the dataset's
//! CSV (../shared/real/ibm_run0.csv: pixel coordinates times 5 of the pivot, joint and tip
//! markers as (down, right) pairs), FPS the frame rate assumed (400). Positions are taken
//! relative to the pivot marker in each row, in pixels; with g given as 9.81 the time-scale
//! check's implied g is then in pixels/s^2 over m/s^2: the camera's pixels per metre.

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let file = args.get(1).expect("FILE");
    let fps: f64 = args.get(2).map_or(400.0, |a| a.parse().unwrap());
    let first: f64 = args.get(3).map_or(0.0, |a| a.parse().unwrap());
    let seconds: f64 = args.get(4).map_or(f64::INFINITY, |a| a.parse().unwrap());
    let text = std::fs::read_to_string(file).unwrap();
    let (mut frames, mut data) = (Vec::new(), Vec::new());
    for (k, line) in text.lines().enumerate() {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse::<f64>().unwrap() / 5.0)
            .collect();
        let time = k as f64 / fps;
        if time < first || time > first + seconds {
            continue;
        }
        // (down, right) pairs: x right, y up, relative to the pivot marker.
        let at = |i: usize| (v[2 * i + 1] - v[1], -(v[2 * i] - v[0]));
        let ((x1, y1), (x2, y2)) = (at(1), at(2));
        frames.push(chaoscope::fit::TrackedRow {
            t: time,
            x1,
            y1,
            x2,
            y2,
        });
        data.push([x1, y1, x2, y2]);
    }
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let angles = chaoscope::fit::angles(&frames, (0.0, 0.0));
    let rows = chaoscope::fit::window::TrackRows {
        t: &t,
        data: &data,
        angles: &angles,
    };
    let hidden = chaoscope::monitor::Monitor::hidden();
    let id = chaoscope::fit::identify::identify(&rows, 9.81, &hidden).unwrap();
    let ts = id.time_scale;
    println!("rows {} from {first} s at {fps} frames/s", t.len());
    for (k, name) in chaoscope::fit::identify::MOMENTS.iter().enumerate() {
        println!("{name} = {:.5e} ± {:.1e}", id.values[k], id.errors[k]);
    }
    println!(
        "marker radii {:.2} and {:.2} px; physical {}; misfit {:.1e} {:.1e}; {} stretches of {:.3} s ({} left out)",
        id.l1,
        id.l2,
        id.physical(),
        id.misfit[0],
        id.misfit[1],
        id.stretches,
        id.stretch,
        id.rejected
    );
    let ppm = ts.g_implied / 9.81;
    println!(
        "the motion implies {:.1} ± {:.1} px/m at {fps} frames/s: l1 {:.4} m, l2 {:.4} m",
        ppm,
        ts.g_implied_error / 9.81,
        id.l1 / ppm,
        id.l2 / ppm
    );
}
