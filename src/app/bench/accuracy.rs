//! The accurate rows: the accurate flip map and the accurate divergence map against
//! converged references, each path with the share of its pixels right.

use super::peers::{PeerRun, run_peer};
use super::{BenchJob, Sample};
use crate::cpu;
use crate::error::Result;
use crate::field::Field;
use crate::model::Params;
use crate::monitor::Monitor;
use crate::spec::{FlipSpec, Grid, Integrator, LyapunovSpec, Method, Precision, Stepping};
use std::time::Instant;

/// The "accurate map" problem (issue 11): the default pendulum over the full grid at
/// `accurate_size`, `accurate_t_max`.
pub(super) fn accurate_problem(
    args: &BenchJob,
    precision: Precision,
    integrator: Integrator,
    dt: f64,
) -> FlipSpec {
    FlipSpec {
        precision,
        integrator,
        ..FlipSpec::new(
            Params::default(),
            Grid::square(args.accurate_size),
            Stepping {
                dt,
                t_max: args.accurate_t_max,
            },
        )
    }
}

/// The converged reference of the accurate-map problem: the f64 CPU's DP54 at rtol 1e-12
/// (at 256^2 and 30 s the GPU's f64 DP54 at 1e-12 agrees with it on every pixel).
pub(super) fn accurate_reference(args: &BenchJob, monitor: &Monitor) -> Result<Field> {
    let spec = accurate_problem(args, Precision::F64, converged(1e-12), 0.05);
    cpu::flip_map_adaptive(&spec, monitor)
}

/// DP54 at `tolerance` relative and absolute: a converged reference's steps.
fn converged(tolerance: f64) -> Integrator {
    Integrator::Dp54 {
        rtol: tolerance,
        atol: tolerance,
    }
}

/// The fraction of `map`'s pixels that match `reference` (the verdict's agreement rule).
pub(super) fn right(map: &[f32], reference: &Field) -> f64 {
    crate::verdict::fraction(&crate::verdict::mask(
        &Field {
            data: map.to_vec(),
            ..reference.clone()
        },
        reference,
        crate::quantity::flip_times_agree,
    ))
}

/// Steps at which the peers run the accurate-map problem in f64 RK4 (issue 11 measured
/// numba: dt 0.005 right on 99.29 % of the pixels, 0.0025 on 99.77 %).
pub(super) const PEER_ACCURATE_DT: [f64; 2] = [0.005, 0.0025];

/// One repetition of the accurate-map rows: today's f32 RK4 map at dt `args.dt`, the
/// `--accurate` map, DOP853 at its tolerance, and each peer in f64 at the steps of PEER_ACCURATE_DT, each with the
/// fraction of its pixels that match `reference`.
pub(super) fn accurate_samples(
    args: &BenchJob,
    engine: &crate::engine::Engine,
    reference: &Field,
    quiet: &Monitor,
    notices: &mut Vec<String>,
) -> Result<Vec<Sample>> {
    let mut out = Vec::new();
    for (name, spec) in [
        (
            format!("chaoscope gpu f32 rk4 dt {}", args.dt),
            accurate_problem(args, Precision::F32, Integrator::Rk4, args.dt),
        ),
        (
            "chaoscope [[accurate]] (gpu f64 dp54)".to_string(),
            accurate_problem(args, Precision::F32, Integrator::Rk4, args.dt).accurate(),
        ),
        // The higher-order pair at the same tolerance, with the longest steps RK4's
        // stability check allows this pendulum.
        (
            "chaoscope gpu f64 dop853 1e-9 dt 0.1".to_string(),
            accurate_problem(
                args,
                Precision::F64,
                Integrator::Dop853 {
                    rtol: 1e-9,
                    atol: 1e-9,
                },
                0.1,
            ),
        ),
    ] {
        let t0 = Instant::now();
        let field = engine.map(&spec, quiet)?;
        out.push(Sample {
            name,
            mode: "accurate",
            wall_s: t0.elapsed().as_secs_f64(),
            pendulum_steps: f64::NAN,
            right: Some(right(&field.data, reference)),
        });
    }
    if let Some(dir) = &args.peers {
        let map = std::env::temp_dir().join(format!("chaoscope-bench-{}.npy", std::process::id()));
        for peer in &args.peer {
            for dt in PEER_ACCURATE_DT {
                let run = PeerRun {
                    n: args.accurate_size,
                    t_max: args.accurate_t_max,
                    dt,
                    full: false,
                    f64: true,
                    out: Some(&map),
                };
                match run_peer(args, dir, peer, &run).and_then(|mut s| {
                    // The peer's map: n x n float32 and a header.
                    let cap = 4 * (args.accurate_size as u64).pow(2) + 4096;
                    let data = crate::input::read_bounded("peers", &map, cap)?;
                    let npy = npyz::NpyFile::new(&data[..])?;
                    s.right = Some(right(&npy.into_vec::<f32>()?, reference));
                    s.name = format!("{} dt {dt}", s.name);
                    s.mode = "accurate";
                    s.pendulum_steps = f64::NAN;
                    Ok(s)
                }) {
                    Ok(s) => out.push(s),
                    Err(e) => notices.push(format!("peer {peer} (accurate map, dt {dt}): {e}")),
                }
            }
        }
        std::fs::remove_file(&map).ok();
    }
    Ok(out)
}

/// The divergence-map accuracy problem (issue 11): the default pendulum on the accurate
/// rows' grid at half the side and a third of the time (by default 128 x 128, 10 s: BENCH.md's
/// table), the tangent method renormalised every 0.1 s, the point-symmetric half integrated
/// as `chaoscope lyapunov` does.
pub(super) fn ftle_accuracy_spec(
    args: &BenchJob,
    precision: Precision,
    integrator: Integrator,
    dt: f64,
) -> LyapunovSpec {
    LyapunovSpec {
        params: Params::default(),
        grid: Grid::square(ftle_accuracy_size(args)),
        stepping: Stepping {
            dt,
            t_max: args.accurate_t_max / 3.0,
        },
        method: Method::Tangent,
        renorm: 0.1,
        use_symmetry: true,
        precision,
        band: None,
        integrator,
        indicator: crate::spec::Indicator::default(),
    }
}

/// Grid side of the accurate divergence-map rows.
pub fn ftle_accuracy_size(args: &BenchJob) -> u32 {
    (args.accurate_size / 2).max(2)
}

/// The converged divergence map: the f64 CPU's DP54 at rtol 1e-11.
pub(super) fn ftle_reference(args: &BenchJob, monitor: &Monitor) -> Result<Field> {
    cpu::ftle_map(
        &ftle_accuracy_spec(args, Precision::F64, converged(1e-11), 0.1),
        monitor,
    )
}

/// The accurate divergence-map rows' paths: f32 and f64 RK4 at dt 0.01, and `lyapunov
/// --accurate` (f64 DP54 at 1e-9, steps of at most 0.1 s).
pub(super) fn ftle_accuracy_paths(args: &BenchJob) -> [(&'static str, LyapunovSpec); 3] {
    [
        (
            "chaoscope gpu f32 rk4 dt 0.01",
            ftle_accuracy_spec(args, Precision::F32, Integrator::Rk4, 0.01),
        ),
        (
            "chaoscope gpu f64 rk4 dt 0.01",
            ftle_accuracy_spec(args, Precision::F64, Integrator::Rk4, 0.01),
        ),
        (
            "chaoscope lyapunov [[accurate]] (gpu f64 dp54)",
            ftle_accuracy_spec(args, Precision::F32, Integrator::Rk4, 0.01).accurate(),
        ),
    ]
}

/// One repetition of the accurate divergence-map rows, each with the fraction of its
/// exponents that agree with `reference` by the verdict's rule.
pub(super) fn ftle_accuracy_samples(
    args: &BenchJob,
    engine: &crate::engine::Engine,
    reference: &Field,
    quiet: &Monitor,
) -> Result<Vec<Sample>> {
    let mut out = Vec::new();
    for (name, spec) in ftle_accuracy_paths(args) {
        let t0 = Instant::now();
        let field = engine.map(&spec, quiet)?;
        let wall_s = t0.elapsed().as_secs_f64();
        let agree = crate::verdict::mask(&field, reference, crate::quantity::exponents_agree);
        out.push(Sample {
            name: name.to_string(),
            mode: "accurate-ftle",
            wall_s,
            pendulum_steps: f64::NAN,
            right: Some(crate::verdict::fraction(&agree)),
        });
    }
    Ok(out)
}
