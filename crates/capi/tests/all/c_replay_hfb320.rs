//! The C example (`examples/c/replay_samples.c`, compiled with gcc against the committed header
//! and `libaeroident_capi.a`, and again against `libaeroident_capi.so`) replays the HFB-320
//! record (Jategaonkar 2015, test case 4) through the C library and prints the same estimates,
//! row for row, as the command line's `estimates.csv` and `summary.json`, to 1e-12 (each σ of
//! `estimates.csv` to the four significant digits it is written with), for `rls`, `ftr` and
//! `ekf`.
//!
//! The C program is fed the samples the command line's estimator is fed
//! (`aeroident_pipelines::replay::fed::fed_samples`, written as CSV): the record's reading, mapping,
//! spike screen and conditioning stay in the library, the C caller feeds their output.
//! Skips without `../shared` (fails under `CI=true`).

use crate::common::{
    cli_binary, compile_c, compile_c_shared, have_gcc, scratch, shared, workspace,
};
use aeroident_capi::replayed::write_samples_csv;
use aeroident_io::replay_output::SIGMA_DIGITS;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_pipelines::Named;
use aeroident_pipelines::estimators::{EstimatorKind, parse_options};
use aeroident_pipelines::replay::ReplayOptions;
use aeroident_pipelines::replay::fed::fed_samples;
use std::path::Path;
use std::process::Command;

const RECORD: &str = "jategaonkar_hfb320_attas/csv/hfb320_1_10.csv";
const MAPPING: &str = "mappings/hfb320.toml";
const MODEL: &str = "models/hfb320_jategaonkar.toml";

/// `aeroident replay` of the record with `kind` and `options` (`--estimator-option` pairs):
/// its `estimates.csv` and `summary.json`.
fn cli(
    bin: &Path,
    record: &Path,
    kind: &str,
    options: &[&str],
    out: &Path,
) -> (String, serde_json::Value) {
    let mut c = Command::new(bin);
    c.arg("replay").arg(record).arg("--map").arg(workspace().join(MAPPING));
    c.arg("--model").arg(workspace().join(MODEL)).args(["--estimator", kind]);
    for o in options {
        c.args(["--estimator-option", o]);
    }
    let o = c.arg("--out").arg(out).output().unwrap();
    assert!(o.status.success(), "aeroident replay: {}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    (csv, serde_json::from_str(&summary).unwrap())
}

/// The samples the command line's estimator is fed for the same replay, written to `path`.
fn samples(record: &Path, kind: &str, options: &str, path: &Path) -> usize {
    let mapping = Mapping::from_path(&workspace().join(MAPPING)).unwrap();
    let kind = EstimatorKind::from_name(kind).unwrap();
    let table: toml::Table = options.parse().unwrap();
    let estimator_options =
        parse_options(kind, table.iter().map(|(k, v)| (k.as_str(), v.clone()))).unwrap();
    let model = ModelSpec::from_path(&workspace().join(MODEL)).unwrap();
    let opts = ReplayOptions {
        estimator: kind,
        model: Some(model),
        estimator_options,
        ..Default::default()
    };
    let reader = open_log(record.to_str().unwrap(), None, &mapping).unwrap();
    let (fed, _) = fed_samples(reader, &mapping, &opts).unwrap();
    let rows: Vec<_> = fed.iter().map(|f| (f.manoeuvre, f.sample)).collect();
    let mut file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    write_samples_csv(&mut file, &rows).unwrap();
    rows.len()
}

/// The C program run for `kind` with `options` over the samples in `samples`, succeeded.
fn run_c(program: &Path, kind: &str, samples: &Path, options: &str) -> std::process::Output {
    let o = Command::new(program)
        .arg(kind)
        .arg(workspace().join(MODEL))
        .arg(samples)
        .arg(options)
        .output()
        .unwrap();
    assert!(o.status.success(), "{kind}: {}", String::from_utf8_lossy(&o.stderr));
    o
}

/// The C program's estimates for `kind` with `options` over the samples in `samples`.
fn c_estimates(program: &Path, kind: &str, samples: &Path, options: &str) -> String {
    String::from_utf8(run_c(program, kind, samples, options).stdout).unwrap()
}

/// The C program's final verdicts (`verdict NAME STATUS` lines on its stderr), in order.
fn c_verdicts(program: &Path, kind: &str, samples: &Path, options: &str) -> Vec<(String, String)> {
    let err = String::from_utf8(run_c(program, kind, samples, options).stderr).unwrap();
    err.lines()
        .filter_map(|l| l.strip_prefix("verdict "))
        .map(|l| {
            let (name, status) = l.split_once(' ').unwrap();
            (name.to_string(), status.to_string())
        })
        .collect()
}

/// The C verdicts against the command line's: the C caller's evidence is a subset of the
/// command line's (no record-level tests, no sample-timing σ), so a parameter the command line
/// identifies the C library identifies too, and one without an estimate is `not identified`
/// in both.
fn check_verdicts(kind: &str, c: &[(String, String)], summary: &serde_json::Value) {
    let params = summary["parameters"].as_array().unwrap();
    assert_eq!(c.len(), params.len(), "{kind}: {c:?}");
    for ((name, status), p) in c.iter().zip(params) {
        assert_eq!(p["name"].as_str().unwrap(), name, "{kind}");
        let cli = p["status"].as_str().unwrap();
        if cli == "identified" || cli == "not identified" {
            assert_eq!(status, cli, "{kind} {name}: {p}");
        }
    }
}

/// The largest difference between the estimates of two tables, relative to max(1, |value|),
/// with the header, the number of rows and the identified (non-empty) cells required equal,
/// and each σ of `cli` (written to [`SIGMA_DIGITS`] significant digits) required to be `c`'s
/// rounded: within half a unit of its fourth digit, 5 × 10⁻⁴ of it.
fn largest_difference(c: &str, cli: &str) -> Result<f64, String> {
    let (c, cli): (Vec<&str>, Vec<&str>) = (c.lines().collect(), cli.lines().collect());
    if c.first() != cli.first() {
        return Err(format!("headers differ:\n{:?}\n{:?}", c.first(), cli.first()));
    }
    if c.len() != cli.len() {
        return Err(format!("{} rows against the command line's {}", c.len(), cli.len()));
    }
    let n = c[0].split(',').count() / 2;
    let mut worst = 0.0f64;
    for (row, (a, b)) in c.iter().zip(&cli).enumerate().skip(1) {
        for (col, (x, y)) in a.split(',').zip(b.split(',')).enumerate() {
            match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(x), Ok(y)) if col > n => {
                    if (x - y).abs() > 0.5 * 10f64.powi(1 - SIGMA_DIGITS as i32) * x.abs() {
                        return Err(format!("row {row}, σ column {col}: {y} is not {x} rounded"));
                    }
                }
                (Ok(x), Ok(y)) => worst = worst.max((x - y).abs() / y.abs().max(1.0)),
                _ if x.is_empty() && y.is_empty() => {}
                _ => return Err(format!("row {row}, column {col}: `{x}` against `{y}`")),
            }
        }
    }
    Ok(worst)
}

/// The summary's final estimates and σ against the last row of the C program's estimates (its
/// σ with the summary's sample-timing and unmodelled σ added in quadrature).
fn check_summary(kind: &str, c: &str, summary: &serde_json::Value) {
    let header: Vec<&str> = c.lines().next().unwrap().split(',').collect();
    let last: Vec<&str> = c.lines().last().unwrap().split(',').collect();
    let params = summary["parameters"].as_array().unwrap();
    let n = params.len();
    assert_eq!(header.len(), 1 + 2 * n, "{kind}");
    for (i, p) in params.iter().enumerate() {
        assert_eq!(p["name"].as_str().unwrap(), header[1 + i], "{kind}");
        // The summary's σ holds the sample-timing test's σ (the CLI refits the record; a live
        // feed through the C ABI cannot be read twice) and the unmodelled σ in quadrature, so
        // the C σ is set beside it with both added.
        let timing = p["timing_std_error"].as_f64().unwrap_or(0.0);
        let timing = timing.hypot(p["unmodelled_std_error"].as_f64().unwrap_or(0.0));
        for (key, cell) in [("estimate", last[1 + i]), ("std_error", last[1 + n + i])] {
            let from_c: Option<f64> = cell.parse().ok();
            let from_c = from_c.map(|a| if key == "std_error" { a.hypot(timing) } else { a });
            let from_cli = p[key].as_f64();
            match (from_c, from_cli) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{kind} {key} {a} {b}")
                }
                (a, b) => assert_eq!(a, b, "{kind}: {} {key}", header[1 + i]),
            }
        }
    }
}

#[test]
fn c_example_replays_hfb320_with_the_command_lines_estimates() {
    let Some(record) = shared(RECORD) else { return };
    if !have_gcc() {
        return;
    }
    let bin = cli_binary();
    let dir = scratch("hfb320");
    let program = dir.join("replay_samples");
    compile_c("examples/c/replay_samples.c", &program);
    let shared_program = dir.join("replay_samples_shared");
    compile_c_shared("examples/c/replay_samples.c", &shared_program);
    for (kind, options) in [("rls", ""), ("ftr", "forgetting = 0.999"), ("ekf", "")] {
        let cli_options: Vec<String> =
            options.split_terminator('\n').map(|l| l.replace(" = ", "=")).collect();
        let cli_options: Vec<&str> = cli_options.iter().map(String::as_str).collect();
        let (csv, summary) =
            cli(&bin, &record, kind, &cli_options, &dir.join(format!("cli-{kind}")));
        let fed = dir.join(format!("samples-{kind}.csv"));
        let n = samples(&record, kind, options, &fed);
        assert!(n > 500, "{kind}: {n} samples fed");
        let from_c = c_estimates(&program, kind, &fed, options);
        let worst = largest_difference(&from_c, &csv).unwrap_or_else(|e| panic!("{kind}: {e}"));
        eprintln!("{kind}: {} rows, largest relative difference {worst:e}", csv.lines().count());
        assert!(worst <= 1e-12, "{kind}: {worst:e}");
        check_summary(kind, &from_c, &summary);
        check_verdicts(kind, &c_verdicts(&program, kind, &fed, options), &summary);
        // Linked against the shared library instead: the same output.
        assert_eq!(c_estimates(&shared_program, kind, &fed, options), from_c, "{kind}: shared");
        // The comparison sees a difference: another forgetting factor (RLS) or no option
        // (FTR) moves the estimates by far more than 1e-12.
        if kind != "ekf" {
            let other = if options.is_empty() { "forgetting = 0.99" } else { "" };
            let moved = c_estimates(&program, kind, &fed, other);
            let d = largest_difference(&moved, &csv);
            assert!(d.as_ref().is_err() || *d.as_ref().unwrap() > 1e-6, "{kind}: {d:?}");
        }
    }
}
