//! The one judge of every estimate: the status and the flags that explain it, the same for
//! every command (`replay` online and batch, `fit`, `run`, `montecarlo`, the live page,
//! Python and the C ABI's final report all read the verdicts judged here).
//!
//! A flag is a doubt the run found about the value: a warning about the parameter or its
//! coefficient (sign checks, input timing, the cross-check's tested disagreements, the thrust
//! test), an estimator that ended before every parameter was identified, a value a
//! conventional aircraft cannot have ([`crate::plausibility`]), a degenerate filter, no σ at
//! all, an estimate whose ±2σ spans zero ([`precision::insignificant`]). Any flag
//! makes the status `flagged`; without one it is `identified`. A note is no doubt (a σ between
//! 10 % and half of the estimate says imprecise, not wrong, [`crate::precision`]; a value
//! that does not repeat across manoeuvres, its σ scaled to their spread,
//! `aeroident_pipelines::replay::repeatability`; a value the record fixes only in combination with
//! another, [`combination_notes`]) and never blocks `identified`. A reference (a simulation's truth, a model file's published value) is
//! never read here: it is set beside the verdict in `reference_check`
//! ([`aeroident_io::ParameterResult::check_reference`]).
//!
//! The statuses (docs/output-schema.md): `diverged` when the estimator diverged; `not
//! converged` for a batch fit still moving by more than σ at its iteration limit; `not
//! identified` without an estimate (a withdrawn drag term, a term a batch method cannot see,
//! a failed fit), each with its reason; else `flagged` or `identified`.

use crate::precision;
use aeroident_estimators::Status;
use aeroident_io::ModelSpec;
use aeroident_io::ParameterResult;
use aeroident_io::replay_output::Correlation;

/// What a verdict weighs beside the parameter's own numbers.
#[derive(Debug, Default)]
pub struct Evidence<'a> {
    /// The doubts about the parameter, in words (the warnings about it or its coefficient; an
    /// estimator failure); each becomes a flag.
    pub doubts: Vec<String>,
    /// The model whose plausible ranges apply, and whether thrust is mapped (the drag terms are
    /// withdrawn without it); `None`: the plausibility check is not made.
    pub plausibility: Option<(&'a ModelSpec, bool)>,
    /// A doubt about every estimate of the run that has one (a degenerate filter, an estimator
    /// that has not converged), without touching a parameter without an estimate.
    pub estimate_doubts: Vec<String>,
    /// A status that replaces the verdict (`diverged`, `not converged`).
    pub failure: Option<&'a str>,
    /// What is worth knowing and no doubt about the value (a value that does not repeat
    /// across manoeuvres, its σ scaled to their spread); each becomes a note.
    pub notes: Vec<String>,
}

/// Judges `r` on `evidence` (module doc): its flags are those `r` holds (a held or withdrawn
/// parameter's reason) and the evidence's doubts; its notes are recomputed; a second call on
/// new evidence replaces the first's notes, and the caller resets the flags it replaces.
pub fn judge(r: &mut ParameterResult, evidence: &Evidence) {
    for d in &evidence.doubts {
        r.flag(d.clone());
    }
    r.notes.clear();
    if let Some(f) = evidence.failure {
        r.judge(Some(f));
        return;
    }
    if r.estimate.is_some() {
        evidence.estimate_doubts.iter().for_each(|d| r.flag(d.clone()));
    }
    if let Some((model, thrust_mapped)) = evidence.plausibility {
        crate::plausibility::check(model, thrust_mapped, std::iter::once(&mut *r));
    }
    evidence.notes.iter().for_each(|n| r.note(n.clone()));
    if let Some(ratio) = precision::insignificant(&r.name, r.estimate, r.std_error) {
        r.flag(precision::insignificant_flag(ratio));
    } else if let Some(relative) = precision::imprecise(&r.name, r.estimate, r.std_error) {
        r.note(precision::flag(relative));
    }
    r.judge(None);
}

/// The verdict on one current estimate of a recursive estimator fed by a caller the library
/// does not read the record for (the C ABI): `estimate` and `std_error` as the estimator
/// gives them (`None` while not identified), `status` its state ([`Status::name`]). The
/// evidence is what those numbers carry: the unmodelled σ added
/// ([`crate::unmodelled`]), the estimator's state ([`unconverged`]; `diverged`
/// replaces the verdict), the plausibility check for `model` (drag terms withdrawn unless
/// `thrust_mapped`) and the precision test. The record-level tests of a replay (sign tests,
/// sample timing, the cross-check) need the record and are not made.
pub fn judge_estimate(
    name: &str,
    estimate: Option<f64>,
    std_error: Option<f64>,
    status: &str,
    model: &ModelSpec,
    thrust_mapped: bool,
) -> ParameterResult {
    let mut r = ParameterResult::new(name, estimate, std_error, None, None);
    r.add_unmodelled_std_error(crate::unmodelled::UNMODELLED_FRACTION);
    let diverged = status == Status::Diverged.name();
    let evidence = Evidence {
        doubts: Vec::new(),
        plausibility: Some((model, thrust_mapped)),
        estimate_doubts: unconverged(status).into_iter().collect(),
        failure: diverged.then_some(aeroident_io::parameter::STATUS_DIVERGED),
        notes: Vec::new(),
    };
    judge(&mut r, &evidence);
    r
}

/// The notes on parameter `name` from the run's strongly correlated pairs (`correlations`,
/// |ρ| > 0.9): one per partner, saying that the record fixes a combination of the two rather
/// than each (Cm_q and Cm_α̇ in a short period; a constant and a speed term over a narrow
/// speed range). A note, not a doubt: each value may be right, and its σ already carries the
/// spread along the combination the record leaves free.
pub fn combination_notes(name: &str, correlations: &[Correlation]) -> Vec<String> {
    combinations(name, correlations)
        .iter()
        .map(|c| {
            format!(
                "combines with {} (ρ = {:+.2}): the record fixes a combination of the two, not each; excite them apart to separate them",
                c.with, c.rho
            )
        })
        .collect()
}

/// The partners of parameter `name` among the run's strongly correlated pairs
/// (`correlations`, |ρ| > 0.9), each with ρ: the `combines` field of its result, the pairs
/// [`combination_notes`] puts in words.
pub fn combinations(
    name: &str,
    correlations: &[Correlation],
) -> Vec<aeroident_io::parameter::Combination> {
    correlations
        .iter()
        .filter_map(|c| {
            let other = if c.a == name {
                &c.b
            } else if c.b == name {
                &c.a
            } else {
                return None;
            };
            Some(aeroident_io::parameter::Combination { with: other.clone(), rho: c.rho })
        })
        .collect()
}

/// The doubt on every estimate of a recursive estimator that ended in `status` before every
/// parameter was identified (`initialising`): its covariance has not yet shrunk from its
/// priors for some parameter, and the others' σ is read off a filter that has not settled.
/// `None` for a running or diverged estimator (a divergence is its own status).
pub fn unconverged(status: &str) -> Option<String> {
    (status == Status::Initialising.name()).then(|| {
        "the estimator ended `initialising`: not every parameter left its prior, so no estimate of the run is settled".to_string()
    })
}

#[cfg(test)]
mod tests;
