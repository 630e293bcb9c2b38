//! The `aeroident` command-line program. It only parses arguments; see [`aeroident::cli`].

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(aeroident::run_main(std::env::args_os()))
}
