//! Helpers shared by the estimators crate's integration tests. `records.rs` is included with
//! `#[path]` by the crate's benches and examples too.

pub mod records;
