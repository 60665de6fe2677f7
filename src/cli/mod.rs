//! The command line: the only place that knows flag names and prints. Flags become jobs
//! (`src/app`), jobs run, summaries become words; library errors name a job's field, which
//! `names` turns back into the flag the user typed.

mod args;
mod bench;
mod boundary;
pub mod command_line;
mod fit;
mod flip;
mod forecast;
mod info;
mod lyapunov;
mod names;
pub mod parse;
mod phase;
mod serve;
mod shell;
mod store;
mod sweep;
mod traces;
mod track;
mod trajectory;
mod twin;
mod web;
mod zoom;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::error::Error;
use crate::monitor::Monitor;

pub use lyapunov::LyapunovJob;

#[derive(Parser, Debug)]
#[command(
    name = "chaoscope",
    version,
    about = "Chaos in the double pendulum, millions of pendulums at once"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Also print the run's summary (figures, files written, where it ran, seconds) as one
    /// JSON object on standard output, for scripts and notebooks.
    #[arg(long, global = true)]
    pub json: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Flip-time map: time until either arm first flips over, for a grid of starts.
    Flip(flip::FlipArgs),
    /// Divergence map: the largest finite-time Lyapunov exponent (1/s) of every start; with
    /// single angles (--theta1 A --theta2 B), its convergence over time as CSV `t,ftle`.
    Lyapunov(lyapunov::LyapunovArgs),
    /// One trajectory as CSV: t,theta1,omega1,theta2,omega2,x1,y1,x2,y2,energy,dissipated
    /// (after a `#` line with the command that reproduces it).
    Trajectory(trajectory::TrajectoryArgs),
    /// How fractal a flip map's class boundary is: the uncertainty exponent alpha of seeded
    /// pairs of starts eps apart, fitted over several eps, and the boundary's dimension
    /// D = 2 - alpha, with a log-log plot.
    Boundary(boundary::BoundaryArgs),
    /// Frames of a map while a parameter changes (--vary), as numbered PNGs and an animated
    /// PNG; an interrupted sweep resumes where it stopped.
    Sweep(sweep::SweepArgs),
    /// A film zooming from a map's plane into a view of it (or through several): every frame
    /// the map of its view in the precision its pixel step needs (f32, then f64, refused past
    /// f64), numbered PNGs that resume and split over tasks (--tile), then an MP4.
    Zoom(zoom::ZoomArgs),
    /// Long-exposure light trails of the lower bob for releases from "the same" start.
    Traces(traces::TracesArgs),
    /// Phase portraits, omega against theta of each arm, as time-density images; --single for
    /// the single pendulum with its separatrix.
    Phase(phase::PhaseArgs),
    /// The positions of both masses in every frame of a film of the pendulum (bright or
    /// coloured markers), as the CSV fit and forecast read: the pivot and scale from the
    /// markers' own geometry, each row measured or not seen, with its uncertainty.
    Track(track::TrackArgs),
    /// Fit the model to a camera's tracked positions: pivot, arm lengths, energies and their
    /// decay, the state and damping by a GPU ensemble search; plots and summary.json.
    Fit(fit::FitArgs),
    /// How long the model follows tracked data: fit on --window, then an ensemble drawn from
    /// the fit's uncertainty to the data's end; bands, horizons, the FTLE along the orbit and
    /// the horizon in Lyapunov times; forecast.png, bands.csv, summary.json.
    Forecast(forecast::ForecastArgs),
    /// Twin experiments of the forecast: tracks made by the model (a chaotic release of the
    /// lab pendulum) with position noise, fitted and forecast; the truth's coverage by the
    /// 90 % band and the horizon against the noise, beside -1/lambda.
    Twin(twin::TwinArgs),
    /// The explorer: a local web page to zoom into flip, divergence and verdict maps computed
    /// on demand, and to watch a clicked pixel's pendulum.
    Serve(serve::ServeArgs),
    /// The explorer as a folder of static files: a page that computes flip-time maps with
    /// WebGPU on the viewer's own GPU, to host on any web server or course page.
    Web(web::WebArgs),
    /// What a Zarr store of a map (flip --data MAP.zarr) still lacks, and which --tile runs
    /// would fill it.
    Status(store::StatusArgs),
    /// A PNG of a Zarr store's map, read band by band (optionally every n-th pixel).
    Render(store::RenderArgs),
    /// GPU adapters found, the one chosen, its limits and features.
    Info,
    /// Throughput of the GPU and CPU paths on FLIP-512, optionally beside the peers.
    Bench(bench::BenchArgs),
    /// A shell completion script on standard output, e.g.
    /// `chaoscope completions bash > ~/.local/share/bash-completion/completions/chaoscope`.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::Cli;

    /// Every flag and argument of every command says what it is.
    #[test]
    fn every_flag_has_help() {
        let cli = Cli::command();
        let missing: Vec<String> = cli
            .get_subcommands()
            .flat_map(|sub| {
                sub.get_arguments()
                    .filter(|a| {
                        let id = a.get_id().as_str();
                        let help = a.get_help().map(|h| h.to_string()).unwrap_or_default();
                        !["help", "version"].contains(&id) && help.trim().is_empty()
                    })
                    .map(|a| format!("{} {}", sub.get_name(), a.get_id()))
                    .collect::<Vec<_>>()
            })
            .collect();
        assert!(missing.is_empty(), "flags without help: {missing:?}");
    }
}

/// The job a parsed command line describes (for checking that a stored command line
/// reproduces its run): flip, lyapunov, trajectory, sweep, traces, phase and fit.
#[derive(Clone, Debug, PartialEq)]
pub enum Job {
    Flip(crate::app::flip::FlipJob),
    Lyapunov(LyapunovJob),
    Trajectory(crate::app::trajectory::TrajectoryJob),
    Sweep(crate::app::sweep::SweepJob),
    Boundary(Box<crate::app::boundary::BoundaryJob>),
    Traces(crate::app::traces::TracesJob),
    Phase(crate::app::phase::PhaseJob),
    Fit(crate::app::fit::FitJob),
    Forecast(crate::app::forecast::ForecastJob),
    Twin(crate::app::twin::TwinJob),
}

impl Command {
    /// The command's name, as typed.
    pub fn name(&self) -> &'static str {
        match self {
            Command::Flip(_) => "flip",
            Command::Lyapunov(_) => "lyapunov",
            Command::Trajectory(_) => "trajectory",
            Command::Sweep(_) => "sweep",
            Command::Zoom(_) => "zoom",
            Command::Boundary(_) => "boundary",
            Command::Traces(_) => "traces",
            Command::Track(_) => "track",
            Command::Phase(_) => "phase",
            Command::Fit(_) => "fit",
            Command::Forecast(_) => "forecast",
            Command::Twin(_) => "twin",
            Command::Serve(_) => "serve",
            Command::Web(_) => "web",
            Command::Status(_) => "status",
            Command::Render(_) => "render",
            Command::Info => "info",
            Command::Bench(_) => "bench",
            Command::Completions { .. } => "completions",
        }
    }

    /// The job of a command that makes files; None for info and bench.
    pub fn job(&self) -> crate::Result<Option<Job>> {
        Ok(Some(match self {
            Command::Flip(a) => Job::Flip(a.job()?),
            Command::Lyapunov(a) => Job::Lyapunov(a.job()?),
            Command::Trajectory(a) => Job::Trajectory(a.job()?),
            Command::Sweep(a) => Job::Sweep(a.job()?),
            Command::Boundary(a) => Job::Boundary(Box::new(a.job()?)),
            Command::Traces(a) => Job::Traces(a.job()?),
            Command::Phase(a) => Job::Phase(a.job()?),
            Command::Fit(a) => Job::Fit(a.job()),
            Command::Forecast(a) => Job::Forecast(a.job()),
            Command::Twin(a) => Job::Twin(a.job()),
            Command::Info
            | Command::Bench(_)
            | Command::Completions { .. }
            | Command::Serve(_)
            | Command::Web(_)
            | Command::Track(_)
            | Command::Zoom(_)
            | Command::Status(_)
            | Command::Render(_) => return Ok(None),
        }))
    }
}

impl Cli {
    /// Parses `args` (the program name first) as `Cli::try_parse_from` does, after one
    /// check of its own: a flag that takes a value followed directly by another flag of the
    /// command. Numbers may start with `-` (`-pi`), so clap would take `--cw` in
    /// `--l1 --cw 2` as the value of `--l1` and then stop at the stray `2` without naming
    /// `--l1`; this names it. Every flag's value may start with `-`, so that a negative
    /// value given as its own word (`--exponent -1`) reaches the flag's own check, which
    /// names the flag and its range, instead of clap's "unexpected argument '-1'".
    pub fn parse_args<I, T>(args: I) -> Result<Cli, clap::Error>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        use clap::CommandFactory;
        let args: Vec<std::ffi::OsString> = args.into_iter().map(Into::into).collect();
        let hyphens = |a: clap::Arg| {
            let one_value = a.get_num_args().is_none_or(|n| n.max_values() == 1);
            match a.get_long().is_some() && a.get_action().takes_values() && one_value {
                true => a.allow_hyphen_values(true),
                false => a,
            }
        };
        // A zoom's map (`zoom ... flip ...`) is a command of its own one level down.
        let mut command = Cli::command().mut_subcommands(|sub| {
            sub.mut_args(hyphens)
                .mut_subcommands(|map| map.mut_args(hyphens))
        });
        let words: Vec<String> = args
            .iter()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        if let Some(sub) = words.get(1).and_then(|name| command.find_subcommand(name)) {
            let takes_value = |long: &str| {
                sub.get_arguments()
                    .find(|a| a.get_long() == Some(long))
                    .map(|a| a.get_action().takes_values())
            };
            for pair in words[2..].windows(2) {
                let (Some(flag), Some(next)) =
                    (pair[0].strip_prefix("--"), pair[1].strip_prefix("--"))
                else {
                    continue;
                };
                if takes_value(flag) == Some(true) && takes_value(next).is_some() {
                    return Err(command.error(
                        clap::error::ErrorKind::InvalidValue,
                        format!(
                            "a value is required for '--{flag}' but none was supplied (found the flag '--{next}' instead)"
                        ),
                    ));
                }
            }
        }
        use clap::FromArgMatches;
        let mut matches = command.try_get_matches_from_mut(args)?;
        Cli::from_arg_matches_mut(&mut matches).map_err(|e| e.format(&mut command))
    }
}

fn json_needs_output() -> crate::Error {
    crate::Error::invalid(
        "json",
        "needs --output here: without it the CSV itself goes to standard output",
    )
}

/// A run's summary as JSON.
fn json(summary: &impl serde::Serialize) -> crate::Result<serde_json::Value> {
    serde_json::to_value(summary).map_err(|e| crate::Error::Format(format!("summary: {e}")))
}

/// `text` on standard output; a reader that went away (`status ... | head`) ends the
/// output quietly instead of a panic.
pub fn out(text: &str) -> crate::Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// Notices from a run of `command`, one a line, the settings they name as its flags.
fn say(command: &str, notices: &[String]) {
    for n in notices {
        eprintln!("{}", spelt(command, n));
    }
}

/// `text` with the settings it names (`crate::error::spell`) as `command`'s flags:
/// `--precision f64`.
pub fn spelt(command: &str, text: &str) -> String {
    crate::error::spell(text, |field, value| {
        let flag = names::flag(command, field);
        match value {
            Some(v) => format!("{flag} {v}"),
            None => flag,
        }
    })
}

/// The exit status of a fit that ran but whose model does not follow its data (`fit`,
/// `forecast`): the outputs are written, the verdict is in them.
pub const UNFOLLOWED: u8 = 3;

/// Runs a parsed command. Invalid values exit 2 (like clap's own errors) naming the flag,
/// an interruption 130, other failures 1.
pub fn run(cli: Cli, monitor: &Monitor) -> ExitCode {
    ExitCode::from(run_code(cli, monitor))
}

/// The command line of a process: `args` parsed (clap's errors and --help exit here), run
/// with Ctrl-C feeding the monitor's cancel flag; the exit status. The binary's `main`, and
/// the Python wheel's `chaoscope` command.
pub fn main<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let cli = Cli::parse_args(args).unwrap_or_else(|e| e.exit());
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    // First Ctrl-C (or SIGTERM, SIGHUP): stop at the next dispatch, row or chunk and leave no
    // partial file; second: now, removing the temporary files being written.
    // FFmpeg's programs stop at once: the run may be blocked on one that stalled.
    let _ = ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::Relaxed) {
            crate::render::remove_pending();
            std::process::exit(130);
        }
        crate::video::stop_all();
    });
    run_code(cli, &Monitor::terminal(cancel))
}

/// [`run`]'s exit status as a number.
pub fn run_code(cli: Cli, monitor: &Monitor) -> u8 {
    let command = cli.command.name();
    let started = std::time::Instant::now();
    let result = match &cli.command {
        // Their CSV goes to standard output without --output: no room for JSON there too.
        Command::Trajectory(a) if cli.json && a.output.is_none() => Err(json_needs_output()),
        // Only a single-point run's CSV goes there; a map writes its PNG or store.
        Command::Lyapunov(a)
            if cli.json && a.output.is_none() && matches!(a.job(), Ok(LyapunovJob::Point(_))) =>
        {
            Err(json_needs_output())
        }
        Command::Flip(args) => flip::run(args, monitor),
        Command::Lyapunov(args) => lyapunov::run(args, monitor),
        Command::Trajectory(args) => trajectory::run(args, monitor),
        Command::Sweep(args) => sweep::run(args, monitor),
        Command::Zoom(args) => zoom::run(args, monitor),
        Command::Boundary(args) => boundary::run(args, monitor),
        Command::Traces(args) => traces::run(args, monitor),
        Command::Track(args) => track::run(args, monitor),
        Command::Phase(args) => phase::run(args, monitor),
        Command::Fit(args) => fit::run(args, monitor),
        Command::Forecast(args) => forecast::run(args, monitor),
        Command::Twin(args) => twin::run(args, monitor),
        Command::Serve(args) => serve::run(args, monitor, cli.json),
        Command::Web(args) => web::run(args, monitor),
        Command::Status(args) => store::status(args, cli.json),
        Command::Render(args) => store::render(args, monitor),
        Command::Info => info::run(cli.json),
        Command::Bench(args) => bench::run(args, monitor, cli.json),
        // A shell script is no summary: there is no JSON to give.
        Command::Completions { .. } if cli.json => Err(Error::invalid(
            "json",
            "completions writes a shell script to standard output, not a summary",
        )),
        Command::Completions { shell } => {
            use clap::CommandFactory;
            use std::io::Write;
            // Into memory first: clap_complete panics on a failed write (a full disk, a
            // closed pipe), which must be an error instead.
            let mut script = Vec::new();
            clap_complete::generate(*shell, &mut Cli::command(), "chaoscope", &mut script);
            let mut out = std::io::stdout().lock();
            out.write_all(&script)
                .and_then(|()| out.flush())
                .map(|()| serde_json::Value::Null)
                .map_err(Error::from)
        }
    };
    // A run stopped by Ctrl-C may fail where it was waiting (a pipe to an FFmpeg that was
    // stopped with it): it was interrupted, whatever the failure says.
    let result = match result {
        Err(_) if monitor.is_cancelled() => Err(Error::Interrupted),
        other => other,
    };
    let result = result.map(|mut summary| {
        // A fit whose model does not follow its data ran to the end and wrote its outputs,
        // but its figures are no findings: scripts learn it from the status.
        let unfollowed =
            summary.pointer("/verdict/follows") == Some(&serde_json::Value::Bool(false));
        if cli.json && !summary.is_null() {
            if let Some(object) = summary.as_object_mut() {
                object.insert("command".into(), command.into());
                if let Some(serde_json::Value::Array(notices)) = object.get_mut("notices") {
                    for n in notices.iter_mut() {
                        if let serde_json::Value::String(text) = n {
                            *text = spelt(command, text);
                        }
                    }
                }
                object
                    .entry("seconds")
                    .or_insert(started.elapsed().as_secs_f64().into());
            }
            println!("{summary}");
        }
        unfollowed
    });
    match result {
        Ok(false) => 0,
        Ok(true) => UNFOLLOWED,
        Err(Error::InvalidSpec { field, reason }) => {
            eprintln!(
                "error: invalid value for {}: {}",
                names::flag(command, field),
                spelt(command, &reason)
            );
            2
        }
        Err(Error::SameFile {
            field,
            other,
            path,
            input,
        }) => {
            let what = match input {
                true => "this run reads: writing it would replace it",
                false => "of this run: each output needs a file of its own",
            };
            eprintln!(
                "error: invalid value for {}: {} is also the {} file {what}",
                names::flag(command, field),
                path.display(),
                names::flag(command, other)
            );
            2
        }
        Err(Error::Missing { field, path }) => {
            eprintln!(
                "error: invalid value for {}: {}: no such file",
                names::flag(command, field),
                path.display()
            );
            2
        }
        Err(Error::StoreDiffers {
            field,
            path,
            differences,
            command: made_by,
        }) => {
            let what: Vec<String> = differences
                .iter()
                .map(|(setting, theirs, ours)| {
                    let flag = names::flag(command, setting);
                    format!("`{flag} {theirs}` where this run has `{flag} {ours}`")
                })
                .collect();
            eprintln!(
                "error: invalid value for {}: {} was made by another command: it has {} (its command: {made_by})",
                names::flag(command, field),
                path.display(),
                what.join(", ")
            );
            2
        }
        Err(e) => {
            eprintln!("error: {e}");
            match e {
                Error::Interrupted => 130,
                _ => 1,
            }
        }
    }
}
