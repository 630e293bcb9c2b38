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
