//! The real pendulum: rods with mass, joint damping, air drag; presets and parameter files.

mod common;

use common::chaoscope;

use chaoscope::cpu;
use chaoscope::gpu::{self, FlipTimeKernel};
use chaoscope::model::{Losses, Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::params::{ParamSources, Preset};
use chaoscope::spec::{FlipSpec, Grid, Stepping};
use predicates::prelude::*;

#[test]
fn massless_rods_are_point_masses() {
    let p = Params {
        m1: 1.3,
        m2: 0.6,
        l1: 0.9,
        l2: 1.4,
        ..Params::default()
    };
    let i = p.inertia();
    let m = p.m1 + p.m2;
    let close = |a: f64, b: f64| (a - b).abs() < 1e-14 * b.abs();
    assert!(close(i.a, m * p.l1 * p.l1));
    assert!(close(i.b, p.m2 * p.l2 * p.l2));
    assert!(close(i.c, p.m2 * p.l1 * p.l2));
    assert!(close(i.p, m * p.g * p.l1));
    assert!(close(i.q, p.m2 * p.g * p.l2));
}

#[test]
fn a_rod_pendulum_swings_with_the_compound_pendulum_period() {
    // Upper arm: a bob m1 on a rod r1; the lower arm almost nothing. Small oscillations of a
    // compound pendulum: w^2 = g (m1 + r1/2) l / ((m1 + r1/3) l^2), independent of the
    // Lagrangian's form (moment of inertia about the pivot, centre of mass).
    let p = Params {
        m1: 0.3,
        rod1: 0.6,
        l1: 0.8,
        m2: 1e-9,
        l2: 1e-3,
        ..Params::default()
    };
    let (slow, _) = p.normal_modes_squared();
    let expect = p.g * (p.m1 + p.rod1 / 2.0) * p.l1 / ((p.m1 + p.rod1 / 3.0) * p.l1 * p.l1);
    // The tiny lower arm perturbs the mode by ~m2 / m1 = 3e-9.
    assert!((slow / expect - 1.0).abs() < 1e-6, "{slow} vs {expect}");
    // And the simulation swings with it: zero crossings of theta1 a half period apart.
    let run = cpu::trajectory(&p, State::at_rest(0.01, 0.01), 1e-3, 4000);
    let crossings: Vec<f64> = run
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0].theta1 > 0.0 && w[1].theta1 <= 0.0)
        .map(|(k, w)| (k as f64 + w[0].theta1 / (w[0].theta1 - w[1].theta1)) * 1e-3)
        .collect();
    let period = crossings[1] - crossings[0];
    let want = std::f64::consts::TAU / expect.sqrt();
    // Amplitude correction theta0^2/16 = 6e-6; interpolation error ~ (dt/T)^2.
    assert!((period / want - 1.0).abs() < 1e-4, "{period} vs {want}");
}

/// Largest |E + W - E0| over 20 s at step `dt`, checking on the way that E never rises.
fn worst_balance(p: &Params, start: State, dt: f64) -> f64 {
    let states = cpu::trajectory(p, start, dt, (20.0 / dt).round() as u32);
    let work = cpu::dissipated_along(p, &states, dt);
    let e0 = p.energy(&start);
    let mut worst: f64 = 0.0;
    for (k, (s, w)) in states.iter().zip(&work).enumerate() {
        let e = p.energy(s);
        if k > 0 {
            // Each step loses energy, up to RK4's own error per step, O(dt^5).
            assert!(
                e <= p.energy(&states[k - 1]) + 1e-9 * p.energy_scale(),
                "energy rose at step {k} from {start:?}"
            );
        }
        worst = worst.max((e + w - e0).abs());
    }
    assert!(work.last().unwrap() > &0.0);
    worst
}

#[test]
fn energy_never_increases_and_energy_plus_dissipated_is_conserved() {
    let p = common::rods_and_every_loss();
    let fast = State {
        theta1: 0.5,
        omega1: 6.0,
        theta2: -2.0,
        omega2: -8.0,
    };
    for start in [State::at_rest(2.5, -1.0), State::at_rest(0.4, 0.2), fast] {
        let coarse = worst_balance(&p, start, 0.005);
        let fine = worst_balance(&p, start, 0.0025);
        // The books balance to RK4's global error: measured <= 2.2e-6 of the energy scale at
        // dt 0.005 (below the lossless energy drift at that step), and the error falls like
        // dt^4 (x16 per halving; measured x8..x22 - asserted > 6).
        assert!(coarse < 1e-5 * p.energy_scale(), "{start:?}: {coarse}");
        assert!(fine * 6.0 < coarse, "{start:?}: {coarse} -> {fine}");
    }
}

#[test]
fn bearing_friction_alone_takes_energy_and_stops_with_the_joints() {
    let mut p = Preset::Lab.params();
    p.losses = Losses {
        bearing: 1e-3,
        bearing_radius: 0.004,
        ..Losses::default()
    };
    let dt = 0.002;
    let start = State::at_rest(1.2, -0.4);
    let states = cpu::trajectory(&p, start, dt, 10_000);
    let work = cpu::dissipated_along(&p, &states, dt);
    // Power c_R r |F| |w| tanh(|w| / 0.01) >= 0 at every step, and the books balance.
    assert!(work.windows(2).all(|w| w[1] >= w[0] - 1e-15));
    let e0 = p.energy(&start);
    let last = states.len() - 1;
    let balance = (p.energy(&states[last]) + work[last] - e0).abs();
    // The smoothed sign switches within about one step at each turning point, where RK4
    // loses its order: measured 1.7e-7 of the energy scale (4.9e-7 J), asserted 1e-6.
    assert!(balance < 1e-6 * p.energy_scale(), "{balance}");
    // Loads of order the weight (~7 N) at r = 4 mm, c_R 1e-3: ~3e-5 N m against speeds of
    // a few rad/s take a few 1e-4 W, so 20 s lose a few mJ of ~0.5 J.
    let lost = work[last];
    assert!(lost > 1e-4 && lost < 0.05, "lost {lost} J");
}

#[test]
fn small_oscillations_decay_exponentially_at_the_modal_rate() {
    // Joint damping only, the slow normal mode excited: the energy decays like exp(-g t) with
    // g = v' D v / v' M0 v (v the mode shape, D = [[c1 + c2, -c2], [-c2, c2]], M0 the mass
    // matrix at rest), the report's exponential fit of section 2.4.
    let mut p = Params::default();
    p.losses.joint1 = 0.02;
    p.losses.joint2 = 0.01;
    let i = p.inertia();
    let (slow, _) = p.normal_modes_squared();
    // (P - w^2 A) v1 = w^2 C v2 gives the shape.
    let v = (slow * i.c, i.p - slow * i.a);
    let (c1, c2) = (p.losses.joint1, p.losses.joint2);
    let vdv = (c1 + c2) * v.0 * v.0 - 2.0 * c2 * v.0 * v.1 + c2 * v.1 * v.1;
    let vmv = i.a * v.0 * v.0 + 2.0 * i.c * v.0 * v.1 + i.b * v.1 * v.1;
    let rate = vdv / vmv;
    let amp = 1e-3 / v.0.abs().max(v.1.abs());
    let start = State::at_rest(amp * v.0, amp * v.1);
    let period = std::f64::consts::TAU / slow.sqrt();
    let dt = period / 400.0;
    let n = 20 * 400;
    let states = cpu::trajectory(&p, start, dt, n);
    let (e0, e1) = (p.energy(&start), p.energy(&states[n as usize]));
    let rest = p.potential_energy(0.0, 0.0);
    let measured = -((e1 - rest) / (e0 - rest)).ln() / (n as f64 * dt);
    // Light damping (rate/w ~ 3e-3): the modal formula holds to (rate/w)^2.
    assert!((measured / rate - 1.0).abs() < 0.01, "{measured} vs {rate}");
}

/// Largest difference of any state component between the GPU and CPU over 200 steps of 0.01 s.
fn worst_gpu_cpu_difference(ctx: &gpu::GpuContext, p: &Params, start: State) -> f64 {
    let want = cpu::trajectory(p, start, 0.01, 200);
    let got = common::gpu_trajectory(ctx, p, start, 0.01, 200);
    got.iter()
        .zip(&want)
        .flat_map(|(g, c)| {
            g.to_array()
                .into_iter()
                .zip(c.to_array())
                .map(|(a, b)| (a - b).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn every_gpu_loss_variant_follows_the_cpu() {
    // The shaders compile each kind of loss in or out (override LOSSES): check each alone.
    let Some(ctx) = common::gpu() else { return };
    let only = |f: fn(&mut Losses)| {
        let mut p = common::rods_and_every_loss();
        p.losses = Losses::default();
        f(&mut p.losses);
        p
    };
    let variants = [
        only(|l| (l.joint1, l.joint2) = (0.05, 0.02)),
        only(|l| (l.rho, l.cw, l.bob_area1, l.rod_area2) = (1.2, 2.0, 5e-3, 3e-3)),
        only(|l| (l.bearing, l.bearing_radius) = (0.05, 0.004)),
    ];
    for p in variants {
        let start = State::at_rest(0.5, 0.3);
        let worst = worst_gpu_cpu_difference(&ctx, &p, start);
        // A regular start: f32 round-off only (as in tests/gpu_vs_cpu.rs).
        assert!(worst < 1e-4, "{:?}: {worst}", p.losses);
        // And the maps: same fraction of flips within a percent (chaotic pixels may differ).
        let spec = FlipSpec::new(
            p,
            Grid::square(40),
            Stepping {
                dt: 0.01,
                t_max: 10.0,
            },
        );
        let c = flipped_fraction(&cpu::flip_map(&spec, &Monitor::hidden()).unwrap());
        let g = flipped_fraction(
            &FlipTimeKernel::new(&ctx)
                .run(&ctx, &spec, &Monitor::hidden())
                .unwrap(),
        );
        assert!(
            (c - g).abs() < 0.01,
            "{:?}: flipped cpu {c} gpu {g}",
            p.losses
        );
    }
}

#[test]
fn gpu_and_cpu_agree_with_rods_and_every_loss() {
    let Some(ctx) = common::gpu() else { return };
    let p = common::rods_and_every_loss();
    // Regular start and a short chaotic horizon, tolerances as for the lossless comparison.
    for (start, tol) in [
        (State::at_rest(0.5, 0.3), 1e-4),
        (State::at_rest(2.0, 1.5), 2e-3),
    ] {
        let worst = worst_gpu_cpu_difference(&ctx, &p, start);
        assert!(worst < tol, "{start:?}: {worst}");
    }
    // The shader's dual-number Jacobian carries the losses too.
    let states: Vec<State> = (0..50)
        .map(|k| State {
            theta1: 0.1 * k as f64 - 2.0,
            omega1: 3.0 - 0.13 * k as f64,
            theta2: 1.5 - 0.07 * k as f64,
            omega2: 0.2 * k as f64 - 4.0,
        })
        .collect();
    common::check_jacobians(&ctx, &p, &states);
}

#[test]
fn divergence_maps_carry_the_damping_on_both_paths() {
    let Some(ctx) = common::gpu() else { return };
    let mut p = Params::default();
    p.losses.joint1 = 0.1;
    p.losses.joint2 = 0.1;
    // The default divergence map (tangent, RK4, f32): the FTLE.
    let stepping = Stepping {
        dt: 0.01,
        t_max: 10.0,
    };
    let spec = chaoscope::spec::LyapunovSpec::new(p, Grid::square(40), stepping);
    let c = cpu::ftle_map(&spec, &Monitor::hidden()).unwrap();
    let g = gpu::LyapunovKernel::new(&ctx, spec.method)
        .run(&ctx, &spec, &Monitor::hidden())
        .unwrap();
    // Damping contracts phase space: the exponents' mean drops below the undamped map's.
    let undamped = cpu::ftle_map(
        &chaoscope::spec::LyapunovSpec {
            params: Params::default(),
            ..spec
        },
        &Monitor::hidden(),
    )
    .unwrap();
    let mean =
        |f: &chaoscope::Field| f.data.iter().map(|&x| x as f64).sum::<f64>() / f.data.len() as f64;
    assert!(
        mean(&c) < mean(&undamped),
        "{} vs {}",
        mean(&c),
        mean(&undamped)
    );
    // Same classification as for the undamped maps (tests/lyapunov.rs), at 10 s.
    let same = c
        .data
        .iter()
        .zip(&g.data)
        .filter(|(a, b)| (**a > 0.5) == (**b > 0.5))
        .count() as f64
        / c.data.len() as f64;
    assert!(same >= 0.97, "classes agree on {same}");
}

fn flipped_fraction(field: &chaoscope::Field) -> f64 {
    field.data.iter().filter(|t| t.is_finite()).count() as f64 / field.data.len() as f64
}

#[test]
fn damping_shrinks_the_flipping_region_and_the_no_flip_bound_still_holds() {
    let gpu_ctx = common::gpu();
    let mut last = f64::INFINITY;
    for c in [0.0, 0.3, 1.5] {
        let mut p = Params::default();
        p.losses.joint1 = c;
        p.losses.joint2 = c;
        let spec = FlipSpec {
            early_exit: false,
            ..FlipSpec::new(
                p,
                Grid::square(48),
                Stepping {
                    dt: 0.01,
                    t_max: 10.0,
                },
            )
        };
        let cpu_map = cpu::flip_map(&spec, &Monitor::hidden()).unwrap();
        let mut maps = vec![cpu_map];
        if let Some(ctx) = &gpu_ctx {
            maps.push(
                FlipTimeKernel::new(ctx)
                    .run(ctx, &spec, &Monitor::hidden())
                    .unwrap(),
            );
        }
        for map in &maps {
            // Losses only take energy away: below E* nothing can flip.
            for row in 0..48 {
                for col in 0..48 {
                    let s = spec.grid.start(col, row);
                    if p.energy(&s) < p.no_flip_threshold(1e-6) {
                        assert!(map.get(col, row).is_infinite(), "flip below E* at {s:?}");
                    }
                }
            }
        }
        let f = flipped_fraction(&maps[0]);
        assert!(f < last, "damping {c}: {f} flipped, not fewer than {last}");
        last = f;
    }
}

#[test]
fn presets_files_and_flags_combine_and_bad_keys_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("p.toml");
    std::fs::write(
        &file,
        "m1 = 0.5\nrod_mass = [0.1, 0.05]\njoint_damping = [0.01, 0.02]\n[air_drag]\nrho = 1.1\nrod_area = [1e-3, 2e-3]\n",
    )
    .unwrap();
    let csv = dir.path().join("t.csv");
    chaoscope()
        .args("trajectory --theta1 1 --theta2 1 --t-max 0.1".split(' '))
        .args(["--preset", "lab", "--params"])
        .arg(&file)
        .args(["--m2", "0.4", "--output"])
        .arg(&csv)
        .assert()
        .success();
    let header = std::fs::read_to_string(&csv).unwrap();
    let command = header.lines().next().unwrap();
    // Preset l1, file m1 and losses, flag m2: the CSV records what was used.
    for part in [
        "--m1 0.5 ",
        "--m2 0.4 ",
        "--l1 0.3 ",
        "--rod-mass 0.1,0.05",
        "--joint-damping 0.01,0.02",
        "--rho 1.1 ",
        "--rod-drag-area 0.001,0.002",
    ] {
        assert!(command.contains(part), "{part} missing from {command}");
    }
    let lab = Preset::Lab.params();
    assert_eq!((lab.m1, lab.m2, lab.rod1), (0.301, 0.297, 0.140));
    // The shipped example file is the preset written out.
    let from_file = ParamSources {
        params: Some(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab.toml")),
        ..Default::default()
    }
    .resolve()
    .unwrap();
    assert_eq!(from_file, lab);
    // Unknown keys and impossible values are errors naming the key.
    for (text, key) in [
        ("m1 = 1\nlength = 2\n", "length"),
        ("l2 = -1\n", "l2"),
        ("[air_drag]\nrho = -1\n", "air_drag.rho"),
    ] {
        std::fs::write(&file, text).unwrap();
        chaoscope()
            .args(["flip", "--size", "4", "--backend", "cpu", "--params"])
            .arg(&file)
            .arg("--output")
            .arg(dir.path().join("x.png"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains("--params").and(predicate::str::contains(key)));
    }
    chaoscope()
        .args("flip --size 4 --backend cpu --joint-damping -1".split(' '))
        .arg("--output")
        .arg(dir.path().join("x.png"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--joint-damping"));
}
