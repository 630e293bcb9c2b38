//! The `aeroident` command-line program. It only parses arguments; see [`aeroident::cli`].

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    match aeroident::cli::Cli::parse().execute() {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`| head`): end quietly, as a filter should.
        Err(e) if aeroident::cli::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line ("file:line: field: reason"), with no backtrace
/// whatever RUST_BACKTRACE says: errors here are problems with the user's input. Some error
/// types print their source in their own message and some do not, so a cause is appended only
/// when the text so far does not already contain it.
fn error_chain(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg
}
