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

/// Running sums of what the measurement updates did to one parameter's variance, from which
/// the change test takes the variance of a drift and the fraction of a jump taken up between
/// any two times (differences of the sums).
///
/// With constant parameters they telescope to the variances themselves (`Σ (P⁻ − P⁺) = P₀ −
/// P₁`, `Π P⁺/P⁻ = P₁/P₀`), the form the test had first. With a parameter random walk the
/// variance settles at a steady state where `P₀ − P₁ → 0` and `P₁/P₀ → 1` while every update
/// still moves the estimate and still takes up part of a jump: the variance ratio then gave
/// jump estimates `D/κ` 10–10⁷ times the drift, which the prior cap turned into a full prior
/// variance, and standardised drifts too large (false alarms). Measured in
/// docs/uncertainty.md, "EKF: the change test under a parameter random walk".
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Uptake {
    /// `Σ (P⁻ − P⁺)` over the measurement updates: the variance of the estimate's increments
    /// under the filter's own model (the drift variance of a window is its difference).
    pub reduced: f64,
    /// `Σ ln(P⁺/P⁻)`: a jump's error is multiplied by `P⁺/P⁻` at each update (scalar
    /// parameter, `1 − g` with `g` the gain fraction), so `1 − exp(Δ)` over an interval is the
    /// fraction of a jump the filter took up in it.
    pub log_kept: f64,
}

impl Uptake {
    /// Adds one sample's measurement update, from the predicted variance `prior` (after the
    /// propagation and any random walk) to the updated `post`; a sample that brought nothing
    /// (all outputs rejected or absent) adds nothing.
    pub fn add(&mut self, prior: f64, post: f64) {
        if prior > 0.0 && post > 0.0 && post < prior {
            self.reduced += prior - post;
            self.log_kept += libm::log(post / prior);
        }
    }
}

/// One side of a parameter's CUSUM: the statistic, and the estimate and the uptake sums at the
/// start of its current excursion.
#[derive(Debug, Clone, Copy, Default)]
struct Side {
    g: f64,
    theta0: f64,
    uptake0: Uptake,
}

/// The change test's state: the current window's start (time, parameter estimates and uptake
/// sums) and a two-sided CUSUM per parameter on the standardised window drifts.
#[derive(Debug, Clone, Copy)]
pub(super) struct DriftWindow {
    /// Window start, s; NaN before the first window.
    pub t0_s: f64,
    pub theta0: [f64; MAX_PARAMS],
    uptake0: [Uptake; MAX_PARAMS],
    up: [Side; MAX_PARAMS],
    down: [Side; MAX_PARAMS],
}

impl Default for DriftWindow {
    fn default() -> Self {
        Self {
            t0_s: f64::NAN,
            theta0: [0.0; MAX_PARAMS],
            uptake0: [Uptake::default(); MAX_PARAMS],
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

    /// Starts a window at `t_s` from estimates `theta` and uptake sums `uptake` (same order).
    pub fn open(&mut self, t_s: f64, theta: &[f64], uptake: &[Uptake]) {
        self.t0_s = t_s;
        for (i, (&v, &u)) in theta.iter().zip(uptake).enumerate() {
            self.theta0[i] = v;
            self.uptake0[i] = u;
        }
    }

    /// The CUSUM step of parameter `i` at the window's end, estimate `theta`, uptake sums
    /// `uptake`, variance `p`. The window drift `d = θ̂ − θ̂₀` is standardised by its standard
    /// deviation under the filter's own parameter model, `√(f ΣΔ(P⁻ − P⁺))` (`f` the
    /// coloured-innovation factor; the estimate's increments are the gains times the
    /// innovations, whose variance is the reduction of `P` by each update; with constant
    /// parameters this is `P₀ − P`, the martingale form), and fed to the two CUSUMs
    /// `g± ← max(0, g± ± u − k)`. When one exceeds `h`: an alarm; returns the variance to add,
    /// the squared jump estimate `δ̂ = D / κ` with `D` the drift since the start of the
    /// excursion and `κ = 1 − exp(Δ Σ ln(P⁺/P⁻))` the fraction of a jump the filter took up
    /// over it ([`Uptake`]), capped so that the variance stays ≤ `prior_sigma²`; both CUSUMs
    /// restart. Returns the standardised drift `u` (`None` when the window brought no
    /// information) and the variance to add (`None` without an alarm or with nothing to add).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        i: usize,
        theta: f64,
        uptake: Uptake,
        p: f64,
        f: f64,
        h: f64,
        prior_sigma: f64,
    ) -> (Option<f64>, Option<f64>) {
        let (u0, d) = (self.uptake0[i], theta - self.theta0[i]);
        let var = f * (uptake.reduced - u0.reduced);
        if var.is_nan() || var <= 0.0 {
            return (None, None);
        }
        let u = d / libm::sqrt(var);
        let mut alarm = None;
        for (side, sign) in [(&mut self.up[i], 1.0), (&mut self.down[i], -1.0)] {
            if side.g <= 0.0 {
                side.theta0 = self.theta0[i];
                side.uptake0 = u0;
            }
            side.g = (side.g + sign * u - CUSUM_REFERENCE).max(0.0);
            if side.g > h {
                alarm = Some((side.theta0, side.uptake0));
            }
        }
        let Some((theta_s, uptake_s)) = alarm else { return (Some(u), None) };
        self.up[i].g = 0.0;
        self.down[i].g = 0.0;
        let kappa = (1.0 - libm::exp(uptake.log_kept - uptake_s.log_kept)).max(1e-9);
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
/// written to `ph` (first `n` entries). Reads only the lower triangle of `p` (`p[i][j]`,
/// `j ≤ i`): during a step's measurement updates only that triangle is kept current
/// (`Ekf::correct`, [`mirror_lower`]). `P` is exactly symmetric, so this is the
/// same number to the bit as reading the full rows.
pub(super) fn p_times_row(
    p: &Square,
    unit: Option<usize>,
    h: &[f64; MAX_AUG],
    n: usize,
    ph: &mut [f64; MAX_AUG],
) -> f64 {
    match unit {
        Some(k) => {
            ph[..=k].copy_from_slice(&p[k][..=k]);
            for (j, phj) in ph.iter_mut().enumerate().take(n).skip(k + 1) {
                *phj = p[j][k];
            }
            ph[k]
        }
        None => {
            // An output sees the states and the parameters of its own coefficient: most of
            // `h` is exact zeros, whose products add nothing (the sums keep their order, so
            // the result is the same to the bit; a non-finite `P` is caught by the divergence
            // check of the step).
            let mut nz = [0usize; MAX_AUG];
            let mut m = 0;
            for (j, &hj) in h[..n].iter().enumerate() {
                if hj != 0.0 {
                    nz[m] = j;
                    m += 1;
                }
            }
            let nz = &nz[..m];
            for (i, phi) in ph.iter_mut().enumerate().take(n) {
                let mut acc = 0.0;
                for &j in nz {
                    let pij = if j <= i { p[i][j] } else { p[j][i] };
                    acc += pij * h[j];
                }
                *phi = acc;
            }
            nz.iter().map(|&j| h[j] * ph[j]).sum()
        }
    }
}

/// Copies the lower triangle of the leading `n × n` block of `p` onto its upper one: after
/// the measurement updates, which keep only the lower triangle, `p` is whole (and exactly
/// symmetric) again for whatever reads it next.
pub(super) fn mirror_lower(p: &mut Square, n: usize) {
    for i in 1..n {
        for j in 0..i {
            p[j][i] = p[i][j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `P hᵀ` and `h P hᵀ` from the lower triangle equal the full symmetric product (a dense
    /// row and a unit row), with the upper triangle spoilt; `mirror_lower` makes it whole.
    #[test]
    fn the_measurement_row_reads_only_the_lower_triangle() {
        let n = 7;
        let mut full: Square = [[0.0; MAX_AUG]; MAX_AUG];
        for i in 0..n {
            for j in 0..n {
                // Symmetric, positive definite: a diagonal of n plus small cross terms.
                full[i][j] = if i == j { n as f64 } else { 0.1 * (i + j) as f64 / n as f64 };
            }
        }
        let mut h = [0.0; MAX_AUG];
        (h[1], h[4], h[6]) = (0.5, -2.0, 1.5);
        let mut lower = full;
        for i in 0..n {
            for j in i + 1..n {
                lower[i][j] = f64::NAN;
            }
        }
        for unit in [None, Some(2), Some(6)] {
            let (mut a, mut b) = ([0.0; MAX_AUG], [0.0; MAX_AUG]);
            let want = p_times_row(&full, unit, &h, n, &mut a);
            let got = p_times_row(&lower, unit, &h, n, &mut b);
            assert_eq!(want.to_bits(), got.to_bits(), "{unit:?}");
            for i in 0..n {
                let direct: f64 = match unit {
                    Some(k) => full[i][k],
                    None => (0..n).map(|j| full[i][j] * h[j]).sum(),
                };
                assert!((b[i] - direct).abs() < 1e-12, "{unit:?} row {i}: {} vs {direct}", b[i]);
            }
        }
        mirror_lower(&mut lower, n);
        assert_eq!(lower, full);
    }

    #[test]
    fn cusum_threshold_inverts_siegmund() {
        // k = 1, h = 5: ARL₀ = (e^{12.332} − 13.332) / 2 ≈ 1.13·10⁵ (Siegmund 1985).
        let h = cusum_threshold(1.13e5);
        assert!((h - 5.0).abs() < 0.01, "{h}");
        assert!(cusum_threshold(1e3) < cusum_threshold(1e6));
    }

    /// The uptake sums of one window in which the variance fell from `p0` to `p1` by
    /// measurement updates alone (constant parameters).
    fn window(mut acc: Uptake, p0: f64, p1: f64) -> Uptake {
        acc.add(p0, p1);
        acc
    }

    #[test]
    fn persistent_drift_raises_an_alarm_sized_by_the_jump_and_noise_does_not() {
        let h = 5.0;
        // Constant-parameter windows: P halves each window from 1e-4, drift of ±1σ.
        let mut w = DriftWindow::default();
        assert!(!w.is_open());
        let (mut theta, mut p, mut acc) = (1.0, 1e-4, Uptake::default());
        for k in 0..40 {
            w.open(k as f64, &[theta], &[acc]);
            let p1 = p * (k as f64 + 1.0) / (k as f64 + 2.0);
            let sd = (p - p1).sqrt();
            theta += if k % 2 == 0 { sd } else { -sd };
            acc = window(acc, p, p1);
            assert_eq!(w.step(0, theta, acc, p1, 1.0, h, 1.0).1, None, "window {k}");
            p = p1;
        }
        // A persistent drift of 3σ per window: alarm on the third window (g = 2, 4, 6 > 5).
        let theta_s = theta;
        let p_s = p;
        let mut alarm = None;
        for k in 0..3 {
            w.open(40.0 + k as f64, &[theta], &[acc]);
            let p1 = p * 0.9;
            theta += 3.0 * (p - p1).sqrt();
            acc = window(acc, p, p1);
            alarm = w.step(0, theta, acc, p1, 1.0, h, 1.0).1;
            p = p1;
            assert_eq!(alarm.is_some(), k == 2, "window {k}");
        }
        // The jump estimate: the drift since the excursion began over the fraction taken up,
        // which for constant parameters is 1 − P/P_start.
        let kappa = 1.0 - p / p_s;
        let want = ((theta - theta_s) / kappa).powi(2);
        assert!((alarm.unwrap() - want).abs() < 1e-9 * want, "{alarm:?} {want}");
        // The same drift with coloured innovations (f = 16: a quarter of the standardised
        // drift) raises nothing.
        let mut w = DriftWindow::default();
        for k in 0..3 {
            w.open(k as f64, &[theta], &[acc]);
            let p1 = p * 0.9;
            theta += 3.0 * (p - p1).sqrt();
            acc = window(acc, p, p1);
            assert_eq!(w.step(0, theta, acc, p1, 16.0, h, 1.0).1, None);
            p = p1;
        }
        // The inflation is capped by the prior variance.
        let mut w = DriftWindow::default();
        w.open(0.0, &[0.0], &[Uptake::default()]);
        let acc = window(Uptake::default(), 1e-4, 0.5e-4);
        let add = w.step(0, 1.0, acc, 0.5e-4, 1.0, h, 0.1).1.unwrap();
        assert!((add + 0.5e-4 - 0.01).abs() < 1e-15, "{add}");
    }

    /// A scalar random-walk Kalman filter, `θ_k = θ_{k−1} + w`, `y = θ + v`, at its steady
    /// state, where the variance no longer falls: the drift of a window must still be
    /// standardised to unit variance while nothing changes, and after a jump the alarm's jump
    /// estimate must be the jump's size. With the variance ratio (`P₀ − P₁`, `1 − P₁/P₀`)
    /// neither holds: at the steady state both are about 0 (`D/κ` was 10–10⁷ times the drift in
    /// the F-16 campaign runs; docs/uncertainty.md).
    #[test]
    fn random_walk_filter_standardises_drifts_and_sizes_a_jump() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        /// Truth, estimate, variance and uptake sums of the scalar filter.
        struct Walk {
            truth: f64,
            est: f64,
            p: f64,
            acc: Uptake,
        }
        const R: f64 = 1.0; // measurement variance
        const Q: f64 = 1e-4; // walk variance per sample
        impl Walk {
            fn step(&mut self, rng: &mut rand_pcg::Pcg64) {
                let mut n01 = || -> f64 { StandardNormal.sample(rng) };
                self.truth += Q.sqrt() * n01();
                let prior = self.p + Q;
                let y = self.truth + R.sqrt() * n01();
                let g = prior / (prior + R);
                self.est += g * (y - self.est);
                self.p = (1.0 - g) * prior;
                self.acc.add(prior, self.p);
            }
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let per_window = 100;
        let h = cusum_threshold(1e6);
        let mut f = Walk { truth: 0.0, est: 0.0, p: 1.0, acc: Uptake::default() };
        // Settle (the steady-state variance is reached within a few hundred samples).
        for _ in 0..2000 {
            f.step(&mut rng);
        }
        let mut w = DriftWindow::default();
        let (mut sum_u2, mut n, mut alarms) = (0.0, 0, 0);
        for k in 0..400 {
            w.open(k as f64, &[f.est], &[f.acc]);
            let p0 = f.p;
            for _ in 0..per_window {
                f.step(&mut rng);
            }
            assert!((f.p - p0).abs() < 1e-9 * p0, "not at the steady state");
            let (u, add) = w.step(0, f.est, f.acc, f.p, 1.0, h, 10.0);
            sum_u2 += u.expect("an informative window").powi(2);
            n += 1;
            alarms += usize::from(add.is_some());
        }
        let ms = sum_u2 / f64::from(n);
        assert!((0.8..1.25).contains(&ms), "mean square standardised drift {ms}");
        assert_eq!(alarms, 0, "false alarms while nothing changed");
        // A jump of 2 (20 steady-state σ; a window takes up 1 − (1 − g)^100 ≈ 63 % of it): the
        // alarm's estimate of its size.
        let jump = 2.0;
        f.truth += jump;
        let mut add = None;
        for k in 0..20 {
            w.open(400.0 + k as f64, &[f.est], &[f.acc]);
            for _ in 0..per_window {
                f.step(&mut rng);
            }
            add = w.step(0, f.est, f.acc, f.p, 1.0, h, 10.0).1;
            if add.is_some() {
                break;
            }
        }
        let size = add.expect("the jump raises an alarm").sqrt();
        assert!((size / jump - 1.0).abs() < 0.3, "jump estimate {size} for a jump of {jump}");
    }
}
