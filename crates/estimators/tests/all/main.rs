//! The estimators crate's integration tests: one test binary, each file of this directory a
//! module of it (a file of its own under `tests/` would be a binary of its own, compiled and
//! linked separately). A new test file is added here with `mod <name>;`; proptest keeps its
//! failure cases in `tests/proptest-regressions/<module>.txt`.

mod common;

mod ekf_jsbsim;
mod jsbsim_records;
mod model_reference;
mod output_error_hfb320;
mod prop_estimators;
mod rls;
mod rls_iv;
