//! Exit codes and messages of the CLI end to end: a closed output pipe ends quietly (no panic),
//! bad numbers and states outside the model's domain are errors naming the argument.

use crate::common;
use std::process::{Command, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

/// `aeroident f16 linearize … | true`: the reader is gone before the output is written; the
/// program must not panic ("failed printing to stdout") and must exit 0 with an empty stderr.
#[test]
fn errors_closed_pipe_ends_quietly() {
    for args in [
        vec!["f16", "linearize", "--alt-ft", "20000", "--vt-fps", "675"],
        vec!["f16", "trim", "--alt-ft", "20000", "--vt-fps", "675", "--json"],
        vec![
            "f16",
            "xdot",
            "--state",
            "500,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90",
            "--controls",
            "0.9,20,-15,-20",
            "--xcg",
            "0.4",
        ],
    ] {
        let mut child =
            bin().args(&args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        drop(child.stdout.take()); // close the read end: every write gets EPIPE
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(out.status.success(), "{args:?}: {:?} {err}", out.status);
    }
}

/// `aeroident compat … 2>&1 | head` on the HFB-320 record (../shared), the reader gone: the notes and the "wrote" line on a
/// closed stderr must not panic (exit 101) after the results are written; the run exits 0 with
/// its files.
#[test]
fn errors_closed_stderr_ends_quietly_with_the_results_written() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let out_dir =
        std::env::temp_dir().join(format!("aeroident-closed-stderr-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out_dir);
    let mut child = bin()
        .arg("compat")
        .arg(data)
        .arg("--map")
        .arg(common::workspace().join("mappings/hfb320.toml"))
        .arg("--out")
        .arg(&out_dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take()); // every write to stderr gets EPIPE
    drop(child.stdout.take());
    let status = child.wait().unwrap();
    let wrote = out_dir.join("compat.json").exists() || out_dir.join("summary.json").exists();
    let _ = std::fs::remove_dir_all(&out_dir);
    assert_ne!(status.code(), Some(101), "panicked on the closed pipe");
    assert!(wrote, "no results written ({status:?})");
}

/// A state the model cannot evaluate (V = 1e308) is an error naming the derivative, not NaN
/// output with exit 0.
#[test]
fn errors_non_finite_derivative_is_an_error() {
    let out = bin()
        .args([
            "f16",
            "xdot",
            "--state=1e308,0.5,-0.2,-1,1,-1,0.7,-0.8,0.9,1000,900,10000,90",
            "--controls",
            "0.9,20,-15,-20",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--state") && err.contains("not finite"), "{err}");
    assert!(out.stdout.is_empty());
}

/// Malformed numbers name the argument and the element.
#[test]
fn errors_malformed_numbers_name_the_element() {
    let out = bin()
        .args(["f16", "xdot", "--state", "500,abc,0,0,0,0,0,0,0,0,0,0,0", "--controls", "0,0,0,0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--state: element 2 (`abc`)"), "{err}");
}
