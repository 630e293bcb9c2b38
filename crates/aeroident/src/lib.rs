//! # aeroident
//!
//! The command-line face of aeroident: argument parsing ([`cli`]), signals ([`interrupt`]),
//! the live MAVLink front end ([`live`]) and progress on the terminal ([`progress`]), over the
//! jobs and pipelines of [`aeroident_pipelines`], rendered by [`aeroident_report`]. `main.rs`
//! only parses arguments; every command is a function here so tests can call it directly.

pub mod cli;
pub mod interrupt;
pub mod live;
pub mod progress;

/// The rendering modules, under the paths the command line has always used for them.
pub use aeroident_report::{aircraft, console, outdir, plot, poc, report, sim, table};

/// The whole program on `args` (the first is the program's name, as `std::env::args_os`):
/// parse, run, report an error on stderr; the process exit code (0 success, 1 failure, 2 a
/// usage error, `128 + signal` for a run ended by a signal). `main.rs` and the Python
/// package's `aeroident` console script call it.
pub fn run_main<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match cli::Cli::try_parse_args(args) {
        Ok(cli) => cli,
        Err(e) => {
            // `--help` and `--version` print to stdout and succeed; usage errors go to stderr.
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    aeroident_pipelines::install_worker_stacks();
    match cli.execute() {
        Ok(()) => 0,
        // The reader of our output went away (`| head`): end quietly, as a filter should.
        Err(e) if cli::is_broken_pipe(&e) => 0,
        Err(e) => {
            aeroident_report::note!("error: {}", cli::error_chain(&e));
            e.downcast_ref::<interrupt::Interrupted>().map_or(1, |i| i.exit_code())
        }
    }
}
