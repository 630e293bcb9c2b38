//! [`run_result_from_json`]: a [`RunResult`] back from its JSON form (the per-run results a
//! distributed campaign sends between processes, the Python bindings' `montecarlo_reduce`).

use serde_json::Value;

use super::{EstimatorRun, ParamRun, RunResult};
use aeroident_io::ParameterResult;

/// The inverse of `serde_json::to_value(&RunResult)`: floats are carried exactly; `restarts`,
/// `sigma_candidates`, `bootstrap_failed` and `bootstrap_bias` may be absent (results of older
/// versions), a non-string `failure` is no failure, a non-boolean `primary` is `false`.
///
/// # Errors
/// A message `per-run result: …` naming the key that is missing or of the wrong type.
pub fn run_result_from_json(v: &Value) -> Result<RunResult, String> {
    let outcome = field(v, "outcome")?;
    let outcome = if let Some(e) = outcome.get("Err") {
        Err(e.as_str().unwrap_or_default().to_owned())
    } else {
        let ests = outcome
            .get("Ok")
            .and_then(Value::as_array)
            .ok_or("per-run result: `outcome` is neither Ok nor Err")?;
        Ok(ests.iter().map(estimator_run).collect::<Result<Vec<_>, _>>()?)
    };
    Ok(RunResult { index: u64_of(v, "index")?, sensor_seed: u64_of(v, "sensor_seed")?, outcome })
}

fn estimator_run(e: &Value) -> Result<EstimatorRun, String> {
    let params = field(e, "params")?
        .as_array()
        .ok_or("per-run result: `params` is not a list")?
        .iter()
        .map(param_run)
        .collect::<Result<Vec<_>, _>>()?;
    Ok(EstimatorRun {
        name: string(e, "name")?,
        failure: field(e, "failure")?.as_str().map(str::to_owned),
        nis: opt_f64(e, "nis")?,
        restarts: match e.get("restarts") {
            None | Some(Value::Null) => 0,
            Some(x) => x
                .as_u64()
                .and_then(|v| u32::try_from(v).ok())
                .ok_or("per-run result: `restarts` is not a count")?,
        },
        iterations: match field(e, "iterations")? {
            Value::Null => None,
            x => Some(x.as_u64().ok_or("per-run result: `iterations` is not an integer")? as usize),
        },
        fit_wall_s: opt_f64(e, "fit_wall_s")?,
        sigma_candidates: match e.get("sigma_candidates") {
            None | Some(Value::Null) => Vec::new(),
            Some(x) => serde_json::from_value(x.clone())
                .map_err(|e| format!("per-run result: `sigma_candidates`: {e}"))?,
        },
        bootstrap_failed: match e.get("bootstrap_failed") {
            None | Some(Value::Null) => None,
            Some(x) => {
                Some(x.as_u64().ok_or("per-run result: `bootstrap_failed` is not a count")? as usize)
            }
        },
        bootstrap_bias: opt_f64_list(e, "bootstrap_bias")?,
        params,
    })
}

fn param_run(p: &Value) -> Result<ParamRun, String> {
    let result = ParameterResult {
        name: string(p, "name")?,
        estimate: opt_f64(p, "estimate")?,
        std_error: opt_f64(p, "std_error")?,
        std_error_source: match field(p, "std_error_source")? {
            Value::Null => None,
            x => Some(
                serde_json::from_value(x.clone())
                    .map_err(|e| format!("per-run result: `std_error_source`: {e}"))?,
            ),
        },
        crb_std_error: opt_f64(p, "crb_std_error")?,
        timing_std_error: match p.get("timing_std_error") {
            None => None,
            Some(_) => opt_f64(p, "timing_std_error")?,
        },
        unmodelled_std_error: match p.get("unmodelled_std_error") {
            None => None,
            Some(_) => opt_f64(p, "unmodelled_std_error")?,
        },
        reference: opt_f64(p, "reference")?,
        reference_check: match p.get("reference_check") {
            None | Some(Value::Null) => None,
            Some(x) => Some(
                serde_json::from_value(x.clone())
                    .map_err(|e| format!("per-run result: `reference_check`: {e}"))?,
            ),
        },
        status: string(p, "status")?,
        flags: serde_json::from_value(field(p, "flags")?.clone())
            .map_err(|e| format!("per-run result: `flags`: {e}"))?,
        notes: match p.get("notes") {
            None | Some(Value::Null) => Vec::new(),
            Some(x) => serde_json::from_value(x.clone())
                .map_err(|e| format!("per-run result: `notes`: {e}"))?,
        },
        combines: match p.get("combines") {
            None | Some(Value::Null) => Vec::new(),
            Some(x) => serde_json::from_value(x.clone())
                .map_err(|e| format!("per-run result: `combines`: {e}"))?,
        },
    };
    Ok(ParamRun {
        result,
        primary: field(p, "primary")?.as_bool().unwrap_or(false),
        truth_before: opt_f64(p, "truth_before")?,
        truth_after: opt_f64(p, "truth_after")?,
        time_to_10pct_s: opt_f64(p, "time_to_10pct_s")?,
        reconvergence_10pct_s: opt_f64(p, "reconvergence_10pct_s")?,
    })
}

fn field<'a>(v: &'a Value, k: &str) -> Result<&'a Value, String> {
    v.get(k).ok_or_else(|| format!("per-run result: missing `{k}`"))
}

fn opt_f64(v: &Value, k: &str) -> Result<Option<f64>, String> {
    match field(v, k)? {
        Value::Null => Ok(None),
        x => x.as_f64().map(Some).ok_or_else(|| format!("per-run result: `{k}` is not a number")),
    }
}

/// An optional list of numbers (`None` when absent or `null`).
fn opt_f64_list(v: &Value, k: &str) -> Result<Option<Vec<f64>>, String> {
    match v.get(k) {
        None | Some(Value::Null) => Ok(None),
        Some(x) => x
            .as_array()
            .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
            .map(Some)
            .ok_or_else(|| format!("per-run result: `{k}` is not a list of numbers")),
    }
}

fn string(v: &Value, k: &str) -> Result<String, String> {
    field(v, k)?
        .as_str()
        .map(str::to_owned)
        .ok_or_else(|| format!("per-run result: `{k}` is not a string"))
}

fn u64_of(v: &Value, k: &str) -> Result<u64, String> {
    field(v, k)?.as_u64().ok_or_else(|| format!("per-run result: `{k}` is not an integer"))
}
