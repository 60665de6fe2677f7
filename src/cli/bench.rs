//! `chaoscope bench`.

use std::path::PathBuf;

use clap::Args;

use super::parse::{parse_number, parse_u32, parse_usize};
use super::say;
use crate::app::bench::{self, BenchJob};
use crate::error::Result;
use crate::monitor::Monitor;

#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// Grid side (FLIP-512: 512).
    #[arg(long, default_value = "512", value_parser = parse_u32, allow_hyphen_values = true)]
    pub size: u32,
    /// Grid side for the CPU rows (steps per second do not depend on it; the f64 CPU path
    /// is slow enough that 512 would dominate the run).
    #[arg(long, default_value = "256", value_parser = parse_u32, allow_hyphen_values = true)]
    pub cpu_size: u32,
    /// Simulated time (s).
    #[arg(long, default_value = "20", value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    /// RK4 time step (s).
    #[arg(long, default_value = "0.01", value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    /// Repetitions of every configuration, interleaved; the median is reported.
    #[arg(long, default_value = "3", value_parser = parse_u32, allow_hyphen_values = true)]
    pub repeat: u32,
    /// Skip the CPU rows.
    #[arg(long)]
    pub no_cpu: bool,
    /// Skip the divergence-map (FTLE) rows.
    #[arg(long)]
    pub no_ftle: bool,
    /// Directory of the peer scripts (numba_peer.py, taichi_peer.py, ...: other implementations
    /// of the same maps, not part of chaoscope); no peers are run without it.
    #[arg(long)]
    pub peers: Option<PathBuf>,
    /// Python with the peers' requirements installed.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Peers to run, as SCRIPT[:ARCH] (e.g. taichi:vulkan, numba), in f32.
    #[arg(long, default_values = ["taichi:vulkan", "numba"])]
    pub peer: Vec<String>,
    /// Grid side of the "accurate map" rows (time to a map right on >= 99.5 % of its pixels
    /// against a converged reference; 0 leaves them out).
    #[arg(long, default_value = "256", value_parser = parse_u32, allow_hyphen_values = true)]
    pub accurate_size: u32,
    /// Simulated time of the accurate-map rows (s).
    #[arg(long, default_value = "30", value_parser = parse_number, allow_hyphen_values = true)]
    pub accurate_t_max: f64,
    /// Grid side of the chaos indicators' rows (each indicator beside the FTLE map, f32 and
    /// f64, and beside the Numba indicators peer with --peers; 0 leaves them out).
    #[arg(long, default_value = "256", value_parser = parse_u32, allow_hyphen_values = true)]
    pub indicator_size: u32,
    /// Members of the forecast row: an ensemble of tracked data (the lab pendulum, its own
    /// joint damping each) over 6 s past a fit window, bands and FTLE included (0 leaves it
    /// out).
    #[arg(long, default_value = "10000", value_parser = parse_usize, allow_hyphen_values = true)]
    pub forecast_members: usize,
}

impl BenchArgs {
    pub fn job(&self) -> BenchJob {
        BenchJob {
            size: self.size,
            cpu_size: self.cpu_size,
            t_max: self.t_max,
            dt: self.dt,
            repeat: self.repeat,
            no_cpu: self.no_cpu,
            no_ftle: self.no_ftle,
            peers: self.peers.clone(),
            // The peers run in their own directory: a relative path to Python is the
            // caller's, made absolute here.
            python: match self.python.contains('/') {
                true => std::path::absolute(&self.python)
                    .map(|p| p.display().to_string())
                    .unwrap_or_else(|_| self.python.clone()),
                false => self.python.clone(),
            },
            peer: self.peer.clone(),
            accurate_size: self.accurate_size,
            accurate_t_max: self.accurate_t_max,
            indicator_size: self.indicator_size,
            forecast_members: self.forecast_members,
        }
    }
}

pub fn run(args: &BenchArgs, monitor: &Monitor, as_json: bool) -> Result<serde_json::Value> {
    let job = args.job();
    // Before the minutes of GPU and CPU rows, not after them.
    if let Some(dir) = &job.peers
        && !dir.join("common.py").is_file()
    {
        return Err(crate::Error::invalid(
            "peers",
            format!("{} holds no peer scripts (no common.py)", dir.display()),
        ));
    }
    let mut r = bench::run(&job, monitor)?;
    // The rows and findings name chaoscope's settings as fields: said as its flags.
    for row in &mut r.rows {
        row.path = super::spelt("bench", &row.path);
    }
    for line in &mut r.ratios {
        *line = super::spelt("bench", line);
    }
    say("bench", &r.notices);
    if as_json {
        return super::json(&r);
    }
    eprintln!("GPU: {}", r.adapter);
    println!(
        "FLIP-{} (RK4, dt {}, t_max {} s): medians of {} interleaved runs; cpu rows scaled from n={}",
        job.size, job.dt, job.t_max, job.repeat, job.cpu_size
    );
    println!(
        "pendulum-steps as the peers count them: early-all and full integrate every pixel; early \
         and full-half integrate the top half of the symmetric grid and mirror it"
    );
    // The path column as wide as the longest name (adapter names are long).
    let w = r
        .rows
        .iter()
        .map(|row| row.path.len())
        .max()
        .unwrap_or(0)
        .max(4);
    println!(
        "accurate: {0}x{0}, {1} s; right = within 1 % or 0.02 s of f64 DP54 at rtol 1e-12",
        job.accurate_size, job.accurate_t_max
    );
    if !job.no_ftle {
        println!(
            "accurate-ftle: {0}x{0}, {1} s, tangent renormalised every 0.1 s; right = within 5 % \
             or 0.02 /s of f64 DP54 at rtol 1e-11",
            bench::ftle_accuracy_size(&job),
            job.accurate_t_max / 3.0
        );
    }
    println!(
        "{:<w$} {:>13} {:>10} {:>16} {:>8}",
        "path", "mode", "wall s", "pendulum-steps/s", "right"
    );
    for row in &r.rows {
        let rate = match row.steps_per_s.is_finite() {
            true => format!("{:.3e}", row.steps_per_s),
            false => "-".into(),
        };
        let right = row
            .right
            .map_or(String::new(), |f| format!("{:.2} %", 100.0 * f));
        println!(
            "{:<w$} {:>13} {:>10.3} {:>16} {:>8}",
            row.path, row.mode, row.wall_s, rate, right
        );
    }
    for line in &r.ratios {
        println!("{line}");
    }
    super::json(&r)
}
