//! Writes the samples `aeroident replay` feeds its estimator for a record, as CSV on stdout,
//! for a C program to feed the C library the same ones (`examples/c/replay_samples.c`).
//!
//! ```text
//! cargo run --release -p aeroident-capi --example conditioned_samples -- \
//!     RECORD MAPPING MODEL KIND [OPTIONS] > samples.csv
//! ```
//!
//! The replay is `aeroident replay RECORD --map MAPPING --model MODEL --estimator KIND` with the
//! command line's defaults (derivatives `auto`, differentiator window 5, spike screen on) and
//! the estimator options OPTIONS as TOML (`forgetting = 0.99`), the `--estimator-option` pairs.

use aeroident_capi::replayed::write_samples_csv;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_pipelines::Named;
use aeroident_pipelines::estimators::{EstimatorKind, parse_options};
use aeroident_pipelines::replay::ReplayOptions;
use aeroident_pipelines::replay::fed::fed_samples;
use std::path::Path;

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [record, mapping, model, kind, rest @ ..] = args.as_slice() else {
        return Err("usage: conditioned_samples RECORD MAPPING MODEL KIND [OPTIONS]".into());
    };
    let mapping = Mapping::from_path(Path::new(mapping)).map_err(|e| e.to_string())?;
    let model = ModelSpec::from_arg(model).map_err(|e| e.to_string())?;
    let kind = EstimatorKind::from_name(kind).ok_or(format!("unknown estimator `{kind}`"))?;
    let table: toml::Table =
        rest.first().map_or("", |s| s.as_str()).parse().map_err(|e| format!("OPTIONS: {e}"))?;
    let estimator_options = parse_options(kind, table.iter().map(|(k, v)| (k.as_str(), v.clone())))
        .map_err(|e| e.to_string())?;
    let opts = ReplayOptions {
        estimator: kind,
        model: Some(model),
        estimator_options,
        ..Default::default()
    };
    let reader = open_log(record, None, &mapping).map_err(|e| e.to_string())?;
    let (fed, _) = fed_samples(reader, &mapping, &opts).map_err(|e| e.to_string())?;
    let rows: Vec<_> = fed.iter().map(|f| (f.manoeuvre, f.sample)).collect();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    write_samples_csv(&mut out, &rows).map_err(|e| e.to_string())
}
