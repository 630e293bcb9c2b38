//! Change detection for the equation-error estimators ([`crate::Rls`],
//! [`crate::FiniteTimeSmpe`]): a sequential test per coefficient equation on its normalised
//! a-priori residuals, which on an alarm re-opens that equation's memory.
//!
//! Sources: Willsky & Jones, "A generalized likelihood ratio approach to the detection and
//! estimation of jumps in linear systems", *IEEE TAC* 21(1), 1976; Basseville & Nikiforov,
//! *Detection of Abrupt Changes: Theory and Application*, Prentice Hall 1993, §2.4 and §7.2
//! (GLR tests for an additive change in a regression model, on a window); Abramowitz & Stegun
//! 26.4.4–26.4.5 (the χ² tail of whole degrees of freedom).
//!
//! # The statistic
//!
//! Equation `C = φᵀθ + v` with a-priori residual `e_n = y_n − φ_nᵀθ̂_{n−1}`. A jump `Δ` of the
//! parameters at the onset adds `φ_nᵀΔ` to every later residual. Over a window of `W` samples
//! ([`ChangeConfig::block_s`]) the log-likelihood ratio of "a jump `Δ` at the window's start"
//! against "no jump", maximised over `Δ`, is the generalised likelihood ratio
//!
//! ```text
//! T = sᵀ A⁻¹ s / (σ̂² f),     s = Σ_window φ_n e_n,   A = Σ_window φ_n φ_nᵀ,   Δ̂ = A⁻¹ s
//! ```
//!
//! (Willsky & Jones 1976; the normalised residuals `e/σ̂` weighted by their regressors). With no
//! change `s` is a sum of regressors times residuals of variance `σ̂²`: for white residuals
//! `Var s = σ² A` and `T ~ χ²_p` exactly (Gaussian residuals, `p` terms). It sums the jump's
//! effect coherently over the window, whatever the sign of the regressors (a change of a
//! damping derivative multiplies a zero-mean rate, so the residual's mean need not move, and
//! the residual variance grows by only `(φᵀΔ)²/σ²`, a quarter on the default flight: a test on
//! the variance of `e` did not see the default damage at all).
//!
//! The residuals of the equation-error pipeline are coloured (differentiated gyros, smoothed
//! channels, turbulence): `Var s = σ² Σ_i Σ_j ρ(i−j) φ_i φ_jᵀ`, the matrix `M` of the
//! coloured-residual σ ([`crate::coloured`]) over the window. The regressors of the aircraft
//! equations vary little over a window (excitation ≤ 1.6 Hz, window 0.25 s), so it is taken as
//! `f A` with the window's variance factor of a mean (Bartlett's effective-sample-size factor)
//!
//! ```text
//! f = 1 + 2 Σ_{k=1}^{K} (1 − k/W) ρ̂(k)      (K < W the coloured sum's truncation lag)
//! ```
//!
//! floored at [`MIN_COLOUR_FACTOR`] (differentiated noise has a negative lobe that cancels most
//! of the positive one). The memory's own long-run factor (`tr(P M)` over its white value) was
//! tried first: over 2 s it sees the slow part of the residual colour (turbulence, model error)
//! that a 0.25-s window hardly does, and made the roll equation's `f` ≈ 25, its test deaf.
//! `σ̂²` and `f` are those of the memory at the window's start (the window's own residuals
//! would raise them with the change they test). `σ̂²` comes from a memory of finite length, so
//! `T` is slightly heavier-tailed than `χ²_p`.
//!
//! # The threshold
//!
//! Windows follow each other without overlap, each tested once, so the tests are independent
//! (residuals correlated for less than a window) and the mean time between false alarms of one
//! equation is `W_s / α` (`W_s` the window in seconds, `α` the false-alarm probability of one
//! test). For a mean time `T_fa` between false alarms over the `E` equations of an estimator
//! ([`ChangeConfig::false_alarm_interval_s`]):
//!
//! ```text
//! α = W_s / (T_fa E),     alarm when  T > χ²_p(1 − α)
//! ```
//!
//! (the upper `α` quantile of `χ²_p`, by bisection on its exact tail, [`chi2_upper_tail`]).
//! On white residuals through the RLS recursion the measured rate is 0.66 of the design
//! (`tests::white_residuals_false_alarm_rate_matches_the_design`); on the default F-16 flight it
//! is 50 times the design (docs/change-detection.md): the linear model's slow error there makes
//! `T` far heavier-tailed than χ², which is why the test is off by default.
//! One hour, six equations and 0.25-s windows give `α = 1.16·10⁻⁵`: `T > 39.7` for 8 terms,
//! `T > 19.2` for one. The default `T_fa` is one hour, as the EKF's change test
//! ([`crate::ekf::DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S`]).
//!
//! # What an alarm does
//!
//! The fit keeps the window's information (`A`, `Σ λ^{n−i} φ y`, `Σ y²`, their count) beside
//! its memory, at the cost of a rank-one update per sample. On an alarm the memory from before
//! the window is kept with weight `w` ([`ChangeConfig::memory_kept`]) and the window's samples
//! with weight 1:
//!
//! ```text
//! A_mem ← w (A_mem − A_win) + A_win,   b ← w (b − b_win) + b_win,   θ̂ = A_mem⁻¹ b,   P = A_mem⁻¹
//! ```
//!
//! (`A_mem = P⁻¹`, `b = A_mem θ̂` are the memory's exact normal equations.) The directions the
//! new samples determine follow them at once; those they do not (a fraction of a second of
//! data does not separate every term) stay near the old estimate, regularised by the kept
//! fraction of the old memory, rather than jumping on noise. The residual sum of squares and
//! the effective count are re-formed the same way; the coloured-residual sum keeps `w²` of the
//! old and adds the window as white. Then the tests rest for [`ChangeConfig::holdoff_s`] (`σ̂²`
//! re-settles from the new memory), as they do after the fit's exact initialisation. Each alarm
//! is an [`crate::EventKind::ChangeDetected`] event naming the coefficient, with `T` as its
//! statistic.

use crate::EstimatorError;
use crate::linalg::{Square, cholesky, cholesky_solve};
use crate::vocabulary::N_TERMS;

/// Default window, s: long enough that the residual correlation of the default pipeline (its
/// 21-point, 0.2-s differentiator at 100 Hz) does not couple successive windows much, short
/// enough for a one-second re-convergence.
pub const DEFAULT_BLOCK_S: f64 = 0.25;

/// Default weight `w` of the memory from before the window of an alarm.
pub const DEFAULT_MEMORY_KEPT: f64 = 0.02;

/// Default rest of the tests after an alarm and after the exact initialisation, s: the
/// default memory's length (2 s), over which `σ̂²` settles.
pub const DEFAULT_HOLDOFF_S: f64 = 2.0;

/// Floor of the colour factor `f` (module doc): differentiated noise has a negative lobe that
/// can cancel most of the memory's long-run variance; the window is shorter than the memory and
/// sees less of that cancellation.
pub const MIN_COLOUR_FACTOR: f64 = 0.25;

/// Configuration of the change test of the equation-error estimators (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeConfig {
    /// Mean time between false alarms over all of the estimator's equations, s (> 0).
    pub false_alarm_interval_s: f64,
    /// Window `W_s`, s (> 0).
    pub block_s: f64,
    /// Weight `w ∈ (0, 1]` kept of the memory from before an alarm's window.
    pub memory_kept: f64,
    /// Rest of the tests after an alarm and after the exact initialisation, s (≥ 0).
    pub holdoff_s: f64,
}

impl Default for ChangeConfig {
    /// One false alarm per hour, 0.25-s windows, `w` = 0.02, 2-s rest.
    fn default() -> Self {
        Self {
            false_alarm_interval_s: crate::ekf::DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S,
            block_s: DEFAULT_BLOCK_S,
            memory_kept: DEFAULT_MEMORY_KEPT,
            holdoff_s: DEFAULT_HOLDOFF_S,
        }
    }
}

impl ChangeConfig {
    /// The configuration, checked.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] naming the first field out of its range.
    pub fn validated(self) -> Result<Self, EstimatorError> {
        let positive = |v: f64| v > 0.0 && v.is_finite();
        let checks: [(&'static str, f64, bool, &'static str); 4] = [
            (
                "change_false_alarm_interval_s",
                self.false_alarm_interval_s,
                positive(self.false_alarm_interval_s),
                "must be finite and > 0",
            ),
            ("change_block_s", self.block_s, positive(self.block_s), "must be finite and > 0"),
            (
                "change_memory_kept",
                self.memory_kept,
                self.memory_kept > 0.0 && self.memory_kept <= 1.0,
                "must be in (0, 1]",
            ),
            (
                "change_holdoff_s",
                self.holdoff_s,
                self.holdoff_s >= 0.0 && self.holdoff_s.is_finite(),
                "must be finite and ≥ 0",
            ),
        ];
        for (field, value, ok, reason) in checks {
            if !ok {
                return Err(EstimatorError::InvalidConfig { field, value, reason });
            }
        }
        Ok(self)
    }

    /// The false-alarm probability `α = W_s / (T_fa E)` of one window's test with `equations`
    /// equations tested at once (module doc), at most 1.
    pub fn alpha(&self, equations: usize) -> f64 {
        (self.block_s / (self.false_alarm_interval_s * equations.max(1) as f64)).min(1.0)
    }

    /// The threshold `χ²_p(1 − α)` of an equation with `terms` terms among `equations`.
    pub fn threshold(&self, equations: usize, terms: usize) -> f64 {
        chi2_upper_quantile(terms.max(1), self.alpha(equations))
    }
}

/// `P(χ²_k > x)` for whole `k ≥ 1` (Abramowitz & Stegun 26.4.4–26.4.5: a finite sum for even
/// `k`; `erfc` and a finite sum for odd `k`).
pub fn chi2_upper_tail(k: usize, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let h = 0.5 * x;
    let e = libm::exp(-h);
    if k.is_multiple_of(2) {
        let (mut term, mut sum) = (1.0, 1.0);
        for j in 1..k / 2 {
            term *= h / j as f64;
            sum += term;
        }
        (e * sum).min(1.0)
    } else {
        // erfc(√(x/2)) + e^{−x/2} Σ_{j=1}^{(k−1)/2} (x/2)^{j−½} / Γ(j + ½).
        let mut term = libm::sqrt(h) / (0.5 * libm::sqrt(core::f64::consts::PI));
        let mut sum = 0.0;
        for j in 1..=(k - 1) / 2 {
            if j > 1 {
                term *= h / (j as f64 - 0.5);
            }
            sum += term;
        }
        (libm::erfc(libm::sqrt(h)) + e * sum).min(1.0)
    }
}

/// The `x` with `P(χ²_k > x) = α` (bisection on [`chi2_upper_tail`]), `α ∈ (0, 1]`.
pub fn chi2_upper_quantile(k: usize, alpha: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 10.0 * k as f64 + 200.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi2_upper_tail(k, mid) > alpha { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// What the end of a window decided ([`ChangeTest::close_block`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Verdict {
    /// No change (or no test: resting, or an incomplete window).
    Clear,
    /// A change, with the statistic `T`.
    Alarm(f64),
}

/// One equation's test: the current window's score `s`, its reference `σ̂² f`, the threshold
/// and the rest period.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChangeTest {
    pub(crate) config: ChangeConfig,
    threshold: f64,
    block_t0_s: Option<f64>,
    last_t_s: Option<f64>,
    score: [f64; N_TERMS],
    /// `σ̂² f` at the window's start.
    reference: Option<f64>,
    /// Whether every sample of the window had a residual variance to refer to.
    complete: bool,
    last_statistic: f64,
    /// Samples in the current window so far, and in the last complete one (0 before one).
    count: usize,
    window_len: usize,
    /// Tests count from this time on (rest after the initialisation and after an alarm).
    resume_t_s: Option<f64>,
}

impl ChangeTest {
    /// A test with the checked `config` and threshold `threshold`.
    pub(crate) fn new(config: ChangeConfig, threshold: f64) -> Self {
        Self {
            config,
            threshold,
            block_t0_s: None,
            last_t_s: None,
            score: [0.0; N_TERMS],
            reference: None,
            complete: true,
            last_statistic: 0.0,
            count: 0,
            window_len: 0,
            resume_t_s: None,
        }
    }

    /// The statistic `T` of the last complete window (0 before one).
    pub(crate) fn statistic(&self) -> f64 {
        self.last_statistic
    }

    /// The threshold `χ²_p(1 − α)`.
    pub(crate) fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Samples in the last complete window, `None` before one.
    pub(crate) fn window_len(&self) -> Option<usize> {
        (self.window_len > 0).then_some(self.window_len)
    }

    /// Adds one sample: regressors `phi` (leading `n`), a-priori residual `e`, forgetting `λ`,
    /// and the memory's `σ̂² f` before it (`None` while `σ̂²` is undefined). Returns whether
    /// this sample ends the window (the next, one interval later, would pass its length).
    pub(crate) fn add(
        &mut self,
        t_s: f64,
        phi: &[f64; N_TERMS],
        n: usize,
        e: f64,
        lambda: f64,
        reference: Option<f64>,
    ) -> bool {
        if self.resume_t_s.is_none() {
            self.resume_t_s = Some(t_s + self.config.holdoff_s);
        }
        let t0 = *self.block_t0_s.get_or_insert_with(|| {
            self.reference = reference;
            t_s
        });
        let dt = self.last_t_s.map_or(0.0, |l| t_s - l);
        self.last_t_s = Some(t_s);
        if reference.is_none() {
            self.complete = false;
        }
        for i in 0..n {
            self.score[i] = lambda * self.score[i] + phi[i] * e;
        }
        self.count += 1;
        dt > 0.0 && t_s + dt >= t0 + self.config.block_s * (1.0 - 1e-9)
    }

    /// The test at the end of a window whose information is `a` (leading `n × n`), at `t_s`;
    /// the window's sums restart.
    pub(crate) fn close_block(&mut self, t_s: f64, a: &Square<N_TERMS>, n: usize) -> Verdict {
        let score = core::mem::replace(&mut self.score, [0.0; N_TERMS]);
        let reference = self.reference.take();
        let complete = core::mem::replace(&mut self.complete, true);
        self.block_t0_s = None;
        self.window_len = core::mem::replace(&mut self.count, 0);
        let resting = self.resume_t_s.is_none_or(|r| t_s < r);
        let Some(reference) = reference.filter(|r| *r > 0.0 && complete && !resting) else {
            return Verdict::Clear;
        };
        // sᵀ A⁻¹ s with a relative ridge: a short window may not separate every term, and the
        // score has no component where A has none.
        let mut ridged = *a;
        let scale = (0..n).map(|i| a[i][i]).fold(0.0, f64::max);
        for i in 0..n {
            ridged[i][i] += 1e-10 * scale;
        }
        let mut l = [[0.0; N_TERMS]; N_TERMS];
        if scale <= 0.0 || !cholesky(&ridged, n, &mut l) {
            return Verdict::Clear;
        }
        let mut x = score;
        cholesky_solve(&l, n, &mut x);
        let t = (0..n).map(|i| score[i] * x[i]).sum::<f64>() / reference;
        self.last_statistic = t;
        if t > self.threshold {
            self.resume_t_s = Some(t_s + self.config.holdoff_s);
            Verdict::Alarm(t)
        } else {
            Verdict::Clear
        }
    }
}

#[cfg(test)]
mod tests;
