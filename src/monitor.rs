//! Progress and interruption for long runs: a progress bar on a terminal, plain log lines
//! every few seconds elsewhere (a log file, a batch job), and a cancel flag that Ctrl-C sets
//! and every long loop checks.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use crate::error::{Error, Result};

/// Seconds between log lines when stderr is not a terminal, unless the environment's
/// CHAOSCOPE_PROGRESS_SECONDS says otherwise.
fn log_every() -> Duration {
    std::env::var("CHAOSCOPE_PROGRESS_SECONDS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .map_or(Duration::from_secs(10), Duration::from_secs_f64)
}

#[derive(Clone)]
pub struct Monitor {
    bar: ProgressBar,
    /// Log lines instead of a bar (stderr is not a terminal).
    log: Option<Arc<Mutex<LogState>>>,
    /// The current phase's whole work, when a caller knows it (see `estimate`).
    estimate: Arc<Mutex<Option<f64>>>,
    cancel: Arc<AtomicBool>,
}

struct LogState {
    every: Duration,
    phase: String,
    total: u64,
    done: u64,
    started: Instant,
    last: Instant,
}

impl Monitor {
    /// No bar, never cancelled: for tests and library callers.
    pub fn hidden() -> Self {
        Monitor {
            bar: ProgressBar::hidden(),
            log: None,
            estimate: Arc::default(),
            cancel: Arc::new(AtomicBool::new(false)),
        }
    }

    /// No bar, cancelled through `cancel`: work run for someone who may go away (the
    /// explorer's requests).
    pub fn cancelled_by(cancel: Arc<AtomicBool>) -> Self {
        Monitor {
            cancel,
            ..Monitor::hidden()
        }
    }

    /// Whether the user asked to stop.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// A bar on stderr when it is a terminal, else log lines; cancelled through `cancel`.
    pub fn terminal(cancel: Arc<AtomicBool>) -> Self {
        let logs = !std::io::stderr().is_terminal();
        Monitor {
            bar: if logs {
                ProgressBar::hidden()
            } else {
                ProgressBar::new(0)
            },
            log: logs.then(|| {
                Arc::new(Mutex::new(LogState {
                    every: log_every(),
                    phase: String::new(),
                    total: 0,
                    done: 0,
                    started: Instant::now(),
                    last: Instant::now(),
                }))
            }),
            estimate: Arc::default(),
            cancel,
        }
    }

    /// No bar, but cancelled with this one: for work nested inside a phase with its own bar.
    pub fn quiet(&self) -> Self {
        Monitor {
            bar: ProgressBar::hidden(),
            log: None,
            estimate: Arc::default(),
            cancel: self.cancel.clone(),
        }
    }

    /// Starts a phase of `total` units of work.
    pub fn start(&self, message: &str, total: u64) {
        self.bar.set_style(
            ProgressStyle::with_template(
                "{msg:>10} [{bar:40}] {percent:>3}% {elapsed_precise} eta {eta}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        self.bar.set_message(message.to_string());
        self.bar.set_length(total);
        self.bar.set_position(0);
        self.bar.reset_eta();
        if let Some(log) = &self.log
            && let Ok(mut s) = log.lock()
        {
            let now = Instant::now();
            *s = LogState {
                every: s.every,
                phase: message.to_string(),
                total,
                done: 0,
                started: now,
                last: now,
            };
        }
    }

    /// Says how much work the next phase will take in all, when known better than its
    /// running estimate (`start` keeps it for the phase it starts).
    pub fn estimate(&self, units: f64) {
        if let Ok(mut e) = self.estimate.lock() {
            *e = Some(units);
        }
    }

    /// The whole phase's estimated work, if one was given.
    pub fn estimated(&self) -> Option<f64> {
        self.estimate.lock().ok().and_then(|e| *e)
    }

    /// The current phase's name, work done and whole work (if known): for a caller that
    /// shows progress its own way (Python's tqdm).
    pub fn progress(&self) -> (String, u64, Option<u64>) {
        (self.bar.message(), self.bar.position(), self.bar.length())
    }

    /// Work done so far in this phase.
    pub fn position(&self) -> u64 {
        self.bar.position()
    }

    /// Sets the phase's total to the work done so far plus `units` still expected.
    pub fn expect(&self, units: u64) {
        let done = self.bar.position();
        self.bar.set_length(done + units);
        if let Some(log) = &self.log
            && let Ok(mut s) = log.lock()
        {
            s.total = s.done + units;
        }
    }

    pub fn advance(&self, units: u64) {
        self.bar.inc(units);
        if let Some(log) = &self.log
            && let Ok(mut s) = log.lock()
        {
            s.done = (s.done + units).min(s.total);
            let now = Instant::now();
            if now - s.last >= s.every {
                s.last = now;
                let elapsed = (now - s.started).as_secs_f64();
                let fraction = s.done as f64 / s.total.max(1) as f64;
                let eta = if s.done > 0 {
                    format!("{:.0} s", elapsed * (1.0 - fraction) / fraction)
                } else {
                    "unknown".into()
                };
                eprintln!(
                    "{}: {:.0} % ({} of {}), {elapsed:.0} s elapsed, eta {eta}",
                    s.phase,
                    100.0 * fraction,
                    s.done,
                    s.total
                );
            }
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
        if let Ok(mut e) = self.estimate.lock() {
            *e = None;
        }
    }

    /// Err(Interrupted) once the user asked to stop.
    pub fn check(&self) -> Result<()> {
        if self.cancel.load(Ordering::Relaxed) {
            Err(Error::Interrupted)
        } else {
            Ok(())
        }
    }
}
