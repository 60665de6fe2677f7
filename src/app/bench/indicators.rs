//! The chaos indicators' rows: each indicator's map on the GPU in f32 and f64 beside the
//! largest-exponent map of the same grid, step and time (its cost ratio), and beside the Numba
//! f64 peer `indicators_numba.py` (f64, exact Jacobian, RK4) on the same problem.

use super::peers::peer_report;
use super::{BenchJob, Row, Sample, ftle_spec};
use crate::engine::Engine;
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::Indicator;
use crate::spec::{Grid, LyapunovSpec, Precision};
use std::process::Command;
use std::time::Instant;

/// The indicators timed, by the names of their rows, the FTLE first (the baseline): each
/// measure's own choice ([`crate::measure::Measure::bench`]).
pub(super) fn problems() -> Vec<(&'static str, Indicator)> {
    crate::measure::MEASURES
        .iter()
        .flat_map(|m| m.bench())
        .collect()
}

/// The peer's names for the indicators it has.
const PEER_HAS: [&str; 4] = ["ftle", "spectrum", "sali", "megno"];

/// The indicator map of the bench: the FLIP-512 time and step on `size`, tangent method,
/// renormalised every 0.1 s, every pixel integrated (no mirrored half).
fn problem(size: u32, args: &BenchJob, indicator: Indicator, precision: Precision) -> LyapunovSpec {
    LyapunovSpec {
        grid: Grid::square(size),
        precision,
        indicator,
        ..ftle_spec(size, args)
    }
}

/// The precisions the GPU rows run in.
fn precisions(engine: &Engine) -> Vec<Precision> {
    match engine.has_f64() {
        true => vec![Precision::F32, Precision::F64],
        false => vec![Precision::F32],
    }
}

/// Compiles every indicator's kernel on a small grid (the peers exclude their JIT too).
pub(super) fn warm_up(args: &BenchJob, engine: &Engine, quiet: &Monitor) -> Result<()> {
    for precision in precisions(engine) {
        for (_, indicator) in problems() {
            engine.map(&problem(8, args, indicator, precision), quiet)?;
        }
    }
    Ok(())
}

/// One repetition of every indicator on the GPU (rows of mode "indicator", named
/// "chaoscope gpu f32 sali" ...), and of the peer's where `args.peers` is set.
pub(super) fn samples(
    args: &BenchJob,
    engine: &Engine,
    quiet: &Monitor,
    notices: &mut Vec<String>,
) -> Result<Vec<Sample>> {
    let mut out = Vec::new();
    let n = args.indicator_size;
    for precision in precisions(engine) {
        for (name, indicator) in problems() {
            let s = problem(n, args, indicator, precision);
            let t0 = Instant::now();
            engine.map(&s, quiet)?;
            out.push(Sample {
                name: format!("chaoscope gpu {} {name}", precision.name()),
                mode: "indicator",
                wall_s: t0.elapsed().as_secs_f64(),
                pendulum_steps: s.grid.pixels() as f64 * s.stepping.steps() as f64,
                right: None,
            });
        }
    }
    if let Some(dir) = &args.peers {
        for name in PEER_HAS {
            let mut cmd = Command::new(&args.python);
            cmd.current_dir(dir).arg("indicators_numba.py").args([
                "--indicator",
                name,
                "--n",
                &n.to_string(),
                "--t-max",
                &args.t_max.to_string(),
                "--dt",
                &args.dt.to_string(),
                "--renorm",
                "0.1",
            ]);
            match peer_report(cmd, "numba-indicators") {
                Ok((wall_s, pendulum_steps)) => out.push(Sample {
                    name: format!("peer numba-indicators f64 {name}"),
                    mode: "indicator",
                    wall_s,
                    pendulum_steps,
                    right: None,
                }),
                Err(e) => notices.push(format!("peer numba-indicators {name}: {e}")),
            }
        }
    }
    Ok(out)
}

/// The same-run comparisons of the indicator rows: each indicator's time against the FTLE
/// map's in the same precision, and the f64 rows against the peer's.
pub(super) fn ratios(rows: &[Row]) -> Vec<String> {
    let time = |path: &str| {
        rows.iter()
            .find(|r| r.mode == "indicator" && r.path == path)
            .map(|r| r.wall_s)
    };
    let mut out = Vec::new();
    for precision in Precision::ALL {
        let p = precision.name();
        let Some(ftle) = time(&format!("chaoscope gpu {p} ftle")) else {
            continue;
        };
        let costs: Vec<String> = problems()
            .iter()
            .skip(1)
            .filter_map(|(name, _)| {
                time(&format!("chaoscope gpu {p} {name}"))
                    .map(|t| format!("{name} {:.2}x", t / ftle))
            })
            .collect();
        out.push(format!(
            "indicators, gpu {p}: time against the largest-exponent map of the same grid and step: {}",
            costs.join(", ")
        ));
    }
    let against_peer: Vec<String> = PEER_HAS
        .iter()
        .filter_map(|name| {
            let ours = time(&format!("chaoscope gpu f64 {name}"))?;
            let peer = time(&format!("peer numba-indicators f64 {name}"))?;
            Some(format!("{name} {:.1}x", peer / ours))
        })
        .collect();
    if !against_peer.is_empty() {
        out.push(format!(
            "indicators, gpu f64 against the Numba f64 peer (its time over ours): {}",
            against_peer.join(", ")
        ));
    }
    out
}
