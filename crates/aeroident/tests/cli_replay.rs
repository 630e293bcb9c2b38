//! `aeroident replay` end to end through the binary: output files and their keys, the live
//! stdin → stdout feed, and the bad-input corpus through the whole pipeline.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

fn tmp(name: &str) -> PathBuf {
    let d =
        std::env::temp_dir().join(format!("aeroident-cli-replay-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The bad-input corpus through the CLI: the run succeeds, every rejected row and gap is in
/// `summary.json` with its row, and the summary has exactly the keys.
#[test]
fn errors_bad_corpus_counted_in_summary_with_exact_keys() {
    let out = tmp("bad");
    let io_data = workspace().join("crates/io/tests/data");
    let st = bin()
        .args(["replay"])
        .arg(io_data.join("bad_values.csv"))
        .arg("--map")
        .arg(io_data.join("min.toml"))
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    let mut expect = [
        "estimator",
        "samples_read",
        "samples_rejected",
        "rejections",
        "throughput_samples_per_s",
        "parameters",
    ];
    let mut got = keys.clone();
    got.sort_unstable();
    expect.sort_unstable();
    assert_eq!(got, expect);
    assert_eq!(v["samples_read"], 12);
    assert_eq!(v["samples_rejected"], 8);
    let rows: Vec<u64> =
        v["rejections"].as_array().unwrap().iter().map(|r| r["row"].as_u64().unwrap()).collect();
    assert_eq!(rows, vec![3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
    for p in v["parameters"].as_array().unwrap() {
        let keys: Vec<&str> = p.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        assert_eq!(keys.len(), 4);
        assert!(p["estimate"].as_f64().unwrap().is_finite());
    }
    let csv = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    assert!(
        csv.starts_with("t_s,Cm_0,Cm_alpha,Cm_q,Cm_de,CL_0,CL_alpha,CD_0,CD_alpha,sigma_Cm_0,")
    );
    assert!(!csv.to_lowercase().contains("nan"));
    assert!(out.join("estimates.png").exists());
}

#[test]
fn errors_missing_channel_mapping_fails_with_file_and_channel() {
    let io_data = workspace().join("crates/io/tests/data");
    let o = bin()
        .args(["replay"])
        .arg(io_data.join("good.csv"))
        .arg("--map")
        .arg(io_data.join("missing_channel.toml"))
        .arg("--out")
        .arg(tmp("missing"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("missing_channel.toml") && err.contains("required channel `q`"), "{err}");
}

/// Live mode: the HFB-320 record on stdin gives one estimates line per sample on stdout.
#[test]
fn val_live_stdin_one_line_per_sample() {
    let data =
        workspace().join("../shared/flightdata/jategaonkar_hfb320_attas/csv/hfb320_1_10.csv");
    if !data.exists() {
        eprintln!(
            "SKIPPED: {} is absent (CI provides ../shared beside the repository)",
            data.display()
        );
        return;
    }
    let mut child = bin()
        .args(["replay", "-", "--estimator", "ekf", "--map"])
        .arg(workspace().join("mappings/hfb320.toml"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Feed stdin from a thread: the child writes stdout while it reads, so a single-threaded
    // write-then-read would deadlock once the pipe buffers fill.
    let mut stdin = child.stdin.take().unwrap();
    let bytes = std::fs::read(&data).unwrap();
    let feeder = std::thread::spawn(move || stdin.write_all(&bytes));
    let o = child.wait_with_output().unwrap();
    feeder.join().unwrap().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 601);
    assert!(lines[0].starts_with("t_s,CD_0,"));
    assert!(lines[601].starts_with("60.0000"), "{}", lines[601]);
    // Without --out the summary goes to stderr as JSON.
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("\"samples_read\": 601"), "{err}");
}
