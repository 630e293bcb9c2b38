//! Sliding-mode parameter estimation (SMPE), thesis §3.2–§3.4 (`spec/thesis-method.md` §1).
//!
//! Two estimators share one model trait and one sample type:
//! - [`PublishedSmpe`]: the thesis's estimator equation (3.20)–(3.22) with the Lyapunov gain
//!   (3.36)/(3.72), in both readings of its implicit equation ([`Reading`]).
//! - [`CorrectedSmpe`]: a sliding-surface estimator with a Lyapunov-derived composite
//!   adaptation law and bound projection that identifies several parameters from one shared
//!   surface (see `docs/smpe-corrected.md`).
//!
//! The estimated model is a [`ParametricModel`]: it gives `ż` for states `z`, input `u`, time
//! `t` and parameters `θ`. The caller integrates the estimated model (thesis Figure 3.2: the
//! estimated model is its own block) and passes its state in [`SmpeSample::z`] together with
//! the measured states `z_m` and their derivatives `ż_m`.
//!
//! Instantiating for a new system (e.g. the F-16) needs only
//! 1. a type implementing [`ParametricModel<N, P>`] (13 states and 2–4 increments for the
//!    aircraft; [`ParametricModel::sensitivity`] has a finite-difference default),
//! 2. a [`SlidingSurface<N>`] saying which states slide (e.g. `p, q, r`:
//!    [`SlidingSurface::first_order`] with those three indices), and
//! 3. one [`ParamSpec`] per parameter (name, bounds, λ, initial guess).
//!
//! [`PublishedSmpe`]: crate::smpe::PublishedSmpe
//! [`Reading`]: crate::smpe::Reading
//! [`CorrectedSmpe`]: crate::smpe::CorrectedSmpe
//! [`ParametricModel`]: crate::smpe::ParametricModel
//! [`ParametricModel<N, P>`]: crate::smpe::ParametricModel
//! [`ParametricModel::sensitivity`]: crate::smpe::ParametricModel::sensitivity
//! [`SmpeSample::z`]: crate::smpe::SmpeSample::z
//! [`SlidingSurface<N>`]: crate::smpe::SlidingSurface
//! [`SlidingSurface::first_order`]: crate::smpe::SlidingSurface::first_order
//! [`ParamSpec`]: crate::smpe::ParamSpec

use crate::EstimatorError;
use nalgebra::{SMatrix, SVector};

mod corrected;
mod published;

pub use corrected::{CorrectedConfig, CorrectedSmpe, CorrectedStep};
pub use published::{GainForm, PublishedSmpe, PublishedStep, Reading, SmpeConfig, SolveStats};

/// An estimation model `ż = f(t, z, u; θ)` with `N` states and `P` unknown parameters.
///
/// One job: give the state derivative for a parameter vector. Units are the model's own
/// (radians and seconds for aircraft). Implementations must not allocate.
pub trait ParametricModel<const N: usize, const P: usize> {
    /// The input held over a sample, e.g. a scalar command or a control-surface struct.
    type Input;

    /// The state derivative `ż` at time `t_s` (s), state `z`, input `u`, parameters `theta`.
    ///
    /// # Errors
    /// [`EstimatorError`] when the state or input is outside the model's domain.
    fn derivatives(
        &self,
        t_s: f64,
        z: &SVector<f64, N>,
        u: &Self::Input,
        theta: &SVector<f64, P>,
    ) -> Result<SVector<f64, N>, EstimatorError>;

    /// Parameter sensitivity `∂ż/∂θ` (`N × P`) at the same arguments. The default is a central
    /// difference with step `1e-6·max(1, |θ_j|)`; exact to rounding for models affine in `θ`
    /// (all the thesis's models, including the F-16 increments of (3.100)). Override it when an
    /// analytic form is at hand.
    ///
    /// # Errors
    /// As [`ParametricModel::derivatives`].
    fn sensitivity(
        &self,
        t_s: f64,
        z: &SVector<f64, N>,
        u: &Self::Input,
        theta: &SVector<f64, P>,
    ) -> Result<SMatrix<f64, N, P>, EstimatorError> {
        let mut s = SMatrix::<f64, N, P>::zeros();
        for j in 0..P {
            let h = 1e-6 * libm::fabs(theta[j]).max(1.0);
            let mut tp = *theta;
            let mut tm = *theta;
            tp[j] += h;
            tm[j] -= h;
            let col =
                (self.derivatives(t_s, z, u, &tp)? - self.derivatives(t_s, z, u, &tm)?) / (2.0 * h);
            s.set_column(j, &col);
        }
        Ok(s)
    }
}

/// One sample for the SMPE estimators: the estimated model's state and the measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmpeSample<const N: usize, U> {
    /// Sample time, s.
    pub t_s: f64,
    /// State of the estimated model (integrated by the caller with the current estimate).
    pub z: SVector<f64, N>,
    /// Measured states of the reference system.
    pub z_m: SVector<f64, N>,
    /// Measured state derivatives of the reference system (thesis: `ż_m`, `ẍ_m`).
    pub zdot_m: SVector<f64, N>,
    /// Input applied to both systems.
    pub u: U,
}

impl<const N: usize, U> SmpeSample<N, U> {
    /// Checks every numeric field is finite.
    ///
    /// # Errors
    /// [`EstimatorError::NonFiniteInput`] naming the first non-finite field.
    pub fn check_finite(&self) -> Result<(), EstimatorError> {
        let bad = |field: &'static str, value: f64| EstimatorError::NonFiniteInput {
            field,
            value,
            t_s: self.t_s,
        };
        if !self.t_s.is_finite() {
            return Err(bad("t_s", self.t_s));
        }
        for (field, v) in [("z", &self.z), ("z_m", &self.z_m), ("zdot_m", &self.zdot_m)] {
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return Err(bad(field, *x));
            }
        }
        Ok(())
    }
}

/// The sliding surface as weights on the model states (thesis (3.19), (3.39), (3.57)).
///
/// With `E_i = ½(z_i² − z_m,i²)` the surface derivative used by the estimator equation is
///
/// ```text
/// ṡ_j = Σ_i rate_i Ė_i + λ_j [ Σ_i lambda_energy_i Ė_i + Σ_i lambda_integral_i E_i ]
/// B   = Σ_i bracket_i Ė_i            (the bracket multiplying K, (3.20)/(3.58))
/// ```
///
/// where `Ė_i = z_i ż_i(θ̂) − z_m,i ż_m,i`. Weights are usually 0 or 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingSurface<const N: usize> {
    /// Sliding states whose energy error is the surface (`½(ż…)` terms of (3.19)/(3.57)).
    pub rate: [f64; N],
    /// States whose energy error is multiplied by λ directly (second-order surfaces (3.57)).
    pub lambda_energy: [f64; N],
    /// States whose energy error is integrated and multiplied by λ (first-order (3.19)).
    pub lambda_integral: [f64; N],
    /// States whose energy-error rate multiplies K in the estimator denominator.
    pub bracket: [f64; N],
}

impl<const N: usize> SlidingSurface<N> {
    /// First-order form (3.19)/(3.39): `s = Σ E_i + λ ∫ Σ E_i dt` over the given state
    /// indices, K bracket `Σ Ė_i`. Used for `x` (2.1), `x, y` (2.2) and `p, q, r` (aircraft).
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when an index is `≥ N`.
    pub fn first_order(states: &[usize]) -> Result<Self, EstimatorError> {
        let mut w = [0.0; N];
        for &i in states {
            *w.get_mut(i).ok_or(EstimatorError::InvalidConfig {
                field: "sliding state index",
                value: i as f64,
                reason: "must be < number of model states",
            })? = 1.0;
        }
        Ok(Self { rate: w, lambda_energy: [0.0; N], lambda_integral: w, bracket: w })
    }

    /// Second-order form (3.57): `s_j = ½(ẋ² − ẋ_m²) + λ_j ½(x² − x_m²)` with `x` at index
    /// `position` and `ẋ` at `velocity`; K bracket `x ẋ − x_m ẋ_m` ((3.58), spec §2).
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when an index is `≥ N`.
    pub fn second_order(position: usize, velocity: usize) -> Result<Self, EstimatorError> {
        let bad = |i: usize| EstimatorError::InvalidConfig {
            field: "sliding state index",
            value: i as f64,
            reason: "must be < number of model states",
        };
        if position >= N {
            return Err(bad(position));
        }
        if velocity >= N {
            return Err(bad(velocity));
        }
        let mut rate = [0.0; N];
        let mut pos = [0.0; N];
        rate[velocity] = 1.0;
        pos[position] = 1.0;
        Ok(Self { rate, lambda_energy: pos, lambda_integral: [0.0; N], bracket: pos })
    }

    fn validate(&self) -> Result<(), EstimatorError> {
        for (field, w) in [
            ("surface.rate", &self.rate),
            ("surface.lambda_energy", &self.lambda_energy),
            ("surface.lambda_integral", &self.lambda_integral),
            ("surface.bracket", &self.bracket),
        ] {
            if let Some(x) = w.iter().find(|x| !x.is_finite()) {
                return Err(EstimatorError::InvalidConfig {
                    field,
                    value: *x,
                    reason: "weights must be finite",
                });
            }
        }
        if self.rate.iter().all(|&x| x == 0.0) {
            return Err(EstimatorError::InvalidConfig {
                field: "surface.rate",
                value: 0.0,
                reason: "at least one sliding state is needed",
            });
        }
        Ok(())
    }
}

/// One unknown parameter: name, bounds (3.29), surface gain λ and initial guess.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Name, also the CSV header (e.g. `"a1"`, `"dCm_alpha"`).
    pub name: &'static str,
    /// Lower bound θ_low (3.29), parameter units.
    pub lower: f64,
    /// Upper bound θ_upp (3.29), parameter units.
    pub upper: f64,
    /// Surface gain λ_j > 0, 1/s ((3.19), (3.57)).
    pub lambda: f64,
    /// Initial estimate, inside the bounds. [`ParamSpec::geometric_mean`] gives the thesis's
    /// prior (3.30).
    pub initial: f64,
}

impl ParamSpec {
    /// The thesis's prior (3.30): the geometric mean `±√(θ_low θ_upp)` of same-signed bounds,
    /// with their sign; `None` when the bounds straddle zero.
    pub fn geometric_mean(lower: f64, upper: f64) -> Option<f64> {
        let prod = lower * upper;
        (prod > 0.0).then(|| libm::sqrt(prod) * if lower < 0.0 { -1.0 } else { 1.0 })
    }

    /// The gain margin (3.32) `α = √(max|θ| / min|θ|) ≥ 1` over the bounds, written with
    /// magnitudes so that it also holds for negative parameters (the thesis's
    /// `√(θ_upp/θ_low)` is below 1 for negative bounds). `None` when the bounds straddle 0.
    pub fn gain_margin(&self) -> Option<f64> {
        let (a, b) = (libm::fabs(self.lower), libm::fabs(self.upper));
        (self.lower * self.upper > 0.0).then(|| libm::sqrt(a.max(b) / a.min(b)))
    }

    pub(crate) fn validate(&self, need_margin: bool) -> Result<(), EstimatorError> {
        let bad =
            |field, value, reason| Err(EstimatorError::InvalidConfig { field, value, reason });
        for (field, v) in [
            ("lower", self.lower),
            ("upper", self.upper),
            ("lambda", self.lambda),
            ("initial", self.initial),
        ] {
            if !v.is_finite() {
                return bad(field, v, "must be finite");
            }
        }
        if self.lower >= self.upper {
            return bad("lower", self.lower, "must be below `upper`");
        }
        if need_margin && self.lower * self.upper <= 0.0 {
            return bad(
                "lower",
                self.lower,
                "bounds must have the same sign for the gain margin (3.32)",
            );
        }
        if self.lambda <= 0.0 {
            return bad("lambda", self.lambda, "must be > 0");
        }
        if self.initial < self.lower || self.initial > self.upper {
            return bad("initial", self.initial, "must lie within [lower, upper]");
        }
        Ok(())
    }
}

/// Energy-error rates `Ė_i = z_i ż_i − z_m,i ż_m,i` and errors `E_i = ½(z_i² − z_m,i²)`.
/// Time since the previous sample, s: 0 for the first sample (`last_t_s = None`).
///
/// # Errors
/// [`EstimatorError::Numerical`] when `t_s` is earlier than the previous sample's time.
pub(crate) fn sample_interval_s(last_t_s: Option<f64>, t_s: f64) -> Result<f64, EstimatorError> {
    match last_t_s {
        None => Ok(0.0),
        Some(t0) if t_s >= t0 => Ok(t_s - t0),
        Some(_) => Err(EstimatorError::Numerical { what: "sample time decreased", t_s }),
    }
}

pub(crate) fn energy_terms<const N: usize>(
    z: &SVector<f64, N>,
    zdot: &SVector<f64, N>,
    z_m: &SVector<f64, N>,
    zdot_m: &SVector<f64, N>,
) -> (SVector<f64, N>, SVector<f64, N>) {
    let mut e_dot = SVector::<f64, N>::zeros();
    let mut e = SVector::<f64, N>::zeros();
    for i in 0..N {
        e_dot[i] = z[i] * zdot[i] - z_m[i] * zdot_m[i];
        e[i] = 0.5 * (z[i] * z[i] - z_m[i] * z_m[i]);
    }
    (e_dot, e)
}

pub(crate) fn weighted<const N: usize>(w: &[f64; N], v: &SVector<f64, N>) -> f64 {
    w.iter().zip(v.iter()).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests;
