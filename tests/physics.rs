//! The physics against independent references: the report's closed form, energy
//! conservation, small-angle normal modes, symmetry, the energetic no-flip region.

use std::f64::consts::PI;

use chaoscope::cpu::{self, accelerations, flip_time, rk4_step};
use chaoscope::model::{Params, State};
use chaoscope::spec::Stepping;

fn random_params(rng: &mut fastrand::Rng) -> Params {
    Params {
        m1: 0.1 + 5.0 * rng.f64(),
        m2: 0.1 + 5.0 * rng.f64(),
        l1: 0.1 + 3.0 * rng.f64(),
        l2: 0.1 + 3.0 * rng.f64(),
        g: 1.0 + 20.0 * rng.f64(),
        ..Default::default()
    }
}

fn random_state(rng: &mut fastrand::Rng) -> State {
    State {
        theta1: (rng.f64() - 0.5) * 4.0 * PI,
        omega1: (rng.f64() - 0.5) * 20.0,
        theta2: (rng.f64() - 0.5) * 4.0 * PI,
        omega2: (rng.f64() - 0.5) * 20.0,
    }
}

#[test]
fn closed_form_equals_mass_matrix_solve() {
    let mut rng = fastrand::Rng::with_seed(7);
    for i in 0..10_000 {
        let p = random_params(&mut rng);
        let s = random_state(&mut rng);
        let (a1, a2) = accelerations(&p, &s);
        let (b1, b2) = p.accelerations_closed_form(&s);
        // Two f64 evaluations of the same quantity: round-off of a few dozen operations on
        // terms as large as the largest term.
        let scale =
            1.0 + a1.abs().max(a2.abs()) + p.g / p.l1.min(p.l2) * (1.0 + p.m2 / p.m1) + 400.0;
        let tol = 1e-12 * scale;
        assert!(
            (a1 - b1).abs() < tol && (a2 - b2).abs() < tol,
            "case {i}: {p:?} {s:?}: solve ({a1}, {a2}) vs closed form ({b1}, {b2}), tol {tol}"
        );
    }
}

/// Largest relative energy error over `t` seconds from `start` with step `dt`.
fn energy_drift(p: &Params, start: State, dt: f64, t: f64) -> f64 {
    let e0 = p.energy(&start);
    let mut y = start;
    let mut worst: f64 = 0.0;
    for _ in 0..(t / dt).round() as u32 {
        y = rk4_step(p, &y, dt);
        worst = worst.max((p.energy(&y) - e0).abs());
    }
    worst / p.energy_scale()
}

#[test]
fn rk4_energy_error_shrinks_like_dt_to_the_fourth() {
    let p = Params::default();
    // A regular (non-chaotic) start, so the error is the integrator's and not amplified.
    let start = State::at_rest(0.5, 0.3);
    let errors: Vec<f64> = [0.01, 0.005, 0.0025]
        .iter()
        .map(|&dt| energy_drift(&p, start, dt, 50.0))
        .collect();
    for pair in errors.windows(2) {
        let order = (pair[0] / pair[1]).log2();
        // RK4 is fourth order: halving dt divides the error by at least 2^4 (3.7 leaves room
        // for higher-order terms). On this regular orbit the dt^4 term of the energy error
        // averages out and the measured order is 5.0; above 5.5 the errors would be round-off.
        assert!(
            (3.7..5.5).contains(&order),
            "energy error order {order:.2} from {errors:?}"
        );
    }
    // The default step keeps the energy to 1e-7 of its scale over 50 s on a regular orbit.
    assert!(
        errors[0] < 1e-7,
        "relative energy error {:e} at dt 0.01",
        errors[0]
    );
}

/// Angular frequency of theta1 from the mean spacing of its upward zero crossings.
fn measured_frequency(p: &Params, start: State, dt: f64, t: f64) -> f64 {
    let traj = cpu::trajectory(p, start, dt, (t / dt) as u32);
    let mut crossings = Vec::new();
    for (k, w) in traj.windows(2).enumerate() {
        if w[0].theta1 < 0.0 && w[1].theta1 >= 0.0 {
            let s = -w[0].theta1 / (w[1].theta1 - w[0].theta1);
            crossings.push((k as f64 + s) * dt);
        }
    }
    assert!(crossings.len() > 5, "too few oscillations");
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    2.0 * PI / period
}

#[test]
fn small_angle_normal_modes_match_the_analytic_frequencies() {
    let p = Params::default();
    let (slow, fast) = p.normal_modes_squared();
    let sqrt2 = 2f64.sqrt();
    // Equal masses and lengths: omega^2 = (2 -+ sqrt 2) g / l.
    assert!(
        (slow - (2.0 - sqrt2) * p.g).abs() < 1e-12 && (fast - (2.0 + sqrt2) * p.g).abs() < 1e-12
    );
    // The modes' shapes for equal arms: theta2 = +-sqrt 2 theta1. Released in one mode, the
    // pendulum oscillates at that mode's frequency alone.
    let amp = 1e-4;
    for (shape, w2) in [(sqrt2, slow), (-sqrt2, fast)] {
        let got = measured_frequency(&p, State::at_rest(amp, shape * amp), 0.001, 30.0);
        let want = w2.sqrt();
        // Amplitude 1e-4 rad shifts the frequency by O(amp^2) = 1e-8; crossings are located
        // to O(dt^2) by linear interpolation, averaged over many periods: 1e-6 relative.
        assert!(
            (got / want - 1.0).abs() < 1e-5,
            "mode {shape}: measured {got}, analytic {want}"
        );
    }
    // Unequal arms: the numbers from the quadratic are the eigenvalues of M^-1 K.
    let q = Params {
        m1: 2.0,
        m2: 0.5,
        l1: 1.5,
        l2: 0.7,
        g: 9.81,
        ..Default::default()
    };
    let (s, f) = q.normal_modes_squared();
    let m = q.m1 + q.m2;
    let det = m * q.m2 * q.l1 * q.l1 * q.l2 * q.l2 - (q.m2 * q.l1 * q.l2).powi(2);
    let trace = (q.m2 * q.l2 * q.l2 * m * q.g * q.l1 + m * q.l1 * q.l1 * q.m2 * q.g * q.l2) / det;
    assert!(((s + f) / trace - 1.0).abs() < 1e-12, "sum of eigenvalues");
    assert!(s > 0.0 && f > s);
    let got = measured_frequency(&q, State::at_rest(1e-4, 0.0), 0.001, 60.0);
    // A generic start mixes both modes, so theta1 crossings are not periodic; check instead
    // that the mixture's crossings lie between the two frequencies.
    assert!(
        got > s.sqrt() * 0.99 && got < f.sqrt() * 1.01,
        "{got} outside [{}, {}]",
        s.sqrt(),
        f.sqrt()
    );
}

#[test]
fn mirrored_starts_flip_at_the_same_time() {
    // The equations are odd in the state, and sin, the solve and RK4 keep that exactly in
    // floating point, so theta -> -theta gives bit-identical flip times, chaos or not.
    let mut rng = fastrand::Rng::with_seed(3);
    let p = Params::default();
    let stepping = Stepping {
        dt: 0.01,
        t_max: 20.0,
    };
    let mut flipped = 0;
    for _ in 0..200 {
        let s = State::at_rest((rng.f64() - 0.5) * 2.0 * PI, (rng.f64() - 0.5) * 2.0 * PI);
        let m = State::at_rest(-s.theta1, -s.theta2);
        let (a, b) = (
            flip_time(&p, s, &stepping, true),
            flip_time(&p, m, &stepping, true),
        );
        assert_eq!(a.to_bits(), b.to_bits(), "{s:?}: {a} vs mirrored {b}");
        flipped += a.is_finite() as u32;
    }
    assert!(
        flipped > 50,
        "the sample should contain flipping starts, got {flipped}"
    );
}

#[test]
fn no_flip_threshold_is_where_an_arm_can_just_reach_the_top() {
    // Independent check of E*: the least potential energy over a fine sampling of the two
    // "flipped" circles theta1 = pi and theta2 = pi.
    let mut rng = fastrand::Rng::with_seed(11);
    for _ in 0..50 {
        let p = random_params(&mut rng);
        let least = (0..=10_000)
            .map(|i| -PI + 2.0 * PI * i as f64 / 10_000.0)
            .map(|a| p.potential_energy(PI, a).min(p.potential_energy(a, PI)))
            .fold(f64::INFINITY, f64::min);
        assert!(
            (least - p.flip_energy()).abs() < 1e-9 * p.energy_scale(),
            "{p:?}: {least} vs {}",
            p.flip_energy()
        );
    }
}
