//! The `jetid` binary: parse arguments, dispatch, print an error once, return the exit code.
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = match jetid::cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            let is_error = err.use_stderr();
            // Help and version go to stdout with status 0; usage errors exit 1 like every other error.
            let _ = err.print();
            return if is_error { ExitCode::FAILURE } else { ExitCode::SUCCESS };
        }
    };
    match jetid::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", jetid::cli::error_message(&err));
            ExitCode::FAILURE
        }
    }
}
