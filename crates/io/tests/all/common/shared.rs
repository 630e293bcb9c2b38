//! The workspace root and the third-party records of `../shared/flightdata` for the io crate's
//! integration tests (the module `common::shared`).

use std::path::PathBuf;

/// The workspace root (two levels above this crate's manifest).
pub fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The record at `../shared/flightdata/<rel>` beside the workspace root, or `None` with a
/// SKIPPED message when the shared data are absent. Under CI (`CI=true`) a missing record is a
/// failure: CI always has `../shared`, so a skip there would hide a broken path.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = workspace().join("../shared/flightdata").join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "{} is absent under CI",
        p.display()
    );
    eprintln!("SKIPPED: {} is absent (CI provides ../shared beside the repository)", p.display());
    None
}
