//! Recursive least squares (equation error) with exponential forgetting and standard errors.
//!
//! Source: Klein & Morelli, *Aircraft System Identification*, AIAA 2006, ch. 5 (ordinary least
//! squares, `cov θ̂ = σ̂² (XᵀX)⁻¹`, `σ̂² = RSS/(N − p)`) and its chapter on real-time estimation
//! (recursive least squares with forgetting); Jategaonkar 2015, ch. 7 (`RLSff.m`).
//!
//! With forgetting factor `λ ∈ (0, 1]` the estimate minimises `J_n = Σ_k λ^{n−k} (y_k − φ_kᵀθ)²`:
//!
//! ```text
//! e_n = y_n − φ_nᵀ θ_{n−1}                      (a-priori residual)
//! k_n = P_{n−1} φ_n / (λ + φ_nᵀ P_{n−1} φ_n)
//! θ_n = θ_{n−1} + k_n e_n
//! P_n = (P_{n−1} − k_n φ_nᵀ P_{n−1}) / λ          (P_n = (Σ λ^{n−k} φ_k φ_kᵀ)⁻¹)
//! J_n = λ J_{n−1} + λ e_n² / (λ + φ_nᵀ P_{n−1} φ_n)   (exact weighted RSS recursion)
//! N_n = λ N_{n−1} + 1                           (effective sample count)
//! cov θ_n = J_n / (N_n − p) · P_n
//! ```
//!
//! **Exact initialisation** (no prior): the first samples are accumulated in information form
//! `A = Σ λ^{n−k} φφᵀ`, `b = Σ λ^{n−k} φ y` until `A` is well conditioned (see
//! [`INIT_MIN_SCALED_PIVOT`]) and at least `init_samples` samples were seen; then `θ = A⁻¹b`, `P = A⁻¹`. From then on the recursion
//! above is algebraically identical to batch least squares on all samples so far (weighted by
//! `λ^{n−k}`), so with `λ = 1` RLS equals the batch solution to rounding.
//!
//! **WARNING:** the standard errors assume white equation errors. On real flight data the
//! residuals are coloured and the σ are optimistic (Morelli's residual-spectrum
//! correction, Klein & Morelli ch. 5, is not applied here). Equation error is also biased when
//! the regressors are noisy (errors-in-variables, Klein & Morelli ch. 5).

use crate::regressors::{Regressor, Timed};
use crate::{Estimate, EstimatorError, ParametricEstimator};
use nalgebra::{SMatrix, SVector};

/// Configuration of [`Rls`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RlsConfig {
    /// Forgetting factor `λ ∈ (0, 1]`; 1 is ordinary least squares. Data `n` samples old weighs
    /// `λⁿ` (memory ≈ `1/(1−λ)` samples).
    pub forgetting: f64,
    /// Minimum number of samples before the exact initialisation (at least `P`).
    pub init_samples: usize,
}

impl Default for RlsConfig {
    fn default() -> Self {
        Self { forgetting: 1.0, init_samples: 0 }
    }
}

/// Recursive least squares on the regression `R` with `P` parameters. No allocation.
#[derive(Debug, Clone)]
pub struct Rls<R: Regressor<P>, const P: usize> {
    regressor: R,
    lambda: f64,
    init_samples: usize,
    /// Information matrix accumulated before initialisation.
    info: SMatrix<f64, P, P>,
    info_b: SVector<f64, P>,
    info_yy: f64,
    /// `P_n` after initialisation (unscaled covariance).
    p: SMatrix<f64, P, P>,
    initialised: bool,
    count: usize,
    n_eff: f64,
    rss: f64,
    est: Estimate<P>,
}

impl<R: Regressor<P>, const P: usize> Rls<R, P> {
    /// A new estimator; the estimate is zero with no covariance until initialised.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] if `forgetting ∉ (0, 1]`.
    pub fn new(regressor: R, config: RlsConfig) -> Result<Self, EstimatorError> {
        if !(config.forgetting > 0.0 && config.forgetting <= 1.0) {
            return Err(EstimatorError::InvalidConfig {
                field: "forgetting",
                value: config.forgetting,
                reason: "must be in (0, 1]",
            });
        }
        Ok(Self {
            regressor,
            lambda: config.forgetting,
            init_samples: config.init_samples.max(P),
            info: SMatrix::zeros(),
            info_b: SVector::zeros(),
            info_yy: 0.0,
            p: SMatrix::zeros(),
            initialised: false,
            count: 0,
            n_eff: 0.0,
            rss: 0.0,
            est: Estimate::new(0.0, SVector::zeros()),
        })
    }

    /// The regression this estimator fits.
    pub fn regressor(&self) -> &R {
        &self.regressor
    }

    /// Residual variance estimate `σ̂² = J_n/(N_n − p)`, once defined.
    pub fn residual_variance(&self) -> Option<f64> {
        (self.initialised && self.n_eff > P as f64).then(|| self.rss / (self.n_eff - P as f64))
    }

    fn publish(&mut self, t_s: f64) {
        self.est.t_s = t_s;
        self.est.covariance = self.residual_variance().map(|s2| self.p * s2);
    }
}

/// Smallest admissible pivot of the unit-diagonal-scaled information matrix at initialisation:
/// every regressor must carry at least this fraction of its energy independently of the
/// others (a reciprocal-condition guard; with fewer informative samples the exact solution
/// would be dominated by rounding).
pub const INIT_MIN_SCALED_PIVOT: f64 = 1e-8;

/// Whether `A` is positive definite with Cholesky pivots of `D^{-1/2} A D^{-1/2}` (unit
/// diagonal) all at least [`INIT_MIN_SCALED_PIVOT`].
fn well_conditioned<const P: usize>(a: &SMatrix<f64, P, P>) -> bool {
    let mut d = SVector::<f64, P>::zeros();
    for i in 0..P {
        if !a[(i, i)].is_finite() || a[(i, i)] <= 0.0 {
            return false;
        }
        d[i] = 1.0 / libm::sqrt(a[(i, i)]);
    }
    let scaled = SMatrix::<f64, P, P>::from_fn(|i, j| a[(i, j)] * d[i] * d[j]);
    match scaled.cholesky() {
        Some(c) => (0..P).all(|i| {
            let l = c.l_dirty()[(i, i)];
            l * l >= INIT_MIN_SCALED_PIVOT
        }),
        None => false,
    }
}

impl<R: Regressor<P>, const P: usize> ParametricEstimator<P> for Rls<R, P>
where
    R::Sample: Timed,
{
    type Sample = R::Sample;

    fn param_names(&self) -> [&'static str; P] {
        self.regressor.names()
    }

    fn update(&mut self, sample: &Self::Sample) -> Result<&Estimate<P>, EstimatorError> {
        let t_s = sample.t_s();
        let (phi, y) = self.regressor.regress(sample);
        if !y.is_finite() {
            return Err(EstimatorError::NonFiniteInput { field: "y", value: y, t_s });
        }
        if let Some(v) = phi.iter().find(|v| !v.is_finite()) {
            return Err(EstimatorError::NonFiniteInput { field: "phi", value: *v, t_s });
        }
        let lambda = self.lambda;
        if !self.initialised {
            self.info = self.info * lambda + phi * phi.transpose();
            self.info_b = self.info_b * lambda + phi * y;
            self.info_yy = self.info_yy * lambda + y * y;
            self.n_eff = self.n_eff * lambda + 1.0;
            self.count += 1;
            if self.count >= self.init_samples
                && well_conditioned(&self.info)
                && let Some(chol) = self.info.cholesky()
            {
                let theta = chol.solve(&self.info_b);
                let p = chol.inverse();
                if theta.iter().chain(p.iter()).all(|v| v.is_finite()) {
                    self.est.theta = theta;
                    self.p = p;
                    self.rss = (self.info_yy - self.info_b.dot(&theta)).max(0.0);
                    self.initialised = true;
                }
            }
            self.publish(t_s);
            return Ok(&self.est);
        }
        let e = y - phi.dot(&self.est.theta);
        let p_phi = self.p * phi;
        let denom = lambda + phi.dot(&p_phi);
        if !(denom.is_finite() && denom > 0.0) {
            return Err(EstimatorError::Numerical { what: "RLS gain denominator", t_s });
        }
        let k = p_phi / denom;
        let mut p_new = (self.p - k * p_phi.transpose()) / lambda;
        p_new = (p_new + p_new.transpose()) * 0.5;
        let theta_new = self.est.theta + k * e;
        if !theta_new.iter().chain(p_new.iter()).all(|v| v.is_finite()) {
            return Err(EstimatorError::Numerical { what: "RLS update", t_s });
        }
        self.est.theta = theta_new;
        self.p = p_new;
        self.rss = lambda * self.rss + lambda * e * e / denom;
        self.n_eff = lambda * self.n_eff + 1.0;
        self.count += 1;
        self.publish(t_s);
        Ok(&self.est)
    }

    fn estimate(&self) -> &Estimate<P> {
        &self.est
    }
}
