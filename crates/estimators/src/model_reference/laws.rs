//! The three adaptation laws on one coefficient's sliding state, each a thin wrapper over its
//! engine (no copy of a law): bounds from the priors, gains from the flight condition.

use super::{CoefficientLaw, CoefficientRate, CoefficientSpec, RateInput, SlidingState};
use crate::EstimatorError;
use crate::ParametricEstimator;
use crate::mrac::{GradientConfig, GradientStep, ModelReferenceGradient};
use crate::sample::AirDataSample;
use crate::smpe::{
    CorrectedConfig, CorrectedSmpe, CorrectedStep, GainForm, ParamSpec, PublishedSmpe,
    PublishedStep, Reading, SlidingSurface, SmpeConfig, SmpeSample,
};
use crate::vocabulary::{N_TERMS, Param, Term};

/// Placeholder of an unused parameter slot (zero regressor): bounds `±1e-150` around 0 so it
/// adds nothing to a gain's trace, and the smallest positive gain.
const UNUSED: ParamSpec = ParamSpec {
    name: "unused",
    lower: -1e-150,
    upper: 1e-150,
    lambda: f64::MIN_POSITIVE,
    initial: 0.0,
};

fn bad(field: &'static str, value: f64, reason: &'static str) -> EstimatorError {
    EstimatorError::InvalidConfig { field, value, reason }
}

/// `[v − k_σ σ, v + k_σ σ]`, initial `v` (corrected and gradient laws).
fn additive_spec(spec: &CoefficientSpec<'_>, j: usize, lambda: f64) -> ParamSpec {
    let p = spec.priors[j];
    let half = spec.prior_sigmas * p.sigma;
    ParamSpec {
        name: Param::new(spec.coefficient, spec.terms[j]).name(),
        lower: p.value - half,
        upper: p.value + half,
        lambda,
        initial: p.value,
    }
}

fn specs_with_unused(spec: &CoefficientSpec<'_>, lambda: f64) -> [ParamSpec; N_TERMS] {
    core::array::from_fn(
        |j| if j < spec.terms.len() { additive_spec(spec, j, lambda) } else { UNUSED },
    )
}

// ---------------------------------------------------------------------------------------------
// Corrected.

/// Configuration of [`CorrectedLaw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectedLawConfig {
    /// Information weight κ_C in coefficient space, 1/s: one second of data with a
    /// coefficient prediction error `ΔC` carries information `κ_C ΔC²` (the reciprocal of the
    /// equation-error power spectral density, `σ_C² Δt`). The engine's κ in state units is
    /// `κ_C / k₀²` with `k₀ = ∂ż/∂C` at the first sample. Default `10⁶`/s: an equation error
    /// of σ_C = 0.01 at 100 Hz (accelerometer noise plus unmodelled terms); with bounds at
    /// ±3σ of the generic priors the data then outweigh the bounds within a few ms of a 1°,
    /// 5°/s excitation of a term; in nearly collinear directions of weakly excited terms the
    /// prior still acts (a regularised least squares; `docs/model-reference.md`).
    pub information_per_s: f64,
    /// Weight of the surface term relative to the prediction-error term, `γ / (κ λ)` ≥ 0.
    /// Default 0 (the κ term alone) for constant parameters (ρ = 0): Γ then decays as 1/t, so
    /// anything the surface term adds that is not least squares decays only as 1/t (on exact
    /// simulated data ratio 1 leaves 0.5 % after 20 s, ratio 0 leaves 0.03 %). With ρ > 0, 1 is
    /// the natural value: below `λ` the surface is `s ≈ e/λ`, so both terms of the composite law
    /// then pull equally, and the explicit surface step stays stable (its per-sample gain is at
    /// most 1, because Γ is updated by the same sample's information first).
    pub tracking_ratio: f64,
    /// Forgetting rate ρ ≥ 0, 1/s (0: a constant parameter; > 0 follows a change).
    pub forgetting_per_s: f64,
}

impl Default for CorrectedLawConfig {
    fn default() -> Self {
        Self { information_per_s: 1e6, tracking_ratio: 0.0, forgetting_per_s: 0.0 }
    }
}

/// The corrected sliding-mode law ([`CorrectedSmpe`], `docs/smpe-corrected.md`) on one
/// coefficient, `P = N_TERMS` with unused slots.
#[derive(Debug, Clone)]
pub struct CorrectedLaw {
    engine: CorrectedSmpe<CoefficientRate, 1, N_TERMS>,
    config: CorrectedConfig<1, N_TERMS>,
    information_c_per_s: f64,
    tracking_ratio: f64,
}

impl CorrectedLaw {
    /// The engine (surface, adaptation gain Γ).
    pub fn engine(&self) -> &CorrectedSmpe<CoefficientRate, 1, N_TERMS> {
        &self.engine
    }
}

impl CoefficientLaw for CorrectedLaw {
    const METHOD: &'static str = "smpe-corrected";
    type Config = CorrectedLawConfig;
    type Step = CorrectedStep<1, N_TERMS>;

    fn new(spec: &CoefficientSpec<'_>, c: &CorrectedLawConfig) -> Result<Self, EstimatorError> {
        if !(c.tracking_ratio.is_finite() && c.tracking_ratio >= 0.0) {
            return Err(bad("tracking_ratio", c.tracking_ratio, "must be finite and ≥ 0"));
        }
        let config = CorrectedConfig {
            params: specs_with_unused(spec, spec.lambda_per_s),
            sliding: [1.0],
            lambda_per_s: spec.lambda_per_s,
            information_per_s: c.information_per_s,
            tracking_weight: c.tracking_ratio * c.information_per_s * spec.lambda_per_s,
            forgetting_per_s: c.forgetting_per_s,
        };
        // Validates the configuration now; the gains in state units are set at `start`.
        // The slots beyond the coefficient's terms have zero regressors (RateInput::phi).
        let engine = CorrectedSmpe::new(CoefficientRate, config)?.with_active(spec.terms.len());
        Ok(Self {
            engine,
            config,
            information_c_per_s: c.information_per_s,
            tracking_ratio: c.tracking_ratio,
        })
    }

    fn start(&mut self, first: &RateInput, _s: &AirDataSample) -> Result<(), EstimatorError> {
        let k0 = first.rate.k;
        let kappa = self.information_c_per_s / (k0 * k0);
        if !(kappa.is_finite() && kappa > 0.0) {
            return Err(bad(
                "information_per_s",
                kappa,
                "k = ∂ż/∂C at the first sample must be finite and ≠ 0",
            ));
        }
        self.config.information_per_s = kappa;
        self.config.tracking_weight = self.tracking_ratio * kappa * self.config.lambda_per_s;
        let n = self.engine.active();
        self.engine = CorrectedSmpe::new(CoefficientRate, self.config)?.with_active(n);
        Ok(())
    }

    fn theta(&self, j: usize) -> f64 {
        self.engine.estimate().theta[j]
    }

    fn propose(&self, s: &SmpeSample<1, RateInput>) -> Result<Self::Step, EstimatorError> {
        self.engine.propose(s)
    }

    fn theta_after(&self, step: &Self::Step, j: usize) -> f64 {
        step.theta()[j]
    }

    fn commit(&mut self, step: Self::Step) {
        self.engine.commit(step);
    }

    fn new_manoeuvre(&mut self) {
        self.engine.new_manoeuvre();
    }
}

// ---------------------------------------------------------------------------------------------
// Gradient (3.3).

/// Reference amplitude of an angle or control deflection, rad (1°, a flight-test input).
pub const ANGLE_REF_RAD: f64 = 0.017_453_292_519_943_295;
/// Reference amplitude of a body rate, rad/s (5°/s, a flight-test response).
pub const RATE_REF_RAD_S: f64 = 5.0 * ANGLE_REF_RAD;
/// Reference relative airspeed change, – (1 %).
pub const SPEED_REF_FRACTION: f64 = 0.01;

/// Configuration of [`GradientLaw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GradientLawConfig {
    /// Loop gain G > 0 of (3.3) at the reference amplitudes (default 10). Because the bracket
    /// of (3.3) is the time derivative of `E = ½(z² − z_m²)` along the estimated model,
    /// (3.3) integrates to `θ̂_j(t) = θ̂_j(0) − λ_j [E(t) − E(0)]`: a static map of the current
    /// energy error. For one parameter under a held input, `E ≈ z s` with the surface
    /// `s = k φ θ̃ / λ` (filter gain λ), so the parameter error settles at
    /// `θ̃∞ = θ̃₀ / (1 + G)`, `G = λ_j z k φ / λ`. The gain of parameter `j` is therefore
    /// `λ_j = G λ / (|k₀| z_ref φ_ref,j)`, with `k₀ = ∂ż/∂C` at the first sample, `z_ref` the
    /// sliding state's magnitude at the first sample plus its reference amplitude, and
    /// `φ_ref,j` the regressor's reference amplitude ([`ANGLE_REF_RAD`], [`RATE_REF_RAD_S`],
    /// [`SPEED_REF_FRACTION`]). G = 10 leaves 1/11 of the initial error of a damping derivative
    /// at the reference amplitudes; a larger G lowers that bias and amplifies noise in
    /// proportion (θ̂ follows `E` instantaneously).
    pub loop_gain: f64,
}

impl Default for GradientLawConfig {
    fn default() -> Self {
        Self { loop_gain: 10.0 }
    }
}

/// The model-reference gradient law (3.3) ([`ModelReferenceGradient`]) on one coefficient,
/// `P = N_TERMS` with unused slots.
///
/// **WARNING:** (3.3) moves every parameter of a coefficient by the same scalar
/// `z ż_est − z_m ż_m` times its gain, so `θ̂(t) − θ̂(0)` stays on the line through `θ̂(0)` along
/// `(λ_1, …, λ_n)` (until a bound is hit): with two or more parameters per coefficient it
/// cannot reach the truth, except by coincidence. And it has no memory: `θ̂_j(t) − θ̂_j(0) =
/// −λ_j [E(t) − E(0)]` ([`GradientLawConfig::loop_gain`]), so under periodic excitation it
/// oscillates about its start, and under a held input it settles with a bias `1/(1 + G)` of
/// the initial error, and only where `z ∂ż/∂θ > 0` (a damping derivative: `Cm_q` with `q`,
/// `Cl_p` with `p`); where `z ∂ż/∂θ < 0` (e.g. `CL_0` with `α > 0`, since `∂α̇/∂CL < 0`) it
/// moves away from the truth.
#[derive(Debug, Clone)]
pub struct GradientLaw {
    engine: ModelReferenceGradient<CoefficientRate, 1, N_TERMS>,
    config: GradientConfig<1, N_TERMS>,
    terms: [Term; N_TERMS],
    n: usize,
    state: SlidingState,
    loop_gain: f64,
    filter_per_s: f64,
}

impl GradientLaw {
    /// The engine (gains, counters).
    pub fn engine(&self) -> &ModelReferenceGradient<CoefficientRate, 1, N_TERMS> {
        &self.engine
    }
}

fn regressor_reference(t: Term, s: &AirDataSample) -> f64 {
    let two_v = 2.0 * s.vt_mps;
    let k = &s.constants;
    match t {
        Term::Bias => 1.0,
        Term::Alpha | Term::Beta | Term::De | Term::Da | Term::Dr => ANGLE_REF_RAD,
        Term::P | Term::R => RATE_REF_RAD_S * k.b_m.unwrap_or(f64::NAN) / two_v,
        Term::Q | Term::Alphadot => RATE_REF_RAD_S * k.cbar_m.unwrap_or(f64::NAN) / two_v,
        Term::Q0 => {
            RATE_REF_RAD_S * k.cbar_m.unwrap_or(f64::NAN) / (2.0 * k.v0_mps.unwrap_or(f64::NAN))
        }
        Term::V => SPEED_REF_FRACTION,
        // A perturbation of α past the knot; of M and M² by the reference fraction of V.
        Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => ANGLE_REF_RAD,
        Term::Mach => SPEED_REF_FRACTION * s.mach().unwrap_or(f64::NAN),
        Term::Mach2 => 2.0 * SPEED_REF_FRACTION * s.mach().map_or(f64::NAN, |m| m * m),
        Term::Alpha2 | Term::AlphaDe | Term::AlphaBeta | Term::AlphaDa | Term::AlphaDr => {
            ANGLE_REF_RAD * ANGLE_REF_RAD
        }
        Term::AlphaP | Term::AlphaR => {
            ANGLE_REF_RAD * RATE_REF_RAD_S * k.b_m.unwrap_or(f64::NAN) / two_v
        }
        Term::AlphaQ => ANGLE_REF_RAD * RATE_REF_RAD_S * k.cbar_m.unwrap_or(f64::NAN) / two_v,
    }
}

/// Reference magnitude of the sliding state in (3.3)'s energy rate `z ż`: the state's own
/// magnitude at the first sample (V ≈ V₀, α ≈ α_trim: (3.3) multiplies by `z`, not by its
/// perturbation) plus the perturbation reference.
fn state_reference(state: SlidingState, z0: f64, vt_mps: f64) -> f64 {
    libm::fabs(z0)
        + match state {
            SlidingState::P | SlidingState::Q | SlidingState::R => RATE_REF_RAD_S,
            SlidingState::Alpha | SlidingState::Beta => ANGLE_REF_RAD,
            SlidingState::V | SlidingState::U => SPEED_REF_FRACTION * vt_mps,
            SlidingState::W => ANGLE_REF_RAD * vt_mps,
        }
}

impl CoefficientLaw for GradientLaw {
    const METHOD: &'static str = "gradient";
    type Config = GradientLawConfig;
    type Step = GradientStep<N_TERMS>;

    fn new(spec: &CoefficientSpec<'_>, c: &GradientLawConfig) -> Result<Self, EstimatorError> {
        if !(c.loop_gain.is_finite() && c.loop_gain > 0.0) {
            return Err(bad("loop_gain", c.loop_gain, "must be finite and > 0"));
        }
        let mut terms = [Term::Bias; N_TERMS];
        terms[..spec.terms.len()].copy_from_slice(spec.terms);
        // Provisional unit gains (validates the bounds); the gains are set at `start`.
        let config =
            GradientConfig { params: specs_with_unused(spec, 1.0), states: [[1.0]; N_TERMS] };
        Ok(Self {
            engine: ModelReferenceGradient::new(CoefficientRate, config)?,
            config,
            terms,
            n: spec.terms.len(),
            state: SlidingState::of(spec.coefficient),
            loop_gain: c.loop_gain,
            filter_per_s: spec.lambda_per_s,
        })
    }

    fn start(&mut self, first: &RateInput, s: &AirDataSample) -> Result<(), EstimatorError> {
        let z_ref = state_reference(self.state, first.rate.z_m, s.vt_mps);
        let zk = libm::fabs(first.rate.k) * z_ref / (self.loop_gain * self.filter_per_s);
        for j in 0..self.n {
            let lambda = 1.0 / (zk * regressor_reference(self.terms[j], s));
            if !(lambda.is_finite() && lambda > 0.0) {
                return Err(bad(
                    "gradient gain",
                    lambda,
                    "not finite at the first sample's flight condition",
                ));
            }
            self.config.params[j].lambda = lambda;
        }
        self.engine = ModelReferenceGradient::new(CoefficientRate, self.config)?;
        Ok(())
    }

    fn theta(&self, j: usize) -> f64 {
        self.engine.estimate().theta[j]
    }

    fn propose(&self, s: &SmpeSample<1, RateInput>) -> Result<Self::Step, EstimatorError> {
        self.engine.propose(s)
    }

    fn theta_after(&self, step: &Self::Step, j: usize) -> f64 {
        step.theta()[j]
    }

    fn commit(&mut self, step: Self::Step) {
        self.engine.commit(step);
    }

    fn new_manoeuvre(&mut self) {
        self.engine.new_manoeuvre();
    }
}

// ---------------------------------------------------------------------------------------------
// Published.

/// Configuration of [`PublishedLaw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PublishedLawConfig {
    /// η > 0 of (3.20), units of the energy rate `z ż` per unit parameter. Default `10⁻⁶`:
    /// 0.3 % of the energy rate of a 1°/s, 1°/s² rate excitation (3·10⁻⁴ rad²/s³) per unit
    /// parameter — small, as the thesis intends, yet it sets the published form's bias.
    pub eta: f64,
    /// Implicit (the thesis's Simulink algebraic loop, default) or explicit reading.
    pub reading: Reading,
    /// Shared K (3.72)/(3.128), the thesis's, default; or per-parameter.
    pub gain: GainForm,
}

impl Default for PublishedLawConfig {
    fn default() -> Self {
        Self { eta: 1e-6, reading: Reading::Implicit, gain: GainForm::Shared }
    }
}

macro_rules! published_engines {
    ($($variant:ident = $p:literal),*) => {
        /// The published engine instantiated with exactly the number of estimated parameters.
        #[derive(Debug, Clone)]
        #[allow(clippy::large_enum_variant)] // no_std, no allocation: no Box.
        enum PublishedEngine {
            $($variant(PublishedSmpe<CoefficientRate, 1, $p>)),*
        }

        /// A step of [`PublishedEngine`], of the same size.
        #[derive(Debug, Clone, Copy)]
        enum PublishedEngineStep {
            $($variant(PublishedStep<$p>)),*
        }

        impl PublishedEngineStep {
            fn theta(&self, e: usize) -> f64 {
                match self { $(Self::$variant(s) => s.theta()[e]),* }
            }
        }

        impl PublishedEngine {
            fn new(params: &[ParamSpec], c: &PublishedLawConfig) -> Result<Self, EstimatorError> {
                let surface = SlidingSurface::first_order(&[0])?;
                match params.len() {
                    $($p => Ok(Self::$variant(PublishedSmpe::new(CoefficientRate, SmpeConfig {
                        params: core::array::from_fn(|j| params[j]),
                        eta: c.eta,
                        surface,
                        gain: c.gain,
                        reading: c.reading,
                    })?)),)*
                    n => Err(bad("published parameters", n as f64, "1 to N_TERMS per coefficient")),
                }
            }

            fn theta(&self, j: usize) -> f64 {
                match self { $(Self::$variant(e) => e.estimate().theta[j]),* }
            }

            fn propose(
                &self,
                s: &SmpeSample<1, RateInput>,
            ) -> Result<PublishedEngineStep, EstimatorError> {
                match self { $(Self::$variant(e) => e.propose(s).map(PublishedEngineStep::$variant)),* }
            }

            fn commit(&mut self, step: PublishedEngineStep) {
                match (self, step) {
                    $((Self::$variant(e), PublishedEngineStep::$variant(step)) => e.commit(step),)*
                    // Only a law's own engine proposes its steps, so the sizes match.
                    _ => unreachable!("a published step committed to another engine"),
                }
            }

            fn stats(&self) -> crate::smpe::SolveStats {
                match self { $(Self::$variant(e) => e.stats()),* }
            }
        }
    };
}

published_engines!(
    P1 = 1,
    P2 = 2,
    P3 = 3,
    P4 = 4,
    P5 = 5,
    P6 = 6,
    P7 = 7,
    P8 = 8,
    P9 = 9,
    P10 = 10,
    P11 = 11,
    P12 = 12,
    P13 = 13,
    P14 = 14
);

/// The published sliding-mode law ([`PublishedSmpe`], thesis (3.20)–(3.22), (3.72)) on one
/// coefficient, with exactly its sign-known parameters (module doc of the parent: bounds).
///
/// **WARNING** (`docs/reproduction-poc.md`): the truth is not a fixed point (with perfect
/// tracking `F_j(θ) = −η θ_j ≠ 0`); with the shared K and one λ, all parameters of one
/// coefficient solve one scalar equation and are forced equal whenever the root is inside the
/// bounds; with the states at rest (`z = z_m = 0`) `F_j = −η θ̂_j` has no root in same-signed
/// bounds and the estimate sits on the bound nearest 0.
#[derive(Debug, Clone)]
pub struct PublishedLaw {
    engine: Option<PublishedEngine>,
    /// Engine index of each term, `None` = held at its prior (unknown sign).
    index: [Option<usize>; N_TERMS],
    held: [f64; N_TERMS],
    n: usize,
}

/// One update of [`PublishedLaw`] computed but not applied ([`CoefficientLaw::propose`]).
#[derive(Debug, Clone, Copy)]
pub struct PublishedLawStep(Option<PublishedEngineStep>);

impl PublishedLaw {
    /// Counters of the engine's per-sample solve (no root, clamped …), if any parameter is
    /// estimated.
    pub fn stats(&self) -> Option<crate::smpe::SolveStats> {
        self.engine.as_ref().map(PublishedEngine::stats)
    }
}

impl CoefficientLaw for PublishedLaw {
    const METHOD: &'static str = "smpe";
    type Config = PublishedLawConfig;
    type Step = PublishedLawStep;

    fn new(spec: &CoefficientSpec<'_>, c: &PublishedLawConfig) -> Result<Self, EstimatorError> {
        let mut params = [UNUSED; N_TERMS];
        let mut index = [None; N_TERMS];
        let mut held = [0.0; N_TERMS];
        let mut m = 0;
        for (j, prior) in spec.priors.iter().enumerate() {
            let v = prior.value;
            if v == 0.0 {
                continue; // no sign: held at 0, never identified
            }
            let rho = 1.0 + spec.prior_sigmas * prior.sigma / libm::fabs(v);
            let (a, b) = (v / rho, v * rho);
            params[m] = ParamSpec {
                name: Param::new(spec.coefficient, spec.terms[j]).name(),
                lower: a.min(b),
                upper: a.max(b),
                lambda: spec.lambda_per_s,
                initial: v,
            };
            index[j] = Some(m);
            m += 1;
        }
        for (j, h) in held.iter_mut().enumerate().take(spec.terms.len()) {
            if index[j].is_none() {
                *h = spec.priors[j].value;
            }
        }
        let engine = if m > 0 { Some(PublishedEngine::new(&params[..m], c)?) } else { None };
        Ok(Self { engine, index, held, n: spec.terms.len() })
    }

    fn theta(&self, j: usize) -> f64 {
        match (self.index[j], &self.engine) {
            (Some(e), Some(engine)) => engine.theta(e),
            _ => self.held[j],
        }
    }

    fn is_estimated(&self, j: usize) -> bool {
        self.index[j].is_some()
    }

    fn propose(&self, s: &SmpeSample<1, RateInput>) -> Result<Self::Step, EstimatorError> {
        let Some(engine) = self.engine.as_ref() else { return Ok(PublishedLawStep(None)) };
        // Re-pack the regressors to the engine's parameters; held terms are known inputs.
        let mut u = s.u;
        u.phi = [0.0; N_TERMS];
        for j in 0..self.n {
            match self.index[j] {
                Some(e) => u.phi[e] = s.u.phi[j],
                None => u.c_m -= self.held[j] * s.u.phi[j],
            }
        }
        engine.propose(&SmpeSample { u, ..*s }).map(|step| PublishedLawStep(Some(step)))
    }

    fn theta_after(&self, step: &Self::Step, j: usize) -> f64 {
        match (self.index[j], &step.0) {
            (Some(e), Some(step)) => step.theta(e),
            _ => self.held[j],
        }
    }

    fn commit(&mut self, step: Self::Step) {
        if let (Some(engine), Some(step)) = (self.engine.as_mut(), step.0) {
            engine.commit(step);
        }
    }

    fn new_manoeuvre(&mut self) {}
}
