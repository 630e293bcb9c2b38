//! Causal numerical differentiation for real-time use (e.g. `q̇` from a recorded `q` when the
//! record has no angular accelerations).
//!
//! Method: least-squares slope of a straight line fitted to the last `N` uniformly spaced
//! samples (a first-order Savitzky–Golay differentiator; Savitzky & Golay, *Anal. Chem.* 36,
//! 1964; Klein & Morelli 2006, ch. 11 on smoothing and numerical differentiation):
//!
//! ```text
//! ẋ̂(t_c) = Σ_k w_k x_k,   w_k = (k − c) / (dt · Σ_j (j − c)²),   c = (N−1)/2,   k = 0 … N−1
//! ```
//!
//! The weights are antisymmetric about the window centre, so the filter has **linear phase**:
//! its output is the derivative estimate at the window centre, i.e. it **lags by exactly
//! `(N−1)·dt/2`** at every frequency. It is exact for ramps (and for quadratics, whose
//! second-order term the antisymmetric weights cancel); for a sinusoid of angular frequency ω
//! the gain relative to the true derivative is `G(ω) = Σ_k w_k sin(ω(k−c)dt) / ω` (→ 1 as
//! `ω·N·dt → 0`). Callers that combine the derivative with other signals should delay those by
//! the same lag (whole samples when `N` is odd) to keep them aligned.
//!
//! No allocation after construction; the window restarts after [`CausalDifferentiator::reset`](crate::differentiate::CausalDifferentiator::reset)
//! (e.g. across a data gap).
//!
//! # The matched smoother
//! The differentiator is itself a smoothing of the derivative. Summation by parts (with
//! `Σ w_k = 0`) gives
//!
//! ```text
//! Σ_k w_k x_k = Σ_{j=0}^{N−2} s_j (x_{j+1} − x_j)/dt,   s_j = −dt Σ_{k≤j} w_k  (≥ 0, Σ s_j = 1)
//! ```
//!
//! i.e. a parabolic (Epanechnikov-shaped) weighting of the derivative at the half-sample points
//! — the discrete form of `∫ K(τ) ẋ(t+τ) dτ`, `K(τ) = 6(T²/4 − τ²)/T³`.
//! [`MatchedSmoother`](crate::differentiate::MatchedSmoother) applies the same weighting to any other signal, `ỹ = Σ_j s_j (y_j + y_{j+1})/2`, i.e. FIR
//! weights `a_k = (s_{k−1} + s_k)/2` with the same length and lag. Passing every other channel
//! of an equation-error regression through it keeps the equation consistent at every frequency
//! (both sides see the same filter), where a plain delay leaves the channels unfiltered against
//! a smoothed derivative (a bias towards zero for regressors with content above the
//! differentiator's band, e.g. turbulence). For `y = ẋ` with `x` a polynomial of degree ≤ 2 the
//! two are equal exactly; in general to second order in `dt`.

/// Errors from constructing a [`CausalDifferentiator`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DifferentiateError {
    /// The window length is below 2.
    #[error("differentiator window must be at least 2 samples, got {window}")]
    Window {
        /// The window length given.
        window: usize,
    },
    /// The sample interval is not finite and positive.
    #[error("differentiator dt_s must be finite and > 0, got {dt_s}")]
    Interval {
        /// The interval given, s.
        dt_s: f64,
    },
}

/// Least-squares-slope differentiator over the last `window` samples, for samples spaced
/// `dt_s` apart. Output units: input units per second.
#[derive(Debug, Clone)]
pub struct CausalDifferentiator {
    fir: Fir,
}

/// An FIR filter over the last `N = weights.len()` samples spaced `dt_s` apart (a ring
/// buffer; no allocation after construction): the running part shared by
/// [`CausalDifferentiator`] and [`MatchedSmoother`], which differ only in their weights.
#[derive(Debug, Clone)]
struct Fir {
    /// Weights, oldest sample first.
    weights: Vec<f64>,
    buf: Vec<f64>,
    head: usize,
    filled: usize,
    dt_s: f64,
}

impl Fir {
    fn new(weights: Vec<f64>, dt_s: f64) -> Self {
        let n = weights.len();
        Self { weights, buf: vec![0.0; n], head: 0, filled: 0, dt_s }
    }

    /// `(N−1)·dt/2`, s: the lag of a linear-phase filter's output behind its newest input.
    fn lag_s(&self) -> f64 {
        (self.weights.len() as f64 - 1.0) * self.dt_s / 2.0
    }

    fn reset(&mut self) {
        self.head = 0;
        self.filled = 0;
    }

    /// Pushes `x`; `Σ_k w_k x_k` over the window once `N` samples were seen, else `None`.
    fn update(&mut self, x: f64) -> Option<f64> {
        let n = self.weights.len();
        self.buf[self.head] = x;
        self.head = (self.head + 1) % n;
        self.filled = (self.filled + 1).min(n);
        if self.filled < n {
            return None;
        }
        // Oldest sample is at `head` (after the increment).
        let mut acc = 0.0;
        for (k, w) in self.weights.iter().enumerate() {
            acc += w * self.buf[(self.head + k) % n];
        }
        Some(acc)
    }
}

impl CausalDifferentiator {
    /// A differentiator over `window ≥ 2` samples spaced `dt_s > 0` apart.
    ///
    /// # Errors
    /// [`DifferentiateError`] for `window < 2` or a non-positive `dt_s`.
    pub fn new(window: usize, dt_s: f64) -> Result<Self, DifferentiateError> {
        if window < 2 {
            return Err(DifferentiateError::Window { window });
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(DifferentiateError::Interval { dt_s });
        }
        let c = (window as f64 - 1.0) / 2.0;
        let denom: f64 = (0..window).map(|k| (k as f64 - c).powi(2)).sum::<f64>() * dt_s;
        let weights = (0..window).map(|k| (k as f64 - c) / denom).collect();
        Ok(Self { fir: Fir::new(weights, dt_s) })
    }

    /// The lag of the output behind the newest input, s: `(N−1)·dt/2`.
    pub fn lag_s(&self) -> f64 {
        self.fir.lag_s()
    }

    /// The window length `N`.
    pub fn window(&self) -> usize {
        self.fir.weights.len()
    }

    /// Forgets all samples (the next `N−1` calls return `None`).
    pub fn reset(&mut self) {
        self.fir.reset();
    }

    /// Pushes the newest sample `x` and returns the derivative estimate at the window centre
    /// (time of the newest sample minus [`Self::lag_s`]), or `None` until `N` samples were seen.
    pub fn update(&mut self, x: f64) -> Option<f64> {
        self.fir.update(x)
    }

    /// The gain `G(ω)` of the estimate relative to the true derivative for a sinusoid of angular
    /// frequency `omega_rad_s` (phase is the pure lag [`Self::lag_s`]).
    pub fn gain(&self, omega_rad_s: f64) -> f64 {
        let c = (self.fir.weights.len() as f64 - 1.0) / 2.0;
        let s: f64 = self
            .fir
            .weights
            .iter()
            .enumerate()
            .map(|(k, w)| w * (omega_rad_s * (k as f64 - c) * self.fir.dt_s).sin())
            .sum();
        s / omega_rad_s
    }
}

/// FIR smoother matched to a [`CausalDifferentiator`] of the same window (module doc): weights
/// `a_k = (s_{k−1} + s_k)/2`, symmetric, summing to 1, same lag `(N−1)·dt/2`.
///
/// For a signal **held** between samples (a command applied with a zero-order hold, value
/// `y_j` on `[t_j, t_{j+1})`), the same weighting of the continuous signal is `Σ_j s_j y_j`
/// exactly: [`MatchedSmoother::held_weights`]. A derivative of the integral of such a signal
/// (e.g. `x_{j+1} = x_j + y_j dt`) through the differentiator equals it to rounding.
#[derive(Debug, Clone)]
pub struct MatchedSmoother {
    fir: Fir,
    held: Vec<f64>,
}

impl MatchedSmoother {
    /// The smoother matched to `CausalDifferentiator::new(window, dt_s)`.
    ///
    /// # Errors
    /// As [`CausalDifferentiator::new`].
    pub fn new(window: usize, dt_s: f64) -> Result<Self, DifferentiateError> {
        let d = CausalDifferentiator::new(window, dt_s)?;
        // s_j = −dt Σ_{k≤j} w_k, j = 0 … N−2 (s_{−1} = s_{N−1} = 0).
        let mut s = vec![0.0; window + 1];
        let mut acc = 0.0;
        for j in 0..window - 1 {
            acc -= d.fir.weights[j] * dt_s;
            s[j + 1] = acc;
        }
        let weights = (0..window).map(|k| 0.5 * (s[k] + s[k + 1])).collect();
        let held = (0..window).map(|k| s[k + 1]).collect();
        Ok(Self { fir: Fir::new(weights, dt_s), held })
    }

    /// The FIR weights `a_k`, oldest sample first.
    pub fn weights(&self) -> &[f64] {
        &self.fir.weights
    }

    /// The weights `s_j` for a signal held between samples (struct doc), oldest sample first
    /// (the newest sample's weight is 0: its interval has not elapsed).
    pub fn held_weights(&self) -> &[f64] {
        &self.held
    }

    /// The lag of the output behind the newest input, s: `(N−1)·dt/2`.
    pub fn lag_s(&self) -> f64 {
        self.fir.lag_s()
    }

    /// Forgets all samples (the next `N−1` calls return `None`).
    pub fn reset(&mut self) {
        self.fir.reset();
    }

    /// Pushes the newest sample and returns the smoothed value at the window centre, or `None`
    /// until `N` samples were seen.
    pub fn update(&mut self, x: f64) -> Option<f64> {
        self.fir.update(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_ramp_and_quadratic_exact_with_stated_lag() {
        let dt = 0.02;
        for n in [2usize, 3, 5, 8] {
            let mut d = CausalDifferentiator::new(n, dt).unwrap();
            for k in 0..40 {
                let t = k as f64 * dt;
                // x = 3 + 2 t + 5 t²  →  ẋ(t − lag) = 2 + 10 (t − lag)
                let out = d.update(3.0 + 2.0 * t + 5.0 * t * t);
                if k + 1 < n {
                    assert!(out.is_none());
                } else {
                    let expect = 2.0 + 10.0 * (t - d.lag_s());
                    assert!((out.unwrap() - expect).abs() < 1e-9, "n={n} k={k}");
                }
            }
            assert!((d.lag_s() - (n as f64 - 1.0) * dt / 2.0).abs() < 1e-15);
        }
    }

    #[test]
    fn analytic_sinusoid_pure_lag_and_gain() {
        let dt = 0.02;
        let w = 2.0 * std::f64::consts::PI * 1.5; // 1.5 Hz
        let mut d = CausalDifferentiator::new(5, dt).unwrap();
        // Closed form of the gain for N = 5: Σ w_k sin(ω(k−c)dt) = 2(sin ωdt + 2 sin 2ωdt)/(10 dt).
        let g_closed = 2.0 * ((w * dt).sin() + 2.0 * (2.0 * w * dt).sin()) / (10.0 * dt) / w;
        assert!((d.gain(w) - g_closed).abs() < 1e-12);
        assert!(g_closed < 1.0 && g_closed > 0.95);
        for k in 0..200 {
            let t = k as f64 * dt;
            if let Some(v) = d.update((w * t).sin()) {
                let expect = g_closed * w * (w * (t - d.lag_s())).cos();
                assert!((v - expect).abs() < 1e-9, "k={k}: {v} vs {expect}");
            }
        }
    }

    #[test]
    fn errors_bad_window_and_interval() {
        assert_eq!(
            CausalDifferentiator::new(1, 0.1).unwrap_err(),
            DifferentiateError::Window { window: 1 }
        );
        assert!(CausalDifferentiator::new(3, 0.0).is_err());
        assert!(CausalDifferentiator::new(3, f64::NAN).is_err());
    }

    #[test]
    fn reset_restarts_window() {
        let mut d = CausalDifferentiator::new(3, 0.1).unwrap();
        for k in 0..5 {
            d.update(k as f64);
        }
        d.reset();
        assert!(d.update(100.0).is_none());
        assert!(d.update(101.0).is_none());
        assert!((d.update(102.0).unwrap() - 10.0).abs() < 1e-12);
    }

    /// The smoother's weights are the summation-by-parts weights (non-negative, symmetric,
    /// summing to 1); applied to ẋ it reproduces the differentiator of x exactly for
    /// quadratics and to second order in dt for a sinusoid, far closer than the plain delay.
    #[test]
    fn analytic_matched_smoother_reproduces_the_differentiator() {
        let dt = 0.01;
        for n in [3usize, 11, 21] {
            let sm = MatchedSmoother::new(n, dt).unwrap();
            let a = sm.weights();
            assert!((a.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for k in 0..n {
                assert!(a[k] >= 0.0 && (a[k] - a[n - 1 - k]).abs() < 1e-15, "n={n} k={k}");
            }
            assert!((sm.lag_s() - CausalDifferentiator::new(n, dt).unwrap().lag_s()).abs() < 1e-15);
        }
        // N = 3: w = (−1, 0, 1)/(2dt) → s = (½, ½) → a = (¼, ½, ¼).
        let a3 = MatchedSmoother::new(3, dt).unwrap().weights().to_vec();
        for (got, want) in a3.iter().zip([0.25, 0.5, 0.25]) {
            assert!((got - want).abs() < 1e-15);
        }
        let w = 2.0 * std::f64::consts::PI * 2.0; // 2 Hz
        let (mut d, mut s) =
            (CausalDifferentiator::new(21, dt).unwrap(), MatchedSmoother::new(21, dt).unwrap());
        let (mut worst_matched, mut worst_delay) = (0.0f64, 0.0f64);
        for k in 0..300 {
            let t = k as f64 * dt;
            let (dx, sy) = (d.update((w * t).sin()), s.update(w * (w * t).cos()));
            if let (Some(dx), Some(sy)) = (dx, sy) {
                let delayed = w * (w * (t - s.lag_s())).cos();
                worst_matched = worst_matched.max((dx - sy).abs() / w);
                worst_delay = worst_delay.max((dx - delayed).abs() / w);
            }
        }
        assert!(worst_matched < 2e-3, "matched {worst_matched}");
        assert!(worst_delay > 20.0 * worst_matched, "delay {worst_delay} vs {worst_matched}");
        // Quadratic: exact.
        let (mut d, mut s) =
            (CausalDifferentiator::new(11, dt).unwrap(), MatchedSmoother::new(11, dt).unwrap());
        for k in 0..30 {
            let t = k as f64 * dt;
            if let (Some(dx), Some(sy)) =
                (d.update(1.0 + 2.0 * t - 3.0 * t * t), s.update(2.0 - 6.0 * t))
            {
                assert!((dx - sy).abs() < 1e-10, "{dx} vs {sy}");
            }
        }
    }

    /// A held (zero-order-hold) signal and its exact integral: the differentiator of the
    /// integral equals the held weighting of the signal to rounding.
    #[test]
    fn analytic_held_weights_match_a_zero_order_hold() {
        let dt = 0.01;
        let n = 11;
        let sm = MatchedSmoother::new(n, dt).unwrap();
        let h = sm.held_weights();
        assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-12 && h[n - 1] == 0.0);
        let mut d = CausalDifferentiator::new(n, dt).unwrap();
        let y: Vec<f64> = (0..60).map(|k| (0.37 * k as f64).sin() + 0.1 * k as f64).collect();
        let mut x = 0.0;
        for k in 0..60 {
            let out = d.update(x);
            if let Some(dx) = out {
                let held: f64 = (0..n).map(|j| h[j] * y[k + 1 - n + j]).sum();
                assert!((dx - held).abs() < 1e-9, "k={k}: {dx} vs {held}");
            }
            x += y[k] * dt;
        }
    }
}
