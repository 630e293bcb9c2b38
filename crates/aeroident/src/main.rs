//! The `aeroident` command-line program. It only parses arguments; see [`aeroident::cli`].

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    match aeroident::cli::Cli::parse().execute() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}` prints the whole context chain on one line ("reading x.toml: line 3: ...")
            // without a backtrace, whatever RUST_BACKTRACE says: errors here are the user's
            // input problems, and the chain names the file, line and field.
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
