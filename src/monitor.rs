//! Progress and interruption for long runs: a progress bar (hidden when stderr is not a
//! terminal) and a cancel flag that Ctrl-C sets and every long loop checks.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use indicatif::{ProgressBar, ProgressStyle};

use crate::error::{Error, Result};

#[derive(Clone)]
pub struct Monitor {
    bar: ProgressBar,
    cancel: Arc<AtomicBool>,
}

impl Monitor {
    /// No bar, never cancelled: for tests and library callers.
    pub fn hidden() -> Self {
        Monitor {
            bar: ProgressBar::hidden(),
            cancel: Arc::new(AtomicBool::new(false)),
        }
    }

    /// A bar on stderr, cancelled through `cancel`.
    pub fn terminal(cancel: Arc<AtomicBool>) -> Self {
        Monitor {
            bar: ProgressBar::new(0),
            cancel,
        }
    }

    /// No bar, but cancelled with this one: for work nested inside a phase with its own bar.
    pub fn quiet(&self) -> Self {
        Monitor {
            bar: ProgressBar::hidden(),
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
    }

    pub fn advance(&self, units: u64) {
        self.bar.inc(units);
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
