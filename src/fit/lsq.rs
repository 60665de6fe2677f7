//! Nonlinear least squares (Levenberg-Marquardt) on our nalgebra. The levenberg-marquardt
//! crate pins an older nalgebra (a second copy to build), and the problems here have 2 to 6
//! parameters, so the 40 lines below do.

use nalgebra::{DMatrix, DVector};

/// A least-squares solution: parameters, their standard errors (scaled by the reduced chi^2,
/// as scipy's curve_fit does by default), chi^2 (sum of squared residuals) and degrees of
/// freedom.
#[derive(Clone, Debug)]
pub struct Fit {
    pub params: Vec<f64>,
    pub errors: Vec<f64>,
    pub chi2: f64,
    pub dof: usize,
    /// The parameters' covariance, s^2 (J^T J)^-1 with s^2 = chi^2/dof (None: J^T J singular).
    pub covariance: Option<DMatrix<f64>>,
}

impl Fit {
    pub fn reduced_chi2(&self) -> f64 {
        self.chi2 / self.dof.max(1) as f64
    }
}

/// Minimises |r(p)|^2 from `p0`; `model` returns the residuals and their Jacobian.
pub fn least_squares(
    model: impl Fn(&DVector<f64>) -> (DVector<f64>, DMatrix<f64>),
    p0: DVector<f64>,
    iterations: usize,
) -> Fit {
    let mut p = p0;
    let (mut r, mut j) = model(&p);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        let jt = j.transpose();
        let jtj = &jt * &j;
        let g = &jt * &r;
        let mut improved = false;
        for _ in 0..20 {
            let mut a = jtj.clone();
            for k in 0..a.nrows() {
                a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
            }
            let Some(step) = a.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let trial = &p + &step;
            let (rt, jt2) = model(&trial);
            let c = rt.norm_squared();
            if c.is_finite() && c < cost {
                let done = (cost - c) <= 1e-14 * cost.max(1e-300);
                p = trial;
                r = rt;
                j = jt2;
                cost = c;
                lambda = (lambda / 10.0).max(1e-12);
                improved = !done;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let dof = r.len().saturating_sub(p.len());
    let jtj = j.transpose() * &j;
    let scale = cost / dof.max(1) as f64;
    let covariance = jtj.try_inverse().map(|c| c * scale);
    let errors = match &covariance {
        Some(cov) => (0..p.len()).map(|k| cov[(k, k)].sqrt()).collect(),
        None => vec![f64::NAN; p.len()],
    };
    Fit {
        params: p.iter().copied().collect(),
        errors,
        chi2: cost,
        dof,
        covariance,
    }
}

/// Jacobian of `f` at `p` by central differences with steps `h` (for residuals that come
/// from a simulation).
pub fn numeric_jacobian(
    f: &impl Fn(&DVector<f64>) -> DVector<f64>,
    p: &DVector<f64>,
    h: &[f64],
) -> DMatrix<f64> {
    let r0 = f(p);
    let mut j = DMatrix::zeros(r0.len(), p.len());
    for k in 0..p.len() {
        let (mut a, mut b) = (p.clone(), p.clone());
        a[k] += h[k];
        b[k] -= h[k];
        let d = (f(&a) - f(&b)) / (2.0 * h[k]);
        j.set_column(k, &d);
    }
    j
}
