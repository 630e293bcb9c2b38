//! The one place an aircraft estimator is built: [`build`] turns an [`EstimatorKind`], a model
//! structure, its priors and the options into a `Box<dyn Estimator>`; the replay pipeline (and
//! anything else that drives estimators over recorded or simulated samples) uses only that box.
//!
//! Adding an estimator: implement [`aeroident_estimators::Estimator`] in the core, add a
//! variant to [`EstimatorKind`] and an arm to [`build`].

use aeroident_estimators::rls::{Rls, RlsConfig};
use aeroident_estimators::{Estimator, EstimatorError, ModelStructure, Priors};

/// The aircraft estimators, by command-line name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum EstimatorKind {
    /// Recursive least squares (equation error) on every modelled coefficient.
    Rls,
    /// Extended Kalman filter (states and parameters; recursive output error).
    Ekf,
    /// The thesis's sliding-mode parameter estimator.
    Smpe,
    /// The corrected sliding-mode parameter estimator.
    SmpeCorrected,
    /// The model-reference gradient estimator.
    Gradient,
}

impl EstimatorKind {
    /// The name used on the command line and in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            EstimatorKind::Rls => "rls",
            EstimatorKind::Ekf => "ekf",
            EstimatorKind::Smpe => "smpe",
            EstimatorKind::SmpeCorrected => "smpe-corrected",
            EstimatorKind::Gradient => "gradient",
        }
    }

    /// Whether the estimator regresses on the measured coefficients
    /// ([`AirDataSample::measured_coefficients`](aeroident_estimators::AirDataSample::measured_coefficients)),
    /// and so needs the angular accelerations `ṗ, q̇, ṙ` of the moment coefficients (the
    /// replay differentiates the rates when the record lacks them). Estimators that integrate
    /// their own model (Kalman filters) do not: a differentiated rate is not an independent
    /// measurement, so they are not given one.
    pub fn uses_measured_coefficients(self) -> bool {
        !matches!(self, EstimatorKind::Ekf)
    }
}

/// Options of the estimators (each uses the ones that apply to it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorOptions {
    /// RLS forgetting factor `λ ∈ (0, 1]` (1 = ordinary least squares).
    pub forgetting: f64,
    /// Nominal sample interval of the data, s, when known (the record's `nominal_dt_s`).
    pub sample_interval_s: Option<f64>,
}

impl Default for EstimatorOptions {
    fn default() -> Self {
        Self { forgetting: 1.0, sample_interval_s: None }
    }
}

/// Why an estimator could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// The estimator is not part of this build.
    #[error("estimator `{0}` is not available in this build")]
    NotAvailable(&'static str),
    /// The estimator rejected its configuration.
    #[error("estimator `{estimator}`: {source}")]
    Config {
        /// Estimator name.
        estimator: &'static str,
        /// Why.
        source: EstimatorError,
    },
}

/// Builds estimator `kind` over `structure` with `priors` (one per parameter, parameter
/// order; used by the estimators that start from a prior) and `options`.
///
/// # Errors
/// [`BuildError::NotAvailable`] for an estimator not in this build; [`BuildError::Config`]
/// when the estimator rejects the structure or an option (e.g. a forgetting factor outside
/// (0, 1]).
pub fn build(
    kind: EstimatorKind,
    structure: ModelStructure,
    priors: Priors,
    options: &EstimatorOptions,
) -> Result<Box<dyn Estimator>, BuildError> {
    let config = |source| BuildError::Config { estimator: kind.name(), source };
    // RLS starts without a prior (exact initialisation).
    let _ = priors;
    match kind {
        EstimatorKind::Rls => {
            let cfg = RlsConfig { forgetting: options.forgetting, init_samples: 0 };
            Ok(Box::new(Rls::new(structure, cfg).map_err(config)?))
        }
        EstimatorKind::Ekf
        | EstimatorKind::Smpe
        | EstimatorKind::SmpeCorrected
        | EstimatorKind::Gradient => Err(BuildError::NotAvailable(kind.name())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_rls_and_names_the_missing_ones() {
        let st = ModelStructure::longitudinal();
        let pr = Priors::generic(&st);
        let e = build(EstimatorKind::Rls, st, pr, &EstimatorOptions::default()).unwrap();
        assert_eq!(e.method(), "rls");
        assert_eq!(e.structure().n_params(), 12);
        for k in [
            EstimatorKind::Ekf,
            EstimatorKind::Smpe,
            EstimatorKind::SmpeCorrected,
            EstimatorKind::Gradient,
        ] {
            let err = build(k, st, pr, &EstimatorOptions::default()).err().unwrap();
            assert_eq!(
                err.to_string(),
                format!("estimator `{}` is not available in this build", k.name())
            );
        }
        let bad = EstimatorOptions { forgetting: 1.5, ..Default::default() };
        let err = build(EstimatorKind::Rls, st, pr, &bad).err().unwrap().to_string();
        assert!(err.starts_with("estimator `rls`: invalid configuration `forgetting`"), "{err}");
    }
}
