use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(chaoscope::cli::main(std::env::args_os()))
}
