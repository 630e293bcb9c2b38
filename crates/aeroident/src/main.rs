//! The `aeroident` command-line program. It only parses arguments; see [`aeroident::cli`].

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    match aeroident::cli::Cli::parse().execute() {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`| head`): end quietly, as a filter should.
        Err(e) if aeroident::cli::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", aeroident::cli::error_chain(&e));
            ExitCode::FAILURE
        }
    }
}
