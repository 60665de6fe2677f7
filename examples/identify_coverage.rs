//! Whether the identified moments' stated errors hold: `cargo run --release --example
//! identify_coverage -- [CASES]` films CASES (50) seeded compound pendulums (bars with bobs,
//! masses from 50 g to 5 kg, a heavy upper arm, the lower marker at the bar's tip or at its
//! centre, 30 to 400 frames a second, 0.1 mm of noise on every coordinate), identifies each
//! from its motion alone and counts how often the truth lies inside each moment's 95 %
//! interval (1.96 standard errors). Also how often the time-scale check stays quiet, as it
//! should for every case here.

use chaoscope::fit::identify::{MOMENTS, identify};
use chaoscope::fit::window::TrackRows;
use chaoscope::model::{Params, State};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

fn main() {
    let cases: usize = std::env::args()
        .nth(1)
        .map_or(50, |a| a.parse().expect("CASES"));
    let mut inside = [0usize; 4];
    let (mut quiet, mut identified, mut refined) = (0, 0, 0);
    for seed in 0..cases as u64 {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let scale = 10f64.powf(rng.random_range(-1.3..0.7));
        let p = Params {
            m1: scale * rng.random_range(0.01..0.1),
            m2: scale * rng.random_range(0.001..0.02),
            l1: rng.random_range(0.08..0.3),
            l2: rng.random_range(0.06..0.25),
            g: 9.81,
            rod1: scale * rng.random_range(0.1..0.3),
            rod2: scale * rng.random_range(0.02..0.05),
            ..Params::default()
        };
        let mut p = p;
        let k = p.inertia();
        // Light joint damping: an e-fold of the swing in tens of seconds.
        (p.losses.joint1, p.losses.joint2) = (2e-3 * k.a, 2e-3 * k.b);
        let fps: f64 = [30.0, 60.0, 100.0, 240.0, 400.0][seed as usize % 5];
        let at_centre = seed % 2 == 1;
        let start = State::at_rest(rng.random_range(1.6..2.6), rng.random_range(1.5..3.0));
        let seconds = 20.0;
        let sub = (4000.0 / fps).ceil() as usize;
        let frames = (seconds * fps) as usize;
        let states =
            chaoscope::cpu::trajectory(&p, start, 1.0 / (fps * sub as f64), (frames * sub) as u32);
        let noise = Normal::new(0.0, 1e-4).unwrap();
        let r2 = if at_centre { 0.5 * p.l2 } else { p.l2 };
        let (mut t, mut data) = (Vec::new(), Vec::new());
        for (i, s) in states.iter().step_by(sub).take(frames).enumerate() {
            let (x1, y1) = (p.l1 * s.theta1.sin(), -p.l1 * s.theta1.cos());
            let (x2, y2) = (x1 + r2 * s.theta2.sin(), y1 - r2 * s.theta2.cos());
            let mut e = || noise.sample(&mut rng);
            t.push(i as f64 / fps);
            data.push([x1 + e(), y1 + e(), x2 + e(), y2 + e()]);
        }
        let rows: Vec<chaoscope::fit::TrackedRow> = t
            .iter()
            .zip(&data)
            .map(|(&t, d)| chaoscope::fit::TrackedRow {
                t,
                x1: d[0],
                y1: d[1],
                x2: d[2],
                y2: d[3],
            })
            .collect();
        let angles = chaoscope::fit::angles(&rows, (0.0, 0.0));
        let track = TrackRows {
            t: &t,
            data: &data,
            angles: &angles,
        };
        let truth = [k.a / k.p, k.b / k.p, k.c / k.p, k.q / k.p];
        match identify(&track, p.g, &chaoscope::monitor::Monitor::hidden()) {
            Ok(id) => {
                identified += 1;
                let hits: Vec<bool> = (0..4)
                    .map(|j| (id.values[j] - truth[j]).abs() <= 1.96 * id.errors[j])
                    .collect();
                for (j, &h) in hits.iter().enumerate() {
                    inside[j] += h as usize;
                }
                quiet += !id.time_scale.disagrees() as usize;
                refined += id.refinement.is_some() as usize;
                println!(
                    "seed {seed}: {fps} frames/s, masses x{scale:.2}, marker at the {}: {}; time scale z {:.2}",
                    if at_centre { "bar's centre" } else { "tip" },
                    (0..4)
                        .map(|j| format!(
                            "{} {:+.2} sd",
                            MOMENTS[j],
                            (id.values[j] - truth[j]) / id.errors[j]
                        ))
                        .collect::<Vec<_>>()
                        .join(", "),
                    id.time_scale.z
                );
            }
            Err(e) => println!("seed {seed}: {fps} frames/s: not identified: {e}"),
        }
    }
    println!("\n{identified} of {cases} identified; the truth inside the 95 % interval:");
    for j in 0..4 {
        println!(
            "  {}: {} of {identified} ({:.0} %)",
            MOMENTS[j],
            inside[j],
            100.0 * inside[j] as f64 / identified.max(1) as f64
        );
    }
    println!("the time-scale check quiet in {quiet} of {identified}");
    println!("refined on the angles in {refined} of {identified} (else the weak form's)");
}
