//! How fractal a basin boundary is: the uncertainty exponent (Grebogi, McDonald, Ott and Yorke
//! 1983). A start is eps-uncertain when a start eps away has another outcome; the fraction
//! f(eps) of uncertain starts scales as eps^alpha, and the boundary's box-counting dimension
//! in a plane is D = 2 - alpha (a smooth curve: alpha = 1, D = 1).
//!
//! The samples are pairs of starts ([`crate::spec::Sampling::Pairs`]); [`fit`] turns the
//! counts at several eps into alpha with its standard error.

/// The counts at one perturbation size.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Level {
    /// The perturbation, as a fraction of the plane's width or height.
    pub eps: f64,
    /// Pairs drawn.
    pub pairs: u64,
    /// Pairs whose both outcomes the numerics vouch for (the rest are left out).
    pub resolved: u64,
    /// Resolved pairs whose outcomes differ.
    pub uncertain: u64,
}

impl Level {
    /// f(eps): the uncertain share of the resolved pairs.
    pub fn fraction(&self) -> f64 {
        self.uncertain as f64 / self.resolved.max(1) as f64
    }

    /// Whether it has enough uncertain pairs for its log to be measured (a relative error of
    /// about 1 / sqrt(uncertain) <= 1/3).
    pub fn counts(&self) -> bool {
        self.uncertain >= MIN_UNCERTAIN && self.uncertain < self.resolved
    }
}

/// Levels with fewer uncertain pairs are left out of the fit.
pub const MIN_UNCERTAIN: u64 = 10;

/// alpha, its standard error, and what it was fitted on.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Fit {
    pub alpha: f64,
    pub alpha_se: f64,
    /// ln f = intercept + alpha ln eps.
    pub intercept: f64,
    /// The smallest and largest eps fitted.
    pub eps_range: (f64, f64),
    /// Levels fitted.
    pub levels: usize,
    /// chi^2 per degree of freedom of the fit (about 1 when f is a power law within the
    /// binomial noise; larger, and the standard error is widened by its root).
    pub reduced_chi2: f64,
}

impl Fit {
    /// The boundary's box-counting dimension in the plane, D = 2 - alpha.
    pub fn dimension(&self) -> f64 {
        2.0 - self.alpha
    }
}

/// Weighted least squares of ln f(eps) on ln eps over the levels that count
/// ([`Level::counts`]), each weighted by its binomial variance (by the delta method,
/// var ln f = (1 - f) / (n f)). The slope's standard error is the fit's, widened by
/// sqrt(reduced chi^2) where the points scatter more than their counts explain. None with
/// fewer than three levels.
pub fn fit(levels: &[Level]) -> Option<Fit> {
    let points: Vec<(f64, f64, f64)> = levels
        .iter()
        .filter(|l| l.counts())
        .map(|l| {
            let f = l.fraction();
            let var = (1.0 - f) / (l.resolved as f64 * f);
            (l.eps.ln(), f.ln(), 1.0 / var)
        })
        .collect();
    if points.len() < 3 {
        return None;
    }
    let sw: f64 = points.iter().map(|p| p.2).sum();
    let mx = points.iter().map(|p| p.2 * p.0).sum::<f64>() / sw;
    let my = points.iter().map(|p| p.2 * p.1).sum::<f64>() / sw;
    let sxx: f64 = points.iter().map(|p| p.2 * (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| p.2 * (p.0 - mx) * (p.1 - my)).sum();
    let alpha = sxy / sxx;
    let intercept = my - alpha * mx;
    let chi2: f64 = points
        .iter()
        .map(|p| p.2 * (p.1 - intercept - alpha * p.0).powi(2))
        .sum();
    let reduced_chi2 = chi2 / (points.len() - 2) as f64;
    let eps: Vec<f64> = points.iter().map(|p| p.0.exp()).collect();
    Some(Fit {
        alpha,
        alpha_se: (1.0 / sxx).sqrt() * reduced_chi2.max(1.0).sqrt(),
        intercept,
        eps_range: (
            eps.iter().copied().fold(f64::INFINITY, f64::min),
            eps.iter().copied().fold(0.0, f64::max),
        ),
        levels: points.len(),
        reduced_chi2,
    })
}

/// `levels` perturbation sizes spaced evenly in log from `min` to `max`.
pub fn eps_levels(min: f64, max: f64, levels: u32) -> Vec<f64> {
    let n = levels.max(2) - 1;
    (0..=n)
        .map(|k| (min.ln() + (max.ln() - min.ln()) * k as f64 / n as f64).exp())
        .collect()
}

/// The counts of one level from the outcomes of its pairs (`class[row]` of member 0 and 1,
/// None where the numerics do not vouch for it).
pub fn count(eps: f64, classes: &[[Option<u32>; 2]]) -> Level {
    let resolved: Vec<_> = classes
        .iter()
        .filter_map(|[a, b]| Some((a.as_ref()?, b.as_ref()?)))
        .collect();
    Level {
        eps,
        pairs: classes.len() as u64,
        resolved: resolved.len() as u64,
        uncertain: resolved.iter().filter(|(a, b)| a != b).count() as u64,
    }
}

/// The seed of level `k` of a run seeded `seed`: each level draws its own starts.
pub fn level_seed(seed: u32, k: u32) -> u32 {
    crate::spec::pcg(seed ^ crate::spec::pcg(k.wrapping_add(0x9e37_79b9)))
}
