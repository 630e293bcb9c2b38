//! The verdict on each parameter of a finished replay, in its `summary.json` entry: a status
//! and the flags that explain it, judged once here for every face (the console table,
//! `report.html`, Python).
//!
//! The status, first rule that applies:
//! 1. `diverged`: the estimator diverged (no estimate is a result);
//! 2. `differs from oe by 3.1σ`: `--cross-check` flagged the estimate ([`super::cross_check`]);
//! 3. `outside ±2σ`: the model file's reference lies further than 2σ from the estimate;
//! 4. `σ 32 % of |estimate|`: the record does not determine it ([`super::precision`]);
//! 5. `not identified` without an estimate, else `ok`.
//!
//! The flags are the texts of every warning of the run about the parameter (sign checks,
//! cross-check disagreements).

use super::{ReplayOutcome, precision};

/// Sets the status and flags of every parameter of `outcome` (module doc); judging again after
/// a later stage (the cross-check) replaces the earlier verdict.
pub fn judge(outcome: &mut ReplayOutcome) {
    let diverged = outcome.diverged();
    let flagged: Vec<(String, String)> = match &outcome.cross_check {
        Some(c) => c
            .flagged
            .iter()
            .map(|d| {
                let status =
                    format!("differs from {} by {:.1}σ", c.batch_estimator, d.combined_sigmas);
                (d.parameter.clone(), status)
            })
            .collect(),
        None => Vec::new(),
    };
    let summary = &mut outcome.summary;
    for p in &mut summary.parameters {
        let r = &mut p.result;
        let failure = if diverged {
            Some("diverged".to_string())
        } else if let Some((_, s)) = flagged.iter().find(|(n, _)| *n == r.name) {
            Some(s.clone())
        } else {
            let relative = precision::imprecise(&r.name, r.estimate, r.std_error);
            relative.filter(|_| !r.outside_2sigma()).map(precision::status)
        };
        r.judge(failure.as_deref());
        r.flags = summary.warnings.about(&r.name);
    }
}
