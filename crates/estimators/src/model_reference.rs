//! Model-reference estimators of the aircraft's aerodynamic derivatives over any
//! [`ModelStructure`]: the thesis's sliding-mode estimator as published (`smpe`), the corrected
//! sliding-mode estimator (`smpe-corrected`) and the model-reference gradient law (`gradient`,
//! thesis (3.3)). Each implements [`Estimator`], is fed with [`AirDataSample`]s alone, and
//! carries and integrates its own estimated model state. `no_std`, no allocation per update.
//!
//! # The estimated model
//!
//! Every modelled coefficient `C` drives one *sliding state* `z` through a rigid-body rate
//! equation ([`rigid_body`], thesis §3.4: `Cl → p`, `Cm → q`, `Cn → r`, `CL → α`, `CD → V`,
//! `CY → β`, `CX → u`, `CZ → w`):
//!
//! ```text
//! ż = a(sample) + k(sample) · C,        k = ∂ż/∂C
//! ```
//!
//! where `a` collects everything but this coefficient (gravity, kinematics, thrust, inertial
//! coupling, the other coefficients) and is taken from the measured sample. The measured rate
//! is `ż_m = a + k C_m` (`C_m` = [`AirDataSample::measured_coefficients`]). The estimated model
//! replaces `C_m` by the structure's linear model with the current estimates `θ̂` and the
//! **measured** regressors `φ` (series-parallel form, Ioannou & Sun, *Robust Adaptive Control*,
//! 1996, §4.2.2, as `aeroident`'s pitch-only `replay/smpe.rs` does):
//!
//! ```text
//! dz_est/dt = ż_m + k (θ̂ᵀφ − C_m) − λ (z_est − z_m)
//! ```
//!
//! The `−λ (z_est − z_m)` term is the series-parallel model's stable filter: without it
//! `z_est − z_m` integrates every constant model error for ever (a drift, not information).
//! It is also exactly the estimated model of the corrected estimator (`docs/smpe-corrected.md`),
//! whose surface is `s = z_est − z_m`. Per sample interval `[t₋, t]` the estimator integrates
//! this equation exactly for the interval's mean input (trapezoid of the two samples' `ż_m`,
//! `k`, `φ`, `C_m`, `z_m`, with the estimate `θ̂` held at its value before the update):
//!
//! ```text
//! z_est(t) = e^{−λΔt} z_est(t₋) + (1 − e^{−λΔt})/λ · (ḡ + λ z̄_m),   g = ż_m + k (θ̂ᵀφ − C_m)
//! ```
//!
//! `Δt` comes from the timestamps; a sample with `Δt ≤ 0` is refused and nothing changes. The
//! first sample (and the first after [`Estimator::new_manoeuvre`]) initialises `z_est = z_m`.
//! Then the sample, with `z = z_est`, `z_m`, `ż_m`, goes to the coefficient's adaptation law
//! through [`CoefficientRate`], a [`ParametricModel`] whose derivative is the right-hand side
//! above (so `ż_est − ż_m = k (θ̂ᵀφ − C_m) − λ (z_est − z_m)`) and whose sensitivity is `k φ`.
//!
//! # The adaptation laws (the existing engines, not copies)
//!
//! - [`CorrectedLaw`] (`smpe-corrected`): [`CorrectedSmpe`](crate::smpe::CorrectedSmpe), the
//!   composite-Lyapunov law with bound projection.
//! - [`PublishedLaw`] (`smpe`): [`PublishedSmpe`](crate::smpe::PublishedSmpe), thesis
//!   (3.20)–(3.22) with the shared K (3.72)/(3.128), implicit reading.
//! - [`GradientLaw`] (`gradient`): [`ModelReferenceGradient`](crate::mrac::ModelReferenceGradient),
//!   thesis (3.3).
//!
//! Each coefficient has its own engine with `N = 1` sliding state. The corrected and gradient
//! engines have a fixed capacity of `P = N_TERMS` parameters, the coefficient's terms first and
//! the unused ones with a zero regressor: they behave exactly as with `P = n` (an unused
//! parameter has a zero row in the corrected law's `Γ` and a zero regressor, and a negligible
//! gain in the gradient law; checked by test). The published engine does **not**: its implicit
//! equations `F_j = N(θ̂) − D(θ̂) θ̂_j` for an unused `j` have a root only if `N/D` is inside
//! that parameter's bounds, and otherwise the least-residual compromise moves the used ones;
//! it is instantiated with exactly the number of estimated terms (`P = 1 … 14`).
//!
//! # Bounds and initial values (from [`Priors`], never from a truth)
//!
//! With prior value `v` and standard deviation `σ`, and `k_σ` =
//! [`ModelReferenceConfig::prior_sigmas`] (default 3, the 99.7 % interval of a Gaussian prior):
//! - corrected and gradient: bounds `[v − k_σ σ, v + k_σ σ]`, initial value `v`;
//! - published: the thesis needs bounds of one sign (gain margin (3.29)–(3.32)) with the prior
//!   their geometric mean (3.30): `[v/ρ, v ρ]`, `ρ = 1 + k_σ σ/|v|` (same far end `|v| + k_σ σ`
//!   as the additive interval). A parameter whose prior value is 0 has no known sign: the
//!   published form cannot estimate it; it is held at 0 and never identified.
//!
//! # Identified, diverged
//!
//! A coefficient's parameters are identified once its regressors have been persistently
//! exciting: the accumulated information `Σ φφᵀ` passes the same test as recursive least
//! squares' exact initialisation (the scaled-pivot test of [`crate::rls`] with
//! [`INIT_MIN_SCALED_PIVOT`], at least `n` samples). Before
//! that `value(i)` is `None`. These methods give no standard errors: `sigma` and
//! [`Estimator::covariance`] are `None`. A non-finite estimate or state, or an estimated state
//! further than [`SlidingState::runaway_bound`] from the measured one, is a divergence: the
//! update returns an error, the status becomes [`Status::Diverged`], no value is reported as
//! identified, and every later update is refused.

use crate::EstimatorError;
use crate::estimator::{Estimates, Estimator, Status, check_finite};
use crate::linalg::{Square, well_conditioned};
use crate::prior::{ParamPrior, Priors};
use crate::rls::INIT_MIN_SCALED_PIVOT;
use crate::sample::{AirDataSample, CoefficientValues};
use crate::smpe::{ParametricModel, SmpeSample};
use crate::vocabulary::{AlphaKnots, Coefficient, ModelStructure, N_TERMS, Term};
use nalgebra::{SMatrix, SVector};

mod laws;
pub mod rigid_body;

pub use laws::{
    ANGLE_REF_RAD, CorrectedLaw, CorrectedLawConfig, GradientLaw, GradientLawConfig, PublishedLaw,
    PublishedLawConfig, PublishedLawStep, RATE_REF_RAD_S, SPEED_REF_FRACTION,
};
pub use rigid_body::{SlidingState, StateRate, state_rate};

/// The sliding-mode parameter estimator as published, over any structure (`smpe`).
pub type PublishedSmpeEstimator = ModelReference<PublishedLaw>;
/// The corrected sliding-mode parameter estimator over any structure (`smpe-corrected`).
pub type CorrectedSmpeEstimator = ModelReference<CorrectedLaw>;
/// The model-reference gradient law (3.3) over any structure (`gradient`).
pub type GradientEstimator = ModelReference<GradientLaw>;

/// One coefficient's input to its adaptation law at one sample (the `u` of [`SmpeSample`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RateInput {
    /// The sliding state's measured value, rate and rate per unit coefficient.
    pub rate: StateRate,
    /// Measured coefficient `C_m`, –.
    pub c_m: f64,
    /// Regressors `φ` of the coefficient's terms, in structure order; zero beyond them.
    pub phi: [f64; N_TERMS],
    /// Filter gain `λ` of the estimated model, 1/s.
    pub lambda_per_s: f64,
}

impl RateInput {
    /// The estimated model's rate without the filter term, `ż_m + k (θᵀφ − C_m)`, for the
    /// first `theta.len()` terms.
    pub fn open_loop_rate(&self, theta: &[f64]) -> f64 {
        let c: f64 = theta.iter().zip(&self.phi).map(|(t, p)| t * p).sum();
        self.rate.zdot_m + self.rate.k * (c - self.c_m)
    }
}

/// The estimated model of one coefficient's sliding state as a [`ParametricModel`] with one
/// state and `P ≤ N_TERMS` parameters (module doc):
/// `ż(z; θ) = ż_m + k (Σ_{j<P} θ_j φ_j − C_m) − λ (z − z_m)`, sensitivity `k φ_j`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CoefficientRate;

impl<const P: usize> ParametricModel<1, P> for CoefficientRate {
    type Input = RateInput;

    fn derivatives(
        &self,
        _t_s: f64,
        z: &SVector<f64, 1>,
        u: &RateInput,
        theta: &SVector<f64, P>,
    ) -> Result<SVector<f64, 1>, EstimatorError> {
        let filter = u.lambda_per_s * (z[0] - u.rate.z_m);
        Ok(SVector::<f64, 1>::new(u.open_loop_rate(theta.as_slice()) - filter))
    }

    fn sensitivity(
        &self,
        _t_s: f64,
        _z: &SVector<f64, 1>,
        u: &RateInput,
        _theta: &SVector<f64, P>,
    ) -> Result<SMatrix<f64, 1, P>, EstimatorError> {
        Ok(SMatrix::<f64, 1, P>::from_fn(|_, j| u.rate.k * u.phi.get(j).copied().unwrap_or(0.0)))
    }
}

/// What a law is built from: one coefficient, its terms and their priors.
#[derive(Debug, Clone, Copy)]
pub struct CoefficientSpec<'a> {
    /// The coefficient.
    pub coefficient: Coefficient,
    /// Its terms, in structure order (`n = terms.len() ≤ N_TERMS`).
    pub terms: &'a [Term],
    /// Prior of each term's parameter.
    pub priors: &'a [ParamPrior],
    /// Bound half-width in prior standard deviations, `k_σ`.
    pub prior_sigmas: f64,
    /// Filter / surface gain `λ`, 1/s.
    pub lambda_per_s: f64,
}

/// One adaptation law acting on one coefficient's sliding state (module doc). Adding a law is
/// implementing this trait; [`ModelReference`] does the rest.
pub trait CoefficientLaw: Clone {
    /// The method's name ([`Estimator::method`]).
    const METHOD: &'static str;
    /// The law's own configuration.
    type Config: Copy;
    /// One update computed but not applied ([`CoefficientLaw::propose`]).
    type Step;

    /// The law for one coefficient.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] naming the offending value.
    fn new(spec: &CoefficientSpec<'_>, config: &Self::Config) -> Result<Self, EstimatorError>;

    /// Called once, with the first accepted sample, before its update (laws whose gains depend
    /// on the flight condition set them here).
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when a gain cannot be formed from the sample.
    fn start(&mut self, _first: &RateInput, _sample: &AirDataSample) -> Result<(), EstimatorError> {
        Ok(())
    }

    /// The current estimate of the coefficient's `j`-th term's parameter.
    fn theta(&self, j: usize) -> f64;

    /// Whether the `j`-th parameter is estimated at all (the published form holds parameters
    /// of unknown sign at their prior).
    fn is_estimated(&self, _j: usize) -> bool {
        true
    }

    /// One update with the estimated state `s.z`, measured `s.z_m`, `s.zdot_m`, input `s.u`,
    /// computed without changing the law: [`ModelReference`] commits it only once every
    /// coefficient's update has succeeded.
    ///
    /// # Errors
    /// As the engine's; the law is unchanged.
    fn propose(&self, s: &SmpeSample<1, RateInput>) -> Result<Self::Step, EstimatorError>;

    /// The `j`-th parameter's estimate once `step` is committed.
    fn theta_after(&self, step: &Self::Step, j: usize) -> f64;

    /// Applies a step proposed from the law's current state.
    fn commit(&mut self, step: Self::Step);

    /// A new manoeuvre starts with the next sample: no time step to it; keep θ̂.
    fn new_manoeuvre(&mut self);
}

/// Settings shared by the three estimators, plus the law's own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelReferenceConfig<C> {
    /// Bound half-width in prior standard deviations, `k_σ > 0` (default 3).
    pub prior_sigmas: f64,
    /// Filter / surface gain `λ > 0`, 1/s (default 1: slower than the short-period, roll and
    /// Dutch-roll modes of a conventional aircraft (1–5 rad/s), so over one mode period the
    /// estimated model integrates the prediction error nearly unfiltered, while a constant
    /// model error gives a bounded `|z_est − z_m| = |k ΔC|/λ` instead of a drift).
    pub lambda_per_s: f64,
    /// The law's configuration.
    pub law: C,
}

impl<C: Default> Default for ModelReferenceConfig<C> {
    fn default() -> Self {
        Self { prior_sigmas: 3.0, lambda_per_s: 1.0, law: C::default() }
    }
}

/// Why a channel's step failed: the estimator diverged (with the reason), or the sample is
/// refused (state unchanged).
enum StepFailure {
    Diverged(&'static str),
    Refused(EstimatorError),
}

#[derive(Debug, Clone)]
struct Channel<L> {
    coefficient: Coefficient,
    state: SlidingState,
    first: usize,
    n: usize,
    terms: [Term; N_TERMS],
    knots: AlphaKnots,
    law: L,
    started: bool,
    z_est: f64,
    z_m: f64,
    prev: Option<RateInput>,
    info: Square<N_TERMS>,
    count: usize,
    excited: bool,
}

/// A channel's step computed but not applied: the estimated state at the sample and the law's
/// step.
struct Pending<S> {
    z: f64,
    law: S,
}

impl<L: CoefficientLaw> Channel<L> {
    /// Sets the law's gains from the first accepted sample, once. This changes the channel
    /// before the sample is known to be accepted: the caller restores it if the update fails.
    fn start(&mut self, s: &AirDataSample, input: &RateInput) -> Result<(), StepFailure> {
        if !self.started {
            self.law.start(input, s).map_err(StepFailure::Refused)?;
            self.started = true;
        }
        Ok(())
    }

    /// One sample's step of this channel (module doc), computed without changing it: the
    /// estimated model integrated over the interval `dt` (`None`: restart from the measured
    /// state) and the law's update. `commit` applies it.
    fn propose(
        &self,
        s: &AirDataSample,
        input: &RateInput,
        dt: Option<f64>,
    ) -> Result<Pending<L::Step>, StepFailure> {
        let z = match (dt, &self.prev) {
            (Some(dt), Some(prev)) => integrate(self.z_est, prev, input, &self.theta(), dt),
            _ => input.rate.z_m,
        };
        let gap = libm::fabs(z - input.rate.z_m);
        if gap.is_nan() || gap > self.state.runaway_bound(s.vt_mps) {
            return Err(StepFailure::Diverged("estimated model ran away from the measured state"));
        }
        let sample = SmpeSample {
            t_s: s.t_s,
            z: SVector::<f64, 1>::new(z),
            z_m: SVector::<f64, 1>::new(input.rate.z_m),
            zdot_m: SVector::<f64, 1>::new(input.rate.zdot_m),
            u: *input,
        };
        let step = match self.law.propose(&sample) {
            Ok(step) => step,
            Err(EstimatorError::Numerical { what, .. }) => return Err(StepFailure::Diverged(what)),
            Err(e) => return Err(StepFailure::Refused(e)),
        };
        if (0..self.n).any(|j| !self.law.theta_after(&step, j).is_finite()) {
            return Err(StepFailure::Diverged("non-finite parameter estimate"));
        }
        Ok(Pending { z, law: step })
    }

    /// Applies a step proposed from the channel's current state, and the excitation
    /// bookkeeping.
    fn commit(&mut self, input: &RateInput, step: Pending<L::Step>) {
        self.law.commit(step.law);
        self.z_est = step.z;
        self.z_m = input.rate.z_m;
        self.prev = Some(*input);
        let phi = &input.phi;
        for i in 0..self.n {
            for j in 0..self.n {
                self.info[i][j] += phi[i] * phi[j];
            }
        }
        self.count += 1;
        if !self.excited && self.count >= self.n {
            self.excited =
                well_conditioned(&self.info, self.n, self.count as f64, INIT_MIN_SCALED_PIVOT);
        }
    }

    fn theta(&self) -> [f64; N_TERMS] {
        let mut th = [0.0; N_TERMS];
        for (j, t) in th.iter_mut().enumerate().take(self.n) {
            *t = self.law.theta(j);
        }
        th
    }

    fn input(
        &self,
        s: &AirDataSample,
        measured: &CoefficientValues,
        lambda_per_s: f64,
    ) -> Result<RateInput, EstimatorError> {
        let missing = |field| EstimatorError::NonFiniteInput { field, value: f64::NAN, t_s: s.t_s };
        let rate = state_rate(self.coefficient, s).map_err(missing)?;
        let c_m = measured[self.coefficient.index()].ok_or_else(|| {
            missing(self.coefficient.missing_field(s).unwrap_or(self.coefficient.name()))
        })?;
        let mut phi = [0.0; N_TERMS];
        for (x, t) in phi.iter_mut().zip(&self.terms[..self.n]) {
            *x = t
                .value(s, &self.knots)
                .ok_or_else(|| missing(t.missing_field(s).unwrap_or("regressor")))?;
        }
        Ok(RateInput { rate, c_m, phi, lambda_per_s })
    }
}

/// Integrates the estimated model over one interval (module doc).
fn integrate(z: f64, prev: &RateInput, cur: &RateInput, theta: &[f64], dt: f64) -> f64 {
    let lam = cur.lambda_per_s;
    let g_bar = 0.5 * (prev.open_loop_rate(theta) + cur.open_loop_rate(theta));
    let z_bar = 0.5 * (prev.rate.z_m + cur.rate.z_m);
    let decay = libm::exp(-lam * dt);
    let gain = if lam * dt > 1e-12 { (1.0 - decay) / lam } else { dt };
    decay * z + gain * (g_bar + lam * z_bar)
}

/// A model-reference estimator over a [`ModelStructure`] with adaptation law `L` (module doc);
/// use the aliases [`PublishedSmpeEstimator`], [`CorrectedSmpeEstimator`],
/// [`GradientEstimator`].
#[derive(Debug, Clone)]
pub struct ModelReference<L: CoefficientLaw> {
    structure: ModelStructure,
    lambda_per_s: f64,
    channels: [Option<Channel<L>>; 8],
    last_t_s: Option<f64>,
    restart: bool,
    est: Estimates,
}

impl<L: CoefficientLaw> ModelReference<L> {
    /// A new estimator: each coefficient's law starts from the priors (module doc). Nothing is
    /// identified until its regressors have been exciting.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] if the structure is invalid (empty, over capacity,
    /// CX/CZ mixed with CL/CD), `priors` does not cover it, `k_σ` or `λ` is not finite and
    /// positive, a prior is not finite or its σ not positive, or the law's configuration is
    /// invalid.
    pub fn new(
        structure: ModelStructure,
        priors: &Priors,
        config: ModelReferenceConfig<L::Config>,
    ) -> Result<Self, EstimatorError> {
        let bad = |field, value, reason| EstimatorError::InvalidConfig { field, value, reason };
        let structure = structure.validated().map_err(|_| {
            bad(
                "model structure",
                structure.n_params() as f64,
                "empty, over capacity, or mixes CX/CZ with CL/CD",
            )
        })?;
        if priors.n != structure.n_params() {
            return Err(bad("priors", priors.n as f64, "must have one entry per parameter"));
        }
        for (field, v) in
            [("prior_sigmas", config.prior_sigmas), ("lambda_per_s", config.lambda_per_s)]
        {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(field, v, "must be finite and > 0"));
            }
        }
        let mut channels: [Option<Channel<L>>; 8] = Default::default();
        for c in structure.coefficients() {
            let first = structure.first_index(c);
            let mut terms = [Term::Bias; N_TERMS];
            let mut n = 0;
            for (k, t) in structure.terms_of(c).enumerate() {
                terms[k] = t;
                n = k + 1;
            }
            let pri = &priors.prior[first..first + n];
            if let Some(p) = pri.iter().find(|p| !(p.value.is_finite() && p.sigma > 0.0)) {
                return Err(bad("prior", p.sigma, "value must be finite and σ finite and > 0"));
            }
            let spec = CoefficientSpec {
                coefficient: c,
                terms: &terms[..n],
                priors: pri,
                prior_sigmas: config.prior_sigmas,
                lambda_per_s: config.lambda_per_s,
            };
            channels[c.index()] = Some(Channel {
                coefficient: c,
                state: SlidingState::of(c),
                first,
                n,
                terms,
                knots: *structure.knots(),
                law: L::new(&spec, &config.law)?,
                started: false,
                z_est: 0.0,
                z_m: 0.0,
                prev: None,
                info: [[0.0; N_TERMS]; N_TERMS],
                count: 0,
                excited: false,
            });
        }
        let mut me = Self {
            structure,
            lambda_per_s: config.lambda_per_s,
            channels,
            last_t_s: None,
            restart: false,
            est: Estimates::new(structure.n_params()),
        };
        me.publish(0.0);
        Ok(me)
    }

    /// The estimated model's state `z_est` of coefficient `c`'s sliding state after the last
    /// accepted sample (unit of [`SlidingState::of`]`(c)`), if `c` is modelled and a sample was
    /// accepted.
    pub fn estimated_state(&self, c: Coefficient) -> Option<f64> {
        let ch = self.channels[c.index()].as_ref()?;
        ch.prev.is_some().then_some(ch.z_est)
    }

    /// The sliding surface `z_est − z_m` of coefficient `c` at the last accepted sample.
    pub fn surface(&self, c: Coefficient) -> Option<f64> {
        let ch = self.channels[c.index()].as_ref()?;
        ch.prev.is_some().then_some(ch.z_est - ch.z_m)
    }

    /// Whether coefficient `c`'s regressors have been persistently exciting (its parameters are
    /// reported from then on).
    pub fn is_excited(&self, c: Coefficient) -> bool {
        self.channels[c.index()].as_ref().is_some_and(|ch| ch.excited)
    }

    /// The adaptation law of coefficient `c` (for diagnostics: its engine and counters).
    pub fn law(&self, c: Coefficient) -> Option<&L> {
        self.channels[c.index()].as_ref().map(|ch| &ch.law)
    }

    /// Every channel's step, computed before any is applied (all or nothing); only a first
    /// sample's `start` changes a channel here.
    fn propose(
        &mut self,
        s: &AirDataSample,
        inputs: &[RateInput; 8],
        dt: Option<f64>,
    ) -> Result<[Option<Pending<L::Step>>; 8], StepFailure> {
        let mut pending: [Option<Pending<L::Step>>; 8] = Default::default();
        for (slot, (ch, input)) in pending.iter_mut().zip(self.channels.iter_mut().zip(inputs)) {
            let Some(ch) = ch.as_mut() else { continue };
            ch.start(s, input)?;
            *slot = Some(ch.propose(s, input, dt)?);
        }
        Ok(pending)
    }

    fn publish(&mut self, t_s: f64) {
        self.est.t_s = t_s;
        let mut all = true;
        for ch in self.channels.iter().flatten() {
            for j in 0..ch.n {
                let id = ch.excited && ch.law.is_estimated(j);
                self.est.set(ch.first + j, ch.law.theta(j), None, id);
            }
            all &= ch.excited;
        }
        self.est.status = if all { Status::Running } else { Status::Initialising };
    }

    fn diverge(&mut self, what: &'static str, t_s: f64) -> EstimatorError {
        self.est.status = Status::Diverged;
        self.est.t_s = t_s;
        for i in 0..self.est.n {
            self.est.set(i, self.est.raw_value(i), None, false);
        }
        EstimatorError::Numerical { what, t_s }
    }
}

impl<L: CoefficientLaw> Estimator for ModelReference<L> {
    fn method(&self) -> &'static str {
        L::METHOD
    }

    fn structure(&self) -> &ModelStructure {
        &self.structure
    }

    fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        check_finite(s)?;
        if self.est.status == Status::Diverged {
            return Err(EstimatorError::Numerical {
                what: "estimator diverged earlier; its state is not a result",
                t_s: s.t_s,
            });
        }
        if s.qbar_pa.is_nan() || s.qbar_pa <= 0.0 {
            return Err(EstimatorError::NonFiniteInput {
                field: "qbar_pa",
                value: s.qbar_pa,
                t_s: s.t_s,
            });
        }
        let dt = match self.last_t_s {
            Some(t0) if !self.restart => {
                let dt = s.t_s - t0;
                if dt.is_nan() || dt <= 0.0 {
                    return Err(EstimatorError::Numerical {
                        what: "sample time not after the previous sample's",
                        t_s: s.t_s,
                    });
                }
                Some(dt)
            }
            _ => None,
        };
        let measured = s.measured_coefficients();
        // All or nothing: form every input before touching any state.
        let mut inputs = [RateInput::default(); 8];
        for ch in self.channels.iter().flatten() {
            inputs[ch.coefficient.index()] = ch.input(s, &measured, self.lambda_per_s)?;
        }
        // The first accepted sample starts the laws (their gains come from it), which cannot
        // be proposed: the channels are copied then, and only then, to be restored on failure.
        let unstarted = self.channels.iter().flatten().any(|ch| !ch.started);
        let saved = unstarted.then(|| self.channels.clone());
        let pending = match self.propose(s, &inputs, dt) {
            Ok(pending) => pending,
            Err(fail) => {
                if let Some(saved) = saved {
                    self.channels = saved;
                }
                return Err(match fail {
                    StepFailure::Diverged(what) => self.diverge(what, s.t_s),
                    StepFailure::Refused(e) => e,
                });
            }
        };
        for ((slot, step), input) in self.channels.iter_mut().zip(pending).zip(&inputs) {
            if let (Some(ch), Some(step)) = (slot.as_mut(), step) {
                ch.commit(input, step);
            }
        }
        self.last_t_s = Some(s.t_s);
        self.restart = false;
        self.publish(s.t_s);
        Ok(&self.est)
    }

    fn estimates(&self) -> &Estimates {
        &self.est
    }

    /// Re-initialises every estimated state from the next sample and keeps the parameters
    /// (and the accumulated excitation). A diverged estimator restarts from its last good
    /// parameters: a divergence is never committed to the state.
    fn new_manoeuvre(&mut self) {
        self.restart = true;
        if self.est.status == Status::Diverged {
            self.est.status = Status::Initialising;
        }
        for ch in self.channels.iter_mut().flatten() {
            ch.law.new_manoeuvre();
            ch.prev = None;
        }
    }
}

#[cfg(test)]
mod tests;
