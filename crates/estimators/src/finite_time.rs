//! Finite-time sliding-mode estimator on the forgotten information memory (`smpe-finite-time`),
//! over any [`ModelStructure`]: one regression per modelled coefficient, as [`crate::rls`], with
//! a sliding (unit-vector) law driving the estimate to the least-squares solution of that
//! memory, and the memory's σ.
//!
//! Sources: Adetola & Guay, "Finite-time parameter estimation in adaptive control of nonlinear
//! systems", *IEEE TAC* 53(3), 2008; Na, Mahyuddin, Herrmann, Ren & Barber, "Robust adaptive
//! finite-time parameter estimation and control for robotic systems", *Int. J. Robust Nonlinear
//! Control* 25(16), 2015 (the memory `P, Q` and the law `θ̂̇ = −Γ W/‖W‖`, `W = P θ̂ − Q`); Gao,
//! Wang & Homaifa, "Discrete-time variable structure control systems", *IEEE TIE* 42(2), 1995
//! (the reaching law `ṡ = −q s − ε sgn s` and its discrete form); Ortega, Romero, Aranovskiy &
//! Tao, 2025 (with noise these estimators converge to the least-squares solution of the same
//! memory: the claim is a transient, not an accuracy).
//!
//! # The memory and the sliding variable
//!
//! Per coefficient `C = φᵀθ + v` (`φ` the regressors of its terms, `y = C_m` the measured
//! coefficient), with forgetting `λ` (memory `τ = Δt/(1 − λ)`), the information memory is
//!
//! ```text
//! A_n = λ A_{n−1} + φ_n φ_nᵀ,   b_n = λ b_{n−1} + φ_n y_n        (Na et al.'s P and Q)
//! W_n = A_n θ̂ − b_n = A_n (θ̂ − θ̄_n),                           θ̄_n = A_n⁻¹ b_n
//! ```
//!
//! `θ̄_n` is the least-squares solution of the memory, kept by the recursion of [`crate::rls`]
//! (with its exact initialisation, its residual variance `σ̂²` and its coloured-residual
//! covariance); `W` is formed as `A (θ̂ − θ̄)`, the same vector without the cancellation of
//! `A θ̂ − b` near the solution.
//!
//! # The law
//!
//! The unit-vector law of Na et al. with the gain `Γ = A⁻¹` (so the convergence does not
//! depend on the conditioning or the units of the regressors) and Gao's exponential term:
//!
//! ```text
//! θ̂̇ = −(q + ε / ‖W‖_{A⁻¹}) A⁻¹ W,     ‖W‖_{A⁻¹} = √(Wᵀ A⁻¹ W) = ‖θ̂ − θ̄‖_A,   ε = γ σ̂
//! ```
//!
//! For a fixed memory `d = ‖θ̂ − θ̄‖_A` obeys `ḋ = −q d − ε`: it reaches 0 in finite time
//! `t ≤ ln(1 + q d₀/ε)/q` (≤ `d₀/ε`). `d/σ̂` is the distance to the memory's solution in
//! standard errors of its white-residual fit, so `γ` is in standard errors per second and `q` in
//! 1/s. Per sample interval (`Δt` from the timestamps) the discrete law (Gao et al.) is applied
//! to the distance after the memory took the sample:
//!
//! ```text
//! d⁺ = max(0, (1 − qΔt) d − εΔt),    θ̂⁺ = θ̄_n + (d⁺/d) (θ̂ − θ̄_n)
//! ```
//!
//! so a distance within one step lands on the surface `W = 0` (no chattering about it) and the
//! estimate never overshoots `θ̄`. At the memory's exact initialisation `θ̂ = θ̄` (nothing to
//! reach); afterwards the law tracks `θ̄` as the memory moves (a change of the aircraft moves
//! `θ̄` over the memory `τ`; the law follows a ramp with lag `1/q`). The estimate is never more
//! accurate than `θ̄`: that is what the contest in `docs/smpe-finite-time.md` measures.
//!
//! # σ, status, null
//!
//! The estimate is `θ̄ + δ`, `δ = θ̂ − θ̄` known: its covariance is reported as the memory's
//! coloured-residual covariance of `θ̄` ([`crate::rls`], [`crate::coloured`]) plus `δ δᵀ` (the
//! distance still to slide is counted as error; it is 0 on the surface). Before the memory's
//! exact initialisation a coefficient's parameters are not identified (`null`); a numerical
//! failure is a divergence ([`crate::Status::Diverged`]). A sample whose time is not after the previous
//! one is refused and nothing changes. Without change detection the memory horizon `τ` bounds
//! how long a change takes to show, as for [`crate::Rls`]; with it
//! ([`FiniteTimeSmpe::enable_change_detection`], `crate::change`) an alarm re-opens the memory
//! and the estimate starts on the new memory's solution.

// Index loops follow the recursion's equations line by line.
#![allow(clippy::needless_range_loop)]

use crate::EstimatorError;
use crate::change::ChangeConfig;
use crate::estimator::{Estimates, Estimator, EventLog};
use crate::linalg::{Square, cholesky, cholesky_inverse};
use crate::rls::{CoefficientFit, Fit, Regression, covariance, update_fits, validated};
use crate::sample::AirDataSample;
use crate::vocabulary::{Coefficient, ModelStructure, N_TERMS};

/// Configuration of [`FiniteTimeSmpe`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiniteTimeConfig {
    /// Forgetting factor `λ ∈ (0, 1]` of the information memory (memory `Δt/(1 − λ)` s), the
    /// same meaning as [`crate::RlsConfig::forgetting`].
    pub forgetting: f64,
    /// Minimum number of samples before the memory's exact initialisation.
    pub init_samples: usize,
    /// Sliding gain `γ ≥ 0`: the constant reaching speed `ε = γ σ̂`, standard errors per second.
    pub sliding_gain_per_s: f64,
    /// Exponential reaching rate `q ≥ 0`, 1/s (`q Δt < 1` is not required: the step is
    /// clamped at the surface).
    pub reaching_rate_per_s: f64,
}

impl Default for FiniteTimeConfig {
    /// `λ = 1`; `γ = 10` standard errors per second and `q = 10/s`: a memory solution moving by
    /// a 30 % change over a 2-s memory (tens of standard errors per second) is followed with a
    /// lag of `1/q = 0.1 s`, well inside a 5-s re-convergence budget.
    fn default() -> Self {
        Self {
            forgetting: 1.0,
            init_samples: 0,
            sliding_gain_per_s: 10.0,
            reaching_rate_per_s: 10.0,
        }
    }
}

/// One coefficient: the memory's least-squares fit and the sliding estimate.
#[derive(Debug, Clone, Copy)]
struct SlidingFit {
    memory: Fit,
    /// The information matrix `A` of the memory (lower and upper triangle).
    info: Square<N_TERMS>,
    theta: [f64; N_TERMS],
    /// `θ̂ − θ̄` after the last update.
    offset: [f64; N_TERMS],
    last_t_s: Option<f64>,
    gain: f64,
    rate: f64,
}

impl SlidingFit {
    fn new(structure: &ModelStructure, c: Coefficient, config: &FiniteTimeConfig) -> Self {
        Self {
            memory: Fit::new(structure, c),
            info: [[0.0; N_TERMS]; N_TERMS],
            theta: [0.0; N_TERMS],
            offset: [0.0; N_TERMS],
            last_t_s: None,
            gain: config.sliding_gain_per_s,
            rate: config.reaching_rate_per_s,
        }
    }

    /// The discrete reaching law over `dt` towards the memory's solution `θ̄` (module doc).
    fn slide(&mut self, dt: f64) {
        let n = self.memory.regression().n;
        let bar = *self.memory.theta();
        let mut delta = [0.0; N_TERMS];
        for i in 0..n {
            delta[i] = self.theta[i] - bar[i];
        }
        // d² = δᵀ W with W = A δ.
        let mut d2 = 0.0;
        for i in 0..n {
            let w: f64 = (0..n).map(|j| self.info[i][j] * delta[j]).sum();
            d2 += delta[i] * w;
        }
        let d = libm::sqrt(d2.max(0.0));
        let eps = self.gain * self.memory.residual_variance().map_or(0.0, libm::sqrt);
        let d_next = ((1.0 - self.rate * dt) * d - eps * dt).max(0.0);
        let shrink = if d > 0.0 { d_next / d } else { 0.0 };
        for i in 0..n {
            self.offset[i] = shrink * delta[i];
            self.theta[i] = bar[i] + self.offset[i];
        }
    }
}

impl CoefficientFit for SlidingFit {
    fn regression(&self) -> &Regression {
        self.memory.regression()
    }

    fn update(
        &mut self,
        phi: &[f64; N_TERMS],
        y: f64,
        lambda: f64,
        init_samples: usize,
        t_s: f64,
    ) -> Result<(), EstimatorError> {
        let was_initialised = self.memory.initialised();
        self.memory.update(phi, y, lambda, init_samples, t_s)?;
        let n = self.memory.regression().n;
        if self.memory.change_pending() {
            // The memory was re-opened on a detected change: its information is no longer the
            // running sum, and the estimate starts on the new memory's solution.
            let mut l = [[0.0; N_TERMS]; N_TERMS];
            if !cholesky(&self.memory.p, n, &mut l) {
                return Err(EstimatorError::Numerical { what: "re-opened memory", t_s });
            }
            cholesky_inverse(&l, n, &mut self.info);
            self.theta = *self.memory.theta();
            self.offset = [0.0; N_TERMS];
            self.last_t_s = Some(t_s);
            return Ok(());
        }
        for i in 0..n {
            for j in 0..=i {
                let v = self.info[i][j] * lambda + phi[i] * phi[j];
                self.info[i][j] = v;
                self.info[j][i] = v;
            }
        }
        let dt = self.last_t_s.map_or(0.0, |t0| t_s - t0);
        self.last_t_s = Some(t_s);
        if !self.memory.initialised() {
            return Ok(());
        }
        if !was_initialised {
            // The exact initialisation: the estimate starts on the surface.
            self.theta = *self.memory.theta();
            self.offset = [0.0; N_TERMS];
            return Ok(());
        }
        self.slide(dt);
        // Non-finite after finite inputs is an overflow: the caller marks the estimator
        // diverged, so nothing is rolled back (as RLS's fits).
        if self.theta[..n].iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(EstimatorError::Numerical { what: "sliding-mode memory law", t_s })
        }
    }

    fn initialised(&self) -> bool {
        self.memory.initialised()
    }

    fn theta(&self) -> &[f64; N_TERMS] {
        &self.theta
    }

    fn residual_variance(&self) -> Option<f64> {
        self.memory.residual_variance()
    }

    /// The memory's covariance of `θ̄` plus `δ_i δ_j` (module doc).
    fn cov(&self, s2: f64, i: usize, j: usize) -> f64 {
        self.memory.cov(s2, i, j) + self.offset[i] * self.offset[j]
    }

    fn variance(&self, s2: f64, k: usize) -> f64 {
        self.memory.variance(s2, k) + self.offset[k] * self.offset[k]
    }

    fn take_change(&mut self) -> Option<f64> {
        self.memory.take_change()
    }
}

/// The finite-time sliding-mode estimator on the forgotten information memory over every
/// coefficient of a structure (module doc). No allocation per update.
#[derive(Debug, Clone)]
pub struct FiniteTimeSmpe {
    structure: ModelStructure,
    fits: [Option<SlidingFit>; 8],
    lambda: f64,
    init_samples: usize,
    last_t_s: Option<f64>,
    est: Estimates,
    events: EventLog,
}

impl FiniteTimeSmpe {
    /// A new estimator; nothing is identified until each memory's exact initialisation.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] if `forgetting ∉ (0, 1]`, a gain or rate is negative or
    /// not finite, or the structure is invalid (empty, over capacity, CX/CZ mixed with CL/CD).
    pub fn new(
        structure: ModelStructure,
        config: FiniteTimeConfig,
    ) -> Result<Self, EstimatorError> {
        let structure = validated(structure, config.forgetting)?;
        for (field, value) in [
            ("sliding_gain_per_s", config.sliding_gain_per_s),
            ("reaching_rate_per_s", config.reaching_rate_per_s),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(EstimatorError::InvalidConfig {
                    field,
                    value,
                    reason: "must be finite and ≥ 0",
                });
            }
        }
        // Built in place, as `Rls::new` (a moved stack-built array of fits was miscompiled).
        let mut est = Self {
            structure,
            fits: [None; 8],
            lambda: config.forgetting,
            init_samples: config.init_samples,
            last_t_s: None,
            est: Estimates::new(structure.n_params()),
            events: EventLog::new(),
        };
        for c in structure.coefficients() {
            est.fits[c.index()] = Some(SlidingFit::new(&structure, c, &config));
        }
        Ok(est)
    }

    /// Adds change detection to every memory, as [`crate::Rls::enable_change_detection`]: on
    /// an alarm the memory is re-opened and the estimate starts on its new solution.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] naming a field of `config` out of range.
    pub fn enable_change_detection(&mut self, config: ChangeConfig) -> Result<(), EstimatorError> {
        let config = config.validated()?;
        let equations = self.fits.iter().flatten().count();
        for f in self.fits.iter_mut().flatten() {
            f.memory.enable_change_test(config, equations);
        }
        Ok(())
    }

    /// Distance of coefficient `c`'s estimate from its memory's least-squares solution,
    /// `‖θ̂ − θ̄‖_A / σ̂` in standard errors (0 on the sliding surface); `None` before `σ̂` is
    /// defined.
    pub fn distance_to_surface(&self, c: Coefficient) -> Option<f64> {
        let f = self.fits[c.index()].as_ref()?;
        let s2 = f.memory.residual_variance()?;
        let n = f.memory.regression().n;
        let mut d2 = 0.0;
        for i in 0..n {
            for j in 0..n {
                d2 += f.offset[i] * f.info[i][j] * f.offset[j];
            }
        }
        (s2 > 0.0).then(|| libm::sqrt(d2.max(0.0) / s2))
    }
}

impl Estimator for FiniteTimeSmpe {
    fn method(&self) -> &'static str {
        "smpe-finite-time"
    }

    fn structure(&self) -> &ModelStructure {
        &self.structure
    }

    fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        if let Some(t0) = self.last_t_s {
            let dt = s.t_s - t0;
            if dt.is_nan() || dt <= 0.0 {
                return Err(EstimatorError::Numerical {
                    what: "sample time not after the previous sample's",
                    t_s: s.t_s,
                });
            }
        }
        let (lambda, init) = (self.lambda, self.init_samples);
        let what = "the sliding-mode memory estimator has diverged";
        update_fits(&mut self.fits, &mut self.est, &mut self.events, lambda, init, s, what)?;
        self.last_t_s = Some(s.t_s);
        Ok(&self.est)
    }

    fn estimates(&self) -> &Estimates {
        &self.est
    }

    fn events(&self) -> &EventLog {
        &self.events
    }

    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        covariance(&self.structure, &self.fits, i, j)
    }
}

#[cfg(test)]
mod tests;
