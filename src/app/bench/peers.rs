//! The peers of `../shared/peers`, run beside chaoscope in the same bench: one process each,
//! its JSON report read back.

use super::{BenchJob, Sample};
use crate::error::{Error, Result};
use std::path::PathBuf;
use std::process::Command;

/// What a peer is asked to run.
pub(super) struct PeerRun<'a> {
    pub(super) n: u32,
    pub(super) t_max: f64,
    pub(super) dt: f64,
    pub(super) full: bool,
    pub(super) f64: bool,
    /// Where it writes its map.
    pub(super) out: Option<&'a std::path::Path>,
}

impl<'a> PeerRun<'a> {
    pub(super) fn flip512(args: &BenchJob, full: bool) -> Self {
        PeerRun {
            n: args.size,
            t_max: args.t_max,
            dt: args.dt,
            full,
            f64: false,
            out: None,
        }
    }
}

pub(super) fn run_peer(
    args: &BenchJob,
    dir: &PathBuf,
    peer: &str,
    run: &PeerRun,
) -> Result<Sample> {
    let (script, arch) = peer
        .split_once(':')
        .map_or((peer, None), |(s, a)| (s, Some(a)));
    let mut cmd = Command::new(&args.python);
    cmd.current_dir(dir).arg(format!("{script}_peer.py"));
    if let Some(arch) = arch {
        cmd.args(["--arch", arch]);
    }
    cmd.args([
        "--n",
        &run.n.to_string(),
        "--t-max",
        &run.t_max.to_string(),
        "--dt",
        &run.dt.to_string(),
        if run.f64 { "--f64" } else { "--f32" },
    ]);
    if run.full {
        cmd.arg("--full");
    }
    if let Some(out) = run.out {
        cmd.arg("--out").arg(out);
    }
    let (wall_s, pendulum_steps) = peer_report(cmd, peer)?;
    Ok(Sample {
        name: format!("peer {peer} {}", if run.f64 { "f64" } else { "f32" }),
        mode: if run.full { "full" } else { "early" },
        wall_s,
        pendulum_steps,
        right: None,
    })
}

/// Runs a peer's `cmd` and reads its one JSON line: (wall_s, pendulum_steps).
pub(super) fn peer_report(mut cmd: Command, peer: &str) -> Result<(f64, f64)> {
    let out = cmd.output()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .ok_or_else(|| {
            Error::Io(std::io::Error::other(format!(
                "peer {peer} printed no result: {}",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            )))
        })?;
    let field = |key: &str| -> f64 {
        line.split(&format!("\"{key}\": "))
            .nth(1)
            .and_then(|r| r.split([',', '}']).next())
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(f64::NAN)
    };
    Ok((field("wall_s"), field("pendulum_steps")))
}
