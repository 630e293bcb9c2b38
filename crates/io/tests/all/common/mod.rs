//! Helpers shared by the io crate's integration tests (not every module uses every helper).
//! `logs.rs` includes `log_writers.rs` itself: this crate's unit tests (`src/mat5.rs`) and
//! other crates' tests include those files with `#[path]`.

pub mod logs;
pub mod mutate;
pub mod shared;
