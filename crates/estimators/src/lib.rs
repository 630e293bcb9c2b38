//! # aeroident-estimators
//!
//! Real-time parameter estimators for aerodynamic identification, over one vocabulary:
//!
//! - one sample, [`AirDataSample`] (every channel a six-axis identification uses, absent
//!   channels `None`), with its [`AircraftConstants`] and measured coefficients
//!   ([`AirDataSample::measured_coefficients`]);
//! - one model vocabulary, [`vocabulary`]: coefficient × term, parameters named
//!   `<coefficient>_<term>` (`Cm_alpha`, `Cl_p`, `Cn_beta` …), structures declared freely or by
//!   preset ([`ModelStructure`]);
//! - one estimator interface, [`Estimator`]: consume a sample, give [`Estimates`] (value, σ,
//!   whether identified) of the structure's parameters. Estimators that need a model state carry
//!   and integrate it themselves, so each is usable from samples alone: [`Rls`] (and its
//!   instrumental-variable form [`RlsIv`], for noisy regressors), [`Ftr`],
//!   [`Ekf`] (each with its config at the crate root), and the model-reference estimators of
//!   [`model_reference`] (the thesis's sliding-mode estimator as published, the corrected one,
//!   and the gradient law (3.3)); the batch output-error and filter-error fits are
//!   `output_error::fit` and `output_error::filter_error::fit` (with `std`).
//!
//! The linear algebra and the dual numbers of the exact partials are internal; [`Scalar`] and
//! [`Dual`] are exported for the flight model's generic evaluation.
//!
//! The crate is `no_std` (build with `--no-default-features`): fixed-capacity arrays, no
//! allocation and no I/O in a per-sample update, so the same code can run on a flight computer.
//!
//! The generic sliding-mode and gradient engines over any [`smpe::ParametricModel`] (the
//! thesis's proof-of-concept systems and its F-16 increments) keep their own const-generic
//! interface, [`ParametricEstimator`].
//!
//! Sources: P. M. Gurbacki, M.S. thesis, RIT 2010 (equation numbers as in
//! `spec/thesis-method.md`); Klein & Morelli, *Aircraft System Identification*, AIAA 2006;
//! Jategaonkar, *Flight Vehicle System Identification*, AIAA 2015.
#![cfg_attr(not(feature = "std"), no_std)]
// Numerical kernels index several arrays with one loop variable, as the equations do.
#![allow(clippy::needless_range_loop)]

use nalgebra::{SMatrix, SVector};

pub mod change;
pub mod coloured;
#[cfg(feature = "std")]
pub mod compat;
pub(crate) mod dual;
pub mod ekf;
pub mod estimator;
pub mod finite_time;
pub mod flight_model;
pub mod ftr;
pub mod iv;
pub(crate) mod linalg;
pub mod model_reference;
#[cfg(feature = "std")]
pub mod output_error;
pub mod prior;
pub mod rls;
pub mod sample;
#[cfg(feature = "std")]
pub mod structure;
pub mod vocabulary;

// The test-support aircraft names the crate `aeroident_estimators` so that the bench and the
// examples can include the same file.
#[cfg(test)]
extern crate self as aeroident_estimators;
#[cfg(test)]
pub(crate) mod test_aircraft;

pub use change::ChangeConfig;
pub use dual::{Dual, Scalar};
pub use ekf::{Ekf, EkfConfig, SigmaOption};
pub use estimator::{Estimates, Estimator, Event, EventKind, EventLog, Status};
pub use finite_time::{FiniteTimeConfig, FiniteTimeSmpe};
pub use flight_model::{FlightModel, Output, StateSet};
pub use ftr::{Ftr, FtrConfig};
pub use iv::{IvConfig, RlsIv};
pub use prior::{ParamPrior, Priors};
pub use rls::{Rls, RlsConfig};
pub use sample::{AirDataSample, AircraftConstants, CoefficientValues};
pub use vocabulary::{AlphaKnots, Coefficient, MAX_PARAMS, ModelStructure, Param, Term, TermInput};
/// Model-reference gradient estimator of thesis (3.3), the comparison of thesis §4.2.5.
pub mod mrac;

/// A parameter estimate at one time.
///
/// `theta` holds `P` parameters in the order of [`ParametricEstimator::param_names`]; `covariance` is the
/// `P × P` estimation-error covariance where the method provides one (RLS, Kalman filters) and
/// `None` where it does not (sliding-mode, gradient): never a made-up number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate<const P: usize> {
    /// Time of the sample that produced this estimate, s.
    pub t_s: f64,
    /// Parameter estimates, units as documented by each estimator (per rad for derivatives).
    pub theta: SVector<f64, P>,
    /// Estimation-error covariance, units of `theta` squared, where the method gives one.
    pub covariance: Option<SMatrix<f64, P, P>>,
}

impl<const P: usize> Estimate<P> {
    /// An estimate at `t_s` with the given parameters and no covariance.
    pub fn new(t_s: f64, theta: SVector<f64, P>) -> Self {
        Self { t_s, theta, covariance: None }
    }

    /// Standard error of parameter `i` (square root of the covariance diagonal), if known.
    pub fn std_error(&self, i: usize) -> Option<f64> {
        self.covariance.map(|c| libm::sqrt(c[(i, i)].max(0.0)))
    }
}

/// Errors an estimator can return from one update. Each names what was wrong.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EstimatorError {
    /// An input sample value was not finite.
    #[error("non-finite input `{field}` = {} at t = {t_s} s", aeroident_physics::text::ExactOrShort(*.value))]
    NonFiniteInput {
        /// Name of the offending sample field.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Sample time, s.
        t_s: f64,
    },
    /// An input value is finite but outside what any aircraft can produce (e.g. V = 1e308 m/s,
    /// |α| > 10 rad, a measured coefficient of 1e300): a corrupt record, never a data point.
    #[error(
        "implausible input `{field}` = {} at t = {t_s} s (limit {})",
        aeroident_physics::text::ExactOrShort(*.value),
        aeroident_physics::text::ExactOrShort(*.limit)
    )]
    ImplausibleInput {
        /// Name of the offending sample field.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Sample time, s.
        t_s: f64,
        /// The physical limit it exceeds, in the field's unit.
        limit: f64,
    },
    /// A configuration value was out of its valid range.
    #[error(
        "invalid configuration `{field}` = {}: {reason}",
        aeroident_physics::text::ExactOrShort(*.value)
    )]
    InvalidConfig {
        /// Name of the configuration field.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// A structure whose longitudinal or lateral-directional coefficients are incomplete, so
    /// the states of that axis cannot be integrated (the estimators that simulate the
    /// aircraft need a whole axis, [`StateSet::of`]).
    #[error("{}", IncompleteAxisMessage { lateral: *lateral, declared: *declared })]
    IncompleteAxis {
        /// Whether the lateral-directional axis (else the longitudinal one) is incomplete.
        lateral: bool,
        /// The coefficients the structure declares: bit `i` for `Coefficient::ALL[i]`.
        declared: u8,
    },
    /// A batch fit whose estimated peak memory is over its limit, refused before anything is
    /// simulated (`output_error::estimated_peak_bytes`).
    #[error(
        "{samples} samples × {outputs} outputs × {unknowns} unknowns (the longest manoeuvre {longest} samples): the fit would need about {} MB at its peak, more than the limit of {} MB; fit windows of the record (replay --window) or fewer manoeuvres",
        libm::round(*bytes / 1e6),
        libm::round(*limit / 1e6)
    )]
    TooLarge {
        /// Samples in all manoeuvres.
        samples: usize,
        /// Outputs fitted.
        outputs: usize,
        /// Unknowns (parameters, biases, free initial states).
        unknowns: usize,
        /// Samples of the longest manoeuvre (its transforms are held at once).
        longest: usize,
        /// Estimated peak memory, bytes.
        bytes: f64,
        /// The limit, bytes.
        limit: f64,
    },
    /// A matrix that must be positive definite was not (e.g. a Cholesky factorisation failed).
    #[error("numerical failure in `{what}` at t = {t_s} s")]
    Numerical {
        /// What failed.
        what: &'static str,
        /// Sample time, s.
        t_s: f64,
    },
}

/// The message of [`EstimatorError::IncompleteAxis`], in the coefficient names a model file
/// uses; written as it is displayed, without allocating (the core is `no_std`).
struct IncompleteAxisMessage {
    lateral: bool,
    declared: u8,
}

impl core::fmt::Display for IncompleteAxisMessage {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(if self.lateral {
            "a lateral-directional model needs CY, Cl and Cn (its states beta, p, r, phi are integrated)"
        } else {
            "a longitudinal model needs a force pair (CL and CD, or CX and CZ) and Cm (its states V, alpha, theta, q are integrated)"
        })?;
        f.write_str("; this model declares ")?;
        let declared = vocabulary::Coefficient::ALL
            .iter()
            .enumerate()
            .filter(|(i, _)| self.declared >> i & 1 == 1);
        for (k, (_, c)) in declared.enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            f.write_str(c.name())?;
        }
        Ok(())
    }
}

/// The engine-level interface of the generic sliding-mode and gradient estimators over a
/// [`smpe::ParametricModel`] with `P` parameters (any ODE, not only aircraft): consumes one
/// sample, gives the current estimate. Aircraft estimation goes through [`Estimator`].
///
/// Implementations must not allocate or do I/O in [`ParametricEstimator::update`].
pub trait ParametricEstimator<const P: usize> {
    /// One measurement sample (a plain struct of named, unit-suffixed fields).
    type Sample;
    /// Parameter names, the same strings as CSV headers (e.g. `"Cm_alpha"`, `"dCm_q"`).
    fn param_names(&self) -> [&'static str; P];
    /// Consumes one sample and returns the updated estimate.
    ///
    /// # Errors
    /// [`EstimatorError`] when the sample is not finite or the update fails numerically; the
    /// estimator's state is left as it was before the call.
    fn update(&mut self, sample: &Self::Sample) -> Result<&Estimate<P>, EstimatorError>;
    /// The current estimate.
    fn estimate(&self) -> &Estimate<P>;
}

/// Sliding-mode parameter estimators (thesis §3.2–§3.4): published and corrected.
pub mod smpe;

#[cfg(test)]
mod tests {
    use super::Estimate;
    use nalgebra::{SMatrix, SVector};

    /// The standard error is the square root of the covariance diagonal (σ² = 4, 0.25 → 2,
    /// 0.5), a rounding-negative variance reads as 0, and an estimate without a covariance has
    /// none.
    #[test]
    fn analytic_std_error_is_the_root_of_the_covariance_diagonal() {
        let theta = SVector::<f64, 3>::new(1.0, -2.0, 0.5);
        let mut e = Estimate::new(0.0, theta);
        assert_eq!(e.std_error(0), None);
        let mut c = SMatrix::<f64, 3, 3>::from_diagonal(&SVector::from([4.0, 0.25, -1e-18]));
        c[(0, 1)] = 0.3;
        c[(1, 0)] = 0.3;
        e.covariance = Some(c);
        assert_eq!(
            [e.std_error(0), e.std_error(1), e.std_error(2)],
            [Some(2.0), Some(0.5), Some(0.0)]
        );
    }
}
