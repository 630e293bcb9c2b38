//! The pipelines crate's integration tests: one test binary, each file of this directory a
//! module of it (a file of its own under `tests/` would be a binary of its own, compiled and
//! linked separately). A new test file is added here with `mod <name>;`.

mod export_uav;
mod freqresp_f16;
mod inspect_manoeuvres;
