//! A forecast's members, drawn from a window fit's distribution.

use nalgebra::SymmetricEigen;
use rand::SeedableRng;
use rand_distr::{ChiSquared, Distribution, StandardNormal};
use rand_pcg::Pcg64;

use crate::fit::window::{PARAMETERS, WindowFit};
use crate::model::State;

/// A forecast's members: where each starts, its joint damping and its pivot.
pub struct Members {
    pub starts: Vec<State>,
    pub damping: Vec<(f64, f64)>,
    /// Where each puts the pivot in the data's frame (m): its positions move by it.
    pub pivots: Vec<(f64, f64)>,
    /// Members drawn with a negative damping, which took zero instead.
    pub clamped: usize,
}

/// Draws `n` members (state, joint damping and pivot) from the fit's distribution: the
/// multivariate t the covariance and the residuals' degrees of freedom give (the covariance's
/// scale is itself estimated from the window's residuals, so the fitted values are t
/// distributed about the truth, not normal; a few rows at 3 Hz leave 14 degrees of freedom,
/// whose 90 % interval is 7 % wider than the normal's). Correlated tracking errors carry
/// less information than their count: the degrees of freedom are divided by the same
/// inflation that widened the covariance. No measurement allows a joint that pushes: a damping drawn below zero takes zero, and the
/// member's other parameters move with it as the fit's covariance says they go together
/// (by their regression on the damping, Sigma_od Sigma_dd^-1), so that its state is one the
/// data allow with that damping (clamping alone would keep a state that only suits a
/// pushing joint). The members that did are counted. The scale and the lower arm are drawn
/// with the rest (their correlations widen the others' spread) but every member keeps the
/// fitted ones: the engine integrates members under one gravity and one pair of arms.
pub fn draw_members(fit: &WindowFit, n: usize, seed: u64) -> Members {
    let sigma = &fit.covariance;
    let eigen = SymmetricEigen::new(sigma.clone());
    // Sigma = V diag(l) V^T: a draw is the fit plus V sqrt(l) z (l < 0 from rounding: 0).
    let root = &eigen.eigenvectors
        * nalgebra::DMatrix::from_diagonal(&eigen.eigenvalues.map(|l| l.max(0.0).sqrt()));
    const DAMPING: [usize; 2] = [4, 5];
    let dd = nalgebra::Matrix2::from_fn(|i, j| sigma[(DAMPING[i], DAMPING[j])]);
    let regression = dd.try_inverse().map(|inverse| {
        nalgebra::DMatrix::from_fn(PARAMETERS, 2, |i, j| sigma[(i, DAMPING[j])]) * inverse
    });
    let fitted = nalgebra::DVector::from_row_slice(&fit.values);
    let freedom = effective_freedom(fit);
    let scatter = ChiSquared::new(freedom).expect("at least 3 degrees of freedom");
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut members = Members {
        starts: Vec::with_capacity(n),
        damping: Vec::with_capacity(n),
        pivots: Vec::with_capacity(n),
        clamped: 0,
    };
    for _ in 0..n {
        let z = nalgebra::DVector::from_fn(PARAMETERS, |_, _| StandardNormal.sample(&mut rng));
        // A t draw: a normal over the root of a chi-square over its degrees of freedom.
        let widen = (freedom / scatter.sample(&mut rng)).sqrt();
        let mut v = &fitted + &root * z * widen;
        let lift = nalgebra::Vector2::new((-v[4]).max(0.0), (-v[5]).max(0.0));
        if lift != nalgebra::Vector2::zeros() {
            members.clamped += 1;
            if let Some(k) = &regression {
                v += k * lift;
            }
            // Exactly zero where the regression left a rounding error below it.
            (v[4], v[5]) = (v[4].max(0.0), v[5].max(0.0));
        }
        members
            .starts
            .push(State::from_array([v[0], v[1], v[2], v[3]]));
        members.damping.push((v[4], v[5]));
        members.pivots.push((v[6], v[7]));
    }
    members
}

/// The degrees of freedom the fit's covariance carries: the residuals' over the inflation
/// that their correlation gave it, at least 3: the t's variance is infinite below 2, and a
/// thinner fit than that is too thin to draw members from at all (its heavy tails would
/// fill the bands with members that no window could have fitted).
pub fn effective_freedom(fit: &WindowFit) -> f64 {
    (fit.dof as f64 / fit.correlation.inflation.max(1.0)).max(3.0)
}
