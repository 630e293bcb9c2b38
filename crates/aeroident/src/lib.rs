//! # aeroident
//!
//! The application crate: experiments (trim → fly → sense → estimate), reports, figures and
//! the `aeroident` command-line interface. `main.rs` only parses arguments; every command is a
//! function here so tests can call it directly.

/// Aircraft estimation experiments: two F-16s, sensors, estimators (issue 4).
pub mod aircraft;
pub mod cli;
pub mod estimators;
pub mod export;
pub mod live;
/// Convergence-time and error metrics of estimate histories.
pub mod metrics;
pub mod montecarlo;
pub mod outdir;
/// Stacked time-series panels rendered to PNG and SVG.
pub mod plot;
/// Proof-of-concept experiments (thesis §4.1): scenarios, simulation loop, outputs, report.
pub mod poc;
pub mod progress;
pub mod replay;
pub mod report;
pub mod results;
pub mod sample_log;
pub mod scenario_kind;
/// Open-loop F-16 simulation: trim → inputs, gusts, turbulence → sensors → CSV and figures.
pub mod sim;
pub mod table;
/// Model validation metrics: fit, residual whiteness, input correlation, prediction intervals.
pub mod validation;
