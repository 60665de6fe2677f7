//! Divergence maps: the FTLE by the tangent and twin methods on the CPU (f64), the Jacobian
//! against Liouville's theorem, and the GPU (f32, lavapipe in CI) against the CPU.

mod common;

use chaoscope::cpu;
use chaoscope::field::Field;
use chaoscope::gpu::{self, LyapunovKernel};
use chaoscope::model::{Params, State};
use chaoscope::monitor::Monitor;
use chaoscope::spec::{Grid, LyapunovSpec, Method, Stepping};

/// FTLE (1/s) above which a pixel counts as chaotic at t-max = 20 s. A regular
/// (quasi-periodic) orbit's tangent grows at most linearly, |v(t)| <= 1 + K t with K the
/// frequency shear (<~ 10 /s here), so its FTLE is <= ln(1 + K t) / t = 0.27 /s at 20 s;
/// chaotic pixels average ~1.1 /s.
const CHAOTIC: f32 = 0.5;

const CHAOTIC_STARTS: [(f64, f64); 4] = [
    (std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2),
    (2.0, 1.0),
    (3.0, 0.0),
    (1.0, -2.5),
];

fn spec(n: u32, t_max: f64, dt: f64, method: Method) -> LyapunovSpec {
    LyapunovSpec {
        params: Params::default(),
        grid: Grid::square(n),
        stepping: Stepping { dt, t_max },
        method,
        renorm: 0.1,
        use_symmetry: true,
        precision: chaoscope::spec::Precision::F32,
        band: None,
        integrator: chaoscope::spec::Integrator::Rk4,
        indicator: chaoscope::spec::Indicator::Ftle,
    }
}

/// ln det M(q) up to a constant: det M = m2 l1^2 l2^2 (m1 + m2 sin^2 (theta1 - theta2)).
fn log_det_mass(p: &Params, s: &State) -> f64 {
    (p.m1 + p.m2 * (s.theta1 - s.theta2).sin().powi(2)).ln()
}

#[test]
fn tangent_and_twin_methods_agree_on_chaotic_starts() {
    for (a, b) in CHAOTIC_STARTS {
        let start = State::at_rest(a, b);
        let tangent = cpu::ftle(&spec(4, 20.0, 0.01, Method::Tangent), start).last();
        let twin = cpu::ftle(&spec(4, 20.0, 0.01, Method::Twin { eps: 1e-8 }), start).last();
        assert!(
            tangent > 0.5,
            "({a}, {b}) should be chaotic, FTLE {tangent}"
        );
        // The twin differs by its nonlinearity (eps e^(lambda tau) ~ 1e-8 relative per
        // renormalisation) and by f64 cancellation in the 1e-8 separation (1e-16 / 1e-8);
        // over 200 renormalisations that is <~ 1e-5 relative (measured <= 4e-6).
        assert!(
            (tangent - twin).abs() <= 1e-4 * tangent,
            "({a}, {b}): tangent {tangent}, twin {twin}"
        );
    }
}

#[test]
fn the_tangent_result_does_not_depend_on_the_renormalisation_interval() {
    // The tangent equations are linear, so renormalising only rescales: same result up to
    // round-off, whatever the interval.
    let start = State::at_rest(2.0, 1.0);
    let often = cpu::ftle(&spec(4, 20.0, 0.01, Method::Tangent), start).last();
    let rarely = cpu::ftle(
        &LyapunovSpec {
            renorm: 2.0,
            ..spec(4, 20.0, 0.01, Method::Tangent)
        },
        start,
    );
    assert_eq!(rarely.t.len(), 10);
    assert!(
        (often - rarely.last()).abs() < 1e-9,
        "{often} vs {}",
        rarely.last()
    );
}

#[test]
fn small_angle_ftle_goes_to_zero() {
    for (a, b) in [(0.1, 0.1), (0.2, -0.15), (-0.3, 0.1)] {
        let start = State::at_rest(a, b);
        let at = |t| cpu::ftle(&spec(4, t, 0.01, Method::Tangent), start).last();
        let (short, long) = (at(10.0), at(100.0));
        // Regular motion: |v| grows at most linearly, so FTLE <= ln(1 + K t) / t -> 0; at
        // 100 s with K <~ 1 /s for these small oscillations that is <= 0.046 /s.
        assert!(long.abs() < 0.046, "({a}, {b}): FTLE(100 s) = {long}");
        assert!(long.abs() < short.abs(), "({a}, {b}): {short} -> {long}");
    }
}

#[test]
fn jacobian_trace_is_liouvilles_volume_change() {
    // In canonical coordinates (q, p) the flow keeps phase volume (trace 0). In (theta, omega)
    // the volume element carries det M(q), so trace J = -d/dt ln det M(q) exactly.
    let mut rng = fastrand::Rng::with_seed(3);
    for _ in 0..1000 {
        let p = Params {
            m1: 0.1 + 3.0 * rng.f64(),
            m2: 0.1 + 3.0 * rng.f64(),
            l1: 0.1 + 3.0 * rng.f64(),
            l2: 0.1 + 3.0 * rng.f64(),
            g: 1.0 + 20.0 * rng.f64(),
            ..Default::default()
        };
        let s = State {
            theta1: 10.0 * (rng.f64() - 0.5),
            omega1: 20.0 * (rng.f64() - 0.5),
            theta2: 10.0 * (rng.f64() - 0.5),
            omega2: 20.0 * (rng.f64() - 0.5),
        };
        let j = cpu::jacobian(&p, &s);
        let d = s.theta1 - s.theta2;
        let expected = -2.0 * p.m2 * d.sin() * d.cos() * (s.omega1 - s.omega2)
            / (p.m1 + p.m2 * d.sin().powi(2));
        let scale = 1.0 + j.abs().max();
        assert!(
            (j.trace() - expected).abs() < 1e-12 * scale,
            "trace {} vs {expected} at {s:?}",
            j.trace()
        );
    }
}

#[test]
fn the_four_exponents_sum_to_the_volume_change_and_so_to_zero() {
    let p = Params::default();
    for (a, b) in CHAOTIC_STARTS {
        let start = State::at_rest(a, b);
        let t = 20.0;
        let s = spec(4, t, 0.01, Method::Tangent);
        let sum: f64 = cpu::lyapunov_spectrum(&s, start).iter().sum();
        let end = *cpu::trajectory(&p, start, 0.01, s.stepping.steps())
            .last()
            .unwrap();
        let volume = log_det_mass(&p, &start) - log_det_mass(&p, &end);
        // RK4 keeps volume only up to its truncation error: measured <= 2e-4 over 20 s at
        // dt = 0.01, and 20-30x less at dt = 0.005 (the O(dt^4) of the method).
        assert!(
            (sum * t - volume).abs() < 1e-3,
            "({a}, {b}): sum x t = {}, ln det M ratio = {volume}",
            sum * t
        );
        // det M lies between m2 l1^2 l2^2 m1 and that times (1 + m2 / m1): the sum of the
        // exponents is bounded by ln 2 / t, i.e. it goes to zero.
        assert!(sum.abs() < 2f64.ln() / t + 1e-3 / t, "sum {sum}");
    }
}

#[test]
fn gpu_jacobian_matches_the_cpu_at_random_states() {
    let Some(ctx) = common::gpu() else { return };
    let p = Params {
        m1: 1.3,
        m2: 0.7,
        l1: 0.9,
        l2: 1.2,
        g: 9.81,
        ..Default::default()
    };
    let mut rng = fastrand::Rng::with_seed(11);
    let states: Vec<State> = (0..500)
        .map(|_| State {
            theta1: 6.0 * (rng.f64() - 0.5),
            omega1: 16.0 * (rng.f64() - 0.5),
            theta2: 6.0 * (rng.f64() - 0.5),
            omega2: 16.0 * (rng.f64() - 0.5),
        })
        .collect();
    common::check_jacobians(&ctx, &p, &states);
}

fn gpu_map(ctx: &gpu::GpuContext, s: &LyapunovSpec) -> Field {
    LyapunovKernel::new(ctx, s.method)
        .run(ctx, s, &Monitor::hidden())
        .unwrap()
}

/// Pixels whose 3x3 neighbourhood on the reference map is all clearly regular.
fn regular_mask(reference: &Field, below: f32) -> Vec<bool> {
    let (w, h) = (reference.width as i64, reference.height as i64);
    let mut mask = vec![true; reference.data.len()];
    for row in 0..h {
        for col in 0..w {
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let (r, c) = ((row + dr).clamp(0, h - 1), (col + dc).clamp(0, w - 1));
                    if reference.get(c as u32, r as u32) >= below {
                        mask[(row * w + col) as usize] = false;
                    }
                }
            }
        }
    }
    mask
}

fn quantile(values: &mut [f32], q: f64) -> f32 {
    values.sort_by(f32::total_cmp);
    values[((values.len() - 1) as f64 * q).round() as usize]
}

#[test]
fn gpu_and_cpu_ftle_maps_agree() {
    let Some(ctx) = common::gpu() else { return };
    let s = spec(128, 20.0, 0.01, Method::Tangent);
    let g = gpu_map(&ctx, &s);
    let c = cpu::ftle_map(&s, &Monitor::hidden()).unwrap();

    let same_class = g
        .data
        .iter()
        .zip(&c.data)
        .filter(|(a, b)| (**a > CHAOTIC) == (**b > CHAOTIC))
        .count() as f64
        / c.data.len() as f64;
    assert!(same_class >= 0.97, "classification agrees on {same_class}");

    // Regular region: f32 round-off grows only linearly there (~1e-7 per step, 2000 steps),
    // so the log stretch over 20 s agrees to ~1e-4 /s (measured 1.8e-4).
    let mask = regular_mask(&c, 0.2);
    let regular: Vec<f32> = g
        .data
        .iter()
        .zip(&c.data)
        .zip(&mask)
        .filter(|(_, m)| **m)
        .map(|((a, b), _)| (a - b).abs())
        .collect();
    assert!(regular.len() > 2000, "{} regular pixels", regular.len());
    let worst = regular.iter().copied().fold(0.0, f32::max);
    eprintln!("regular: {} px, worst |gpu - cpu| {worst}", regular.len());
    assert!(worst < 1e-3, "worst regular difference {worst} /s");

    // Chaotic region: trajectories part after a few Lyapunov times, so compare distributions.
    let (mut gc, mut cc): (Vec<f32>, Vec<f32>) = g
        .data
        .iter()
        .zip(&c.data)
        .filter(|(_, b)| **b > CHAOTIC)
        .map(|(a, b)| (*a, *b))
        .unzip();
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    let (mg, mc) = (mean(&gc), mean(&cc));
    eprintln!("chaotic: {} px, mean gpu {mg} cpu {mc}", cc.len());
    // Means over ~10 000 pixels of a spread of ~0.3 /s: sampling noise is ~0.003 /s.
    assert!(
        (mg - mc).abs() < 0.02 * mc,
        "chaotic means gpu {mg} cpu {mc}"
    );
    for q in [0.1, 0.5, 0.9] {
        let (a, b) = (quantile(&mut gc, q), quantile(&mut cc, q));
        assert!((a - b).abs() < 0.05, "quantile {q}: gpu {a} cpu {b}");
    }
}

#[test]
fn f32_exponents_do_not_saturate_over_50_s() {
    let Some(ctx) = common::gpu() else { return };
    let s = spec(64, 50.0, 0.01, Method::Tangent);
    let g = gpu_map(&ctx, &s);
    let c = cpu::ftle_map(&s, &Monitor::hidden()).unwrap();
    let pairs: Vec<(f64, f64)> = g
        .data
        .iter()
        .zip(&c.data)
        .filter(|(_, b)| **b > CHAOTIC)
        .map(|(a, b)| (*a as f64, *b as f64))
        .collect();
    assert!(pairs.len() > 1000, "{} chaotic pixels", pairs.len());
    let mg = pairs.iter().map(|p| p.0).sum::<f64>() / pairs.len() as f64;
    let mc = pairs.iter().map(|p| p.1).sum::<f64>() / pairs.len() as f64;
    eprintln!("50 s: {} chaotic px, mean gpu {mg} cpu {mc}", pairs.len());
    // The bound: on average within 10 %. A tangent vector saturating f32 (or a twin
    // lost in round-off) would drag the mean far down.
    assert!((mg - mc).abs() < 0.1 * mc, "gpu {mg} vs cpu {mc}");
}

#[test]
fn tiled_lyapunov_map_equals_untiled() {
    let Some(ctx) = common::gpu() else { return };
    let s = spec(48, 5.0, 0.01, Method::Tangent);
    let kernel = LyapunovKernel::new(&ctx, s.method);
    let whole = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
    let tiled = kernel.run_tiled(&ctx, &s, &Monitor::hidden(), 100).unwrap();
    assert_eq!(whole.data, tiled.data);
}

#[test]
fn gpu_twin_method_runs_and_is_coarser_than_tangent_in_f32() {
    let Some(ctx) = common::gpu() else { return };
    let tangent = gpu_map(&ctx, &spec(32, 20.0, 0.01, Method::Tangent));
    let twin = gpu_map(&ctx, &spec(32, 20.0, 0.01, Method::Twin { eps: 1e-3 }));
    // A 1e-3 twin is resolvable in f32 and sees the same chaos: the classes mostly agree.
    let same = tangent
        .data
        .iter()
        .zip(&twin.data)
        .filter(|(a, b)| (**a > CHAOTIC) == (**b > CHAOTIC))
        .count() as f64
        / tangent.data.len() as f64;
    assert!(same > 0.9, "tangent and 1e-3 twin classify alike on {same}");
}

#[test]
fn tangent_maps_are_point_symmetric_bit_for_bit_and_the_mirrored_half_equals_them() {
    // The Jacobian of the odd vector field is even, so the tangent vector (the same start on
    // both) evolves identically along mirrored trajectories; the f32 and f64 arithmetic is
    // sign-symmetric, so this holds exactly, not to a tolerance.
    let mut s = spec(40, 4.0, 0.01, Method::Tangent);
    s.grid.height = 27;
    let mut every = s;
    every.use_symmetry = false;
    let cpu_half = cpu::ftle_map(&s, &Monitor::hidden()).unwrap();
    let cpu_full = cpu::ftle_map(&every, &Monitor::hidden()).unwrap();
    let mut maps = vec![("cpu", cpu_half, cpu_full)];
    if let Some(ctx) = common::gpu() {
        let kernel = LyapunovKernel::new(&ctx, Method::Tangent);
        let half = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
        let full = kernel.run(&ctx, &every, &Monitor::hidden()).unwrap();
        maps.push(("gpu", half, full));
    }
    for (path, half, full) in maps {
        common::check_mirror(&full, &half, path);
    }
    // Twins are not mirror images of each other's twins: never mirrored.
    let twin = spec(40, 4.0, 0.01, Method::Twin { eps: 1e-8 });
    assert_eq!(twin.rows_to_integrate(), 40);
}

/// The tangent method with DP54 steps (`--integrator dp54`): the GPU's f64 map against the
/// CPU twin at the same tolerance, both against converged RK4, and the point symmetry.
#[test]
fn adaptive_tangent_maps_match_the_cpu_and_converged_rk4() {
    use chaoscope::spec::{Integrator, Precision};
    let Some(ctx) = common::f64_gpu() else { return };
    let adaptive = |rtol: f64, precision: Precision| LyapunovSpec {
        integrator: Integrator::Dp54 { rtol, atol: rtol },
        precision,
        ..spec(16, 3.0, 0.1, Method::Tangent)
    };
    let s = adaptive(1e-10, Precision::F64);
    let kernel = LyapunovKernel::with_precision(&ctx, Method::Tangent, Precision::F64);
    let gpu = kernel.run(&ctx, &s, &Monitor::hidden()).unwrap();
    let cpu = cpu::ftle_map(&s, &Monitor::hidden()).unwrap();
    let rk4 = cpu::ftle_map(&spec(16, 3.0, 0.001, Method::Tangent), &Monitor::hidden()).unwrap();
    let worst = |a: &Field, b: &Field| {
        a.data
            .iter()
            .zip(&b.data)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max)
    };
    let (gpu_cpu, cpu_rk4) = (worst(&gpu, &cpu), worst(&cpu, &rk4));
    eprintln!("adaptive FTLE over 3 s: gpu vs cpu {gpu_cpu:e}, cpu vs rk4 dt 1e-3 {cpu_rk4:e}");
    // Over 3 s the tangent grows by at most e^(2.3 * 3) ~ 1e3: local errors of ~1e-10
    // (the tolerance; the GPU's cos/sin carried outside the error control) reach ~1e-7 in
    // the log sum, 3e-8 /s; RK4 at dt 1e-3 is converged to ~1e-9 relative. What remains is
    // the f32 storage of the exponent (ulp 2.4e-7 at 2 /s): measured 1.2e-7 both.
    assert!(gpu_cpu <= 1e-6, "gpu vs cpu {gpu_cpu:e} /s");
    assert!(cpu_rk4 <= 1e-6, "cpu vs rk4 {cpu_rk4:e} /s");
    // The symmetry holds bit for bit with adaptive steps too (each mirrored pixel takes
    // the same steps).
    let every = LyapunovSpec {
        use_symmetry: false,
        ..s
    };
    let full = kernel.run(&ctx, &every, &Monitor::hidden()).unwrap();
    common::check_mirror(&full, &gpu, "gpu f64 dp54");
    // With rods and every loss (the same dual-number rate as RK4's).
    let lossy = LyapunovSpec {
        params: common::rods_and_every_loss(),
        ..s
    };
    let lossy_gap = worst(
        &kernel.run(&ctx, &lossy, &Monitor::hidden()).unwrap(),
        &cpu::ftle_map(&lossy, &Monitor::hidden()).unwrap(),
    );
    eprintln!("with every loss: gpu vs cpu {lossy_gap:e}");
    // As without losses, the f32 storage's ulps (measured 2.4e-7); the friction's turns near
    // zero speed could cost the error control more (the flip maps allow 5e4 rtol), so a
    // few ulps.
    assert!(lossy_gap <= 1e-6, "every loss: gpu vs cpu {lossy_gap:e} /s");
    // f32 at its tightest tolerance runs and stays near the f64 map (local errors of 1e-5
    // grown ~1e3-fold over 3 s, in the log: ~3e-3 /s; measured 4.5e-3).
    let f32_map = LyapunovKernel::new(&ctx, Method::Tangent)
        .run(&ctx, &adaptive(1e-5, Precision::F32), &Monitor::hidden())
        .unwrap();
    let f32_err = worst(&f32_map, &gpu);
    eprintln!("f32 dp54 1e-5 vs f64: {f32_err:e}");
    assert!(f32_err <= 1e-2, "f32 {f32_err:e} /s");
}

#[test]
fn adaptive_divergence_flags() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.png");
    let run = |args: &[&str]| {
        common::chaoscope()
            .args(["lyapunov", "--size", "8", "--t-max", "1", "--output"])
            .arg(&out)
            .args(args)
            .output()
            .unwrap()
    };
    for (args, flag) in [
        (
            &["--integrator", "dp54", "--method", "twin"][..],
            "--integrator",
        ),
        (&["--rtol", "1e-6"][..], "--rtol"),
        (&["--integrator", "dop853"][..], "--integrator"),
    ] {
        let o = run(args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(flag), "{args:?}: {stderr}");
    }
    let o = run(&["--integrator", "dp54", "--backend", "cpu", "--rtol", "1e-8"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let command = common::png_text(&out, "chaoscope:command");
    assert!(
        command.contains("--integrator dp54 --rtol 0.00000001 --atol 0.00000001"),
        "{command}"
    );
}

/// Adaptive window runs whose attempts in one dispatch pass lavapipe's loop limit (it ends
/// all of an invocation's loops after 65,535 iterations, silently): at dt 0.1 a window is one
/// step, so a dispatch holds up to 5,461 windows, and at rtol 1e-12 each takes ~20 attempts,
/// ~10^5 a dispatch. A pixel stops at the attempt budget and goes on from there in the next
/// dispatch, so the GPU's exponents equal the CPU's. Compared where the orbit is regular
/// (the CPU's FTLE below 0.1 /s over 100 s): there errors grow linearly, so both sit within
/// the f32 storage's ulps (5e-9 at 0.05 /s) plus round-off of 1e-12 per step, far below the
/// 3e-3 /s a window skipped in every dispatch cost (measured before the budget).
#[test]
fn adaptive_windows_past_the_loop_limit_match_the_cpu() {
    use chaoscope::engine::{Backend, Engine};
    use chaoscope::spec::{Integrator, Precision};
    let Some(ctx) = common::f64_gpu() else { return };
    let s = LyapunovSpec {
        integrator: Integrator::Dp54 {
            rtol: 1e-12,
            atol: 1e-12,
        },
        precision: Precision::F64,
        ..spec(8, 100.0, 0.1, Method::Tangent)
    };
    let spectrum = LyapunovSpec {
        indicator: chaoscope::spec::Indicator::Exponent(1),
        ..s
    };
    let (gpu, cpu) = (Engine::on_gpu(ctx), Engine::new(Backend::Cpu).unwrap());
    let quiet = Monitor::hidden();
    let pairs = [
        (
            "ftle",
            gpu.map(&s, &quiet).unwrap(),
            cpu.map(&s, &quiet).unwrap(),
        ),
        (
            "largest exponent",
            gpu.spectrum(&spectrum, &quiet).unwrap()[0].clone(),
            cpu.spectrum(&spectrum, &quiet).unwrap()[0].clone(),
        ),
    ];
    for (name, g, c) in pairs {
        let regular: Vec<(f32, f32)> = g
            .data
            .iter()
            .zip(&c.data)
            .filter(|(_, c)| c.abs() < 0.1)
            .map(|(g, c)| (*g, *c))
            .collect();
        let worst = regular
            .iter()
            .map(|(g, c)| (g - c).abs())
            .fold(0.0f32, f32::max);
        eprintln!(
            "{name}: {} regular pixels, gpu vs cpu {worst:e} /s",
            regular.len()
        );
        assert!(regular.len() >= 8, "{name}: only {} regular", regular.len());
        assert!(worst <= 1e-5, "{name}: gpu vs cpu {worst:e} /s");
    }
}
