//! `chaoscope traces`.

use std::path::PathBuf;

use clap::Args;

use super::args::{LentEngineArgs, PhysicalArgs, StartArgs};
use super::parse::{parse_number, parse_spread, parse_u32};
use super::{command_line, json, say};
use crate::app::film::FilmSpec;
use crate::app::traces::{self, TracesJob};
use crate::error::Result;
use crate::monitor::Monitor;
use crate::spec::{Spread, Stepping};

#[derive(Args, Debug, Clone)]
pub struct TracesArgs {
    #[command(flatten)]
    pub start: StartArgs,
    /// Number of releases.
    #[arg(long, default_value = "3", value_parser = parse_u32, allow_hyphen_values = true)]
    pub runs: u32,
    /// Distance between releases: rad (0.01) or a position error (5mm, the report's).
    #[arg(long, default_value = "5mm", value_parser = parse_spread, allow_hyphen_values = true)]
    pub spread: Spread,
    /// Exposure time (s): the report's photographs were 3.2 s.
    #[arg(long, default_value = "3.2", value_parser = parse_number, allow_hyphen_values = true)]
    pub exposure: f64,
    /// RK4 time step (s); small, so the trails are smooth.
    #[arg(long, default_value = "0.001", value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
    /// Picture side (px).
    #[arg(long, default_value = "1024", value_parser = parse_u32, allow_hyphen_values = true)]
    pub size: u32,
    #[command(flatten)]
    pub physical: PhysicalArgs,
    #[command(flatten)]
    pub engine: LentEngineArgs,
    /// PNG to write.
    #[arg(long, default_value = "out/traces.png")]
    pub output: PathBuf,
    /// Also a film of the trails growing as the pendulums swing and part, its format by its
    /// extension: .gif, .png (APNG) or .mp4 (H.264, through FFmpeg; up to 720 pixels a side,
    /// the others up to 480). `--gif` is its older name.
    #[arg(long, alias = "gif")]
    pub film: Option<PathBuf>,
    /// The film's frames a second (the exposure plays in real time).
    #[arg(long, default_value = "25", value_parser = parse_number, allow_hyphen_values = true)]
    pub fps: f64,
    /// An MP4's quality: H.264's constant rate factor, 0 (lossless) to 51 (18 looks
    /// lossless; each 6 more halves the file).
    #[arg(long, default_value = "18", value_parser = parse_u32, allow_hyphen_values = true)]
    pub crf: u32,
    /// Lower-bob positions as float32 .npy, shape (runs, samples, 4): x1, y1, x2, y2 (m).
    #[arg(long)]
    pub data: Option<PathBuf>,
}

impl TracesArgs {
    pub fn job(&self) -> Result<TracesJob> {
        Ok(TracesJob {
            params: self.physical.sources().resolve()?,
            start: self.start.state(),
            runs: self.runs,
            spread: self.spread,
            stepping: Stepping {
                dt: self.dt,
                t_max: self.exposure,
            },
            size: self.size,
            backend: self.engine.backend,
            precision: self.engine.precision.unwrap_or_default(),
            output: self.output.clone(),
            film: self.film.clone().map(|path| FilmSpec {
                path,
                fps: self.fps,
                crf: self.crf,
            }),
            data: self.data.clone(),
        })
    }
}

pub fn run(args: &TracesArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let job = args.job()?;
    let s = args
        .engine
        .run(&job, command_line::traces, monitor, traces::run)?;
    say("traces", &s.notices);
    eprintln!(
        "{} releases over {} s on {} -> {}",
        s.runs,
        s.exposure,
        s.place,
        s.output.display()
    );
    json(&s)
}
