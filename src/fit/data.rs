//! Tracked positions from a camera: reading them, finding the pivot and the arm lengths,
//! angles, velocities and energies with error bars (the lab report's analysis, section 3).

use nalgebra::{DMatrix, DVector};

use super::lsq::{Fit, least_squares};
use crate::error::{Error, Result};
pub use crate::track::file::{PixelScale, RELEASE, TrackedRow};
pub use crate::track::reader::{Units, read_frames};

/// The pivot from a least-squares circle through the upper-mass positions: an algebraic
/// (Kasa) fit to start, then the geometric fit of |p - c| - r, with standard errors.
pub struct Pivot {
    pub x: f64,
    pub y: f64,
    pub radius: f64,
    pub errors: [f64; 3],
    pub rms_residual: f64,
}

pub fn fit_pivot(frames: &[TrackedRow]) -> Result<Pivot> {
    let n = frames.len();
    // x^2 + y^2 + D x + E y + F = 0, linear in (D, E, F).
    let a = DMatrix::from_fn(n, 3, |i, j| match j {
        0 => frames[i].x1,
        1 => frames[i].y1,
        _ => 1.0,
    });
    let b = DVector::from_fn(n, |i, _| -(frames[i].x1.powi(2) + frames[i].y1.powi(2)));
    let sol = a
        .svd(true, true)
        .solve(&b, 1e-12)
        .map_err(|e| Error::invalid("file", format!("circle fit: {e}")))?;
    let (cx, cy) = (-sol[0] / 2.0, -sol[1] / 2.0);
    let r = (cx * cx + cy * cy - sol[2]).max(0.0).sqrt();
    let residuals = |p: &DVector<f64>| {
        let r = DVector::from_fn(n, |i, _| {
            ((frames[i].x1 - p[0]).powi(2) + (frames[i].y1 - p[1]).powi(2)).sqrt() - p[2]
        });
        let j = DMatrix::from_fn(n, 3, |i, k| {
            let d = ((frames[i].x1 - p[0]).powi(2) + (frames[i].y1 - p[1]).powi(2)).sqrt();
            match k {
                0 => -(frames[i].x1 - p[0]) / d,
                1 => -(frames[i].y1 - p[1]) / d,
                _ => -1.0,
            }
        });
        (r, j)
    };
    let fit = least_squares(residuals, DVector::from_vec(vec![cx, cy, r]), 100);
    // The upper mass swings on an arc around the pivot: positions that span only a sliver of
    // a circle (or a line) give no pivot, only a far-away guess. Ask for an arc that the
    // radius does not dwarf: a bounding box whose diagonal is at least 1/20 of it.
    let (x, y) = (frames.iter().map(|f| f.x1), frames.iter().map(|f| f.y1));
    let extent = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        hi - lo
    };
    let spread = extent(&mut x.clone()).hypot(extent(&mut y.clone()));
    if !(fit.params[2].is_finite() && spread >= 0.05 * fit.params[2]) {
        return Err(Error::invalid(
            "file",
            format!(
                "the upper mass's positions span {spread:.3} m, too little of a circle (radius {:.3} m) to locate the pivot: they must swing through an arc",
                fit.params[2]
            ),
        ));
    }
    Ok(Pivot {
        x: fit.params[0],
        y: fit.params[1],
        radius: fit.params[2],
        errors: [fit.errors[0], fit.errors[1], fit.errors[2]],
        rms_residual: (fit.chi2 / n as f64).sqrt(),
    })
}

/// The report's method: the point of a grid (step `step` m, within `half` m of `around`)
/// whose distances to all upper-mass positions have the least variance.
pub fn grid_pivot(frames: &[TrackedRow], around: (f64, f64), half: f64, step: f64) -> (f64, f64) {
    let k = (half / step).round() as i64;
    let mut best = (f64::INFINITY, around);
    for i in -k..=k {
        for j in -k..=k {
            let (x, y) = (around.0 + i as f64 * step, around.1 + j as f64 * step);
            let d: Vec<f64> = frames
                .iter()
                .map(|f| ((f.x1 - x).powi(2) + (f.y1 - y).powi(2)).sqrt())
                .collect();
            let mean = d.iter().sum::<f64>() / d.len() as f64;
            let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / d.len() as f64;
            if var < best.0 {
                best = (var, (x, y));
            }
        }
    }
    best.1
}

/// Mean and its standard error, and the standard deviation.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Estimate {
    pub value: f64,
    pub error: f64,
    pub spread: f64,
}

pub fn estimate(values: &[f64]) -> Estimate {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    Estimate {
        value: mean,
        error: (var / n).sqrt(),
        spread: var.sqrt(),
    }
}

/// Arm lengths from the distances pivot - mass 1 and mass 1 - mass 2.
pub fn arm_lengths(frames: &[TrackedRow], pivot: (f64, f64)) -> (Estimate, Estimate) {
    let d1: Vec<f64> = frames
        .iter()
        .map(|f| ((f.x1 - pivot.0).powi(2) + (f.y1 - pivot.1).powi(2)).sqrt())
        .collect();
    let d2: Vec<f64> = frames
        .iter()
        .map(|f| ((f.x2 - f.x1).powi(2) + (f.y2 - f.y1).powi(2)).sqrt())
        .collect();
    (estimate(&d1), estimate(&d2))
}

/// Angles from the downward vertical (rad), unwrapped along the run.
pub fn angles(frames: &[TrackedRow], pivot: (f64, f64)) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(frames.len());
    for f in frames {
        let mut a = (
            (f.x1 - pivot.0).atan2(-(f.y1 - pivot.1)),
            (f.x2 - f.x1).atan2(-(f.y2 - f.y1)),
        );
        if let Some(prev) = out.last() {
            let unwrap = |x: f64, p: f64| {
                x + std::f64::consts::TAU * ((p - x) / std::f64::consts::TAU).round()
            };
            a = (unwrap(a.0, prev.0), unwrap(a.1, prev.1));
        }
        out.push(a);
    }
    out
}

/// Central differences (x(t+) - x(t-)) / (t+ - t-) at the interior rows, as the report.
pub fn central_differences(t: &[f64], x: &[f64]) -> Vec<f64> {
    let gap = gaps(t);
    (1..t.len() - 1)
        .map(|i| match gap(i) {
            true => f64::NAN,
            false => (x[i + 1] - x[i - 1]) / (t[i + 1] - t[i - 1]),
        })
        .collect()
}

/// Whether row `i` of the times `t` borders a gap: an interval over 1.5 times the rows'
/// usual one (a step Tracker left unmarked, a frame a tracker missed). No difference is
/// taken across one: a velocity there would average the motion over the gap, and the
/// energy from it be wrong by many of its errors (the rows' velocities are NaN there).
pub fn gaps(t: &[f64]) -> impl Fn(usize) -> bool + '_ {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let usual = crate::stats::median(&mut steps).unwrap_or(0.0);
    move |i: usize| {
        let long = |a: usize, b: usize| t[b] - t[a] > 1.5 * usual;
        (i > 0 && long(i - 1, i)) || (i + 1 < t.len() && long(i, i + 1))
    }
}

/// Energy (J) at the interior rows, zero with both masses hanging at rest, and its error
/// by propagation (the report's equation 23): dE = dv sqrt(m1^2 v1^2 + m2^2 v2^2).
pub struct Energies {
    pub t: Vec<f64>,
    pub e: Vec<f64>,
    pub de: Vec<f64>,
}

pub fn energies(
    frames: &[TrackedRow],
    pivot: (f64, f64),
    masses: (f64, f64),
    lengths: (f64, f64),
    g: f64,
    dv: f64,
) -> Energies {
    let t: Vec<f64> = frames.iter().map(|f| f.t).collect();
    let col = |f: fn(&TrackedRow) -> f64| -> Vec<f64> { frames.iter().map(f).collect() };
    let (vx1, vy1) = (
        central_differences(&t, &col(|f| f.x1)),
        central_differences(&t, &col(|f| f.y1)),
    );
    let (vx2, vy2) = (
        central_differences(&t, &col(|f| f.x2)),
        central_differences(&t, &col(|f| f.y2)),
    );
    let (m1, m2) = masses;
    let (l1, l2) = lengths;
    let mut out = Energies {
        t: Vec::new(),
        e: Vec::new(),
        de: Vec::new(),
    };
    for i in 1..frames.len() - 1 {
        let f = &frames[i];
        let (v1sq, v2sq) = (
            vx1[i - 1].powi(2) + vy1[i - 1].powi(2),
            vx2[i - 1].powi(2) + vy2[i - 1].powi(2),
        );
        let kinetic = 0.5 * m1 * v1sq + 0.5 * m2 * v2sq;
        let potential = g * (m1 * (f.y1 - pivot.1 + l1) + m2 * (f.y2 - pivot.1 + l1 + l2));
        out.t.push(f.t);
        out.e.push(kinetic + potential);
        out.de.push(dv * (m1 * m1 * v1sq + m2 * m2 * v2sq).sqrt());
    }
    out
}

/// The two decay laws of section 2.4, fitted to E(t) with weights 1/dE^2:
/// exponential E = a exp(b t) (viscous losses) and E = a (b t + d)^-2 (pure quadratic drag;
/// a, b, d are degenerate - only a/d^2 and b/d matter - so d is fixed at 1).
pub struct DecayFits {
    pub exponential: Fit,
    pub inverse_square: Fit,
}

pub fn fit_decay(en: &Energies) -> DecayFits {
    // Only the rows with an energy (none beside a gap in the rows).
    let keep: Vec<usize> = (0..en.t.len()).filter(|&i| en.e[i].is_finite()).collect();
    let en = &Energies {
        t: keep.iter().map(|&i| en.t[i]).collect(),
        e: keep.iter().map(|&i| en.e[i]).collect(),
        de: keep.iter().map(|&i| en.de[i]).collect(),
    };
    let n = en.t.len();
    // Errors of zero (a mass at rest at the bottom) would get infinite weight.
    let floor = en.de.iter().copied().fold(0.0, f64::max) * 0.05 + 1e-6;
    let sigma: Vec<f64> = en.de.iter().map(|d| d.max(floor)).collect();
    let e0 = en.e.iter().copied().fold(0.0, f64::max).max(1e-6);
    let exponential = least_squares(
        |p: &DVector<f64>| {
            let r = DVector::from_fn(n, |i, _| {
                (en.e[i] - p[0] * (p[1] * en.t[i]).exp()) / sigma[i]
            });
            let j = DMatrix::from_fn(n, 2, |i, k| {
                let ex = (p[1] * en.t[i]).exp();
                -(if k == 0 { ex } else { p[0] * en.t[i] * ex }) / sigma[i]
            });
            (r, j)
        },
        DVector::from_vec(vec![e0, -0.02]),
        200,
    );
    let inverse_square = least_squares(
        |p: &DVector<f64>| {
            let r = DVector::from_fn(n, |i, _| {
                (en.e[i] - p[0] * (p[1] * en.t[i] + 1.0).powi(-2)) / sigma[i]
            });
            let j = DMatrix::from_fn(n, 2, |i, k| {
                let u = p[1] * en.t[i] + 1.0;
                -(if k == 0 {
                    u.powi(-2)
                } else {
                    -2.0 * p[0] * en.t[i] * u.powi(-3)
                }) / sigma[i]
            });
            (r, j)
        },
        DVector::from_vec(vec![e0, 0.01]),
        200,
    );
    DecayFits {
        exponential,
        inverse_square,
    }
}
