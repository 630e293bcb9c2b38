//! The verdict on each parameter of a finished replay, in its `summary.json` entry: a status
//! and the flags that explain it, judged once here for every face (the console table,
//! `report.html`, Python).
//!
//! The flags: every warning of the run about the parameter (sign checks, cross-check
//! disagreements), an imprecise estimate ([`super::precision`]), a value a conventional
//! aircraft cannot have ([`crate::plausibility`]), a reference outside ±2σ. The status:
//! `diverged` when the estimator diverged; `not identified` without an estimate (a drag term
//! of a record without thrust is withdrawn, with the reason); else `flagged` with any flag and
//! `identified` without one (docs/output-schema.md).

use super::{ReplayOutcome, precision};
use aeroident_io::parameter::STATUS_DIVERGED;

/// Sets the status and flags of every parameter of `outcome` (module doc), the drag terms
/// withdrawn unless `thrust_mapped`; judging again after a later stage (the cross-check)
/// replaces the earlier verdict.
pub fn judge(outcome: &mut ReplayOutcome, thrust_mapped: bool) {
    let diverged = outcome.diverged();
    let model = &outcome.model;
    let summary = &mut outcome.summary;
    for p in &mut summary.parameters {
        let r = &mut p.result;
        r.flags = summary.warnings.about(&r.name);
        if diverged {
            r.judge(Some(STATUS_DIVERGED));
            continue;
        }
        // A withdrawn drag term is judged by its reason alone.
        crate::plausibility::check(model, thrust_mapped, std::iter::once(&mut *r));
        if let Some(relative) = precision::imprecise(&r.name, r.estimate, r.std_error) {
            r.flag(precision::flag(relative));
        }
        r.judge(None);
    }
}
