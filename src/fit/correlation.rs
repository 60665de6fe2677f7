//! How a camera's tracking errors are correlated from frame to frame, measured on the rigid
//! rods: what widens a window fit's covariance ([`super::window::fit_window`]).

/// The tracking errors' correlation from one row to the next, measured on the rigid rods.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Correlation {
    /// The rods' length residuals' RMS (m): the tracking error along them, a coordinate's
    /// (the lower rod's divided by sqrt 2, its two ends' errors adding).
    pub rms: f64,
    /// The lag-one autocorrelation of the rods' length residuals.
    pub lag_one: f64,
    /// The lags summed (Andrews' rule for an AR(1) series, 1991).
    pub lags: usize,
    /// The long-run variance over the variance, 1 + 2 sum (1 - l/(L+1)) rho_l, at least 1:
    /// by how much correlated errors widen a least-squares covariance that took them for
    /// independent (exactly so for a mean, closely for smooth regressors).
    pub inflation: f64,
}

/// The correlation of the tracking errors along the whole of `data` (positions relative to
/// the pivot): each mass's distance from where its rigid rod holds it (|m1| - l1 and
/// |m2 - m1| - l2, both lengths their mean) is tracking error alone, whatever the motion.
/// It sees the errors along the rods; those across them (along the motion) are taken to
/// be alike.
pub fn rod_correlation(data: &[[f64; 4]]) -> Correlation {
    let series: [Vec<f64>; 2] = [
        data.iter().map(|d| d[0].hypot(d[1])).collect(),
        data.iter()
            .map(|d| (d[2] - d[0]).hypot(d[3] - d[1]))
            .collect(),
    ];
    let centred: Vec<Vec<f64>> = series
        .iter()
        .map(|s| {
            let s: Vec<f64> = s.iter().copied().filter(|x| x.is_finite()).collect();
            let mean = s.iter().sum::<f64>() / s.len().max(1) as f64;
            s.iter().map(|x| x - mean).collect()
        })
        .collect();
    let rms = {
        let square = |e: &Vec<f64>| e.iter().map(|x| x * x).sum::<f64>();
        ((square(&centred[0]) + square(&centred[1]) / 2.0)
            / (centred[0].len() + centred[1].len()).max(1) as f64)
            .sqrt()
    };
    let (lag_one, lags, inflation) = long_run(&centred);
    Correlation {
        rms,
        lag_one,
        lags,
        inflation,
    }
}

/// The lag-one autocorrelation of `centred` (series of residuals about their means, pooled),
/// the lags summed and the long-run variance over the variance (see [`Correlation`]); no
/// correlation (NaN, 0, 1) for series under 8 long.
pub fn long_run(centred: &[Vec<f64>]) -> (f64, usize, f64) {
    let rho = |l: usize| {
        let (mut lagged, mut square) = (0.0, 0.0);
        for e in centred {
            lagged += (l..e.len()).map(|i| e[i] * e[i - l]).sum::<f64>();
            square += e.iter().map(|x| x * x).sum::<f64>();
        }
        lagged / square.max(1e-300)
    };
    let n = centred.iter().map(Vec::len).min().unwrap_or(0);
    if n < 8 {
        return (f64::NAN, 0, 1.0);
    }
    let lag_one = rho(1).clamp(-0.97, 0.97);
    let alpha = 4.0 * lag_one.powi(2) / ((1.0 - lag_one).powi(2) * (1.0 + lag_one).powi(2));
    let lags = ((1.1447 * (alpha * n as f64).cbrt()).floor() as usize).min(n / 4);
    let sum: f64 = (1..=lags)
        .map(|l| (1.0 - l as f64 / (lags + 1) as f64) * rho(l))
        .sum();
    (lag_one, lags, (1.0 + 2.0 * sum).max(1.0))
}
