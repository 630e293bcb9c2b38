//! Feature unification for the Python wheel's build (no code).
//!
//! `maturin build` builds the one package `aeroident-python`, and cargo resolves the features
//! of a one-package build on its own: without this crate the workspace's test build (whose
//! dev-dependencies switch on features such as `syn/fold`, `either/use_std`,
//! `parking_lot/arc_lock`) and the wheel's build disagree on the features of a few leaf crates,
//! so every crate above them, ours included, is compiled a second time. This crate depends on
//! those crates with the union of the workspace's features, and the Python crate depends on it,
//! so both builds resolve the same features and the wheel reuses the tests' artifacts.
//!
//! Its dependency list is written by `cargo hakari generate` (cargo-hakari, configured in
//! `.config/hakari.toml`); regenerate it after changing a dependency or a feature.
