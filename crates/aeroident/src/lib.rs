//! # aeroident
//!
//! The command-line face of aeroident: argument parsing ([`cli`]), rendering (reports, figures,
//! tables) and printing, over the pipelines of [`aeroident_pipelines`]. `main.rs` only parses
//! arguments; every command is a function here so tests can call it directly.

/// Outputs of the closed-loop experiment: files, console table, figures.
pub mod aircraft;
pub mod cli;
pub mod console;
pub mod interrupt;
pub mod live;
pub mod outdir;
/// Stacked time-series panels rendered to PNG and SVG.
pub mod plot;
/// Proof-of-concept outputs: CSV, JSON, figures and the thesis-versus-ours report.
pub mod poc;
pub mod progress;
pub mod report;
/// `aeroident f16 sim`: the open-loop simulation's files and figures.
pub mod sim;
pub mod table;
