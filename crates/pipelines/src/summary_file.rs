//! A replay summary read back: the identified parameters of a `summary.json` (online or a
//! batch fit), with its estimator, model, α knots and status, checked to be numbers a fit can
//! report. The exports turn it into aircraft models and the airframe flies it, so it lives
//! below both.

use aeroident_estimators::prior::ParamPrior;
use aeroident_estimators::vocabulary::Param;
use aeroident_io::parameter::ParameterResult;
use serde::Deserialize;
use std::path::Path;

/// One parameter read from a summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Identified {
    /// The parameter.
    pub param: Param,
    /// Estimate; `None` if not identified.
    pub value: Option<f64>,
    /// Standard error, if given.
    pub sigma: Option<f64>,
}

/// The identified parameters of a `replay` summary (`summary.json`, online or `oe`), with the
/// estimator and model names.
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryParameters {
    /// `estimator` of the summary.
    pub estimator: String,
    /// `model` of the summary.
    pub model: String,
    /// The parameters in summary order.
    pub parameters: Vec<Identified>,
    /// The model's α knots, rad (`alpha_knots_rad` of the summary; empty without one).
    pub alpha_knots_rad: Vec<f64>,
    /// `status` of the summary (`complete`, `converged` …; `?` when it has none).
    pub status: String,
}

/// Summary statuses of a run that finished: a real-time replay that reached the record's end
/// with every parameter identified, or a batch fit that converged.
const FINISHED: [&str; 3] = ["complete", "converged", "converged_in_cost"];

impl SummaryParameters {
    /// What a model made of this summary must be told when its run did not finish
    /// (`interrupted`, `not_converged`, `diverged`, `initialising`): the estimates are a
    /// partial result. `None` for a finished run, or a summary without a status.
    pub fn unfinished(&self) -> Option<String> {
        if FINISHED.contains(&self.status.as_str()) || self.status == "?" {
            return None;
        }
        Some(format!(
            "the summary's status is `{}`, not a finished run's ({}): its estimates are where the run stopped, not an identified model",
            self.status,
            FINISHED.join(", ")
        ))
    }
}

/// A `summary.json` as the exports read it back: its parameters as the result type the
/// replay wrote ([`ParameterResult`]) and the run's estimator, model, status and α knots (`?`
/// and empty where a summary leaves them out or gives `null`). Every other key is passed over.
#[derive(Debug, Deserialize)]
struct SummaryFile {
    estimator: Option<String>,
    model: Option<String>,
    status: Option<String>,
    alpha_knots_rad: Option<Vec<f64>>,
    parameters: Vec<ParameterResult>,
}

/// Reads `parameters[].{name, estimate, std_error}` (plus `estimator`, `model`, `status`,
/// `alpha_knots_rad`) of a summary, deserialised as the replay's result types.
///
/// # Errors
/// The file cannot be read or is not a summary (serde's message with the line and column: no
/// `parameters` array, a value of the wrong type), names a parameter outside the vocabulary or
/// twice, or has an absurd estimate (beyond ±1e4) or a negative σ; each naming the file and
/// parameter.
pub fn read_summary(path: &Path) -> crate::error::Result<SummaryParameters> {
    let file = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| crate::err!("{file}: {e}"))?;
    let doc: SummaryFile = serde_json::from_str(&text)
        .map_err(|e| crate::err!("{file}: not a replay summary.json: {e}"))?;
    let mut parameters: Vec<Identified> = Vec::with_capacity(doc.parameters.len());
    for (i, p) in doc.parameters.iter().enumerate() {
        let name = p.name.as_str();
        let param = Param::from_name(name).ok_or_else(|| {
            crate::err!(
                "{file}: parameter `{name}` is not of the vocabulary (<coefficient>_<term>)"
            )
        })?;
        let (value, sigma) = (p.estimate, p.std_error);
        check_identified(name, value, sigma).map_err(|why| crate::err!("{file}: {why}"))?;
        if let Some(first) = parameters.iter().position(|q| q.param == param) {
            // Two values of one derivative: JSBSim would sum both, a linearisation take one.
            return Err(crate::err!(
                "{file}: parameter `{name}` is listed twice (parameters[{first}] and [{i}]): a model has each derivative once"
            ));
        }
        parameters.push(Identified { param, value, sigma });
    }
    let text_of = |v: Option<String>| v.unwrap_or_else(|| "?".to_string());
    Ok(SummaryParameters {
        estimator: text_of(doc.estimator),
        model: text_of(doc.model),
        parameters,
        alpha_knots_rad: doc.alpha_knots_rad.unwrap_or_default(),
        status: text_of(doc.status),
    })
}

/// Checks an estimate and its σ are numbers a fit can report: `|estimate|` at most
/// [`ParamPrior::MAX_ABS_VALUE`] (ten times the largest plausible coefficient) and σ ≥ 0. A
/// hand-edited or corrupted summary would otherwise become an aircraft model JSBSim flies.
fn check_identified(name: &str, value: Option<f64>, sigma: Option<f64>) -> Result<(), String> {
    let max = ParamPrior::MAX_ABS_VALUE;
    if let Some(v) = value.filter(|v| v.abs() > max) {
        return Err(format!(
            "parameter `{name}`: estimate {v:e} is beyond ±{max:e}, no identified coefficient (is the summary edited or corrupted?)"
        ));
    }
    if let Some(s) = sigma.filter(|s| *s < 0.0) {
        return Err(format!("parameter `{name}`: std_error {s} is negative"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A summary with `CL_alpha` = `estimate`, σ `std_error`, read back from a file.
    fn read_one(estimate: f64, std_error: f64) -> crate::error::Result<SummaryParameters> {
        let json = serde_json::json!({"estimator": "oe", "model": "m", "parameters": [
            {"name": "CL_alpha", "estimate": estimate, "std_error": std_error}]});
        read_doc(&format!("s{:x}", estimate.to_bits() ^ std_error.to_bits()), &json)
    }

    #[test]
    fn absurd_estimates_and_negative_sigmas_are_refused_naming_the_parameter() {
        assert_eq!(read_one(4.4, 0.1).unwrap().parameters[0].value, Some(4.4));
        let e = read_one(1e308, 0.1).unwrap_err().to_string();
        assert!(e.contains("`CL_alpha`") && e.contains("1e308") && e.contains(".json"), "{e}");
        let e = read_one(4.4, -0.1).unwrap_err().to_string();
        assert!(e.contains("`CL_alpha`") && e.contains("negative"), "{e}");
    }

    /// The summary `doc`, written to a file named by `tag` and read back.
    fn read_doc(tag: &str, doc: &serde_json::Value) -> crate::error::Result<SummaryParameters> {
        let dir =
            std::env::temp_dir().join(format!("aeroident-summary-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{tag}.json"));
        std::fs::write(&path, doc.to_string()).unwrap();
        let read = read_summary(&path);
        std::fs::remove_file(&path).unwrap();
        read
    }

    /// A summary read back with the result types: a value of the wrong type or a missing
    /// `parameters` is refused naming the file, what was expected and where.
    #[test]
    fn errors_a_summary_not_of_the_result_types_is_refused_naming_where() {
        let doc = serde_json::json!({"parameters": [{"name": "CL_alpha", "estimate": "x"}]});
        let e = read_doc("wrong-type", &doc).unwrap_err().to_string();
        assert!(e.contains(".json") && e.contains("expected f64") && e.contains("line 1"), "{e}");
        let e = read_doc("no-params", &serde_json::json!({"status": "converged"}));
        let e = e.unwrap_err().to_string();
        assert!(e.contains("missing field `parameters`"), "{e}");
    }

    #[test]
    fn a_parameter_listed_twice_is_refused_naming_both_places() {
        let doc = serde_json::json!({"status": "converged", "parameters": [
            {"name": "Cm_q", "estimate": -12.76}, {"name": "Cm_alpha", "estimate": -0.5},
            {"name": "Cm_q", "estimate": 99.0}]});
        let e = read_doc("twice", &doc).unwrap_err().to_string();
        assert!(e.contains("`Cm_q` is listed twice (parameters[0] and [2])"), "{e}");
        let doc = serde_json::json!({"parameters": [
            {"name": "Cm_q", "estimate": -12.76}, {"name": "Cm_alpha", "estimate": -0.5}]});
        assert_eq!(read_doc("once", &doc).unwrap().parameters.len(), 2);
    }

    #[test]
    fn an_unfinished_run_is_named_and_a_finished_one_is_not() {
        let of = |status: &str| {
            let doc = serde_json::json!({"status": status, "parameters": [
                {"name": "Cm_q", "estimate": -12.76}]});
            read_doc(&format!("st-{status}"), &doc).unwrap().unfinished()
        };
        for finished in ["complete", "converged", "converged_in_cost"] {
            assert_eq!(of(finished), None, "{finished}");
        }
        for partial in ["interrupted", "not_converged", "diverged", "initialising"] {
            let note = of(partial).unwrap_or_else(|| panic!("{partial} not named"));
            assert!(note.contains(&format!("`{partial}`")), "{note}");
        }
        let doc = serde_json::json!({"parameters": [{"name": "Cm_q", "estimate": -12.76}]});
        assert_eq!(read_doc("st-none", &doc).unwrap().unfinished(), None);
    }

    #[test]
    fn estimates_up_to_the_limit_and_a_zero_sigma_are_accepted() {
        assert_eq!(check_identified("CL_0", Some(1e4), Some(0.0)), Ok(()));
        assert_eq!(check_identified("CL_0", Some(-1e4), None), Ok(()));
        assert!(
            check_identified("CL_0", Some(10_000.001), None).unwrap_err().contains("beyond ±1e4")
        );
        assert!(check_identified("CL_0", None, Some(-1e-300)).unwrap_err().contains("negative"));
        assert_eq!(check_identified("CL_0", None, None), Ok(()));
    }
}
