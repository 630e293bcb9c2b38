//! # aeroident-report
//!
//! The rendering of the pipelines' outcomes, for every face: `report.html` ([`report`]),
//! figures in PNG and SVG ([`plot`]), console tables ([`table`]), the output directory a run
//! writes into ([`outdir`]: locked, the previous run's files cleared), and the files of the
//! closed-loop experiment, the proof-of-concept cases and the open-loop simulation. It
//! computes nothing the pipelines do not: it lays out what an outcome holds.

/// Outputs of the closed-loop experiment: files, console table, figures.
pub mod aircraft;
pub mod console;
pub mod interactive;
pub mod outdir;
pub mod outfile;
/// Stacked time-series panels rendered to PNG and SVG.
pub mod plot;
/// Proof-of-concept outputs: CSV, JSON, figures and the thesis-versus-ours report.
pub mod poc;
pub mod report;
/// `aeroident f16 sim`: the open-loop simulation's files and figures.
pub mod sim;
pub mod table;
