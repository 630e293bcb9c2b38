//! `aeroident replay` end to end through the binary: output files and their keys, the live
//! stdin → stdout feed, and the bad-input corpus through the whole pipeline.

use crate::common;
use common::workspace;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

fn tmp(name: &str) -> PathBuf {
    let d = tmp_path(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The scratch directory of `name`, as it is (not cleared).
fn tmp_path(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aeroident-cli-replay-{}-{name}", std::process::id()))
}

/// `replay DATA --map mappings/MAP ARGS --out DIR` through the binary (a batch fit): asserts
/// success and returns the parsed `summary.json` and `report.html` (the directory is removed).
fn batch_replay(data: &Path, map: &str, args: &[&str], name: &str) -> (serde_json::Value, String) {
    let out = tmp(name);
    let o = bin()
        .args(["replay"])
        .arg(data)
        .arg("--map")
        .arg(workspace().join("mappings").join(map))
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let v =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    (v, html)
}

/// `x` to two significant digits, as the results table prints a σ (0.043, 0.0087, 2.9).
fn fmt2(x: f64) -> String {
    let decimals = (1 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// The last iteration's `ln_det_r` of a batch summary.
fn final_ln_det(v: &serde_json::Value) -> f64 {
    v["iterations"].as_array().unwrap().last().unwrap()["ln_det_r"].as_f64().unwrap()
}

/// The bad-input corpus through the CLI: the run succeeds, every rejected row and gap is in
/// `summary.json` with its row, and the summary has exactly the documented keys. Four good
/// samples of nearly the same state cannot determine any 4-term fit: every estimate is `null`
/// (never a placeholder 0 or NaN) and the status is `initialising`.
#[test]
fn errors_bad_corpus_counted_in_summary_with_exact_keys() {
    let out = tmp("bad");
    let io_data = workspace().join("crates/io/tests/data");
    let o = bin()
        .args(["replay"])
        .arg(io_data.join("bad_values.csv"))
        .arg("--map")
        .arg(io_data.join("min.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("model: longitudinal (default"), "the model is printed: {err}");
    assert!(err.contains("status `initialising`"), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    let mut expect = [
        "schema_version",
        "estimator",
        "model",
        "status",
        "samples_read",
        "samples_rejected",
        "rejections",
        "throughput_samples_per_s",
        "parameters",
        "coefficients",
        "correlations",
        "events",
        "warnings",
        "identifiability",
        "validation",
        "validation_on",
        "cross_check",
        "repeatability",
        "reader",
        "sign_tests",
    ];
    let mut got = keys.clone();
    got.sort_unstable();
    expect.sort_unstable();
    assert_eq!(got, expect);
    assert_eq!(v["estimator"], "rls");
    assert_eq!(v["events"]["listed"], serde_json::json!([]), "RLS has no events");
    assert!(v["validation_on"].is_null(), "no --validate-on");
    assert!(v["repeatability"].is_null(), "one window: nothing to compare");
    assert_eq!(v["validation"]["used_for_fit"], true);
    assert_eq!(v["model"], "longitudinal");
    assert_eq!(v["status"], "initialising");
    assert_eq!(v["samples_read"], 12);
    assert_eq!(v["samples_rejected"], 8);
    let rows: Vec<u64> =
        v["rejections"].as_array().unwrap().iter().map(|r| r["row"].as_u64().unwrap()).collect();
    assert_eq!(rows, vec![3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
    let params = v["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 12);
    for p in params {
        let mut keys: Vec<&str> = p.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        keys.sort_unstable();
        let mut want = common::PARAMETER_KEYS.to_vec();
        want.push("settle_time_s");
        want.sort_unstable();
        assert_eq!(keys, want);
        assert!(p["estimate"].is_null() && p["std_error"].is_null(), "{p}");
        assert_eq!(p["status"], "not identified", "{p}");
    }
    let coefs = v["coefficients"].as_array().unwrap();
    let names: Vec<&str> = coefs.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["CL", "CD", "Cm"]);
    for c in coefs {
        let mut keys: Vec<&str> = c.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["condition_number", "name"]);
        assert!(c["condition_number"].is_null());
    }
    assert_eq!(v["correlations"].as_array().unwrap().len(), 0);
    let csv = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    assert!(
        csv.starts_with("t_s,CL_0,CL_alpha,CL_q,CL_de,CD_0,CD_alpha,CD_q,CD_de,Cm_0,"),
        "{csv}"
    );
    assert!(!csv.to_lowercase().contains("nan"));
    // Not identified: empty fields, not numbers.
    assert!(csv.lines().nth(1).unwrap().ends_with(",,,,"), "{csv}");
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
    assert!(
        err.contains("missing_channel.toml") && err.contains("required channel `mass`"),
        "{err}"
    );
}

fn replay_good(extra: &[&str], name: &str) -> (bool, String) {
    let io_data = workspace().join("crates/io/tests/data");
    let o = bin()
        .args(["replay"])
        .arg(io_data.join("good.csv"))
        .arg("--map")
        .arg(io_data.join("min.toml"))
        .arg("--out")
        .arg(tmp(name))
        .args(extra)
        .output()
        .unwrap();
    (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Unknown estimators, unsupported models and bad model files are clear errors.
#[test]
fn errors_estimator_model_and_model_file_problems_are_named() {
    let (ok, err) = replay_good(&["--estimator", "kalman"], "kalman");
    assert!(!ok && err.contains("invalid value 'kalman'") && err.contains("ekf"), "{err}");
    let (ok, err) = replay_good(&["--model", "lateral"], "lat");
    assert!(!ok, "{err}");
    assert!(
        err.contains("model `lateral` is not supported by") && err.contains("min.toml"),
        "{err}"
    );
    assert!(
        err.contains("term `beta` (needs beta)") && err.contains("coefficient `CY` (needs ay)"),
        "{err}"
    );
    let dir = tmp("modelfile");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad_model.toml");
    std::fs::write(&file, "[coefficients]\nCm = [\"0\", \"alpha\"]\nCn = [\"beta\", \"yaw\"]\n")
        .unwrap();
    let (ok, err) = replay_good(&["--model", file.to_str().unwrap()], "modelfile-run");
    assert!(!ok, "{err}");
    assert!(err.contains("bad_model.toml: line 3: coefficient `Cn`: unknown term `yaw`"), "{err}");
    let (ok, err) = replay_good(&["--forgetting", "1.5"], "forget");
    assert!(!ok && err.contains("option `--forgetting`: must be in (0, 1]"), "{err}");
}

/// A numeric option out of range names the option as it is typed (`--instrument-delay`, not
/// the estimator's configuration field) and the value exactly as given, not rounded through
/// a float.
#[test]
fn errors_numeric_options_name_the_cli_option_and_the_exact_value() {
    let delay = ["--estimator", "rls-iv", "--instrument-delay", "18446744073709551615"];
    let (ok, err) = replay_good(&delay, "delay");
    assert!(!ok, "{err}");
    assert!(
        err.contains(
            "option `--instrument-delay`: must be 1 to 64 samples, got 18446744073709551615"
        ),
        "{err}"
    );
    assert!(!err.contains("instrument_delay") && !err.contains("18446744073709552000"), "{err}");
    let (ok, err) = replay_good(&["--estimator", "rls-iv", "--instrument-delay", "0"], "d0");
    assert!(!ok && err.contains("option `--instrument-delay`") && err.contains("got 0"), "{err}");
    let (ok, err) = replay_good(&["--estimator", "ftr", "--forgetting", "NaN"], "fnan");
    assert!(!ok && err.contains("option `--forgetting`") && err.contains("got NaN"), "{err}");
    let (ok, err) = replay_good(&["--diff-window", "18446744073709551615"], "dw");
    assert!(!ok, "{err}");
    assert!(
        err.contains("option `--diff-window`") && err.contains("18446744073709551615"),
        "{err}"
    );
}

/// The last line of `estimates.csv` of the HFB-320 record `data` replayed with `args`.
fn last_estimates_line(data: &std::path::Path, args: &[&str], name: &str) -> String {
    estimates_csv(data, args, name).lines().last().unwrap().to_string()
}

/// `replay DATA --map mappings/hfb320.toml ARGS` through the binary: its `estimates.csv`.
fn estimates_csv(data: &std::path::Path, args: &[&str], name: &str) -> String {
    let out = tmp(name);
    let o = bin()
        .args(["replay"])
        .arg(data)
        .arg("--map")
        .arg(workspace().join("mappings/hfb320.toml"))
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    csv
}

/// The estimator-option flags are checked by the estimator registry, which knows which kind
/// takes which: `ekf` has no forgetting factor and `smpe` no instrument delay (refused naming
/// the flag, the kind and the options it takes, not ignored), while `smpe-finite-time` takes
/// `--forgetting` (the CLI refused it though the registry builds it with one) and the factor
/// reaches the estimator. The second half skips without `../shared`.
#[test]
fn errors_forgetting_refused_by_ekf_taken_by_smpe_finite_time() {
    let (ok, err) = replay_good(&["--estimator", "ekf", "--forgetting", "0.9"], "ekf-forget");
    assert!(!ok, "{err}");
    assert!(
        err.contains("--forgetting is not an option of --estimator ekf, which takes `parameter_walk_per_sqrt_s`, `samples`, `blocks` and `update_every` (it would be ignored)"),
        "{err}"
    );
    let (ok, err) = replay_good(&["--estimator", "smpe", "--instrument-delay", "8"], "smpe-delay");
    assert!(!ok, "{err}");
    assert!(
        err.contains("--instrument-delay is not an option of --estimator smpe, which takes none"),
        "{err}"
    );
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let last_estimates = |extra: &[&str], name: &str| {
        last_estimates_line(
            &data,
            &[&["--estimator", "smpe-finite-time"][..], extra].concat(),
            name,
        )
    };
    let forgetting = last_estimates(&["--forgetting", "0.99"], "sft-forget");
    let none = last_estimates(&[], "sft");
    assert_eq!(forgetting.split(',').next(), none.split(',').next(), "the same last sample");
    assert_ne!(forgetting, none, "--forgetting 0.99 did not reach the estimator");
}

/// Any estimator option reaches the registry by `--estimator-option KEY=VALUE`: one the kind
/// does not take is refused naming the key, the kind and what it takes; a malformed one names
/// the form; `rls-iv`'s instrument delay given that way reaches the estimator (the last
/// estimates differ from the default delay's). The second half skips without `../shared`.
#[test]
fn errors_estimator_option_goes_through_the_registry() {
    let opt = ["--estimator-option", "parameter_walk_per_sqrt_s=0.01"];
    let (ok, err) = replay_good(&[&["--estimator", "rls"][..], &opt[..]].concat(), "rls-walk");
    assert!(!ok, "{err}");
    assert!(
        err.contains("--estimator-option parameter_walk_per_sqrt_s is not an option of --estimator rls, which takes `forgetting`"),
        "{err}"
    );
    let (ok, err) = replay_good(&["--estimator-option", "forgetting"], "no-equals");
    assert!(!ok && err.contains("give KEY=VALUE"), "{err}");
    let (ok, err) = replay_good(&["--estimator-option", "forgetting=\"x\""], "bad-type");
    assert!(!ok && err.contains("forgetting") && err.contains("must be a number"), "{err}");
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let last_estimates = |extra: &[&str], name: &str| {
        last_estimates_line(&data, &[&["--estimator", "rls-iv"][..], extra].concat(), name)
    };
    let given = last_estimates(&["--estimator-option", "instrument_delay=12"], "iv-12");
    let flag = last_estimates(&["--instrument-delay", "12"], "iv-flag-12");
    let default = last_estimates(&[], "iv-default");
    assert_eq!(given, flag, "the option and the flag are one setting");
    assert_ne!(given, default, "instrument_delay=12 did not reach the estimator");
}

/// A batch fit's options from the command line go through the one parser of a batch fit's
/// options: `--estimator-option` names any of them, a real-time estimator's option is refused
/// naming what the fit takes, a batch fit's option given to a real-time estimator names the
/// fits that take it, and an option of the other method names whose it is.
#[test]
fn errors_batch_fit_options_go_through_one_parser() {
    let (ok, err) = replay_good(&["--estimator", "oe", "--forgetting", "0.9"], "oe-forget");
    assert!(!ok, "{err}");
    assert!(
        err.contains("--forgetting is not an option of --estimator oe, which takes `initial_states`, `step`, `bootstrap_refits`, `max_iterations` and `robust`"),
        "{err}"
    );
    // A real-time estimator refuses a batch fit's option, naming the fits that take it.
    let (ok, err) = replay_good(&["--estimator", "rls", "--max-iterations", "3"], "rls-iter");
    assert!(
        !ok && err.contains(
            "--max-iterations applies to the batch fits (--estimator oe, fem or fdoe), not to --estimator rls"
        ),
        "{err}"
    );
    let (ok, err) =
        replay_good(&["--estimator", "fem", "--estimator-option", "robust=true"], "fem-robust");
    assert!(!ok && err.contains("`--robust`") && err.contains("output error"), "{err}");
    let (ok, err) =
        replay_good(&["--estimator", "oe", "--estimator-option", "max_iterations=0"], "oe-zero");
    // Named as typed: the same key by its flag names the flag.
    assert!(
        !ok && err.contains(
            "option `--estimator-option max_iterations`: must be an integer of at least 1"
        ),
        "{err}"
    );
    let (ok, err) = replay_good(&["--estimator", "oe", "--max-iterations", "0"], "oe-zero-flag");
    assert!(!ok && err.contains("--max-iterations"), "{err}");
}

/// The replay job refuses what does not go together before the output directory is touched:
/// several records for a real-time estimator (a batch fit's `--and`).
#[test]
fn errors_replay_job_refuses_and_for_a_real_time_estimator() {
    let good = workspace().join("crates/io/tests/data/good.csv").display().to_string();
    let (ok, err) = replay_good(&["--and", &good], "and-online");
    assert!(!ok && err.contains("--and fits several records together"), "{err}");
    assert!(
        !tmp_path("and-online").exists(),
        "the output directory was created before the refusal"
    );
}

/// A record given twice to a batch fit, or to `compat` (the same file under another path, a
/// copy of it, or its rows with other line endings), is refused naming both, before the output directory is touched; once it was
/// fitted as new data, every σ shrunk by √2. `--allow-duplicate-records` lets it through.
#[test]
fn errors_a_record_given_twice_is_refused_unless_asked() {
    let io_data = workspace().join("crates/io/tests/data");
    let good = io_data.join("good.csv").display().to_string();
    let dir = tmp_path("dup-records");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join("copy.csv");
    std::fs::copy(&good, &copy).unwrap();
    let copy = copy.display().to_string();
    let respelled = io_data.join(".").join("good.csv").display().to_string();
    for (and, how) in [(&respelled, "is the same file as"), (&copy, "has the same content as")] {
        let (ok, err) = replay_good(&["--estimator", "oe", "--and", and], "dup-out");
        assert!(!ok && err.contains(&format!("`{and}` {how} `{good}`")), "{err}");
        assert!(err.contains("--allow-duplicate-records"), "{err}");
        assert!(!tmp_path("dup-out").exists(), "the output directory was touched first");
    }
    let (_, err) =
        replay_good(&["--estimator", "oe", "--and", &copy, "--allow-duplicate-records"], "dup-ok");
    assert!(!err.contains("has the same content"), "{err}");
    let _ = std::fs::remove_dir_all(tmp_path("dup-ok"));
    let o = bin()
        .args(["compat", &good, "--map"])
        .arg(io_data.join("min.toml"))
        .args(["--and", &copy, "--and", &good])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("has the same content as"), "{err}");
    // The same rows with CRLF line endings: other bytes, the same samples.
    let crlf = dir.join("crlf.csv");
    let text = std::fs::read_to_string(&good).unwrap();
    std::fs::write(&crlf, text.replace('\n', "\r\n")).unwrap();
    let crlf = crlf.display().to_string();
    let (ok, err) = replay_good(&["--estimator", "oe", "--and", &crlf], "dup-crlf");
    assert!(!ok && err.contains(&format!("`{crlf}` holds the same samples as `{good}`")), "{err}");
    assert!(!tmp_path("dup-crlf").exists(), "the output directory was touched first");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A record most of whose rows are rejected (here 30 of 40 with a negative airspeed) says so in
/// the summary's warnings, with the share and the cause, in the real-time replay as in the batch
/// fits: once the estimator ran on the 10 left and only the rejection count told.
#[test]
fn most_rows_rejected_is_a_warning_naming_the_share_and_cause() {
    let dir = tmp_path("most-rejected");
    std::fs::create_dir_all(&dir).unwrap();
    let mut csv = String::from("t,V,a,q,ax,az,de,qbar,qd\n");
    for i in 0..40 {
        let v = if i % 4 == 0 { 200 } else { -5 };
        csv.push_str(&format!("{:.1},{v},2.0,0.5,0.01,-1.0,1.0,100,0.1\n", i as f64 * 0.1));
    }
    std::fs::write(dir.join("r.csv"), csv).unwrap();
    let out = dir.join("out");
    let o = bin()
        .arg("replay")
        .arg(dir.join("r.csv"))
        .arg("--map")
        .arg(workspace().join("crates/io/tests/data/min.toml"))
        .args(["--estimator", "rls", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    let s: serde_json::Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stderr)));
    let warned = s["warnings"].as_array().unwrap().iter().filter_map(|w| w.as_str());
    let w: Vec<&str> = warned.filter(|w| w.contains("rows (75 %) were rejected")).collect();
    assert!(
        w.len() == 1
            && w[0].contains("30 of 40 rows")
            && w[0].contains("the fit uses the other 10"),
        "{s}"
    );
}

/// `--cross-check` beside a batch fit runs the record's other methods: `summary.json`
/// `cross_check` names the fit's method first, then the panel's others, and judges every
/// estimate with a σ; on stdin (read once) it is refused before the output directory is made.
#[test]
fn cross_check_with_a_batch_fit_runs_the_other_methods() {
    let (ok, err) = replay_good(&["--estimator", "oe", "--cross-check"], "xc-batch");
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(tmp_path("xc-batch").join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let c = &s["cross_check"];
    let methods: Vec<&str> =
        c["methods"].as_array().unwrap().iter().map(|m| m["method"].as_str().unwrap()).collect();
    assert_eq!(methods, ["oe", "rls", "rls-iv", "ekf", "fem", "fdoe"]);
    let with_sigma =
        s["parameters"].as_array().unwrap().iter().filter(|p| p["std_error"].is_f64()).count();
    assert_eq!(c["compared"].as_u64().unwrap() as usize, with_sigma);
    std::fs::remove_dir_all(tmp_path("xc-batch")).unwrap();
    let o = bin()
        .args(["replay", "-", "--map"])
        .arg(workspace().join("crates/io/tests/data/min.toml"))
        .args(["--estimator", "oe", "--cross-check", "--out"])
        .arg(tmp_path("xc-stdin"))
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--cross-check") && err.contains("stdin"), "{err}");
    assert!(!tmp_path("xc-stdin").exists(), "the output directory was touched first");
}

/// Live mode: the HFB-320 record on stdin gives one estimates line per sample on stdout.
#[test]
fn val_live_stdin_one_line_per_sample() {
    // Absent: skipped with a message, a failure under CI (`common::shared`).
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else {
        return;
    };
    let mut child = bin()
        .args(["replay", "-", "--estimator", "rls", "--map"])
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
    assert!(lines[0].starts_with("t_s,CL_0,"));
    assert!(lines[601].starts_with("60.0000"), "{}", lines[601]);
    // Without --out the summary goes to stderr as JSON.
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("\"samples_read\": 601"), "{err}");
    assert!(err.contains("\"status\": \"complete\""), "{err}");
}

/// `replay --estimator oe` on the HFB-320 with the book's model (`models/hfb320_book_q0.toml`)
/// reproduces the published output-error result (the shared README: Cm_alpha −1.002 ± 0.009,
/// Cm_q −27.06 ± 0.68, Cm_de −1.437 ± 0.017, CL_alpha 3.212 ± 0.039) within 1 % and its
/// Cramér–Rao σ within 20 %, blind (noise covariance from the fit itself, start from equation
/// error). Skips without `../shared`; fails under CI if the record is missing.
#[test]
fn val_output_error_reproduces_the_hfb320_reference_through_the_cli() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let out = tmp("oe_hfb320");
    let o = bin()
        .args(["replay"])
        .arg(&data)
        .arg("--map")
        .arg(workspace().join("mappings/hfb320.toml"))
        .arg("--model")
        .arg(workspace().join("models/hfb320_book_q0.toml"))
        .args(["--estimator", "oe", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("batch method"), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v["status"], "converged");
    let get = |name: &str| {
        let p = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name).unwrap();
        (p["estimate"].as_f64().unwrap(), p["crb_std_error"].as_f64().unwrap())
    };
    for (name, value, sigma) in [
        ("Cm_alpha", -1.002, 0.009),
        ("Cm_q0", -27.06, 0.68),
        ("Cm_de", -1.437, 0.017),
        ("CL_alpha", 3.212, 0.039),
    ] {
        let (est, s) = get(name);
        assert!(((est - value) / value).abs() < 0.01, "{name}: {est} vs {value}");
        assert!((s / sigma - 1.0).abs() < 0.2, "{name}: σ {s} vs {sigma}");
    }
    // The record's residuals are coloured: both coloured-residual σ (the reported spectral one
    // and the prewhitened diagnostic) exceed the Cramér–Rao σ of every parameter.
    for p in v["parameters"].as_array().unwrap() {
        let crb = p["crb_std_error"].as_f64().unwrap();
        for key in ["coloured_std_error", "prewhitened_std_error"] {
            let c = p[key].as_f64().unwrap_or_else(|| panic!("{key} missing: {p}"));
            assert!(c > crb, "{}: {key} {c} ≤ Cramér–Rao σ {crb}", p["name"]);
        }
    }
    // The results table on stdout (estimate ± CRB σ, fit quality of the simulated outputs)
    // and the report with the model-vs-measured figure beside the summary.
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("Cm_alpha") && stdout.contains("Theil"), "{stdout}");
    // One σ: the table's is the summary's std_error (here the coloured-residual σ), the
    // Cramér–Rao σ beside it, labelled.
    let (_, crb) = get("Cm_alpha");
    let std_error = v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "Cm_alpha")
        .unwrap()["std_error"]
        .as_f64()
        .unwrap();
    let row = stdout.lines().find(|l| l.contains("Cm_alpha ")).unwrap();
    assert!(row.contains(&format!("± {}", fmt2(std_error))), "{row} vs {std_error}");
    assert!(row.contains(&fmt2(crb)), "{row} vs {crb}");
    assert!(stdout.contains("Cramér–Rao σ") && stdout.contains("(coloured-residual)"), "{stdout}");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("Cm_q0") && html.contains("alpha_rad"), "report lacks the tables");
    assert!(html.contains("<svg") && out.join("fit.png").exists() && out.join("fit.svg").exists());
    let _ = std::fs::remove_dir_all(&out);
}

/// A batch fit stopped by `--max-iterations` reports its last iterate instead of failing: exit 0,
/// status `not_converged` with the reason, every estimate finite, and a likelihood no better
/// than the converged fit's (Gauss–Newton only descends); the bootstrap is not run on it. The
/// same record with the default limit converges on both criteria. Skips without `../shared`.
#[test]
fn val_a_batch_fit_stopped_by_the_iteration_limit_reports_its_last_iterate() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let model = workspace().join("models/hfb320_book_q0.toml");
    let base = ["--model", model.to_str().unwrap(), "--estimator", "oe"];
    let (done, _) = batch_replay(&data, "hfb320.toml", &base, "oe_limit_done");
    assert_eq!(done["status"], "converged");
    assert!(done["status_reason"].is_null());
    let args = [&base[..], &["--max-iterations", "2", "--bootstrap", "4"]].concat();
    let (v, html) = batch_replay(&data, "hfb320.toml", &args, "oe_limit_2");
    assert_eq!(v["status"], "not_converged");
    let why = v["status_reason"].as_str().unwrap();
    assert!(why.contains("iteration limit") && why.contains("after 2 iterations"), "{why}");
    assert_eq!(v["iterations"].as_array().unwrap().len(), 3);
    assert!(
        final_ln_det(&v) >= final_ln_det(&done),
        "{} vs {}",
        final_ln_det(&v),
        final_ln_det(&done)
    );
    // The last iterate still moves by more than its σ after 2 iterations: every parameter's
    // verdict is `not converged` (the fit's own status is not enough for a reader of one row).
    let last = v["iterations"].as_array().unwrap().last().unwrap().clone();
    assert!(last["max_step_sigma"].as_f64().unwrap() > 1.0, "{last}");
    for p in v["parameters"].as_array().unwrap() {
        assert!(p["estimate"].as_f64().is_some_and(f64::is_finite), "{p}");
        assert_eq!(p["status"], "not converged", "{p}");
    }
    for p in done["parameters"].as_array().unwrap() {
        assert_ne!(p["status"], "not converged", "{p}");
    }
    assert!(v["bootstrap"].is_null());
    let warnings: Vec<&str> =
        v["warnings"].as_array().unwrap().iter().filter_map(|w| w.as_str()).collect();
    assert!(warnings.iter().any(|w| w.starts_with("NOT CONVERGED")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.starts_with("bootstrap not run")), "{warnings:?}");
    assert!(html.contains("not_converged"), "the report does not say how the fit ended");
}

/// `replay --estimator fem` on the HFB-320 with Jategaonkar's model converges to a likelihood
/// at least as good as output error's: the filter-error model nests output error (process
/// noise at its lower bound is the output-error simulation), so its innovations' `ln det B`
/// at the optimum cannot exceed output error's residual `ln det R` on the same record and
/// model. Before the filter-error fit estimated `R` by maximum likelihood (it used
/// Jategaonkar's relaxation of `B` and `R`) it stopped without a descent direction after 21
/// iterations, `ln det B` having risen from −68.9 to −60.0 (module doc of
/// `output_error::filter_error`). Cm_alpha, fixed by the short-period frequency, agrees with
/// the published output-error value within 5 %. Skips without `../shared`.
#[test]
fn val_filter_error_converges_on_the_hfb320_to_a_likelihood_above_output_error() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let model = workspace().join("models/hfb320_jategaonkar.toml");
    let fit = |estimator: &str| {
        let args = ["--model", model.to_str().unwrap(), "--estimator", estimator];
        let (v, _) = batch_replay(&data, "hfb320.toml", &args, &format!("fem_hfb320_{estimator}"));
        assert_eq!(v["status"], "converged", "{estimator}");
        v
    };
    let (oe, fem) = (fit("oe"), fit("fem"));
    assert!(
        final_ln_det(&fem) <= final_ln_det(&oe),
        "FEM ln det B {} > OE ln det R {}",
        final_ln_det(&fem),
        final_ln_det(&oe)
    );
    let cm_alpha = fem["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "Cm_alpha")
        .unwrap()["estimate"]
        .as_f64()
        .unwrap();
    assert!((cm_alpha / -1.002 - 1.0).abs() < 0.05, "FEM Cm_alpha {cm_alpha}");
    assert!(!fem["process_noise"].as_array().unwrap().is_empty(), "F is reported");
}

/// `f16 sim` then `replay` of its `timeseries.csv` with the shipped `aeroident-sim.toml`, as a
/// user types them: no rejected row, nothing differentiated, every parameter identified
/// (the accuracy against the model's truth is `tests/all/sim_replay.rs`).
#[test]
fn val_f16_sim_output_replays_through_the_cli_with_the_shipped_mapping() {
    let out = tmp("sim6");
    let o = bin()
        .args(["f16", "sim"])
        .arg(workspace().join("scenarios/sim/six_axis_excitation.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = bin()
        .arg("replay")
        .arg(out.join("timeseries.csv"))
        .arg("--map")
        .arg(workspace().join("mappings/aeroident-sim.toml"))
        .arg("--out")
        .arg(out.join("replay"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("model: six-axis (default"), "six-axis by default: {err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("replay/summary.json")).unwrap())
            .unwrap();
    assert_eq!(v["samples_rejected"], 0);
    assert_eq!(v["status"], "complete");
    let params = v["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 30);
    assert!(params.iter().all(|p| p["estimate"].is_f64()), "all identified");
    let cl_da = params.iter().find(|p| p["name"] == "Cl_da").unwrap()["estimate"].as_f64();
    // The F-16's convention and the sample's: δa > 0 rolls left (Stevens & Lewis DLDA < 0).
    assert!(cl_da.unwrap() < 0.0, "the aileron sign: {cl_da:?}");
    let _ = std::fs::remove_dir_all(&out);
}

/// `--format` overrides the extension and gives the CSV's estimates from the same numbers as
/// whitespace text; a bad name lists the valid ones; a format without a reader says so.
#[test]
fn formats_by_flag_and_extension_through_the_cli() {
    let out = tmp("fmt");
    std::fs::create_dir_all(&out).unwrap();
    let io_data = workspace().join("crates/io/tests/data");
    // 60 rows of min.toml's columns, each a different sinusoid so the fit is determined.
    let header = "t,V,a,q,ax,az,de,qbar,qd";
    let rows: Vec<String> = (0..60)
        .map(|k| {
            let t = f64::from(k) * 0.1;
            let w = |f: f64, a: f64, c: f64| c + a * (f * t).sin();
            format!(
                "{t},{},{},{},{},{},{},{},{}",
                w(0.3, 5.0, 200.0),
                w(1.1, 1.0, 2.0),
                w(1.7, 2.0, 0.0),
                w(0.7, 0.02, 0.01),
                w(2.3, 0.1, -1.0),
                w(2.9, 1.0, 1.0),
                w(0.5, 3.0, 100.0),
                w(3.7, 1.0, 0.0)
            )
        })
        .collect();
    let csv_file = out.join("rec.csv");
    std::fs::write(&csv_file, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
    // The same rows, whitespace-separated, without the header, in a file whose extension
    // names no format.
    let data = out.join("rec.log");
    let text: String = rows.iter().map(|l| format!("  {}\n", l.replace(',', "   "))).collect();
    std::fs::write(&data, text).unwrap();
    let names: Vec<String> = header.split(',').map(|n| format!("\"{n}\"")).collect();
    let map = out.join("m.toml");
    let min = std::fs::read_to_string(io_data.join("min.toml")).unwrap();
    std::fs::write(&map, format!("{min}[columns]\nnames = [{}]\n", names.join(", "))).unwrap();
    let replay = |format: Option<&str>, file: &std::path::Path, dir: &str| {
        let mut c = bin();
        c.arg("replay").arg(file).arg("--map").arg(&map).arg("--out").arg(out.join(dir));
        if let Some(fm) = format {
            c.args(["--format", fm]);
        }
        c.output().unwrap()
    };
    let o = replay(Some("asc"), &data, "asc");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = replay(None, &csv_file, "csv");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = |dir: &str| -> serde_json::Value {
        let text = std::fs::read_to_string(out.join(dir).join("summary.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    };
    let (a, c) = (summary("asc"), summary("csv"));
    assert_eq!(a["samples_read"], 60, "{a}");
    assert_eq!(a["status"], "complete", "identified: {a}");
    for key in ["samples_read", "samples_rejected", "status", "parameters"] {
        assert_eq!(a[key], c[key], "{key}");
    }
    // Read as CSV (the extension names no format), the first row is a header without `t`.
    let o = replay(None, &data, "x");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("column `t` for channel `time` is missing"),
        "{err}"
    );
    let o = replay(Some("xls"), &data, "x");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("csv, asc, mat, ulog, dataflash"), "{err}");
    let o = replay(None, &out.join("flight.ulg"), "x");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("flight.ulg"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

/// The real PX4 ULog (`../shared/flightdata/px4_ardupilot/`, a scaled F-16 RC jet) replays end
/// to end through the CLI with the shipped `mappings/px4-fixedwing.toml`: the format is taken
/// from the `.ulg` extension, the airborne part gives samples (the io crate's
/// `multirate_logs` test checks the same 453 samples against the independent pyulog
/// inventory), the taxi rows are rejected with a reason, and the run ends with a summary.
/// Skips without `../shared`; fails under CI if the log is missing.
#[test]
fn val_real_px4_ulog_replays_through_the_cli_with_the_shipped_mapping() {
    let Some(data) = common::shared("px4_ardupilot/f16capstone_log_52_2021-5-22-12-42-56.ulg")
    else {
        return;
    };
    let out = tmp("ulog_f16");
    let o = bin()
        .args(["replay"])
        .arg(&data)
        .arg("--map")
        .arg(workspace().join("mappings/px4-fixedwing.toml"))
        .args(["--estimator", "rls", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // 2999 aligned rows at 50 Hz; 2546 taxi rows without a defined α/β, and 4 rows at the
    // ends of the airborne part inside the rate differentiator's window.
    assert_eq!(v["samples_read"], 2999, "{}", v["samples_read"]);
    assert_eq!(v["samples_rejected"], 2550, "{}", v["samples_rejected"]);
    assert_ne!(v["status"], "diverged");
    let _ = std::fs::remove_dir_all(&out);
}

/// The real ArduPlane DataFlash ground log (`../shared/flightdata/px4_ardupilot/`, a minimal
/// LOG_BITMASK without IMU and RCOU) through the CLI: the shipped `arduplane.toml` refuses it
/// naming the missing message, and the shipped `arduplane-minimal.toml` reads, aligns and maps
/// it end to end, then rejects every row for the reason that holds (carried on the ground at
/// ≤ 1.9 m/s, α/β undefined below 3 m/s) — the replay says so rather than identifying
/// anything. Skips without `../shared`; fails under CI if the log is missing.
#[test]
fn val_real_dataflash_log_replays_through_the_cli_with_the_shipped_mappings() {
    let Some(data) = common::shared("px4_ardupilot/pyflightcoach_center_0003.bin") else { return };
    let run = |mapping: &str| {
        let dir =
            std::env::temp_dir().join(format!("aeroident-df-{}", std::process::id())).join(mapping);
        let o = bin()
            .args(["replay"])
            .arg(&data)
            .arg("--map")
            .arg(workspace().join("mappings").join(mapping))
            .arg("--model")
            .arg(workspace().join("models/moments_in_rates.toml"))
            .arg("--out")
            .arg(&dir)
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (code, err) = run("arduplane.toml");
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("IMU.GyrX") && err.contains("no topic/message `IMU`"), "{err}");
    let (code, err) = run("arduplane-minimal.toml");
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("no usable samples") && err.contains("column `air."), "{err}");
}

/// `replay --estimator oe --initial-states estimate` on ATTAS Elv2: the initial state becomes
/// an unknown of the fit (Jategaonkar's `parFlagX0 = 1`). Output error with the initial state
/// fixed at the first sample is the same model with those unknowns held, so at the optimum
/// the estimated-state fit's `ln det R` cannot be larger (it is 3.8 lower: −52.49 against
/// −56.32, docs/real-data.md). The estimated states are reported with σ and stay within a
/// degree of α's first measurement and within 5 m/s of V's; the summary and the report say
/// which setting was used; the flag is refused for a real-time estimator. Skips without
/// `../shared`.
#[test]
fn val_output_error_estimates_the_initial_state_on_request() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/fAttasElv2.csv") else { return };
    let fit = |setting: &str| {
        let args = ["--estimator", "oe", "--initial-states", setting];
        let (v, html) = batch_replay(&data, "attas.toml", &args, &format!("oe_x0_{setting}"));
        assert!(html.contains("initial states") && html.contains(setting), "report setting");
        v
    };
    let fixed = fit("first-sample");
    let free = fit("estimate");
    for (v, setting) in [(&fixed, "first-sample"), (&free, "estimate")] {
        assert_eq!(v["status"], "converged");
        assert_eq!(v["initial_states"], setting);
    }
    assert!(fixed["estimated_initial_states"].as_array().unwrap().is_empty());
    assert!(
        final_ln_det(&free) <= final_ln_det(&fixed) + 1e-6,
        "free initial state: ln det R {} > fixed {}",
        final_ln_det(&free),
        final_ln_det(&fixed)
    );
    let x0 = free["estimated_initial_states"].as_array().unwrap();
    assert!(!x0.is_empty());
    let first = |column: &str| -> f64 {
        let text = std::fs::read_to_string(&data).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let k = header.iter().position(|h| h.trim() == column).unwrap();
        lines.next().unwrap().split(',').nth(k).unwrap().trim().parse().unwrap()
    };
    for entry in x0 {
        let (name, value, sigma) =
            (entry[0].as_str().unwrap(), entry[1].as_f64().unwrap(), entry[2].as_f64().unwrap());
        assert!(name.starts_with("x0_m1_"), "{name}");
        assert!(value.is_finite() && sigma.is_finite() && sigma > 0.0, "{entry}");
        if name.ends_with("_alpha_rad") {
            let a0 = first("alpha_deg").to_radians();
            assert!((value - a0).abs() < 1f64.to_radians(), "{name} {value} vs {a0}");
        }
        if name.ends_with("_vt_mps") {
            let v0 = first("vtas_mps");
            assert!((value - v0).abs() < 5.0, "{name} {value} vs {v0}");
        }
    }
    let o = bin()
        .args(["replay"])
        .arg(&data)
        .arg("--map")
        .arg(workspace().join("mappings/attas.toml"))
        .args(["--estimator", "rls", "--initial-states", "estimate"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--initial-states"));
}

/// `replay --estimator oe --bootstrap 20` on the HFB-320 (book model): the estimates are the
/// plain fit's (the bootstrap changes the σ only); every parameter's reported σ is its
/// bootstrap σ (with the sample-timing σ in quadrature), positive and at least 0.65 of its Cramér–Rao σ (without process noise the
/// bootstrap of this model is the Cramér–Rao bound, estimators' unit test; process noise only
/// adds); the summary names the replicas, the seed and the filter-error noise levels they were
/// flown with (positive `F` on V and α); a second run gives the same σ (seeded); and the flag
/// is refused for `fem` and for a real-time estimator. Skips without `../shared`.
#[test]
fn val_output_error_bootstrap_sigma_on_request() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let model = workspace().join("models/hfb320_book_q0.toml");
    let model = model.to_str().unwrap();
    // Initial states estimated, so that their σ is the bootstrap's too.
    let x0 = ["--initial-states", "estimate"];
    let plain_args = ["--model", model, "--estimator", "oe", x0[0], x0[1]];
    let plain = batch_replay(&data, "hfb320.toml", &plain_args, "oe_plain").0;
    let args = ["--model", model, "--estimator", "oe", x0[0], x0[1], "--bootstrap", "20"];
    let (boot, html) = batch_replay(&data, "hfb320.toml", &args, "oe_boot");
    let again = batch_replay(&data, "hfb320.toml", &args, "oe_boot_again").0;
    assert!(plain["bootstrap"].is_null());
    let b = &boot["bootstrap"];
    assert_eq!(b["refits"], 20);
    assert_eq!(b["failed"], 0);
    assert_eq!(b["seed"], 1);
    let f = b["process_noise"].as_array().unwrap();
    let names: Vec<&str> = f.iter().map(|e| e["state"].as_str().unwrap()).collect();
    assert_eq!(names, ["vt_mps", "alpha_rad"]);
    assert!(f.iter().all(|e| e["f"].as_f64().unwrap() > 0.0), "{f:?}");
    let params = |v: &serde_json::Value| v["parameters"].as_array().unwrap().clone();
    for ((p, q), r) in params(&plain).iter().zip(params(&boot)).zip(params(&again)) {
        assert_eq!(p["name"], q["name"]);
        assert_eq!(p["estimate"], q["estimate"], "the bootstrap changed the estimate");
        assert!(p["bootstrap_std_error"].is_null());
        let (sb, crb) =
            (q["bootstrap_std_error"].as_f64().unwrap(), q["crb_std_error"].as_f64().unwrap());
        // The reported σ is the bootstrap's with the sample-timing and unmodelled σ in
        // quadrature.
        let timing = q["timing_std_error"].as_f64().unwrap();
        let unmodelled = q["unmodelled_std_error"].as_f64().unwrap_or(0.0);
        let reported = q["std_error"].as_f64().unwrap();
        let want = sb.hypot(timing).hypot(unmodelled);
        assert!((reported - want).abs() <= 1e-12 * reported, "{}: σ", q["name"]);
        assert!(sb > 0.65 * crb, "{}: bootstrap σ {sb} vs Cramér–Rao {crb}", q["name"]);
        assert_eq!(q["bootstrap_std_error"], r["bootstrap_std_error"], "not reproducible");
        // The bias estimate is the refits' mean less the estimate: within 2σ of zero (20
        // replicas of a fit near its optimum; their mean scatters 0.22σ), never the mean itself.
        assert!(p["bootstrap_bias"].is_null());
        let bias = q["bootstrap_bias"].as_f64().unwrap();
        assert!(bias.abs() < 2.0 * sb, "{}: bootstrap bias {bias} vs σ {sb}", q["name"]);
        assert_eq!(q["bootstrap_bias"], r["bootstrap_bias"], "not reproducible");
    }
    // The estimated initial states: same values, σ no longer the coloured one, reproducible.
    let x0s = |v: &serde_json::Value| v["estimated_initial_states"].as_array().unwrap().clone();
    let (xp, xb, xa) = (x0s(&plain), x0s(&boot), x0s(&again));
    assert!(!xp.is_empty() && xp.len() == xb.len(), "{xp:?} / {xb:?}");
    for ((p, q), r) in xp.iter().zip(&xb).zip(&xa) {
        assert_eq!((&p[0], &p[1]), (&q[0], &q[1]), "the bootstrap changed an initial state");
        let (sp, sb) = (p[2].as_f64().unwrap(), q[2].as_f64().unwrap());
        assert!(sb > 0.0 && sb != sp, "{}: σ {sb} is still the coloured {sp}", q[0]);
        assert_eq!(q[2], r[2], "{}: not reproducible", q[0]);
    }
    assert!(html.contains("bootstrap"), "the report does not say the σ is the bootstrap's");
    assert!(html.contains("bootstrap bias estimate"), "the report does not give the bias estimate");
    for (estimator, needle) in [("fem", "output error"), ("rls", "--bootstrap")] {
        let o = bin()
            .args(["replay"])
            .arg(&data)
            .arg("--map")
            .arg(workspace().join("mappings/hfb320.toml"))
            .args(["--estimator", estimator, "--bootstrap", "5", "--out"])
            .arg(tmp("oe_boot_refused"))
            .output()
            .unwrap();
        assert!(!o.status.success(), "{estimator} accepted --bootstrap");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("bootstrap") && err.contains(needle), "{estimator}: {err}");
    }
}

/// ATTAS AilRud1, initial states estimated: the replicas carry process noise on `β` only, and
/// the initial bank angles' bootstrap σ falls far below their coloured-residual σ (0.04–0.06×
/// measured with 30 replicas): the summary warns, naming them, and flags none of the structure
/// parameters (0.65× and more, measured with 30 replicas).
#[test]
fn val_output_error_bootstrap_flags_a_sigma_far_below_the_coloured_one() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv") else {
        return;
    };
    let args = ["--estimator", "oe", "--initial-states", "estimate", "--bootstrap", "10"];
    let v = batch_replay(&data, "attas_lateral.toml", &args, "oe_boot_flags").0;
    let flagged: Vec<&str> = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .filter(|w| w.contains("its coloured-residual σ"))
        .collect();
    for m in 1..=2 {
        let name = format!("x0_m{m}_phi_rad");
        assert!(flagged.iter().any(|w| w.contains(&name)), "{name} not flagged: {flagged:?}");
    }
    let params = v["parameters"].as_array().unwrap();
    for p in params {
        let name = p["name"].as_str().unwrap();
        assert!(
            !flagged.iter().any(|w| w.contains(&format!(" of {name} is"))),
            "{name} flagged: {flagged:?}"
        );
    }
}

/// One setting, one value: a key given by its flag and by `--estimator-option`, or by
/// `--estimator-option` twice, is refused naming both as typed (the last one silently won:
/// `--forgetting 0.98 --estimator-option forgetting=0.99` ran with 0.99, recorded nowhere); a
/// second key smuggled after a newline, an empty key or an empty value is a form error, not
/// dropped.
#[test]
fn errors_one_setting_has_one_value() {
    let twice = ["--forgetting", "0.98", "--estimator-option", "forgetting=0.99"];
    let (ok, err) = replay_good(&twice, "twice-flag");
    assert!(!ok, "{err}");
    assert!(
        err.contains("`forgetting` is set twice, by --forgetting 0.98 and by --estimator-option forgetting=0.99"),
        "{err}"
    );
    let rls_iv = ["--estimator", "rls-iv", "--instrument-delay", "5"];
    let (ok, err) = replay_good(
        &[&rls_iv[..], &["--estimator-option", "instrument_delay=7"][..]].concat(),
        "twice-delay",
    );
    assert!(
        !ok && err.contains("`instrument_delay` is set twice, by --instrument-delay 5"),
        "{err}"
    );
    let opt = |v: &'static str| ["--estimator-option", v];
    let (ok, err) =
        replay_good(&[&opt("forgetting=0.98")[..], &opt("forgetting=0.99")[..]].concat(), "tw2");
    assert!(!ok && err.contains("by --estimator-option forgetting=0.98 and by"), "{err}");
    for (bad, needle) in [
        ("forgetting=0.99\nmax_iterations=3", "one value after `forgetting=` on one line"),
        ("=0.99", "the key must be a name"),
        ("forgetting=", "one value after `forgetting=`"),
    ] {
        let (ok, err) = replay_good(&opt(bad), "form");
        assert!(!ok && err.contains(needle), "{bad:?}: {err}");
    }
}

/// `--estimates-every 0.5` on the 10-Hz HFB-320 record: the rows are those of the full-rate
/// `estimates.csv` (`--estimates-every 0`) that the rule picks, computed here from the full
/// file (the first row, then each row at least 0.95 × 0.5 s after the last one kept, and the
/// last row), character for character. The default (0.1 s) keeps every row of this 10-Hz
/// record although its intervals jitter from 0.09999 to 0.10001 s. A negative interval is
/// refused naming the option.
#[test]
fn estimates_every_keeps_one_row_per_interval_and_the_last() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else {
        return;
    };
    let full = estimates_csv(&data, &["--estimates-every", "0"], "every-full");
    assert_eq!(estimates_csv(&data, &[], "every-default"), full);
    let every = estimates_csv(&data, &["--estimates-every", "0.5"], "every-half");
    let rows: Vec<&str> = full.lines().skip(1).collect();
    let t = |row: &str| row.split(',').next().unwrap().parse::<f64>().unwrap();
    let mut want = vec![full.lines().next().unwrap()];
    let mut last: Option<f64> = None;
    for (k, row) in rows.iter().enumerate() {
        let keep = last.is_none_or(|l| t(row) - l >= 0.5 * 0.95);
        if keep {
            last = Some(t(row));
        }
        if keep || k + 1 == rows.len() {
            want.push(row);
        }
    }
    assert_eq!(every.lines().collect::<Vec<_>>(), want);
    assert!(want.len() < rows.len() / 4, "{} of {} rows", want.len(), rows.len());
    let o = bin().args(["replay", "x.csv", "--map", "m.toml", "--estimates-every=-1"]).output();
    let err = String::from_utf8_lossy(&o.unwrap().stderr).to_string();
    assert!(err.contains("--estimates-every") && err.contains("0 or above"), "{err}");
}

/// A 700-s six-axis `f16 sim` record at 50 Hz whose inputs are in its first 16 s, replayed by
/// default: the record runs longer than the 600 s one kinematic stretch is judged whole on,
/// so the EKF and the batch fits of the panel run on its manoeuvres (a warning names the
/// window, which holds the inputs and not the 680 s of steady flight after them), and output
/// error, which refuses a 35,000-sample six-axis fit for its memory, converges there. The
/// estimates file keeps one row per 0.1 s by default (every fifth sample) and the last
/// sample's.
#[test]
fn a_long_record_s_panel_runs_its_costly_methods_on_the_manoeuvres() {
    let dir = tmp("long-panel");
    std::fs::create_dir_all(&dir).unwrap();
    let scenario =
        std::fs::read_to_string(workspace().join("scenarios/sim/six_axis_excitation.toml"))
            .unwrap()
            .replace("duration_s = 16.0", "duration_s = 700.0")
            .replace("dt_s = 0.01", "dt_s = 0.02");
    assert!(scenario.contains("duration_s = 700.0") && scenario.contains("dt_s = 0.02"));
    std::fs::write(dir.join("long.toml"), scenario).unwrap();
    let sim = dir.join("sim");
    let o = bin().args(["f16", "sim"]).arg(dir.join("long.toml")).arg("--out").arg(&sim).output();
    let o = o.unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = bin()
        .arg("replay")
        .arg(sim.join("timeseries.csv"))
        .arg("--map")
        .arg(workspace().join("mappings/aeroident-sim.toml"))
        .arg("--out")
        .arg(dir.join("r"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r/summary.json")).unwrap())
            .unwrap();
    let warnings: Vec<&str> =
        v["warnings"].as_array().unwrap().iter().filter_map(|w| w.as_str()).collect();
    let long = warnings.iter().find(|w| w.contains("the EKF and the batch fits ran on its best"));
    let long = long.unwrap_or_else(|| panic!("no long-record warning: {warnings:?}"));
    let span = long.split("window(s): ").nth(1).unwrap().split(';').next().unwrap();
    let ends: Vec<f64> = span
        .split(", ")
        .flat_map(|w| w.trim_end_matches(" s").split('–').map(|x| x.parse::<f64>().unwrap()))
        .collect();
    assert!(ends[0] < 2.0 && *ends.last().unwrap() < 60.0, "the inputs' window: {span}");
    let methods = v["cross_check"]["methods"].as_array().unwrap();
    let oe = methods.iter().find(|m| m["method"] == "oe").unwrap();
    assert_eq!(oe["status"], "converged", "{oe}");
    let csv = std::fs::read_to_string(dir.join("r/estimates.csv")).unwrap();
    let rows = csv.lines().count() - 1;
    assert!((6_990..=7_010).contains(&rows), "one row per 0.1 s of 700 s: {rows}");
    let t_last = csv.lines().last().unwrap().split(',').next().unwrap().parse::<f64>().unwrap();
    assert!((t_last - 700.0).abs() < 1e-9, "the last sample's row: {t_last}");
    let _ = std::fs::remove_dir_all(&dir);
}
