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
            eprintln!("error: {}", message(&err));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", each said once: an error whose message already quotes
/// its cause (`segmentation of 'run': no steps found …`) does not get the cause appended again.
fn message(err: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}
