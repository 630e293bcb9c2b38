//! # aeroident-estimators
//!
//! Real-time parameter estimators for aerodynamic identification. Every estimator consumes one
//! sample at a time through [`Estimator::update`] and returns its current [`Estimate`]. The crate
//! is `no_std` (build with `--no-default-features`): fixed-size `nalgebra` types, no allocation
//! and no I/O in a per-sample update, so the same code can run on a flight computer.
//!
//! Sources: P. M. Gurbacki, M.S. thesis, RIT 2010 (equation numbers as in
//! `spec/thesis-method.md`); Klein & Morelli, *Aircraft System Identification*, AIAA 2006;
//! Jategaonkar, *Flight Vehicle System Identification*, AIAA 2015.
#![cfg_attr(not(feature = "std"), no_std)]

use nalgebra::{SMatrix, SVector};

pub mod kalman;
/// Model-reference gradient estimator of thesis (3.3), the comparison of thesis §4.2.5.
pub mod mrac;
pub mod regressors;
pub mod rls;

/// A parameter estimate at one time.
///
/// `theta` holds `P` parameters in the order of [`Estimator::param_names`]; `covariance` is the
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
    #[error("non-finite input `{field}` = {value} at t = {t_s} s")]
    NonFiniteInput {
        /// Name of the offending sample field.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Sample time, s.
        t_s: f64,
    },
    /// A configuration value was out of its valid range.
    #[error("invalid configuration `{field}` = {value}: {reason}")]
    InvalidConfig {
        /// Name of the configuration field.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
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

/// An online estimator: consumes one sample, gives the current estimate of `P` parameters.
///
/// Implementations must not allocate or do I/O in [`Estimator::update`].
pub trait Estimator<const P: usize> {
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
