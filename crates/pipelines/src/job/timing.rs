//! The timing refits of both jobs. When the record's timing test named a surface leading its
//! response, the record is fitted again by the run's own estimator, model and options with
//! the lead undone, and each estimate that moves beyond its ±2σ is flagged with both values
//! ([`crate::replay::sign_tests::refit`]). Always, the record is fitted twice more with the
//! gyros half a sample late and early, and each estimate such a skew moves by more than 10 %
//! is flagged ([`crate::replay::sample_timing`]). Not for a live feed (it cannot be read twice).

use super::{Guard, JobLog, Records, Step};
use crate::record::Corrections;
use crate::replay::ReplayError;
use crate::replay::cross_check::MethodEstimates;
use crate::replay::sample_timing;
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

/// The sample-timing test of a run whose own estimates are `own` and corrections `compat`:
/// `fit` runs the own estimator on the records with the corrections it is given, once with the
/// gyros half a sample late and once early; each estimate the skew moves by more than 10 % is
/// flagged in `warnings` ([`sample_timing::moved`]). Returns each estimate's sample-timing σ
/// ([`sample_timing::spreads`]), for the caller to add to its σ; empty on a live feed, a run
/// without estimates, a record whose sample interval cannot be read, or a refit that failed or
/// was stopped (each but the first two with a warning that the test was not done).
///
/// # Errors
/// The face could not run the step.
pub fn skew_step(
    records: &Records,
    own: &MethodEstimates,
    compat: Option<&Corrections>,
    fit: impl Fn(Corrections) -> MethodEstimates + Clone + Send + 'static,
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
    warnings: &mut Warnings,
) -> Result<Vec<(String, f64)>, ReplayError> {
    if records.live || own.estimates.is_empty() {
        return Ok(Vec::new());
    }
    let Some(skew) = records.sample_interval_s().and_then(sample_timing::skew_s) else {
        return Ok(skew_note(
            log,
            warnings,
            "not done: the record's sample interval could not be read",
        ));
    };
    let skewed = |by: f64| compat.cloned().unwrap_or_default().with_rate_skew(by);
    let (late, early) = match (skewed(skew), skewed(-skew)) {
        (Ok(l), Ok(e)) => (l, e),
        (Err(why), _) | (_, Err(why)) => {
            return Ok(skew_note(log, warnings, &format!("not done: {why}")));
        }
    };
    log.note("sample timing: fitting the record again with the gyros half a sample late and early");
    let again = fit.clone();
    // The two refits are independent: on two cores they cost one.
    let both = move || rayon::join(move || fit(late), move || again(early));
    let Some((late, early)) = guard.run(Step::SampleTiming, both)? else {
        super::cross_check::abandoned("the sample-timing test", log, warnings);
        return Ok(Vec::new());
    };
    if let Some(failed) = [&late, &early].into_iter().find(|m| m.estimates.is_empty()) {
        let why = format!("not done: {} {}", failed.method, failed.status);
        return Ok(skew_note(log, warnings, &why));
    }
    warnings.extend(sample_timing::moved(own, &late, &early, skew));
    Ok(sample_timing::spreads(own, &late, &early))
}

/// A warning that the sample-timing test was not done (`why`), to `log` and `warnings`; no
/// spreads.
fn skew_note(log: &mut dyn JobLog, warnings: &mut Warnings, why: &str) -> Vec<(String, f64)> {
    let w = format!("sample timing: the refits with the gyros skewed by half a sample were {why}");
    log.warning(&w);
    warnings.push(w);
    Vec::new()
}

/// A warning that the refit was not done (the timing test's warnings stand), to `log` and
/// `warnings`; `false` (nothing to judge again).
fn note(log: &mut dyn JobLog, warnings: &mut Warnings, why: &str) -> bool {
    let w = format!("input timing: the refit with the measured lead undone was {why}");
    log.warning(&w);
    warnings.push(w);
    false
}

/// The σ of a record's fit beyond its noise, added to every result of `results`: each
/// estimate's sample-timing σ of `spreads` ([`sample_timing::widen`]), then the unmodelled σ
/// ([`crate::replay::unmodelled`]). Both jobs call it before their last judgement.
pub fn widen_sigma<'a>(
    results: impl IntoIterator<Item = &'a mut aeroident_io::ParameterResult>,
    spreads: &[(String, f64)],
) {
    for r in results {
        sample_timing::widen([&mut *r], spreads);
        r.add_unmodelled_std_error(crate::replay::unmodelled::UNMODELLED_FRACTION);
    }
}
