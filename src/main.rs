use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use chaoscope::cli::{Cli, run};
use chaoscope::monitor::Monitor;
use chaoscope::render::remove_pending;

fn main() -> ExitCode {
    let cli = Cli::parse_args(std::env::args_os()).unwrap_or_else(|e| e.exit());
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    // First Ctrl-C (or SIGTERM, SIGHUP): stop at the next dispatch, row or chunk and leave no
    // partial file; second: now, removing the temporary files being written.
    let _ = ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::Relaxed) {
            remove_pending();
            std::process::exit(130);
        }
    });
    run(cli, &Monitor::terminal(cancel))
}
