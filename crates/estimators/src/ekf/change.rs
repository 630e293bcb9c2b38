//! Parameter-change test of the EKF on the drift of its own parameter estimates, and the
//! inflation of a parameter's variance that follows an alarm (module doc of [`crate::ekf`],
//! "Parameter changes").
//!
//! Sources: Page, "Continuous inspection schemes", Biometrika 41, 1954 (CUSUM); Basseville &
//! Nikiforov, *Detection of Abrupt Changes: Theory and Application*, Prentice Hall 1993,
//! §2.2 (CUSUM for a change in the mean of independent Gaussian increments), eq. 5.2.44
//! (Siegmund's approximation of the mean run length) and ch. 7 (changes in state-space models
//! tested on filter outputs); the size of the inflation from the drift, in the spirit of
//! covariance matching (Mehra, "Approaches to adaptive filtering", IEEE TAC 17(5), 1972; Myers
//! & Tapley, "Adaptive sequential estimation with unknown noise statistics", IEEE TAC 21(4),
//! 1976; Jategaonkar 2015 §7.5).

use super::{MAX_AUG, Square};
use crate::vocabulary::MAX_PARAMS;

/// CUSUM reference value `k` of the standardised window drift (module doc): tuned to a shift
/// of `2k` = 2 standard deviations per window (Basseville & Nikiforov 1993, §2.2.2).
pub const CUSUM_REFERENCE: f64 = 1.0;

/// One side of a parameter's CUSUM: the statistic and the estimate and variance at the start
/// of its current excursion.
#[derive(Debug, Clone, Copy, Default)]
struct Side {
    g: f64,
    theta0: f64,
    p0: f64,
}

/// The change test's state: the current window's start (time, parameter estimates and
/// variances) and a two-sided CUSUM per parameter on the standardised window drifts.
#[derive(Debug, Clone, Copy)]
pub(super) struct DriftWindow {
    /// Window start, s; NaN before the first window.
    pub t0_s: f64,
    pub theta0: [f64; MAX_PARAMS],
    pub p0: [f64; MAX_PARAMS],
    up: [Side; MAX_PARAMS],
    down: [Side; MAX_PARAMS],
}

impl Default for DriftWindow {
    fn default() -> Self {
        Self {
            t0_s: f64::NAN,
            theta0: [0.0; MAX_PARAMS],
            p0: [0.0; MAX_PARAMS],
            up: [Side::default(); MAX_PARAMS],
            down: [Side::default(); MAX_PARAMS],
        }
    }
}

impl DriftWindow {
    /// Whether a window is running.
    pub fn is_open(&self) -> bool {
        !self.t0_s.is_nan()
    }

    /// Starts a window at `t_s` from estimates `theta` and variances `var(i)`.
    pub fn open(&mut self, t_s: f64, theta: &[f64], var: impl Fn(usize) -> f64) {
        self.t0_s = t_s;
        for (i, &v) in theta.iter().enumerate() {
            self.theta0[i] = v;
            self.p0[i] = var(i);
        }
    }

    /// The CUSUM step of parameter `i` at the window's end, estimate `theta`, variance `p`.
    /// The window drift `d = θ̂ − θ̂₀` is standardised by its standard deviation under constant
    /// parameters, `√(f (P₀ − P))` (`f` the coloured-innovation factor; the estimate of a
    /// consistent filter is a martingale whose increments have variance `P₀ − P`), and fed to
    /// the two CUSUMs `g± ← max(0, g± ± u − k)`. When one exceeds `h`: an alarm; returns the
    /// variance to add, the squared jump estimate `δ̂ = D / κ` with `D` the drift since the
    /// start of the excursion and `κ = 1 − P/P_start` the fraction of a jump a
    /// constant-parameter filter takes up over it, capped so that the variance stays ≤
    /// `prior_sigma²`; both CUSUMs restart. Returns the standardised drift `u` (`None` when
    /// the window brought no information) and the variance to add (`None` without an alarm or
    /// with nothing to add).
    pub fn step(
        &mut self,
        i: usize,
        theta: f64,
        p: f64,
        f: f64,
        h: f64,
        prior_sigma: f64,
    ) -> (Option<f64>, Option<f64>) {
        let (p0, d) = (self.p0[i], theta - self.theta0[i]);
        let var = f * (p0 - p);
        if !(var > 0.0 && p0 > 0.0) {
            return (None, None);
        }
        let u = d / libm::sqrt(var);
        let mut alarm = None;
        for (side, sign) in [(&mut self.up[i], 1.0), (&mut self.down[i], -1.0)] {
            if side.g <= 0.0 {
                side.theta0 = self.theta0[i];
                side.p0 = p0;
            }
            side.g = (side.g + sign * u - CUSUM_REFERENCE).max(0.0);
            if side.g > h {
                alarm = Some((side.theta0, side.p0));
            }
        }
        let Some((theta_s, p_s)) = alarm else { return (Some(u), None) };
        self.up[i].g = 0.0;
        self.down[i].g = 0.0;
        let kappa = (1.0 - p / p_s).max(1e-9);
        let jump = (theta - theta_s) / kappa;
        let add = (jump * jump).min(prior_sigma * prior_sigma - p);
        (Some(u), (add > 0.0).then_some(add))
    }
}

/// The CUSUM threshold `h` for a mean run length `arl` (windows) between false alarms of one
/// side with standard-normal increments and reference `k` = [`CUSUM_REFERENCE`], from
/// Siegmund's approximation `ARL₀ = (e^{2kb} − 2kb − 1) / (2k²)`, `b = h + 1.166`
/// (Basseville & Nikiforov 1993, eq. 5.2.44), solved by bisection.
pub(super) fn cusum_threshold(arl: f64) -> f64 {
    let k = CUSUM_REFERENCE;
    let arl_of = |h: f64| {
        let x = 2.0 * k * (h + 1.166);
        (libm::exp(x) - x - 1.0) / (2.0 * k * k)
    };
    let (mut lo, mut hi) = (0.0, 50.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if arl_of(mid) < arl { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// `h P hᵀ` for output row `h` (or the unit row of integrated state `unit`), with `P hᵀ`
/// written to `ph` (first `n` entries).
pub(super) fn p_times_row(
    p: &Square,
    unit: Option<usize>,
    h: &[f64; MAX_AUG],
    n: usize,
    ph: &mut [f64; MAX_AUG],
) -> f64 {
    match unit {
        Some(k) => {
            ph[..n].copy_from_slice(&p[k][..n]);
            ph[k]
        }
        None => {
            for i in 0..n {
                let mut acc = 0.0;
                for j in 0..n {
                    acc += p[i][j] * h[j];
                }
                ph[i] = acc;
            }
            (0..n).map(|j| h[j] * ph[j]).sum()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cusum_threshold_inverts_siegmund() {
        // k = 1, h = 5: ARL₀ = (e^{12.332} − 13.332) / 2 ≈ 1.13·10⁵ (Siegmund 1985).
        let h = cusum_threshold(1.13e5);
        assert!((h - 5.0).abs() < 0.01, "{h}");
        assert!(cusum_threshold(1e3) < cusum_threshold(1e6));
    }

    #[test]
    fn persistent_drift_raises_an_alarm_sized_by_the_jump_and_noise_does_not() {
        let h = 5.0;
        // Constant-parameter windows: P halves each window from 1e-4, drift of ±1σ.
        let mut w = DriftWindow::default();
        assert!(!w.is_open());
        let (mut theta, mut p) = (1.0, 1e-4);
        for k in 0..40 {
            w.open(k as f64, &[theta], |_| p);
            let p1 = p * (k as f64 + 1.0) / (k as f64 + 2.0);
            let sd = (p - p1).sqrt();
            theta += if k % 2 == 0 { sd } else { -sd };
            assert_eq!(w.step(0, theta, p1, 1.0, h, 1.0).1, None, "window {k}");
            p = p1;
        }
        // A persistent drift of 3σ per window: alarm on the third window (g = 2, 4, 6 > 5).
        let theta_s = theta;
        let p_s = p;
        let mut alarm = None;
        for k in 0..3 {
            w.open(40.0 + k as f64, &[theta], |_| p);
            let p1 = p * 0.9;
            theta += 3.0 * (p - p1).sqrt();
            alarm = w.step(0, theta, p1, 1.0, h, 1.0).1;
            p = p1;
            assert_eq!(alarm.is_some(), k == 2, "window {k}");
        }
        // The jump estimate: the drift since the excursion began over the fraction taken up.
        let kappa = 1.0 - p / p_s;
        let want = ((theta - theta_s) / kappa).powi(2);
        assert!((alarm.unwrap() - want).abs() < 1e-12 * want);
        // The same drift with coloured innovations (f = 16: a quarter of the standardised
        // drift) raises nothing.
        let mut w = DriftWindow::default();
        for k in 0..3 {
            w.open(k as f64, &[theta], |_| p);
            let p1 = p * 0.9;
            theta += 3.0 * (p - p1).sqrt();
            assert_eq!(w.step(0, theta, p1, 16.0, h, 1.0).1, None);
            p = p1;
        }
        // The inflation is capped by the prior variance.
        let mut w = DriftWindow::default();
        w.open(0.0, &[0.0], |_| 1e-4);
        let add = w.step(0, 1.0, 0.5e-4, 1.0, h, 0.1).1.unwrap();
        assert!((add + 0.5e-4 - 0.01).abs() < 1e-15, "{add}");
    }
}
