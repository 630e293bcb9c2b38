//! The filter-error method: maximum-likelihood estimation with process noise, a steady-state
//! Kalman filter inside the cost (Jategaonkar, *Flight Vehicle System Identification*, 2nd
//! ed., AIAA 2015, ch. 5, the book's `ml_fem.m`; Maine & Iliff, NASA RP-1168, 1986, ch. 7).
//! Section and equation numbers are not quoted: they were not checked against the books.
//!
//! Output error ([`super::fit`]) treats everything the model does not explain as measurement
//! noise; in turbulence the aircraft's response to the gusts is then a slowly varying,
//! strongly coloured "residual", the estimates scatter far beyond the Cramér–Rao bound and
//! their σ is optimistic. The filter-error method models the gusts as process noise:
//!
//! ```text
//! ẋ = f(x, u, θ) + F w,   z_k = h(x_k, u_k, θ) + b + v_k,   w, v white, cov v = R
//! ```
//!
//! with `F` diagonal, one σ per state equation (units of the state per √s), estimated with
//! `θ` as `ln F` (positive by construction; the likelihood is far closer to quadratic in
//! `ln F` than in `F`: with `F` itself the Gauss–Newton steps of the slow `F_V` overshot and
//! alternated, measured on the F-16 campaign). Which state equations carry process noise is configurable
//! ([`FemConfig::process_noise`]); the default ([`AIR_DATA_STATES`]) is the translational
//! air-data states `V, α, β` of the structure's state set: a translational gust `(u_g, v_g,
//! w_g)` enters the air-relative `V, α, β` equations as its time derivative, which for the
//! Dryden spectrum is nearly white above `V/L` (≈ 0.4 rad/s for the F-16 campaign), while the
//! rate equations get no direct gust input.
//!
//! # The filter (per cost evaluation)
//!
//! Reuses the output-error problem (manoeuvres, outputs, biases, free initial states) and its
//! RK4 step (`output_error/simulation.rs`). At the unknowns `β = (θ, b, x0, F)`:
//!
//! 1. `A = ∂f/∂x`, `C = ∂h/∂x` ([`crate::flight_model::FlightModel::linearise`], exact) averaged over up to
//!    [`LINEARISATION_POINTS`] samples spread over the record, at their **measured** states
//!    (so the gain is a smooth function of `β`); `Φ = exp(A Δt)` with `Δt` the median sample
//!    interval; `Q = F Fᵀ Δt` (first order); the steady-state filter from the discrete
//!    Riccati equation with the current `R` ([`super::riccati`]).
//! 2. Per manoeuvre from its initial state: prediction `x̃_k` by the nonlinear model (RK4
//!    between samples, inputs linear), `ŷ_k = h(x̃_k) + b`, innovation `ν_k = z_k − ŷ_k`,
//!    correction `x̂_k = x̃_k + K ν_k`.
//!
//! With `F = 0` the gain is zero and the filter is the output-error simulation.
//!
//! # Estimation: maximum likelihood in `θ`, `F` and `R` together
//!
//! The negative log-likelihood of the innovations of the steady-state filter (prediction-error
//! form; Åström, "Maximum likelihood and prediction error methods", *Automatica* 16, 1980;
//! Maine & Iliff RP-1168 ch. 5), with the filter's own innovation variance
//! `b_j = diag(C P Cᵀ)_j + R_j` (diagonal, as output error's `R`):
//!
//! ```text
//! L(β, R) = ½ Σ_k Σ_j ν_kj² / b_j + (N/2) Σ_j ln b_j
//! ```
//!
//! is minimised over all unknowns `(θ, b, x0, ln F, ln R)` by Fisher scoring with
//! Levenberg–Marquardt damping: information `M = Σ Sᵀ W S + (N/2) Σ_j D_j D_jᵀ / b_j²` and
//! descent direction `g = Σ Sᵀ W ν − Σ_j D_j (N/(2 b_j) − Σ_k ν_kj²/(2 b_j²))`, with
//! `W = diag(1/b)`, `S = ∂ŷ/∂β` and `D_j = ∂b_j/∂β` (the information of a Gaussian whose
//! mean and variance both depend on the unknowns); a step is accepted when `L` falls. The
//! `ln F` and `ln R` components move by [`F_STEP`] (half) of their step, at most
//! [`MAX_LN_STEP`] (a factor 4): full steps alternated on the slowly identified `F_V`
//! (measured on the F-16 campaign), and unlimited ones overshot by orders of magnitude from
//! the start on the ATTAS elevator record. Both are bounded below
//! (`ln F` at [`F_MIN_FRACTION`], `ln R` at [`R_FLOOR`] of its start); a step beyond goes to
//! the bound, and a bounded unknown whose gradient points further down is held there (active
//! set: on calm data the information on `F` vanishes).
//!
//! **Why not the book's relaxation.** Jategaonkar's `ml_fem.m` alternates a Gauss–Newton step
//! on `(θ, F)` with the innovation covariance `B` held at its sample value, and an update of
//! `B` (here of `R` through the compatibility `R = B − C P Cᵀ`). With `B` held, a larger `F`
//! only shrinks the innovations (the filter follows the measurements); the growth of the
//! filter's own innovation variance, the `ln det` term that balances it in the likelihood, is
//! not in that step. On a record with model error the two steps then feed each other: `F`
//! grows, the compatibility lowers `R`, the gain grows. The book bounds this with the
//! constraint `diag(K C) ≤ 1` and a heuristic `F` correction; measured here on the HFB-320
//! record with Jategaonkar's model (`models/hfb320_jategaonkar.toml`), the relaxation drove
//! `F_α` from 10⁻⁴ to 500 rad/√s and `R` of five outputs to its floor while `ln det B` rose
//! from −68.9 (iteration 7) to −60.0, and stopped without a descent direction; with `R` fixed
//! but the `ln det` term in the step, `R_α` still ran to 0.5 % of `B_α`. With the likelihood
//! in all unknowns the fit converges (31 iterations, 1.1 s, `ln det B` −69.16 against output
//! error's −54.17), with `F_V` 0.34 m/s/√s and `F_α` 0.0027 rad/√s. On the ATTAS records the
//! relaxation converged but to far worse likelihoods at implausible process noise (Elv1:
//! `F_α` 384 rad/√s, `ln det B` −58.2; Ail1: `F_β` 0.17 rad/√s, −67.8); maximum likelihood
//! gives −67.9 (`F_α` 0.0015) and −68.7 (`F_β` 0.0018). On the synthetic
//! coloured-process-noise records of the tests 16 of 16 fits converge (12 with the
//! relaxation).
//!
//! # The gain constraint
//!
//! Jategaonkar's filter-error method holds every diagonal element of `K C` (`nx × nx`) at or
//! below 1 (2015 ch. 5; `kcle1.m`, called from `ml_fem.m` after each Gauss–Newton step): a
//! correction may remove at most a state's whole prediction error, never over-correct it. The
//! book linearises `diag(K C)` in the step, `kc + G Δ` (`G` its gradient, from the perturbed
//! gains of the sensitivities), and for the elements whose prediction exceeds 1 replaces the
//! step by the minimum of the quadratic model on those constraints held as equalities:
//! `Δ ← Δ − M⁻¹ Gᵀ (G M⁻¹ Gᵀ)⁻¹ s`, `s` the excesses. Built here the same way
//! ([`FemConfig::gain_limit`], default [`GAIN_LIMIT`] = 1, `None` to switch it off), in all
//! unknowns (`θ`, `ln F`, `ln R`; biases and initial states do not move the gain) with two
//! additions: the metric is the damped `M + λ diag M` of the trial (the constrained minimum of
//! the model that step minimises), and the projection is redone when it pushes another element
//! over (at most `nx` rounds). The linearisation is exact to first order only, so a trial is
//! also checked with its own gain: one with an element above the bound plus [`KC_TOLERANCE`]
//! (and above the iterate's) is rejected like one that raises the cost, and the damping grows.
//! Cramér–Rao σ are those of the unconstrained information, as the book's.
//!
//! **Where it binds.** In the book the innovation covariance `B` is the residuals' sample
//! covariance and the gain `P Cᵀ B⁻¹` with `P` from the continuous Riccati equation: nothing
//! ties `C P Cᵀ` to stay below `B`, and `(K C)_jj > 1` for a state measured alone means the
//! implied measurement noise `B − C P Cᵀ` is negative (Maine & Iliff RP-1168 discuss the same
//! compatibility). Here `R` is an unknown of its own, positive by construction, and `K = P Cᵀ
//! (C P Cᵀ + R)⁻¹`: for a state measured by one output alone `(K C)_jj = P_jj / (P_jj + R_j)
//! < 1`. Only cross-coupling through the other outputs (the accelerations) can carry an
//! element over 1. Measured: on the HFB-320 record (process noise on `V, α, θ, q`) the free
//! fit ends at `diag(K C)` = 0.974, 0.994, 0.340, 0.9993 and the constraint changes nothing
//! (docs/uncertainty.md, "Filter-error method: the gain constraint"); on the synthetic records
//! of the tests it stays below 1 too. The `R` floor ([`R_FLOOR`]), active on the HFB-320's
//! `q`, is what bounds the gain there.
//!
//! **Steps that leave the physical domain.** A trial whose filter pass fails (a state
//! non-finite, `V ≤ 0`, `|α|` or `|β|` over 1.5 rad, no stabilising Riccati solution) or whose
//! likelihood is not finite is rejected and the step shortened by more damping; only when no
//! damping up to 10¹⁰ gives a lower cost does the fit stop ([`NotConverged::NoDescent`]).
//! An accepted iterate's sensitivities that cannot be formed (both passes of a difference
//! failing, at the next iteration or at the end) end the fit at the last iterate whose were,
//! as [`NotConverged::NumericalFailure`] (output error's module doc, "Numerical failure").
//!
//! **Sensitivities** `S = ∂ŷ/∂β` and `D_j = ∂b_j/∂β` by central differences of the **whole
//! filter**, as `ml_fem.m`: each unknown (`ln R` included) perturbed by
//! `±10⁻⁴ max(|β_i|, 10⁻³)`, the gain recomputed for the perturbed values (the innovations
//! depend on `F` and `R` only through the gain, so it must be). `2 (nβ + ny)` filter passes
//! per iteration.
//!
//! **Convergence** as output error: the change of `2L/N` (≈ the relative change of `det B`)
//! below [`super::OeConfig::cost_tolerance`] and the largest step below
//! [`super::OeConfig::step_tolerance_sigma`] Cramér–Rao σ. A fit that reaches the iteration
//! limit or stops descending with a large step is [`OeError::NotConverged`] (never a result).
//!
//! # Starting values
//!
//! `θ`, the biases and the free initial states from the output-error fit of the same record
//! ([`FemConfig::start_from_output_error`]; Jategaonkar 2015 ch. 5 starts the filter-error
//! method from output error's estimates); when that fit fails or the filter cannot run at its
//! result, `θ` as output error starts ([`super::Start`]) and the initial states at the first
//! samples. `R` from the second differences of each measured
//! output (`Σ (z_{k+1} − 2 z_k + z_{k−1})² / (6 (N − 2))`, the white-noise variance of a
//! smooth signal); `F` from [`FemConfig::process_noise_start`], else
//! `0.1 sqrt(R_j / Δt)` of the output measuring the state (10⁻³ when none does).
//!
//! # Data
//!
//! The measurement errors must be white from sample to sample: on pre-smoothed records (the
//! campaign's matched smoother) the one-step predictor follows the smoothed noise and `F`
//! grows without bound (measured; the campaign fits the unsmoothed samples).
//!
//! # Accuracy
//!
//! Cramér–Rao σ `sqrt(diag M⁻¹)` with `M = Σ Sᵀ B⁻¹ S` at the estimate
//! ([`OeResult::sigma`]), and the coloured-residual sandwich ([`OeResult::sigma_coloured`],
//! Morelli & Klein 1997, full cross-output residual autocorrelation, from a multitaper
//! estimate of the innovations' cross-spectral matrix as for output error:
//! [`crate::coloured::batch`], "Spectral form"). Jategaonkar ch. 5 takes
//! the innovations of the correct filter as white, so that the Cramér–Rao σ suffices; that
//! needs the filter's model exact, process noise included. A flight-test model never is: on
//! the F-16 campaign (Dryden turbulence, whose `ġ` is coloured below `V/L`; no process noise
//! on the rate equations; lateral model error) the innovations are autocorrelated over
//! hundreds of samples and the Cramér–Rao σ is 0.34–0.76 of the scatter of the estimates,
//! the coloured one 0.68–1.69 with the lag-truncated sandwich (40 runs; docs/uncertainty.md,
//! "Filter-error method: σ and bias"), 0.60–1.86 with the prewhitened one (20 runs, "Where
//! the targets stand") and, in the 20-run campaign after the merges, 0.63–2.29 with the
//! spectral one now used (prewhitened 0.58–3.44; docs/uncertainty.md, "Output error: the
//! spectral coloured-residual σ"). Callers therefore report the coloured σ where formed, as for output error
//! (`aeroident_pipelines::replay::batch::fem_reported_sigma`). Diagnostics: the lag-0 sandwich with the
//! full cross-output innovation covariance ([`FemResult::sigma_lag0`]) and the full-`B`
//! Cramér–Rao σ ([`FemResult::sigma_full_b`]) are within 6 % of the Cramér–Rao σ there (the
//! cross-correlation through the gain is not what makes it short);
//! [`FemResult::sigma_coloured_theta`] is the coloured σ when only the `F` block of the
//! sandwich is not positive. `F` and its σ are reported from `ln F` to first order
//! (`σ_F = F σ_ln F`, covariance rows scaled by `F`).
//!
//! The biases once seen on that campaign and shared with output error (Cl_p +2.8 %, Cl_δa
//! +1.9 %, Cm_q +2.2 %, Cn_δr +2.4 % of the truth) were the simulator's inputs held over each
//! integration step, a dt/2 lag (docs/uncertainty.md, "Bias: the staircase inputs"); what
//! remains is amplitude-dependent model structure. Cn_r's dependence on the process-noise
//! model is this method's: `F` absorbs lateral model error.

use super::riccati;
use super::simulation::Problem;
use super::{
    Fitted, NotConverged, OeConfig, OeError, OeIteration, OeResult, Termination, assemble,
    damped_step, first_start, normal_equations, prepare, residuals, spd_inverse, unknown_names,
    weighted_cost,
};
use crate::EstimatorError;
use crate::coloured::batch as coloured;
use crate::flight_model::{Linearisation, N_STATES, Output, STATE_NAMES, state};
use crate::sample::AirDataSample;
use crate::vocabulary::ModelStructure;
use core::fmt;
use nalgebra::DMatrix;
use std::boxed::Box;
use std::format;
use std::vec;
use std::vec::Vec;

/// The default process-noise states (full-state order `(V, α, β, p, q, r, φ, θ)`): the
/// translational air-data states `V, α, β` (module doc).
pub const AIR_DATA_STATES: [bool; N_STATES] = {
    let mut m = [false; N_STATES];
    m[state::V] = true;
    m[state::ALPHA] = true;
    m[state::BETA] = true;
    m
};

/// Most samples at which `A` and `C` are linearised and averaged (module doc).
pub const LINEARISATION_POINTS: usize = 50;

/// Lower bound of each process-noise σ, as a fraction of `sqrt(R_j / Δt)` of the output
/// measuring the state (`10⁻²` state units per √s when none does): the gain goes with `F²`, so
/// at the bound the process noise no longer affects the filter (`ln F` cannot run to `−∞` on
/// calm data, where the information on it vanishes).
pub const F_MIN_FRACTION: f64 = 1e-3;

/// Fraction of the scoring step taken in `ln F` and `ln R` (module doc).
pub const F_STEP: f64 = 0.5;

/// Largest change of an `ln F` or `ln R` in one iteration (a factor 4; module doc): far from
/// the optimum the scoring information of the noise unknowns is poor, and an unlimited first
/// step multiplied `R` by 10¹⁰ on the ATTAS elevator record.
pub const MAX_LN_STEP: f64 = core::f64::consts::LN_2 * 2.0;

/// The book's bound of every `diag(K C)` element ([`FemConfig::gain_limit`]'s default): a
/// correction may remove at most the whole prediction error of a state, never more
/// (Jategaonkar 2015 ch. 5, `kcle1.m`).
pub const GAIN_LIMIT: f64 = 1.0;

/// Largest excess of a `diag(K C)` element over its limit that an accepted step may leave
/// ([`FemConfig::gain_limit`]): the projection onto the linearised constraint is exact to
/// first order in the step only, and a trial beyond this is rejected like one that raises the
/// cost (the damping grows, the step shortens).
pub const KC_TOLERANCE: f64 = 1e-3;

/// Lower bound of each measurement-noise variance `R_j`, as a fraction of its starting value
/// (the second-difference estimate of the output's white noise; module doc).
pub const R_FLOOR: f64 = 1e-3;

/// Configuration of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FemConfig {
    /// Everything output error has (structure, outputs, biases, initial states, start,
    /// iterations, tolerances, coloured lag); its `step` is not used (always the scoring step
    /// of the module doc).
    pub oe: OeConfig,
    /// State equations with process noise, full-state order; only integrated states count
    /// (default [`AIR_DATA_STATES`]).
    pub process_noise: [bool; N_STATES],
    /// Starting values of `F` (state units per √s), one per process-noise state of the state
    /// set in filter order; `None`: from the measurement noise (module doc).
    pub process_noise_start: Option<Vec<f64>>,
    /// Upper bound of every diagonal element of the gain product `K C` (`nx × nx`,
    /// dimensionless); `None`: unconstrained. Default [`GAIN_LIMIT`] (1, Jategaonkar 2015
    /// ch. 5, `kcle1.m`; module doc, "The gain constraint").
    pub gain_limit: Option<f64>,
    /// Start `θ`, the biases and the initial states from the output-error fit of the same
    /// record (default true; module doc, "Starting values"); false: from
    /// [`OeConfig::start`] as output error itself starts.
    pub start_from_output_error: bool,
}

impl FemConfig {
    /// [`OeConfig::new`]'s defaults with process noise on [`AIR_DATA_STATES`].
    pub fn new(structure: ModelStructure) -> Self {
        Self {
            oe: OeConfig::new(structure),
            process_noise: AIR_DATA_STATES,
            process_noise_start: None,
            gain_limit: Some(GAIN_LIMIT),
            start_from_output_error: true,
        }
    }
}

/// The result of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FemResult {
    /// The common part, as output error's: unknowns `(θ, b, x0, F)` with names
    /// (`F_<state>` for the process noise, e.g. `F_alpha_rad`), values, Cramér–Rao σ,
    /// covariance and correlation; `r` the measurement-noise variances `R`; `residuals` the
    /// innovations `ν`, `residual_rms` their RMS `sqrt(B)`; `iterations` with `ln_det_r` =
    /// `ln det B` (the innovations' sample variances) and `cost` = the negative
    /// log-likelihood `L` of the module doc.
    pub result: OeResult,
    /// Full-state indices of the process-noise states, in the order of the `F` unknowns.
    pub process_noise_states: Vec<usize>,
    /// Index of the first `F` unknown in `result.values`.
    pub first_f: usize,
    /// `diag(C K)` per output of the final filter (`C P Cᵀ S⁻¹`: 0, the output does not
    /// correct the state; → 1, the filter follows the measurement).
    pub ck_diag: Vec<f64>,
    /// `diag(K C)` per integrated state of the final filter, in the order of
    /// [`FemResult::kc_states`] (dimensionless: the fraction of a state's prediction error
    /// that one correction removes; the gain constraint holds it at or below 1).
    pub kc_diag: Vec<f64>,
    /// Full-state indices of the integrated states, the order of [`FemResult::kc_diag`].
    pub kc_states: Vec<usize>,
    /// Diagnostic σ of every unknown (order of `result.values`, `F` as `F`): the sandwich
    /// `M⁻¹ (Σ Sᵀ B⁻¹ r̂(0) B⁻¹ S) M⁻¹` with the lag-0 innovation covariance `r̂(0) = (1/N) Σ ν νᵀ`
    /// in full (innovations cross-correlated across outputs but white in time); `None` when a
    /// diagonal element is not positive. Between [`OeResult::sigma`] (`r̂(0)` diagonal) and
    /// [`OeResult::sigma_coloured`] (all lags).
    pub sigma_lag0: Option<Vec<f64>>,
    /// Diagnostic σ of every unknown: `sqrt(diag M_B⁻¹)`, `M_B = Σ Sᵀ r̂(0)⁻¹ S` with the full
    /// innovation covariance, the Cramér–Rao σ of an estimator that weighted the innovations by
    /// the full `B` (this one weights by its diagonal); `None` when `r̂(0)` or `M_B` is singular.
    pub sigma_full_b: Option<Vec<f64>>,
    /// Diagnostic σ of every unknown from the prewhitened coloured-residual sandwich
    /// ([`OeResult::sigma_coloured_prewhitened`]'s form), formed whenever the diagonal of the
    /// structure-parameter block is positive (`OeResult::sigma_coloured` needs every unknown,
    /// `F` included, and is `None` on the F-16 campaign); an `F` entry that is not positive is
    /// NaN.
    pub sigma_coloured_theta: Option<Vec<f64>>,
}

impl FemResult {
    /// `(F, σ)` of the process noise on full-state index `i`, if estimated.
    pub fn process_noise(&self, i: usize) -> Option<(f64, f64)> {
        let q = self.process_noise_states.iter().position(|&s| s == i)?;
        let k = self.first_f + q;
        Some((self.result.values[k], self.result.sigma[k]))
    }
}

impl fmt::Display for FemResult {
    /// Output error's summary (with `R` as the measurement noise and the innovations as
    /// residuals), then the process noise and `diag(K C)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "filter error (ML with process noise; ln det R below is ln det B):")?;
        write!(f, "{}", self.result)?;
        writeln!(f, "{:<14} {:>12} {:>12}", "output", "R", "diag(CK)")?;
        for (j, o) in self.result.outputs.iter().enumerate() {
            writeln!(f, "{:<14} {:>12.5e} {:>12.4}", o.name(), self.result.r[j], self.ck_diag[j])?;
        }
        writeln!(f, "{:<14} {:>12}", "state", "diag(KC)")?;
        for (&i, v) in self.kc_states.iter().zip(&self.kc_diag) {
            writeln!(f, "{:<14} {:>12.4}", STATE_NAMES[i], v)?;
        }
        Ok(())
    }
}

/// The steady-state gain at one `β` and what the estimation needs of the filter.
struct Gain {
    /// `K` (`nx × ny`).
    k: DMatrix<f64>,
    /// `diag(C P Cᵀ)` per output (the state-prediction part of the innovation variance).
    cpc_diag: Vec<f64>,
    /// `diag(C K)` per output.
    ck_diag: Vec<f64>,
    /// `diag(K C)` per filter state.
    kc_diag: Vec<f64>,
}

/// The filter over a prepared problem (module doc).
struct Filter<'a> {
    p: &'a Problem,
    /// Filter-order indices of the process-noise states.
    noisy: Vec<usize>,
    /// Index of the first `F` unknown.
    first_f: usize,
    /// Total unknowns.
    nb: usize,
    dt: f64,
    /// `(manoeuvre, sample)` of the linearisation points.
    points: Vec<(usize, usize)>,
}

impl Filter<'_> {
    /// The steady-state filter at `β` with measurement-noise variances `r`.
    fn gain(&self, beta: &[f64], r: &[f64]) -> Result<Gain, EstimatorError> {
        let p = self.p;
        let (nx, ny) = (p.nx, p.ny());
        let theta = &beta[..p.np];
        let states = p.model.state_set().states();
        let mut a = DMatrix::<f64>::zeros(nx, nx);
        let mut c = DMatrix::<f64>::zeros(ny, nx);
        let mut lin = Linearisation::default();
        for &(m, i) in &self.points {
            let u = &p.man[m].u[i];
            let mut x = [0.0; N_STATES];
            for (k, &s) in states.iter().enumerate() {
                x[k] = u.x_meas[s];
            }
            p.model.linearise(theta, u, &x[..nx], &mut lin)?;
            for rr in 0..nx {
                for cc in 0..nx {
                    a[(rr, cc)] += lin.dfdx[rr][cc];
                }
            }
            for (j, o) in p.outputs.iter().enumerate() {
                for cc in 0..nx {
                    c[(j, cc)] += lin.dydx[o.index()][cc];
                }
            }
        }
        let npts = self.points.len() as f64;
        a /= npts;
        c /= npts;
        let phi = (a * self.dt).exp();
        let mut q = DMatrix::<f64>::zeros(nx, nx);
        for (k, &s) in self.noisy.iter().enumerate() {
            let f = beta[self.first_f + k].exp();
            q[(s, s)] = f * f * self.dt;
        }
        let rm = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(r));
        let ss = riccati::steady_state(&phi, &c, &q, &rm)?;
        let cpc = &c * &ss.p * c.transpose();
        let ck = &c * &ss.k;
        let kc = &ss.k * &c;
        Ok(Gain {
            cpc_diag: (0..ny).map(|j| cpc[(j, j)]).collect(),
            ck_diag: (0..ny).map(|j| ck[(j, j)]).collect(),
            kc_diag: (0..nx).map(|i| kc[(i, i)]).collect(),
            k: ss.k,
        })
    }

    /// One filter pass (module doc): predicted outputs `ŷ` (`N × ny`) into `y`; returns the
    /// gain used.
    fn pass(&self, beta: &[f64], r: &[f64], y: &mut Vec<f64>) -> Result<Gain, EstimatorError> {
        let p = self.p;
        let (nx, ny) = (p.nx, p.ny());
        let theta = &beta[..p.np];
        let ss = self.gain(beta, r)?;
        y.clear();
        y.resize(p.n_samples * ny, 0.0);
        let mut row0 = 0;
        let mut nu = vec![0.0; ny];
        for (m, man) in p.man.iter().enumerate() {
            let mut x = p.x0(m, beta);
            let n = man.u.len();
            for i in 0..n {
                let u = &man.u[i];
                p.check_state(&x, u.t_s)?;
                let yrow = &mut y[(row0 + i) * ny..(row0 + i + 1) * ny];
                p.outputs_at(beta, u, &x, yrow)?;
                if i + 1 == n {
                    break;
                }
                let z = &man.z[i * ny..(i + 1) * ny];
                for j in 0..ny {
                    nu[j] = z[j] - yrow[j];
                }
                for rr in 0..nx {
                    x[rr] += (0..ny).map(|j| ss.k[(rr, j)] * nu[j]).sum::<f64>();
                }
                p.check_state(&x, u.t_s)?;
                let k1 = p.model.derivatives(theta, u, &x[..nx])?;
                x = p.rk4_step(theta, u, &man.u[i + 1], &x, k1)?;
            }
            row0 += n;
        }
        Ok(ss)
    }

    /// `S = ∂ŷ/∂u` (`N·ny × cols` row-major) for the first `cols` unknowns `u` of `full =
    /// (β, ln R)` by central differences of the **whole filter** (gain recomputed, `R =
    /// exp(ln R)` from the last `ny` of `full`); returns `∂ diag(C P Cᵀ + R)/∂u` (`cols × ny`
    /// row-major) and `∂ diag(K C)/∂u` (`cols × nx` row-major) from the same perturbed gains.
    /// The scoring step takes all `nβ + ny` unknowns; the accuracy at the end the first `nβ`.
    fn sensitivities(
        &self,
        full: &[f64],
        cols: usize,
        s: &mut Vec<f64>,
    ) -> Result<GainDerivatives, EstimatorError> {
        #[cfg(test)]
        super::fault::check()?;
        let nb = self.nb;
        let (nx, ny) = (self.p.nx, self.p.ny());
        let rows = self.p.n_samples * ny;
        s.clear();
        s.resize(rows * cols, 0.0);
        let mut dbf = vec![0.0; cols * ny];
        let mut dkc = vec![0.0; cols * nx];
        let (mut yp, mut ym) = (Vec::new(), Vec::new());
        let mut b = full.to_vec();
        let r_of = |v: &[f64]| -> Vec<f64> { v[nb..].iter().map(|x| x.exp()).collect() };
        for a in 0..cols {
            let h = 1e-4 * full[a].abs().max(1e-3);
            b[a] = full[a] + h;
            let rp = r_of(&b);
            let plus = self.pass(&b[..nb], &rp, &mut yp);
            b[a] = full[a] - h;
            let rm = r_of(&b);
            let minus = self.pass(&b[..nb], &rm, &mut ym);
            b[a] = full[a];
            // At the edge of the physical domain one side's pass may fail where the iterate's
            // did not: a one-sided difference from the iterate, as far as it goes.
            let (gp, gm, rp, rm, span) = match (plus, minus) {
                (Ok(gp), Ok(gm)) => (gp, gm, rp, rm, 2.0 * h),
                (Ok(gp), Err(_)) => (gp, self.pass(&b[..nb], &r_of(&b), &mut ym)?, rp, r_of(&b), h),
                (Err(_), Ok(gm)) => (self.pass(&b[..nb], &r_of(&b), &mut yp)?, gm, r_of(&b), rm, h),
                (Err(e), Err(_)) => return Err(e),
            };
            for row in 0..rows {
                s[row * cols + a] = (yp[row] - ym[row]) / span;
            }
            for j in 0..ny {
                dbf[a * ny + j] = (gp.cpc_diag[j] + rp[j] - gm.cpc_diag[j] - rm[j]) / span;
            }
            for i in 0..nx {
                dkc[a * nx + i] = (gp.kc_diag[i] - gm.kc_diag[i]) / span;
            }
        }
        Ok(GainDerivatives { dbf, dkc })
    }
}

/// Derivatives of the filter's gain-dependent quantities from [`Filter::sensitivities`].
struct GainDerivatives {
    /// `∂ diag(C P Cᵀ + R)/∂u` (`cols × ny` row-major).
    dbf: Vec<f64>,
    /// `∂ diag(K C)/∂u` (`cols × nx` row-major).
    dkc: Vec<f64>,
}

/// Negative log-likelihood of the innovations `e` (`N × ny` row-major) under the filter's own
/// innovation variances `bf = diag(C P Cᵀ) + R`, constants dropped:
/// `½ Σ_k Σ_j e_kj² / bf_j + (N/2) Σ_j ln bf_j` (module doc, "Estimation").
fn filter_likelihood(e: &[f64], bf: &[f64], n: usize) -> f64 {
    weighted_cost(e, &bf.iter().map(|v| 1.0 / v).collect::<Vec<_>>())
        + 0.5 * n as f64 * bf.iter().map(|v| v.ln()).sum::<f64>()
}

/// Adds to the Gauss–Newton information `m` and descent direction `g` of
/// [`normal_equations`] the terms of the likelihood's dependence on the innovation variances
/// `bf_j(β)` (Fisher scoring for a Gaussian with parameter-dependent variance): with
/// `D_aj = ∂bf_j/∂β_a` (`dbf`, one row of `ny` per unknown, `ln R` included) and
/// `s_j = Σ_k e_kj²`,
/// `m_ab += (N/2) Σ_j D_aj D_bj / bf_j²` and `g_a −= Σ_j D_aj (N/(2 bf_j) − s_j/(2 bf_j²))`.
fn add_variance_terms(
    m: &mut DMatrix<f64>,
    g: &mut nalgebra::DVector<f64>,
    dbf: &[f64],
    e: &[f64],
    bf: &[f64],
    n_samples: usize,
) {
    let ny = bf.len();
    let nb = g.len();
    let n = n_samples as f64;
    let mut ss = vec![0.0; ny];
    for (k, v) in e.iter().enumerate() {
        ss[k % ny] += v * v;
    }
    for a in 0..nb {
        for j in 0..ny {
            let d = dbf[a * ny + j];
            g[a] -= d * (0.5 * n / bf[j] - 0.5 * ss[j] / (bf[j] * bf[j]));
        }
        for c in 0..nb {
            let v: f64 = (0..ny).map(|j| dbf[a * ny + j] * dbf[c * ny + j] / (bf[j] * bf[j])).sum();
            m[(a, c)] += 0.5 * n * v;
        }
    }
}

/// Second-difference estimate of each output's white-noise variance (module doc), floored
/// at 10⁻¹² of its mean square.
fn noise_start(p: &Problem) -> Vec<f64> {
    let ny = p.ny();
    let (mut sum, mut ms, mut count) = (vec![0.0; ny], vec![0.0; ny], 0usize);
    for man in &p.man {
        let n = man.u.len();
        for i in 0..n {
            for j in 0..ny {
                ms[j] += man.z[i * ny + j].powi(2);
            }
        }
        for i in 1..n.saturating_sub(1) {
            for j in 0..ny {
                let d2 =
                    man.z[(i + 1) * ny + j] - 2.0 * man.z[i * ny + j] + man.z[(i - 1) * ny + j];
                sum[j] += d2 * d2;
            }
            count += 1;
        }
    }
    (0..ny)
        .map(|j| {
            let v = sum[j] / (6.0 * count.max(1) as f64);
            v.max(1e-12 * ms[j] / p.n_samples as f64).max(1e-300)
        })
        .collect()
}

/// Fits the structure's parameters and the process-noise distribution `F` (and any biases and
/// free initial states) to the manoeuvres by the filter-error method (module doc).
///
/// `manoeuvres` as [`super::fit`]; sample intervals should be (nearly) constant, the
/// steady-state filter uses the median one.
///
/// # Errors
/// As [`super::fit`]; also [`EstimatorError::InvalidConfig`] for a wrong-length
/// [`FemConfig::process_noise_start`] and [`EstimatorError::Numerical`] when the Riccati
/// equation has no stabilising solution at the starting values.
pub fn fit(manoeuvres: &[&[AirDataSample]], config: &FemConfig) -> Result<FemResult, OeError> {
    let fem = fit_to_end(manoeuvres, config)?;
    match fem.result.termination {
        Termination::NotConverged(reason) => {
            Err(OeError::NotConverged { reason, result: Box::new(fem.result) })
        }
        _ => Ok(fem),
    }
}

/// [`fit`], but a fit that does not converge is returned too: its last iterate, with
/// `result.termination` saying why it stopped (for a caller that reports it as such).
///
/// # Errors
/// As [`fit`], except [`OeError::NotConverged`].
pub fn fit_to_end(
    manoeuvres: &[&[AirDataSample]],
    config: &FemConfig,
) -> Result<FemResult, OeError> {
    let oe = &config.oe;
    let p = prepare(manoeuvres, oe)?;
    let fem = Fem::new(&p, config)?;
    let (mut it, start) = fem.start(manoeuvres, oe)?;
    let (converged, failure) = fem.iterate(&mut it, oe)?;
    let failure = failure.unwrap_or(NotConverged::MaxIterations);
    let mut termination = Termination::of(&it.log, converged, failure, oe.cost_tolerance);
    // The final iterate was flown but, unless the fit stopped where it linearized, its
    // sensitivities were never formed: when they cannot be, the last iterate whose were is
    // the answer.
    if let Err(err) = fem.filter.sensitivities(&it.beta, fem.nb, &mut it.s) {
        let why = fem.fall_back(&mut it, err.into())?;
        termination = Termination::of(&it.log, false, why, oe.cost_tolerance);
        fem.filter.sensitivities(&it.beta, fem.nb, &mut it.s)?;
    }
    fem.finish(it, start, termination, oe)
}

/// The filter-error problem set up: the filter, and the starts and lower bounds of the noise
/// unknowns.
struct Fem<'a> {
    p: &'a Problem,
    filter: Filter<'a>,
    /// Filter-order indices of the process-noise states.
    noisy: Vec<usize>,
    /// Index of the first `F` unknown.
    first_f: usize,
    /// Unknowns of the filter (θ, b, x0, ln F); the `ln R` follow them.
    nb: usize,
    ny: usize,
    /// Starting measurement-noise variances (second differences) and process noise `F`.
    r0: Vec<f64>,
    f0: Vec<f64>,
    /// Lower bounds of the noise unknowns (ln F, then ln R).
    ln_min: Vec<f64>,
    /// [`FemConfig::gain_limit`].
    gain_limit: Option<f64>,
    /// [`FemConfig::start_from_output_error`].
    from_output_error: bool,
}

/// The current iterate, its residuals and the iteration log.
struct Iterate {
    /// All unknowns: β = (θ, b, x0, ln F) then ln R.
    beta: Vec<f64>,
    /// Innovation variances per output.
    bf: Vec<f64>,
    /// Residual variances per output.
    b: Vec<f64>,
    y: Vec<f64>,
    e: Vec<f64>,
    /// Sensitivities (scratch).
    s: Vec<f64>,
    y_try: Vec<f64>,
    e_try: Vec<f64>,
    /// Levenberg–Marquardt damping, kept from one iteration to the next.
    lambda: f64,
    /// `diag(K C)` per filter state at the iterate.
    kc: Vec<f64>,
    /// Its derivatives by the unknowns (`(nβ + ny) × nx` row-major; zero rows for unknowns
    /// held at a bound), from the last normal equations.
    dkc: Vec<f64>,
    log: Vec<OeIteration>,
    /// The last iterate whose innovations and sensitivities were both formed: all unknowns
    /// and the length of the log up to it (`None` before the first normal equations).
    good: Option<(Vec<f64>, usize)>,
}

/// A trial that lowered the likelihood cost.
struct Accepted {
    beta: Vec<f64>,
    step: nalgebra::DVector<f64>,
    bf: Vec<f64>,
    b: Vec<f64>,
    kc: Vec<f64>,
    value: f64,
}

/// How an iteration ended the fit, if it did: converged, or stopped for a reason.
type Stop = Option<(bool, Option<NotConverged>)>;

/// The median sample interval of the manoeuvres, s (the steady-state filter's step).
fn median_interval(p: &Problem) -> f64 {
    let mut dts: Vec<f64> =
        p.man.iter().flat_map(|m| m.u.windows(2).map(|w| w[1].t_s - w[0].t_s)).collect();
    dts.sort_by(f64::total_cmp);
    dts[dts.len() / 2]
}

/// The starting `F` of each process-noise state: the configured ones, or 0.1 × the scale of
/// its output's noise per √s.
fn process_noise_start(
    config: &FemConfig,
    p: &Problem,
    noisy: &[usize],
    r0: &[f64],
    dt: f64,
) -> Result<Vec<f64>, OeError> {
    let states = p.model.state_set().states();
    match &config.process_noise_start {
        Some(v) if v.len() != noisy.len() => Err(EstimatorError::InvalidConfig {
            field: "process_noise_start",
            value: v.len() as f64,
            reason: "one starting F per process-noise state of the state set is needed",
        }
        .into()),
        Some(v) if v.iter().any(|f| !(*f > 0.0 && f.is_finite())) => {
            Err(EstimatorError::InvalidConfig {
                field: "process_noise_start",
                value: v.iter().copied().fold(f64::NAN, f64::min),
                reason: "every starting F must be positive and finite",
            }
            .into())
        }
        Some(v) => Ok(v.clone()),
        None => Ok(noisy
            .iter()
            .map(|&k| {
                let o = Output::ALL[states[k]];
                p.outputs.iter().position(|x| *x == o).map_or(1e-3, |j| 0.1 * (r0[j] / dt).sqrt())
            })
            .collect()),
    }
}

/// Lower bounds of the noise unknowns (ln F, then ln R): ln F at 10⁻³ of the scale of its
/// default start, where the process noise no longer matters (the gain goes with F²); ln R at
/// R_FLOOR of the second-difference estimate (module doc).
fn noise_bounds(p: &Problem, noisy: &[usize], r0: &[f64], dt: f64) -> Vec<f64> {
    let states = p.model.state_set().states();
    let mut ln_min: Vec<f64> = noisy
        .iter()
        .map(|&k| {
            let o = Output::ALL[states[k]];
            let scale =
                p.outputs.iter().position(|x| *x == o).map_or(1e-2, |j| (r0[j] / dt).sqrt());
            (F_MIN_FRACTION * scale).ln()
        })
        .collect();
    ln_min.extend(r0.iter().map(|v| (R_FLOOR * v).ln()));
    ln_min
}

impl<'a> Fem<'a> {
    fn new(p: &'a Problem, config: &FemConfig) -> Result<Self, OeError> {
        let states = p.model.state_set().states();
        let noisy: Vec<usize> = (0..p.nx).filter(|&k| config.process_noise[states[k]]).collect();
        let first_f = p.n_unknowns;
        let nb = first_f + noisy.len();
        let dt = median_interval(p);
        let stride = p.n_samples.div_ceil(LINEARISATION_POINTS).max(1);
        let points: Vec<(usize, usize)> = p
            .man
            .iter()
            .enumerate()
            .flat_map(|(m, man)| (0..man.u.len()).step_by(stride).map(move |i| (m, i)))
            .collect();
        let filter = Filter { p, noisy: noisy.clone(), first_f, nb, dt, points };
        let r0 = noise_start(p);
        let f0 = process_noise_start(config, p, &noisy, &r0, dt)?;
        let ln_min = noise_bounds(p, &noisy, &r0, dt);
        let gain_limit = config.gain_limit;
        let from_output_error = config.start_from_output_error;
        Ok(Self {
            p,
            filter,
            noisy,
            first_f,
            nb,
            ny: p.ny(),
            r0,
            f0,
            ln_min,
            gain_limit,
            from_output_error,
        })
    }

    /// The measurement-noise variances of unknowns `full`.
    fn r_of(&self, full: &[f64]) -> Vec<f64> {
        full[self.nb..].iter().map(|v| v.exp()).collect()
    }

    /// The innovation variances: the state-prediction part plus `R`.
    fn innovation_var(&self, g: &Gain, full: &[f64]) -> Vec<f64> {
        (0..self.ny).map(|j| g.cpc_diag[j] + full[self.nb + j].exp()).collect()
    }

    /// The starting iterate (the output-error start, then `F` and `R` at their starts) and
    /// the output-error start's report.
    fn start(
        &self,
        manoeuvres: &[&[AirDataSample]],
        oe: &OeConfig,
    ) -> Result<(Iterate, Vec<f64>), OeError> {
        let mut y = Vec::new();
        let (beta_oe, start) = match self.output_error_start(manoeuvres, oe, &mut y) {
            Some(s) => s,
            None => first_start(self.p, manoeuvres, oe, |b| {
                let mut full = b.to_vec();
                full.extend(self.f0.iter().map(|f| f.ln()));
                self.filter.pass(&full, &self.r0, &mut y).map(|_| ())
            })?,
        };
        let mut beta = beta_oe;
        beta.extend(self.f0.iter().map(|f| f.ln()));
        beta.extend(self.r0.iter().map(|v| v.ln()));
        let mut e = Vec::new();
        let st = self.filter.pass(&beta[..self.nb], &self.r_of(&beta), &mut y)?;
        let b = residuals(self.p, &y, &mut e);
        let bf = self.innovation_var(&st, &beta);
        let log = vec![OeIteration {
            iteration: 0,
            ln_det_r: ln_det(&b),
            cost: filter_likelihood(&e, &bf, self.p.n_samples),
            lambda: 0.0,
            max_step_sigma: f64::NAN,
        }];
        let (s, y_try, e_try, dkc) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let kc = st.kc_diag;
        let good = None;
        let it = Iterate { beta, bf, b, y, e, s, y_try, e_try, lambda: 0.0, kc, dkc, log, good };
        Ok((it, start))
    }

    /// `(θ, b, x0)` and `θ` of the output-error fit of the record when
    /// [`FemConfig::start_from_output_error`] asks for it, the fit ends with a finite result
    /// (converged or not: its last iterate is still nearer than the equation-error start) and
    /// the filter runs there at the starting noise; else `None` (module doc, "Starting values").
    fn output_error_start(
        &self,
        manoeuvres: &[&[AirDataSample]],
        oe: &OeConfig,
        y: &mut Vec<f64>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        if !self.from_output_error {
            return None;
        }
        let r = super::fit_to_end(manoeuvres, oe).ok()?;
        let n = self.p.n_unknowns;
        if r.values.len() != n || !r.values.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut full = r.values.clone();
        full.extend(self.f0.iter().map(|f| f.ln()));
        self.filter.pass(&full, &self.r0, y).ok()?;
        Some((r.values.clone(), r.values[..r.n_params].to_vec()))
    }

    /// Gauss–Newton iterations until convergence, no descent, or the iteration limit.
    /// Returns whether it converged and, if not, why.
    fn iterate(
        &self,
        it: &mut Iterate,
        oe: &OeConfig,
    ) -> Result<(bool, Option<NotConverged>), OeError> {
        for iteration in 1..=oe.max_iterations {
            if super::stop_raised(oe.stop.as_ref()) {
                return Ok((false, Some(NotConverged::Stopped)));
            }
            match self.step(it, iteration, oe) {
                Ok(Some(stop)) => return Ok(stop),
                Ok(None) => {}
                Err(err) => return Ok((false, Some(self.fall_back(it, err)?))),
            }
        }
        Ok((false, Some(NotConverged::MaxIterations)))
    }

    /// After `err` at the current iterate: back to the last iterate whose sensitivities were
    /// formed (its filter run again, its log entry the last), returning the reason the fit
    /// then ends with (output error's module doc, "Numerical failure").
    ///
    /// # Errors
    /// `err` itself when it is not numerical or no earlier iterate was linearized.
    fn fall_back(&self, it: &mut Iterate, err: OeError) -> Result<NotConverged, OeError> {
        let why = match &err {
            OeError::Estimator(e) => NotConverged::numerical(e),
            OeError::NotConverged { .. } => None,
        };
        let (Some(why), Some((beta, log_len))) = (why, it.good.take()) else {
            return Err(err);
        };
        if beta == it.beta {
            return Err(err);
        }
        let st = self.filter.pass(&beta[..self.nb], &self.r_of(&beta), &mut it.y)?;
        it.b = residuals(self.p, &it.y, &mut it.e);
        it.bf = self.innovation_var(&st, &beta);
        it.kc = st.kc_diag;
        it.beta = beta;
        it.log.truncate(log_len);
        Ok(why)
    }

    /// One iteration: the normal equations with the variance terms, a damped step that
    /// lowers the cost, the convergence test.
    fn step(&self, it: &mut Iterate, iteration: usize, oe: &OeConfig) -> Result<Stop, OeError> {
        if it.b.iter().any(|v| v.is_nan() || *v <= 0.0) {
            return Err(EstimatorError::Numerical {
                what: "an output's innovations are all zero: its variance cannot be estimated",
                t_s: 0.0,
            }
            .into());
        }
        let (m, g) = self.normal_equations(it, oe)?;
        it.good = Some((it.beta.clone(), it.log.len()));
        let minv = spd_inverse(&m);
        let nfull = self.nb + self.ny;
        let step_sigma = |step: &nalgebra::DVector<f64>| match &minv {
            Some(mi) => (0..nfull).map(|i| step[i].abs() / mi[(i, i)].sqrt()).fold(0.0, f64::max),
            None => f64::INFINITY,
        };
        let merit0 = filter_likelihood(&it.e, &it.bf, self.p.n_samples);
        let Some(a) = self.search(it, &m, &g, merit0, oe.stop.as_ref()) else {
            if super::stop_raised(oe.stop.as_ref()) {
                return Ok(Some((false, Some(NotConverged::Stopped))));
            }
            // At the optimum to the rounding of the finite-difference sensitivities, or stuck.
            let tiny = self
                .full_step(it, &m, &g)
                .is_some_and(|st| step_sigma(&st) < oe.step_tolerance_sigma);
            return Ok(Some(if tiny {
                (true, None)
            } else {
                (false, Some(NotConverged::NoDescent))
            }));
        };
        let max_step_sigma = step_sigma(&a.step);
        let used_lambda = it.lambda;
        it.lambda = if it.lambda < 1e-6 { 0.0 } else { it.lambda / 10.0 };
        let rel = 2.0 * ((a.value - merit0) / self.p.n_samples as f64).abs();
        it.beta = a.beta;
        it.bf = a.bf;
        std::mem::swap(&mut it.y, &mut it.y_try);
        std::mem::swap(&mut it.e, &mut it.e_try);
        it.b = a.b;
        it.kc = a.kc;
        it.log.push(OeIteration {
            iteration,
            ln_det_r: ln_det(&it.b),
            cost: a.value,
            lambda: used_lambda,
            max_step_sigma,
        });
        let done = rel < oe.cost_tolerance && max_step_sigma < oe.step_tolerance_sigma;
        Ok(done.then_some((true, None)))
    }

    /// The normal equations of all unknowns at the iterate, with the innovation-variance
    /// terms. A noise unknown at its bound whose gradient points further down is held there
    /// this iteration (active set): its information vanishes there and would spoil the step.
    fn normal_equations(
        &self,
        it: &mut Iterate,
        oe: &OeConfig,
    ) -> Result<(DMatrix<f64>, nalgebra::DVector<f64>), OeError> {
        let nfull = self.nb + self.ny;
        let w: Vec<f64> = it.bf.iter().map(|v| 1.0 / v).collect();
        let d = self.filter.sensitivities(&it.beta, nfull, &mut it.s)?;
        let (mut m, mut g, _) = normal_equations(&it.s, &it.e, &w, nfull);
        add_variance_terms(&mut m, &mut g, &d.dbf, &it.e, &it.bf, self.p.n_samples);
        check_identifiable(&m, self.p, oe, self.first_f)?;
        it.dkc = d.dkc;
        let nx = self.p.nx;
        for (k, lo) in self.ln_min.iter().enumerate() {
            let i = self.first_f + k;
            if it.beta[i] <= *lo && g[i] <= 0.0 {
                for j in 0..nfull {
                    m[(i, j)] = 0.0;
                    m[(j, i)] = 0.0;
                }
                m[(i, i)] = 1.0;
                g[i] = 0.0;
                it.dkc[i * nx..(i + 1) * nx].fill(0.0);
            }
        }
        Ok((m, g))
    }

    /// The least-damped step that lowers the cost below `merit0`, raising the damping tenfold
    /// after each failure (`None` past 10¹⁰, or once `stop` is raised).
    fn search(
        &self,
        it: &mut Iterate,
        m: &DMatrix<f64>,
        g: &nalgebra::DVector<f64>,
        merit0: f64,
        stop: Option<&super::StopFlag>,
    ) -> Option<Accepted> {
        // Each trial is a filter pass over the whole record: a stop asked for ends the search.
        while !super::stop_raised(stop) {
            if let Some(trial) = self.propose(it, m, g, it.lambda) {
                let nfull = self.nb + self.ny;
                let step = nalgebra::DVector::from_fn(nfull, |i, _| trial[i] - it.beta[i]);
                // A trial whose filter or prediction fails (the state leaves the physical
                // domain, no stabilising Riccati solution) or whose gain breaks the constraint
                // is a step too long: rejected like one that raises the cost, the damping grows.
                if let Ok(st) =
                    self.filter.pass(&trial[..self.nb], &self.r_of(&trial), &mut it.y_try)
                    && self.gain_admissible(&st.kc_diag, &it.kc)
                {
                    let bf = self.innovation_var(&st, &trial);
                    let b = residuals(self.p, &it.y_try, &mut it.e_try);
                    let value = filter_likelihood(&it.e_try, &bf, self.p.n_samples);
                    if value.is_finite() && value < merit0 {
                        let kc = st.kc_diag;
                        return Some(Accepted { beta: trial, step, bf, b, kc, value });
                    }
                }
            }
            it.lambda = if it.lambda == 0.0 { 1e-3 } else { it.lambda * 10.0 };
            if it.lambda > 1e10 {
                return None;
            }
        }
        None
    }

    /// The trial unknowns at damping `lambda`: the damped scoring step, its noise unknowns
    /// scaled and bounded ([`Self::trial`]), then projected onto the linearised gain
    /// constraint ([`constrain_gain`]) when it is on; `None` when a system is singular.
    fn propose(
        &self,
        it: &Iterate,
        m: &DMatrix<f64>,
        g: &nalgebra::DVector<f64>,
        lambda: f64,
    ) -> Option<Vec<f64>> {
        let trial = self.trial(&it.beta, &damped_step(m, m, g, lambda)?);
        let Some(limit) = self.gain_limit else { return Some(trial) };
        let n = trial.len();
        let mut delta = nalgebra::DVector::from_fn(n, |i, _| trial[i] - it.beta[i]);
        constrain_gain(&it.kc, &it.dkc, limit, &damped_matrix(m, lambda), &mut delta)?;
        let delta = self.taken(&it.beta, &delta);
        Some((0..n).map(|i| it.beta[i] + delta[i]).collect())
    }

    /// The undamped, unscaled step as it would be taken (bounds, gain constraint): the
    /// distance to the optimum the convergence test measures when no step lowers the cost.
    fn full_step(
        &self,
        it: &Iterate,
        m: &DMatrix<f64>,
        g: &nalgebra::DVector<f64>,
    ) -> Option<nalgebra::DVector<f64>> {
        let mut delta = self.taken(&it.beta, &damped_step(m, m, g, 0.0)?);
        if let Some(limit) = self.gain_limit {
            constrain_gain(&it.kc, &it.dkc, limit, m, &mut delta)?;
            delta = self.taken(&it.beta, &delta);
        }
        Some(delta)
    }

    /// Whether a trial's `diag(K C)` (`kc_trial`) keeps the gain constraint: each element at
    /// most the limit plus [`KC_TOLERANCE`] (the linearised projection's second-order error),
    /// or no larger than at the iterate (`kc_now`; a start beyond the bound is led back, not
    /// refused). Always true with the constraint off.
    fn gain_admissible(&self, kc_trial: &[f64], kc_now: &[f64]) -> bool {
        self.gain_limit.is_none_or(|limit| {
            kc_trial.iter().zip(kc_now).all(|(t, n)| *t <= (limit + KC_TOLERANCE).max(*n))
        })
    }

    /// The trial unknowns `beta + step`: the noise unknowns (logarithms) bounded below (a
    /// step beyond goes to the bound) and their steps scaled and limited (module doc).
    fn trial(&self, beta: &[f64], step: &nalgebra::DVector<f64>) -> Vec<f64> {
        let first_f = self.first_f;
        beta.iter()
            .zip(step.iter())
            .enumerate()
            .map(|(i, (b, d))| {
                if i < first_f {
                    b + d
                } else if b + d <= self.ln_min[i - first_f] {
                    self.ln_min[i - first_f]
                } else {
                    b + (F_STEP * d).clamp(-MAX_LN_STEP, MAX_LN_STEP)
                }
            })
            .collect()
    }

    /// The step as it would be taken from `beta` (noise unknowns cut at their bounds).
    fn taken(&self, beta: &[f64], st: &nalgebra::DVector<f64>) -> nalgebra::DVector<f64> {
        let first_f = self.first_f;
        nalgebra::DVector::from_fn(self.nb + self.ny, |i, _| {
            if i >= first_f {
                (beta[i] + st[i]).max(self.ln_min[i - first_f]) - beta[i]
            } else {
                st[i]
            }
        })
    }

    /// The result at the final iterate, converged or not ([`Termination`]): accuracy from the
    /// sensitivities of β (in `it.s`, formed there by the caller) with B and R final, the
    /// diagnostic σ, `F` back from its logarithm.
    fn finish(
        &self,
        it: Iterate,
        start: Vec<f64>,
        termination: Termination,
        oe: &OeConfig,
    ) -> Result<FemResult, OeError> {
        let (nb, first_f) = (self.nb, self.first_f);
        let states = self.p.model.state_set().states();
        let w: Vec<f64> = it.b.iter().map(|v| 1.0 / v).collect();
        let r = self.r_of(&it.beta);
        let mut beta = it.beta;
        beta.truncate(nb);
        let mut names = unknown_names(self.p, &oe.structure);
        names.extend(self.noisy.iter().map(|&k| format!("F_{}", STATE_NAMES[states[k]])));
        let fit = Fitted { beta: &beta, s: &it.s, e: &it.e, w: &w, u: &[], r: &r, names };
        let mut result = assemble(self.p, &oe.structure, fit, it.log, start, termination, oe)?;
        let max_lag = oe
            .coloured_max_lag
            .unwrap_or_else(|| result.manoeuvre_lengths.iter().copied().min().unwrap_or(4) / 4);
        // Stopped on request: the Cramér–Rao σ only (the diagnostic σ cost seconds on a long
        // record, which the stop is for).
        let [mut sigma_lag0, mut sigma_full_b, mut sigma_coloured_theta] =
            if super::stop_raised(oe.stop.as_ref()) {
                [None, None, None]
            } else {
                let stop = || super::stop_raised(oe.stop.as_ref());
                diagnostic_sigmas(&it.s, &it.e, &w, &result, nb, max_lag, &stop)
            };
        let f_scale: Vec<f64> =
            (0..nb).map(|i| if i >= first_f { beta[i].exp() } else { 1.0 }).collect();
        for v in [sigma_lag0.as_mut(), sigma_full_b.as_mut(), sigma_coloured_theta.as_mut()]
            .into_iter()
            .flatten()
        {
            v.iter_mut().zip(&f_scale).for_each(|(x, k)| *x *= k);
        }
        from_log_f(&mut result, first_f);
        let gain = self.filter.gain(&beta, &r)?;
        let out = FemResult {
            result,
            process_noise_states: self.noisy.iter().map(|&k| states[k]).collect(),
            first_f,
            ck_diag: gain.ck_diag,
            kc_diag: gain.kc_diag,
            kc_states: states[..self.p.nx].to_vec(),
            sigma_lag0,
            sigma_full_b,
            sigma_coloured_theta,
        };
        Ok(out)
    }
}

/// `M + λ diag(M)`: the matrix whose step [`damped_step`] solves for at damping `lambda`
/// (the metric of the constrained step at that damping).
fn damped_matrix(m: &DMatrix<f64>, lambda: f64) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| {
        m[(i, j)] + if i == j { lambda * m[(i, i)] } else { 0.0 }
    })
}

/// Projects the step `delta` onto the linearised gain constraint `diag(K C) ≤ limit`
/// (Jategaonkar 2015 ch. 5, limit 1; module doc, "The gain constraint"): with `kc` the current
/// `diag(K C)` (`nx`) and `dkc` its derivatives (`n × nx` row-major, `n = delta.len()`), the
/// elements whose linear prediction `kc_i + ∇kc_i · δ` exceeds `limit` form the rows of `G`
/// and the excesses `s`, and `δ ← δ − A⁻¹ Gᵀ (G A⁻¹ Gᵀ)⁻¹ s`: the minimum of the quadratic model with
/// metric `A` (`n × n`, symmetric positive definite) on those constraints held as equalities.
/// A projection can push another element over; it then joins the set and the projection is
/// redone from the original step (at most `nx` rounds). Elements no unknown moves (a zero row)
/// are left out. `None` when `A` or `G A⁻¹ Gᵀ` is singular.
fn constrain_gain(
    kc: &[f64],
    dkc: &[f64],
    limit: f64,
    a: &DMatrix<f64>,
    delta: &mut nalgebra::DVector<f64>,
) -> Option<()> {
    let (n, nx) = (delta.len(), kc.len());
    let excess = |d: &nalgebra::DVector<f64>, i: usize| {
        kc[i] + (0..n).map(|k| dkc[k * nx + i] * d[k]).sum::<f64>() - limit
    };
    let movable = |i: usize| (0..n).any(|k| dkc[k * nx + i] != 0.0);
    let chol = a.clone().cholesky()?;
    let d0 = delta.clone();
    let mut active: Vec<usize> = Vec::new();
    for _ in 0..nx {
        let new: Vec<usize> = (0..nx)
            .filter(|&i| !active.contains(&i) && movable(i) && excess(delta, i) > 0.0)
            .collect();
        if new.is_empty() {
            break;
        }
        active.extend(new);
        let g = DMatrix::from_fn(active.len(), n, |r, k| dkc[k * nx + active[r]]);
        let ainv_gt = chol.solve(&g.transpose());
        let s = nalgebra::DVector::from_fn(active.len(), |r, _| excess(&d0, active[r]));
        let mult = (&g * &ainv_gt).lu().solve(&s)?;
        *delta = &d0 - ainv_gt * mult;
    }
    delta.iter().all(|v| v.is_finite()).then_some(())
}

/// `ln det` of a diagonal given as its entries.
fn ln_det(v: &[f64]) -> f64 {
    v.iter().map(|x| x.ln()).sum::<f64>()
}

/// The lag-0 sandwich σ and the full-`B` Cramér–Rao σ ([`FemResult::sigma_lag0`],
/// [`FemResult::sigma_full_b`]) and the coloured sandwich of the parameter block
/// ([`FemResult::sigma_coloured_theta`], lags up to `max_lag`) at the estimate, unknowns as estimated (`ln F`). `s`: `N × ny ×
/// nb` sensitivities, `e`: `N × ny` innovations, `w`: `B⁻¹` diagonal.
fn diagnostic_sigmas(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    r: &OeResult,
    nb: usize,
    max_lag: usize,
    stop: coloured::Stop,
) -> [Option<Vec<f64>>; 3] {
    let ny = w.len();
    let (m, _, _) = normal_equations(s, e, w, nb);
    let Some(minv) = spd_inverse(&m) else { return [None, None, None] };
    let lengths = &r.manoeuvre_lengths;
    let Some(pre) = coloured::prewhitened_until(s, e, w, lengths, &minv, max_lag, stop) else {
        return [None, None, None];
    };
    let full = pre.coloured.full;
    let coloured_theta = (0..r.n_params).all(|i| full[(i, i)] > 0.0).then(|| {
        (0..nb).map(|i| if full[(i, i)] > 0.0 { full[(i, i)].sqrt() } else { f64::NAN }).collect()
    });
    let Some(lag0) = coloured::covariance_until(s, e, w, lengths, &minv, 0, stop) else {
        return [None, None, None];
    };
    let lag0 = lag0.covariance.map(|c| (0..nb).map(|i| c[(i, i)].sqrt()).collect());
    let n = (e.len() / ny) as f64;
    let mut b = DMatrix::<f64>::zeros(ny, ny);
    for nu in e.chunks_exact(ny) {
        for a in 0..ny {
            for c in 0..ny {
                b[(a, c)] += nu[a] * nu[c] / n;
            }
        }
    }
    let full_b = spd_inverse(&b).and_then(|binv| {
        let mut mb = DMatrix::<f64>::zeros(nb, nb);
        let mut t = vec![0.0; ny * nb];
        for sk in s.chunks_exact(ny * nb) {
            // t = B⁻¹ S_k (ny × nb), then M_B += S_kᵀ t.
            for a in 0..ny {
                for q in 0..nb {
                    t[a * nb + q] = (0..ny).map(|c| binv[(a, c)] * sk[c * nb + q]).sum();
                }
            }
            for a in 0..ny {
                for p in 0..nb {
                    let sp = sk[a * nb + p];
                    if sp != 0.0 {
                        for q in 0..nb {
                            mb[(p, q)] += sp * t[a * nb + q];
                        }
                    }
                }
            }
        }
        spd_inverse(&mb).map(|c| (0..nb).map(|i| c[(i, i)].sqrt()).collect())
    });
    [lag0, full_b, coloured_theta]
}

/// The `F` unknowns are estimated as `ln F` (module doc); reports them as `F`, with
/// `σ_F = F σ_ln F` and the covariance rows and columns scaled by `F` (first-order).
fn from_log_f(r: &mut OeResult, first_f: usize) {
    let n = r.values.len();
    let scale: Vec<f64> =
        (0..n).map(|i| if i >= first_f { r.values[i].exp() } else { 1.0 }).collect();
    for i in first_f..n {
        r.values[i] = scale[i];
        r.sigma[i] *= scale[i];
        if let Some(c) = r.sigma_coloured.as_mut() {
            c[i] *= scale[i];
        }
    }
    for i in 0..n {
        for j in 0..n {
            r.covariance[i * n + j] *= scale[i] * scale[j];
        }
    }
}

/// Refuses an unknown with no effect on any innovation (a zero column of `S`); an `F` at
/// exactly zero has none (its gain derivative vanishes), so a zero start is refused here.
fn check_identifiable(
    m: &DMatrix<f64>,
    p: &Problem,
    oe: &OeConfig,
    first_f: usize,
) -> Result<(), EstimatorError> {
    for i in 0..m.nrows() {
        if !(m[(i, i)] > 0.0 && m[(i, i)].is_finite()) {
            let field = if i < p.np {
                oe.structure.param(i).map_or("parameter", |q| q.name())
            } else if i < p.np + p.n_biases() {
                "output bias"
            } else if i < first_f {
                "initial state"
            } else {
                "process noise F"
            };
            return Err(EstimatorError::InvalidConfig {
                field,
                value: i as f64,
                reason: "this unknown does not affect any innovation (a process noise F of exactly 0 does not)",
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
