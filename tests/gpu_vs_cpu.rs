//! The GPU path (f32, lavapipe in CI) against the f64 CPU reference, and the properties both
//! maps must have. GPU tests need a real adapter: under CI=true a missing one fails.

mod common;

use std::f64::consts::PI;

use chaoscope::cpu;
use chaoscope::field::Field;
use chaoscope::gpu::{FlipTimeKernel, TrajectoryKernel};
use chaoscope::model::{Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::spec::{FlipSpec, Grid, Precision, Range, Stepping};

fn spec(n: u32, t_max: f64, params: Params, early_exit: bool) -> FlipSpec {
    FlipSpec {
        early_exit,
        ..FlipSpec::new(params, Grid::square(n), Stepping { dt: 0.01, t_max })
    }
}

/// Two flip times agree within one step (as the peers compare), or both never flip.
fn agree(a: f32, b: f32) -> bool {
    (a.is_infinite() && b.is_infinite()) || (a - b).abs() <= 0.011
}

/// Pixels whose 3x3 neighbourhood on the reference map is smooth: all never flip, or all
/// flip within `spread` s of each other. The rest is the chaotic part of the map.
fn regular_mask(reference: &Field, spread: f32) -> Vec<bool> {
    let (w, h) = (reference.width as i64, reference.height as i64);
    let mut mask = vec![false; reference.data.len()];
    for row in 0..h {
        for col in 0..w {
            let mut vals = Vec::new();
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let (r, c) = (row + dr, col + dc);
                    if (0..h).contains(&r) && (0..w).contains(&c) {
                        vals.push(reference.get(c as u32, r as u32));
                    }
                }
            }
            let all_never = vals.iter().all(|v| v.is_infinite());
            let finite: Vec<f32> = vals.iter().copied().filter(|v| v.is_finite()).collect();
            let smooth = finite.len() == vals.len()
                && finite.iter().copied().fold(f32::MIN, f32::max)
                    - finite.iter().copied().fold(f32::MAX, f32::min)
                    < spread;
            mask[(row * w + col) as usize] = all_never || smooth;
        }
    }
    mask
}

#[test]
fn gpu_and_cpu_trajectories_agree_over_a_short_horizon() {
    let Some(ctx) = common::gpu() else { return };
    let p = Params::default();
    let dt = 0.01;
    let steps = 200;
    // (start, tolerance in rad and rad/s). f32 round-off of ~1e-7 per step adds up over 200
    // steps to ~2e-5 and is amplified by the local stretching: little on a regular orbit,
    // e^(lambda t) with lambda ~ 2/s over 2 s (x50) on the chaotic ones.
    let cases = [
        (State::at_rest(0.5, 0.3), 1e-4),
        (State::at_rest(PI / 2.0, PI / 2.0), 2e-3),
        (
            State {
                theta1: 2.0,
                omega1: 1.0,
                theta2: -1.5,
                omega2: -2.0,
            },
            2e-3,
        ),
    ];
    for (start, tol) in cases {
        let want = cpu::trajectory(&p, start, dt, steps);
        let got = common::gpu_trajectory(&ctx, &p, start, dt, steps);
        assert_eq!(got.len(), want.len());
        let mut worst: f64 = 0.0;
        for (k, (g, c)) in got.iter().zip(&want).enumerate() {
            let d = g
                .to_array()
                .iter()
                .zip(c.to_array())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                d < tol,
                "start {start:?}, step {k}: gpu {g:?} cpu {c:?}, difference {d:e} > tolerance {tol:e}"
            );
            worst = worst.max(d);
        }
        eprintln!("start {start:?}: largest difference over {steps} steps {worst:e}");
        // The f32 path conserves energy as well as f64 RK4 does, up to f32 round-off of the
        // state (about 2 ulp = 1.2e-7 of the scale per step, adding up at worst linearly).
        let e0 = p.energy(&start);
        let drift = |states: &[State]| {
            states
                .iter()
                .map(|s| (p.energy(s) - e0).abs())
                .fold(0.0, f64::max)
                / p.energy_scale()
        };
        let (gpu_drift, cpu_drift) = (drift(&got), drift(&want));
        let allowance = cpu_drift + steps as f64 * 1.2e-7;
        assert!(
            gpu_drift < allowance,
            "start {start:?}: gpu energy drift {gpu_drift:e}, cpu {cpu_drift:e}"
        );
    }
}

#[test]
fn gpu_and_cpu_flip_maps_agree_on_the_regular_part() {
    let Some(ctx) = common::gpu() else { return };
    let s = spec(128, 10.0, Params::default(), true);
    let cpu_map = cpu::flip_map(&s, &Monitor::hidden()).unwrap();
    let gpu_map = FlipTimeKernel::new(&ctx)
        .run(&ctx, &s, &Monitor::hidden())
        .unwrap();
    let regular = regular_mask(&cpu_map, 0.5);
    let (mut reg, mut reg_ok, mut chaotic, mut chaotic_ok) = (0, 0, 0, 0);
    for ((&c, &g), &is_regular) in cpu_map.data.iter().zip(&gpu_map.data).zip(&regular) {
        let ok = agree(c, g);
        if is_regular {
            reg += 1;
            reg_ok += ok as u32;
        } else {
            chaotic += 1;
            chaotic_ok += ok as u32;
        }
    }
    let reg_frac = reg_ok as f64 / reg as f64;
    let chaotic_frac = chaotic_ok as f64 / chaotic.max(1) as f64;
    eprintln!(
        "regular: {reg} pixels, {reg_frac:.4} agree; chaotic: {chaotic} pixels, {chaotic_frac:.4} agree"
    );
    if reg_frac < 0.99 || chaotic_frac > reg_frac {
        let paths = common::dump_maps(
            "flip-gpu-vs-cpu",
            &[("cpu", &cpu_map), ("gpu", &gpu_map)],
            10.0,
        );
        panic!(
            "regular part agrees on {reg_frac:.4} (want >= 0.99), chaotic part on {chaotic_frac:.4}; maps: {paths}"
        );
    }
    assert!(
        reg > 8000,
        "the map should be mostly regular, got {reg} regular pixels"
    );
}

#[test]
fn no_start_inside_the_energetic_region_flips_and_some_just_outside_do() {
    let Some(ctx) = common::gpu() else { return };
    let kernel = FlipTimeKernel::new(&ctx);
    let sets = [
        Params::default(),
        Params {
            m1: 1.0,
            m2: 0.3,
            l1: 1.0,
            l2: 0.6,
            g: 9.81,
            ..Default::default()
        },
        Params {
            m1: 0.5,
            m2: 2.0,
            l1: 0.7,
            l2: 1.2,
            g: 3.7,
            ..Default::default()
        },
    ];
    for p in sets {
        // Integrate every start (no early exit, no skipping) so the region is tested, not assumed.
        let s = spec(48, 20.0, p, false);
        let maps = [
            ("cpu", cpu::flip_map(&s, &Monitor::hidden()).unwrap()),
            ("gpu", kernel.run(&ctx, &s, &Monitor::hidden()).unwrap()),
        ];
        let e_star = p.flip_energy();
        // RK4 at dt 0.01 keeps energy to ~1e-7 of its scale (tests/physics.rs), f32 to ~1e-6:
        // a margin of 1e-4 of the scale keeps numerical drift from deciding the test.
        let margin = 1e-4 * p.energy_scale();
        let mut inside = 0;
        let mut outside_flipped = 0;
        for row in 0..s.grid.height {
            for col in 0..s.grid.width {
                let e = p.energy(&s.grid.start(col, row));
                for (name, map) in &maps {
                    let t = map.get(col, row);
                    if e < e_star - margin {
                        assert!(
                            t.is_infinite(),
                            "{name} {p:?}: start ({col}, {row}) with E {e} < E* {e_star} flipped at {t}"
                        );
                    }
                    if e > e_star
                        && e < e_star + 0.1 * p.energy_scale()
                        && t.is_finite()
                        && *name == "cpu"
                    {
                        outside_flipped += 1;
                    }
                }
                inside += (e < e_star - margin) as u32;
            }
        }
        assert!(
            inside > 100,
            "{p:?}: the region should cover many pixels, got {inside}"
        );
        eprintln!("{p:?}: {inside} pixels inside; {outside_flipped} just outside flipped");
        assert!(outside_flipped > 0, "{p:?}: no start just above E* flipped");
    }
}

#[test]
fn early_exit_and_full_runs_give_the_same_map() {
    let Some(ctx) = common::gpu() else { return };
    let kernel = FlipTimeKernel::new(&ctx);
    let early = kernel
        .run(
            &ctx,
            &spec(64, 10.0, Params::default(), true),
            &Monitor::hidden(),
        )
        .unwrap();
    let full = kernel
        .run(
            &ctx,
            &spec(64, 10.0, Params::default(), false),
            &Monitor::hidden(),
        )
        .unwrap();
    // Same arithmetic per pixel either way: skipped starts never flip in the full run.
    assert_eq!(early, full);
}

#[test]
fn tiled_map_equals_untiled_map() {
    let Some(ctx) = common::gpu() else { return };
    let kernel = FlipTimeKernel::new(&ctx);
    let mut s = spec(64, 5.0, Params::default(), true);
    s.grid.height = 50;
    let whole = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
    // 7 rows per tile: 8 tiles, the last one partial.
    let tiled = kernel
        .run_tiled(&ctx, &s, &Monitor::hidden(), 7 * 64 + 5)
        .unwrap();
    assert_eq!(whole, tiled);
}

#[test]
fn gpu_maps_are_point_symmetric_bit_for_bit_and_the_mirrored_half_equals_them() {
    let Some(ctx) = common::gpu() else { return };
    let kernel = FlipTimeKernel::new(&ctx);
    // An odd height (the middle row is its own mirror image), without and with losses.
    for (params, early_exit, what) in [
        (Params::default(), true, "point masses, early exit"),
        (Params::default(), false, "point masses, every step"),
        (common::lab_with_every_loss(), true, "lab with every loss"),
    ] {
        let mut s = spec(96, 10.0, params, early_exit);
        s.grid.height = 71;
        let half = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
        s.use_symmetry = false;
        let full = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
        common::check_mirror(&full, &half, what);
    }
}

#[test]
fn cpu_maps_are_point_symmetric_bit_for_bit_and_the_mirrored_half_equals_them() {
    for (params, what) in [
        (Params::default(), "point masses"),
        (common::lab_with_every_loss(), "lab with every loss"),
    ] {
        let mut s = spec(24, 6.0, params, true);
        s.grid.height = 17;
        let half = cpu::flip_map(&s, &Monitor::hidden()).unwrap();
        s.use_symmetry = false;
        let full = cpu::flip_map(&s, &Monitor::hidden()).unwrap();
        common::check_mirror(&full, &half, what);
    }
}

#[test]
fn only_symmetric_grids_are_mirrored() {
    let s = spec(64, 1.0, Params::default(), true);
    assert_eq!(s.rows_to_integrate(), 32);
    let mut odd = s;
    odd.grid.height = 7;
    assert_eq!(odd.rows_to_integrate(), 4);
    let mut shifted = s;
    shifted.grid.x.range = Range {
        min: -3.0,
        max: 3.1,
    };
    assert_eq!(shifted.rows_to_integrate(), 64);
    let mut moving = s;
    moving.grid.fixed.omega2 = 0.5;
    assert_eq!(moving.rows_to_integrate(), 64);
    let mut off = s;
    off.use_symmetry = false;
    assert_eq!(off.rows_to_integrate(), 64);
}

#[test]
fn zoomed_grid_uses_pixel_centres() {
    let Some(ctx) = common::gpu() else { return };
    // A 2x1 grid over theta1 in [0, 1], theta2 in [-0.5, 0.5]: the centres are 0.25 and 0.75.
    let grid = Grid::angles(
        2,
        1,
        Range { min: 0.0, max: 1.0 },
        Range {
            min: -0.5,
            max: 0.5,
        },
        0.0,
        0.0,
    );
    assert_eq!(
        (grid.x_at(0), grid.x_at(1), grid.y_at(0)),
        (0.25, 0.75, 0.0)
    );
    let s = FlipSpec {
        early_exit: false,
        ..FlipSpec::new(
            Params::default(),
            grid,
            Stepping {
                dt: 0.01,
                t_max: 1.0,
            },
        )
    };
    let map = FlipTimeKernel::new(&ctx)
        .run(&ctx, &s, &Monitor::hidden())
        .unwrap();
    assert!(
        map.data.iter().all(|t| t.is_infinite()),
        "small angles never flip: {:?}",
        map.data
    );
}

/// lavapipe ends all of an invocation's loops after 65535 iterations in all and goes on
/// silently: a trajectory of more steps, and a map whose few pixels take more steps in a
/// dispatch, came back short (a trajectory's last states zero). f64 on both paths, so the
/// tolerance is the two discretisations' difference (carried cos and sin on the GPU), far
/// below what a step cut short would leave.
#[test]
fn gpu_runs_go_past_lavapipes_loop_limit() {
    let Some(ctx) = common::f64_gpu() else { return };
    let p = Params::default();
    let (start, dt, steps) = (State::at_rest(0.5, 0.3), 1e-4, 70_000);
    let want = cpu::trajectory(&p, start, dt, steps);
    let got = TrajectoryKernel::with_precision(&ctx, Precision::F64)
        .run(
            &ctx,
            &chaoscope::spec::EnsembleSpec::new(p, &[start], dt, steps),
        )
        .unwrap()
        .remove(0);
    for k in [65_535, 65_536, 70_000] {
        let d = (0..4)
            .map(|i| (got[k].to_array()[i] - want[k].to_array()[i]).abs())
            .fold(0.0, f64::max);
        assert!(d < 1e-8, "step {k}: gpu {:?} cpu {:?}", got[k], want[k]);
    }
    // 16 pixels at 1e-5 s: 65535 steps are 0.66 s, and a dispatch of 16 active pixels asked
    // for 2^20 steps.
    let s = FlipSpec::new(
        p,
        Grid::square(4),
        Stepping {
            dt: 1e-5,
            t_max: 3.0,
        },
    );
    let cpu_map = cpu::flip_map(&s, &Monitor::hidden()).unwrap();
    let gpu_map = FlipTimeKernel::with_precision(&ctx, Precision::F64)
        .run(&ctx, &s, &Monitor::hidden())
        .unwrap();
    let late = cpu_map
        .data
        .iter()
        .filter(|&&t| t > 0.66 && t < 3.0)
        .count();
    assert!(
        late > 0,
        "no pixel flips after 65535 steps: {:?}",
        cpu_map.data
    );
    for (k, (&c, &g)) in cpu_map.data.iter().zip(&gpu_map.data).enumerate() {
        // Flip times agree within ten steps: f64 on both paths, which differ by the two
        // discretisations; a flip missed past step 65535 reads as never.
        assert!(
            (c.is_infinite() && g.is_infinite()) || (c - g).abs() < 1e-4,
            "pixel {k}: cpu {c} gpu {g} (cpu map {:?})",
            cpu_map.data
        );
    }
}
