//! Each crate's integration tests stay one test binary: no Rust file directly under a crate's
//! `tests/` (cargo would build it as a binary of its own, compiled and linked separately), and
//! every file of `tests/all/` declared in that directory's `main.rs` (an undeclared one is
//! never compiled, so its tests would silently not run).

use crate::common::workspace;
use std::path::Path;

/// The `.rs` files directly in `dir`, by file stem.
fn rust_files(dir: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut stems: Vec<String> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "rs"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    stems.sort();
    stems
}

#[test]
fn every_integration_test_is_a_module_of_its_crates_one_binary() {
    let mut problems = Vec::new();
    for krate in std::fs::read_dir(workspace().join("crates")).unwrap().flatten() {
        let tests = krate.path().join("tests");
        for stem in rust_files(&tests) {
            problems.push(format!("{}/{stem}.rs: move it to tests/all/", tests.display()));
        }
        let all = tests.join("all");
        let Ok(main) = std::fs::read_to_string(all.join("main.rs")) else { continue };
        for stem in rust_files(&all) {
            if stem != "main" && !main.lines().any(|l| l.trim() == format!("mod {stem};")) {
                problems.push(format!("{}/{stem}.rs: not declared in main.rs", all.display()));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
