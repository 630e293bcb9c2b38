//! The io crate's integration tests: one test binary, each file of this directory a module of
//! it (a file of its own under `tests/` would be a binary of its own, compiled and linked
//! separately). A new test file is added here with `mod <name>;`; helpers shared by the modules
//! are in `common/`. The test data stay in `tests/data/`, proptest's saved failure cases in
//! `tests/proptest-regressions/<module>.txt` (where proptest looks for a binary's modules).

mod common;

mod bad_input;
mod computed_channels;
mod fuzz_logs;
mod fuzz_mutations;
mod fuzz_parsers;
mod fuzz_tables;
mod inspect_logs;
mod mat_limits;
mod mavlink_link;
mod multirate_logs;
mod reader_limits;
mod record_hardening;
mod shipped;
mod thrust_model;
