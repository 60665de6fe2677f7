//! `chaoscope status` and `chaoscope render`: a Zarr store's progress, and its picture.

use std::path::PathBuf;

use clap::Args;

use super::args::PictureArgs;
use super::parse::parse_u32;
use super::{json, say};
use crate::app::store::{self, RenderJob, StatusJob};
use crate::error::Result;
use crate::monitor::Monitor;

#[derive(Args, Debug, Clone)]
pub struct StatusArgs {
    /// The store (MAP.zarr).
    pub store: PathBuf,
    /// Name the `--tile INDEX/COUNT` runs for this COUNT [default: the count the store was
    /// made with].
    #[arg(long, value_parser = parse_u32)]
    pub tiles: Option<u32>,
}

/// What a store lacks, in words on standard output (on standard error with `json`, whose
/// standard output holds the summary alone).
pub fn status(args: &StatusArgs, json_out: bool) -> Result<serde_json::Value> {
    let s = store::status(&StatusJob {
        store: args.store.clone(),
        tiles: args.tiles,
    })?;
    let mut text = format!(
        "{}: {}x{} map, {} of {} chunks written\n",
        s.store.display(),
        s.width,
        s.height,
        s.written,
        s.chunks
    );
    if s.complete {
        text += "complete\n";
    } else {
        let rows: Vec<String> = s
            .missing
            .iter()
            .map(|(first, rows)| format!("{first}..{}", first + rows))
            .collect();
        text += &format!("missing rows: {}\n", rows.join(", "));
        let tiles: Vec<String> = s.tiles_to_run.iter().map(u32::to_string).collect();
        text += &format!(
            "to fill them: --tile I/{} for I in {} (with the store's command: {})\n",
            s.tiles,
            tiles.join(" "),
            s.command
        );
    }
    match json_out {
        true => eprint!("{text}"),
        false => super::out(&text)?,
    }
    json(&s)
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// The store (MAP.zarr).
    pub store: PathBuf,
    /// PNG to write.
    #[arg(long, default_value = "out/map.png")]
    pub output: PathBuf,
    /// The picture's larger side at most, taking every n-th pixel each way [default: the
    /// map's full size].
    #[arg(long, value_parser = parse_u32)]
    pub max_size: Option<u32>,
    #[command(flatten)]
    pub picture: PictureArgs,
}

pub fn render(args: &RenderArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let (command, spec) = store::stored_map(&args.store)?;
    let job = RenderJob {
        store: args.store.clone(),
        spec,
        picture: args.picture.spec(),
        output: args.output.clone(),
        max_size: args.max_size,
    };
    let s = store::render(&job, command, monitor)?;
    say("render", &s.notices);
    eprintln!(
        "{}x{} picture ({}) in {:.2} s -> {}",
        s.width,
        s.height,
        match s.step {
            1 => "every pixel".to_string(),
            n => format!("every {n}th pixel each way"),
        },
        s.seconds,
        s.output.display()
    );
    json(&s)
}
