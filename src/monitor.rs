//! Progress and interruption for long runs: a progress bar on a terminal, plain log lines
//! every few seconds elsewhere (a log file, a batch job), and a cancel flag that Ctrl-C sets
//! and every long loop checks.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use crate::error::{Error, Result};

/// Seconds between log lines when stderr is not a terminal.
const LOG_EVERY: Duration = Duration::from_secs(10);

#[derive(Clone)]
pub struct Monitor {
    bar: ProgressBar,
    /// Log lines instead of a bar (stderr is not a terminal).
    log: Option<Arc<Mutex<LogState>>>,
    cancel: Arc<AtomicBool>,
}

struct LogState {
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
            cancel: Arc::new(AtomicBool::new(false)),
        }
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
                    phase: String::new(),
                    total: 0,
                    done: 0,
                    started: Instant::now(),
                    last: Instant::now(),
                }))
            }),
            cancel,
        }
    }

    /// No bar, but cancelled with this one: for work nested inside a phase with its own bar.
    pub fn quiet(&self) -> Self {
        Monitor {
            bar: ProgressBar::hidden(),
            log: None,
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
                phase: message.to_string(),
                total,
                done: 0,
                started: now,
                last: now,
            };
        }
    }

    pub fn advance(&self, units: u64) {
        self.bar.inc(units);
        if let Some(log) = &self.log
            && let Ok(mut s) = log.lock()
        {
            s.done = (s.done + units).min(s.total);
            let now = Instant::now();
            if now - s.last >= LOG_EVERY {
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
