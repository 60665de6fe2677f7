//! `chaoscope serve`: the explorer in the browser.

use std::net::IpAddr;
use std::path::PathBuf;

use clap::Args;

use super::args::{PhysicalArgs, backend_parser};
use super::{command_line, json, say};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::serve::{self, Commands, ServeJob, StoredMap};

#[derive(Args, Debug, Clone)]
pub struct ServeArgs {
    /// Port to listen on (0: any free port; the URL printed says which).
    #[arg(long, default_value = "8080")]
    pub port: u16,
    /// Address to listen on. The default answers this machine only; reach a remote one
    /// through an SSH tunnel (ssh -L 8080:127.0.0.1:8080 host) rather than opening it.
    #[arg(long, default_value = "127.0.0.1")]
    pub host: IpAddr,
    /// auto: the GPU when an adapter exists, else the CPU (with a notice); gpu; cpu (f64).
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    /// The physics the page starts from (the page can change masses, lengths and damping).
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// Show a Zarr store's map (flip/lyapunov --data MAP.zarr) instead: tiles read from it
    /// down to its own pixels, computed with its command's settings below them.
    #[arg(long)]
    pub store: Option<PathBuf>,
}

impl ServeArgs {
    pub fn job(&self) -> Result<ServeJob> {
        let store = match &self.store {
            None => None,
            Some(path) => {
                if self.physical.sources() != ParamSources::default() {
                    return Err(Error::invalid(
                        "store",
                        "its command fixes the physics: give the store alone",
                    ));
                }
                let (command, map) = crate::app::store::stored_map(path)?;
                Some(StoredMap {
                    path: path.clone(),
                    command,
                    map,
                })
            }
        };
        Ok(ServeJob {
            host: self.host,
            port: self.port,
            base: self.physical.sources(),
            backend: self.backend,
            store,
            site: super::web::site(&self.physical, None)?,
        })
    }
}

/// The commands the page shows and the saved views carry.
pub const COMMANDS: Commands = Commands {
    flip: command_line::flip,
    lyapunov: command_line::lyapunov_map,
    trajectory: command_line::trajectory,
    zoom_flip: |job| command_line::zoom(job, &command_line::flip(&job.map)),
    zoom_lyapunov: |job| command_line::zoom(job, &command_line::lyapunov_map(&job.map)),
};

/// Serves until Ctrl-C. Standard output holds the URL once listening (scripts and tests read
/// it), and with `json` only JSON: the URL as `{"url": ...}`, then the summary.
pub fn run(args: &ServeArgs, monitor: &Monitor, json_out: bool) -> Result<serde_json::Value> {
    let job = args.job()?;
    // The explorer's one engine, lent to every tile, point, range and saved view.
    let engine = super::args::lent_engine(None, job.backend)?;
    let summary = serve::run(&job, engine, COMMANDS, monitor, |ready| {
        say("serve", &ready.notices);
        match json_out {
            true => println!("{}", serde_json::json!({ "url": ready.url })),
            false => println!("{}", ready.url),
        }
        eprintln!(
            "chaoscope explorer at {} (tiles on {}); Ctrl-C stops it",
            ready.url, ready.place
        );
    })?;
    eprintln!(
        "stopped: {} tiles computed, {} from the cache, {} cancelled, {} refused (queue full)",
        summary.computed, summary.cached, summary.cancelled, summary.refused
    );
    json(&summary)
}
