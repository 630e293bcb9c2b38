//! A corrected sliding-mode parameter estimator (derivation and
//! convergence condition in `docs/smpe-corrected.md`).
//!
//! It keeps the thesis's ingredients — a sliding surface between measured and model states, a
//! Lyapunov argument, parameter bounds — but makes θ̂ a *state* updated by a Lyapunov-derived
//! law instead of the instantaneous solution of one scalar equation, so that information from
//! different instants accumulates and several parameters sharing one surface are identifiable.

use super::{ParamSpec, ParametricModel, SmpeSample, sample_interval_s};
use crate::{Estimate, EstimatorError, ParametricEstimator};
use nalgebra::{SMatrix, SVector};

/// Configuration of [`CorrectedSmpe`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectedConfig<const N: usize, const P: usize> {
    /// Parameters: name, bounds (projection set) and initial guess. `ParamSpec::lambda` is not
    /// used here; the surface gain is [`CorrectedConfig::lambda_per_s`].
    pub params: [ParamSpec; P],
    /// Weights of the sliding states (1 = slides, 0 = not used), e.g. `ẋ` for (2.3).
    pub sliding: [f64; N],
    /// Surface gain λ > 0, 1/s: `ṡ = −λ s + (ż(z_m, θ̂) − ż_m)`.
    pub lambda_per_s: f64,
    /// Information weight κ > 0, 1/s: trust in the measured derivative (prediction error)
    /// relative to the prior spread of the bounds. Larger is faster and noisier.
    pub information_per_s: f64,
    /// Weight γ ≥ 0 of the surface (tracking) term in the adaptation law.
    pub tracking_weight: f64,
    /// Forgetting rate ρ ≥ 0, 1/s (0: none). ρ > 0 lets the estimate follow a parameter change.
    pub forgetting_per_s: f64,
}

/// The corrected SMPE.
///
/// With `e = W(ż(z_m, u; θ̂) − ż_m)` the derivative-prediction error on the sliding states
/// (`W` = diag of [`CorrectedConfig::sliding`]), `Φ = W ∂ż/∂θ` at the measured state, and
/// `s = ẑ − z_m` the sliding surface of the series-parallel estimated model
/// `dẑ/dt = ż(z_m, u; θ̂) − λ s`:
///
/// ```text
/// ṡ   = −λ s + Φ θ̃                         (θ̃ = θ̂ − θ; exact for models affine in θ)
/// dθ̂/dt = −Γ Φᵀ (κ e + γ s),   dΓ⁻¹/dt = κ ΦᵀΦ − ρ Γ⁻¹,   θ̂ projected onto the bounds
/// V   = (γ/2) sᵀs + ½ θ̃ᵀ Γ⁻¹ θ̃,  V̇ = −γλ sᵀs − ½ κ |Φθ̃|² − ½ ρ θ̃ᵀΓ⁻¹θ̃ ≤ 0
/// ```
///
/// Discretisation per sample (`dt` = time since the previous sample): the surface is advanced
/// exactly for a held `e`, the information update is the sequential (row by row) recursive
/// least-squares form with weight `κ dt`, which is unconditionally stable for any κ, and the
/// surface term is an explicit Euler step. `Γ(0) = diag((θ_upp − θ_low)²)`; forgetting never
/// lets `trace Γ` exceed its initial value. Convergence of θ̂ to θ needs persistent excitation:
/// `∫ ΦᵀΦ dt` over a window must be positive definite.
#[derive(Debug, Clone)]
pub struct CorrectedSmpe<M, const N: usize, const P: usize> {
    model: M,
    cfg: CorrectedConfig<N, P>,
    gamma: SMatrix<f64, P, P>,
    gamma_trace0: f64,
    surface: SVector<f64, N>,
    last_t_s: Option<f64>,
    estimate: Estimate<P>,
    /// Parameters `0..active` are adapted; those beyond have zero sensitivity
    /// ([`CorrectedSmpe::with_active`]) and are skipped.
    active: usize,
}

impl<M, const N: usize, const P: usize> CorrectedSmpe<M, N, P>
where
    M: ParametricModel<N, P>,
{
    /// A new estimator at each parameter's initial guess.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when a parameter's bounds are not finite and ordered
    /// or its initial guess is outside them, λ or κ is not finite and positive, γ or ρ is
    /// negative or not finite, or no state slides.
    pub fn new(model: M, cfg: CorrectedConfig<N, P>) -> Result<Self, EstimatorError> {
        let bad =
            |field, value, reason| Err(EstimatorError::InvalidConfig { field, value, reason });
        for p in &cfg.params {
            p.validate(false)?;
        }
        if !(cfg.lambda_per_s.is_finite() && cfg.lambda_per_s > 0.0) {
            return bad("lambda_per_s", cfg.lambda_per_s, "must be finite and > 0");
        }
        if !(cfg.information_per_s.is_finite() && cfg.information_per_s > 0.0) {
            return bad("information_per_s", cfg.information_per_s, "must be finite and > 0");
        }
        if !(cfg.tracking_weight.is_finite() && cfg.tracking_weight >= 0.0) {
            return bad("tracking_weight", cfg.tracking_weight, "must be finite and ≥ 0");
        }
        if !(cfg.forgetting_per_s.is_finite() && cfg.forgetting_per_s >= 0.0) {
            return bad("forgetting_per_s", cfg.forgetting_per_s, "must be finite and ≥ 0");
        }
        if let Some(x) = cfg.sliding.iter().find(|x| !x.is_finite() || **x < 0.0) {
            return bad("sliding", *x, "weights must be finite and ≥ 0");
        }
        if cfg.sliding.iter().all(|&x| x == 0.0) {
            return bad("sliding", 0.0, "at least one sliding state is needed");
        }
        let gamma = SMatrix::<f64, P, P>::from_fn(|i, j| {
            if i == j {
                let r = cfg.params[i].upper - cfg.params[i].lower;
                r * r
            } else {
                0.0
            }
        });
        let theta = SVector::<f64, P>::from_fn(|j, _| cfg.params[j].initial);
        Ok(Self {
            model,
            cfg,
            gamma_trace0: gamma.trace(),
            gamma,
            surface: SVector::zeros(),
            last_t_s: None,
            estimate: Estimate::new(0.0, theta),
            active: P,
        })
    }

    /// Adapts only the leading `n` parameters (`n ≤ P`): the model promises that the
    /// sensitivity to the others is zero at every sample (unused slots of a fixed-size
    /// parameter vector), so they never move and their rows and columns of Γ stay diagonal.
    /// The update then costs `O(n²)` instead of `O(P²)` with the same numbers for the leading
    /// `n`: every skipped term is an exact zero, and the sums keep nalgebra's order
    /// (`dot_leading`). The trailing gains are not forgotten (they are never used).
    pub fn with_active(mut self, n: usize) -> Self {
        self.active = n.min(P);
        self
    }

    /// How many leading parameters are adapted ([`Self::with_active`]; `P` by default).
    pub fn active(&self) -> usize {
        self.active
    }

    /// The configuration.
    pub fn config(&self) -> &CorrectedConfig<N, P> {
        &self.cfg
    }

    /// The current surface `s = ẑ − z_m` (zero on states that do not slide).
    pub fn surface(&self) -> &SVector<f64, N> {
        &self.surface
    }

    /// The current adaptation gain Γ (`P × P`, parameter units squared). Not a covariance.
    pub fn gain(&self) -> &SMatrix<f64, P, P> {
        &self.gamma
    }

    /// A new manoeuvre starts with the next sample (a gap in the record): the surface is reset
    /// to zero (the estimated model restarts on the measured state) and the next sample is
    /// treated as a first one (no time step); θ̂ and Γ are kept.
    pub fn new_manoeuvre(&mut self) {
        self.surface = SVector::zeros();
        self.last_t_s = None;
    }
}

/// `xᵀy` over the leading `n` entries, bit-identical to nalgebra's `x.dot(y)` when the rest are
/// zero: nalgebra sums whole blocks of 8 into 8 accumulators, adds them pairwise (0 + 4, 1 + 5,
/// 2 + 6, 3 + 7), then the tail in order; adding the exact zeros beyond `n` changes nothing.
/// Short vectors (`P ≤ 4`, nalgebra's special cases) and `n = P` go to nalgebra itself.
fn dot_leading<const P: usize>(x: &SVector<f64, P>, y: &SVector<f64, P>, n: usize) -> f64 {
    if P <= 4 || n >= P {
        return x.dot(y);
    }
    let blocks = P / 8 * 8;
    let mut acc = [0.0; 8];
    for i in 0..n.min(blocks) {
        acc[i % 8] += x[i] * y[i];
    }
    let mut res = 0.0;
    for j in 0..4 {
        res += acc[j] + acc[j + 4];
    }
    for i in blocks..n {
        res += x[i] * y[i];
    }
    res
}

/// `Γ x` over the leading `n × n` block (zero beyond), in nalgebra's order (a column sweep:
/// `y = Γ₀ x₀`, then `y += Γⱼ xⱼ`), so bit-identical to `Γ * x` when `x` is zero beyond `n`
/// and Γ is block-diagonal between the leading `n` and the rest. Γ is given entry by entry,
/// `g(a, b)`, because the Γ of a proposed step exists only as Γ before and its change.
fn mul_leading<const P: usize>(
    g: impl Fn(usize, usize) -> f64,
    x: &SVector<f64, P>,
    n: usize,
) -> SVector<f64, P> {
    let mut y = SVector::<f64, P>::zeros();
    if n == 0 {
        return y;
    }
    for a in 0..n {
        y[a] = g(a, 0) * x[0];
    }
    for b in 1..n {
        for a in 0..n {
            y[a] += g(a, b) * x[b];
        }
    }
    y
}

/// Γ's change over one update, kept as what produces it rather than as a new Γ, so that a
/// proposed step is a few vectors instead of a `P × P` copy. Each leading entry is scaled by
/// the forgetting factor and by the trace cap, then loses the rank-one term `k_i[a] (Γφ_i)[b]`
/// of each sliding state in order, then the block is symmetrised: the operations, in the
/// order, of the in-place update, so the entries are bit-identical to it.
#[derive(Debug, Clone, Copy)]
struct GainChange<const N: usize, const P: usize> {
    forget: Option<f64>,
    cap: Option<f64>,
    used: [bool; N],
    k: [SVector<f64, P>; N],
    gphi: [SVector<f64, P>; N],
}

impl<const N: usize, const P: usize> GainChange<N, P> {
    fn none() -> Self {
        Self {
            forget: None,
            cap: None,
            used: [false; N],
            k: [SVector::zeros(); N],
            gphi: [SVector::zeros(); N],
        }
    }

    /// Entry `(a, b)` after the scaling and the first `upto` sliding states' updates, from
    /// `g` = Γ before the step.
    fn entry(&self, g: &SMatrix<f64, P, P>, a: usize, b: usize, upto: usize) -> f64 {
        let mut v = g[(a, b)];
        if let Some(f) = self.forget {
            v *= f;
        }
        if let Some(f) = self.cap {
            v *= f;
        }
        for i in 0..upto {
            if self.used[i] {
                v -= self.k[i][a] * self.gphi[i][b];
            }
        }
        v
    }

    /// Entry `(a, b)` of the new Γ: `(Γ + Γᵀ)/2` of the updated block (rounding keeps Γ
    /// symmetric).
    fn symmetric(&self, g: &SMatrix<f64, P, P>, a: usize, b: usize) -> f64 {
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        (self.entry(g, lo, hi, N) + self.entry(g, hi, lo, N)) * 0.5
    }
}

/// One update of [`CorrectedSmpe`] computed but not applied ([`CorrectedSmpe::propose`]):
/// the new estimate and surface, and the change of the adaptation gain.
#[derive(Debug, Clone, Copy)]
pub struct CorrectedStep<const N: usize, const P: usize> {
    t_s: f64,
    theta: SVector<f64, P>,
    surface: SVector<f64, N>,
    gain: GainChange<N, P>,
}

impl<const N: usize, const P: usize> CorrectedStep<N, P> {
    /// The estimate θ̂ once the step is committed.
    pub fn theta(&self) -> &SVector<f64, P> {
        &self.theta
    }
}

impl<M, const N: usize, const P: usize> CorrectedSmpe<M, N, P>
where
    M: ParametricModel<N, P>,
{
    /// One update computed from the current state without changing it, so that a caller
    /// updating several estimators can apply all of them or none
    /// ([`ParametricEstimator::update`] is this and [`CorrectedSmpe::commit`]).
    ///
    /// # Errors
    /// As [`ParametricEstimator::update`].
    pub fn propose(
        &self,
        s: &SmpeSample<N, M::Input>,
    ) -> Result<CorrectedStep<N, P>, EstimatorError> {
        s.check_finite()?;
        let dt = sample_interval_s(self.last_t_s, s.t_s)?;
        let theta0 = self.estimate.theta;
        let zdot = self.model.derivatives(s.t_s, &s.z_m, &s.u, &theta0)?;
        let sens = self.model.sensitivity(s.t_s, &s.z_m, &s.u, &theta0)?;
        let (cfg, n, g0) = (&self.cfg, self.active, &self.gamma);
        let lam = cfg.lambda_per_s;
        // Surface, exact for a held prediction error over dt.
        let decay = libm::exp(-lam * dt);
        let gain_in = if lam * dt > 1e-12 { (1.0 - decay) / lam } else { dt };
        let mut surface = self.surface;
        let mut change = GainChange::<N, P>::none();
        if cfg.forgetting_per_s > 0.0 && dt > 0.0 {
            let f = libm::exp(cfg.forgetting_per_s * dt);
            change.forget = Some(f);
            let tr: f64 = (0..n).map(|a| g0[(a, a)] * f).sum();
            if tr > self.gamma_trace0 {
                change.cap = Some(self.gamma_trace0 / tr);
            }
        }
        let mut theta = theta0;
        for i in 0..N {
            let w = cfg.sliding[i];
            if w == 0.0 {
                continue;
            }
            let e0 = zdot[i] - s.zdot_m[i];
            surface[i] = decay * surface[i] + gain_in * e0;
            let weight = cfg.information_per_s * dt * w;
            if weight <= 0.0 {
                continue;
            }
            let phi = sens.row(i).transpose();
            // Prediction error at the current (already partly updated) estimate.
            let e = e0 + dot_leading(&phi, &(theta - theta0), n);
            let gphi = mul_leading(|a, b| change.entry(g0, a, b, i), &phi, n);
            let denom = 1.0 / weight + dot_leading(&phi, &gphi, n);
            if !(denom.is_finite() && denom > 0.0) {
                continue;
            }
            let k = gphi / denom;
            theta -= k * e;
            (change.used[i], change.k[i], change.gphi[i]) = (true, k, gphi);
        }
        // Surface (tracking) term of the composite law, explicit Euler.
        if cfg.tracking_weight > 0.0 && dt > 0.0 {
            let mut phis = SVector::<f64, P>::zeros();
            for i in 0..N {
                if cfg.sliding[i] != 0.0 {
                    phis += sens.row(i).transpose() * (cfg.sliding[i] * surface[i]);
                }
            }
            let gamma = |a, b| change.symmetric(g0, a, b);
            theta -= mul_leading(gamma, &phis, n) * (cfg.tracking_weight * dt);
        }
        for j in 0..P {
            theta[j] = theta[j].clamp(cfg.params[j].lower, cfg.params[j].upper);
        }
        let gamma_finite = (0..n).all(|b| (0..=b).all(|a| change.symmetric(g0, a, b).is_finite()));
        if !(gamma_finite && theta.iter().chain(surface.iter()).all(|x| x.is_finite())) {
            return Err(EstimatorError::Numerical { what: "corrected SMPE update", t_s: s.t_s });
        }
        Ok(CorrectedStep { t_s: s.t_s, theta, surface, gain: change })
    }

    /// Applies a step proposed from the current state ([`CorrectedSmpe::propose`]; a step
    /// proposed before another update changed the state must be dropped, not committed). Γ
    /// is updated in place: each pair `(a, b)`, `(b, a)` is read before it is written, and
    /// by no other pair.
    pub fn commit(&mut self, step: CorrectedStep<N, P>) {
        for b in 0..self.active {
            for a in 0..=b {
                let v = step.gain.symmetric(&self.gamma, a, b);
                self.gamma[(a, b)] = v;
                self.gamma[(b, a)] = v;
            }
        }
        self.surface = step.surface;
        self.last_t_s = Some(step.t_s);
        self.estimate.t_s = step.t_s;
        self.estimate.theta = step.theta;
    }
}

impl<M, const N: usize, const P: usize> ParametricEstimator<P> for CorrectedSmpe<M, N, P>
where
    M: ParametricModel<N, P>,
{
    type Sample = SmpeSample<N, M::Input>;

    fn param_names(&self) -> [&'static str; P] {
        self.cfg.params.map(|p| p.name)
    }

    fn update(&mut self, s: &Self::Sample) -> Result<&Estimate<P>, EstimatorError> {
        let step = self.propose(s)?;
        self.commit(step);
        Ok(&self.estimate)
    }

    fn estimate(&self) -> &Estimate<P> {
        &self.estimate
    }
}
