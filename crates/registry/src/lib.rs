//! # aeroident-registry
//!
//! What a caller of the estimator core needs beside it, and nothing of the pipelines (records,
//! jobs, reports): the C library (`aeroident-capi`) links this crate, and `aeroident-pipelines`
//! re-exports every module under its old path.
//!
//! - [`estimators`]: every estimator kind by name, its options, its default feed and
//!   [`estimators::build`], the one place an estimator is built.
//! - [`verdict`]: the status of one estimate from its evidence ([`verdict::judge_estimate`]),
//!   with [`plausibility`] (sign and magnitude ranges a conventional aircraft keeps),
//!   [`precision`] (a σ too wide to claim a value) and [`unmodelled`] (the σ a model's missing
//!   terms add).
//! - [`Named`]: a choice made by name (estimators, scenario kinds).

pub mod estimators;
pub mod named;
pub mod plausibility;
pub mod precision;
pub mod unmodelled;
pub mod verdict;

pub use named::Named;
