//! # aeroident-pipelines
//!
//! The pipelines of aeroident, from samples to one outcome value, with no command line, no
//! printing and no drawing: the command-line program (`aeroident`) and the Python module are
//! two thin faces over this crate, and the reports and figures render its outcomes.
//!
//! - [`job`]: the replay job and the batch-fit job a face runs, from options to one outcome.
//! - [`live`]: the live view of a replay (per-derivative states, history, the feed's counts)
//!   that a server streams to a browser.
//! - [`replay`]: a recorded (or streamed) flight through an estimator, online or as a batch
//!   fit ([`replay::batch`]), with validation on a second record.
//! - [`aircraft`]: the closed-loop experiment (trim → fly → sense → estimate → summarise).
//! - [`airframe`]: an aircraft built from identified derivatives (model file, summary,
//!   mapping), trimmed, linearized and flown like the F-16.
//! - [`montecarlo`]: seeded campaigns of the experiment and their statistics.
//! - [`poc`]: the thesis's proof-of-concept systems; [`sim`]: open-loop F-16 simulation.
//! - [`export`]: input design and the JSBSim `<aerodynamics>` export.
//! - [`freqresp`]: frequency responses (composite windows, coherence) and transfer-function fits.
//! - [`inspect`]: what a log holds and its candidate manoeuvres (`aeroident inspect`).
//! - [`record`]: the record stage below every job (read → map → screen → correct → window →
//!   manoeuvres), with its own error type.
//! - [`condition`]: the conditioning stage every pipeline shares (derivatives, alignment);
//!   [`window`]: the time windows of a long record, each a manoeuvre.
//! - [`estimators`], [`verdict`], [`plausibility`], [`Named`]: the estimator registry and the
//!   per-estimate verdict, re-exported from `aeroident-registry` (the crate the C library
//!   links instead of this one).
//! - [`summary_file`]: a replay's `summary.json` read back (what the exports and the airframe
//!   take).

/// Aircraft estimation experiments: two F-16s, sensors, estimators.
pub mod aircraft;
/// An aircraft flying identified derivatives (model file + summary + mapping).
pub mod airframe;
pub mod compat;
pub mod condition;
pub mod error;
pub use aeroident_registry::estimators;
pub mod export;
pub mod freqresp;
pub mod inspect;
pub mod job;
pub mod kinematics;
pub mod live;
/// Convergence-time and error metrics of estimate histories.
pub mod metrics;
pub mod montecarlo;
pub use aeroident_registry::{named, plausibility};
/// Proof-of-concept experiments (thesis §4.1): scenarios and the simulation loop.
pub mod poc;
pub mod record;
pub mod replay;
pub mod results;
pub mod sample_log;
pub mod scenario_kind;
/// Open-loop F-16 simulation: trim → inputs, gusts, turbulence → sensors.
pub mod sim;
pub mod structure;
pub mod summary_file;
/// Model validation metrics: fit, residual whiteness, input correlation, prediction intervals.
pub mod validation;
pub use aeroident_registry::verdict;
pub mod window;

pub use error::{Context, PipelineError};
pub use named::Named;

/// Stack size, bytes, for the threads that fly, replay and fit (rayon workers, fit threads):
/// margin over the 2 MiB default of a spawned thread, which every six-axis run fits in.
///
/// The estimators are fixed-capacity and allocation-free (the core is `no_std`), so each is
/// built by value before it is boxed ([`estimators::build`], one estimator on the stack at a
/// time). Measured with `crates/aeroident/examples/stack_need.rs`, a six-axis run needs at
/// most 1.2 MiB (`replay --estimator rls-iv`; `aeroident run` and `montecarlo` 0.6 MiB). The
/// CLI and Python give this to every thread pool they build, `.cargo/config.toml` to test
/// threads (`RUST_MIN_STACK`); it is address space reserved per thread, not memory used.
pub const WORKER_STACK_BYTES: usize = 8 << 20;

/// Makes rayon's global pool use [`WORKER_STACK_BYTES`] stacks. Call before any parallel work;
/// a pool already built keeps its stacks (the call then does nothing).
pub fn install_worker_stacks() {
    // An error only says the global pool exists already: nothing to do then.
    let _ = rayon::ThreadPoolBuilder::new().stack_size(WORKER_STACK_BYTES).build_global();
}
