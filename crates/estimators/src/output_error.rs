//! Batch output-error (maximum-likelihood) estimation over any [`ModelStructure`]: the
//! post-flight reference a flight-test engineer compares every other estimate to.
//!
//! Sources: Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., AIAA 2015, ch. 4
//! (output-error method: ML cost with unknown noise covariance, relaxation, Gauss–Newton and
//! Levenberg–Marquardt, sensitivities, Cramér–Rao bounds; the book's `ml_oem.m`, `ruku4.m`);
//! Klein & Morelli, *Aircraft System Identification*, AIAA 2006, ch. 6 (maximum likelihood /
//! output error, the Cramér–Rao bound, coloured residuals). Section and equation numbers are
//! not quoted: they were not checked against the books.
//!
//! Batch: it reads whole manoeuvres and allocates (it is not an [`crate::Estimator`]); it is
//! built only with the crate's `std` feature.
//!
//! Before flight, [`design::predict_crb`] predicts the Cramér–Rao σ a planned input will give,
//! from this module's simulation and sensitivities.
//!
//! # Model
//!
//! The structure's [`FlightModel`] (its state set, longitudinal, lateral or coupled, follows
//! from the structure, [`StateSet::of`]): states integrated from an initial state, outputs
//! `y = h(x, u, θ) + b` with optional constant output biases `b` ([`OeConfig::output_biases`],
//! shared by all manoeuvres). Each manoeuvre has its own initial state: the first sample's
//! measurements, or estimated ([`InitialStates`]). A state the record does not measure (β on
//! a record without a sideslip vane) is still a state, integrated from its own equation and
//! seen through the outputs it drives (`ay`, `p`, `r`): its initial value is estimated per
//! manoeuvre from a start of 0, and [`OeResult::unmeasured_states`] names it. Integration: classical RK4 over each sample
//! interval with the inputs interpolated linearly between the two samples (start, midpoint,
//! end), as Jategaonkar's `ruku4.m`. A record with time gaps must be split into manoeuvres
//! first ([`split_at_gaps`]).
//!
//! # Sensitivities (exact)
//!
//! `S_i = ∂y_i/∂β` for the unknowns `β = (θ, b, x0)` are the exact derivatives of the discrete
//! RK4 map: with `X = ∂x/∂β` and, at each stage `s` (stage state `x + c_s dt k_{s−1}`),
//! `A_s = ∂f/∂x`, `B_s = ∂f/∂θ` from [`FlightModel::linearise`] (forward-mode duals),
//! `X_s = X + c_s dt K_{s−1}`, `K_s = A_s X_s + B_s`, `X' = X + dt/6 (K1 + 2K2 + 2K3 + K4)`
//! (the sensitivity equations `Ẋ = A X + B` integrated by the same scheme), and
//! `S = C X + D` (+1 in an output's bias column), `C = ∂h/∂x`, `D = ∂h/∂θ`. No finite
//! differences; the tests check them against central differences.
//!
//! # Cost, noise covariance and step
//!
//! With residuals `e_i = z_i − y_i(β)` over all `N` samples of all manoeuvres, the negative
//! log-likelihood of Gaussian white measurement noise with unknown diagonal covariance `R`,
//! minimised over `R`, is `½ N ln det R(β) + const` with `R(β) = diag((1/N) Σ_i e_i e_iᵀ)`.
//! Each iteration:
//!
//! 1. `R = diag((1/N) Σ_i e_i e_iᵀ)` at the current `β` (the ML estimate; the relaxation of
//!    Jategaonkar ch. 4 alternates this with the `β` step);
//! 2. `M = Σ S_iᵀ R⁻¹ S_i`, `g = Σ S_iᵀ R⁻¹ e_i` and the step `(H + λ diag M) Δ = g`, solved by
//!    Cholesky with Jacobi scaling (nalgebra), where ([`StepKind`]):
//!    - [`StepKind::Relaxation`] (Jategaonkar): `H = M`, the Gauss–Newton step on
//!      `J = ½ Σ eᵀ R⁻¹ e` with `R` fixed, accepted when that `J` falls;
//!    - [`StepKind::Concentrated`] (default): `H = M − (2/N) Σ_j g_j g_jᵀ` with the per-output
//!      gradients `g_j = R_jj⁻¹ Σ_i e_ij S_ij`, the Gauss–Newton Hessian of `½ N ln det R(β)`
//!      itself (it adds the curvature of `R(β)` that the relaxation ignores; `M` is used where
//!      `H` is not positive definite), accepted when `det R` falls. Same fixed point (the
//!      gradients are equal); it converges in a few iterations where systematic residuals
//!      pull the outputs apart and the relaxation creeps (Twin Otter: 8 against > 50).
//!
//!    Levenberg–Marquardt damping: `λ = 0` (pure Gauss–Newton) while steps are accepted; a
//!    rejected step, or one that makes the simulation diverge, is retried with `λ` raised ×10
//!    from 10⁻³ (up to 10¹⁰); after an accepted step `λ` falls ×10, to 0 below 10⁻⁶.
//!
//! **Step length.** When the undamped step `Δ` is accepted, one more simulation is run at
//! `α Δ`, `α` the minimum of the parabola through the merit and its slope at `α = 0`
//! (`d ln det R/dα = −(2/N) gᵀΔ` concentrated, `−gᵀΔ` for the relaxation) and the merit at
//! `α = 1`, when that minimum exists, lies in `[0.1, 4]` and differs from 1 by more than 10 %;
//! the better of the two is taken (quadratic line search, Dennis & Schnabel, *Numerical
//! Methods for Unconstrained Optimization*, 1983, §6.3.2, here also allowed to lengthen the
//! step). Gauss–Newton's `M` leaves out the curvature of the residuals `Σ e ∂²y/∂β²`, which
//! is not small when turbulence or model error keeps the residuals large: along a direction
//! where it adds curvature the full step overshoots and the iterates zigzag towards the
//! minimum at a rate near 1 (default-campaign run 24 of a 20-s window: steps shrinking by 0.97
//! per iteration, not converged after 250 iterations; with the parabolic length, 23). Same
//! fixed point; the replays of the HFB-320 and ATTAS records are unchanged to the printed
//! digits (docs/uncertainty.md, "Output error: step length").
//!
//! **Convergence** ([`Termination`]): [`Termination::Converged`] when the relative change of
//! `det R` over the iteration is below [`OeConfig::cost_tolerance`] (default 10⁻⁶) **and** the
//! largest step is below [`OeConfig::step_tolerance_sigma`] (default 10⁻³) Cramér–Rao σ of its
//! unknown. A fit that reaches [`OeConfig::max_iterations`] first, or that cannot reduce the
//! cost while its Gauss–Newton step is still larger than that tolerance, has converged in the
//! cost alone ([`Termination::CostConverged`], returned as a result) when its last accepted
//! iteration changed `det R` by less than the cost tolerance: the criterion of Jategaonkar's
//! `ml_oem2` (Jategaonkar 2015 §4.10), met on a cost that is flat along a direction the record
//! does not determine, where the remaining step (in the iteration log) is a σ-sized wander, not
//! a descent. Otherwise it is returned as [`OeError::NotConverged`] carrying the last iterate
//! (never silently as a result).
//!
//! **Numerical failure.** A step is accepted only once the model has been flown at it, but its
//! sensitivities (each iteration's linearization, and the accuracy at the end) are formed
//! afterwards. When they cannot be ([`EstimatorError::Numerical`]: the state left the physical
//! domain, a singular equation), the fit is not lost: it goes back to the last iterate whose
//! outputs and sensitivities were both formed, its log ends there, and it ends as
//! [`NotConverged::NumericalFailure`] (what failed, and at which sample time), judged by the
//! criteria above like any other stop, so a caller writes its estimates and summary with the
//! reason. Only a starting point that cannot be flown or linearized is an error.
//!
//! # Starting values ([`Start`])
//!
//! By default the equation-error (least-squares) fit of each coefficient to the measured
//! coefficients ([`AirDataSample::measured_coefficients`]; the regression of Klein & Morelli
//! 2006 ch. 5, the usual source of output-error starting values); a coefficient that cannot be measured
//! from the records (e.g. `Cl` without `ṗ`) starts at its generic prior ([`Priors::generic`]).
//! If the model diverges from these values the generic priors are tried before giving up.
//!
//! A fit from the equation-error start that ends without converging (the iteration limit, no
//! descent, or a numerical failure) is fitted again from the generic priors ([`fit_to_end`]), and the converged one,
//! else the one with the lower `det R`, is kept; [`OeResult::restart`] says what both did.
//! A second start that cannot be flown at all (the priors' model leaves the physical domain
//! on the record) keeps the first fit, not converged, with the reason in the restart: a fit
//! that ran is never lost to the start that did not.
//! Gauss–Newton converges to the minimum whose basin holds the start, and a start that is
//! right on the measured axes but generic on the others (a record without a sideslip vane:
//! every lateral coefficient needs β) can lie in a valley that leads to a worse local minimum
//! or creeps along it: on a 10-Hz F-16 record with no β vane, its biases removed, the
//! equation-error start crept for 50 iterations to `ln det R` −58.0 with Cn_β at a seventh of
//! its value, while the priors converged in 20 to −63.6 (Jategaonkar 2015 §4.8 on starting
//! values and local minima; a second start is the cheapest of its remedies, and it costs a
//! second fit only where the first failed).
//!
//! # Accuracy
//!
//! - **Cramér–Rao σ** `sqrt(diag M⁻¹)` with `M` at the estimate and the final `R`
//!   (Jategaonkar ch. 4; Klein & Morelli ch. 6), the correlation matrix.
//! - **Coloured-residual σ** ([`OeResult::sigma_coloured`]): `M⁻¹ [Σ_i Σ_j S_iᵀ R⁻¹ R_vv(i−j)
//!   R⁻¹ S_j] M⁻¹` (Morelli & Klein, J. Guidance Control Dyn. 20(1), 1997; Klein & Morelli
//!   2006 ch. 6), evaluated in the frequency domain with a multitaper (sine-taper) estimate of
//!   the residuals' cross-spectral matrix and the fitted share of the residuals put back
//!   ([`crate::coloured::batch`], "Spectral form"): no noise model, no lag truncation. On
//!   flight data with model error or turbulence this, not the Cramér–Rao σ, is the honest
//!   uncertainty. Two diagnostics are kept: [`OeResult::sigma_coloured_prewhitened`] (the
//!   same sandwich with `R_vv` from a vector autoregression of the residuals, Andrews &
//!   Monahan 1992; exact for autoregressive noise, 0.71–12.5 × the exact σ when the noise is a
//!   lightly damped resonance, with or without white sensor noise) and
//!   [`OeResult::sigma_coloured_truncated`] (sample autocovariances truncated at the first
//!   lag where every output's normalised autocorrelation is inside `±2/√N`, at most
//!   [`OeConfig::coloured_max_lag`]).
//!
//! # Dominant samples
//!
//! One corrupt sample can own a least-squares fit. [`OeResult::dominance`] names the sample
//! with the largest share of the weighted cost `Σ_i e_iᵀ R⁻¹ e_i` (and the output that
//! contributes most to it), and the sample with the largest Cook's distance
//! `D_i = g_iᵀ M⁻¹ g_i / nβ`, `g_i = S_iᵀ R⁻¹ e_i` (the one-step change of the estimate were
//! the sample removed, in the metric of its covariance; Cook & Weisberg, *Residuals and
//! Influence in Regression*, 1982, without the `(1 − h_ii)⁻²` factor). A fit is dominated by
//! one sample when that share is at least [`Dominance::SHARE_LIMIT`] (5 %) with a χ² of at
//! least `10 ny`, or when that Cook's distance is at least [`Dominance::COOK_LIMIT`] (1).
//!
//! # Robust option
//!
//! With [`OeConfig::robust`], Huber's M-estimate (Huber, *Robust Statistics*, Wiley 1981,
//! ch. 7; the output-error form as iteratively reweighted least squares, Holland & Welsch,
//! Commun. Statist. A6(9), 1977): the cost is `Σ_ij ρ(e_ij/σ_j)`, Huber's `ρ` with
//! [`Huber::k`], the scale `σ_j = 1.4826 · MAD` of output `j`'s residuals (the mean square
//! where the MAD is 0). Each iteration fixes the scale and the weights `u_ij = min(1,
//! k/|e_ij/σ_j|)` at the current residuals and takes the relaxation's Gauss–Newton step with
//! `M = Σ Sᵀ U R⁻¹ S`, accepted when Huber's cost at that scale falls (the concentrated step
//! does not apply). Convergence as above with `R = diag(σ_j²)`. The σ are those of the
//! weighted problem (`√u e`, `√u S`): the Cramér–Rao and coloured-residual formulas at the
//! final weights, without Huber's asymptotic efficiency factor (about 5 % at `k` = 1.345 on
//! Gaussian residuals). A residual outlier (a spike in a measured output) then counts
//! linearly; an outlier in an input (thrust, a control surface) is integrated by the model
//! and corrupts the simulation after it: the replay's spike screen is the remedy for those.
//!
//! # Errors
//!
//! [`OeError::Estimator`] with [`EstimatorError::InvalidConfig`] for a structure without a
//! state set, no manoeuvre, a manoeuvre with fewer than two samples, non-increasing times, an
//! output the state set does not predict (or selected twice), a bias on an output not
//! selected, a time gap within a manoeuvre, a wrong-sized [`Start::Given`] vector, an unknown that does not affect any output,
//! or fewer measurements than unknowns; [`EstimatorError::NonFiniteInput`] naming a missing or
//! non-finite channel (a selected output or a model input must be present in every sample; an
//! unmeasured state is not an error);
//! [`EstimatorError::Numerical`] when the model diverges at every starting point tried (or
//! cannot be linearized at the one that flew). A numerical failure at a later iterate is not an
//! error: the last good iterate is returned as [`NotConverged::NumericalFailure`] ("Numerical
//! failure" above). An information matrix singular at the last iterate is not an error either:
//! the iterate is returned as [`NotConverged::Unidentifiable`] with NaN σ.

use crate::coloured::batch as coloured;
pub mod bootstrap;
pub mod design;
pub mod filter_error;
pub mod frequency;
pub mod riccati;
mod simulation;
pub use simulation::{MAX_FIT_BYTES, MAX_SENSITIVITY_VALUES, estimated_peak_bytes};

use crate::EstimatorError;
use crate::flight_model::{FlightModel, N_STATES, Output, STATE_NAMES, StateSet};
use crate::prior::Priors;
use crate::sample::AirDataSample;
use crate::vocabulary::ModelStructure;
use core::fmt;
use nalgebra::{DMatrix, DVector};
use simulation::Problem;
use std::boxed::Box;
use std::format;
use std::string::String;
use std::vec;
use std::vec::Vec;

/// Which initial states are estimated (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialStates {
    /// Every manoeuvre starts at its first sample's measured states (Jategaonkar's default,
    /// `parFlagX0 = 0`).
    FirstSample,
    /// The states flagged `true` (full-state order `(V, α, β, p, q, r, φ, θ)`, only integrated
    /// states count) are estimated for every manoeuvre; the others start at the first sample.
    Estimate([bool; N_STATES]),
}

/// How the two fits of a restarted fit ended ([`OeResult::restart`], module doc "Starting
/// values").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Restart {
    /// How the fit from the equation-error start ended, and its last `ln det R`.
    pub first: (Termination, f64),
    /// How the fit from the generic priors ended, and its last `ln det R`; the error when it
    /// could not run at all (the priors' model left the physical domain on the record): the
    /// first fit is then kept, as it was.
    pub second: Result<(Termination, f64), EstimatorError>,
    /// Whether the fit returned is the second (from the generic priors).
    pub kept_second: bool,
}

/// Starting values of the structure's parameters (module doc).
#[derive(Debug, Clone, PartialEq)]
pub enum Start {
    /// Equation-error least squares on the measured coefficients, else the generic prior.
    EquationError,
    /// The generic priors ([`Priors::generic`]).
    Priors,
    /// Given values, structure order (length = number of parameters).
    Given(Vec<f64>),
}

/// How the Gauss–Newton step treats the noise covariance (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepKind {
    /// Jategaonkar's relaxation: the step minimises `J` with `R` fixed (matrix `M`), accepted
    /// when `J` at that `R` falls.
    Relaxation,
    /// The step includes the curvature of `R(β)`: the Gauss–Newton Hessian of the
    /// concentrated cost `½ N ln det R(β)`, `H = M − (2/N) Σ_j g_j g_jᵀ` (`M` where `H` is not
    /// positive definite), accepted when `det R` falls. Same fixed point, far fewer iterations
    /// when systematic residuals pull the outputs apart.
    Concentrated,
}

/// Configuration of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct OeConfig {
    /// The model structure whose parameters are estimated.
    pub structure: ModelStructure,
    /// The outputs fitted; `None`: every output of the state set ([`StateSet::outputs`]) that
    /// the first sample of the first manoeuvre has.
    pub outputs: Option<Vec<Output>>,
    /// Outputs with a constant bias estimated (shared by all manoeuvres).
    pub output_biases: Vec<Output>,
    /// Initial states fixed or estimated.
    pub initial_states: InitialStates,
    /// Starting values.
    pub start: Start,
    /// The Gauss–Newton step (default [`StepKind::Concentrated`]).
    pub step: StepKind,
    /// Most Gauss–Newton iterations (default 50).
    pub max_iterations: usize,
    /// Convergence: relative change of `det R` between iterations (default 10⁻⁶).
    pub cost_tolerance: f64,
    /// Convergence: largest step in Cramér–Rao σ of its unknown (default 10⁻³).
    pub step_tolerance_sigma: f64,
    /// Largest lag of the coloured-residual sum; `None`: a quarter of the shortest manoeuvre.
    pub coloured_max_lag: Option<usize>,
    /// Outlier-resistant fit with Huber's weights ([`Huber`], module doc "Robust option");
    /// `None` (default): the Gaussian maximum-likelihood fit.
    pub robust: Option<Huber>,
    /// A request to stop, looked at before every iteration and every damped trial step: once
    /// raised, the fit ends with its last iterate ([`NotConverged::Stopped`]) and its
    /// Cramér–Rao σ only (the coloured-residual σ, the slowest part after the iterations, are
    /// then `None`). Raised while the coloured σ are formed, it ends them at their next look
    /// (between passes and manoeuvres): the σ are then `None` and the termination the fit's
    /// own. `None` (default): it runs to its end.
    pub stop: Option<StopFlag>,
}

/// A request to stop a batch fit at its next iteration (and a bootstrap before its next
/// replica), raised from another thread (a signal handler's, a user interface's). Clones share
/// the request.
#[derive(Debug, Clone, Default)]
pub struct StopFlag(std::sync::Arc<core::sync::atomic::AtomicBool>);

impl StopFlag {
    /// A flag shared with `flag` (raised when `flag` is set).
    pub fn new(flag: std::sync::Arc<core::sync::atomic::AtomicBool>) -> Self {
        Self(flag)
    }

    /// Asks the fits that hold this flag to stop.
    pub fn raise(&self) {
        self.0.store(true, core::sync::atomic::Ordering::SeqCst);
    }

    /// Whether a stop was asked for.
    pub fn raised(&self) -> bool {
        self.0.load(core::sync::atomic::Ordering::SeqCst)
    }
}

impl PartialEq for StopFlag {
    /// Equal when shared: the same request.
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Whether `stop` (a config's [`OeConfig::stop`]) has been raised.
fn stop_raised(stop: Option<&StopFlag>) -> bool {
    stop.is_some_and(StopFlag::raised)
}

/// Huber's M-estimate for output error (module doc, "Robust option"): residuals beyond `k`
/// robust standard deviations of their output count linearly, not quadratically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Huber {
    /// The tuning constant `k`, in robust standard deviations `1.4826 · MAD` (default 1.345:
    /// 95 % efficiency on Gaussian residuals, Huber 1981).
    pub k: f64,
}

impl Default for Huber {
    fn default() -> Self {
        Self { k: 1.345 }
    }
}

impl Huber {
    /// The IRLS weight `ψ(z)/z = min(1, k/|z|)` of a normalised residual `z`.
    pub fn weight(self, z: f64) -> f64 {
        if z.abs() <= self.k { 1.0 } else { self.k / z.abs() }
    }

    /// Huber's loss `ρ(z)`: `z²/2` within `k`, `k|z| − k²/2` beyond.
    pub fn loss(self, z: f64) -> f64 {
        if z.abs() <= self.k { 0.5 * z * z } else { self.k * z.abs() - 0.5 * self.k * self.k }
    }
}

/// The sample that weighs most on a fit ([`OeResult::dominance`]): a warning when one sample
/// owns the estimate (module doc, "Dominant samples").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dominance {
    /// The sample with the largest share of the cost: index over the manoeuvres concatenated.
    pub share_sample: usize,
    /// Its share of the weighted cost `Σ eᵀ R⁻¹ e` (of the robust weighted cost with
    /// [`OeConfig::robust`]), 0…1.
    pub share: f64,
    /// Its term `e_iᵀ R⁻¹ e_i` (a χ² with `ny` degrees of freedom for Gaussian residuals).
    pub chi2: f64,
    /// The output that contributes most to that term.
    pub share_output: Output,
    /// The sample with the largest Cook's distance.
    pub cook_sample: usize,
    /// Its Cook's distance `D_i = g_iᵀ M⁻¹ g_i / nβ`, `g_i = S_iᵀ R⁻¹ e_i`: the shift of the
    /// estimate without the sample, in the metric of its covariance, per unknown.
    pub cook: f64,
}

impl Dominance {
    /// Share of the cost above which one sample dominates ([`Dominance::share_dominates`]).
    pub const SHARE_LIMIT: f64 = 0.05;
    /// Cook's distance above which one sample dominates (Cook & Weisberg 1982's rule of thumb:
    /// removing it moves the estimate beyond its 50 % confidence region).
    pub const COOK_LIMIT: f64 = 1.0;

    /// Whether the largest share dominates: at least [`Dominance::SHARE_LIMIT`] of the cost
    /// and a χ² of at least `10 · ny` (out of reach of Gaussian residuals, so that a short
    /// record's largest sample is not flagged for being one of few).
    pub fn share_dominates(&self, ny: usize) -> bool {
        self.share >= Self::SHARE_LIMIT && self.chi2 >= 10.0 * ny as f64
    }

    /// Whether the largest Cook's distance dominates (≥ [`Dominance::COOK_LIMIT`]).
    pub fn cook_dominates(&self) -> bool {
        self.cook >= Self::COOK_LIMIT
    }
}

impl OeConfig {
    /// The documented defaults for `structure`: outputs from the data, no biases, initial
    /// states at the first sample, equation-error start, 50 iterations, tolerances 10⁻⁶
    /// (relative `det R`) and 10⁻³ σ (step).
    pub fn new(structure: ModelStructure) -> Self {
        Self {
            structure,
            outputs: None,
            output_biases: Vec::new(),
            initial_states: InitialStates::FirstSample,
            start: Start::EquationError,
            step: StepKind::Concentrated,
            max_iterations: 50,
            cost_tolerance: 1e-6,
            step_tolerance_sigma: 1e-3,
            coloured_max_lag: None,
            robust: None,
            stop: None,
        }
    }
}

/// One Gauss–Newton iteration of the log.
#[derive(Debug, Clone, PartialEq)]
pub struct OeIteration {
    /// Iteration number (0 = the starting values).
    pub iteration: usize,
    /// `ln det R` after the iteration (sum of the logs of the output variances; the
    /// concentrated negative log-likelihood is `½ N ln det R` + const).
    pub ln_det_r: f64,
    /// `J = ½ Σ eᵀ R⁻¹ e` after the step, with the `R` the step was taken with (equals
    /// `N·ny/2` at iteration 0).
    pub cost: f64,
    /// Levenberg–Marquardt `λ` of the accepted step (0: pure Gauss–Newton).
    pub lambda: f64,
    /// Largest step, in Cramér–Rao σ of its unknown.
    pub max_step_sigma: f64,
}

/// Why a fit stopped without converging.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NotConverged {
    /// [`OeConfig::max_iterations`] reached.
    MaxIterations,
    /// No step reduced the cost (λ up to 10¹⁰) while the Gauss–Newton step was still large.
    NoDescent,
    /// The information matrix is singular at the last iterate: some unknowns are not
    /// identifiable from the record, and no σ can be given (the result's σ are NaN).
    Unidentifiable,
    /// A stop was asked for ([`OeConfig::stop`]) before the fit converged.
    Stopped,
    /// The model could not be flown, or its sensitivities not formed, at an iterate after the
    /// start ([`EstimatorError::Numerical`]: what failed, and at which sample time): the
    /// result is the last iterate whose outputs and sensitivities were both formed (module
    /// doc, "Numerical failure").
    NumericalFailure {
        /// What failed.
        what: &'static str,
        /// Sample time of the failure, s.
        t_s: f64,
    },
}

impl NotConverged {
    /// A sentence for people: what stopped the fit.
    pub fn describe(self) -> String {
        match self {
            NotConverged::MaxIterations => "the iteration limit was reached".into(),
            NotConverged::NoDescent => {
                "no step reduced the cost while the Gauss–Newton step was still large".into()
            }
            NotConverged::Unidentifiable => {
                "the information matrix is singular at the last iterate: the unknowns are not all identifiable from this record, so no σ is given".into()
            }
            NotConverged::Stopped => "a stop was asked for before it converged".into(),
            NotConverged::NumericalFailure { what, t_s } => format!(
                "the model could not be flown at the next iterate (numerical failure in `{what}` at t = {t_s} s); the last good iterate is reported"
            ),
        }
    }

    /// The reason a fit ends with when `err` struck at an iterate after the start: a
    /// numerical failure ([`NotConverged::NumericalFailure`]); `None` for any other error
    /// (invalid data or configuration), which stays an error.
    pub fn numerical(err: &EstimatorError) -> Option<Self> {
        match *err {
            EstimatorError::Numerical { what, t_s } => {
                Some(NotConverged::NumericalFailure { what, t_s })
            }
            _ => None,
        }
    }
}

/// How a batch fit's iterations ended (module doc, "Convergence").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Termination {
    /// Both criteria met: the cost stopped changing and the last step was negligible.
    Converged,
    /// The cost stopped changing (relative change of `det R` below the tolerance over the last
    /// accepted iteration) but the step was not negligible when the fit stopped, for the
    /// reason given: converged by `ml_oem2`'s criterion alone.
    CostConverged(NotConverged),
    /// Neither: the result is the last iterate, for the reason given.
    NotConverged(NotConverged),
}

impl Termination {
    /// How a fit with iteration log `log` ended: `converged` when both criteria were met,
    /// else by the last accepted iteration's relative change of `det R` (`ln_det_r` of the
    /// last two log entries) against `cost_tolerance`. A log of the start alone has no
    /// accepted iteration and is [`Termination::NotConverged`].
    pub fn of(
        log: &[OeIteration],
        converged: bool,
        failure: NotConverged,
        cost_tolerance: f64,
    ) -> Self {
        let last_change = match log {
            [.., a, b] => Some((b.ln_det_r - a.ln_det_r).exp_m1().abs()),
            _ => None,
        };
        Self::after(converged, last_change, failure, cost_tolerance)
    }

    /// How a fit ended given whether both criteria were met and the relative change of
    /// `det R` over its last accepted iteration (`None`: no iteration was accepted).
    pub fn after(
        converged: bool,
        last_change: Option<f64>,
        failure: NotConverged,
        cost_tolerance: f64,
    ) -> Self {
        match last_change {
            _ if converged => Termination::Converged,
            Some(rel) if rel < cost_tolerance => Termination::CostConverged(failure),
            _ => Termination::NotConverged(failure),
        }
    }

    /// Whether the fit is a result (both criteria, or the cost criterion alone).
    pub fn is_converged(self) -> bool {
        !matches!(self, Termination::NotConverged(_))
    }

    /// The status word of summaries: `converged`, `converged_in_cost` or `not_converged`.
    pub fn status(self) -> &'static str {
        match self {
            Termination::Converged => "converged",
            Termination::CostConverged(_) => "converged_in_cost",
            Termination::NotConverged(_) => "not_converged",
        }
    }

    /// A sentence for people.
    pub fn describe(self) -> String {
        match self {
            Termination::Converged => "converged".into(),
            Termination::CostConverged(why) => format!(
                "converged in the cost alone (det R stopped changing; {} when it stopped)",
                why.describe()
            ),
            Termination::NotConverged(why) => {
                format!("NOT CONVERGED ({}): the last iterate", why.describe())
            }
        }
    }
}

/// The result of [`fit`] (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct OeResult {
    /// The structure.
    pub structure: ModelStructure,
    /// Names of all unknowns: the structure's parameters (`Cm_alpha` …), then the output
    /// biases (`bias_<output>`), then the free initial states (`x0_m<k>_<state>`, manoeuvre
    /// `k` from 1).
    pub names: Vec<String>,
    /// Number of structure parameters (the first entries of `names`).
    pub n_params: usize,
    /// Estimates, order of `names`.
    pub values: Vec<f64>,
    /// Cramér–Rao σ `sqrt(diag M⁻¹)`.
    pub sigma: Vec<f64>,
    /// Coloured-residual σ (the spectral, multitaper sandwich, [`crate::coloured::batch`],
    /// "Spectral form"); `None` if that correction was not positive, or not formed because a
    /// stop was asked for ([`OeConfig::stop`]).
    pub sigma_coloured: Option<Vec<f64>>,
    /// The prewhitened coloured-residual σ (vector autoregression of the residuals,
    /// [`crate::coloured::batch`], "Prewhitening"), kept as a diagnostic; `None` if not
    /// positive.
    pub sigma_coloured_prewhitened: Option<Vec<f64>>,
    /// Lag at which the prewhitened form's sum over the whitened residuals was truncated.
    pub coloured_lag: usize,
    /// Order of the residuals' vector autoregression in the prewhitened form (0: white).
    pub coloured_ar_order: usize,
    /// The lag-truncated coloured-residual σ (the Morelli & Klein sum of sample
    /// autocovariances, no prewhitening; [`crate::coloured::batch`]), kept as a diagnostic:
    /// it understates the σ when the residual correlation outlasts the lag cap. `None` if not
    /// positive.
    pub sigma_coloured_truncated: Option<Vec<f64>>,
    /// `M⁻¹`, row-major `n × n`.
    pub covariance: Vec<f64>,
    /// Correlation matrix of the estimates, row-major `n × n`.
    pub correlation: Vec<f64>,
    /// The fitted outputs.
    pub outputs: Vec<Output>,
    /// Estimated measurement-noise variances (diagonal of `R`), per output.
    pub r: Vec<f64>,
    /// Residual RMS per output (`sqrt(R)`), units of the output.
    pub residual_rms: Vec<f64>,
    /// Residual mean per output.
    pub residual_mean: Vec<f64>,
    /// Residuals `z − y`, `N × ny` row-major, manoeuvres concatenated.
    pub residuals: Vec<f64>,
    /// Samples per manoeuvre.
    pub manoeuvre_lengths: Vec<usize>,
    /// Iteration log.
    pub iterations: Vec<OeIteration>,
    /// The starting values that were used (structure order).
    pub start: Vec<f64>,
    /// The fit was started twice (module doc, "Starting values"): both fits' endings, and
    /// which is returned; `None` when the first start's fit was kept without a second.
    pub restart: Option<Restart>,
    /// How the iterations ended (module doc, "Convergence").
    pub termination: Termination,
    /// The integrated states with no measurement at a manoeuvre's first sample (names as
    /// [`STATE_NAMES`], e.g. `beta_rad` on a record without a sideslip vane): their initial
    /// values were estimated from 0 (module doc, "Model"), whatever
    /// [`OeConfig::initial_states`] said.
    pub unmeasured_states: Vec<&'static str>,
    /// The sample with the largest share of the cost and the one with the largest Cook's
    /// distance (`None` when the fit is not identified).
    pub dominance: Option<Dominance>,
}

impl OeResult {
    /// The fit's outcome: the result when it converged (both criteria or the cost alone),
    /// else [`OeError::NotConverged`] carrying it as the last iterate.
    ///
    /// # Errors
    /// [`OeError::NotConverged`] for [`Termination::NotConverged`].
    pub fn into_outcome(self) -> Result<OeResult, OeError> {
        match self.termination {
            Termination::NotConverged(reason) => {
                Err(OeError::NotConverged { reason, result: Box::new(self) })
            }
            _ => Ok(self),
        }
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.values.len()
    }

    /// Index of an unknown by name.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Estimate and Cramér–Rao σ of an unknown by name.
    pub fn get(&self, name: &str) -> Option<(f64, f64)> {
        self.index_of(name).map(|i| (self.values[i], self.sigma[i]))
    }

    /// Correlation of unknowns `i` and `j`.
    pub fn correlation(&self, i: usize, j: usize) -> f64 {
        self.correlation[i * self.n() + j]
    }

    /// Number of Gauss–Newton iterations taken.
    pub fn n_iterations(&self) -> usize {
        self.iterations.len().saturating_sub(1)
    }
}

impl fmt::Display for OeResult {
    /// A printable summary: iteration log, estimates with both σ, noise and residuals.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "output error (ML, diagonal R): {} unknowns, {} outputs, {} samples in {} manoeuvre(s): {}",
            self.n(),
            self.outputs.len(),
            self.manoeuvre_lengths.iter().sum::<usize>(),
            self.manoeuvre_lengths.len(),
            self.termination.describe()
        )?;
        writeln!(
            f,
            "{:>5} {:>14} {:>14} {:>10} {:>12}",
            "iter", "ln det R", "J", "lambda", "max step/σ"
        )?;
        for it in &self.iterations {
            writeln!(
                f,
                "{:>5} {:>14.8} {:>14.6e} {:>10.1e} {:>12.3e}",
                it.iteration, it.ln_det_r, it.cost, it.lambda, it.max_step_sigma
            )?;
        }
        writeln!(
            f,
            "{:<22} {:>14} {:>12} {:>14} {:>14}",
            "unknown", "estimate", "CR σ", "coloured σ", "prewhitened σ"
        )?;
        let cell =
            |v: Option<&Vec<f64>>, i: usize| v.map_or("—".into(), |s| format!("{:.6}", s[i]));
        for i in 0..self.n() {
            writeln!(
                f,
                "{:<22} {:>14.6} {:>12.6} {:>14} {:>14}",
                self.names[i],
                self.values[i],
                self.sigma[i],
                cell(self.sigma_coloured.as_ref(), i),
                cell(self.sigma_coloured_prewhitened.as_ref(), i),
            )?;
        }
        writeln!(
            f,
            "coloured σ: multitaper residual spectrum ({} sine tapers); prewhitened diagnostic: VAR order {}, lag {}",
            coloured::SPECTRAL_TAPERS,
            self.coloured_ar_order,
            self.coloured_lag
        )?;
        writeln!(f, "{:<14} {:>12} {:>12}", "output", "rms", "mean")?;
        for (j, o) in self.outputs.iter().enumerate() {
            writeln!(
                f,
                "{:<14} {:>12.5e} {:>12.5e}",
                o.name(),
                self.residual_rms[j],
                self.residual_mean[j]
            )?;
        }
        Ok(())
    }
}

/// Why [`fit`] failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OeError {
    /// Invalid configuration or data, or a numerical failure (module doc).
    #[error(transparent)]
    Estimator(#[from] EstimatorError),
    /// The iteration stopped without meeting the convergence criteria; the last iterate is
    /// attached (its σ and log) for diagnosis, not for use as an estimate.
    #[error("output error did not converge ({reason:?}) after {} iterations", result.n_iterations())]
    NotConverged {
        /// Why.
        reason: NotConverged,
        /// The last iterate.
        result: Box<OeResult>,
    },
}

/// A sample interval longer than this many median intervals is a gap between manoeuvres.
pub const GAP_FACTOR: f64 = 10.0;

/// Splits a record into manoeuvres at its time gaps: an interval longer than [`GAP_FACTOR`]
/// times the record's median interval (or a non-increasing time) starts a new manoeuvre.
/// Jategaonkar's multi-segment records are concatenations of this kind (e.g. `fAttasAilRud1`
/// holds an aileron and a rudder manoeuvre 30 s apart).
pub fn split_at_gaps(samples: &[AirDataSample]) -> Vec<&[AirDataSample]> {
    if samples.len() < 2 {
        return vec![samples];
    }
    let mut dts: Vec<f64> = samples.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    dts.sort_by(f64::total_cmp);
    let median = dts[dts.len() / 2];
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..samples.len() {
        let dt = samples[i].t_s - samples[i - 1].t_s;
        if !(dt > 0.0 && dt <= GAP_FACTOR * median) {
            out.push(&samples[start..i]);
            start = i;
        }
    }
    out.push(&samples[start..]);
    out
}

/// The default outputs: the state set's outputs the first sample has.
fn default_outputs(set: StateSet, first: &AirDataSample) -> Vec<Output> {
    set.outputs().iter().copied().filter(|o| o.measured(first).is_some()).collect()
}

/// Equation-error least squares of each coefficient (module doc), else the generic prior.
fn equation_error_start(structure: &ModelStructure, manoeuvres: &[&[AirDataSample]]) -> Vec<f64> {
    let priors = Priors::generic(structure);
    let mut theta: Vec<f64> = (0..structure.n_params()).map(|i| priors.prior[i].value).collect();
    for c in structure.coefficients() {
        let first = structure.first_index(c);
        let terms: Vec<_> = structure.terms_of(c).collect();
        let mut rows: Vec<f64> = Vec::new();
        let mut rhs: Vec<f64> = Vec::new();
        for s in manoeuvres.iter().flat_map(|m| m.iter()) {
            let Some(y) = s.measured_coefficients()[c.index()] else { continue };
            let xi: Option<Vec<f64>> = terms.iter().map(|t| structure.value(*t, s)).collect();
            if let Some(xi) = xi {
                rows.extend(xi);
                rhs.push(y);
            }
        }
        let n = rhs.len();
        if n < 2 * terms.len() {
            continue;
        }
        let x = DMatrix::from_row_slice(n, terms.len(), &rows);
        let b = DVector::from_vec(rhs);
        let svd = x.svd(true, true);
        let tol = 1e-10 * svd.singular_values.max();
        if let Ok(sol) = svd.solve(&b, tol)
            && sol.iter().all(|v| v.is_finite())
        {
            theta[first..first + terms.len()].copy_from_slice(sol.as_slice());
        }
    }
    theta
}

/// Residuals `z − y` (manoeuvres concatenated, as `y`) and the ML diagonal `R` (per output
/// mean square).
fn residuals(p: &Problem, y: &[f64], e: &mut Vec<f64>) -> Vec<f64> {
    let ny = p.ny();
    e.clear();
    e.extend(p.man.iter().flat_map(|m| m.z.iter()).zip(y).map(|(z, y)| z - y));
    let mut r = vec![0.0; ny];
    for (k, v) in e.iter().enumerate() {
        r[k % ny] += v * v;
    }
    let n = p.n_samples as f64;
    r.iter_mut().for_each(|v| *v /= n);
    r
}

/// The robust noise variances (module doc, "Robust option"): per output `(1.4826 · MAD)²` of
/// the residuals `e` (`ny`-interleaved), the mean square `ms` where the MAD is 0.
fn robust_variances(e: &[f64], ms: Vec<f64>) -> Vec<f64> {
    let ny = ms.len();
    let mut col = Vec::with_capacity(e.len() / ny.max(1));
    ms.iter()
        .enumerate()
        .map(|(j, &m)| {
            col.clear();
            col.extend(e.iter().skip(j).step_by(ny).copied());
            let med = median_in_place(&mut col);
            col.iter_mut().for_each(|v| *v = (*v - med).abs());
            let s = 1.4826 * median_in_place(&mut col);
            if s > 0.0 && s.is_finite() { s * s } else { m }
        })
        .collect()
}

fn median_in_place(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let k = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    *m
}

/// Huber's IRLS weights `min(1, k/|e/σ|)` of the residuals `e` with the noise variances `r`.
fn huber_weights(h: Huber, e: &[f64], r: &[f64]) -> Vec<f64> {
    let ny = r.len();
    let sd: Vec<f64> = r.iter().map(|v| v.sqrt()).collect();
    e.iter().enumerate().map(|(k, v)| h.weight(v / sd[k % ny])).collect()
}

/// Huber's cost `Σ ρ(e/σ)` at the standard deviations `sd`.
fn huber_cost(h: Huber, e: &[f64], sd: &[f64]) -> f64 {
    let ny = sd.len();
    e.iter().enumerate().map(|(k, v)| h.loss(v / sd[k % ny])).sum()
}

fn weighted_cost(e: &[f64], w: &[f64]) -> f64 {
    let ny = w.len();
    0.5 * e.iter().enumerate().map(|(k, v)| v * v * w[k % ny]).sum::<f64>()
}

/// `M = Σ Sᵀ W S`, `g = Σ Sᵀ W e` and the per-output gradients `g_j = w_j Σ_i e_ij S_ij`
/// (`ny × n` row-major, `g = Σ_j g_j`).
fn normal_equations(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    n: usize,
) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
    normal_equations_weighted(s, e, w, &[], n)
}

/// [`normal_equations`] with a further weight per residual `u` (Huber's IRLS weights; empty:
/// all 1).
fn normal_equations_weighted(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    u: &[f64],
    n: usize,
) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
    let ny = w.len();
    let mut m = DMatrix::<f64>::zeros(n, n);
    let mut gj = vec![0.0; ny * n];
    for (row, ev) in e.iter().enumerate() {
        let j = row % ny;
        let wj = w[j] * u.get(row).copied().unwrap_or(1.0);
        let sr = &s[row * n..(row + 1) * n];
        let g = &mut gj[j * n..(j + 1) * n];
        for a in 0..n {
            let wa = wj * sr[a];
            if wa == 0.0 {
                continue;
            }
            g[a] += wa * ev;
            for b in a..n {
                m[(a, b)] += wa * sr[b];
            }
        }
    }
    for a in 0..n {
        for b in 0..a {
            m[(a, b)] = m[(b, a)];
        }
    }
    let g = DVector::from_fn(n, |a, _| (0..ny).map(|j| gj[j * n + a]).sum());
    (m, g, gj)
}

/// The Gauss–Newton Hessian of the concentrated cost `½ N ln det R(β)` (module doc):
/// `H = M − (2/N) Σ_j g_j g_jᵀ`.
fn concentrated_hessian(m: &DMatrix<f64>, gj: &[f64], n_samples: usize) -> DMatrix<f64> {
    let n = m.nrows();
    let mut h = m.clone();
    for g in gj.chunks(n) {
        for a in 0..n {
            for b in 0..n {
                h[(a, b)] -= 2.0 / n_samples as f64 * g[a] * g[b];
            }
        }
    }
    h
}

/// Inverse of a symmetric positive definite `m` by Jacobi-scaled Cholesky.
fn spd_inverse(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = m.nrows();
    let d: Vec<f64> = (0..n).map(|i| 1.0 / m[(i, i)].sqrt()).collect();
    let ms = DMatrix::from_fn(n, n, |i, j| m[(i, j)] * d[i] * d[j]);
    let inv = ms.cholesky()?.inverse();
    let out = DMatrix::from_fn(n, n, |i, j| inv[(i, j)] * d[i] * d[j]);
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The damped step `(H + λ diag M) Δ = g`, Jacobi-scaled by `diag M` (Cholesky).
fn damped_step(
    h: &DMatrix<f64>,
    m: &DMatrix<f64>,
    g: &DVector<f64>,
    lambda: f64,
) -> Option<DVector<f64>> {
    let n = m.nrows();
    let d: Vec<f64> = (0..n).map(|i| 1.0 / m[(i, i)].sqrt()).collect();
    let hs =
        DMatrix::from_fn(n, n, |i, j| h[(i, j)] * d[i] * d[j] + if i == j { lambda } else { 0.0 });
    let gs = DVector::from_fn(n, |i, _| g[i] * d[i]);
    let sol = hs.cholesky()?.solve(&gs);
    let step = DVector::from_fn(n, |i, _| sol[i] * d[i]);
    step.iter().all(|v| v.is_finite()).then_some(step)
}

/// Bounds of the parabolic step length (module doc, "Step length"): outside them the
/// parabola is not trusted (a merit that is far from quadratic along the step).
const STEP_LENGTH_RANGE: (f64, f64) = (0.1, 4.0);

/// The step length `a` at the minimum of the parabola `f(α) = f0 + s α + c α²` through the
/// merit `f0` and its slope `s < 0` at `α = 0` and the merit `f1` at `α = 1`, when it is a
/// minimum (`c > 0`), lies in [`STEP_LENGTH_RANGE`] and differs from 1 by more than 10 %
/// (else `None`: the full step is kept).
fn parabolic_step(f0: f64, slope: f64, f1: f64) -> Option<f64> {
    let c = f1 - f0 - slope;
    if !(slope < 0.0 && c > 0.0) {
        return None;
    }
    let a = -slope / (2.0 * c);
    (a.is_finite() && (a - 1.0).abs() > 0.1)
        .then_some(a.clamp(STEP_LENGTH_RANGE.0, STEP_LENGTH_RANGE.1))
}

/// Fits the structure's parameters (and any biases and free initial states) to the
/// manoeuvres by maximum-likelihood output error (module doc).
///
/// `manoeuvres`: one slice of samples per manoeuvre, each in time order (sample intervals may
/// vary). Every sample must carry the constants and channels the structure's flight model
/// needs ([`FlightModel::inputs`]) and every selected output.
///
/// # Errors
/// [`OeError`] as in the module doc.
pub fn fit(manoeuvres: &[&[AirDataSample]], config: &OeConfig) -> Result<OeResult, OeError> {
    fit_to_end(manoeuvres, config)?.into_outcome()
}

/// [`fit`], but a fit that does not converge is returned too: its last iterate, with
/// [`OeResult::termination`] saying why it stopped (for a caller that reports it as such).
///
/// # Errors
/// As [`fit`], except [`OeError::NotConverged`].
pub fn fit_to_end(manoeuvres: &[&[AirDataSample]], config: &OeConfig) -> Result<OeResult, OeError> {
    let p = prepare(manoeuvres, config)?;
    let first = fit_prepared(p, manoeuvres, config)?;
    let failed = matches!(
        first.termination,
        Termination::NotConverged(
            NotConverged::MaxIterations
                | NotConverged::NoDescent
                | NotConverged::NumericalFailure { .. }
        )
    );
    let priors = priors_start(&config.structure);
    if !failed || config.start != Start::EquationError || first.start == priors {
        return Ok(first);
    }
    let again = OeConfig { start: Start::Priors, ..config.clone() };
    match prepare(manoeuvres, &again).and_then(|p| fit_prepared(p, manoeuvres, &again)) {
        Ok(second) => Ok(keep_better(first, second)),
        // A start that cannot be flown is no reason to lose the fit that ran: its last iterate
        // is still the answer, reported not converged.
        Err(OeError::Estimator(e)) => {
            let mut kept = first;
            let ln_det = kept.iterations.last().map_or(f64::INFINITY, |i| i.ln_det_r);
            let first = (kept.termination, ln_det);
            kept.restart = Some(Restart { first, second: Err(e), kept_second: false });
            Ok(kept)
        }
        Err(e) => Err(e),
    }
}

/// Of two fits of one problem, the converged one, else the one with the lower last `ln det R`
/// (the concentrated likelihood), with [`OeResult::restart`] telling both.
fn keep_better(first: OeResult, second: OeResult) -> OeResult {
    let ending =
        |r: &OeResult| (r.termination, r.iterations.last().map_or(f64::INFINITY, |i| i.ln_det_r));
    let (a, b) = (ending(&first), ending(&second));
    let kept_second = match (a.0.is_converged(), b.0.is_converged()) {
        (false, true) => true,
        (true, false) => false,
        _ => b.1 < a.1,
    };
    let mut kept = if kept_second { second } else { first };
    kept.restart = Some(Restart { first: a, second: Ok(b), kept_second });
    kept
}

/// [`fit`] on a prepared problem (`manoeuvres` only for the equation-error start).
///
/// Each iteration is one [`OeIterate`] pass ([`OeIterate::run`]): linearize at β, search the
/// damping for a step that lowers the merit, try the parabolic step length after an undamped
/// step, then accept the step or stop (module doc); then the result at the final iterate
/// ([`OeIterate::conclude`]).
fn fit_prepared(
    p: Problem,
    manoeuvres: &[&[AirDataSample]],
    config: &OeConfig,
) -> Result<OeResult, OeError> {
    let (mut it, start) = OeIterate::new(&p, manoeuvres, config)?;
    let (converged, failure) = it.run()?;
    it.conclude(start, converged, failure)
}

/// Simulates `beta` with its sensitivities: outputs into `y`, `∂y/∂β` into `s`.
fn simulate_sensitivities(
    p: &Problem,
    beta: &[f64],
    y: &mut Vec<f64>,
    s: &mut Vec<f64>,
) -> Result<(), EstimatorError> {
    #[cfg(test)]
    fault::check()?;
    p.simulate(beta, y, Some(s))
}

/// Fault injection for the tests of the fall-back to the last good iterate (module doc,
/// "Numerical failure"). No record can exercise it: an iterate is accepted only after its
/// simulation succeeded, and its sensitivities follow that same trajectory, so the failure
/// that path guards against cannot be provoked through the data.
#[cfg(test)]
pub(crate) mod fault {
    use crate::EstimatorError;
    use core::cell::Cell;

    std::thread_local! {
        /// Sensitivity computations of this thread that succeed before one fails.
        static LEFT: Cell<Option<usize>> = const { Cell::new(None) };
    }

    /// What an injected failure says it was.
    pub(crate) const WHAT: &str = "injected failure";
    /// The sample time an injected failure reports, s.
    pub(crate) const T_S: f64 = 7.25;

    /// The next `n` sensitivity computations of this thread succeed, the one after fails
    /// (once).
    pub(crate) fn fail_after(n: usize) {
        LEFT.with(|c| c.set(Some(n)));
    }

    /// Counts one sensitivity computation: the failure when it is the one chosen.
    pub(crate) fn check() -> Result<(), EstimatorError> {
        LEFT.with(|c| match c.get() {
            Some(0) => {
                c.set(None);
                Err(EstimatorError::Numerical { what: WHAT, t_s: T_S })
            }
            Some(n) => {
                c.set(Some(n - 1));
                Ok(())
            }
            None => Ok(()),
        })
    }
}

/// `ln det R` of a diagonal `R` given as its variances.
fn ln_det(r: &[f64]) -> f64 {
    r.iter().map(|v| v.ln()).sum::<f64>()
}

/// The noise variances from the residuals `e` and their mean squares `ms`: the ML mean
/// squares, or the robust (MAD) ones with Huber's weights.
fn noise_variances(robust: Option<Huber>, e: &[f64], ms: Vec<f64>) -> Vec<f64> {
    match robust {
        Some(_) => robust_variances(e, ms),
        None => ms,
    }
}

/// `β + Δ`.
fn offset(beta: &[f64], d: &DVector<f64>) -> Vec<f64> {
    beta.iter().zip(d.iter()).map(|(b, d)| b + d).collect()
}

/// The merit a step must lower (module doc): `ln det R` for the concentrated step, Huber's
/// cost at the fixed scale `sd` for the robust (IRLS) fit, else `J` at the fixed weights `w`.
fn merit(
    robust: Option<Huber>,
    concentrated: bool,
    w: &[f64],
    sd: &[f64],
    e: &[f64],
    r: &[f64],
) -> f64 {
    match robust {
        _ if concentrated => ln_det(r),
        Some(h) => huber_cost(h, e, sd),
        None => weighted_cost(e, w),
    }
}

/// The output-error iteration's state: the iterate β with its residuals and noise variances,
/// the Levenberg–Marquardt λ, the log, and the buffers every simulation reuses (allocated once
/// for the whole fit, not per trial).
struct OeIterate<'a> {
    p: &'a Problem,
    config: &'a OeConfig,
    beta: Vec<f64>,
    /// Residuals at β.
    e: Vec<f64>,
    /// Noise variances per output at β.
    r: Vec<f64>,
    lambda: f64,
    log: Vec<OeIteration>,
    /// Outputs at β.
    y: Vec<f64>,
    /// Output sensitivities at β.
    s: Vec<f64>,
    /// Outputs and residuals of the damped trials.
    y_try: Vec<f64>,
    e_try: Vec<f64>,
    /// Residuals of the parabolic-length trial.
    e_ext: Vec<f64>,
    /// The last iterate whose outputs and sensitivities were both formed: β and the length
    /// of the log up to it (`None` before the first linearization).
    good: Option<(Vec<f64>, usize)>,
}

/// The iteration's linearization at β, fixed over its trials: weights `w = 1/R`, scale
/// `sd = √R`, information matrix `M`, gradient `g`, step matrix `H`, `M⁻¹` (for the step in
/// Cramér–Rao σ) and the merit at β.
struct Linearization {
    robust: Option<Huber>,
    concentrated: bool,
    w: Vec<f64>,
    sd: Vec<f64>,
    m: DMatrix<f64>,
    g: DVector<f64>,
    h: DMatrix<f64>,
    minv: Option<DMatrix<f64>>,
    merit0: f64,
    /// d merit / dα along a step Δ is `merit_slope · gᵀΔ` (module doc, "Step length").
    merit_slope: f64,
}

/// A step that lowered the merit: the new β, the step Δ, the noise variances and the merit at
/// the new β (its residuals are in the iterate's `e_try`).
struct Trial {
    beta: Vec<f64>,
    step: DVector<f64>,
    r: Vec<f64>,
    merit: f64,
}

impl Linearization {
    /// [`merit`] at this linearization's weights.
    fn merit(&self, e: &[f64], r: &[f64]) -> f64 {
        merit(self.robust, self.concentrated, &self.w, &self.sd, e, r)
    }

    /// The largest component of `step` in Cramér–Rao σ of its unknown (∞ without `M⁻¹`).
    fn step_sigma(&self, step: &DVector<f64>) -> f64 {
        match &self.minv {
            Some(mi) => {
                (0..mi.nrows()).map(|i| step[i].abs() / mi[(i, i)].sqrt()).fold(0.0, f64::max)
            }
            None => f64::INFINITY,
        }
    }

    /// Whether the undamped (Gauss–Newton) step exists and is below `tolerance_sigma`: a fit
    /// with no descent left has then converged rather than failed.
    fn undamped_step_below(&self, tolerance_sigma: f64) -> bool {
        damped_step(&self.h, &self.m, &self.g, 0.0)
            .is_some_and(|st| self.step_sigma(&st) < tolerance_sigma)
    }
}

impl<'a> OeIterate<'a> {
    /// The state at the first starting value that simulates ([`first_start`]), with its
    /// log entry 0; also returns that start `θ0` (for the result).
    fn new(
        p: &'a Problem,
        manoeuvres: &[&[AirDataSample]],
        config: &'a OeConfig,
    ) -> Result<(Self, Vec<f64>), OeError> {
        let mut y = Vec::new();
        let mut e = Vec::new();
        let (beta, start) =
            first_start(p, manoeuvres, config, |beta| p.simulate(beta, &mut y, None))?;
        let ms = residuals(p, &y, &mut e);
        let r = noise_variances(config.robust, &e, ms);
        let log = vec![OeIteration {
            iteration: 0,
            ln_det_r: ln_det(&r),
            cost: 0.5 * (p.n_samples * p.ny()) as f64,
            lambda: 0.0,
            max_step_sigma: f64::NAN,
        }];
        let it = Self {
            p,
            config,
            beta,
            e,
            r,
            lambda: 0.0,
            log,
            y,
            s: Vec::new(),
            y_try: Vec::new(),
            e_try: Vec::new(),
            e_ext: Vec::new(),
            good: None,
        };
        Ok((it, start))
    }

    /// The iterations until convergence, no descent, a stop, a numerical failure or the
    /// iteration limit: whether both criteria were met and, if not, why.
    ///
    /// # Errors
    /// When the starting point cannot be linearized, or on a failure that is not numerical.
    fn run(&mut self) -> Result<(bool, Option<NotConverged>), OeError> {
        let config = self.config;
        for iteration in 1..=config.max_iterations {
            if stop_raised(config.stop.as_ref()) {
                return Ok((false, Some(NotConverged::Stopped)));
            }
            let lin = match self.linearize() {
                Ok(lin) => lin,
                Err(err) => return Ok((false, Some(self.fall_back(err)?))),
            };
            self.good = Some((self.beta.clone(), self.log.len()));
            let mut accepted = self.damped_search(&lin);
            // The undamped step was accepted (λ is left as it was on acceptance).
            if self.lambda == 0.0
                && let Some(trial) = accepted.as_mut()
            {
                self.try_parabolic_length(&lin, trial);
            }
            let Some(trial) = accepted else {
                if stop_raised(config.stop.as_ref()) {
                    return Ok((false, Some(NotConverged::Stopped)));
                }
                // No descent: converged if the undamped step is already negligible.
                return Ok(if lin.undamped_step_below(config.step_tolerance_sigma) {
                    (true, None)
                } else {
                    (false, Some(NotConverged::NoDescent))
                });
            };
            if self.accept(iteration, &lin, trial) {
                return Ok((true, None));
            }
        }
        Ok((false, Some(NotConverged::MaxIterations)))
    }

    /// After `err` at the current iterate: back to the last iterate whose sensitivities were
    /// formed (its outputs simulated again, its log entry the last), returning the reason the
    /// fit then ends with. An accepted iterate was flown, so only its sensitivities can fail;
    /// the iterations' work up to it is kept rather than lost to the step after.
    ///
    /// # Errors
    /// `err` itself when it is not numerical or no earlier iterate was linearized (the start
    /// cannot be flown).
    fn fall_back(&mut self, err: OeError) -> Result<NotConverged, OeError> {
        let why = match &err {
            OeError::Estimator(e) => NotConverged::numerical(e),
            OeError::NotConverged { .. } => None,
        };
        let (Some(why), Some((beta, log_len))) = (why, self.good.take()) else {
            return Err(err);
        };
        if beta == self.beta {
            return Err(err);
        }
        self.p.simulate(&beta, &mut self.y, None)?;
        let ms = residuals(self.p, &self.y, &mut self.e);
        self.r = noise_variances(self.config.robust, &self.e, ms);
        self.beta = beta;
        self.log.truncate(log_len);
        Ok(why)
    }

    /// The result at the final iterate, or at the last good one when the final iterate's
    /// sensitivities cannot be formed ([`OeIterate::fall_back`]).
    fn conclude(
        mut self,
        start: Vec<f64>,
        converged: bool,
        failure: Option<NotConverged>,
    ) -> Result<OeResult, OeError> {
        let (p, config) = (self.p, self.config);
        let tolerance = config.cost_tolerance;
        let failure = failure.unwrap_or(NotConverged::MaxIterations);
        let termination = Termination::of(&self.log, converged, failure, tolerance);
        // The iterations' buffers go before `finish` simulates the sensitivities again: on a
        // long record each sensitivity array is the largest allocation of the fit.
        for buffer in [&mut self.s, &mut self.y, &mut self.y_try, &mut self.e_try, &mut self.e_ext]
        {
            *buffer = Vec::new();
        }
        let (beta, r, e) = (&self.beta, &self.r, &self.e);
        let log = self.log.clone();
        match finish(p, &config.structure, beta, r, e, log, start.clone(), termination, config) {
            Ok(result) => Ok(result),
            Err(err) => {
                let why = self.fall_back(err.into())?;
                let termination = Termination::of(&self.log, false, why, tolerance);
                let (beta, r, e, log) = (&self.beta, &self.r, &self.e, self.log);
                Ok(finish(p, &config.structure, beta, r, e, log, start, termination, config)?)
            }
        }
    }

    /// Simulates β with its sensitivities and forms the normal equations and the step matrix
    /// (module doc): the relaxation's `M` with `J` at fixed `R`, or the concentrated Hessian
    /// (`M` where that is not positive definite) with `ln det R`. The robust fit is an IRLS
    /// relaxation: the weights and the scale fixed over the step, which is accepted when
    /// Huber's cost at that scale falls.
    fn linearize(&mut self) -> Result<Linearization, OeError> {
        let (p, config) = (self.p, self.config);
        if self.r.iter().any(|v| v.is_nan() || *v <= 0.0) {
            return Err(EstimatorError::Numerical {
                what: "an output's residuals are all zero: its noise variance cannot be estimated",
                t_s: 0.0,
            }
            .into());
        }
        let robust = config.robust;
        let w: Vec<f64> = self.r.iter().map(|v| 1.0 / v).collect();
        let u = robust.map_or_else(Vec::new, |h| huber_weights(h, &self.e, &self.r));
        let sd: Vec<f64> = self.r.iter().map(|v| v.sqrt()).collect();
        simulate_sensitivities(p, &self.beta, &mut self.y, &mut self.s)?;
        let (m, g, gj) = normal_equations_weighted(&self.s, &self.e, &w, &u, p.n_unknowns);
        check_identifiable(&m, p, &config.structure)?;
        let minv = spd_inverse(&m);
        let concentrated = config.step == StepKind::Concentrated && robust.is_none();
        let h = if concentrated {
            let h = concentrated_hessian(&m, &gj, p.n_samples);
            if h.clone().cholesky().is_some() { h } else { m.clone() }
        } else {
            m.clone()
        };
        let merit0 = merit(robust, concentrated, &w, &sd, &self.e, &self.r);
        let merit_slope = if concentrated { -2.0 / p.n_samples as f64 } else { -1.0 };
        Ok(Linearization { robust, concentrated, w, sd, m, g, h, minv, merit0, merit_slope })
    }

    /// Levenberg–Marquardt: the first step from λ (raised ×10 from 10⁻³ up to 10¹⁰) that
    /// simulates and lowers the merit, or `None`. A stop asked for during the damping ends it
    /// too: each trial is a simulation of the whole record, and up to 14 of them may follow.
    fn damped_search(&mut self, lin: &Linearization) -> Option<Trial> {
        let p = self.p;
        while !stop_raised(self.config.stop.as_ref()) {
            if let Some(step) = damped_step(&lin.h, &lin.m, &lin.g, self.lambda) {
                let trial = offset(&self.beta, &step);
                if p.simulate(&trial, &mut self.y_try, None).is_ok() {
                    let ms = residuals(p, &self.y_try, &mut self.e_try);
                    let r_try = noise_variances(lin.robust, &self.e_try, ms);
                    let value = lin.merit(&self.e_try, &r_try);
                    if value.is_finite() && value < lin.merit0 {
                        return Some(Trial { beta: trial, step, r: r_try, merit: value });
                    }
                }
            }
            self.lambda = if self.lambda == 0.0 { 1e-3 } else { self.lambda * 10.0 };
            if self.lambda > 1e10 {
                break;
            }
        }
        None
    }

    /// After an accepted undamped step: one more trial at the minimum of the parabola through
    /// the merit at 0 (value and slope) and at the full step (module doc, "Step length"),
    /// replacing `accepted` when it lowers the merit further.
    fn try_parabolic_length(&mut self, lin: &Linearization, accepted: &mut Trial) {
        let slope = lin.merit_slope * lin.g.dot(&accepted.step);
        let Some(a) = parabolic_step(lin.merit0, slope, accepted.merit) else {
            return;
        };
        let p = self.p;
        let scaled = &accepted.step * a;
        let trial = offset(&self.beta, &scaled);
        if p.simulate(&trial, &mut self.y_try, None).is_ok() {
            let ms = residuals(p, &self.y_try, &mut self.e_ext);
            let r_try = noise_variances(lin.robust, &self.e_ext, ms);
            let v = lin.merit(&self.e_ext, &r_try);
            if v.is_finite() && v < accepted.merit {
                core::mem::swap(&mut self.e_try, &mut self.e_ext);
                *accepted = Trial { beta: trial, step: scaled, r: r_try, merit: v };
            }
        }
    }

    /// Moves β to the accepted trial, relaxes λ (÷10, to 0 below 10⁻⁶) and logs the
    /// iteration; `true` when both the relative change of `det R` and the step (in σ) are
    /// below their tolerances.
    fn accept(&mut self, iteration: usize, lin: &Linearization, trial: Trial) -> bool {
        let max_step_sigma = lin.step_sigma(&trial.step);
        let used_lambda = self.lambda;
        self.lambda = if self.lambda < 1e-6 { 0.0 } else { self.lambda / 10.0 };
        let rel = (ln_det(&trial.r) - ln_det(&self.r)).exp_m1().abs();
        self.beta = trial.beta;
        core::mem::swap(&mut self.e, &mut self.e_try);
        self.r = trial.r;
        self.log.push(OeIteration {
            iteration,
            ln_det_r: ln_det(&self.r),
            cost: weighted_cost(&self.e, &lin.w),
            lambda: used_lambda,
            max_step_sigma,
        });
        rel < self.config.cost_tolerance && max_step_sigma < self.config.step_tolerance_sigma
    }
}

/// The prepared problem of `config` over `manoeuvres` (outputs from the data by default).
fn prepare(manoeuvres: &[&[AirDataSample]], config: &OeConfig) -> Result<Problem, OeError> {
    let model = FlightModel::new(config.structure)?;
    let set = model.state_set();
    let first =
        manoeuvres.first().and_then(|m| m.first()).ok_or(EstimatorError::InvalidConfig {
            field: "manoeuvres",
            value: 0.0,
            reason: "at least one manoeuvre with samples is needed",
        })?;
    let outputs = config.outputs.clone().unwrap_or_else(|| default_outputs(set, first));
    let x0_free = match config.initial_states {
        InitialStates::FirstSample => [false; N_STATES],
        InitialStates::Estimate(mask) => mask,
    };
    Ok(Problem::new(model, manoeuvres, outputs, &config.output_biases, &x0_free)?)
}

/// The first starting value of [`Start`] from which `run` (a simulation or a filter pass at
/// `β`) succeeds: `(β, θ0)` with biases 0 and free initial states at the first sample; the
/// equation-error start falls back to the generic priors.
fn first_start(
    p: &Problem,
    manoeuvres: &[&[AirDataSample]],
    config: &OeConfig,
    mut run: impl FnMut(&[f64]) -> Result<(), EstimatorError>,
) -> Result<(Vec<f64>, Vec<f64>), OeError> {
    let np = config.structure.n_params();
    let starts: Vec<Vec<f64>> = match &config.start {
        Start::Given(v) => {
            if v.len() != np {
                return Err(EstimatorError::InvalidConfig {
                    field: "start",
                    value: v.len() as f64,
                    reason: "Start::Given needs one value per structure parameter",
                }
                .into());
            }
            vec![v.clone()]
        }
        Start::Priors => vec![priors_start(&config.structure)],
        Start::EquationError => {
            vec![
                equation_error_start(&config.structure, manoeuvres),
                priors_start(&config.structure),
            ]
        }
    };
    let mut beta = vec![0.0; p.n_unknowns];
    let mut last_err = None;
    for theta0 in starts {
        beta[..np].copy_from_slice(&theta0);
        for (m, man) in p.man.iter().enumerate() {
            for (q, &k) in p.x0_free.iter().enumerate() {
                beta[p.x0_index(m, q)] = man.x0_meas[k];
            }
        }
        match run(&beta) {
            Ok(()) => return Ok((beta, theta0)),
            Err(err) => last_err = Some(err),
        }
    }
    Err(last_err
        .unwrap_or(EstimatorError::Numerical { what: "no starting values", t_s: 0.0 })
        .into())
}

fn priors_start(structure: &ModelStructure) -> Vec<f64> {
    let pr = Priors::generic(structure);
    (0..structure.n_params()).map(|i| pr.prior[i].value).collect()
}

/// Refuses an unknown with no effect on any output (a zero column of `S`).
fn check_identifiable(
    m: &DMatrix<f64>,
    p: &Problem,
    structure: &ModelStructure,
) -> Result<(), EstimatorError> {
    for i in 0..m.nrows() {
        if !(m[(i, i)] > 0.0 && m[(i, i)].is_finite()) {
            let field = if i < p.np {
                structure.param(i).map_or("parameter", |q| q.name())
            } else if i < p.np + p.n_biases() {
                "output bias"
            } else {
                "initial state"
            };
            return Err(EstimatorError::InvalidConfig {
                field,
                value: i as f64,
                reason: "this unknown does not affect any selected output",
            });
        }
    }
    Ok(())
}

/// Names of the unknowns `β` in order ([`OeResult::names`]): the structure's parameters,
/// `bias_<output>`, `x0_m<k>_<state>`.
fn unknown_names(p: &Problem, structure: &ModelStructure) -> Vec<String> {
    let mut names: Vec<String> = structure.names().map(String::from).collect();
    // Biases in β order (declaration order).
    let mut bias_names: Vec<(usize, String)> = p
        .bias_of
        .iter()
        .enumerate()
        .filter_map(|(j, b)| b.map(|b| (b, format!("bias_{}", p.outputs[j].name()))))
        .collect();
    bias_names.sort();
    names.extend(bias_names.into_iter().map(|(_, n)| n));
    let states = p.model.state_set().states();
    for m in 0..p.man.len() {
        for &k in &p.x0_free {
            names.push(format!("x0_m{}_{}", m + 1, STATE_NAMES[states[k]]));
        }
    }
    names
}

#[allow(clippy::too_many_arguments)]
fn finish(
    p: &Problem,
    structure: &ModelStructure,
    beta: &[f64],
    r: &[f64],
    e: &[f64],
    iterations: Vec<OeIteration>,
    start: Vec<f64>,
    termination: Termination,
    config: &OeConfig,
) -> Result<OeResult, EstimatorError> {
    let w: Vec<f64> = r.iter().map(|v| 1.0 / v).collect();
    let u = config.robust.map_or_else(Vec::new, |h| huber_weights(h, e, r));
    let mut y = Vec::new();
    let mut s = Vec::new();
    simulate_sensitivities(p, beta, &mut y, &mut s)?;
    let fit = Fitted { beta, s: &s, e, w: &w, u: &u, r, names: unknown_names(p, structure) };
    assemble(p, structure, fit, iterations, start, termination, config)
}

/// A converged (or last) iterate, ready for [`assemble`]: unknowns, sensitivities of the
/// predicted outputs (`N·ny × nβ` row-major), residuals `z − ŷ`, weights `1/B` (per output:
/// inverse of the residual variance), Huber's weight per residual (empty: none), the reported
/// noise variances and the unknowns' names.
struct Fitted<'a> {
    beta: &'a [f64],
    s: &'a [f64],
    e: &'a [f64],
    w: &'a [f64],
    u: &'a [f64],
    r: &'a [f64],
    names: Vec<String>,
}

/// The result of a fit: Cramér–Rao σ from `M = Σ Sᵀ W S`, correlations, coloured-residual σ
/// and residual statistics (residual RMS `sqrt(1/w)`).
fn assemble(
    p: &Problem,
    structure: &ModelStructure,
    fit: Fitted<'_>,
    iterations: Vec<OeIteration>,
    start: Vec<f64>,
    termination: Termination,
    config: &OeConfig,
) -> Result<OeResult, EstimatorError> {
    let Fitted { beta, s, e, w, u, r, names } = fit;
    let nb = beta.len();
    let ny = p.ny();
    let (m, _, _) = normal_equations_weighted(s, e, w, u, nb);
    // Singular at the last iterate: its values are still the fit's answer, reported as not
    // converged with NaN σ (a caller's `null`), rather than no result at all.
    let inverse = spd_inverse(&m);
    let identified = inverse.is_some();
    let termination = if identified {
        termination
    } else {
        Termination::NotConverged(NotConverged::Unidentifiable)
    };
    let minv = inverse.unwrap_or_else(|| DMatrix::from_element(nb, nb, f64::NAN));
    let sigma: Vec<f64> = (0..nb).map(|i| minv[(i, i)].sqrt()).collect();
    let correlation: Vec<f64> = (0..nb * nb)
        .map(|k| {
            let (i, j) = (k / nb, k % nb);
            minv[(i, j)] / (sigma[i] * sigma[j])
        })
        .collect();
    let lengths: Vec<usize> = p.man.iter().map(|m| m.u.len()).collect();
    let max_lag =
        config.coloured_max_lag.unwrap_or_else(|| lengths.iter().copied().min().unwrap_or(4) / 4);
    let diag = |c: DMatrix<f64>| (0..nb).map(|i| c[(i, i)].sqrt()).collect::<Vec<_>>();
    let dominance = identified.then(|| dominance(&p.outputs, s, e, w, u, &minv)).flatten();
    // Huber's weights enter the σ as the weighted problem `√u e`, `√u S` (module doc).
    let (s_w, e_w);
    let (s, e_col) = if u.is_empty() {
        (s, e)
    } else {
        e_w = e.iter().zip(u).map(|(e, u)| e * u.sqrt()).collect::<Vec<_>>();
        s_w = s.iter().enumerate().map(|(k, v)| v * u[k / nb].sqrt()).collect::<Vec<_>>();
        (s_w.as_slice(), e_w.as_slice())
    };
    // A fit stopped on request reports its Cramér–Rao σ at once: the coloured forms cost
    // seconds on a long record (several sweeps over all residual lags), which the stop is for;
    // a stop raised while they are formed ends them at their next look (all three dropped).
    let stop = || stop_raised(config.stop.as_ref());
    let formed = if identified && !stop() {
        // The prewhitened form costs about as much as the other two together (a 60,000-
        // sample record: 5.5 s against 2.2 s), and they share nothing but their inputs:
        // on a second core the σ takes the time of the slowest form, not of all three.
        let (pre, other) = std::thread::scope(|scope| {
            let other = scope.spawn(|| {
                let truncated =
                    coloured::covariance_until(s, e_col, w, &lengths, &minv, max_lag, &stop)?;
                let spectral = coloured::spectral_until(s, e_col, w, &lengths, &minv, &stop)?;
                Some((truncated.covariance, spectral.covariance))
            });
            let pre = coloured::prewhitened_until(s, e_col, w, &lengths, &minv, max_lag, &stop);
            (pre, other.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
        });
        pre.zip(other)
    } else {
        None
    };
    let (sigma_coloured, sigma_coloured_prewhitened, sigma_coloured_truncated, lag, order) =
        match formed {
            Some((pre, (truncated, spectral))) => {
                let col = pre.coloured;
                let (lag, order) = (col.lag, pre.order);
                (spectral.map(diag), col.covariance.map(diag), truncated.map(diag), lag, order)
            }
            None => (None, None, None, 0, 0),
        };
    let n = p.n_samples as f64;
    let residual_mean: Vec<f64> =
        (0..ny).map(|j| e.iter().skip(j).step_by(ny).sum::<f64>() / n).collect();
    Ok(OeResult {
        structure: *structure,
        names,
        n_params: p.np,
        values: beta.to_vec(),
        sigma,
        sigma_coloured,
        sigma_coloured_prewhitened,
        coloured_lag: lag,
        coloured_ar_order: order,
        sigma_coloured_truncated,
        covariance: minv.transpose().as_slice().to_vec(),
        correlation,
        outputs: p.outputs.clone(),
        r: r.to_vec(),
        residual_rms: w.iter().map(|v| (1.0 / v).sqrt()).collect(),
        residual_mean,
        residuals: e.to_vec(),
        manoeuvre_lengths: lengths,
        iterations,
        start,
        restart: None,
        termination,
        unmeasured_states: p
            .unmeasured
            .iter()
            .map(|&k| STATE_NAMES[p.model.state_set().states()[k]])
            .collect(),
        dominance,
    })
}

/// The samples that weigh most on the fit (module doc, "Dominant samples"): the largest share
/// of the weighted cost `Σ u w e²` and the largest Cook's distance `g_iᵀ M⁻¹ g_i / nβ`;
/// `None` without samples.
fn dominance(
    outputs: &[Output],
    s: &[f64],
    e: &[f64],
    w: &[f64],
    u: &[f64],
    minv: &DMatrix<f64>,
) -> Option<Dominance> {
    let ny = w.len();
    let nb = minv.nrows();
    let uw = |k: usize| w[k % ny] * u.get(k).copied().unwrap_or(1.0);
    let total: f64 = e.iter().enumerate().map(|(k, v)| uw(k) * v * v).sum();
    let mut best: Option<Dominance> = None;
    let mut g = DVector::<f64>::zeros(nb);
    for i in 0..e.len() / ny {
        g.fill(0.0);
        let (mut chi2, mut top, mut top_j) = (0.0, -1.0, 0);
        for j in 0..ny {
            let k = i * ny + j;
            let term = uw(k) * e[k] * e[k];
            chi2 += term;
            if term > top {
                (top, top_j) = (term, j);
            }
            for a in 0..nb {
                g[a] += uw(k) * e[k] * s[k * nb + a];
            }
        }
        let cook = g.dot(&(minv * &g)) / nb as f64;
        let d = best.get_or_insert(Dominance {
            share_sample: i,
            share: 0.0,
            chi2,
            share_output: outputs[0],
            cook_sample: i,
            cook,
        });
        if chi2 >= d.chi2 {
            (d.share_sample, d.chi2, d.share_output) = (i, chi2, outputs[top_j]);
        }
        if cook >= d.cook {
            (d.cook_sample, d.cook) = (i, cook);
        }
    }
    best.map(|mut d| {
        d.share = if total > 0.0 { d.chi2 / total } else { 0.0 };
        d
    })
}

#[cfg(test)]
mod tests;
