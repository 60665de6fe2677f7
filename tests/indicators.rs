//! The chaos indicators beyond the largest exponent (issue 21): the spectrum's structure
//! (Hamiltonian pairing, the sum against the phase-space volume, with and without joint
//! damping), SALI, GALI_k, MEGNO and the FLI against their known behaviour on regular and
//! chaotic starts, the Lagrangian descriptor against time reversal, and the GPU (f32 and
//! f64) against the f64 CPU twin.

mod common;

use common::argv;

use chaoscope::cpu;
use chaoscope::engine::Engine;
use chaoscope::field::Field;
use chaoscope::model::{Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::spec::{
    Alignment, Grid, Indicator, Integrator, LyapunovSpec, MapSpec, Method, Precision, Stepping,
};

const CHAOTIC_STARTS: [(f64, f64); 4] = [
    (std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2),
    (2.0, 1.0),
    (3.0, 0.0),
    (1.0, -2.5),
];

/// A start on a 2-torus of the regular region (FTLE ~ 0, SALI ~ 0.1), with enough frequency
/// shear that a tangent vector's linear growth shows within minutes (|v| ~ 1 + 0.1 t).
const REGULAR: (f64, f64) = (1.0, 0.0);

fn spec(indicator: Indicator, t_max: f64) -> LyapunovSpec {
    LyapunovSpec {
        params: Params::default(),
        grid: Grid::square(16),
        stepping: Stepping { dt: 0.01, t_max },
        method: Method::Tangent,
        renorm: 0.1,
        use_symmetry: true,
        precision: Precision::F64,
        band: None,
        integrator: Integrator::Rk4,
        indicator,
    }
}

/// (t, columns) at every renormalisation of one start, and the map's value.
fn trace(spec: &LyapunovSpec, (a, b): (f64, f64)) -> (Vec<(f64, Vec<f64>)>, f64) {
    let mut rows = Vec::new();
    let value = cpu::indicator_run(spec, State::at_rest(a, b), None, &mut |t, row| {
        rows.push((t, row.to_vec()))
    })
    .unwrap();
    (rows, value)
}

/// The row of `rows` at time `t`.
fn at(rows: &[(f64, Vec<f64>)], t: f64) -> &[f64] {
    &rows.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1
}

/// Least-squares slope of y against x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// ln det M(q) up to a constant: det M = m2 l1^2 l2^2 (m1 + m2 sin^2 (theta1 - theta2)).
fn log_det_mass(p: &Params, s: &State) -> f64 {
    (p.m1 + p.m2 * (s.theta1 - s.theta2).sin().powi(2)).ln()
}

#[test]
fn the_spectrum_pairs_as_a_hamiltonian_flow_and_sums_to_the_volume_change() {
    let p = Params::default();
    let s = spec(Indicator::ExponentSum, 160.0);
    for start in CHAOTIC_STARTS {
        let (rows, _) = trace(&s, start);
        // The sum times t is ln det of the tangent flow, which in (theta, omega) is the volume
        // change ln det M(q0) - ln det M(q(t)) (Liouville in canonical coordinates), up to
        // RK4's truncation (<= 1e-3 over 20 s at dt 0.01, tests/lyapunov.rs). At 20 s, before
        // chaos parts this run's trajectory from cpu::trajectory's by more than 1e-8.
        let end = *cpu::trajectory(&p, State::at_rest(start.0, start.1), 0.01, 2000)
            .last()
            .unwrap();
        let volume = log_det_mass(&p, &State::at_rest(start.0, start.1)) - log_det_mass(&p, &end);
        let sum = at(&rows, 20.0)[4];
        assert!(
            (sum * 20.0 - volume).abs() < 1e-3,
            "{start:?}: sum x t {} vs {volume}",
            sum * 20.0
        );
        // Hamiltonian pairing: l1 + l4, l2 and l3 tend to 0 like C/t (the frame's transient
        // and bounded fluctuations). Fitting x(t) = a + C/t over 10 .. 160 s estimates the
        // limit a, where a broken pairing would leave a good fraction of l1.
        let l1 = at(&rows, 160.0)[0];
        assert!(l1 > 0.5, "{start:?}: chaotic");
        // The pairs' sums converge fastest (measured <= 0.004 /s); the two zero exponents
        // themselves, along the flow and across the energy surface, like ln t / t (<= 0.032
        // /s), which the C/t fit leaves partly in its limit.
        type Pick = fn(&[f64]) -> f64;
        for (name, pick, bound) in [
            ("l1 + l4", (|r: &[f64]| r[0] + r[3]) as Pick, 0.02),
            ("l2 + l3", |r: &[f64]| r[1] + r[2], 0.02),
            ("l2", |r: &[f64]| r[1], 0.1),
            ("l3", |r: &[f64]| r[2], 0.1),
        ] {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|(t, _)| *t >= 10.0)
                .map(|(t, r)| (1.0 / t, pick(r)))
                .collect();
            let c = slope(&points);
            let n = points.len() as f64;
            let limit = points.iter().map(|(u, x)| x - c * u).sum::<f64>() / n;
            eprintln!("{start:?} {name}: limit {limit:.4} /s, C {c:.2}, l1 {l1:.3}");
            assert!(
                limit.abs() < bound * l1,
                "{start:?}: {name} tends to {limit} /s (C/t fit), l1 = {l1}"
            );
        }
    }
}

#[test]
fn with_joint_damping_the_sum_is_the_mean_divergence_in_canonical_coordinates() {
    // In (q, p) the conservative flow keeps volume; the joint torques tau = -D omega add
    // div = d(p-dot)/dp = -tr(D M(q)^-1), D = [[c1 + c2, -c2], [-c2, c2]]. The sum of the
    // exponents is its time mean plus the coordinates' volume change over t (both computed
    // here from the trajectory alone, not from tangent vectors).
    let (c1, c2) = (0.05, 0.03);
    let mut p = Params::default();
    p.losses.joint1 = c1;
    p.losses.joint2 = c2;
    let t_max = 40.0;
    let s = LyapunovSpec {
        params: p,
        ..spec(Indicator::ExponentSum, t_max)
    };
    let i = p.inertia();
    let divergence = |y: &State| {
        // M = [[A, C cos D], [C cos D, B]]; tr(D M^-1) = (D11 B + D22 A - 2 D12 C cos D) / det M.
        let cd = i.c * (y.theta1 - y.theta2).cos();
        let det = i.a * i.b - cd * cd;
        -((c1 + c2) * i.b + c2 * i.a + 2.0 * c2 * cd) / det
    };
    for start in CHAOTIC_STARTS.into_iter().chain([REGULAR]) {
        let (_, sum) = trace(&s, start);
        let states = cpu::trajectory(&p, State::at_rest(start.0, start.1), 0.01, 4000);
        // The trapezoid rule over the RK4 states: O(dt^2) = 1e-4 relative at worst.
        let integral: f64 = states
            .windows(2)
            .map(|w| 0.005 * (divergence(&w[0]) + divergence(&w[1])))
            .sum();
        let volume = log_det_mass(&p, &states[0]) - log_det_mass(&p, states.last().unwrap());
        let expected = (integral + volume) / t_max;
        eprintln!("{start:?}: sum {sum:.6} expected {expected:.6}");
        // RK4's truncation of the volume (<= 2e-3 over 40 s, as undamped) and the trapezoid
        // rule's 1e-4 of the mean divergence (~0.1 /s).
        assert!(
            (sum - expected).abs() < 1e-4,
            "{start:?}: sum {sum} /s, mean divergence and volume change {expected} /s"
        );
        assert!(expected < -0.05, "damping contracts: {expected}");
    }
}

#[test]
fn the_spectrum_agrees_with_the_qr_reference_and_its_first_exponent_is_the_ftle() {
    // cpu::lyapunov_spectrum steps the 4 x 4 Jacobian matrix and re-orthonormalises by
    // nalgebra's Householder QR: a different algorithm over the same RK4 trajectory.
    for start in CHAOTIC_STARTS {
        let s = spec(Indicator::Exponent(1), 20.0);
        let reference = cpu::lyapunov_spectrum(&s, State::at_rest(start.0, start.1));
        let (rows, l1) = trace(&s, start);
        let ftle = cpu::ftle(&s, State::at_rest(start.0, start.1)).last();
        assert_eq!(l1.to_bits(), ftle.to_bits(), "{start:?}: bit for bit");
        let last = &rows.last().unwrap().1;
        for (k, (ours, theirs)) in last.iter().zip(reference).enumerate() {
            // Both start from the same frame and are exact up to round-off, which chaos
            // amplifies over 20 s by e^(20 l1) ~ 1e10: measured <= 3e-6 /s.
            assert!(
                (ours - theirs).abs() < 1e-4,
                "{start:?}: exponent {} {ours} vs {theirs}",
                k + 1
            );
        }
    }
}

fn alignment(index: Alignment, threshold: f64, t_max: f64) -> LyapunovSpec {
    spec(Indicator::Alignment { index, threshold }, t_max)
}

#[test]
fn sali_stays_near_one_when_regular_and_falls_at_the_rate_l1_minus_l2_when_chaotic() {
    let (rows, value) = trace(&alignment(Alignment::Sali, 1e-12, 200.0), REGULAR);
    let lowest = rows.iter().map(|r| r.1[0]).fold(f64::INFINITY, f64::min);
    eprintln!("regular: log10 SALI at 200 s {value:.3}, lowest {lowest:.3}");
    // Two vectors on a torus keep a finite angle: SALI oscillates but stays O(1).
    assert!(lowest > -2.0, "regular SALI fell to 10^{lowest}");
    for start in CHAOTIC_STARTS {
        let (rows, _) = trace(&alignment(Alignment::Sali, 1e-12, 40.0), start);
        let (spectrum, _) = trace(&spec(Indicator::Exponent(1), 40.0), start);
        let l = spectrum.last().unwrap().1.clone();
        let expected = -(l[0] - l[1]) / std::f64::consts::LN_10;
        // The decay from 10^-2 (past the transient) to 10^-11 (above round-off's 1e-16).
        let falling: Vec<(f64, f64)> = rows
            .iter()
            .map(|(t, r)| (*t, r[0]))
            .filter(|(_, y)| (-11.0..=-2.0).contains(y))
            .collect();
        let fitted = slope(&falling);
        eprintln!(
            "{start:?}: slope {fitted:.3} /s over {} samples, (l1 - l2) / ln 10 = {expected:.3}",
            falling.len()
        );
        assert!(falling.len() > 20, "{start:?}: too few samples");
        // Finite-time exponents fluctuate by ~1/sqrt(t) of themselves: 25 %.
        assert!(
            (fitted - expected).abs() < 0.25 * expected.abs(),
            "{start:?}: slope {fitted} vs {expected}"
        );
    }
}

#[test]
fn gali_of_a_regular_orbit_decays_as_its_torus_dimension_says() {
    // On a 2-torus of a 4-dimensional phase space GALI_2 ~ const, GALI_3 ~ t^-2, GALI_4 ~
    // t^-4 (Skokos, Bountis, Antonopoulos 2007).
    for (k, expected) in [(2u8, 0.0), (3, -2.0), (4, -4.0)] {
        let (rows, _) = trace(&alignment(Alignment::Gali(k), 1e-300, 400.0), REGULAR);
        // (Measured over 40 .. 2000 s: 0.00, -2.00, -4.00; with the first two vectors of the
        // frame sharing their angle parts, GALI_2 fell like 1/t: src/cpu/indicators.rs FRAME.)
        // log10 GALI against log10 t from 40 s on (past the transient).
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|(t, _)| *t >= 40.0)
            .map(|(t, r)| (t.log10(), r[0]))
            .collect();
        let fitted = slope(&points);
        eprintln!("GALI_{k}: slope {fitted:.3}, expected {expected}");
        // The indices oscillate with the orbit's frequencies about their power law; over a
        // decade of t that leaves the fitted exponent within 0.5.
        assert!(
            (fitted - expected).abs() < 0.5,
            "GALI_{k}: slope {fitted}, expected {expected}"
        );
    }
}

#[test]
fn megno_tends_to_zero_isochronous_two_regular_and_grows_at_half_l1_chaotic() {
    let megno = spec(Indicator::Megno, 400.0);
    // Small oscillations are the linear normal modes: isochronous, the tangent vector stays
    // bounded and <Y> -> 0 (like 1/t).
    let (_, small) = trace(&megno, (1e-3, 1e-3));
    let (_, regular) = trace(&megno, REGULAR);
    eprintln!("MEGNO small {small:.4}, regular {regular:.4}");
    assert!(small.abs() < 0.1, "small oscillations: <Y> = {small}");
    // A non-isochronous torus: the tangent vector grows like 1 + a t, Y = 2 - 2 ln(1 + a t)
    // / (a t), and its mean lags further: with a ~ 0.1 /s, <Y> ~ 1.9 at 400 s.
    assert!((regular - 2.0).abs() < 0.25, "regular: <Y> = {regular}");
    for start in CHAOTIC_STARTS {
        let (rows, _) = trace(&spec(Indicator::Megno, 80.0), start);
        let (spectrum, _) = trace(&spec(Indicator::Exponent(1), 80.0), start);
        let l1 = spectrum.last().unwrap().1[0];
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|(t, _)| *t >= 20.0)
            .map(|(t, r)| (*t, r[0]))
            .collect();
        let fitted = slope(&points);
        eprintln!("{start:?}: <Y> slope {fitted:.3}, l1 / 2 = {:.3}", l1 / 2.0);
        assert!(
            (fitted - l1 / 2.0).abs() < 0.25 * l1 / 2.0,
            "{start:?}: <Y> grows at {fitted} /s, l1 / 2 = {}",
            l1 / 2.0
        );
    }
}

#[test]
fn the_fli_grows_like_log_t_when_regular_and_like_l1_t_when_chaotic() {
    let (_, regular) = trace(&spec(Indicator::Fli, 100.0), REGULAR);
    eprintln!("FLI regular {regular:.3}");
    // |v| <= 1 + K t with K the frequency shear (<~ 10 /s, tests/lyapunov.rs).
    assert!(
        regular < (1.0 + 10.0 * 100.0f64).log10(),
        "regular FLI {regular}"
    );
    for start in CHAOTIC_STARTS {
        let (_, fli) = trace(&spec(Indicator::Fli, 40.0), start);
        let ftle = cpu::ftle(
            &spec(Indicator::Ftle, 40.0),
            State::at_rest(start.0, start.1),
        )
        .last();
        eprintln!(
            "{start:?}: FLI {fli:.3}, FTLE t / ln 10 = {:.3}",
            ftle * 40.0 / std::f64::consts::LN_10
        );
        // The FLI is the largest log10 |v| so far, the FTLE the last one over t: equal
        // unless |v| shrank at the end, by at most a few Lyapunov times' swing.
        let last = ftle * 40.0 / std::f64::consts::LN_10;
        assert!(
            fli >= last - 1e-9 && fli < last + 2.0,
            "{start:?}: FLI {fli}, FTLE {last}"
        );
    }
}

#[test]
fn the_descriptor_of_a_start_at_rest_is_twice_its_forward_integral() {
    // Started at rest, the undamped motion is time-reversible: the backward run is the
    // forward one with omega negated, and RK4 with -dt keeps that bit for bit (negation is
    // exact), so M is twice the forward integral of sum |f_i|^p.
    let p = Params::default();
    for power in [0.5, 1.0] {
        let s = spec(Indicator::Descriptor { p: power }, 20.0);
        for start in CHAOTIC_STARTS.into_iter().chain([REGULAR]) {
            let (_, m) = trace(&s, start);
            let states = cpu::trajectory(&p, State::at_rest(start.0, start.1), 0.01, 2000);
            let g = |y: &State| -> f64 {
                cpu::derivative(&p, y)
                    .to_array()
                    .iter()
                    .map(|f| f.abs().powf(power))
                    .sum()
            };
            let forward: f64 = states
                .windows(2)
                .map(|w| 0.005 * (g(&w[0]) + g(&w[1])))
                .sum();
            assert!(
                (m - 2.0 * forward).abs() < 1e-12 * m,
                "{start:?}, p {power}: M {m} vs twice {forward}"
            );
        }
    }
}

/// Every indicator's map settings, from the registry: each name with its options at an f32
/// GPU run's defaults (the threshold and distance f32 resolves), every value of a
/// whole-number option (the exponents, GALI's orders), and every descriptor power.
fn every_indicator() -> Vec<Indicator> {
    let mut all = Vec::new();
    for m in chaoscope::measure::MEASURES {
        for &name in m.names() {
            let mut asked: Vec<Vec<(&'static str, f64)>> = vec![Vec::new()];
            for opt in m.options(name) {
                if let Some((low, high)) = opt.whole {
                    asked = (low..=high)
                        .flat_map(|v| {
                            asked.iter().map(move |given| {
                                let mut given = given.clone();
                                given.push((opt.field, v as f64));
                                given
                            })
                        })
                        .collect();
                }
            }
            for given in &asked {
                let i = chaoscope::measure::IndicatorAsked {
                    options: given,
                    gpu_f32: true,
                    ..chaoscope::measure::IndicatorAsked::named(name)
                }
                .indicator()
                .unwrap();
                match i {
                    Indicator::Descriptor { .. } => all.extend(
                        chaoscope::measure::DESCRIPTOR_POWERS.map(|p| Indicator::Descriptor { p }),
                    ),
                    i => all.push(i),
                }
            }
        }
    }
    all
}

fn map_on(engine: &Engine, s: &LyapunovSpec) -> Field {
    s.validate().unwrap();
    engine.map(s, &Monitor::hidden()).unwrap()
}

#[test]
fn gpu_maps_equal_the_cpu_twin_on_every_indicator() {
    let Some(ctx) = common::f64_gpu() else { return };
    let gpu = Engine::on_gpu(ctx);
    let cpu = Engine::new(chaoscope::engine::Backend::Cpu).unwrap();
    for indicator in every_indicator() {
        // 5 s: chaos amplifies round-off by at most e^(3 x 5) ~ 3e6, so the f64 maps agree
        // to ~1e-9; f32's 6e-8 becomes ~0.2 at worst, but the median pixel keeps ~1e-4.
        let s = LyapunovSpec {
            grid: Grid::square(24),
            ..spec(indicator, 5.0)
        };
        let reference = map_on(&cpu, &s);
        let f64_map = map_on(&gpu, &s);
        let f32_map = map_on(
            &gpu,
            &LyapunovSpec {
                precision: Precision::F32,
                ..s
            },
        );
        let tolerance = s.quantity().agree;
        let agree = |a: f32, b: f32| tolerance.agrees(a, b);
        let agreeing = |map: &Field| {
            map.data
                .iter()
                .zip(&reference.data)
                .filter(|(a, b)| agree(**a, **b) || (a.is_infinite() && a == b))
                .count() as f64
                / reference.data.len() as f64
        };
        let mut differences: Vec<f64> = f64_map
            .data
            .iter()
            .zip(&reference.data)
            .filter(|(g, c)| g.is_finite() && c.is_finite())
            .map(|(g, c)| ((g - c) / (1.0 + c.abs())).abs() as f64)
            .collect();
        differences.sort_by(f64::total_cmp);
        let median = differences
            .get(differences.len() / 2)
            .copied()
            .unwrap_or(0.0);
        let (f64_agree, f32_agree) = (agreeing(&f64_map), agreeing(&f32_map));
        eprintln!(
            "{indicator:?}: f64 agreeing {f64_agree:.3}, median difference {median:.1e}; f32 agreeing {f32_agree:.3}"
        );
        // Two discretisations of one ODE: the shader carries cos and sin of the angles as
        // state (RK4's O(dt^4) truncation), the CPU takes them from the angles; chaos
        // amplifies the difference (measured median 1e-5 for the FTLE at 5 s), so a few
        // pixels near the inverted start (exponents up to ~6 /s) may leave the rule.
        assert!(
            f64_agree >= 0.99,
            "{indicator:?}: GPU f64 agrees on {f64_agree}"
        );
        assert!(median < 1e-3, "{indicator:?}: median difference {median}");
        // f32's 6e-8 grows by the same factor: most pixels keep the rule, not all.
        assert!(f32_agree >= 0.9, "{indicator:?}: f32 agrees on {f32_agree}");
    }
}

#[test]
fn indicator_maps_are_point_symmetric_bit_for_bit_and_the_first_exponent_is_the_ftle() {
    let Some(ctx) = common::f64_gpu() else { return };
    let gpu = Engine::on_gpu(ctx);
    let cpu = Engine::new(chaoscope::engine::Backend::Cpu).unwrap();
    for precision in Precision::ALL {
        // The tangent equations are even under y -> -y and |f(-y)| = |f(y)|: the mirrored
        // start gets every indicator bit for bit (as the FTLE, tests/lyapunov.rs).
        for indicator in every_indicator() {
            let s = LyapunovSpec {
                grid: Grid::square(12),
                use_symmetry: false,
                precision,
                ..spec(indicator, 3.0)
            };
            let m = map_on(&gpu, &s);
            let n = m.data.len();
            for (i, x) in m.data.iter().enumerate() {
                assert_eq!(
                    x.to_bits(),
                    m.data[n - 1 - i].to_bits(),
                    "{indicator:?} {precision:?} pixel {i}"
                );
            }
        }
        let ftle = spec(Indicator::Ftle, 5.0);
        let first = spec(Indicator::Exponent(1), 5.0);
        let (ftle, first) = (
            LyapunovSpec { precision, ..ftle },
            LyapunovSpec { precision, ..first },
        );
        // The FTLE kernel differentiates the rate by dual numbers, the spectrum kernel by its
        // closed-form Jacobian (without drag and bearings): one derivative two ways, equal up
        // to round-off, which chaos amplifies by up to e^(3 x 5) in 5 s. Measured on 64 x 64:
        // f32 <= 8.1e-5 /s (median 2.4e-7), f64 below f32's resolution of the stored value;
        // the CPU twin's one code path is bit for bit (below).
        let (a, b) = (map_on(&gpu, &ftle), map_on(&gpu, &first));
        for (x, y) in a.data.iter().zip(&b.data) {
            let tolerance = match precision {
                Precision::F32 => 1e-3,
                Precision::F64 => 1e-9,
            };
            assert!(
                (x - y).abs() as f64 <= tolerance,
                "{precision:?}: FTLE {x}, exponent 1 {y}"
            );
        }
    }
    let (ftle, first) = (
        spec(Indicator::Ftle, 5.0),
        spec(Indicator::Exponent(1), 5.0),
    );
    assert_eq!(map_on(&cpu, &ftle).data, map_on(&cpu, &first).data, "cpu");
}

#[test]
fn the_command_line_refuses_a_flag_of_another_indicator_naming_it() {
    for (args, flag) in [
        (vec!["--indicator", "sali", "--exponent", "2"], "--exponent"),
        (vec!["--indicator", "megno", "--gali", "3"], "--gali"),
        (
            vec!["--indicator", "fli", "--threshold", "1e-6"],
            "--threshold",
        ),
        (vec!["--indicator", "sali", "--ld-p", "1"], "--ld-p"),
        (
            vec!["--indicator", "exponent", "--exponent", "5"],
            "--exponent",
        ),
        (vec!["--indicator", "gali", "--gali", "5"], "--gali"),
        (vec!["--indicator", "descriptor", "--ld-p", "3"], "--ld-p"),
        (
            vec!["--indicator", "sali", "--threshold", "2"],
            "--threshold",
        ),
        // f32 on the GPU cannot see an alignment index below its round-off.
        (
            argv("--indicator sali --threshold 1e-8 --backend gpu"),
            "--threshold",
        ),
        (vec!["--indicator", "megno", "--accurate"], "--accurate"),
        (vec!["--indicator", "sali", "--method", "twin"], "--method"),
        (
            vec!["--indicator", "sali", "--integrator", "dp54"],
            "--integrator",
        ),
        (vec!["--indicator", "spectrum"], "--indicator"),
    ] {
        let out = common::chaoscope()
            .args(["lyapunov", "--size", "8", "--t-max", "1"])
            .args(&args)
            .args(["--output", "/nonexistent/x.png"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains(flag),
            "{args:?} should name {flag}: {stderr}"
        );
    }
}

#[test]
fn an_indicator_map_writes_its_values_and_a_single_start_its_running_columns() {
    let dir = tempfile::tempdir().unwrap();
    let npy = dir.path().join("m.npy");
    let out = common::chaoscope()
        .args("lyapunov --size 12 --t-max 3 --indicator megno".split(' '))
        .args(["--backend", "cpu", "--json", "--output"])
        .arg(dir.path().join("m.png"))
        .arg("--data")
        .arg(&npy)
        .output()
        .unwrap();
    let summary = common::summary(out);
    assert_eq!(summary["quantity"], "MEGNO", "{summary}");
    let (shape, values) = common::read_npy(&npy);
    assert_eq!(shape, vec![12, 12]);
    // The CPU twin's own value at one pixel (the map's pixel 0: the grid's top-left start).
    let s = LyapunovSpec {
        grid: Grid::square(12),
        ..spec(Indicator::Megno, 3.0)
    };
    let start = s.grid.start(0, 0);
    let expected = cpu::indicator_run(&s, start, None, &mut |_, _| {}).unwrap();
    assert_eq!(values[0], expected as f32);
    // A single start's running spectrum, one row per renormalisation.
    let out = common::chaoscope()
        .args(["lyapunov", "--theta1", "2", "--theta2", "1", "--t-max", "1"])
        .args(["--indicator", "exponent-sum"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].starts_with("# chaoscope lyapunov")
            && lines[0].contains("--indicator exponent-sum")
    );
    assert_eq!(lines[1], "t,lambda1,lambda2,lambda3,lambda4,sum");
    assert_eq!(lines.len(), 2 + 10, "{csv}");
    let last: Vec<f64> = lines[11].split(',').map(|x| x.parse().unwrap()).collect();
    assert!(
        (last[5] - last[1..5].iter().sum::<f64>()).abs() < 1e-12,
        "{csv}"
    );
}

#[test]
fn the_spectrum_of_one_run_is_each_exponents_map_and_the_command_writes_it_with_a_leading_axis() {
    let cpu = Engine::new(chaoscope::engine::Backend::Cpu).unwrap();
    let mut engines = vec![("cpu", cpu)];
    if let Some(ctx) = common::f64_gpu() {
        engines.push(("gpu", Engine::on_gpu(ctx)));
    }
    for (name, engine) in &engines {
        for precision in Precision::ALL {
            let s = LyapunovSpec {
                grid: Grid {
                    width: 10,
                    height: 7,
                    ..Grid::square(1)
                },
                precision,
                ..spec(Indicator::ExponentSum, 2.0)
            };
            let layers = engine.spectrum(&s, &Monitor::hidden()).unwrap();
            for (k, layer) in layers.iter().enumerate() {
                let one = LyapunovSpec {
                    indicator: Indicator::Exponent(k as u8 + 1),
                    ..s
                };
                // The same kernel, the same run: the same bits.
                assert_eq!(
                    layer.data,
                    map_on(engine, &one).data,
                    "{name} {precision:?} exponent {}",
                    k + 1
                );
            }
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spectrum.npy");
    let out = common::chaoscope()
        .args("lyapunov --size 9x6 --t-max 2 --indicator exponent".split(' '))
        .args(["--exponent", "3", "--output"])
        .arg(dir.path().join("l3.png"))
        .arg("--data")
        .arg(dir.path().join("l3.npy"))
        .arg("--spectrum")
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (shape, all) = common::read_npy(&path);
    assert_eq!(shape, vec![4, 6, 9]);
    let (_, third) = common::read_npy(&dir.path().join("l3.npy"));
    assert_eq!(&all[2 * 54..3 * 54], third.as_slice(), "layer 3 is the map");
    // The four sum to the volume change over t: |sum| <= ln 2 / t (det M varies by at most a
    // factor 1 + m2 / m1 = 2), RK4 adding <= 1e-3 / t.
    for i in 0..54 {
        let sum: f32 = (0..4).map(|k| all[54 * k + i]).sum();
        assert!(
            sum.abs() <= (2f32.ln() + 1e-3) / 2.0,
            "pixel {i}: sum {sum}"
        );
    }
}

#[test]
fn the_verdict_vouches_only_for_pixels_a_converged_reference_confirms() {
    // 20 s is past the predictability horizon of much of the chaotic sea: two runs of a
    // start at different steps have parted there, and their finite-time values agree within
    // the accuracy rule by chance about a quarter of the time (measured 96.6 % right with the
    // rule itself as the verdict's, 128 x 128). The verdict's own rule, a fifth of it, must
    // leave >= 99.5 % of the pixels it vouches for right against the f64 map at an eighth of
    // the step, where that reference is itself converged (it agrees with a sixteenth).
    let Some(ctx) = common::f64_gpu() else { return };
    let engine = Engine::on_gpu(ctx);
    let quiet = Monitor::hidden();
    for indicator in [
        Indicator::Ftle,
        Indicator::Exponent(2),
        Indicator::ExponentSum,
        Indicator::Megno,
        Indicator::Fli,
        Indicator::Descriptor { p: 0.5 },
    ] {
        let s = LyapunovSpec {
            grid: Grid::square(64),
            precision: Precision::F32,
            ..spec(indicator, 20.0)
        };
        let (map, mask) = engine
            .planned_map(&engine.plan(&s, true).unwrap(), &quiet)
            .unwrap();
        let mask = mask.unwrap();
        let at = |dt: f64| {
            let fine = LyapunovSpec {
                precision: Precision::F64,
                stepping: Stepping { dt, t_max: 20.0 },
                ..s
            };
            engine.map(&fine, &quiet).unwrap()
        };
        let (reference, check) = (at(0.00125), at(0.000625));
        let tolerance = s.quantity().agree;
        let agree = |a: f32, b: f32| tolerance.agrees(a, b);
        let (mut vouched, mut right) = (0, 0);
        for (((&m, &r), &c), &vouch) in map
            .data
            .iter()
            .zip(&reference.data)
            .zip(&check.data)
            .zip(&mask)
        {
            if vouch == 1 && agree(r, c) {
                vouched += 1;
                right += agree(m, r) as usize;
            }
        }
        let share = right as f64 / vouched.max(1) as f64;
        eprintln!(
            "{indicator:?}: {vouched} vouched where the reference converged, {:.2} % right",
            100.0 * share
        );
        assert!(
            vouched > 400,
            "{indicator:?}: the verdict vouched for {vouched} pixels only"
        );
        assert!(
            share >= 0.995,
            "{indicator:?}: {right} of {vouched} vouched pixels right"
        );
    }
}

#[test]
fn with_losses_the_gpu_indicators_equal_the_cpu_twin() {
    // Joint damping runs through the shader's closed-form Jacobian, drag and bearing friction
    // through its dual numbers: both against the CPU's dual numbers through the mass matrix.
    let Some(ctx) = common::f64_gpu() else { return };
    let gpu = Engine::on_gpu(ctx);
    let cpu = Engine::new(chaoscope::engine::Backend::Cpu).unwrap();
    let mut damped = Params::default();
    damped.losses.joint1 = 0.05;
    damped.losses.joint2 = 0.03;
    for (name, params) in [
        ("joint damping", damped),
        ("every loss", common::rods_and_every_loss()),
    ] {
        for indicator in [
            Indicator::Exponent(1),
            Indicator::Exponent(4),
            Indicator::ExponentSum,
            Indicator::Alignment {
                index: Alignment::Sali,
                threshold: 1e-12,
            },
            Indicator::Alignment {
                index: Alignment::Gali(3),
                threshold: 1e-12,
            },
        ] {
            let s = LyapunovSpec {
                params,
                grid: Grid::square(16),
                ..spec(indicator, 3.0)
            };
            let (g, c) = (map_on(&gpu, &s), map_on(&cpu, &s));
            let mut d: Vec<f64> = g
                .data
                .iter()
                .zip(&c.data)
                .map(|(a, b)| ((a - b) / (1.0 + b.abs())).abs() as f64)
                .collect();
            d.sort_by(f64::total_cmp);
            let agreeing = g
                .data
                .iter()
                .zip(&c.data)
                .filter(|(a, b)| s.quantity().agree.agrees(**a, **b))
                .count();
            eprintln!(
                "{name} {indicator:?}: median {:.1e}, agreeing {agreeing} of 256",
                d[128]
            );
            // As the lossless case (gpu_maps_equal_the_cpu_twin_on_every_indicator), over 3 s.
            assert!(
                d[128] < 1e-3,
                "{name} {indicator:?}: median difference {}",
                d[128]
            );
            assert!(
                agreeing >= 253,
                "{name} {indicator:?}: {agreeing} of 256 agree"
            );
        }
    }
}

#[test]
fn the_spectrum_with_dp54_steps_equals_a_fine_rk4_spectrum() {
    // DP54 at 1e-9 over the state and four vectors against RK4 at a tenth of the step (its
    // error ~1e-12 per unit time): both close to the exact finite-time spectrum at 5 s, where
    // chaos amplifies errors by at most e^(3 x 5). Measured <= 1e-6 /s (f32 storage's ulp).
    let fine = LyapunovSpec {
        grid: Grid::square(12),
        stepping: Stepping {
            dt: 0.001,
            t_max: 5.0,
        },
        ..spec(Indicator::ExponentSum, 5.0)
    };
    let adaptive = LyapunovSpec {
        stepping: Stepping {
            dt: 0.01,
            t_max: 5.0,
        },
        integrator: Integrator::Dp54 {
            rtol: 1e-9,
            atol: 1e-9,
        },
        ..fine
    };
    let cpu = Engine::new(chaoscope::engine::Backend::Cpu).unwrap();
    let mut engines = vec![("cpu", cpu)];
    if let Some(ctx) = common::f64_gpu() {
        engines.push(("gpu f64", Engine::on_gpu(ctx)));
    }
    let quiet = Monitor::hidden();
    let reference = engines[0].1.spectrum(&fine, &quiet).unwrap();
    for (name, engine) in &engines {
        adaptive.validate().unwrap();
        let layers = engine.spectrum(&adaptive, &quiet).unwrap();
        for (k, (a, r)) in layers.iter().zip(&reference).enumerate() {
            let worst = a
                .data
                .iter()
                .zip(&r.data)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst < 1e-4,
                "{name}: exponent {} differs by {worst} /s",
                k + 1
            );
        }
    }
    // Every other indicator refuses it, naming the flag.
    let sali = LyapunovSpec {
        indicator: Indicator::Alignment {
            index: Alignment::Sali,
            threshold: 1e-8,
        },
        ..adaptive
    };
    assert!(matches!(
        sali.validate(),
        Err(chaoscope::Error::InvalidSpec {
            field: "integrator",
            ..
        })
    ));
}
