//! The chaos indicators beyond the largest exponent, in f64: the CPU twin of
//! `shaders/indicators.wgsl`. Every tangent vector takes the FTLE's own step (dual numbers
//! through the mass-matrix solve, [`tangent_step`]), so the spectrum's first exponent is the
//! FTLE map's bit for bit; the shader differentiates its closed form instead (a hand-derived
//! Jacobian, or its own dual numbers with drag and bearings).

use super::lyapunov::{TANGENT_START, norm, tangent_step};
use super::{derivative, map_pixels, rk4_step};
use crate::error::Result;
use crate::field::Field;
use crate::measure::{Alignment, CpuRun};
use crate::model::{Params, State};
use crate::monitor::Monitor;
use crate::spec::LyapunovSpec;

/// The tangent vectors every run starts from: an orthonormal frame whose first vector is the
/// FTLE's (the rows of a 4 x 4 Hadamard matrix, halved). The first two differ in their angle
/// parts: started at rest, a change of the speeds alone changes no action to first order
/// (they are even in the momenta), so two vectors with the same angle part would shear along
/// one direction of a torus and align like 1/t on regular orbits (SALI and GALI_2 would
/// then read regular orbits as slowly chaotic; the order below keeps them constant).
pub const FRAME: [[f64; 4]; 4] = [
    TANGENT_START,
    [0.5, 0.5, -0.5, -0.5],
    [0.5, -0.5, 0.5, -0.5],
    [0.5, -0.5, -0.5, 0.5],
];

fn dot(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Modified Gram-Schmidt in place: each vector made orthogonal to those before it, then unit;
/// the lengths it had (the diagonal of R in V = QR).
pub fn gram_schmidt(v: &mut [[f64; 4]]) -> Vec<f64> {
    let mut lengths = Vec::with_capacity(v.len());
    for j in 0..v.len() {
        for i in 0..j {
            let d = dot(&v[i], &v[j]);
            let vi = v[i];
            for (x, e) in v[j].iter_mut().zip(vi) {
                *x -= d * e;
            }
        }
        let n = norm(&v[j]);
        v[j] = v[j].map(|x| x / n);
        lengths.push(n);
    }
    lengths
}

/// The alignment index of unit vectors `v`: SALI = min(|v1 + v2|, |v1 - v2|), GALI_k = the
/// volume of their parallelotope (the product of Gram-Schmidt's lengths).
pub fn alignment_index(index: Alignment, v: &[[f64; 4]]) -> f64 {
    match index {
        Alignment::Sali => {
            let plus: [f64; 4] = std::array::from_fn(|i| v[0][i] + v[1][i]);
            let minus: [f64; 4] = std::array::from_fn(|i| v[0][i] - v[1][i]);
            norm(&plus).min(norm(&minus))
        }
        Alignment::Gali(_) => gram_schmidt(&mut v.to_vec()).iter().product(),
    }
}

/// One start's run of `spec`'s indicator: its map value, and `sample(t, columns)` at every
/// renormalisation (the measure's columns); progress and Ctrl-C there when `monitor` is given.
pub fn indicator_run(
    spec: &LyapunovSpec,
    start: State,
    monitor: Option<&Monitor>,
    sample: &mut dyn FnMut(f64, &[f64]),
) -> Result<f64> {
    let every = spec.renorm_steps();
    let tick = |k: u32| -> Result<()> {
        if let Some(m) = monitor {
            m.check()?;
            m.advance(every.min(k) as u64);
        }
        Ok(())
    };
    if let Some(m) = monitor {
        m.start("steps", spec.stepping.steps() as u64);
    }
    let mut run = CpuRun {
        params: spec.params,
        stepping: spec.stepping,
        integrator: spec.integrator,
        renorm_steps: spec.renorm_steps(),
        start,
        sample,
        tick: &tick,
    };
    let value = spec.indicator.measure().cpu(spec.indicator, &mut run)?;
    if let Some(m) = monitor {
        m.finish();
    }
    Ok(value)
}

/// The log sums of the first `n` vectors of [`FRAME`] after RK4 steps to t-max, renormalised
/// by Gram-Schmidt every `renorm`; the running exponents sampled there (and their sum when
/// `n` is 4).
pub fn tangent_sums(run: &mut CpuRun, n: usize) -> Result<Vec<f64>> {
    let (p, dt) = (&run.params, run.stepping.dt);
    let mut y = run.start.to_array();
    let mut v = FRAME[..n].to_vec();
    let mut sums = vec![0.0; n];
    for k in 1..=run.stepping.steps() {
        y = step_vectors(p, &y, &mut v, dt);
        if run.renormalise(k) {
            for (sum, l) in sums.iter_mut().zip(gram_schmidt(&mut v)) {
                *sum += l.ln();
            }
            let t = k as f64 * dt;
            let mut row: Vec<f64> = sums.iter().map(|s| s / t).collect();
            if n == 4 {
                row.push(row.iter().sum());
            }
            (run.sample)(t, &row);
            (run.tick)(k)?;
        }
    }
    Ok(sums)
}

/// `index` of normalised vectors after RK4 steps, normalised every `renorm`, until t-max or
/// until it falls below `threshold`: (its log10 at the end, the time it fell below, +inf if
/// it did not).
pub fn alignment_run(run: &mut CpuRun, index: Alignment, threshold: f64) -> Result<(f64, f64)> {
    let (p, dt) = (&run.params, run.stepping.dt);
    let mut y = run.start.to_array();
    let mut v = FRAME[..index.vectors() as usize].to_vec();
    let mut log = 0.0;
    for k in 1..=run.stepping.steps() {
        y = step_vectors(p, &y, &mut v, dt);
        if run.renormalise(k) {
            for v in &mut v {
                let n = norm(v);
                *v = v.map(|x| x / n);
            }
            let a = alignment_index(index, &v);
            log = a.log10();
            let t = k as f64 * dt;
            (run.sample)(t, &[log]);
            (run.tick)(k)?;
            if a < threshold {
                return Ok((log, t));
            }
        }
    }
    Ok((log, f64::INFINITY))
}

/// One vector renormalised every step (ln |v| of a step is the integrand of both): (MEGNO
/// <Y>, the FLI) at t-max, sampled with Y(t) every `renorm`; NaN where it left the numbers.
pub fn growth_run(run: &mut CpuRun) -> Result<(f64, f64)> {
    let (p, dt, steps) = (&run.params, run.stepping.dt, run.stepping.steps());
    let mut y = run.start.to_array();
    let mut v = TANGENT_START;
    let (mut weighted, mut mean, mut total, mut fli) = (0.0, 0.0, 0.0, 0.0f64);
    for k in 1..=steps {
        let (next, w) = tangent_step(p, &y, &v, dt);
        let n = norm(&w);
        (y, v) = (next, w.map(|x| x / n));
        let t = k as f64 * dt;
        // Y(t) = 2/t int_0^t s d(ln |v|), s at the step's middle; <Y> its time mean.
        weighted += (t - 0.5 * dt) * n.ln();
        let y_now = 2.0 * weighted / t;
        mean += dt * y_now;
        total += n.ln();
        fli = fli.max(total / std::f64::consts::LN_10);
        if run.renormalise(k) {
            (run.sample)(t, &[mean / t, y_now, fli]);
            (run.tick)(k)?;
        }
        if !total.is_finite() {
            return Ok((f64::NAN, f64::NAN));
        }
    }
    Ok((mean / (steps as f64 * dt), fli))
}

/// The Lagrangian descriptor with the power `power`: one RK4 trajectory forward and one
/// backward, the trapezoid rule each way; NaN where it left the numbers.
pub fn descriptor_run(run: &mut CpuRun, power: f64) -> Result<f64> {
    let (p, dt) = (&run.params, run.stepping.dt);
    let g = |s: &State| -> f64 {
        derivative(p, s)
            .to_array()
            .iter()
            .map(|f| f.abs().powf(power))
            .sum()
    };
    let (mut ahead, mut back) = (run.start, run.start);
    let (mut g_ahead, mut g_back) = (g(&run.start), g(&run.start));
    let mut m = 0.0;
    for k in 1..=run.stepping.steps() {
        ahead = rk4_step(p, &ahead, dt);
        back = rk4_step(p, &back, -dt);
        let (ga, gb) = (g(&ahead), g(&back));
        m += 0.5 * dt * (g_ahead + ga) + 0.5 * dt * (g_back + gb);
        (g_ahead, g_back) = (ga, gb);
        if run.renormalise(k) {
            (run.sample)(k as f64 * dt, &[m]);
            (run.tick)(k)?;
        }
    }
    Ok(if m.is_finite() { m } else { f64::NAN })
}

/// The spectrum with DP54 steps (`spec.integrator`'s tolerances, steps of at most dt) over
/// the state and the four vectors together, the error controlled over all twenty components,
/// every renormalisation window landed on exactly: the four log sums (NaN where it stalled).
pub fn spectrum_adaptive(run: &mut CpuRun) -> Result<[f64; 4]> {
    use super::adaptive::{Clock, dp54_to};
    use num_dual::Dual64;
    const N: usize = 20;
    let p = &run.params;
    let (rtol, atol) = run.integrator.tolerances().expect("adaptive");
    let (dt, steps, every) = (run.stepping.dt, run.stepping.steps(), run.renorm_steps);
    // x = (y, v1, v2, v3, v4); each vector's rate is the dual part of the rate at y + eps v.
    let rate = |x: &[f64; N]| -> [f64; N] {
        let mut out = [0.0; N];
        for j in 0..4 {
            let d: [Dual64; 4] = std::array::from_fn(|i| Dual64::new(x[i], x[4 + 4 * j + i]));
            let r = super::rate_of(p, &d);
            for i in 0..4 {
                out[i] = r[i].re;
                out[4 + 4 * j + i] = r[i].eps;
            }
        }
        out
    };
    let mut x = [0.0; N];
    x[..4].copy_from_slice(&run.start.to_array());
    for (j, v) in FRAME.iter().enumerate() {
        x[4 + 4 * j..8 + 4 * j].copy_from_slice(v);
    }
    let mut clock = Clock::new(dt);
    let mut sums = [0.0; 4];
    let mut done = 0;
    while done < steps {
        let end = (done + every).min(steps);
        let t_end = end as f64 * dt;
        if dp54_to(&mut x, &mut clock, t_end, (rtol, atol), rate).is_err() {
            (run.sample)(t_end, &[f64::NAN; 5]);
            return Ok([f64::NAN; 4]);
        }
        let mut v: Vec<[f64; 4]> = (0..4)
            .map(|j| std::array::from_fn(|i| x[4 + 4 * j + i]))
            .collect();
        for (sum, l) in sums.iter_mut().zip(gram_schmidt(&mut v)) {
            *sum += l.ln();
        }
        for (j, vj) in v.iter().enumerate() {
            x[4 + 4 * j..8 + 4 * j].copy_from_slice(vj);
        }
        let mut row: Vec<f64> = sums.iter().map(|s| s / t_end).collect();
        row.push(row.iter().sum());
        (run.sample)(t_end, &row);
        (run.tick)(end)?;
        done = end;
    }
    Ok(sums)
}

/// One RK4 step of the state and each of `v` along it (each vector the FTLE's own step); the
/// next state.
fn step_vectors(p: &Params, y: &[f64; 4], v: &mut [[f64; 4]], dt: f64) -> [f64; 4] {
    let mut next = *y;
    for (j, vj) in v.iter_mut().enumerate() {
        let (ny, nv) = tangent_step(p, y, vj, dt);
        *vj = nv;
        if j == 0 {
            next = ny;
        }
    }
    next
}

/// All four exponents of `spec`'s grid (1/s, in Gram-Schmidt order), one run of four vectors a
/// pixel (RK4, or DP54 where `spec` steps with it), rows in parallel.
pub fn spectrum_map(spec: &LyapunovSpec, monitor: &Monitor) -> Result<[Field; 4]> {
    use rayon::prelude::*;
    let (grid, span) = (&spec.grid, spec.row_span());
    let t_end = spec.stepping.steps() as f64 * spec.stepping.dt;
    monitor.start("cpu", span.count as u64);
    let rows: Vec<Vec<[f64; 4]>> = (0..span.count)
        .into_par_iter()
        .map(|row| {
            monitor.check()?;
            let values = (0..grid.width)
                .map(|col| {
                    let (params, start) = grid.pixel(&spec.params, col, span.first + row);
                    let mut run = CpuRun {
                        params,
                        stepping: spec.stepping,
                        integrator: spec.integrator,
                        renorm_steps: spec.renorm_steps(),
                        start,
                        sample: &mut |_, _| {},
                        tick: &|_| Ok(()),
                    };
                    let sums = match spec.integrator.tolerances() {
                        Some(_) => spectrum_adaptive(&mut run)?,
                        None => {
                            let s = tangent_sums(&mut run, 4)?;
                            [s[0], s[1], s[2], s[3]]
                        }
                    };
                    Ok(sums.map(|s| s / t_end))
                })
                .collect::<Result<Vec<_>>>()?;
            monitor.advance(1);
            Ok(values)
        })
        .collect::<Result<_>>()?;
    monitor.finish();
    Ok(std::array::from_fn(|k| {
        let mut field = Field::new(grid.width, span.field_rows(grid), 0.0);
        for (i, v) in rows.iter().flatten().enumerate() {
            field.data[i] = v[k] as f32;
        }
        if span.whole {
            field.mirror_below(span.count);
        }
        field
    }))
}

/// The map of `spec`'s indicator, rows in parallel.
pub fn indicator_map(spec: &LyapunovSpec, monitor: &Monitor) -> Result<Field> {
    map_pixels(spec, monitor, |p, start| {
        let spec = LyapunovSpec {
            params: *p,
            ..*spec
        };
        indicator_run(&spec, start, None, &mut |_, _| {}).expect("never cancelled") as f32
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_is_orthonormal_and_gram_schmidt_keeps_it() {
        let mut v = FRAME.to_vec();
        for (i, a) in FRAME.iter().enumerate() {
            for (j, b) in FRAME.iter().enumerate() {
                assert_eq!(dot(a, b), (i == j) as u8 as f64);
            }
        }
        assert_eq!(gram_schmidt(&mut v), vec![1.0; 4]);
        assert_eq!(v, FRAME.to_vec());
        // Orthonormal vectors span a unit volume; parallel ones none.
        assert_eq!(alignment_index(Alignment::Gali(4), &FRAME), 1.0);
        assert_eq!(alignment_index(Alignment::Sali, &[FRAME[0], FRAME[0]]), 0.0);
        assert!((alignment_index(Alignment::Sali, &FRAME[..2]) - 2f64.sqrt()).abs() < 1e-15);
    }
}
