//! The `aeroident` command-line program. It only parses arguments; see [`aeroident::cli`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = aeroident::cli::Cli::try_parse_args(std::env::args_os()).unwrap_or_else(|e| e.exit());
    aeroident_pipelines::install_worker_stacks();
    match cli.execute() {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`| head`): end quietly, as a filter should.
        Err(e) if aeroident::cli::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            aeroident_report::note!("error: {}", aeroident::cli::error_chain(&e));
            // A run ended by a signal exits as the shell expects of one (128 + signal).
            e.downcast_ref::<aeroident::interrupt::Interrupted>()
                .map_or(ExitCode::FAILURE, |i| ExitCode::from(i.exit_code()))
        }
    }
}
