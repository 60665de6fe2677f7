//! One function per command: a job (what to compute, on which backend, into which files) in,
//! files and a summary out. No flags and no printing here: the command line (src/cli) turns
//! flags into jobs and summaries into words, and supplies the reproducing command line that
//! goes into each file's metadata.

pub mod bench;
pub mod boundary;
mod checks;
pub mod film;
pub mod fit;
pub mod flip;
pub mod forecast;
pub mod frames;
pub mod lyapunov;
pub mod map;
pub mod phase;
pub mod store;
pub mod supersample;
pub mod sweep;
pub mod traces;
pub mod track;
pub mod trajectory;
pub mod twin;
pub mod web;
pub mod zoom;

pub use crate::error::{check_count, check_within};
pub use checks::{check_extension, check_output, write_text};
pub use map::{MapOutputs, check_tile, write_map};

use crate::engine::Engine;
use crate::monitor::Monitor;

/// What a command's run is handed beside its job: the engine it computes on, the monitor
/// that shows its progress and stops it at the first Ctrl-C, and the command line that
/// reproduces it (into summary.json and the pictures' metadata).
pub struct Running<'a> {
    pub engine: &'a Engine,
    pub monitor: &'a Monitor,
    pub command: String,
}

impl<'a> Running<'a> {
    pub fn new(engine: &'a Engine, command: String, monitor: &'a Monitor) -> Self {
        Running {
            engine,
            monitor,
            command,
        }
    }
}
