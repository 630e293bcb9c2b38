//! Whether a real-time estimate can be trusted: the online (equation-error or EKF) estimates of
//! a record set beside the batch output-error fit of the same record and model (`replay
//! --cross-check`).
//!
//! Output error is the reference a flight-test engineer compares to (Jategaonkar 2015 ch. 4;
//! Klein & Morelli 2006 ch. 6): it simulates the outputs from the inputs, so noise on the
//! measured states does not enter its regressors. A parameter whose online estimate is more
//! than [`FLAG_SIGMAS`] combined σ from the batch one is flagged with the likely cause:
//! - **equation error** (`rls`, `ftr`) with the estimate nearer zero than the batch one:
//!   regressor noise, the errors-in-variables bias of least squares towards zero (Klein &
//!   Morelli 2006 ch. 5 on equation error with noisy regressors);
//! - **equation error** otherwise: a time skew or bias between channels (the regressors and the
//!   measured coefficient are not of one instant), which `aeroident compat` measures;
//! - **instrumental variables** (`rls-iv`), which removes the regressor-noise bias: a time skew
//!   or bias as above, or, nearer zero, noise correlated over more than the instrument delay;
//! - **EKF**: its process- and measurement-noise model (unmodelled process noise moves both its
//!   estimates and its σ; the batch fit's do not depend on them);
//! - other estimators: their own bias (docs/smpe-corrected.md, docs/model-reference.md);
//! - a constant term (`Cm_0` …), whatever the estimator: it takes up the others' differences.
//!
//! The combined σ is `√(σ_online² + σ_batch²)`, each estimator's reported σ (the batch one the
//! coloured-residual σ): the two estimates come from the same record, so their errors are
//! correlated and the test is conservative.

use super::batch::BatchSummary;
use crate::estimators::EstimatorKind;
use aeroident_io::replay_output::ReplaySummary;
use aeroident_io::warning::{Warning, WarningKind};
use serde::Serialize;

/// A parameter is flagged when the two estimates differ by more than this many combined σ.
pub const FLAG_SIGMAS: f64 = 2.0;

/// The comparison (`summary.json` `cross_check`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CrossCheck {
    /// The batch fit compared with (`oe`).
    pub batch_estimator: String,
    /// How the batch fit ended (`converged`, `converged_in_cost`, `not_converged`).
    pub batch_status: String,
    /// Parameters with an estimate and a σ from both.
    pub compared: usize,
    /// Those further apart than [`FLAG_SIGMAS`] combined σ.
    pub flagged: Vec<Disagreement>,
}

/// One flagged parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Disagreement {
    /// Parameter name (`Cm_alpha` …).
    pub parameter: String,
    /// The online estimate and its σ.
    pub estimate: f64,
    /// Its reported σ.
    pub std_error: f64,
    /// The batch estimate.
    pub batch_estimate: f64,
    /// The batch fit's reported σ.
    pub batch_std_error: f64,
    /// `|estimate − batch_estimate| / √(std_error² + batch_std_error²)`.
    pub combined_sigmas: f64,
    /// The likely cause (module doc).
    pub likely_cause: String,
}

/// Compares `online` (estimator `kind`; `compat_applied` when compatibility corrections were
/// applied) with `batch`, parameter by parameter, by name.
pub fn cross_check(
    kind: EstimatorKind,
    online: &ReplaySummary,
    batch: &BatchSummary,
    compat_applied: bool,
) -> CrossCheck {
    let rows: Vec<(&str, Option<f64>, Option<f64>)> =
        online.parameters.iter().map(|p| (p.name.as_str(), p.estimate, p.std_error)).collect();
    let reference: Vec<(&str, f64, f64)> = batch
        .parameters
        .iter()
        .filter_map(|p| Some((p.name.as_str(), p.estimate?, p.std_error?)))
        .collect();
    let mut check = compare(kind, &rows, &reference, compat_applied);
    check.batch_estimator.clone_from(&batch.estimator);
    check.batch_status.clone_from(&batch.status);
    check
}

/// [`cross_check`] on `(name, estimate, σ)` rows (the batch's names and status left empty).
fn compare(
    kind: EstimatorKind,
    online: &[(&str, Option<f64>, Option<f64>)],
    batch: &[(&str, f64, f64)],
    compat_applied: bool,
) -> CrossCheck {
    let mut compared = 0;
    let mut flagged = Vec::new();
    for &(name, est, sigma) in online {
        let (Some(est), Some(sigma)) = (est, sigma) else { continue };
        let Some(&(_, b, b_sigma)) = batch.iter().find(|b| b.0 == name) else { continue };
        compared += 1;
        let z = (est - b).abs() / sigma.hypot(b_sigma);
        if z > FLAG_SIGMAS {
            flagged.push(Disagreement {
                parameter: name.to_string(),
                estimate: est,
                std_error: sigma,
                batch_estimate: b,
                batch_std_error: b_sigma,
                combined_sigmas: z,
                likely_cause: likely_cause(kind, name, est, b, compat_applied).into(),
            });
        }
    }
    CrossCheck { batch_estimator: String::new(), batch_status: String::new(), compared, flagged }
}

fn likely_cause(
    kind: EstimatorKind,
    name: &str,
    online: f64,
    batch: f64,
    compat_applied: bool,
) -> &'static str {
    if name.ends_with("_0") {
        return "a constant term: it takes up the other parameters' differences";
    }
    match kind {
        EstimatorKind::Rls | EstimatorKind::Ftr | EstimatorKind::RlsIv => {
            let shrunk = online.signum() == batch.signum() && online.abs() < batch.abs();
            match (shrunk, compat_applied) {
                (true, _) if kind == EstimatorKind::RlsIv => {
                    "regressor noise correlated over more than the instrument delay (raise `instrument_delay`), or a time skew between channels"
                }
                (true, _) => {
                    "regressor noise: least squares on noisy measured states is biased towards zero (errors in variables)"
                }
                (false, false) => {
                    "a time skew or bias between channels: run `aeroident compat` (or `--compat auto`) to measure them"
                }
                (false, true) => {
                    "model structure, or a channel error the compatibility check does not correct"
                }
            }
        }
        EstimatorKind::Ekf => {
            "the EKF's noise model: unmodelled process noise moves its estimates and its σ, the batch fit's do not depend on it"
        }
        _ => "the estimator's own bias (see its documentation)",
    }
}

/// The summary warnings of `check` ([`WarningKind::CrossCheck`]): one per flagged parameter
/// (about it), and one when nothing could be compared.
pub fn warnings(check: &CrossCheck) -> Vec<Warning> {
    if check.compared == 0 {
        let text = format!(
            "cross-check: no parameter has an estimate and a σ from both this estimator and {}",
            check.batch_estimator
        );
        return vec![Warning::new(WarningKind::CrossCheck, text)];
    }
    check
        .flagged
        .iter()
        .map(|d| {
            let text = format!(
                "cross-check: {} = {:.4} ± {:.2e} differs from {} {:.4} ± {:.2e} by {:.1} combined σ; likely cause: {}",
                d.parameter,
                d.estimate,
                d.std_error,
                check.batch_estimator,
                d.batch_estimate,
                d.batch_std_error,
                d.combined_sigmas,
                d.likely_cause
            );
            Warning::new(WarningKind::CrossCheck, text).about(&d.parameter)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3 × 0.05 vs 2.5 ± 0.1 is 4.47 combined σ: flagged, nearer zero, so regressor noise for
    /// least squares; 1.0 ± 0.1 vs 1.2 ± 0.1 (1.41 σ) is not; a parameter without σ or absent
    /// from the batch fit is not compared.
    #[test]
    fn differences_beyond_two_combined_sigma_are_flagged_with_a_cause() {
        let online = [
            ("Cm_q", Some(-2.0), Some(0.05)),
            ("Cm_alpha", Some(1.0), Some(0.1)),
            ("Cm_de", Some(1.0), None),
            ("Cm_0", Some(0.0), Some(0.1)),
        ];
        let batch = [("Cm_q", -2.5, 0.1), ("Cm_alpha", 1.2, 0.1), ("Cm_de", 3.0, 0.1)];
        let c = compare(EstimatorKind::Rls, &online, &batch, false);
        assert_eq!(c.compared, 2);
        assert_eq!(c.flagged.len(), 1);
        let d = &c.flagged[0];
        assert_eq!(d.parameter, "Cm_q");
        assert!((d.combined_sigmas - 0.5 / 0.05f64.hypot(0.1)).abs() < 1e-12);
        assert!(d.likely_cause.starts_with("regressor noise"));
        let away = compare(EstimatorKind::Ftr, &[("Cm_q", Some(-3.0), Some(0.05))], &batch, false);
        assert!(away.flagged[0].likely_cause.contains("aeroident compat"));
        let iv = compare(EstimatorKind::RlsIv, &online[..1], &batch, false);
        assert!(iv.flagged[0].likely_cause.contains("instrument delay"));
        let ekf = compare(EstimatorKind::Ekf, &[("Cm_q", Some(-3.0), Some(0.05))], &batch, true);
        assert!(ekf.flagged[0].likely_cause.starts_with("the EKF's noise model"));
        let bias = [("Cm_0", Some(1.0), Some(0.05))];
        let bias = compare(EstimatorKind::Rls, &bias, &[("Cm_0", 0.0, 0.1)], false);
        assert!(bias.flagged[0].likely_cause.starts_with("a constant term"));
        c.flagged.iter().for_each(|d| assert!(d.combined_sigmas > FLAG_SIGMAS));
    }
}
