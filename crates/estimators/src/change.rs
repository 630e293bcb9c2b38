//! Change detection for the equation-error estimators ([`crate::Rls`],
//! [`crate::FiniteTimeSmpe`]): per coefficient equation, a test on the drift of a short-memory
//! fit against the estimator's own memory, normalised by that drift's observed scatter while
//! nothing changes; an alarm re-opens the equation's memory.
//!
//! Sources: Basseville & Nikiforov, *Detection of Abrupt Changes: Theory and Application*,
//! Prentice Hall 1993, §2.4, §7.2 (GLR for an additive change in a regression, on a window) and
//! §8.1 (the "two models" approach: a short and a long model compared by their distance);
//! Ljung & Gunnarsson, "Adaptation and tracking in system identification — a survey",
//! *Automatica* 26(1), 1990 (the tracking/noise trade-off of a memory's length, which a pair of
//! memories sidesteps); Satterthwaite, "An approximate distribution of estimates of variance
//! components", *Biometrics Bulletin* 2(6), 1946 (a scaled χ² matched to two moments);
//! Abramowitz & Stegun 26.4.4–26.4.5 (the χ² tail of whole degrees of freedom). The EKF's
//! change test (`crate::ekf`, its `change` module) is the precedent in this crate: it too
//! standardises a drift of the estimates rather than a residual.
//!
//! # The statistic
//!
//! Equation `C = φᵀθ + v`, main memory `A_l = P⁻¹` with estimate `θ_l` (forgetting `λ`, τ_l =
//! 2 s by default). Beside it a short memory of the same samples, `A_s = Σ λ_s^{n−i} φφᵀ`,
//! `b_s = Σ λ_s^{n−i} φ y` (`τ_s` = [`ChangeConfig::short_memory_s`]). Its residuals at the main
//! estimate give the score `s = b_s − A_s θ_l`; the short fit, held to `θ_l` by a prior worth
//! `κ A_l` ([`PRIOR_FRACTION`] of the short memory's samples, so that directions the last
//! fraction of a second does not determine drift by nothing rather than by noise), drifts by
//! `Δ = θ_s − θ_l = (A_s + κ A_l)⁻¹ s`, and
//!
//! ```text
//! d = Δᵀ (A_s + κ A_l) Δ = sᵀ (A_s + κ A_l)⁻¹ s
//! ```
//!
//! is both the drift in the short memory's own metric and the GLR of "the parameters of the
//! short memory differ from the long one's" (Basseville & Nikiforov §7.2, on an exponential
//! window). With white Gaussian residuals of variance `σ²` and `κ → 0`, `d/σ² ~ χ²_p`.
//!
//! On the F-16 the linear model's error is slow and heavy-tailed (docs/change-detection.md):
//! `d` is far from `σ² χ²_p`. So it is **normalised by its own scatter**: running moments
//! `m₁ = E d`, `m₂ = E d²` over [`ChangeConfig::scale_memory_s`] (exponential, with `1/k`
//! gains at first so that the start is a plain mean), `d` winsorised at the current threshold
//! before it enters them (a change does not raise its own reference), frozen during the rest
//! after an alarm. `d` is then taken as a scaled χ² with the same two moments (Satterthwaite
//! 1946): `ν = 2 m₁² / (m₂ − m₁²)`, rounded down (a heavier tail), and the alarm is
//!
//! ```text
//! d > m₁ χ²_ν(1 − α) / ν
//! ```
//!
//! A heavy tail shows as a large variance against the mean, a small `ν` and a higher threshold
//! against the mean: measured, not assumed.
//!
//! # The threshold
//!
//! `d` is tested at every sample, but it is a sum over the short memory: two values `τ_s` apart
//! share `e^{−1}` of their score, and one test per `τ_s` is counted as independent. For a mean
//! time `T_fa` between false alarms over the `E` equations
//! ([`ChangeConfig::false_alarm_interval_s`]):
//!
//! ```text
//! α = τ_s / (T_fa E)
//! ```
//!
//! The tests start after [`ChangeConfig::warmup_s`] from the memory's initialisation (the
//! moments learn meanwhile).
//!
//! # What an alarm does
//!
//! The main memory is re-formed with its samples from before the short memory kept with weight
//! `w` ([`ChangeConfig::memory_kept`]) and the short memory's at full weight:
//!
//! ```text
//! A_l ← w (A_l − A_s) + A_s,   b_l ← w (b_l − b_s) + b_s,   θ_l = A_l⁻¹ b_l,   P = A_l⁻¹
//! ```
//!
//! (`b_l = A_l θ_l`; `A_l − A_s` is the part of the main memory the short one forgot.) The
//! residual sum of squares and the effective count are re-formed the same way. The tests then
//! rest, and the moments stay frozen, for [`ChangeConfig::holdoff_s`] (the main memory regrows
//! over its own length). Each alarm is an [`crate::EventKind::ChangeDetected`] event naming
//! the coefficient, with the normalised drift `d/m₁` as its statistic.
//!
//! # On the default flight
//!
//! Measured in docs/change-detection.md (200 Monte Carlo runs): no false alarm in 3.3 h
//! without damage, but the 30 % stiffness and roll-damping loss detected in 8 runs of 200: the
//! linear model's error moves the short memory as far from the long one as the damage does,
//! and the measured tail (`ν` mostly 1) puts the threshold above both. Hence off by default
//! ([`crate::Rls::new`] has no test until [`crate::Rls::enable_change_detection`]).

// Index loops follow the equations line by line.
#![allow(clippy::needless_range_loop)]

use crate::EstimatorError;
use crate::linalg::{Square, cholesky, cholesky_inverse, cholesky_solve};
use crate::vocabulary::N_TERMS;

/// Default short memory `τ_s`, s: a few tenths of a second, so that a re-opened memory holds
/// mostly post-change samples a second after the change; long enough to span part of a
/// short-period cycle (0.27 Hz on the default flight) and separate the stiffness from the bias.
pub const DEFAULT_SHORT_MEMORY_S: f64 = 0.4;

/// Default memory of the drift's moments, s: long against the short memory (about 25
/// independent drifts), short against a flight condition's change.
pub const DEFAULT_SCALE_MEMORY_S: f64 = 10.0;

/// Default warm-up of the moments after the exact initialisation, s, before the first test.
pub const DEFAULT_WARMUP_S: f64 = 5.0;

/// Default weight `w` of the memory from before the short memory on an alarm.
pub const DEFAULT_MEMORY_KEPT: f64 = 0.02;

/// Default rest of the tests after an alarm, s: the default main memory's length (2 s), over
/// which it regrows.
pub const DEFAULT_HOLDOFF_S: f64 = 2.0;

/// The prior `κ A_l` holding the short fit to the main estimate, as a fraction of the short
/// memory's samples (`κ = PRIOR_FRACTION τ_s / τ_l`): weak where the short memory is excited,
/// decisive where it is not.
pub const PRIOR_FRACTION: f64 = 0.25;

/// The recent memory an alarm re-opens the main one on, as a fraction of `τ_s`: the short
/// memory detects, but a tenth of a second after a change most of its weight is still on the
/// samples before it; a quarter of `τ_s` (0.1 s by default) holds mostly samples after the
/// change by the time the test sees it, and the kept fraction of the old memory regularises
/// what it does not determine.
pub const RECENT_FRACTION: f64 = 0.25;

/// Most degrees of freedom of the moment-matched χ² (module doc): more than the terms of any
/// equation would mean a lighter tail than white noise gives, which the test does not credit.
pub const MAX_DOF: usize = N_TERMS;

/// Configuration of the change test of the equation-error estimators (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeConfig {
    /// Mean time between false alarms over all of the estimator's equations, s (> 0).
    pub false_alarm_interval_s: f64,
    /// Short memory `τ_s`, s (> 0).
    pub short_memory_s: f64,
    /// Memory of the drift's moments, s (> 0).
    pub scale_memory_s: f64,
    /// Warm-up of the moments after the initialisation, s (≥ 0).
    pub warmup_s: f64,
    /// Weight `w ∈ (0, 1]` kept of the memory from before the short memory on an alarm.
    pub memory_kept: f64,
    /// Rest of the tests after an alarm, s (≥ 0).
    pub holdoff_s: f64,
}

impl Default for ChangeConfig {
    /// One false alarm per hour, 0.4-s short memory, 10-s moments, 5-s warm-up, `w` = 0.02,
    /// 2-s rest.
    fn default() -> Self {
        Self {
            false_alarm_interval_s: crate::ekf::DEFAULT_CHANGE_FALSE_ALARM_INTERVAL_S,
            short_memory_s: DEFAULT_SHORT_MEMORY_S,
            scale_memory_s: DEFAULT_SCALE_MEMORY_S,
            warmup_s: DEFAULT_WARMUP_S,
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
        let non_negative = |v: f64| v >= 0.0 && v.is_finite();
        let (pos, nonneg) = ("must be finite and > 0", "must be finite and ≥ 0");
        let checks: [(&'static str, f64, bool, &'static str); 6] = [
            (
                "change_false_alarm_interval_s",
                self.false_alarm_interval_s,
                positive(self.false_alarm_interval_s),
                pos,
            ),
            ("change_short_memory_s", self.short_memory_s, positive(self.short_memory_s), pos),
            ("change_scale_memory_s", self.scale_memory_s, positive(self.scale_memory_s), pos),
            ("change_warmup_s", self.warmup_s, non_negative(self.warmup_s), nonneg),
            (
                "change_memory_kept",
                self.memory_kept,
                self.memory_kept > 0.0 && self.memory_kept <= 1.0,
                "must be in (0, 1]",
            ),
            ("change_holdoff_s", self.holdoff_s, non_negative(self.holdoff_s), nonneg),
        ];
        for (field, value, ok, reason) in checks {
            if !ok {
                return Err(EstimatorError::InvalidConfig { field, value, reason });
            }
        }
        Ok(self)
    }

    /// The false-alarm probability `α = dt / (T_fa E)` of one sample's test, `dt_s` apart, with
    /// `equations` equations tested at once (module doc), at most 1.
    pub fn alpha(&self, equations: usize, dt_s: f64) -> f64 {
        (dt_s / (self.false_alarm_interval_s * equations.max(1) as f64)).min(1.0)
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

/// The smallest sudden step of one parameter that a test of it can detect within `window_s`
/// of the step, with probability `power` (in `[0.5, 1)`) and at most one false alarm per
/// `false_alarm_interval_s`, in units of the σ of that parameter's estimate by an
/// exponentially forgotten memory of `memory_s` (`λ = 1 − dt/τ`, what [`crate::Rls`] and
/// [`crate::FiniteTimeSmpe`] publish). The information limit of a detector on the equation's
/// own regressors: a smaller step is not in the window's data; the inverse of
/// [`detection_power`].
///
/// At `τ` = 2 s, 0.5 s, 100 Hz and one false alarm per hour: 13.2 σ_l for even odds, 17.9 σ_l
/// for 95 %. `+∞` for a non-positive interval, window or memory.
pub fn detectable_step_sigmas(
    memory_s: f64,
    window_s: f64,
    dt_s: f64,
    false_alarm_interval_s: f64,
    power: f64,
) -> f64 {
    let Some((z_alpha, gain)) = window_test(memory_s, window_s, dt_s, false_alarm_interval_s)
    else {
        return f64::INFINITY;
    };
    // One-sided normal quantile of `power` from the two-sided χ²₁ tail: P(|Z| > z) = 2(1 − p).
    let z_power = libm::sqrt(chi2_upper_quantile(1, (2.0 * (1.0 - power)).clamp(1e-300, 1.0)));
    (z_alpha + z_power) / gain
}

/// The probability that the best window test detects a sudden step of `step_sigmas` σ_l of one
/// parameter within `window_s` (the arguments of [`detectable_step_sigmas`]): `Φ(z − z_α)`
/// with `z = (δ/σ_l) √(m (1 − λ)/(1 + λ))`, the far tail neglected.
///
/// The test knows the step's onset and size and estimates the other parameters in the window;
/// the residuals are white; the window's regressors are as rich as the memory's. Each favours
/// detection, so a real detector does no better. Its statistic on the `m = window_s/dt_s`
/// samples after the onset is normal with unit variance and mean `z`, because an
/// exponentially forgotten estimate of stationary regressors with covariance `R` has variance
/// `σ_l² = σ² [R⁻¹]_kk (1 − λ)/(1 + λ)` (the sum of `λ^{2j}` over the square of the sum of
/// `λ^j`; the tracking/noise trade-off of Ljung & Gunnarsson 1990) while the window holds
/// `m/(σ² [R⁻¹]_kk)` of information about `θ_k` (Basseville & Nikiforov 1993, §7.2: the GLR of
/// an additive change in a regression). It is tested at every sample with `α = dt/T_fa`,
/// two-sided (the sign unknown). A step that moves several parameters together in a direction the others'
/// regressors do not share (a derivative stepping about the trim, its bias moving with it)
/// carries about this information; one along them carries less.
pub fn detection_power(
    step_sigmas: f64,
    memory_s: f64,
    window_s: f64,
    dt_s: f64,
    false_alarm_interval_s: f64,
) -> f64 {
    let Some((z_alpha, gain)) = window_test(memory_s, window_s, dt_s, false_alarm_interval_s)
    else {
        return 0.0;
    };
    let y = step_sigmas.abs() * gain - z_alpha;
    // Φ(y) from the χ²₁ tail: P(Z > |y|) = P(χ²₁ > y²)/2.
    let tail = 0.5 * chi2_upper_tail(1, y * y);
    if y >= 0.0 { 1.0 - tail } else { tail }
}

/// The window test's two-sided threshold `z_α` (`α = dt/T_fa`) and the gain
/// `√(m (1 − λ)/(1 + λ))` from a step in σ_l to its mean `z`; `None` when undefined.
fn window_test(memory_s: f64, window_s: f64, dt_s: f64, interval_s: f64) -> Option<(f64, f64)> {
    let lambda = 1.0 - dt_s / memory_s;
    let m = libm::floor(window_s / dt_s + 1e-9);
    let per_sample = m * (1.0 - lambda) / (1.0 + lambda);
    if !(per_sample > 0.0 && lambda < 1.0 && interval_s > 0.0 && dt_s > 0.0) {
        return None;
    }
    let alpha = (dt_s / interval_s).min(1.0);
    Some((libm::sqrt(chi2_upper_quantile(1, alpha)), libm::sqrt(per_sample)))
}

/// What a sample's test decided ([`ChangeTest::test`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Verdict {
    /// No change (or no test: warming up, resting).
    Clear,
    /// A change, with the normalised drift `d/m₁`.
    Alarm(f64),
}

/// The short memory's sums (module doc): information, `Σ φ y`, `Σ y²` and the λ_s-weighted
/// count, the pieces an alarm's re-opening takes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ShortMemory {
    pub(crate) a: Square<N_TERMS>,
    pub(crate) b: [f64; N_TERMS],
    pub(crate) yy: f64,
    pub(crate) count: f64,
}

impl ShortMemory {
    /// Adds one sample (leading `n` regressors) with forgetting `lam`.
    fn add(&mut self, phi: &[f64; N_TERMS], n: usize, y: f64, lam: f64) {
        for i in 0..n {
            for j in i..n {
                let v = self.a[i][j] * lam + phi[i] * phi[j];
                self.a[i][j] = v;
                self.a[j][i] = v;
            }
            self.b[i] = self.b[i] * lam + phi[i] * y;
        }
        self.yy = self.yy * lam + y * y;
        self.count = self.count * lam + 1.0;
    }
}

/// Running moments of the drift statistic `d` (module doc).
#[derive(Debug, Clone, Copy, Default)]
struct Moments {
    m1: f64,
    m2: f64,
    /// Values taken, for the `1/k` gains of the start.
    k: f64,
}

impl Moments {
    /// Takes `d` with gain `max(dt/τ, 1/k)`.
    fn add(&mut self, d: f64, dt_over_tau: f64) {
        self.k += 1.0;
        let g = dt_over_tau.max(1.0 / self.k);
        self.m1 += g * (d - self.m1);
        self.m2 += g * (d * d - self.m2);
    }

    /// The moment-matched χ²'s degrees of freedom `⌊2 m₁² / (m₂ − m₁²)⌋` in `1..=MAX_DOF`.
    fn dof(&self) -> usize {
        let var = self.m2 - self.m1 * self.m1;
        if var <= 0.0 {
            return MAX_DOF;
        }
        let nu = 2.0 * self.m1 * self.m1 / var;
        (libm::floor(nu) as usize).clamp(1, MAX_DOF)
    }
}

/// One equation's test: its short memory, the drift's moments, the thresholds per degrees of
/// freedom and the rest periods.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChangeTest {
    pub(crate) config: ChangeConfig,
    /// Equations tested at once, for `α`.
    equations: usize,
    /// `χ²_k(1 − α) / k` for `k = 1..=MAX_DOF`, once the sample interval is known.
    quantiles: Option<[f64; MAX_DOF]>,
    short: ShortMemory,
    /// The memory an alarm re-opens on, `τ_s` × [`RECENT_FRACTION`].
    recent: ShortMemory,
    moments: Moments,
    last_t_s: Option<f64>,
    /// Tests count from this time on; the moments learn from `learn_t_s`.
    resume_t_s: Option<f64>,
    learn_t_s: f64,
    last_statistic: f64,
    last_threshold: f64,
}

impl ChangeTest {
    /// A test with the checked `config`, one of `equations` tested at once.
    pub(crate) fn new(config: ChangeConfig, equations: usize) -> Self {
        let empty =
            ShortMemory { a: [[0.0; N_TERMS]; N_TERMS], b: [0.0; N_TERMS], yy: 0.0, count: 0.0 };
        Self {
            config,
            equations,
            quantiles: None,
            short: empty,
            recent: empty,
            moments: Moments::default(),
            last_t_s: None,
            resume_t_s: None,
            learn_t_s: f64::NEG_INFINITY,
            last_statistic: 0.0,
            last_threshold: f64::INFINITY,
        }
    }

    /// The normalised drift `d/m₁` of the last sample (0 before one).
    pub(crate) fn statistic(&self) -> f64 {
        self.last_statistic
    }

    /// The last threshold on `d/m₁`, `χ²_ν(1 − α)/ν` (infinite before the first test).
    pub(crate) fn threshold(&self) -> f64 {
        self.last_threshold
    }

    /// The recent memory an alarm re-opens the main one on (module doc).
    pub(crate) fn recent(&self) -> &ShortMemory {
        &self.recent
    }

    /// Adds one sample (leading `n` regressors) to the short and the recent memories; returns
    /// the interval `dt` since the last (0 for the first) and `λ_s = e^{−dt/τ_s}`.
    fn add(&mut self, t_s: f64, phi: &[f64; N_TERMS], n: usize, y: f64) -> (f64, f64) {
        let dt = self.last_t_s.map_or(0.0, |l| (t_s - l).max(0.0));
        self.last_t_s = Some(t_s);
        let lam = libm::exp(-dt / self.config.short_memory_s);
        self.short.add(phi, n, y, lam);
        self.recent.add(phi, n, y, libm::exp(-dt / (RECENT_FRACTION * self.config.short_memory_s)));
        if self.quantiles.is_none() && dt > 0.0 {
            let alpha = self.config.alpha(self.equations, dt);
            let mut q = [0.0; MAX_DOF];
            for (k, q) in q.iter_mut().enumerate() {
                *q = chi2_upper_quantile(k + 1, alpha) / (k + 1) as f64;
            }
            self.quantiles = Some(q);
        }
        (dt, lam)
    }

    /// One sample `(φ, y)` after the main memory (forgetting `lambda`) took it (estimate
    /// `theta`, covariance `p`, leading `n`): the short memory, the drift `d`, its moments and
    /// the test.
    pub(crate) fn test(
        &mut self,
        t_s: f64,
        (phi, y): (&[f64; N_TERMS], f64),
        (n, lambda): (usize, f64),
        theta: &[f64; N_TERMS],
        p: &Square<N_TERMS>,
    ) -> Verdict {
        let (dt, lam_s) = self.add(t_s, phi, n, y);
        let resume = *self.resume_t_s.get_or_insert(t_s + self.config.warmup_s);
        // κ A_l worth PRIOR_FRACTION of the short memory's samples: κ/(1 − λ) = f/(1 − λ_s).
        let kappa = PRIOR_FRACTION * (1.0 - lambda) / (1.0 - lam_s).max(1.0 - lambda);
        let Some(d) = drift(&self.short, theta, p, n, kappa) else { return Verdict::Clear };
        let m1 = self.moments.m1;
        let limit = self.quantiles.map_or(f64::INFINITY, |q| m1 * q[self.moments.dof() - 1]);
        let testing = t_s >= resume && m1 > 0.0;
        if t_s >= self.learn_t_s {
            // Winsorised at the current limit (once there is one): a change does not raise
            // its own reference.
            let capped = if testing { d.min(limit) } else { d };
            self.moments.add(capped, dt / self.config.scale_memory_s);
        }
        if !testing {
            return Verdict::Clear;
        }
        self.last_statistic = d / m1;
        self.last_threshold = limit / m1;
        if d > limit {
            self.resume_t_s = Some(t_s + self.config.holdoff_s);
            self.learn_t_s = t_s + self.config.holdoff_s;
            return Verdict::Alarm(d / m1);
        }
        Verdict::Clear
    }
}

/// `d = sᵀ (A_s + κ A_l)⁻¹ s`, `s = b_s − A_s θ_l`, `A_l = P⁻¹` (module doc); `None` when a
/// factorisation fails.
fn drift(
    short: &ShortMemory,
    theta: &[f64; N_TERMS],
    p: &Square<N_TERMS>,
    n: usize,
    kappa: f64,
) -> Option<f64> {
    let mut l = [[0.0; N_TERMS]; N_TERMS];
    if !cholesky(p, n, &mut l) {
        return None;
    }
    let mut m = [[0.0; N_TERMS]; N_TERMS];
    cholesky_inverse(&l, n, &mut m);
    let mut s = [0.0; N_TERMS];
    for i in 0..n {
        s[i] = short.b[i] - (0..n).map(|j| short.a[i][j] * theta[j]).sum::<f64>();
        for j in 0..n {
            m[i][j] = short.a[i][j] + kappa * m[i][j];
        }
    }
    if !cholesky(&m, n, &mut l) {
        return None;
    }
    let mut x = s;
    cholesky_solve(&l, n, &mut x);
    let d = (0..n).map(|i| s[i] * x[i]).sum::<f64>();
    d.is_finite().then_some(d.max(0.0))
}

#[cfg(test)]
mod tests;
