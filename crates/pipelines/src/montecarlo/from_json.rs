//! [`run_result_from_json`]: a [`RunResult`] back from its JSON form (the per-run results a
//! distributed campaign sends between processes, the Python bindings' `montecarlo_reduce`).

use serde_json::Value;

use super::{ParamRun, RunResult};
use aeroident_io::ParameterResult;

/// The inverse of `serde_json::to_value(&RunResult)`, by the same types' `Deserialize`: floats
/// are carried exactly; `restarts`, `sigma_candidates`, `bootstrap_failed`, `bootstrap_bias`
/// and a parameter's `timing_std_error`, `unmodelled_std_error`, `reference_check`, `notes`
/// and `combines` may be absent (results of older versions). Every other key must be there,
/// `null` or not (`REQUIRED_RUN_KEYS`, `REQUIRED_PARAM_KEYS`): serde would read a missing
/// nullable key as `null`, and a result of another schema (`final`, `sigma`) as a run with
/// nothing identified.
///
/// # Errors
/// A message `per-run result: `PATH`: …` naming the key by its path and serde's reason (the
/// key missing, or the value of the wrong type and what was expected).
pub fn run_result_from_json(v: &Value) -> Result<RunResult, String> {
    if let Some(runs) = v.pointer("/outcome/Ok").and_then(Value::as_array) {
        for (i, run) in runs.iter().enumerate() {
            require(run, &REQUIRED_RUN_KEYS, &format!("outcome.Ok[{i}]"))?;
            let params = run.get("params").and_then(Value::as_array).map_or(&[][..], Vec::as_slice);
            for (j, p) in params.iter().enumerate() {
                require(p, &REQUIRED_PARAM_KEYS, &format!("outcome.Ok[{i}].params[{j}]"))?;
            }
        }
    }
    serde_path_to_error::deserialize(v)
        .map_err(|e| format!("per-run result: `{}`: {}", e.path(), e.inner()))
}

/// The keys of an estimator's run that every version of this schema writes.
const REQUIRED_RUN_KEYS: [&str; 6] =
    ["name", "failure", "nis", "iterations", "fit_wall_s", "params"];

/// The keys of a parameter's run that every version of this schema writes.
const REQUIRED_PARAM_KEYS: [&str; 13] = [
    "name",
    "estimate",
    "std_error",
    "std_error_source",
    "crb_std_error",
    "reference",
    "status",
    "flags",
    "primary",
    "truth_before",
    "truth_after",
    "time_to_10pct_s",
    "reconvergence_10pct_s",
];

/// The first of `keys` object `v` (at `path`) lacks, as the error.
fn require(v: &Value, keys: &[&str], path: &str) -> Result<(), String> {
    match keys.iter().find(|k| v.get(**k).is_none()) {
        Some(k) => Err(format!("per-run result: `{path}`: missing field `{k}`")),
        None => Ok(()),
    }
}

/// A parameter's run read back: its result ([`ParameterResult`], flattened into the same
/// object) and the campaign's keys beside it. By hand only in reading the result first, so
/// that an error names its key (`estimate`), which serde's flattening would not.
impl<'de> serde::Deserialize<'de> for ParamRun {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        /// The keys of a [`ParamRun`] beside its result.
        #[derive(serde::Deserialize)]
        struct Beside {
            primary: bool,
            truth_before: Option<f64>,
            truth_after: Option<f64>,
            time_to_10pct_s: Option<f64>,
            reconvergence_10pct_s: Option<f64>,
        }
        use serde::de::Error as _;
        let v = <Value as serde::Deserialize>::deserialize(d)?;
        let named = |e: serde_path_to_error::Error<serde_json::Error>| {
            D::Error::custom(format!("`{}`: {}", e.path(), e.inner()))
        };
        let result: ParameterResult = serde_path_to_error::deserialize(&v).map_err(named)?;
        let b: Beside = serde_path_to_error::deserialize(&v).map_err(named)?;
        Ok(ParamRun {
            result,
            primary: b.primary,
            truth_before: b.truth_before,
            truth_after: b.truth_after,
            time_to_10pct_s: b.time_to_10pct_s,
            reconvergence_10pct_s: b.reconvergence_10pct_s,
        })
    }
}
