//! Variants of thesis cases that decide the illegible λ of tables 4.7/4.8 and show the effect
//! of the lost η (`aeroident run --all`'s `report.md`, section Evidence): a base scenario with
//! one setting of one true increment changed, flown with the published estimators only.

use rayon::prelude::*;

use super::scenario::EstimatorSpec;
use super::summary::{Summary, summarize};
use super::{ExperimentError, Scenario, run};
use crate::metrics::MetricsError;

/// One variant: a base scenario with one setting of one increment changed.
#[derive(Debug, Clone)]
pub struct Variant {
    /// The base scenario (its name unchanged) with [`Variant::setting`] of the increment
    /// [`Variant::param`] set to [`Variant::value`] (when the scenario has that increment) and
    /// only its published-estimator entries ([`EstimatorSpec::Published`]).
    pub scenario: Scenario,
    /// Vocabulary name of the increment changed, e.g. `Cm_alpha`.
    pub param: &'static str,
    /// The setting changed: `lambda_per_s` (forgetting rate, 1/s) or `eta` (gain, –).
    pub setting: &'static str,
    /// Its value.
    pub value: f64,
}

/// The variants of the base scenarios `t4_7_case4` (λ of Cm_alpha 1e-7 and 1e7 /s, η 1e-12 to
/// 1e-6), `t4_8_case1` (λ of Cm_q 2e-4, 0.0625, 2e4 /s) and `t4_10_case1` (η of CD_alpha 1e-12
/// to 1e-6) among `scenarios`, in that order; empty when none of them is there.
pub fn variants(scenarios: &[Scenario]) -> Vec<Variant> {
    let base = |n: &str| scenarios.iter().find(|s| s.name == n);
    let mut out = Vec::new();
    let mut add = |sc: &Scenario, param, setting, values: &[f64]| {
        out.extend(values.iter().map(|&value| variant(sc, param, setting, value)));
    };
    if let Some(sc) = base("t4_7_case4") {
        add(sc, "Cm_alpha", "lambda_per_s", &[1e-7, 1e7]);
        add(sc, "Cm_alpha", "eta", &[1e-12, 1e-10, 1e-8, 1e-6]);
    }
    if let Some(sc) = base("t4_8_case1") {
        add(sc, "Cm_q", "lambda_per_s", &[2e-4, 0.0625, 2e4]);
    }
    if let Some(sc) = base("t4_10_case1") {
        add(sc, "CD_alpha", "eta", &[1e-12, 1e-10, 1e-8, 1e-6]);
    }
    out
}

fn variant(base: &Scenario, param: &'static str, setting: &'static str, value: f64) -> Variant {
    let mut sc = base.clone();
    let key = aeroident_estimators::vocabulary::Param::from_name(param);
    if let Some(p) = key.and_then(|k| sc.increments.get_mut(&k)) {
        match setting {
            "eta" => p.eta = value,
            _ => p.lambda_per_s = value,
        }
    }
    sc.estimator.retain(|e| matches!(e, EstimatorSpec::Published { .. }));
    Variant { scenario: sc, param, setting, value }
}

/// Why a variant gave no summary.
#[derive(Debug, thiserror::Error)]
pub enum EvidenceError {
    /// The variant's experiment failed.
    #[error("variant of `{scenario}`")]
    Run {
        /// The base scenario's name.
        scenario: String,
        /// Why.
        #[source]
        source: ExperimentError,
    },
    /// Its summary could not be formed.
    #[error(transparent)]
    Summary(#[from] MetricsError),
}

/// Flies every variant (in parallel) and summarises it; the summaries in the order of
/// `variants`.
///
/// # Errors
/// The first failed variant's [`EvidenceError`].
pub fn run_variants(variants: Vec<Variant>) -> Result<Vec<(Variant, Summary)>, EvidenceError> {
    variants
        .into_par_iter()
        .map(|v| {
            let out = run(&v.scenario).map_err(|source| EvidenceError::Run {
                scenario: v.scenario.name.clone(),
                source,
            })?;
            let sm = summarize(&out)?;
            Ok((v, sm))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::vocabulary::Param;

    /// `t4_8_case1` gives its three λ variants of Cm_q, published estimators only, the base
    /// untouched; a set without a base scenario gives none.
    #[test]
    fn variants_of_the_base_scenarios() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/f16/t4_8_case1.toml");
        let base = Scenario::from_path(std::path::Path::new(path)).unwrap();
        assert!(variants(&[]).is_empty());
        let vs = variants(std::slice::from_ref(&base));
        let values: Vec<f64> = vs.iter().map(|v| v.value).collect();
        assert_eq!(values, vec![2e-4, 0.0625, 2e4]);
        let cm_q = Param::from_name("Cm_q").unwrap();
        for v in &vs {
            assert_eq!(
                (v.param, v.setting, v.scenario.name.as_str()),
                ("Cm_q", "lambda_per_s", "t4_8_case1")
            );
            assert_eq!(v.scenario.increments[&cm_q].lambda_per_s, v.value);
            assert!(!v.scenario.estimator.is_empty());
            assert!(
                v.scenario.estimator.iter().all(|e| matches!(e, EstimatorSpec::Published { .. }))
            );
        }
        assert!(base.estimator.len() > vs[0].scenario.estimator.len());
    }
}
