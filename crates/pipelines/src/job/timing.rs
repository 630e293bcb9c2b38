//! The timing refit of both jobs: when the record's timing test named a surface leading its
//! response, the record is fitted again by the run's own estimator, model and options with
//! the lead undone, and each estimate that moves beyond its ±2σ is flagged with both values
//! ([`crate::replay::sign_tests::refit`]). Not for a live feed (it cannot be read twice).

use super::{Guard, JobLog, Records, Step};
use crate::record::Corrections;
use crate::replay::ReplayError;
use crate::replay::cross_check::MethodEstimates;
use crate::replay::sign_tests::refit;
use aeroident_io::replay_output::SignTest;
use aeroident_io::warning::Warnings;

/// The refit of a run whose own estimates are `own`, sign tests `tests`, corrections `compat`
/// and summary warnings `warnings` (the refit's flags added, [`refit::moved`]); `fit` runs the own
/// estimator on the records with the corrections it is given. Nothing without a warned lead
/// or on a live feed; a refit that fails or a stop leaves the timing warnings as they were,
/// with a warning that says so. Returns whether the warnings changed (the verdicts are then to
/// be judged again).
///
/// # Errors
/// The face could not run the step.
#[allow(clippy::too_many_arguments)]
pub fn refit_step(
    records: &Records,
    own: &MethodEstimates,
    tests: &[SignTest],
    compat: Option<&Corrections>,
    fit: impl FnOnce(Corrections) -> MethodEstimates + Send + 'static,
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
    warnings: &mut Warnings,
) -> Result<bool, ReplayError> {
    let leads = refit::warned_leads(tests, warnings);
    if leads.is_empty() || records.live {
        return Ok(false);
    }
    let undone = match refit::undone(compat, &leads) {
        Ok(c) => c,
        Err(why) => return Ok(note(log, warnings, &format!("not done: {why}"))),
    };
    log.note("input timing: fitting the record again with the measured lead undone");
    let Some(again) = guard.run(Step::TimingRefit, move || fit(undone))? else {
        super::cross_check::abandoned("the timing refit", log, warnings);
        return Ok(false);
    };
    if again.estimates.is_empty() {
        return Ok(note(log, warnings, &format!("not done: {} {}", again.method, again.status)));
    }
    warnings.extend(refit::moved(own, &again, &leads));
    Ok(true)
}

/// A warning that the refit was not done (the timing test's warnings stand), to `log` and
/// `warnings`; `false` (nothing to judge again).
fn note(log: &mut dyn JobLog, warnings: &mut Warnings, why: &str) -> bool {
    let w = format!("input timing: the refit with the measured lead undone was {why}");
    log.warning(&w);
    warnings.push(w);
    false
}
