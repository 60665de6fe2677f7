//! The identified moments refined on the angles themselves: the weak form
//! ([`super::identify`]) needs the angular velocities for its centripetal terms, and
//! velocities from noisy positions are biased where the film is coarse (at 30 frames a
//! second a and c came out beyond their errors in 4 of 10 seeded cases). Here the model is
//! run instead: the data are cut into pieces about the motion's own time long, each piece
//! gets its own state at its middle row, and all pieces share the six moments (a, b, c, q,
//! k1, k2). Levenberg-Marquardt on the arcs the markers stray by (l1 dtheta1, l2 dtheta2)
//! fits them all at once; the pieces' states are eliminated block by block (a Schur
//! complement), so a long recording costs no large matrix. No velocity is ever taken from
//! the data but as a start.

use std::ops::Range;

use crate::error::Result;
use crate::monitor::Monitor;

use nalgebra::{DMatrix, DVector, Matrix4, Vector4};

/// The moments' count: a, b, c, q, k1, k2 ([`super::identify::MOMENTS`]).
const M: usize = 6;

/// A piece's fewest rows: its four state values need several times as many residuals to be
/// pinned apart from the moments.
const PIECE_ROWS: usize = 10;

/// Integration steps per motion's own time: RK4's error per unit time goes as the fourth
/// power of the step, 1e-8 of the swing here, far below any camera's noise.
const STEPS_PER_TIME: f64 = 100.0;

/// A piece whose weighted RMS lies beyond this many robust deviations above the pieces'
/// median is left out (a knock, a lost marker), as the weak form leaves out its stretches.
const REJECT: f64 = 5.0;

/// The refined moments with their covariance, and how the pieces fitted.
pub struct Refined {
    pub values: [f64; M],
    pub covariance: DMatrix<f64>,
    pub refinement: Refinement,
}

/// How the refinement went: its pieces, those left out, and the RMS of the upper and lower
/// markers' arcs off the model (in the data's lengths).
#[derive(Clone, Copy, Debug)]
pub struct Refinement {
    /// The pieces run on, and of how many the recording holds (a long recording's pieces
    /// are thinned to [`MOST_PIECES`], evenly).
    pub pieces: usize,
    pub of: usize,
    pub rejected: usize,
    pub rms: [f64; 2],
}

/// The data the refinement runs on: times, unwrapped angles, angular velocities (a start
/// only), the markers' radii and the motion's own time (s).
pub struct Motion<'a> {
    pub t: &'a [f64],
    pub theta: [&'a [f64]; 2],
    pub omega: [&'a [f64]; 2],
    pub radii: [f64; 2],
    pub natural: f64,
}

/// The angular accelerations of the moments' model at `s` = (theta1, theta2, omega1,
/// omega2): d/dt(a w1 + c w2 cos D) + c w1 w2 sin D + sin th1 + k1 w1 - k2 (w2 - w1) = 0 and
/// d/dt(b w2 + c w1 cos D) - c w1 w2 sin D + q sin th2 + k2 (w2 - w1) = 0, D = th1 - th2.
fn rates(m: &[f64; M], s: &Vector4<f64>) -> Vector4<f64> {
    let [a, b, c, q, k1, k2] = *m;
    let (t1, t2, o1, o2) = (s[0], s[1], s[2], s[3]);
    let (sd, cd) = (t1 - t2).sin_cos();
    let rel = o2 - o1;
    let r1 = -(c * o2 * o2 * sd + t1.sin() + k1 * o1 - k2 * rel);
    let r2 = -(-c * o1 * o1 * sd + q * t2.sin() + k2 * rel);
    let m12 = c * cd;
    let det = a * b - m12 * m12;
    Vector4::new(o1, o2, (b * r1 - m12 * r2) / det, (a * r2 - m12 * r1) / det)
}

fn rk4(m: &[f64; M], s: &Vector4<f64>, h: f64) -> Vector4<f64> {
    let k1 = rates(m, s);
    let k2 = rates(m, &(s + k1 * (0.5 * h)));
    let k3 = rates(m, &(s + k2 * (0.5 * h)));
    let k4 = rates(m, &(s + k3 * h));
    s + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
}

impl Motion<'_> {
    /// The weighted residuals of `piece` run from `state` at its middle row under `m`:
    /// two a row, the arcs each marker strays by over `sigma`.
    fn residuals(
        &self,
        piece: &Range<usize>,
        state: &Vector4<f64>,
        m: &[f64; M],
        sigma: [f64; 2],
    ) -> DVector<f64> {
        let mid = (piece.start + piece.end) / 2;
        let mut r = DVector::zeros(2 * piece.len());
        let hmax = self.natural / STEPS_PER_TIME;
        let mut put = |i: usize, s: &Vector4<f64>| {
            let k = 2 * (i - piece.start);
            r[k] = self.radii[0] * (s[0] - self.theta[0][i]) / sigma[0];
            r[k + 1] = self.radii[1] * (s[1] - self.theta[1][i]) / sigma[1];
        };
        put(mid, state);
        // Forward to the piece's end, then backward from the middle to its start.
        for dir in [1isize, -1] {
            let mut s = *state;
            let mut i = mid;
            loop {
                let next = i as isize + dir;
                if next < piece.start as isize || next >= piece.end as isize {
                    break;
                }
                let next = next as usize;
                let dt = self.t[next] - self.t[i];
                let n = (dt.abs() / hmax).ceil().max(1.0);
                for _ in 0..n as usize {
                    s = rk4(m, &s, dt / n);
                }
                i = next;
                put(i, &s);
            }
        }
        r
    }
}

/// One piece's residuals and their Jacobian in its state (4 columns) and the moments (6).
fn linearise(
    motion: &Motion,
    piece: &Range<usize>,
    state: &Vector4<f64>,
    m: &[f64; M],
    sigma: [f64; 2],
) -> (DVector<f64>, DMatrix<f64>, DMatrix<f64>) {
    let r = motion.residuals(piece, state, m, sigma);
    let mut s_jac = DMatrix::zeros(r.len(), 4);
    for k in 0..4 {
        // Forward differences: 1e-7 of a radian or of the motion's own rate leaves some 1e-8
        // of each derivative, far inside the moments' errors.
        let step = 1e-7 * if k < 2 { 1.0 } else { 1.0 / motion.natural };
        let mut moved = *state;
        moved[k] += step;
        s_jac.set_column(
            k,
            &((motion.residuals(piece, &moved, m, sigma) - &r) / step),
        );
    }
    let mut m_jac = DMatrix::zeros(r.len(), M);
    for k in 0..M {
        let scale = match k {
            0..=2 => m[0].abs().max(m[1].abs()),
            3 => 1.0,
            _ => m[0].abs() / motion.natural,
        };
        let step = 1e-7 * m[k].abs().max(scale);
        let mut moved = *m;
        moved[k] += step;
        m_jac.set_column(
            k,
            &((motion.residuals(piece, state, &moved, sigma) - &r) / step),
        );
    }
    (r, s_jac, m_jac)
}

/// The most pieces the refinement runs on: each costs its rows' integration at every
/// iteration, so a recording of 10^6 rows would take an hour; 256 pieces (a quarter of an
/// hour of a slow pendulum's motion times, 15 s of the shared high-speed film's) pin the six
/// moments to parts in a thousand, and the moments' errors are measured on the pieces run.
pub const MOST_PIECES: usize = 256;

/// At most `most` of `pieces`, evenly spread over them (all where they are fewer).
fn thinned(pieces: Vec<Range<usize>>, most: usize) -> Vec<Range<usize>> {
    let n = pieces.len();
    if n <= most {
        return pieces;
    }
    (0..most).map(|k| pieces[k * n / most].clone()).collect()
}

/// Cuts `stretches` (ranges of rows) into pieces about the motion's own time long where
/// each lies (1/RMS of the upper arm's rate over it), of at least [`PIECE_ROWS`] rows.
fn pieces(motion: &Motion, stretches: &[Range<usize>]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    for range in stretches {
        let (t, th) = (motion.t, motion.theta[0]);
        let rates: Vec<f64> = (range.start + 1..range.end)
            .map(|i| (th[i] - th[i - 1]) / (t[i] - t[i - 1]))
            .collect();
        let rms = (rates.iter().map(|w| w * w).sum::<f64>() / rates.len().max(1) as f64).sqrt();
        let span = t[range.end - 1] - t[range.start];
        let rows_per_second = (range.len() - 1) as f64 / span.max(1e-12);
        let want = ((rows_per_second / rms.max(1e-12)).round() as usize).max(PIECE_ROWS);
        let count = (range.len() / want).max(1);
        let size = range.len() / count;
        for k in 0..count {
            let end = if k + 1 == count {
                range.end
            } else {
                range.start + (k + 1) * size
            };
            out.push(range.start + k * size..end);
        }
    }
    out.retain(|p| p.len() >= PIECE_ROWS);
    out
}

/// Refines the moments `start` on `stretches` of `motion`. None when the pieces are too few
/// or the fit ends on moments no real pendulum has.
pub fn refine(
    motion: &Motion,
    stretches: &[Range<usize>],
    start: [f64; M],
    monitor: &Monitor,
) -> Result<Option<Refined>> {
    let mut pieces = pieces(motion, stretches);
    let of = pieces.len();
    pieces = thinned(pieces, MOST_PIECES);
    if pieces.len() < 4 {
        return Ok(None);
    }
    let mut states: Vec<Vector4<f64>> = pieces
        .iter()
        .map(|p| {
            let mid = (p.start + p.end) / 2;
            Vector4::new(
                motion.theta[0][mid],
                motion.theta[1][mid],
                motion.omega[0][mid],
                motion.omega[1][mid],
            )
        })
        .collect();
    if states.iter().any(|s| !s.iter().all(|x| x.is_finite())) {
        return Ok(None);
    }
    let mut m = start;
    let mut sigma = [1.0, 1.0];
    let mut rejected = 0;
    // Rounds: the markers' noise (each marker's arc RMS) sets the weights, pieces far off
    // the rest are left out, and the fit runs again until the set and the weights hold.
    for round in 0..4 {
        converge(motion, &pieces, &mut states, &mut m, sigma, monitor)?;
        let rms: Vec<[f64; 2]> = pieces
            .iter()
            .zip(&states)
            .map(|(p, s)| {
                let r = motion.residuals(p, s, &m, [1.0, 1.0]);
                let n = (r.len() / 2) as f64;
                std::array::from_fn(|e| {
                    (r.iter().skip(e).step_by(2).map(|x| x * x).sum::<f64>() / n).sqrt()
                })
            })
            .collect();
        let pooled: [f64; 2] = std::array::from_fn(|e| {
            (rms.iter().map(|r| r[e] * r[e]).sum::<f64>() / rms.len() as f64).sqrt()
        });
        let new_sigma = pooled.map(|s| s.max(1e-300));
        let score: Vec<f64> = rms
            .iter()
            .map(|r| (0..2).map(|e| r[e] / new_sigma[e]).fold(0.0, f64::max))
            .collect();
        let mut sorted = score.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        let mut dev: Vec<f64> = score.iter().map(|s| (s - median).abs()).collect();
        dev.sort_by(f64::total_cmp);
        let limit = median + REJECT * 1.4826 * dev[dev.len() / 2];
        let keep: Vec<bool> = score.iter().map(|&s| round == 0 || s <= limit).collect();
        let dropped = keep.iter().filter(|&&k| !k).count();
        let settled = dropped == 0
            && (0..2).all(|e| (new_sigma[e] / sigma[e] - 1.0).abs() < 0.05)
            && round > 0;
        sigma = new_sigma;
        if settled {
            break;
        }
        rejected += dropped;
        (pieces, states) = pieces
            .into_iter()
            .zip(states)
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(piece, _)| piece)
            .unzip();
        if pieces.len() < 4 {
            return Ok(None);
        }
    }
    let Some(covariance) = sandwich(motion, &pieces, &states, &m, sigma) else {
        return Ok(None);
    };
    let rows: usize = pieces.iter().map(|p| 2 * p.len()).sum();
    let [a, b, c, q, ..] = m;
    if !(a > 0.0 && b > 0.0 && q > 0.0 && a * b > c * c) {
        return Ok(None);
    }
    let n = rows as f64 / 2.0;
    let arcs = pieces
        .iter()
        .zip(&states)
        .map(|(p, s)| motion.residuals(p, s, &m, [1.0, 1.0]))
        .fold([0.0; 2], |acc, r| {
            [
                acc[0] + r.iter().step_by(2).map(|x| x * x).sum::<f64>(),
                acc[1] + r.iter().skip(1).step_by(2).map(|x| x * x).sum::<f64>(),
            ]
        });
    Ok(Some(Refined {
        values: m,
        covariance,
        refinement: Refinement {
            pieces: pieces.len(),
            of,
            rejected,
            rms: arcs.map(|s| (s / n).sqrt()),
        },
    }))
}

/// The covariance by pieces (the sandwich H^-1 (sum u u^T) H^-1, u each piece's score in
/// the moments once its state is eliminated): a real pendulum's residuals are not the
/// camera's white noise alone but the model's small errors too, correlated along a piece,
/// and pieces are independent where rows are not. With white noise it is the usual
/// s^2 H^-1 (on 50 seeded pendulums their standard errors agree within a third, a median
/// 2 % apart; on the shared recording these are 2 to 4 times the white-noise ones).
fn sandwich(
    motion: &Motion,
    pieces: &[Range<usize>],
    states: &[Vector4<f64>],
    m: &[f64; M],
    sigma: [f64; 2],
) -> Option<DMatrix<f64>> {
    let parts = normals(motion, pieces, states, m, sigma);
    let (h, _, inverses) = reduce(&parts, 0.0);
    let h_inv = h.try_inverse()?;
    let mut scores = DMatrix::zeros(M, M);
    for (p, a_inv) in parts.iter().zip(&inverses) {
        let a_inv_d = DMatrix::from_iterator(4, 4, a_inv.iter().copied());
        let u =
            &p.g_m - p.b.transpose() * a_inv_d * DVector::from_iterator(4, p.g_s.iter().copied());
        scores += &u * u.transpose();
    }
    let k = pieces.len() as f64;
    Some(&h_inv * scores * &h_inv * (k / (k - 1.0)))
}

/// A piece's normal equations, undamped: A = S^T S, B = S^T G, C = G^T G, g_s = S^T r and
/// g_m = G^T r, S and G its Jacobian in its state and in the moments.
struct Normal {
    cost: f64,
    a: Matrix4<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    g_s: Vector4<f64>,
    g_m: DVector<f64>,
}

fn normals(
    motion: &Motion,
    pieces: &[Range<usize>],
    states: &[Vector4<f64>],
    m: &[f64; M],
    sigma: [f64; 2],
) -> Vec<Normal> {
    use rayon::prelude::*;
    pieces
        .par_iter()
        .zip(states.par_iter())
        .map(|(p, s)| {
            let (r, sj, mj) = linearise(motion, p, s, m, sigma);
            let st = sj.transpose();
            Normal {
                cost: r.norm_squared(),
                a: Matrix4::from_iterator((&st * &sj).iter().copied()),
                b: &st * &mj,
                c: mj.transpose() * &mj,
                g_s: Vector4::from_iterator((&st * &r).iter().copied()),
                g_m: mj.transpose() * &r,
            }
        })
        .collect()
}

/// The moments' reduced system (C - sum B^T A^-1 B) dm = -(g_m - sum B^T A^-1 g_s) with
/// every diagonal damped by `lambda` (Marquardt's scaling), and each piece's A^-1 to recover
/// its state's step, ds = -A^-1 (g_s + B dm).
fn reduce(parts: &[Normal], lambda: f64) -> (DMatrix<f64>, DVector<f64>, Vec<Matrix4<f64>>) {
    let mut h = DMatrix::zeros(M, M);
    let mut rhs = DVector::zeros(M);
    let mut inverses = Vec::with_capacity(parts.len());
    for p in parts {
        let mut a = p.a;
        let mut c = p.c.clone();
        for k in 0..4 {
            a[(k, k)] *= 1.0 + lambda;
        }
        for k in 0..M {
            c[(k, k)] *= 1.0 + lambda;
        }
        let a_inv = a.try_inverse().unwrap_or_else(Matrix4::zeros);
        let a_inv_d = DMatrix::from_iterator(4, 4, a_inv.iter().copied());
        let bt_ainv = p.b.transpose() * &a_inv_d;
        h += c - &bt_ainv * &p.b;
        rhs -= &p.g_m - &bt_ainv * DVector::from_iterator(4, p.g_s.iter().copied());
        inverses.push(a_inv);
    }
    (h, rhs, inverses)
}

/// Levenberg-Marquardt on every piece's state and the shared moments, to convergence.
fn converge(
    motion: &Motion,
    pieces: &[Range<usize>],
    states: &mut [Vector4<f64>],
    m: &mut [f64; M],
    sigma: [f64; 2],
    monitor: &Monitor,
) -> Result<()> {
    let cost_at = |states: &[Vector4<f64>], m: &[f64; M]| -> f64 {
        use rayon::prelude::*;
        pieces
            .par_iter()
            .zip(states.par_iter())
            .map(|(p, s)| motion.residuals(p, s, m, sigma).norm_squared())
            .sum()
    };
    let mut lambda = 1e-3;
    for _ in 0..40 {
        monitor.check()?;
        let parts = normals(motion, pieces, states, m, sigma);
        let cost: f64 = parts.iter().map(|p| p.cost).sum();
        let mut improved = false;
        for _ in 0..10 {
            let (h, rhs, inverses) = reduce(&parts, lambda);
            let Some(dm) = h.lu().solve(&rhs) else {
                lambda *= 10.0;
                continue;
            };
            let trial_states: Vec<Vector4<f64>> = states
                .iter()
                .zip(parts.iter().zip(&inverses))
                .map(|(s, (p, a_inv))| {
                    let bd = &p.b * &dm;
                    s - a_inv * (p.g_s + Vector4::from_iterator(bd.iter().copied()))
                })
                .collect();
            let trial_m: [f64; M] = std::array::from_fn(|k| m[k] + dm[k]);
            let trial = cost_at(&trial_states, &trial_m);
            if trial.is_finite() && trial < cost {
                states.copy_from_slice(&trial_states);
                *m = trial_m;
                lambda = (lambda / 3.0).max(1e-12);
                improved = (cost - trial) > 1e-10 * cost;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    Ok(())
}
