//! Helpers of the C-ABI integration tests (the test binary's module `common`; not every test
//! module uses every helper).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace root.
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
    assert!(!under_ci(), "{} is absent under CI", p.display());
    eprintln!("SKIPPED: {} is absent (CI provides ../shared beside the repository)", p.display());
    None
}

/// Whether the tests run under CI (`CI=true`).
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// `target/<profile>`: where this test binary's profile puts the libraries and binaries.
pub fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    // target/<profile>/deps/<test binary>
    exe.parent().and_then(Path::parent).expect("target/<profile>/deps").to_path_buf()
}

/// The command line's binary, current: `AEROIDENT_BIN` if set; else this profile's
/// `aeroident` when it is newer than every source file of the workspace (as after `cargo test
/// --workspace`, which builds it with the tests); else built first with the cargo that runs the
/// tests (`cargo test -p aeroident-capi` alone).
pub fn cli_binary() -> PathBuf {
    if let Ok(p) = std::env::var("AEROIDENT_BIN") {
        return PathBuf::from(p);
    }
    let bin = profile_dir().join("aeroident");
    let built = std::fs::metadata(&bin).and_then(|m| m.modified()).ok();
    if built.is_none_or(|b| newest_source().is_none_or(|s| s > b)) {
        cargo_build("aeroident", Some("aeroident"));
    }
    bin
}

/// The latest modification time of the sources and manifests the command line is built from.
fn newest_source() -> Option<std::time::SystemTime> {
    fn walk(dir: &Path, newest: &mut Option<std::time::SystemTime>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, newest);
            } else if let Ok(t) = e.metadata().and_then(|m| m.modified()) {
                *newest = (*newest).max(Some(t));
            }
        }
    }
    let root = workspace();
    let mut newest = None;
    for f in ["Cargo.toml", "Cargo.lock"] {
        walk_file(&root.join(f), &mut newest);
    }
    // The command line depends on every crate but this one and the Python bindings.
    for krate in std::fs::read_dir(root.join("crates")).ok()?.flatten() {
        if ["capi", "python"].iter().any(|c| krate.file_name() == *c) {
            continue;
        }
        walk(&krate.path().join("src"), &mut newest);
        walk_file(&krate.path().join("Cargo.toml"), &mut newest);
    }
    newest
}

fn walk_file(p: &Path, newest: &mut Option<std::time::SystemTime>) {
    if let Ok(t) = std::fs::metadata(p).and_then(|m| m.modified()) {
        *newest = (*newest).max(Some(t));
    }
}

/// Builds `package` (its `--bin` `bin` if given) in this test binary's target directory and
/// profile with the cargo that runs the tests.
pub fn cargo_build(package: &str, bin: Option<&str>) {
    let dir = profile_dir();
    let profile = dir.file_name().and_then(|n| n.to_str()).expect("a profile directory");
    let target = dir.parent().expect("the target directory");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut c = Command::new(cargo);
    c.current_dir(workspace()).args(["build", "-q", "-p", package]).arg("--target-dir").arg(target);
    match profile {
        "debug" => {}
        "release" => {
            c.arg("--release");
        }
        other => {
            c.args(["--profile", other]);
        }
    }
    if let Some(b) = bin {
        c.args(["--bin", b]);
    }
    let out = c.output().expect("running cargo");
    assert!(
        out.status.success(),
        "cargo build -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A fresh scratch directory under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let d = profile_dir().join("capi-tests").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Whether `gcc` runs; `false` with a SKIPPED message, a failure under CI (it has gcc).
pub fn have_gcc() -> bool {
    if Command::new("gcc").arg("--version").output().is_ok_and(|o| o.status.success()) {
        return true;
    }
    assert!(!under_ci(), "gcc is absent under CI");
    eprintln!("SKIPPED: gcc is not installed");
    false
}

/// The static library of this build: the one `cargo test` made beside the test binaries with
/// the crate's other library kinds (`deps/`, the same build as the tests link), else
/// `target/<profile>/libaeroident_capi.a` built first.
pub fn static_library() -> PathBuf {
    let made = profile_dir().join("deps/libaeroident_capi.a");
    if made.exists() {
        return made;
    }
    cargo_build("aeroident-capi", None);
    profile_dir().join("libaeroident_capi.a")
}

/// Compiles the C program `source` (relative to the workspace) against the committed header
/// and [`static_library`] into `out`.
pub fn compile_c(source: &str, out: &Path) {
    let lib = static_library();
    let o = Command::new("gcc")
        .args(["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
        .arg(workspace().join("crates/capi/include"))
        .arg(workspace().join(source))
        .arg(&lib)
        .args(["-lpthread", "-ldl", "-lm", "-Wl,--gc-sections", "-o"])
        .arg(out)
        .output()
        .expect("running gcc");
    assert!(o.status.success(), "gcc {source}: {}", String::from_utf8_lossy(&o.stderr));
}

/// Compiles the C program `source` against the committed header and the shared library
/// `cargo test` built beside [`static_library`] (linked by path, found at run time by rpath)
/// into `out`.
pub fn compile_c_shared(source: &str, out: &Path) {
    let lib_dir = static_library().parent().expect("the library's directory").to_path_buf();
    assert!(
        lib_dir.join("libaeroident_capi.so").exists(),
        "no shared library in {}",
        lib_dir.display()
    );
    let o = Command::new("gcc")
        .args(["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
        .arg(workspace().join("crates/capi/include"))
        .arg(workspace().join(source))
        .arg(format!("-L{}", lib_dir.display()))
        .arg("-laeroident_capi")
        .arg(format!("-Wl,-rpath,{}", lib_dir.display()))
        // DT_RPATH, searched before LD_LIBRARY_PATH (a RUNPATH is searched after it): cargo's
        // test environment puts the profile directory on LD_LIBRARY_PATH, where an older
        // `cargo build -p aeroident-capi` may have left a stale copy of the library.
        .arg("-Wl,--disable-new-dtags")
        .arg("-o")
        .arg(out)
        .output()
        .expect("running gcc");
    assert!(o.status.success(), "gcc {source} (shared): {}", String::from_utf8_lossy(&o.stderr));
}
