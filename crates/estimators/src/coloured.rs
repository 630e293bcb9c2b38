//! Parameter covariance corrected for coloured (autocorrelated) residuals: the recursive,
//! allocation-free form for the real-time equation-error estimators ([`crate::rls`]), and the
//! batch form for output error ([`batch`], std only).
//!
//! Source: Morelli & Klein, "Accuracy of aerodynamic model parameters estimated from flight
//! test data", *J. Guidance, Control, and Dynamics* 20(1), 1997; Klein & Morelli, *Aircraft
//! System Identification*, AIAA 2006, §5.2 (least squares with coloured residuals; the
//! equation-error form below) and ch. 6 (the output-error form); SIDPAC `m_colores.m`.
//!
//! For least squares `θ̂ = (XᵀX)⁻¹ Xᵀy` with residuals `v` whose autocorrelation is
//! `R_vv(k) = E[v_i v_{i−k}]`,
//!
//! ```text
//! Cov(θ̂) = (XᵀX)⁻¹ [ Σ_i Σ_j x_i R_vv(i − j) x_jᵀ ] (XᵀX)⁻¹          (x_i the i-th row of X)
//! ```
//!
//! which reduces to `σ² (XᵀX)⁻¹` for white residuals. The sum over lags is truncated at the
//! first lag `K` at which the normalised autocorrelation `ρ̂(k) = R̂_vv(k)/R̂_vv(0)` lies inside
//! the 95 % band of a white sequence, `±2/√N` (the lags beyond are estimation noise, and
//! summing them only adds variance), and at [`MAX_LAG`]. The batch form and
//! [`Autocorrelation::lag`] (the EKF's) use that rule; the recursive [`ColouredCovariance`]
//! sums through the last significant lobe (below, "Finite memory").
//!
//! # Recursive form ([`ColouredCovariance`])
//!
//! With exponential forgetting `λ` the weighted least-squares estimate is
//! `θ̂_n = P_n Σ_i λ^{n−i} x_i y_i`, `P_n = (Σ_i λ^{n−i} x_i x_iᵀ)⁻¹`, and its covariance is the
//! same sandwich with weights `λ^{n−i} λ^{n−j}` on the pair `(i, j)`:
//!
//! ```text
//! Cov(θ̂_n) = σ̂² P_n M_n P_n,   M_n = Σ_i Σ_j λ^{2n−i−j} ρ(i − j) x_i x_jᵀ
//! M_n = λ² M_{n−1} + x_n g_nᵀ + g_n x_nᵀ − x_n x_nᵀ,   g_n = x_n + Σ_{k=1..K} ρ̂(k) λ^k x_{n−k}
//! ρ̂(k) = c_n(k) / c_n(0),   c_n(k) = λ c_{n−1}(k) + v_n v_{n−k}
//! ```
//!
//! `σ̂²` is the estimator's own residual variance. A ring buffer holds the last [`MAX_LAG`]
//! regressor rows and residuals, so each update costs `O(K p + p²)` and allocates nothing. Each
//! pair is weighted with the `ρ̂(k)` of the last lag row when its later member arrives
//! ("Decimation" below; the batch formula uses the final `ρ̂`); once `ρ̂` has settled the two
//! agree (tests). With `λ = 1` and white
//! residuals (`K = 0`) `M_n = P_n⁻¹` and the covariance is exactly `σ̂² P_n`; with `λ < 1` the
//! `λ²` weighting of `M` is the variance of the exponentially weighted estimate, about half
//! of `σ̂² P_n` for a memory of many samples.
//!
//! # Finite memory: what the residuals hide ([`ColouredCovariance`] only)
//!
//! With a short memory (λ = 0.995: 200 samples) and residuals correlated over tens of samples,
//! the fit takes a large share of the noise into θ̂, and residual-based `σ̂²` and `ρ̂` both
//! understate the noise. Three corrections, each exact or first-order in that share:
//! - **Degrees of freedom.** For `θ̂ = P XᵀΛy`, `H = X P XᵀΛ`, `ε = (I − H)v`, one has
//!   `(I − H)ᵀΛ(I − H) = Λ − ΛH`, hence exactly `E[Σ λ^{n−i} ε_i²] = σ²(N_eff − tr(P M))`
//!   (`M` in correlation units as above). The caller divides its weighted RSS by
//!   `N_eff − tr(P M)` ([`ColouredCovariance::trace_pm`]); for white residuals and λ = 1 this is
//!   the usual `N − p`.
//! - **Lag dependence of the fitted share.** The same fit lowers the residual autocovariance at
//!   lag `k` by the noise it put into θ̂, with the lag shape of the leverage: to first order
//!   `E[ρ̂(k)] ≈ (ρ_v(k) − r ρ_H(k))/(1 − r)`, i.e. `ρ_v(k) ≈ (1 − r) ρ̂(k) + r ρ_H(k)`,
//!   with `r = tr(P M)/N_eff` the fitted share and `ρ_H(k) = s_k/s_0`,
//!   `s_k = Σ_i λ^{n−i} x_iᵀ P x_{i−k}`, the normalised lag-`k` leverage. The sandwich uses the
//!   corrected `ρ_v`.
//! - **Truncation after the last significant lobe.** Differentiated noise (the `ṗ q̇ ṙ` of a
//!   least-squares differentiator) has a positive then a negative lobe that sum to about zero;
//!   stopping at the first insignificant lag keeps only the positive lobe and doubles σ. The
//!   sum runs on through each following lobe (run of one sign of `ρ̂`) whose sum is significant
//!   against `3√len/√N` ([`Autocorrelation::last_significant_lag`], a 3σ test); testing single lags out to
//!   [`MAX_LAG`] instead would pick a chance lag in most white records.
//!
//! `rls::tests::finite_memory_sigma_matches_scatter_for_smoothed_and_differentiated_noise`
//! checks the three against the Monte Carlo scatter and the known noise variance.
//!
//! # Decimation ([`ColouredCovariance`] only)
//!
//! The lag sums are most of an update's cost (`O(K p)` against the recursion's `O(p²)`). What
//! changes slowly is formed on every [`LAG_STRIDE`]-th row (a *lag row*): the lag leverage
//! `s_k` (summed over the lag rows only), the truncation lags, the fitted share `r` and the lag
//! weights `w_k = ρ_v(k) λ^k`, and the estimator's σ factors (`crate::rls`). What carries the
//! data is formed on every row: the residual lag products `c(k)` (so `ρ̂` and its white bands
//! see every residual) and `M` itself, `x_n x_nᵀ + x_n hᵀ + h x_nᵀ` with `h = Σ w_k x_{n−k}` from
//! the last lag row's weights. Forming `M`'s lagged part only on the lag rows (weighted for the
//! rows between) was tried first: with rough regressors (white, or AR(1) with a negative
//! coefficient) and strongly coloured residuals its sampling noise made the sandwich fall back
//! to the white `σ̂² P` in up to a quarter of the runs and took the ±2σ coverage from 96 % to
//! 93 % (`rls::tests::coloured_sigma_holds_with_white_regressors_and_a_short_memory`).
//! Measured on the default job's 200-run Monte Carlo at 100 Hz and at 20 Hz
//! (docs/uncertainty.md, "RLS coloured σ: the slow parts on every fourth row"): RLS's
//! estimates unchanged, their ±2σ coverage and mean σ unchanged within the campaign's
//! sampling error.

#[cfg(feature = "std")]
pub mod batch;

use crate::linalg::Square;

/// Most residual lags the recursive correction sums (a ring buffer of this many rows).
pub const MAX_LAG: usize = 40;

/// Rows per lag row of [`ColouredCovariance`]: the lag leverage, the truncation lags, the
/// fitted share and the lag weights are formed on every `LAG_STRIDE`-th row (module doc,
/// "Decimation").
pub const LAG_STRIDE: usize = 4;

/// The last [`MAX_LAG`] values of a sequence, newest first, each stored twice (slot `j` and
/// `j + MAX_LAG`) so that lags `1..=k` are one contiguous slice: the lag loops, run over every
/// lag at every sample, are then plain slice loops the compiler vectorises, with no index
/// arithmetic per lag.
#[derive(Debug, Clone, Copy)]
struct LagRing {
    buf: [f64; 2 * MAX_LAG],
    /// Slot of the newest value (lag 1 of the next sample).
    head: usize,
}

impl LagRing {
    const fn new() -> Self {
        Self { buf: [0.0; 2 * MAX_LAG], head: 0 }
    }

    /// Lags `1..=len` (`len ≤ MAX_LAG`) of the next sample, newest first.
    #[inline]
    fn lags(&self, len: usize) -> &[f64] {
        &self.buf[self.head..self.head + len]
    }

    #[inline]
    fn push(&mut self, v: f64) {
        self.head = if self.head == 0 { MAX_LAG - 1 } else { self.head - 1 };
        self.buf[self.head] = v;
        self.buf[self.head + MAX_LAG] = v;
    }
}

/// A lobe of `ρ̂` past the first truncation lag is kept when its sum exceeds this multiple of
/// the white band of a sum, `2√len/√N`: 1.5 makes it a 3σ (99.7 %) test, since up to about
/// twenty lobes are tested per update and a chance lobe adds its lags to σ.
pub const LOBE_BAND_FACTOR: f64 = 1.5;

/// The 95 % band `2/√n` of the normalised autocorrelation of `n` white samples.
pub fn white_band(n: f64) -> f64 {
    2.0 / libm::sqrt(n.max(1.0))
}

/// Running autocorrelation of one residual sequence up to [`MAX_LAG`], with the truncation lag
/// of the module doc. No allocation.
#[derive(Debug, Clone, Copy)]
pub struct Autocorrelation {
    residuals: LagRing,
    filled: usize,
    /// `c(k) = Σ_i λ^{n−i} v_i v_{i−k}`, `k = 0..=MAX_LAG`.
    c: [f64; MAX_LAG + 1],
    /// λ-weighted number of residuals in `c(0)`.
    n_res: f64,
    lag: usize,
    last_lag: usize,
}

impl Default for Autocorrelation {
    fn default() -> Self {
        Self::new()
    }
}

impl Autocorrelation {
    /// No residual yet.
    pub const fn new() -> Self {
        Self {
            residuals: LagRing::new(),
            filled: 0,
            c: [0.0; MAX_LAG + 1],
            n_res: 0.0,
            lag: 0,
            last_lag: 0,
        }
    }

    /// Adds residual `v` with forgetting `λ` and updates the truncation lag `K`: the last lag
    /// before the first whose `|ρ̂(k)|` falls inside the white band `2/√N`; and the end of the
    /// last significant lobe ([`Self::last_significant_lag`]).
    pub fn add(&mut self, v: f64, lambda: f64) {
        self.accumulate(v, lambda);
        self.update_truncation();
    }

    /// Adds residual `v` to the lag products without updating the truncation lags (a caller
    /// that needs them only now and then calls [`Self::update_truncation`] then).
    fn accumulate(&mut self, v: f64, lambda: f64) {
        let avail = self.filled.min(MAX_LAG);
        self.c[0] = lambda * self.c[0] + v * v;
        for (c, r) in self.c[1..=avail].iter_mut().zip(self.residuals.lags(avail)) {
            *c = lambda * *c + v * r;
        }
        self.n_res = lambda * self.n_res + 1.0;
        self.push(v);
    }

    /// Sets [`Self::lag`] and [`Self::last_significant_lag`] from the products so far.
    fn update_truncation(&mut self) {
        // The residual just pushed is lag 1 of the next one: the lags formed are one fewer.
        let avail = self.filled.saturating_sub(1).min(MAX_LAG);
        (self.lag, self.last_lag) = self.truncation(avail);
    }

    /// The truncation lag `K` and the end of the last significant lobe for lags `1..=avail`
    /// (the doc of [`Self::add`]); `(0, 0)` before any non-zero residual. The tests compare
    /// `|c(k)|` with `band · c(0)` rather than dividing, since `c(0) > 0`.
    fn truncation(&self, avail: usize) -> (usize, usize) {
        let c0 = self.c[0];
        if c0 <= 0.0 {
            return (0, 0);
        }
        let band = white_band(self.n_res) * c0;
        let k_max = (1..=avail).take_while(|&k| libm::fabs(self.c[k]) >= band).last().unwrap_or(0);
        // Further lobes: runs of one sign of ρ̂ beyond K, each kept while its sum is
        // significant (|Σ ρ̂| ≥ LOBE_BAND_FACTOR · 2√len/√N; 2√len/√N is the band of a sum of
        // len white lags). The insignificant tail of the lobe that ends at K is not a lobe of
        // its own: the test starts at the next sign change.
        let mut k_last = k_max;
        let mut start = k_max + 1;
        let sign_k = self.c[k_max] >= 0.0;
        while start <= avail && (self.c[start] >= 0.0) == sign_k {
            start += 1;
        }
        while start <= avail {
            let positive = self.c[start] >= 0.0;
            let (mut end, mut sum) = (start, 0.0);
            while end <= avail && (self.c[end] >= 0.0) == positive {
                sum += self.c[end];
                end += 1;
            }
            let len = (end - start) as f64;
            if libm::fabs(sum) < LOBE_BAND_FACTOR * band * libm::sqrt(len) {
                break;
            }
            k_last = end - 1;
            start = end;
        }
        (k_max, k_last)
    }

    /// Starts a new sequence (a new manoeuvre): lags never span the break; the sums are kept.
    pub fn restart(&mut self) {
        self.filled = 0;
    }

    /// Stores `v` as the latest residual without counting it (a row without residual).
    fn push(&mut self, v: f64) {
        self.residuals.push(v);
        self.filled += 1;
    }

    /// The truncation lag `K` after the last residual.
    pub fn lag(&self) -> usize {
        self.lag
    }

    /// The truncation lag with further lobes: after [`Self::lag`] and the insignificant tail of
    /// its lobe, each following run of one sign of `ρ̂` (a lobe) whose sum lies outside
    /// [`LOBE_BAND_FACTOR`] × the band `2√len/√N` of a sum of `len` white lags is added, up to
    /// the first that does not (≤ [`MAX_LAG`]). It reaches past sign
    /// changes, e.g. the negative lobe of differentiated noise.
    pub fn last_significant_lag(&self) -> usize {
        self.last_lag
    }

    /// `ρ̂(k) = c(k)/c(0)`, `None` before any non-zero residual or beyond [`MAX_LAG`].
    pub fn rho(&self, k: usize) -> Option<f64> {
        (k <= MAX_LAG && self.c[0] > 0.0).then(|| self.c[k] / self.c[0])
    }

    /// The variance factor `1 + 2 Σ_{k=1..K} ρ̂(k)` of a mean of the residuals (the
    /// effective-sample-size correction, Bayley & Hammersley 1946): the coloured-residual
    /// correction for regressors that vary slowly over `K` samples. 1 before any residual.
    pub fn variance_factor(&self) -> f64 {
        let mut f = 1.0;
        for k in 1..=self.lag {
            f += 2.0 * self.rho(k).unwrap_or(0.0);
        }
        f
    }
}

/// Recursive coloured-residual covariance of one least-squares fit with up to `C` regressors
/// (module doc). No allocation.
#[derive(Debug, Clone, Copy)]
pub struct ColouredCovariance<const C: usize> {
    n: usize,
    /// The last regressor rows by column: `columns[a]` holds entry `a` of each (only the
    /// leading `n` are used), so that a lag sum over one entry is a slice loop.
    columns: [LagRing; C],
    filled: usize,
    acf: Autocorrelation,
    m: Square<C>,
    /// `s_k = Σ_i λ^{n−i} x_iᵀ P x_{i−k}`, `k = 0..=MAX_LAG` (lag leverage, module doc).
    leverage: [f64; MAX_LAG + 1],
    /// λ-weighted number of rows, `N_eff`.
    n_eff: f64,
    /// Fitted share `r = tr(P M)/N_eff` of the last lag row.
    fitted: f64,
    /// The lag weights `ρ_v(k) λ^k`, `k = 1..=k_weights`, of the last lag row.
    weights: [f64; MAX_LAG],
    k_weights: usize,
    /// Rows since the last lag row, modulo [`LAG_STRIDE`] (0: the last row was one).
    phase: usize,
    /// `λ` to the number of rows since the leverage was last decayed.
    decay: f64,
}

impl<const C: usize> ColouredCovariance<C> {
    /// An empty accumulator for a fit with `n ≤ C` regressors.
    pub fn new(n: usize) -> Self {
        Self {
            n: n.min(C),
            columns: [LagRing::new(); C],
            filled: 0,
            acf: Autocorrelation::new(),
            m: [[0.0; C]; C],
            leverage: [0.0; MAX_LAG + 1],
            n_eff: 0.0,
            fitted: 0.0,
            weights: [0.0; MAX_LAG],
            k_weights: 0,
            phase: 0,
            decay: 1.0,
        }
    }

    /// Adds regressor row `x` (leading `n` entries) with its residual `v` and forgetting factor
    /// `λ`. `fit = Some((v, P))` once the fit is initialised (`P` its current inverse
    /// information, leading `n × n` block); `None` before: the row enters `M` as white.
    ///
    /// Every row enters the residual lag products and `M`, with the lag weights of the last
    /// lag row; every [`LAG_STRIDE`]-th row with a residual (a *lag row*) also enters the lag
    /// leverage and sets the truncation lags, the fitted share and the weights (module doc,
    /// "Decimation").
    pub fn add(&mut self, x: &[f64; C], fit: Option<(f64, &Square<C>)>, lambda: f64) {
        let n = self.n;
        self.n_eff = lambda * self.n_eff + 1.0;
        self.decay *= lambda;
        let avail = self.filled.min(MAX_LAG);
        self.phase = (self.phase + 1) % LAG_STRIDE;
        let h = match fit {
            Some((v, p)) => {
                self.acf.accumulate(v, lambda);
                if self.phase == 0 {
                    self.fitted = (self.trace_pm(p) / self.n_eff).clamp(0.0, 1.0);
                    self.add_leverage(x, p, avail);
                    self.acf.update_truncation();
                    self.set_weights(lambda, self.acf.last_significant_lag());
                }
                self.lagged_sum(avail)
            }
            None => {
                self.acf.push(0.0);
                [0.0; C]
            }
        };
        let l2 = lambda * lambda;
        for a in 0..n {
            for b in a..n {
                let v = l2 * self.m[a][b] + x[a] * x[b] + x[a] * h[b] + h[a] * x[b];
                self.m[a][b] = v;
                self.m[b][a] = v;
            }
        }
        for (column, &xa) in self.columns[..n].iter_mut().zip(x) {
            column.push(xa);
        }
        self.filled += 1;
    }

    /// Whether the last [`Self::add`] was the [`LAG_STRIDE`]-th row of its cycle: a lag row
    /// when it carried a residual (`fit` given), which is when a caller forms what it derives
    /// from `M` at the lag rows.
    pub fn lag_row(&self) -> bool {
        self.phase == 0
    }

    /// Lag leverage `s_k = Σ λ^{n−i} x_iᵀ P x_{i−k}`, `k = 0..=avail`, over the lag rows only,
    /// with lag row `x` added (every `s_k` is sampled alike, so only the shape
    /// `ρ_H(k) = s_k/s_0` is used).
    fn add_leverage(&mut self, x: &[f64; C], p: &Square<C>, avail: usize) {
        let n = self.n;
        let mut px = [0.0; C];
        for a in 0..n {
            px[a] = (0..n).map(|b| p[a][b] * x[b]).sum();
        }
        let decay = self.decay;
        self.decay = 1.0;
        self.leverage[0] = decay * self.leverage[0] + (0..n).map(|a| px[a] * x[a]).sum::<f64>();
        let lagged = &mut self.leverage[1..=avail];
        for s in lagged.iter_mut() {
            *s *= decay;
        }
        for (column, &pa) in self.columns[..n].iter().zip(&px) {
            for (s, xa) in lagged.iter_mut().zip(column.lags(avail)) {
                *s += pa * xa;
            }
        }
    }

    /// The lag weights `w_k = ρ_v(k) λ^k`, `k = 1..=k_max`, with `ρ_v(k) = (1 − r) ρ̂(k) +
    /// r ρ_H(k)` (module doc), kept until the next lag row.
    fn set_weights(&mut self, lambda: f64, k_max: usize) {
        let r = self.fitted;
        // Reciprocals once: a division per lag would be the loop's latency.
        let s0 = self.leverage[0];
        let inv_s0 = if s0 > 0.0 { 1.0 / s0 } else { 0.0 };
        let c = &self.acf.c;
        let inv_c0 = if c[0] > 0.0 { 1.0 / c[0] } else { 0.0 };
        let mut lk = 1.0;
        for (k, wk) in self.weights.iter_mut().enumerate().take(k_max) {
            lk *= lambda;
            let rho_v = (1.0 - r) * c[k + 1] * inv_c0 + r * self.leverage[k + 1] * inv_s0;
            *wk = rho_v * lk;
        }
        self.k_weights = k_max;
    }

    /// `h = g − x = Σ_{k=1..K} w_k x_{n−k}` with the weights of the last lag row, over the
    /// `avail` rows before the current one in the ring.
    fn lagged_sum(&self, avail: usize) -> [f64; C] {
        let k_max = self.k_weights.min(avail);
        let w = &self.weights[..k_max];
        let mut h = [0.0; C];
        for (ha, column) in h.iter_mut().zip(&self.columns[..self.n]) {
            *ha = w.iter().zip(column.lags(k_max)).map(|(w, x)| w * x).sum();
        }
        h
    }

    /// Re-opens the memory after a change test's alarm (`crate::change`): the rows before the
    /// test's recent memory kept with weight `w` (`M` with `w²`, `N_eff` with `w`), the recent
    /// memory's `n_run` weighted rows, whose information is `a_run`, entered as white. The residual autocorrelation is
    /// kept: a change of the parameters does not change the noise's colour.
    pub fn reopen(&mut self, w: f64, a_run: &Square<C>, n_run: f64) {
        let n = self.n;
        for a in 0..n {
            for b in 0..n {
                self.m[a][b] = w * w * self.m[a][b] + a_run[a][b];
            }
        }
        self.n_eff = w * (self.n_eff - n_run).max(0.0) + n_run;
    }

    /// The lag `K` at which the last lag row truncated the sum (after the last significant
    /// lobe).
    pub fn lag(&self) -> usize {
        self.acf.last_significant_lag()
    }

    /// The fitted share `r = tr(P M)/N_eff` of the last lag row (module doc; 0 before the fit
    /// is initialised).
    pub fn fitted_share(&self) -> f64 {
        self.fitted
    }

    /// `tr(P M)` for the fit's `P` (leading `n × n` block): the degrees of freedom the fit
    /// takes from the λ-weighted residual sum of squares, `E[RSS] = σ²(N_eff − tr(P M))`
    /// (module doc). `p` for white residuals and λ = 1.
    pub fn trace_pm(&self, p: &Square<C>) -> f64 {
        let n = self.n;
        let mut t = 0.0;
        for a in 0..n {
            for b in 0..n {
                t += p[a][b] * self.m[b][a];
            }
        }
        t
    }

    /// The normalised residual autocorrelation `ρ̂(k)` (`None` before any residual).
    pub fn autocorrelation(&self, k: usize) -> Option<f64> {
        self.acf.rho(k)
    }

    /// Entry `(i, j)` of `σ̂² P M Pᵀ` (module doc) for the fit's `P` (leading `n × n` block):
    /// `σ̂² P M P` for least squares, whose `P` is symmetric; for instrumental variables
    /// (`crate::iv`) `P = (Σ λ z φᵀ)⁻¹` is not, and `M` is built from the instrument rows `z`.
    pub fn covariance(&self, p: &Square<C>, s2: f64, i: usize, j: usize) -> f64 {
        let n = self.n;
        let mut s = 0.0;
        for a in 0..n {
            let mut row = 0.0;
            for b in 0..n {
                row += self.m[a][b] * p[j][b];
            }
            s += p[i][a] * row;
        }
        s2 * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// The variance factor of AR(1) residuals is `(1 + a)/(1 − a)` (the sum `1 + 2 Σ aᵏ`),
    /// minus the tail beyond the truncation lag; of MA(1) residuals `v_i = w_i + b w_{i−1}` it
    /// is `(1 + b)²/(1 + b²)`; of white residuals 1.
    #[test]
    fn analytic_variance_factor_of_ar1_ma1_and_white() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let n01 = Normal::new(0.0, 1.0).unwrap();
        let (a, b) = (0.6, 0.8);
        let (mut ar, mut ma, mut white) =
            (Autocorrelation::new(), Autocorrelation::new(), Autocorrelation::new());
        let (mut v, mut w_prev) = (0.0, 0.0);
        for _ in 0..100_000 {
            let w = n01.sample(&mut rng);
            v = a * v + w;
            ar.add(v, 1.0);
            ma.add(w + b * w_prev, 1.0);
            white.add(w, 1.0);
            w_prev = w;
        }
        let f_ar = ar.variance_factor();
        let f_ma = ma.variance_factor();
        let f_w = white.variance_factor();
        assert!((f_ar / ((1.0 + a) / (1.0 - a)) - 1.0).abs() < 0.05, "AR(1): {f_ar}");
        assert!((f_ma / ((1.0 + b) * (1.0 + b) / (1.0 + b * b)) - 1.0).abs() < 0.05, "MA: {f_ma}");
        assert_eq!(ma.lag(), 1, "MA(1) has one significant lag");
        assert!((f_w - 1.0).abs() < 0.05, "white: {f_w}");
    }
}
