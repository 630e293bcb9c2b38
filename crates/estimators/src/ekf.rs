//! Augmented-state extended Kalman filter over any [`ModelStructure`]: the integrated flight
//! states of [`FlightModel`] and the structure's parameters estimated together, sample by
//! sample, through the one [`Estimator`] interface.
//!
//! Sources: Jategaonkar, *Flight Vehicle System Identification*, AIAA 2015, ch. 7 (augmented
//! state EKF, eq. 7.19–7.31; `ekf_mod.m`, `ruku4_aug.m`); Klein & Morelli, *Aircraft System
//! Identification*, AIAA 2006, ch. 8–9 (filter error, state and parameter estimation); the
//! flight model's equations are in [`crate::flight_model`].
//!
//! # Filter
//!
//! Augmented state `z = (x, θ)`, `x` the state set's integrated states
//! ([`StateSet::states`]), `θ` the parameters in structure order (constant up to an optional
//! random walk and the change test's inflations, below).
//!
//! - **Prediction.** Mean: classical RK4 over the sample interval with the inputs (controls,
//!   thrust, density and the measured non-integrated states) interpolated linearly between the
//!   two samples (start, midpoint, end), as `ruku4_aug.m`. Covariance: `P ← Φ P Φᵀ + Q dt` with
//!   `Φ = I + A dt + (A dt)²/2`, `A = ∂f/∂z` exact (forward-mode duals) at the start of the
//!   interval. `A` has non-zero rows only for the states, so `Φ = [[Φxx, Φxθ], [0, I]]` and
//!   only the state rows are formed: `Φxx = I + Axx dt + (Axx dt)²/2`,
//!   `Φxθ = Axθ dt + Axx dt · Axθ dt / 2`, and `P` is updated block-wise (`Pθθ` is untouched
//!   by the propagation).
//! - **Measurement update.** Sequential scalar updates, one per output the sample has
//!   ([`StateSet::outputs`]), each linearised at the predicted state: with a diagonal `R` this
//!   is exactly the joint update and lets a sample omit any output. `∂h/∂z` exact (duals).
//! - **Innovation gating.** Output `o` with innovation `e` and variance `S = h P hᵀ + R` is
//!   rejected (not used) when `|e| / √S > gate_sigmas` (a scalar χ² test with one degree of
//!   freedom; default 5, i.e. a false rejection rate of 6·10⁻⁷ for a consistent filter). Every
//!   rejection is counted ([`Ekf::rejections`]). **Rule:** an output rejected (or
//!   re-anchored, below) `max_consecutive_rejections` times in a row (default 50) means the
//!   model no longer explains it: the filter reports divergence (error,
//!   [`Status::Diverged`]); nothing is reset silently.
//! - **Re-anchoring** (`reanchor_after > 0`, default 25): an output rejected `reanchor_after`
//!   times in a row is a censored observation, `e² > gate² S`: the predicted variance of what
//!   it sees is raised to that bound and the innovation is used, at the gate
//!   ([`Ekf::reanchors`]). A directly measured state (airspeed, vanes, rate gyros, attitudes):
//!   its variance, `P_kk = e²/gate² − R`. An output that depends on parameters (angular
//!   accelerations, specific forces): the block of those parameters, `P ← D P D` with `D` the
//!   factor on their rows and columns that makes `h P hᵀ + R = e²/gate²`, and only once each of
//!   them has been through [`MIN_DRIFT_WINDOWS`] change-test windows without alarm since it was
//!   identified: a settled filter that loses an output has met a change, a filter still in its
//!   start-up transient has diverged, and the rule above says so. Without it a sudden change of a
//!   moment derivative locked the filter out: the 30 % roll-damping loss of the default
//!   scenario put the roll-rate gyro and `ṗ` outside the gate at once, and rejected they could
//!   correct neither the roll rate nor the parameters, so the change test (which watches the
//!   estimates' drift) saw none (22 of 200 default runs diverged 20.5–22.4 s with a
//!   parameter walk of 0.001). Shorter runs (outliers, glitches) are still rejected.
//!   Measured choices (docs/uncertainty.md, "EKF: re-anchoring after a run of rejections"):
//!   the parameter block in the start-up transient turned run 349's reported divergence into
//!   estimates 20–280 prior σ off with status running; re-anchoring after 5 rejections instead
//!   of 25 moved the model error into the state and left the synthetic roll-damping step 24 %
//!   from its new value.
//! - **Restart** (`max_restarts`, default 1): when the divergence rule fires and restarts are
//!   left, the filter starts again as new (parameters at their priors, `P` at its initial
//!   value, `R` and `Q` at their configured values, NIS and the coloured-residual statistics
//!   empty) with its states from the sample at which it fired, and records an
//!   [`EventKind::Restart`] naming the output ([`Estimator::events`]); the counts of
//!   rejections, re-anchorings and change alarms run on. A start-up transient that went wrong
//!   (run 349 of the 60-s default campaign with every estimator: `Cl_β` "identified" at +0.31
//!   against −0.11 within 0.8 s, then an output rejected 50 times in a row at 1.56 s) is what it is for; after the last restart the rule
//!   is a divergence again. The estimates after a restart come from the samples after it
//!   only, and every report shows the event (docs/uncertainty.md, "EKF start-up divergence").
//!   The first re-anchoring of each run of rejections ([`EventKind::Reanchor`]) and each
//!   change alarm ([`EventKind::ChangeDetected`]) are events too.
//! - **Measurement noise from the record** (`adaptive_r_window > 0`, the default): the
//!   configured σ only start the filter; each output's `R` is then estimated from its own
//!   accepted innovations by covariance matching (Mehra 1970; Myers & Tapley 1976:
//!   `E[e²] = h P hᵀ + R`), `R ← R + a (max(e² − h P hᵀ, R_min) − R)` with
//!   `a = 1/min(k + 20, W)` (a running mean in which the configured `R` counts as 20
//!   innovations, then an exponential window of `W` samples) and `R_min` = (configured σ /
//!   10)². Only gated-in innovations update it, so one
//!   outlier cannot inflate it, with one exception: when the state process noise is estimated
//!   (below), a rejected innovation of an output of the adapted states' equations (their own
//!   measurements, and the specific forces `a_x, a_y, a_z` whose row of `∂h/∂x` has an entry
//!   in an adapted state: with `V`, `α`, `β` the airspeed, the vanes and the force outputs,
//!   through which translational turbulence shows) is a censored observation, `e² > gate² S`, and updates
//!   `R` at that bound, `gate² S − h P hᵀ` (one rejection moves `R` by at most
//!   `a · gate² S`). The estimate of `Q` is noisy (its relative standard error over the
//!   500-sample window is of order 1 on turbulent records) and pauses while an output is
//!   rejected; when it fell towards its floor just before a
//!   strong gust, the `R` of these outputs (at its floor, since `Q` had taken the turbulence)
//!   could not grow either, and the gate stayed shut until the divergence rule fired. The
//!   censored update lets `R` take over what `Q` lost along `P⁻ + R = E[e²]` (measurements:
//!   docs/uncertainty.md, "EKF divergences from the estimated process noise"). The other
//!   outputs (rates, attitudes, angular accelerations) keep the strict rule: a
//!   moment-derivative change or model error still fails their gate and is left to the change
//!   test (with the angular accelerations included, the roll model error of the ATTAS
//!   aileron–rudder record inflated `R` of `ṗ` and the σ of `Cl_β`, `Cl_p` twelvefold).
//!   No noise level is taken from any reference fit.
//! - **State process noise from the record** (`adaptive_q_window > 0`, the default, 500
//!   samples; measurements: docs/uncertainty.md, "Adaptive EKF state process noise"): the
//!   configured `state_process_noise` is the start and the floor; the intensity `q` (units² per
//!   s) of
//!   each state in `adaptive_q_states` (default `V, α, β`: translational turbulence enters the
//!   air-relative velocity as `−ġ`, nearly white above `V/L`; rate gyros and attitudes see
//!   inertial motion and rotational gusts are not modelled) is estimated from the filter's own
//!   **state corrections** `d_o = K_o e_o` of output `o` (covariance matching of the state
//!   corrections: Myers & Tapley 1976; Maybeck 1982 vol. 2 §10.4), keeping only the part that
//!   measurement noise cannot produce. *Identifiability.* For a state measured directly,
//!   `E[e²] = P⁻ + R`, and the Myers–Tapley statistic `d² − (P⁻ − P⁺)` is `K²(e² − S)`, the
//!   same statistic as the adaptive `R`'s `e² − S` up to a factor: from variances alone `Q`
//!   and `R` trade off along `P⁻ + R = E[e²]`. What separates them is correlation. In a
//!   consistent filter the corrections are uncorrelated between outputs and between samples
//!   (the innovations are a martingale-difference sequence; Mehra 1970's optimality test),
//!   while a process-noise deficit makes the filter lag, so the corrections of a state from
//!   *different* sensors, in the same sample and over the next few, agree in sign: a common
//!   cause, which independent sensor noise is not, **even when it is coloured** (smoothed or
//!   differentiated channels: the products of one output with itself are exactly where such
//!   colour shows, so they are left out). The statistic of one sample for state `k` is
//!   `c = Σ_o 2 d_o (A − A_o)`, `A_o = λ A_o + d_o` the forgotten sum of output `o`'s
//!   corrections (`λ = 1 − 1/`[`ADAPTIVE_Q_MEMORY_SAMPLES`]), `A = Σ_o A_o`, each product
//!   taken against what came before it: mean 0 when `Q` is right, whatever `R` is. That is
//!   the guard between the two adaptations: `R` is matched on the squares `e_o²`, `Q` on the
//!   cross products only. A state that only one output informs gets no statistic from them.
//!   *Airspeed.* `V`'s prediction variance is removed by the airspeed alone (the other outputs
//!   see it only through small drag and lift changes), so its cross-sensor share is ≈ 0: the
//!   cross products have no sensitivity to `V`'s own `Q` and carry only what `α`'s corrections
//!   put on `V` through the `V`–`α` covariance (on synthetic records without `V` noise they
//!   lifted it to 4× its floor). For the states in `adaptive_q_own_lags` (default `V`) the
//!   statistic also takes each output's products with its *own earlier* corrections
//!   (lags ≥ 1, `2 d_o A_o`; never the same-sample square, which is `R`'s): the innovation
//!   autocorrelation of Mehra 1970, whose lag terms a scalar random walk with a `Q` deficit
//!   makes positive and a consistent filter leaves at 0; the sensitivity is then the full
//!   random-walk one (cross share 1). The price is the guard against coloured sensor noise:
//!   a smoothed airspeed channel reads as process noise (the statistic cannot tell them
//!   apart), which is why it is not used for the vanes. Measured (tests): 0.3 m/s/√s on the
//!   true `V` of the synthetic records is recovered at 0.97–1.29× on 6 seeds (mean 1.12);
//!   without `V` noise (calm air, or `α`, `β` turbulence only) it ends at 0.015–0.028 m/s/√s
//!   (floor 0.015); on the HFB-320 record (Jategaonkar 2015 test case 4) it rises to 0.36 by 10 s
//!   and ends at 0.56 m/s/√s (the filter-error fit's `F_V` 0.34–0.36), the airspeed's `R`
//!   falls from σ 1.65 to 0.12 m/s (the fixed-`Q` filter put the airspeed's process noise in
//!   its measurement noise), and `CL_α` goes from 3.81 ± 0.24 to 4.38 ± 0.08 (filter error
//!   4.39 ± 0.10); its mean NIS from 0.90 to 0.38 (measured, not explained: the innovation
//!   variances are now larger than the innovations; docs/uncertainty.md).
//!   For a scalar random walk with gain `g_k` (the fraction `Σ_o (P hᵀ)_k²/S_o
//!   / P⁻_kk` of the state's prediction variance this sample removed)
//!   `E[c] ≈ s (Q − Q_used) dt`, `s = 2g(1 − g)λ / ((2 − g)(1 − λ(1 − g)))` (from the lag
//!   correlations `C_j = (1 − g)^(j−1) C_1`, `C_1 = (1 − g)(Q − Q_used) dt / (g(2 − g))`),
//!   times the cross-sensor share `1 − Σ_o w_o²` (`w_o` output `o`'s share of the removed
//!   variance), floored at [`MIN_Q_SENSITIVITY`]. The update is
//!   `q ← max(q_min, q + a c / (s dt))`, `a = 1/min(k + 20, W)` (the configured `q` counts as
//!   [`ADAPTIVE_Q_PRIOR_SAMPLES`] samples), `q_min` = configured `state_process_noise²`. The
//!   estimate pauses while any output is in a run of gate rejections: the model then does not
//!   explain the record, and its corrections are model error (without the pause the filter
//!   diverged on the ATTAS aileron–rudder record: `β`'s `Q` grew through a roll-rate model-error
//!   episode until the bank angle failed the gate 50 times in a row). No level is taken from
//!   any reference fit. *Limits* (tests): the information of the first
//!   second or two is gathered with the floor `Q` and counted as such (a short steady segment
//!   before the input helps); the early transient lifts `Q` a little in calm air (σ 1.18× the
//!   fixed-`Q` filter's on average, up to 2.6×, on the synthetic doublet records); the rates
//!   and attitudes are not adapted by default: rotational process noise is where a moment
//!   derivative's change or model error would go, which the change test is for, and their
//!   cross-sensor statistic reads the start-up parameter error as rotational noise (all states
//!   adapted on 3 calm synthetic records: `q`'s σ rose to 0.014–0.089 rad/s/√s, floor 0.0006).
//! - **Parameter changes** (`change_false_alarm_interval_s > 0`, the default): a change test on
//!   the filter's own parameter estimates, which lets the parameter memory grow to the whole
//!   record while nothing changes and restarts it when something does. For a consistent
//!   filter the increments of `θ̂` are the gains times white innovations: the drift
//!   `d = θ̂(t₁) − θ̂(t₀)` over a window has variance `Σ (P⁻ − P⁺)`, the sum of the reductions
//!   of the parameter's variance by the window's measurement updates (with constant
//!   parameters `θ̂` is a martingale and the sum telescopes to `P(t₀) − P(t₁)`, the law of
//!   total variance; under a random walk the variance settles at a steady state and only the
//!   sum is right). Every `change_window_s` (default 1 s), each identified parameter's drift
//!   is standardised, `u = d / √(f_i Σ (P⁻ − P⁺))` with `f_i` the coloured-innovation factor
//!   below, and fed to a two-sided CUSUM `g± ← max(0, g± ± u − k)`, `k` = 1 (Page 1954;
//!   Basseville & Nikiforov, *Detection of Abrupt Changes*, 1993, §2.2), whose threshold `h`
//!   gives the configured mean time between false alarms over all parameters by Siegmund's
//!   approximation (B&N eq. 5.2.44). On an alarm the parameter's variance grows by the squared
//!   jump estimate `δ̂² = (D/κ)²`, `D` the drift since the CUSUM excursion began and
//!   `κ = 1 − Π P⁺/P⁻` (over the excursion's measurement updates) the fraction of a jump the
//!   filter took up over it: a jump's error is multiplied by `P⁺/P⁻` at each update, and with
//!   constant parameters `κ = 1 − P/P_start`. (The variance forms, used before, are ≈ 0 and
//!   ≈ 1 under a random walk: they blew the jump estimate up to the prior σ and standardised
//!   drifts wrongly; docs/uncertainty.md, "EKF: the change test under a parameter random
//!   walk".) The inflation is the one-epoch process noise that explains the drift, in the
//!   spirit of covariance matching (Mehra 1972, Myers & Tapley 1976, Jategaonkar 2015 §7.5),
//!   capped at the prior variance; a diagonal addition
//!   keeps `P` positive definite. Counted per parameter ([`Ekf::change_alarms`]). Parameters
//!   that are not yet identified are not tested (their estimates are in the prior-dominated
//!   transient, not a martingale).
//! - **Drift-consistency factor.** The mean square of a parameter's standardised window drifts
//!   without alarm, `r_i = Σu²/n` (χ²(n)/n, mean 1 for a consistent filter), measures from the
//!   record how much more the estimate moves than its covariance says: colour beyond the
//!   autocorrelation window, model error. With [`SigmaOption::ColouredResiduals`] the reported
//!   variance is `f_i r_i P_ii` once [`MIN_DRIFT_WINDOWS`] windows exist ([`Ekf::drift_factor`];
//!   a filter whose noise is `r` times what it assumes has increments of variance
//!   `r Σ (P⁻ − P⁺)` and error variance `r P`).
//! - **Identified.** A parameter is reported (`identified = true`, [`Estimates::value`] not
//!   `None`) once its filter posterior σ is below **half its prior σ**: the data, not the
//!   prior, then determine it. Once identified it stays identified. Until every parameter is
//!   identified the status is [`Status::Initialising`], then [`Status::Running`].
//! - **σ.** [`SigmaOption::Filter`]: the square root of the parameter block of `P`, a
//!   Cramér–Rao-like bound if the model, `Q` and `R` are right, i.e. if the innovations are
//!   white. They are not when turbulence (process noise the filter does not model) or model
//!   error drives an output: the filter then counts correlated innovations as independent
//!   information. [`SigmaOption::ColouredResiduals`] (the default) corrects each parameter's
//!   variance by `f_i = Σ_o I_oi F_o / Σ_o I_oi`: `F_o = 1 + 2 Σ_{k=1..K_o} ρ̂_o(k)` is the
//!   variance factor of output `o`'s normalised innovations `e/√S`, with the autocorrelation
//!   `ρ̂_o` summed to the first lag inside the white band `±2/√N` (at most
//!   [`crate::coloured::MAX_LAG`]; floored at [`MIN_COLOURED_FACTOR`]), and
//!   `I_oi = Σ (P hᵀ)_i² / S` the information output `o` gave parameter `i` (the decrease of
//!   its variance by that output's updates). This is the coloured-residual correction of
//!   Klein & Morelli 2006 §5.2 / ch. 6 (Morelli & Klein 1997) in the form that holds when the
//!   gains vary slowly over the correlation time (Bayley & Hammersley 1946), output by output:
//!   the full truncated autocorrelation, not only lag 1. With white innovations `f_i ≈ 1`.
//!   Times the drift-consistency factor above.
//! - **Initialisation.** The integrated states from the first sample's measurements,
//!   `P0 = diag(state σ0², prior σ²)`, `θ0` the prior values. A state the sample does not
//!   measure (absent from the first sample: β on a record without a sideslip vane) is a state
//!   all the same: it starts at 0, at every (re-)initialisation, with σ0 at least
//!   [`UNMEASURED_STATE_SIGMA0`], and is seen through the outputs it drives (`ay`, `p`, `r`);
//!   its process noise stays at the configured level (not estimated from the record: see
//!   "State process noise from the record").
//!   A measured state's channel missing at a later (re-)initialisation is a dropout: the filter
//!   waits for a sample that has it. [`Estimator::new_manoeuvre`] re-initialises the states (and their covariance
//!   rows) from the next sample and keeps `θ` and its covariance block.
//! - **At the identification bandwidth** (`update_every = n > 1`; default 1): the filter
//!   steps on every `n`-th sample of a manoeuvre, predicting across `n` sample intervals with
//!   the inputs interpolated between the two samples it reads; the samples between are checked
//!   (finite, inputs readable) and not used. It costs `1/n` of the updates, and what it gives
//!   up is their information: fed raw, white-noise samples its σ grows by about `√n`
//!   (docs/six-axis.md, "The EKF at half rate": at `n = 2` the default flight's scatter grows
//!   ×1.36, median over 30 parameters, 0.85–1.65). The adaptive windows count the samples read.
//! - **Divergence.** A non-finite state or covariance, `V ≤ 0`, `|α|` or `|β| > 1.5 rad`, a
//!   singular implicit-α̇ equation or the gating rule above: the update returns
//!   [`EstimatorError::Numerical`], the estimates keep their last good values, their status is
//!   [`Status::Diverged`], and every later update is refused.
//!
//! Fixed capacity (≤ 8 states, ≤ [`MAX_PARAMS`] parameters); no allocation in `update`; all
//! loops run over the active sizes only.
//!
//! **WARNING:** the covariance is only as honest as `Q` and `R`; on real data with unmodelled
//! dynamics the filter σ are optimistic (use the coloured-residual option). An augmented EKF
//! is also a biased parameter estimator when the prior is far off and the first excitation is
//! strong (Ljung 1979, IEEE TAC 24(1)): information gathered while the parameters were wrong is
//! kept with too small a covariance. With noise-free synthetic data and an `R` 100× too small
//! we measured 3–5 % bias on `Cl_da`, `Cl_p`; with consistent `R` the error stays within the
//! reported 3σ (tests). Process noise on the states trades precision for robustness to model
//! error; the defaults were chosen on synthetic data, not on any record.

use crate::EstimatorError;
use crate::coloured::Autocorrelation;
use crate::estimator::{Estimates, Estimator, EventKind, EventLog, Status, check_finite};
use crate::flight_model::{
    FlightModel, Linearisation, ModelInputs, N_OUTPUTS, N_STATES, Output, STATE_NAMES, StateSet,
};
use crate::prior::Priors;
use crate::sample::AirDataSample;
use crate::vocabulary::{MAX_PARAMS, ModelStructure};
use change::{DriftWindow, Uptake};

/// Default [`EkfConfig::reanchor_after`]: half the divergence rule's 50. A consistent filter
/// never produces such a run (each 5σ rejection has probability 6·10⁻⁷), and the parameters
/// have had that long to take a change up through the other outputs: re-anchoring a state
/// moves the model error into the state, which weakens the signal the parameters learn from
/// (re-anchored after 5 rejections, the synthetic 30 % roll-damping step of the tests ended
/// 24 % from the new value; after 25, 4 %).
pub const DEFAULT_REANCHOR_AFTER: u32 = 25;

/// Default [`EkfConfig::max_restarts`]: one restart from the priors on a lock-out (module doc,
/// "Restart"). Measured on the EKF-only 60-s default campaign (350 runs, seed 1): one lock-out
/// (run 349, at 2.14 s with the EKF alone, in the start-up transient), after which that run ends with its primary
/// derivatives within 2.4σ of the truth except `Cm_q` (−4.1σ); every other run is unchanged.
pub const DEFAULT_MAX_RESTARTS: u32 = 1;

/// Capacity of the augmented state.
pub const MAX_AUG: usize = N_STATES + MAX_PARAMS;

type Square = [[f64; MAX_AUG]; MAX_AUG];

/// How the reported parameter σ and covariance are formed (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SigmaOption {
    /// The parameter block of the filter covariance `P`.
    Filter,
    /// `P` scaled by the coloured-residual factor `(1 + ρ̄)/(1 − ρ̄)`.
    ColouredResiduals,
}

/// Default measurement noise σ per [`Output`]: typical flight-test instrumentation levels
/// (our choice, not taken from any record or reference fit): airspeed 0.5 m/s; flow angles
/// and attitudes 0.2° (0.0035 rad); body rates 0.2 °/s; specific forces 0.1 m/s² (≈ 0.01 g);
/// angular accelerations 0.05 rad/s² (≈ 3 °/s², as obtained by differentiating rate gyros).
pub const DEFAULT_MEASUREMENT_SIGMA: [f64; N_OUTPUTS] =
    [0.5, 0.0035, 0.0035, 0.0035, 0.0035, 0.0035, 0.0035, 0.0035, 0.1, 0.1, 0.1, 0.05, 0.05, 0.05];

/// Default initial state σ, full-state order `(V, α, β, p, q, r, φ, θ)`: twice the default
/// measurement σ of each state (the states start at one noisy measurement).
pub const DEFAULT_STATE_SIGMA0: [f64; N_STATES] =
    [1.0, 0.007, 0.007, 0.007, 0.007, 0.007, 0.007, 0.007];

/// Initial σ of a state the sample does not measure (β without a sideslip vane; rad or
/// rad/s), which starts at 0: 0.1 rad (5.7°) is a prior, not a measurement, chosen wide
/// against the sideslip of a trimmed start; the synthetic β-less test and ATTAS AilRud1 start
/// inside it (`ekf::tests::an_unmeasured_sideslip_is_carried_as_a_state`).
pub const UNMEASURED_STATE_SIGMA0: f64 = 0.1;

/// Default state process noise, full-state order, units per √s (`Q = σ² dt`): a small
/// allowance for model error (tabulated non-linearity), m/s/√s for `V`, rad/√s for angles,
/// rad/s/√s for rates; the floor and start of the estimate from the record for the states in
/// [`EkfConfig::adaptive_q_states`] (turbulence: module doc).
pub const DEFAULT_STATE_PROCESS_NOISE: [f64; N_STATES] =
    [0.015, 0.0003, 0.0003, 0.0006, 0.0006, 0.0006, 0.00015, 0.00015];

/// Floor of an output's coloured-innovation variance factor (module doc).
pub const MIN_COLOURED_FACTOR: f64 = 0.25;

/// How many innovations the configured measurement noise is worth in the running estimate of
/// `R` (module doc).
pub const ADAPTIVE_R_PRIOR_SAMPLES: u32 = 20;

/// Default mean time between false alarms of the change test over all parameters, s: the
/// design value, one spurious inflation per hour of consistent data (module doc). It holds only
/// once the estimates behave as a martingale: early in a record the filter is overconfident
/// and the measured rate is far higher (17 alarms on 16 synthetic 50-s records with constant
/// parameters, `ekf::tests`, bounded there at 1.5 per record).
pub const DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S: f64 = 3600.0;

/// Windows without alarm needed before the drift-consistency factor is used (module doc).
pub const MIN_DRIFT_WINDOWS: u32 = 5;

/// Default change-test window, s (module doc).
pub const DEFAULT_CHANGE_WINDOW_S: f64 = 1.0;

/// The states whose process noise is estimated by default, full-state order: `V`, `α` and
/// `β`, through which translational turbulence (and a drag or thrust model error) enters
/// (module doc, "State process noise from the record").
pub const DEFAULT_ADAPTIVE_Q_STATES: [bool; N_STATES] =
    [true, true, true, false, false, false, false, false];

/// The adapted states whose process-noise statistic includes the outputs' own lag products
/// ([`EkfConfig::adaptive_q_own_lags`]), full-state order: `V`, whose prediction variance the
/// airspeed alone removes (module doc, "State process noise from the record").
pub const DEFAULT_ADAPTIVE_Q_OWN_LAGS: [bool; N_STATES] =
    [true, false, false, false, false, false, false, false];

/// Floor of the sensitivity by which the process-noise statistic is divided (module doc):
/// bounds the amplification of its noise for states whose gain is near 0 or 1.
pub const MIN_Q_SENSITIVITY: f64 = 0.1;

/// How many samples the configured state process noise is worth in the running estimate of
/// `Q` (module doc, "State process noise from the record").
pub const ADAPTIVE_Q_PRIOR_SAMPLES: u32 = 20;

/// Memory, in samples, of the accumulated state corrections whose cross products estimate `Q`
/// (module doc, "State process noise from the record"): the forgetting factor is
/// `1 − 1/ADAPTIVE_Q_MEMORY_SAMPLES`.
pub const ADAPTIVE_Q_MEMORY_SAMPLES: f64 = 8.0;

/// Configuration of [`Ekf`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EkfConfig {
    /// The model structure whose parameters are estimated.
    pub structure: ModelStructure,
    /// Prior value (`θ0`) and σ (`P0 = σ²`) of each parameter, structure order.
    pub priors: Priors,
    /// Initial σ of the states, full-state order `(V m/s, α, β, p, q, r, φ, θ rad or rad/s)`
    /// (only the integrated ones are used).
    pub state_sigma0: [f64; N_STATES],
    /// State process noise, full-state order, units per √s (`Q = σ² dt`).
    pub state_process_noise: [f64; N_STATES],
    /// Parameter random-walk noise, structure order, units per √s; 0 = constant parameters.
    pub param_process_noise: [f64; MAX_PARAMS],
    /// Measurement noise σ per [`Output`] index (units of the output).
    pub measurement_sigma: [f64; N_OUTPUTS],
    /// Innovation gate, in innovation σ (module doc); `f64::INFINITY` disables gating.
    pub gate_sigmas: f64,
    /// Consecutive rejections of one output that count as divergence (module doc).
    pub max_consecutive_rejections: u32,
    /// How the reported σ is formed.
    pub sigma: SigmaOption,
    /// Window `W` (samples) of the measurement-noise estimate from the innovations (module
    /// doc); 0 keeps `R` at `measurement_sigma²`.
    pub adaptive_r_window: u32,
    /// Mean time between false alarms of the change test over all parameters, s (module doc,
    /// "Parameter changes"); 0 disables the detector (the parameters then move only by
    /// `param_process_noise`).
    pub change_false_alarm_interval_s: f64,
    /// Length of one change-test window, s (module doc).
    pub change_window_s: f64,
    /// Window `W` (samples) of the state process-noise estimate from the state corrections
    /// (module doc, "State process noise from the record"); 0 keeps `Q` at
    /// `state_process_noise²`, which is otherwise the floor of the estimate.
    pub adaptive_q_window: u32,
    /// Which states' process noise is estimated when `adaptive_q_window > 0`, full-state
    /// order; the others keep `state_process_noise` (module doc: by default `V, α, β`
    /// ([`DEFAULT_ADAPTIVE_Q_STATES`]), through which translational turbulence enters).
    pub adaptive_q_states: [bool; N_STATES],
    /// Which adapted states' statistic also takes each output's products with its own earlier
    /// corrections (lags ≥ 1: the innovation autocorrelation of Mehra 1970), full-state order
    /// (module doc, "State process noise from the record": by default `V`
    /// ([`DEFAULT_ADAPTIVE_Q_OWN_LAGS`]), which one sensor informs).
    pub adaptive_q_own_lags: [bool; N_STATES],
    /// After this many consecutive gate rejections of an output, the predicted variance of what
    /// it sees (a measured state, or the parameters of a settled filter) is raised to the
    /// censored bound and the innovation used (module doc, "Re-anchoring"); 0 disables it (the
    /// rejections then run on to the divergence rule).
    pub reanchor_after: u32,
    /// How many times the divergence rule of the innovation gate may restart the filter from
    /// its priors instead of stopping it (module doc, "Restart"; each restart is an
    /// [`EventKind::Restart`] event); 0: the first lock-out is a divergence.
    pub max_restarts: u32,
    /// The filter steps on every `update_every`-th sample of a manoeuvre (1: every sample),
    /// integrating across the longer interval with the inputs interpolated between the
    /// samples it reads; the samples between are checked and not read (module doc, "At the
    /// identification bandwidth"). The adaptive windows count the samples read.
    pub update_every: u32,
}

impl EkfConfig {
    /// The documented defaults for `structure`: generic priors ([`Priors::generic`]),
    /// [`DEFAULT_STATE_SIGMA0`], [`DEFAULT_STATE_PROCESS_NOISE`], constant parameters,
    /// [`DEFAULT_MEASUREMENT_SIGMA`], a 5σ gate, 50 consecutive rejections, coloured σ, `R`
    /// from a 200-sample window, the process noise of [`DEFAULT_ADAPTIVE_Q_STATES`] from a
    /// 500-sample window, and the change detector on
    /// ([`DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S`], [`DEFAULT_CHANGE_WINDOW_S`]).
    pub fn new(structure: ModelStructure) -> Self {
        Self {
            structure,
            priors: Priors::generic(&structure),
            state_sigma0: DEFAULT_STATE_SIGMA0,
            state_process_noise: DEFAULT_STATE_PROCESS_NOISE,
            param_process_noise: [0.0; MAX_PARAMS],
            measurement_sigma: DEFAULT_MEASUREMENT_SIGMA,
            gate_sigmas: 5.0,
            max_consecutive_rejections: 50,
            sigma: SigmaOption::ColouredResiduals,
            adaptive_r_window: 200,
            change_false_alarm_interval_s: DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S,
            change_window_s: DEFAULT_CHANGE_WINDOW_S,
            adaptive_q_window: 500,
            adaptive_q_states: DEFAULT_ADAPTIVE_Q_STATES,
            adaptive_q_own_lags: DEFAULT_ADAPTIVE_Q_OWN_LAGS,
            reanchor_after: DEFAULT_REANCHOR_AFTER,
            max_restarts: DEFAULT_MAX_RESTARTS,
            update_every: 1,
        }
    }
}

/// The augmented-state EKF (module doc). Large (two 56 × 56 matrices): box it if stack space
/// is short.
#[derive(Debug, Clone)]
pub struct Ekf {
    cfg: EkfConfig,
    model: FlightModel,
    nx: usize,
    np: usize,
    z: [f64; MAX_AUG],
    /// The committed covariance `P` (`cov[front]`) and the step's working copy (the other):
    /// a step writes the whole working block, and its commit swaps the roles instead of
    /// copying the 56 × 56 block back.
    cov: [Square; 2],
    front: usize,
    lin: Linearisation,
    last: Option<ModelInputs>,
    pending_init: bool,
    /// Samples passed over since the last one read ([`EkfConfig::update_every`]).
    passed_over: u32,
    /// The states (full-state order) whose channel the first sample lacked: the record does
    /// not measure them, so every (re-)initialisation starts them at 0. `None` before it.
    unmeasured: Option<[bool; N_STATES]>,
    diverged: bool,
    est: Estimates,
    identified: [bool; MAX_PARAMS],
    innovation: [Option<f64>; N_OUTPUTS],
    rejections: [u32; N_OUTPUTS],
    consecutive: [u32; N_OUTPUTS],
    reanchors: [u32; N_OUTPUTS],
    /// Whether the current run of rejections of each output has been re-anchored (the first
    /// re-anchoring of a run is an [`EventKind::Reanchor`] event).
    run_reanchored: [bool; N_OUTPUTS],
    /// Restarts so far and every event ([`Estimator::events`]).
    restarts: u32,
    events: EventLog,
    /// Autocorrelation of each output's normalised innovations `e/√S`.
    innov_acf: [Autocorrelation; N_OUTPUTS],
    /// `Σ (P hᵀ)_θ² / S` per output and parameter: the information each output gave each
    /// parameter (the decrease of `P_θθ`'s diagonal by its updates).
    innov_info: [[f64; MAX_PARAMS]; N_OUTPUTS],
    /// Current measurement-noise variance per output and its count of updates.
    r_var: [f64; N_OUTPUTS],
    r_count: [u32; N_OUTPUTS],
    /// Σ e²/S over accepted innovations and their count (NIS).
    nis_sum: f64,
    nis_count: u64,
    /// CUSUM threshold `h` of the change test, `None` when it is disabled.
    change_h: Option<f64>,
    /// The change test's current window and the alarm count per parameter.
    drift: DriftWindow,
    /// What the measurement updates did to each parameter's variance, summed (the change
    /// test's drift variance and uptake fraction).
    uptake: [Uptake; MAX_PARAMS],
    alarms: [u32; MAX_PARAMS],
    /// Σ u² of the standardised window drifts without alarm, once identified, and their count
    /// (the drift-consistency factor, module doc).
    drift_u2: [f64; MAX_PARAMS],
    drift_n: [u32; MAX_PARAMS],
    /// Current state process-noise intensity per full-state index (units² per s) and the count
    /// of its updates.
    q_var: [f64; N_STATES],
    q_count: u32,
    /// Exponentially forgotten sum of the state corrections `K e` per integrated state (module
    /// doc, "State process noise from the record").
    q_acc: [[f64; N_OUTPUTS]; N_STATES],
}

/// The gate's counters of the sample at which the divergence rule fired (uncommitted until
/// then): totals and runs of rejections, re-anchorings, and which outputs started a run of
/// re-anchorings at this sample.
struct LockOutCounts {
    rejections: [u32; N_OUTPUTS],
    consecutive: [u32; N_OUTPUTS],
    reanchors: [u32; N_OUTPUTS],
    new_reanchor: [bool; N_OUTPUTS],
}

/// Sensitivity `g` of the state-correction statistic to a process-noise error (module doc,
/// "State process noise from the record"): `E[c] ≈ g (Q − Q_assumed) dt` for a scalar random
/// walk measured with a steady gain `k`, `g = 2 k (1 − k) λ / ((2 − k)(1 − λ (1 − k)))`,
/// floored at [`MIN_Q_SENSITIVITY`].
fn sensitivity(k: f64, forget: f64, cross_share: f64) -> f64 {
    let g = 2.0 * k * (1.0 - k) * forget / ((2.0 - k) * (1.0 - forget * (1.0 - k)));
    (g * cross_share).max(MIN_Q_SENSITIVITY)
}

/// Re-anchoring (module doc): raises the predicted variance of integrated state `k`, measured
/// directly by the output, so that `P_kk = target` (the censored bound `e²/gate² − R`).
/// Returns whether it changed `p` (`false` when `target` is already met). Only the diagonal
/// grows, so `P` stays positive definite.
fn reanchor(p: &mut Square, k: usize, target: f64) -> bool {
    let add = target - p[k][k];
    if add.is_nan() || add <= 0.0 || add.is_infinite() {
        return false;
    }
    p[k][k] += add * (1.0 + 1e-9);
    true
}

/// The committed covariance `cov[front]` to read and the working one to write, at once (a
/// function of the field, so that the rest of the filter stays borrowable).
fn committed_and_work(cov: &mut [Square; 2], front: usize) -> (&Square, &mut Square) {
    let [a, b] = cov;
    if front == 0 { (a, b) } else { (b, a) }
}

/// Re-anchoring of an output that is not a state (module doc): scales the rows and columns of
/// the parameters it depends on (`h` non-zero in `nx..n`) by `s` (their block by `s²`:
/// `P ← D P D`, `D = diag(s on those, 1 elsewhere)`, which keeps `P` positive definite), `s`
/// the root above 1 of `A s² + B s + C = target` with `A` the parameter block's share of
/// `h P hᵀ`, `B` the state–parameter cross share and `C` the states' share. Returns whether it
/// changed `p`.
fn reanchor_parameters(
    p: &mut Square,
    h: &[f64; MAX_AUG],
    nx: usize,
    n: usize,
    target: f64,
) -> bool {
    let in_set = |j: usize| j >= nx && j < n && h[j] != 0.0;
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let v = h[i] * p[i][j] * h[j];
            match (in_set(i), in_set(j)) {
                (true, true) => a += v,
                (false, false) => c += v,
                _ => b += v,
            }
        }
    }
    let target = target * (1.0 + 1e-9);
    if a.is_nan() || a <= 0.0 || target.is_nan() || target <= a + b + c {
        return false;
    }
    let s = (-b + libm::sqrt(b * b - 4.0 * a * (c - target))) / (2.0 * a);
    if s.is_nan() || s <= 1.0 || s.is_infinite() {
        return false;
    }
    for i in 0..n {
        for j in 0..n {
            match (in_set(i), in_set(j)) {
                (true, true) => p[i][j] *= s * s,
                (true, false) | (false, true) => p[i][j] *= s,
                _ => {}
            }
        }
    }
    true
}

/// One step of output `oi`'s measurement-noise estimate (module doc, "Measurement noise from
/// the record"): `R ← R + a (max(excess, R_min) − R)`, `excess` = `e² − h P hᵀ` (or, for a
/// rejected innovation, its lower bound `gate² S − h P hᵀ`), `a = 1/min(k + 20, W)`.
fn adapt_r(
    cfg: &EkfConfig,
    oi: usize,
    excess: f64,
    r_var: &mut [f64; N_OUTPUTS],
    r_count: &mut [u32; N_OUTPUTS],
) {
    r_count[oi] = r_count[oi].saturating_add(1);
    // The configured R counts as `ADAPTIVE_R_PRIOR_SAMPLES` innovations, so the first few
    // cannot collapse it (and with it the gate).
    let k = r_count[oi].saturating_add(ADAPTIVE_R_PRIOR_SAMPLES);
    let a = 1.0 / f64::from(k.min(cfg.adaptive_r_window.max(1)));
    let r0 = cfg.measurement_sigma[oi];
    let r_min = 0.01 * r0 * r0;
    r_var[oi] += a * (excess.max(r_min) - r_var[oi]);
}

fn positive(field: &'static str, v: f64) -> Result<(), EstimatorError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(EstimatorError::InvalidConfig { field, value: v, reason: "must be finite and > 0" })
    }
}

fn nonneg(field: &'static str, v: f64) -> Result<(), EstimatorError> {
    if v >= 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(EstimatorError::InvalidConfig { field, value: v, reason: "must be finite and ≥ 0" })
    }
}

impl Ekf {
    /// The committed covariance `P` of the augmented state.
    fn p(&self) -> &Square {
        &self.cov[self.front]
    }

    /// The committed covariance, to change in place (re-initialisation, drift).
    fn p_mut(&mut self) -> &mut Square {
        &mut self.cov[self.front]
    }

    /// The step's working covariance (predicted, then corrected; committed by
    /// [`Self::commit_covariance`]).
    fn work(&self) -> &Square {
        &self.cov[1 - self.front]
    }

    /// The working covariance, to change in place.
    fn work_mut(&mut self) -> &mut Square {
        &mut self.cov[1 - self.front]
    }

    /// Makes the working covariance the committed one (the old one becomes the next step's
    /// working block, which the next prediction writes whole).
    fn commit_covariance(&mut self) {
        self.front = 1 - self.front;
    }

    /// A new filter; it initialises its states from the first sample.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] for a structure without a state set
    /// ([`StateSet::of`]), priors of another size, or a non-positive / non-finite σ, noise or
    /// gate.
    pub fn new(cfg: EkfConfig) -> Result<Self, EstimatorError> {
        let model = FlightModel::new(cfg.structure)?;
        let np = cfg.structure.n_params();
        if cfg.priors.n != np {
            return Err(EstimatorError::InvalidConfig {
                field: "priors",
                value: cfg.priors.n as f64,
                reason: "number of priors differs from the structure's parameters",
            });
        }
        for pr in &cfg.priors.prior[..np] {
            positive("prior sigma", pr.sigma)?;
            if !pr.value.is_finite() {
                return Err(EstimatorError::InvalidConfig {
                    field: "prior value",
                    value: pr.value,
                    reason: "must be finite",
                });
            }
        }
        for &i in model.state_set().states() {
            positive("state_sigma0", cfg.state_sigma0[i])?;
            nonneg("state_process_noise", cfg.state_process_noise[i])?;
        }
        for v in &cfg.param_process_noise[..np] {
            nonneg("param_process_noise", *v)?;
        }
        for o in model.state_set().outputs() {
            positive("measurement_sigma", cfg.measurement_sigma[o.index()])?;
        }
        if cfg.gate_sigmas.is_nan() || cfg.gate_sigmas <= 0.0 {
            return Err(EstimatorError::InvalidConfig {
                field: "gate_sigmas",
                value: cfg.gate_sigmas,
                reason: "must be > 0 (infinity disables gating)",
            });
        }
        nonneg("change_false_alarm_interval_s", cfg.change_false_alarm_interval_s)?;
        positive("change_window_s", cfg.change_window_s)?;
        if cfg.max_consecutive_rejections == 0 {
            return Err(EstimatorError::InvalidConfig {
                field: "max_consecutive_rejections",
                value: 0.0,
                reason: "must be ≥ 1",
            });
        }
        let nx = model.state_set().states().len();
        let mut z = [0.0; MAX_AUG];
        let mut p = [[0.0; MAX_AUG]; MAX_AUG];
        for i in 0..np {
            let pr = cfg.priors.prior[i];
            z[nx + i] = pr.value;
            p[nx + i][nx + i] = pr.sigma * pr.sigma;
        }
        let mut est = Estimates::new(np);
        for i in 0..np {
            est.set(i, z[nx + i], None, false);
        }
        Ok(Self {
            cfg,
            model,
            nx,
            np,
            z,
            cov: [p, [[0.0; MAX_AUG]; MAX_AUG]],
            front: 0,
            lin: Linearisation::default(),
            last: None,
            pending_init: true,
            passed_over: 0,
            unmeasured: None,
            diverged: false,
            est,
            identified: [false; MAX_PARAMS],
            innovation: [None; N_OUTPUTS],
            rejections: [0; N_OUTPUTS],
            consecutive: [0; N_OUTPUTS],
            reanchors: [0; N_OUTPUTS],
            run_reanchored: [false; N_OUTPUTS],
            restarts: 0,
            events: EventLog::new(),
            innov_acf: [Autocorrelation::new(); N_OUTPUTS],
            innov_info: [[0.0; MAX_PARAMS]; N_OUTPUTS],
            r_var: cfg.measurement_sigma.map(|s| s * s),
            r_count: [0; N_OUTPUTS],
            nis_sum: 0.0,
            nis_count: 0,
            change_h: (cfg.change_false_alarm_interval_s > 0.0).then(|| {
                // Two sides per parameter share the configured interval.
                let windows = cfg.change_false_alarm_interval_s / cfg.change_window_s;
                change::cusum_threshold((windows * 2.0 * np as f64).max(1.0))
            }),
            drift: DriftWindow::default(),
            uptake: [Uptake::default(); MAX_PARAMS],
            alarms: [0; MAX_PARAMS],
            drift_u2: [0.0; MAX_PARAMS],
            drift_n: [0; MAX_PARAMS],
            q_var: cfg.state_process_noise.map(|s| s * s),
            q_count: 0,
            q_acc: [[0.0; N_OUTPUTS]; N_STATES],
        })
    }

    /// The state set integrated.
    pub fn state_set(&self) -> StateSet {
        self.model.state_set()
    }

    /// The current estimate of full-state index `i` ([`state`](crate::flight_model::state))
    /// if it is integrated and the filter has been initialised.
    pub fn state(&self, i: usize) -> Option<f64> {
        self.last?;
        let k = self.model.state_set().states().iter().position(|&j| j == i)?;
        Some(self.z[k])
    }

    /// Innovation (measured − predicted) of output `o` at the last update, `None` if not
    /// measured or rejected.
    pub fn innovation(&self, o: Output) -> Option<f64> {
        self.innovation[o.index()]
    }

    /// The current measurement-noise σ of output `o` (configured, or estimated from the
    /// innovations when `adaptive_r_window > 0`), in the output's unit.
    pub fn measurement_sigma(&self, o: Output) -> f64 {
        libm::sqrt(self.r_var[o.index()])
    }

    /// The current state process noise of full-state index `i`
    /// ([`state`](crate::flight_model::state)), units per √s (configured, or estimated from
    /// the record when `adaptive_q_window > 0`); `None` if the state is not integrated.
    pub fn state_process_noise(&self, i: usize) -> Option<f64> {
        self.model.state_set().states().contains(&i).then(|| libm::sqrt(self.q_var[i]))
    }

    /// How many times the change test of parameter `i` (structure order) raised an alarm and
    /// inflated its variance (module doc, "Parameter changes"); 0 for `i` out of range.
    pub fn change_alarms(&self, i: usize) -> u32 {
        if i < self.np { self.alarms[i] } else { 0 }
    }

    /// How many times output `o` was rejected by the innovation gate.
    pub fn rejections(&self, o: Output) -> u32 {
        self.rejections[o.index()]
    }

    /// How many times output `o` was re-anchored (module doc, "Re-anchoring"): a run of
    /// [`EkfConfig::reanchor_after`] rejections raised the predicted variance of what it sees
    /// to the gate's bound and its innovation was used.
    pub fn reanchors(&self, o: Output) -> u32 {
        self.reanchors[o.index()]
    }

    /// The filter σ of parameter `i` (square root of its diagonal of `P`), whether identified
    /// or not.
    pub fn filter_sigma(&self, i: usize) -> Option<f64> {
        (i < self.np).then(|| libm::sqrt(self.p()[self.nx + i][self.nx + i].max(0.0)))
    }

    /// The coloured-innovation variance factor of each output, `1 + 2 Σ_{k≤K} ρ̂_o(k)` of its
    /// normalised innovations ([`Autocorrelation::variance_factor`]), floored at
    /// [`MIN_COLOURED_FACTOR`] (a truncated sum need not be positive).
    fn output_factor(&self, o: usize) -> f64 {
        self.innov_acf[o].variance_factor().max(MIN_COLOURED_FACTOR)
    }

    /// The coloured-residual variance factor of parameter `i` (module doc): the output factors
    /// weighted by the information each output gave the parameter; 1 until innovations exist.
    pub fn coloured_factor(&self, i: usize) -> f64 {
        self.coloured_factor_of(i, &self.output_factors())
    }

    /// Every output's [`Ekf::output_factor`] (a sum over its residual lags), formed once for
    /// all the parameters that weight them.
    fn output_factors(&self) -> [f64; N_OUTPUTS] {
        core::array::from_fn(|o| self.output_factor(o))
    }

    /// [`Ekf::coloured_factor`] from the output factors `of`.
    fn coloured_factor_of(&self, i: usize, of: &[f64; N_OUTPUTS]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (o, f) in of.iter().enumerate() {
            let w = self.innov_info[o][i];
            if w > 0.0 {
                num += w * f;
                den += w;
            }
        }
        if den > 0.0 { num / den } else { 1.0 }
    }

    /// The information-weighted mean of [`Ekf::coloured_factor`] over the parameters.
    pub fn coloured_residual_factor(&self) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for o in 0..N_OUTPUTS {
            for i in 0..self.np {
                let w = self.innov_info[o][i];
                if w > 0.0 {
                    num += w * self.output_factor(o);
                    den += w;
                }
            }
        }
        if den > 0.0 { num / den } else { 1.0 }
    }

    /// At the end of each change-test window: the drift test of every parameter and, on an
    /// alarm, the inflation of its variance (module doc, "Parameter changes"); then a new
    /// window from the current estimate.
    fn test_for_change(&mut self, t_s: f64, h: f64) {
        let (nx, np) = (self.nx, self.np);
        if self.drift.is_open() && t_s - self.drift.t0_s < self.cfg.change_window_s {
            return;
        }
        if self.drift.is_open() {
            let mut factor = [1.0; MAX_PARAMS];
            for (i, f) in factor.iter_mut().enumerate().take(np) {
                *f = self.coloured_factor(i);
            }
            for i in 0..np {
                let k = nx + i;
                let sigma = self.cfg.priors.prior[i].sigma;
                let identified = self.identified[i];
                if !identified {
                    continue;
                }
                let p_kk = self.p()[k][k];
                match self.drift.step(i, self.z[k], self.uptake[i], p_kk, factor[i], h, sigma) {
                    (_, Some(add)) => {
                        self.p_mut()[k][k] += add;
                        self.alarms[i] = self.alarms[i].saturating_add(1);
                        let name = self.cfg.structure.param(i).map_or("?", |p| p.name());
                        self.events.push(t_s, EventKind::ChangeDetected, name);
                    }
                    (Some(u), None) => {
                        self.drift_u2[i] += u * u;
                        self.drift_n[i] += 1;
                    }
                    _ => {}
                }
            }
        }
        self.drift.open(t_s, &self.z[nx..nx + np], &self.uptake[..np]);
    }

    /// The drift-consistency factor of parameter `i` (module doc): the mean square of its
    /// standardised window drifts, `Σ u² / n`, once [`MIN_DRIFT_WINDOWS`] windows without alarm
    /// have been seen since it was identified; 1 before.
    pub fn drift_factor(&self, i: usize) -> f64 {
        if i < self.np && self.settled(i) {
            self.drift_u2[i] / f64::from(self.drift_n[i])
        } else {
            1.0
        }
    }

    /// Whether parameter `i` has been through [`MIN_DRIFT_WINDOWS`] informative change-test
    /// windows without alarm since it was identified: its drift factor is formed, and a run of
    /// rejections of an output that depends on it is a change, not the start-up transient
    /// (module doc, "Re-anchoring").
    fn settled(&self, i: usize) -> bool {
        self.drift_n[i] >= MIN_DRIFT_WINDOWS
    }

    fn sigma_factor(&self, i: usize) -> f64 {
        self.sigma_factor_of(i, &self.output_factors())
    }

    /// [`Ekf::sigma_factor`] from the output factors `of` ([`Ekf::output_factors`]).
    fn sigma_factor_of(&self, i: usize, of: &[f64; N_OUTPUTS]) -> f64 {
        match self.cfg.sigma {
            SigmaOption::Filter => 1.0,
            SigmaOption::ColouredResiduals => self.coloured_factor_of(i, of) * self.drift_factor(i),
        }
    }

    fn theta(&self) -> &[f64] {
        &self.z[self.nx..self.nx + self.np]
    }

    /// The divergence rule (module doc, "Innovation gating"): output `o` failed the gate
    /// `max_consecutive_rejections` times in a row at sample `s` (inputs `u1`). While restarts
    /// are left (module doc, "Restart"), the filter starts again from its priors with its
    /// states from `s` and records an [`EventKind::Restart`]; otherwise it keeps the rejection
    /// counters of the refused sample and reports the divergence.
    fn locked_out(
        &mut self,
        counts: LockOutCounts,
        o: Output,
        s: &AirDataSample,
        u1: ModelInputs,
    ) -> Result<&Estimates, EstimatorError> {
        let LockOutCounts { rejections, consecutive, reanchors, new_reanchor } = counts;
        self.rejections = rejections;
        self.reanchors = reanchors;
        for o in Output::ALL.iter().filter(|o| new_reanchor[o.index()]) {
            self.events.push(s.t_s, EventKind::Reanchor, o.name());
        }
        if self.restarts >= self.cfg.max_restarts {
            self.consecutive = consecutive;
            return Err(self.diverge(
                "EKF: an output failed the innovation gate too many times in a row",
                s.t_s,
            ));
        }
        let mut fresh = Ekf::new(self.cfg)?;
        fresh.rejections = self.rejections;
        fresh.reanchors = self.reanchors;
        fresh.alarms = self.alarms;
        fresh.restarts = self.restarts + 1;
        fresh.events = self.events;
        fresh.events.push(s.t_s, EventKind::Restart, o.name());
        fresh.unmeasured = self.unmeasured;
        *self = fresh;
        // A sample without every state channel cannot start the states: the restarted filter
        // then waits for one that has them, as a new filter does.
        if self.initialise(s, u1).is_err() {
            self.pending_init = true;
        }
        self.publish(s.t_s);
        Ok(&self.est)
    }

    /// How many times the filter restarted from its priors (module doc, "Restart").
    pub fn restarts(&self) -> u32 {
        self.restarts
    }

    fn diverge(&mut self, what: &'static str, t_s: f64) -> EstimatorError {
        self.diverged = true;
        self.est.status = Status::Diverged;
        EstimatorError::Numerical { what, t_s }
    }

    /// (Re-)initialises the integrated states from sample `s`'s measurements; a state the
    /// record does not measure (absent from the first sample) starts at 0.
    ///
    /// # Errors
    /// [`EstimatorError::NonFiniteInput`] naming a measured state's channel that this sample
    /// lacks (a dropout: the caller waits for a complete sample).
    fn initialise(&mut self, s: &AirDataSample, u: ModelInputs) -> Result<(), EstimatorError> {
        let states = self.model.state_set().states();
        let unmeasured = *self
            .unmeasured
            .get_or_insert_with(|| core::array::from_fn(|i| Output::ALL[i].measured(s).is_none()));
        for &i in states {
            if Output::ALL[i].measured(s).is_none() && !unmeasured[i] {
                return Err(EstimatorError::NonFiniteInput {
                    field: STATE_NAMES[i],
                    value: f64::NAN,
                    t_s: s.t_s,
                });
            }
        }
        let n = self.nx + self.np;
        for (k, &i) in states.iter().enumerate() {
            let measured = Output::ALL[i].measured(s).filter(|_| !unmeasured[i]);
            self.z[k] = measured.unwrap_or(0.0);
            for j in 0..n {
                self.p_mut()[k][j] = 0.0;
                self.p_mut()[j][k] = 0.0;
            }
            let s0 = match measured {
                Some(_) => self.cfg.state_sigma0[i],
                None => self.cfg.state_sigma0[i].max(UNMEASURED_STATE_SIGMA0),
            };
            self.p_mut()[k][k] = s0 * s0;
        }
        self.last = Some(u);
        self.pending_init = false;
        self.passed_over = 0;
        for a in &mut self.innov_acf {
            a.restart();
        }
        self.innovation = [None; N_OUTPUTS];
        self.drift = DriftWindow::default();
        self.q_acc = [[0.0; N_OUTPUTS]; N_STATES];
        Ok(())
    }

    /// RK4 of the integrated states over `dt` with inputs interpolated from `u0` to `u1`.
    fn rk4(
        &self,
        u0: &ModelInputs,
        u1: &ModelInputs,
        dt: f64,
    ) -> Result<[f64; N_STATES], EstimatorError> {
        let nx = self.nx;
        let th = self.theta();
        let um = ModelInputs::lerp(u0, u1, 0.5);
        let x = &self.z[..nx];
        let mut xs = [0.0; N_STATES];
        let k1 = self.model.derivatives(th, u0, x)?;
        for i in 0..nx {
            xs[i] = x[i] + 0.5 * dt * k1[i];
        }
        let k2 = self.model.derivatives(th, &um, &xs[..nx])?;
        for i in 0..nx {
            xs[i] = x[i] + 0.5 * dt * k2[i];
        }
        let k3 = self.model.derivatives(th, &um, &xs[..nx])?;
        for i in 0..nx {
            xs[i] = x[i] + dt * k3[i];
        }
        let k4 = self.model.derivatives(th, u1, &xs[..nx])?;
        let mut out = [0.0; N_STATES];
        for i in 0..nx {
            out[i] = x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        Ok(out)
    }

    /// `work ← Φ P Φᵀ + Q dt` (module doc) with `lin` holding `∂f/∂z` at the interval start.
    fn propagate_covariance(&mut self, dt: f64) {
        let (nx, np) = (self.nx, self.np);
        let n = nx + np;
        let lin = &self.lin;
        // Φxx = I + A dt + (A dt)²/2, Φxθ = B dt + (A dt)(B dt)/2.
        let mut f = [[0.0; N_STATES]; N_STATES];
        let mut g = [[0.0; MAX_PARAMS]; N_STATES];
        for i in 0..nx {
            for (j, fij) in f[i].iter_mut().enumerate().take(nx) {
                let mut a2 = 0.0;
                for k in 0..nx {
                    a2 += lin.dfdx[i][k] * lin.dfdx[k][j];
                }
                *fij = lin.dfdx[i][j] * dt + 0.5 * a2 * dt * dt;
            }
            f[i][i] += 1.0;
            for (j, gij) in g[i].iter_mut().enumerate().take(np) {
                let mut ab = 0.0;
                for k in 0..nx {
                    ab += lin.dfdx[i][k] * lin.dfdtheta[k][j];
                }
                *gij = lin.dfdtheta[i][j] * dt + 0.5 * ab * dt * dt;
            }
        }
        let (p, w) = committed_and_work(&mut self.cov, self.front);
        // Pθθ unchanged.
        for i in nx..n {
            w[i][nx..n].copy_from_slice(&p[i][nx..n]);
        }
        // New Pxθ = Φxx Pxθ + Φxθ Pθθ; T1 = Φxx Pxx + Φxθ Pθx.
        // Row by row over contiguous rows of P: each sum is formed in the same order of k as
        // a dot product per (i, j), so the result is the same to the bit.
        let mut t1 = [[0.0; N_STATES]; N_STATES];
        for i in 0..nx {
            let mut s = [0.0; MAX_AUG];
            for k in 0..nx {
                let fik = f[i][k];
                for (sj, pkj) in s[..n].iter_mut().zip(&p[k][..n]) {
                    *sj += fik * pkj;
                }
            }
            for k in 0..np {
                let gik = g[i][k];
                // Φxθ is sparse (a state sees few parameters); a zero adds nothing.
                if gik == 0.0 {
                    continue;
                }
                for (sj, pkj) in s[..n].iter_mut().zip(&p[nx + k][..n]) {
                    *sj += gik * pkj;
                }
            }
            t1[i][..nx].copy_from_slice(&s[..nx]);
            for j in nx..n {
                w[i][j] = s[j];
                w[j][i] = s[j];
            }
        }
        // New Pxx = T1 Φxxᵀ + Pxθ' Φxθᵀ.
        for i in 0..nx {
            for j in 0..=i {
                let mut s = 0.0;
                for k in 0..nx {
                    s += t1[i][k] * f[j][k];
                }
                for k in 0..np {
                    s += w[i][nx + k] * g[j][k];
                }
                w[i][j] = s;
                w[j][i] = s;
            }
        }
        let states = self.model.state_set().states();
        for (k, &i) in states.iter().enumerate() {
            w[k][k] += self.q_var[i] * dt;
        }
        for i in 0..np {
            let q = self.cfg.param_process_noise[i];
            w[nx + i][nx + i] += q * q * dt;
        }
    }

    /// Whether the process noise of state `i` (full-state order) is estimated: configured so,
    /// and the record measures the state. An unmeasured state's corrections come only from the
    /// outputs it drives, whose innovations carry the parameters' errors too, so the
    /// statistic reads parameter error as process noise: on the synthetic lateral record
    /// without its β channel, adapting β's `Q` ended at `CY_β` −0.50, `Cn_r` −0.92 (truth
    /// −0.90, −0.35); keeping the configured `Q`, within 7 %.
    fn q_adapted(&self, i: usize) -> bool {
        self.cfg.adaptive_q_states[i] && !self.unmeasured.is_some_and(|u| u[i])
    }

    /// One step of the state process-noise estimate (module doc, "State process noise from
    /// the record"): `q ← max(q_min, q + a c / dt)` per adapted state, `c` this sample's
    /// statistic (`cross`: the cross products of the state corrections, for the states in
    /// `adaptive_q_own_lags` also their own-lag products) divided by its sensitivity
    /// ([`sensitivity`]), `a = 1/min(k + ADAPTIVE_Q_PRIOR_SAMPLES, W)`; `acc` becomes the
    /// forgotten sums.
    fn adapt_process_noise(
        &mut self,
        acc: &[[f64; N_OUTPUTS]; N_STATES],
        cross: &[f64; N_STATES],
        dt: f64,
    ) {
        self.q_count = self.q_count.saturating_add(1);
        let k = self.q_count.saturating_add(ADAPTIVE_Q_PRIOR_SAMPLES);
        let a = 1.0 / f64::from(k.min(self.cfg.adaptive_q_window.max(1)));
        for (k, &i) in self.model.state_set().states().iter().enumerate() {
            self.q_acc[k] = acc[k];
            if !self.q_adapted(i) {
                continue;
            }
            let q0 = self.cfg.state_process_noise[i];
            let q = self.q_var[i] + a * cross[k] / dt;
            self.q_var[i] = q.max(q0 * q0);
        }
    }

    fn publish(&mut self, t_s: f64) {
        let nx = self.nx;
        let mut all = true;
        let of = self.output_factors();
        for i in 0..self.np {
            let factor = self.sigma_factor_of(i, &of);
            let var = self.p()[nx + i][nx + i].max(0.0);
            let sf = libm::sqrt(var);
            if sf < 0.5 * self.cfg.priors.prior[i].sigma {
                self.identified[i] = true;
            }
            all &= self.identified[i];
            self.est.set(i, self.z[nx + i], Some(libm::sqrt(var * factor)), self.identified[i]);
        }
        self.est.t_s = t_s;
        self.est.status = if all { Status::Running } else { Status::Initialising };
    }
}

impl Estimator for Ekf {
    fn method(&self) -> &'static str {
        "ekf"
    }

    fn structure(&self) -> &ModelStructure {
        &self.cfg.structure
    }

    fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        if self.diverged {
            return Err(EstimatorError::Numerical {
                what: "EKF diverged earlier; its estimates are not a result",
                t_s: s.t_s,
            });
        }
        check_finite(s)?;
        let u1 = self.model.inputs(s)?;
        let u0 = match self.last {
            Some(u0) if !self.pending_init => u0,
            _ => {
                self.initialise(s, u1)?;
                self.publish(s.t_s);
                return Ok(&self.est);
            }
        };
        let dt = s.t_s - u0.t_s;
        if dt.is_nan() || dt <= 0.0 {
            return Err(EstimatorError::NonFiniteInput { field: "dt_s", value: dt, t_s: s.t_s });
        }
        self.passed_over += 1;
        if self.passed_over < self.cfg.update_every {
            return Ok(&self.est);
        }
        self.passed_over = 0;
        let z = self.predict(&u0, &u1, dt, s.t_s)?;
        let mut pending = self.pending(z);
        for &o in self.model.state_set().outputs() {
            if let update::Measured::LockedOut(o) = self.measure(o, s, &mut pending)? {
                return self.locked_out(pending.counts, o, s, u1);
            }
        }
        let n = self.nx + self.np;
        change::mirror_lower(self.work_mut(), n);
        self.check_state(&pending.z, s.t_s)?;
        self.commit(pending, s.t_s, dt);
        self.last = Some(u1);
        if let Some(h) = self.change_h {
            self.test_for_change(s.t_s, h);
        }
        self.publish(s.t_s);
        Ok(&self.est)
    }

    fn estimates(&self) -> &Estimates {
        &self.est
    }

    fn nis(&self) -> Option<f64> {
        (self.nis_count > 0).then(|| self.nis_sum / self.nis_count as f64)
    }

    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        (i < self.np && j < self.np).then(|| {
            self.p()[self.nx + i][self.nx + j]
                * libm::sqrt(self.sigma_factor(i) * self.sigma_factor(j))
        })
    }

    fn events(&self) -> &EventLog {
        &self.events
    }

    fn new_manoeuvre(&mut self) {
        self.pending_init = true;
    }
}

mod blocks;
mod change;
#[cfg(test)]
mod tests;
mod update;

pub use blocks::EkfBlocks;
