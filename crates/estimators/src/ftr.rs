//! Real-time Fourier-transform regression (equation error in the frequency domain) over any
//! [`ModelStructure`].
//!
//! Source: E. A. Morelli, "Real-time parameter estimation in the frequency domain", *J. Guidance,
//! Control, and Dynamics* 23(5), 2000 (AIAA-99-4043); Klein & Morelli, *Aircraft System
//! Identification*, AIAA 2006, ch. 7 (equation error in the frequency domain); SIDPAC `rtpid`.
//!
//! Every signal the structure needs — each term's regressor `ξ_j` and each modelled measured
//! coefficient `C_k` — is transformed recursively at a fixed grid of angular frequencies `ω_m`:
//!
//! ```text
//! X̃_j(ω_m) ← λ X̃_j(ω_m) + (ξ_j(t_i) − ξ_j(t_0)) e^{−j ω_m t_i} Δt
//! ```
//!
//! (`λ ≤ 1` an optional forgetting factor; the first sample's value is removed so trim values do
//! not leak into the low frequencies). The cost per sample is O(frequencies × signals); the
//! rotating phasor `e^{−jω t_i}` is advanced by multiplication with `e^{−jω Δt}` and
//! recomputed exactly when the interval changes and every 1,000 samples. On demand (every
//! `solve_interval_s`), each coefficient is solved by least squares with an offset column:
//!
//! ```text
//! C̃ = X̃ θ + D̃ c + ε̃,   θ̂ = [Re(X̃ₐ† X̃ₐ)]⁻¹ Re(X̃ₐ† C̃),   X̃ₐ = [X̃ D̃]
//! ```
//!
//! with `m` frequencies and `p` parameters of that coefficient (Morelli 2000; Klein & Morelli
//! 2006 ch. 7). `D̃(ω) = Σ λ^{n−i} Δt e^{−jω t_i}` is the transform of a constant: the offset `c`
//! absorbs whatever constant is left after removing the first sample (the first sample's noise,
//! a bias term, a trim mismatch), which would otherwise leak into the low frequencies of a
//! finite record. It is a nuisance parameter, never reported. Bias terms (`_0`) and trim values
//! have no content at `ω > 0`: **they drop out** and are reported as not identified (`null`). A
//! coefficient is identified once `Re(X̃ₐ†X̃ₐ)` is well conditioned (the same scaled-pivot test
//! as [`crate::rls`]) and `m > p + 1`.
//!
//! # Memory and grid
//!
//! The normal equations `Re(X̃ₐ†X̃ₐ)`, `Re(X̃ₐ†C̃)` are products of two transforms, each
//! weighting sample `i` by `λ^{n−i}`; summed over a grid that spans the signals' band, the
//! cross products of different samples cancel and sample `i` carries `λ^{2(n−i)}`. The memory
//! is therefore `Δt/(1 − λ²) ≈ Δt/(2(1 − λ))`, **half** that of [`crate::rls`] with the same
//! λ (whose loss weights squared residuals by `λ^{n−i}`); the noise enters σ with the same
//! `λ^{2(n−i)}` (`W` below). FTR with `λ_ftr = √λ_rls` has RLS's memory
//! (`tests::analytic_memory_is_the_squared_forgetting`). The window's frequency resolution
//! (half-power half-width) is `(1 − λ)/(2π Δt)` Hz; an excitation harmonic further than a few
//! half-widths outside `[f_min, f_max]` reaches the fit only through that window's leakage,
//! so the grid should span the excitation band plus about two half-widths.
//!
//! # σ: the residual spectrum and the window
//!
//! The book's `cov θ̂ = σ̂² A⁻¹`, `σ̂² = ε̃†ε̃/(m − p)`, `A = Re(X̃†X̃)`, holds when the residual
//! transforms are independent with equal variance at every frequency. On a record of length
//! (or memory) `T` the grid's neighbours closer than `1/T` are strongly correlated, and a
//! residual coloured by turbulence or smoothing has a non-flat spectrum. The covariance
//! reported is the sandwich of the real-parameter least squares on complex data,
//!
//! ```text
//! u = Re(X̃ₐ† ε̃),   Cov θ̂ = A⁻¹ E[u uᵀ] A⁻¹,
//! E[u uᵀ] = M = ½ Re Σ_f Σ_g X̃_f* (C_fg X̃_g + P_fg X̃_g*)
//! C_fg = E[ε̃_f ε̃_g*] ≈ ½(S_f + S_g) W(ω_f − ω_g),   P_fg = E[ε̃_f ε̃_g] ≈ ½(S_f + S_g) W(ω_f + ω_g)
//! W(ω) = Σ_i λ^{2(n−i)} Δt_i² e^{−jω t_i}
//! ```
//!
//! (the exact second moments for a residual spectrum `S` that is flat over the window's
//! resolution; the frequency-domain form of Morelli & Klein's coloured-residual correction,
//! [`crate::coloured`]). `W` is accumulated recursively at the `m` difference and `2m − 1` sum
//! frequencies of the uniform grid from products of the phasors (`O(3m)` per sample, no new
//! phasors). For white noise this `A⁻¹ M A⁻¹` with the true level is the exact covariance of
//! θ̂ (`tests::analytic_white_noise_sandwich_equals_exact_covariance`).
//!
//! ## The level: what the fit removed
//!
//! The level `S_f` is estimated from the residual periodogram `|ε̃_f|²/W(0)`, Daniell-smoothed
//! over ±[`SPECTRUM_HALF_WIDTH`] grid frequencies. But the residual is `ε̃ = ṽ − X̃ₐ A⁻¹ u`,
//! and its periodogram is depleted where the regressors have power, which is exactly where
//! `M` looks. With λ = 0.995 at 100 Hz (transforms over 2 s, an estimate memory of 1 s) the 36
//! frequencies carry only a few independent noise observations (bandwidth × 2 s ≈ 3), so that depletion is large and spread
//! over neighbours (the diagonal leverage `h_f/2` misses it) and the raw level left σ at
//! 0.77–0.88 of the scatter. Its expected value under a level `S` follows exactly from the
//! quantities of `M`:
//!
//! ```text
//! E|ε̃_f|² = C_ff − Re Σ_jk X̃ₐ,fj (A⁻¹)_jk v̄_kf + Σ_jk Re(X̃ₐ,fj* X̃ₐ,fk) (A⁻¹MA⁻¹)_jk,
//! v_kf = Σ_g (C_fg X̃ₐ,gk + P_fg X̃ₐ,gk*)
//! ```
//!
//! (`E[ṽ_f* u_k] = ½ v̄_kf`; summed over `f` it is `tr C − tr A⁻¹M`). The level is the
//! moment estimate whose smoothed expected periodogram matches the smoothed observed one:
//! starting from the raw level, `S_f ← S_f · D[|ε̃|²]_f / D[E|ε̃|²]_f` (`D` the Daniell
//! smoother, the ratio clipped to [0.2, 5]) for [`FITTED_SHARE_ITERATIONS`] passes: the
//! frequency-domain form of the fitted-share correction of [`crate::coloured`] ("Finite
//! memory"), built on the exact second moments of a least-squares residual under correlated
//! errors (`ε = (I − H)ṽ`, so `E[ε εᵀ] = (I − H) Σ (I − H)ᵀ` in the real form, as for the
//! `E[RSS]` identity there). Finally the level is scaled by `κ` so that the model reproduces the
//! observed residual sum of squares, `E[ε̃†ε̃] = tr C − tr(A⁻¹M)` (the generalised
//! degrees-of-freedom correction: `κ = RSS / (tr C − tr A⁻¹M)`). For independent frequencies
//! and white noise this is `RSS/(2m − p)·A⁻¹`: real and imaginary parts are two observations.
//! The solve costs `O(p m²)` more per pass (`1 + FITTED_SHARE_ITERATIONS` passes), spread
//! over the samples as below.
//!
//! ## Cost per update
//!
//! Once a solve is due the coefficients are solved one at a time in turn. A coefficient's
//! estimate is the cheap part (`O(p² m)`); its σ is not: four noise moments of `q m²` terms
//! each, about 60,000 for a six-axis coefficient on 41 frequencies, some 40 µs, against under
//! 1 µs for the rest of an update. Done in the update that solves, it made one update in eight
//! of the six-axis estimator 47 times slower than the median (docs/c-abi.md), which a flight
//! computer's scheduler must budget for. With [`FtrConfig::spread_sigma`] (estimator option
//! `spread_sigma = true`) the σ's inputs are copied when the coefficient is solved and its σ
//! is computed over the following updates (`ftr/sigma.rs`), each update doing an
//! equal share of the round's work: the round's inner-sum terms over the updates one solve
//! interval holds at the current sample interval, so a round ends within the interval at any
//! rate. The estimate and its σ are published together when
//! the σ is done; the previous solution stands until then. The arithmetic is that of one pass
//! in the same order, so the σ is the one of the solve's data however it is split; what
//! changes is when a solution appears: up to one solve interval after its solve instead of up
//! to one update per coefficient. On the default flight's 200-run Monte Carlo that moved the
//! end-of-flight snapshot of some estimates to an earlier solve (Cm_α's scatter +17 %, Cl_p's
//! −13 %, Cl_p's coverage 94.5 → 99 %; docs/reliability.md), so it is not the default: without
//! it (or with an interval that holds no more than three updates per coefficient) each σ is
//! computed in the update that solves its coefficient, one coefficient per update, and the
//! results are those of before bit for bit.

use crate::EstimatorError;
use crate::estimator::{
    Estimates, Estimator, Status, check_finite, measured_coefficient, regressor,
};
use crate::linalg::{Square, cholesky, cholesky_inverse, cholesky_solve, well_conditioned};
use crate::sample::AirDataSample;
use crate::vocabulary::{Coefficient, ModelStructure, N_TERMS, Term};
use core::f64::consts::PI;
use sigma::{SigmaJob, SigmaStart};

mod sigma;

/// Half-width, in grid frequencies, of the Daniell smoothing of the residual spectrum (σ).
pub const SPECTRUM_HALF_WIDTH: usize = 3;

/// Most frequencies of the grid.
pub const MAX_FREQUENCIES: usize = 64;

/// Configuration of [`Ftr`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FtrConfig {
    /// Lowest frequency of the grid, Hz (> 0).
    pub f_min_hz: f64,
    /// Highest frequency of the grid, Hz.
    pub f_max_hz: f64,
    /// Grid step, Hz (> 0); at most [`MAX_FREQUENCIES`] frequencies.
    pub f_step_hz: f64,
    /// Forgetting factor of the recursive transform, `(0, 1]` per sample (1 = none). The
    /// estimate's memory is `Δt/(1 − λ²)`, half that of RLS with the same λ (module doc,
    /// "Memory and grid").
    pub forgetting: f64,
    /// Interval between solves, s (≥ 0; 0 = every sample).
    pub solve_interval_s: f64,
    /// Spread each round of solves' σ evenly over the solve interval (module doc, "Cost per
    /// update"): a bounded update for a flight computer's scheduler, each solution published up
    /// to one interval after its solve. `false` (the default): each σ in the update that
    /// solves its coefficient.
    pub spread_sigma: bool,
}

impl Default for FtrConfig {
    /// Morelli's grid for rigid-body dynamics: 0.1–1.5 Hz in 0.04 Hz steps (36 frequencies),
    /// no forgetting, a solve every second, each σ in its solve's update.
    fn default() -> Self {
        Self {
            f_min_hz: 0.1,
            f_max_hz: 1.5,
            f_step_hz: 0.04,
            forgetting: 1.0,
            solve_interval_s: 1.0,
            spread_sigma: false,
        }
    }
}

/// A complex number as (re, im).
type C64 = (f64, f64);

fn cmul(a: C64, b: C64) -> C64 {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

/// The recursive DFT of up to `N_TERMS + 8` signals.
#[derive(Debug, Clone, Copy)]
struct Transforms {
    /// `terms[t][m]`: transform of term `t` (index in [`Term::ALL`]) at frequency `m`.
    terms: [[C64; MAX_FREQUENCIES]; N_TERMS],
    /// `coefs[k][m]`: transform of measured coefficient `k`.
    coefs: [[C64; MAX_FREQUENCIES]; 8],
}

/// One coefficient's frequency-domain solution.
#[derive(Debug, Clone, Copy)]
struct Solution {
    theta: [f64; N_TERMS],
    cov: Square<N_TERMS>,
    identified: bool,
}

/// Real-time Fourier-transform regression. No allocation per update.
#[derive(Debug, Clone)]
pub struct Ftr {
    structure: ModelStructure,
    cfg: FtrConfig,
    n_freq: usize,
    omega: [f64; MAX_FREQUENCIES],
    phasor: [C64; MAX_FREQUENCIES],
    step: [C64; MAX_FREQUENCIES],
    step_dt: f64,
    since_exact: usize,
    used_terms: u32,
    x: Transforms,
    /// `W(d) = Σ_i λ^{2(n−i)} Δt_i² e^{−j (ω_d − ω_0) t_i}`, `d = 0..m−1` (module doc, σ).
    w_diff: [C64; MAX_FREQUENCIES],
    /// `W⁺(s) = Σ_i λ^{2(n−i)} Δt_i² e^{−j (2ω_0 + s Δω) t_i}`, `s = 0..2m−2`.
    w_sum: [C64; 2 * MAX_FREQUENCIES],
    /// `D̃(ω_m) = Σ_i λ^{n−i} Δt_i e^{−jω_m t_i}`: the transform of a constant 1, the column of
    /// the offset every fit carries (module doc).
    offset: [C64; MAX_FREQUENCIES],
    first_terms: [f64; N_TERMS],
    first_coefs: [f64; 8],
    last_t: Option<f64>,
    /// `new_manoeuvre` was called: the next sample restarts the trim reference.
    restart: bool,
    t0: f64,
    next_solve_t: f64,
    pending: u8,
    /// The σ of the last coefficient solved, while it is computed (module doc, "Cost per
    /// update").
    sigma: SigmaJob,
    /// Inner-sum terms of σ work per update in the current round (`usize::MAX`: all at once).
    sigma_budget: usize,
    solutions: [Solution; 8],
    est: Estimates,
}

impl Ftr {
    /// A new estimator.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] for a grid that is empty, non-positive or has more than
    /// [`MAX_FREQUENCIES`] points, a forgetting factor outside (0, 1], a negative solve interval
    /// or an invalid structure.
    pub fn new(structure: ModelStructure, cfg: FtrConfig) -> Result<Self, EstimatorError> {
        let bad =
            |field, value, reason| Err(EstimatorError::InvalidConfig { field, value, reason });
        if !(cfg.f_min_hz > 0.0 && cfg.f_step_hz > 0.0 && cfg.f_max_hz >= cfg.f_min_hz) {
            return bad(
                "f_min_hz/f_step_hz/f_max_hz",
                cfg.f_min_hz,
                "need 0 < f_min ≤ f_max, step > 0",
            );
        }
        let n = libm::floor((cfg.f_max_hz - cfg.f_min_hz) / cfg.f_step_hz + 1e-9) as usize + 1;
        if n > MAX_FREQUENCIES {
            return bad("f_step_hz", cfg.f_step_hz, "grid has more than 64 frequencies");
        }
        if !(cfg.forgetting > 0.0 && cfg.forgetting <= 1.0) {
            return bad("forgetting", cfg.forgetting, "must be in (0, 1]");
        }
        if !(cfg.solve_interval_s >= 0.0 && cfg.solve_interval_s.is_finite()) {
            return bad("solve_interval_s", cfg.solve_interval_s, "must be finite and ≥ 0");
        }
        let structure = structure.validated().map_err(|_| EstimatorError::InvalidConfig {
            field: "model structure",
            value: structure.n_params() as f64,
            reason: "empty, over capacity, or mixes CX/CZ with CL/CD",
        })?;
        let mut omega = [0.0; MAX_FREQUENCIES];
        for (m, w) in omega.iter_mut().enumerate().take(n) {
            *w = 2.0 * PI * (cfg.f_min_hz + m as f64 * cfg.f_step_hz);
        }
        let mut used_terms = 0u32;
        for p in structure.params() {
            if p.term != Term::Bias {
                used_terms |= 1 << p.term.index();
            }
        }
        Ok(Self {
            structure,
            cfg,
            n_freq: n,
            omega,
            phasor: [(1.0, 0.0); MAX_FREQUENCIES],
            step: [(1.0, 0.0); MAX_FREQUENCIES],
            step_dt: f64::NAN,
            since_exact: 0,
            used_terms,
            x: Transforms {
                terms: [[(0.0, 0.0); MAX_FREQUENCIES]; N_TERMS],
                coefs: [[(0.0, 0.0); MAX_FREQUENCIES]; 8],
            },
            w_diff: [(0.0, 0.0); MAX_FREQUENCIES],
            w_sum: [(0.0, 0.0); 2 * MAX_FREQUENCIES],
            offset: [(0.0, 0.0); MAX_FREQUENCIES],
            first_terms: [0.0; N_TERMS],
            first_coefs: [0.0; 8],
            last_t: None,
            restart: false,
            t0: 0.0,
            next_solve_t: f64::NEG_INFINITY,
            pending: 0,
            sigma: SigmaJob::idle(),
            sigma_budget: usize::MAX,
            solutions: [Solution {
                theta: [0.0; N_TERMS],
                cov: [[0.0; N_TERMS]; N_TERMS],
                identified: false,
            }; 8],
            est: Estimates::new(structure.n_params()),
        })
    }

    /// The angular frequencies of the grid, rad/s.
    pub fn frequencies_rad_s(&self) -> &[f64] {
        &self.omega[..self.n_freq]
    }

    /// Advances the phasors to time `t` (exact every 1,000 samples or when Δt changes).
    fn advance_phasors(&mut self, t: f64, dt: Option<f64>) {
        let exact = match dt {
            None => true,
            Some(dt) => {
                // The first interval (step_dt = NaN) is exact too.
                self.since_exact >= 1000
                    || self.step_dt.is_nan()
                    || libm::fabs(dt - self.step_dt) > 1e-9 * dt.abs().max(1e-3)
            }
        };
        if exact {
            for m in 0..self.n_freq {
                let a = -self.omega[m] * t;
                self.phasor[m] = (libm::cos(a), libm::sin(a));
                if let Some(dt) = dt {
                    let b = -self.omega[m] * dt;
                    self.step[m] = (libm::cos(b), libm::sin(b));
                }
            }
            if let Some(dt) = dt {
                self.step_dt = dt;
            }
            self.since_exact = 0;
        } else {
            for m in 0..self.n_freq {
                self.phasor[m] = cmul(self.phasor[m], self.step[m]);
            }
            self.since_exact += 1;
        }
    }

    /// Solves coefficient `c` (module doc).
    fn solve(&mut self, c: Coefficient) {
        let mut terms = [Term::Bias; N_TERMS];
        let mut p = 0;
        for t in self.structure.terms_of(c) {
            if t != Term::Bias {
                terms[p] = t;
                p += 1;
            }
        }
        let was_identified = self.solutions[c.index()].identified;
        self.solutions[c.index()].identified = false;
        let m = self.n_freq;
        // Columns: the p terms, then the offset D̃.
        let q = p + 1;
        if p == 0 || m <= q {
            return;
        }
        let mut a = [[0.0; N_TERMS]; N_TERMS];
        let mut b = [0.0; N_TERMS];
        let y = &self.x.coefs[c.index()];
        for i in 0..q {
            let xi = self.column(&terms, p, i);
            for j in 0..=i {
                let xj = self.column(&terms, p, j);
                let mut s = 0.0;
                for f in 0..m {
                    s += xi[f].0 * xj[f].0 + xi[f].1 * xj[f].1;
                }
                a[i][j] = s;
                a[j][i] = s;
            }
            let mut s = 0.0;
            for f in 0..m {
                s += xi[f].0 * y[f].0 + xi[f].1 * y[f].1;
            }
            b[i] = s;
        }
        // Weight for the size floor: a transform over the elapsed time T carries ~ (x T)² per
        // frequency, so the floor is m T² · MIN_REGRESSOR_RMS².
        let span = self.last_t.unwrap_or(0.0) - self.t0;
        if !well_conditioned(&a, q, m as f64 * span * span, crate::linalg::MIN_SCALED_PIVOT) {
            return;
        }
        let mut l = [[0.0; N_TERMS]; N_TERMS];
        if !cholesky(&a, q, &mut l) {
            return;
        }
        let mut theta = b;
        cholesky_solve(&l, q, &mut theta);
        let mut resid = [(0.0, 0.0); MAX_FREQUENCIES];
        let mut rss = 0.0;
        for f in 0..m {
            let mut r = y[f];
            for i in 0..q {
                let xi = self.column(&terms, p, i)[f];
                r.0 -= xi.0 * theta[i];
                r.1 -= xi.1 * theta[i];
            }
            resid[f] = r;
            rss += r.0 * r.0 + r.1 * r.1;
        }
        let mut inv = [[0.0; N_TERMS]; N_TERMS];
        cholesky_inverse(&l, q, &mut inv);
        let finite = theta[..q].iter().all(|v| v.is_finite()) && rss.is_finite();
        if !finite {
            return;
        }
        theta[p] = 0.0;
        // Field by field (not through `column`): the job is written while these are read.
        let (x, offset) = (&self.x.terms, &self.offset);
        let cols: [&[C64; MAX_FREQUENCIES]; N_TERMS] =
            core::array::from_fn(|i| if i < p { &x[terms[i].index()] } else { offset });
        let start = SigmaStart {
            m,
            p,
            cols,
            w_diff: &self.w_diff,
            w_sum: &self.w_sum,
            inv: &inv,
            resid: &resid,
            rss,
        };
        // The previous solution stands until this one's σ is done.
        self.solutions[c.index()].identified = was_identified;
        if !self.sigma.start(c.index(), &theta, &start) {
            self.solutions[c.index()].identified = false;
        }
    }

    /// The σ work per update that finishes a round of solves within the solve interval at a
    /// sample interval `dt` (module doc, "Cost per update"): the round's inner-sum terms (as
    /// `ftr/sigma.rs` counts them, each coefficient with its `q = p + 1` columns) over the updates of
    /// one interval, less two per coefficient (the update that solves it, and the part of its
    /// σ's last update left unused); `usize::MAX` when not spread, when the interval holds no
    /// more than three updates per coefficient, or before `dt` is known.
    fn round_budget(&self, dt: f64) -> usize {
        let n = self.structure.coefficients().count();
        let updates = self.cfg.solve_interval_s / dt;
        if !(self.cfg.spread_sigma && updates.is_finite() && updates > 3.0 * n as f64) {
            return usize::MAX;
        }
        let (m, passes) = (self.n_freq, FITTED_SHARE_ITERATIONS);
        let work: usize = self
            .structure
            .coefficients()
            .map(|c| {
                let q = self.structure.terms_of(c).filter(|t| *t != Term::Bias).count() + 1;
                (1 + passes) * (q * m * m + q * q * m) + passes * 2 * m * q * q
            })
            .sum();
        work.div_ceil(updates as usize - 2 * n).max(1)
    }

    /// Advances the σ in progress by the configured work and, when it is done, publishes the
    /// coefficient's solution with it (or marks it not identified when no σ could be formed).
    fn advance_sigma(&mut self) {
        let Some(cov) = self.sigma.advance(self.sigma_budget) else { return };
        let sol = &mut self.solutions[self.sigma.coefficient];
        match cov {
            Some(cov) => {
                sol.theta = self.sigma.theta;
                sol.cov = cov;
                sol.identified = true;
            }
            None => sol.identified = false,
        }
    }

    /// Column `i` of a coefficient's regression: term `terms[i]` for `i < p`, else the offset.
    fn column(&self, terms: &[Term; N_TERMS], p: usize, i: usize) -> &[C64; MAX_FREQUENCIES] {
        if i < p { &self.x.terms[terms[i].index()] } else { &self.offset }
    }

    fn publish(&mut self, t_s: f64) {
        self.est.t_s = t_s;
        let mut all = true;
        for c in self.structure.coefficients() {
            // By reference: a solution holds a 26 × 26 covariance, and a copy of it per
            // coefficient and update was a tenth of the update's time.
            let sol = &self.solutions[c.index()];
            let first = self.structure.first_index(c);
            let mut k = 0;
            for (n, t) in self.structure.terms_of(c).enumerate() {
                if t == Term::Bias {
                    // Drops out of the frequency-domain regression: never identified.
                    self.est.set(first + n, 0.0, None, false);
                    continue;
                }
                let sigma = libm::sqrt(sol.cov[k][k].max(0.0));
                self.est.set(first + n, sol.theta[k], Some(sigma), sol.identified);
                all &= sol.identified;
                k += 1;
            }
        }
        self.est.status = if all { Status::Running } else { Status::Initialising };
    }
}

/// Passes of the fitted-share correction of the residual level (module doc, "The level").
pub const FITTED_SHARE_ITERATIONS: usize = 3;

impl Estimator for Ftr {
    fn method(&self) -> &'static str {
        "ftr"
    }

    fn structure(&self) -> &ModelStructure {
        &self.structure
    }

    /// A new manoeuvre (after a gap): the next sample becomes the trim reference of what
    /// follows and carries no weight (the gap interval is not integrated). The transforms of
    /// the manoeuvres add (the finite Fourier transform of a concatenation; Klein & Morelli
    /// 2006 ch. 7), so a trim or bias change between manoeuvres does not leak into them.
    fn new_manoeuvre(&mut self) {
        self.restart = true;
    }

    fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        check_finite(s)?;
        let measured = s.measured_coefficients();
        let mut term_values = [0.0; N_TERMS];
        for t in Term::ALL {
            if self.used_terms & (1 << t.index()) != 0 {
                term_values[t.index()] = regressor(t, s, self.structure.knots())?;
            }
        }
        let mut coef_values = [0.0; 8];
        for c in self.structure.coefficients() {
            coef_values[c.index()] = measured_coefficient(s, &measured, c)?;
        }
        let dt = match self.last_t.filter(|_| !self.restart) {
            None => {
                self.first_terms = term_values;
                self.first_coefs = coef_values;
                if self.last_t.is_none() {
                    self.t0 = s.t_s;
                }
                self.restart = false;
                None
            }
            Some(t0) => {
                let dt = s.t_s - t0;
                if dt.is_nan() || dt <= 0.0 {
                    return Err(EstimatorError::NonFiniteInput {
                        field: "dt_s (time must increase)",
                        value: dt,
                        t_s: s.t_s,
                    });
                }
                Some(dt)
            }
        };
        self.advance_phasors(s.t_s, dt);
        let w = dt.unwrap_or(0.0);
        let lambda = self.cfg.forgetting;
        for t in Term::ALL {
            if self.used_terms & (1 << t.index()) == 0 {
                continue;
            }
            let v = (term_values[t.index()] - self.first_terms[t.index()]) * w;
            let row = &mut self.x.terms[t.index()];
            for m in 0..self.n_freq {
                row[m].0 = lambda * row[m].0 + v * self.phasor[m].0;
                row[m].1 = lambda * row[m].1 + v * self.phasor[m].1;
            }
        }
        // The noise windows of the σ (module doc): products of the phasors give the difference
        // and sum frequencies without phasors of their own.
        let (l2, w2) = (lambda * lambda, w * w);
        let m = self.n_freq;
        let conj0 = (self.phasor[0].0, -self.phasor[0].1);
        for d in 0..m {
            let e = cmul(self.phasor[d], conj0);
            self.w_diff[d] = (l2 * self.w_diff[d].0 + w2 * e.0, l2 * self.w_diff[d].1 + w2 * e.1);
        }
        for f in 0..m {
            let o = &mut self.offset[f];
            *o = (lambda * o.0 + w * self.phasor[f].0, lambda * o.1 + w * self.phasor[f].1);
        }
        for sidx in 0..2 * m - 1 {
            let f = sidx.min(m - 1);
            let e = cmul(self.phasor[f], self.phasor[sidx - f]);
            self.w_sum[sidx] =
                (l2 * self.w_sum[sidx].0 + w2 * e.0, l2 * self.w_sum[sidx].1 + w2 * e.1);
        }
        for c in self.structure.coefficients() {
            let v = (coef_values[c.index()] - self.first_coefs[c.index()]) * w;
            let row = &mut self.x.coefs[c.index()];
            for m in 0..self.n_freq {
                row[m].0 = lambda * row[m].0 + v * self.phasor[m].0;
                row[m].1 = lambda * row[m].1 + v * self.phasor[m].1;
            }
        }
        self.last_t = Some(s.t_s);
        // Solves: when due, one coefficient at a time in turn, each σ over the updates its work
        // takes (module doc, "Cost per update").
        if self.pending == 0 && !self.sigma.active && s.t_s >= self.next_solve_t {
            self.pending = self.structure.coefficients().count() as u8;
            self.next_solve_t = s.t_s + self.cfg.solve_interval_s;
            // The last known interval at a manoeuvre's first sample (which has none of its own).
            self.sigma_budget = self.round_budget(if w > 0.0 { w } else { self.step_dt });
        }
        if self.sigma.active {
            self.advance_sigma();
        } else if self.pending > 0 {
            let n = self.structure.coefficients().count();
            let k = n - self.pending as usize;
            let next = self.structure.coefficients().nth(k);
            if let Some(c) = next {
                self.solve(c);
                if self.sigma_budget == usize::MAX && self.sigma.active {
                    self.advance_sigma();
                }
            }
            self.pending -= 1;
        }
        self.publish(s.t_s);
        Ok(&self.est)
    }

    fn estimates(&self) -> &Estimates {
        &self.est
    }

    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        let pi = self.structure.param(i)?;
        let pj = self.structure.param(j)?;
        if pi.coefficient != pj.coefficient || pi.term == Term::Bias || pj.term == Term::Bias {
            return None;
        }
        let sol = &self.solutions[pi.coefficient.index()];
        if !sol.identified {
            return None;
        }
        let first = self.structure.first_index(pi.coefficient);
        let has_bias =
            self.structure.contains(crate::vocabulary::Param::new(pi.coefficient, Term::Bias));
        let k = |idx: usize| idx - first - usize::from(has_bias);
        Some(sol.cov[k(i)][k(j)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::AircraftConstants;

    fn constants() -> AircraftConstants {
        AircraftConstants {
            mass_kg: 1000.0,
            S_m2: 10.0,
            cbar_m: Some(1.5),
            b_m: Some(10.0),
            Ixx_kgm2: Some(1000.0),
            Iyy_kgm2: Some(2000.0),
            Izz_kgm2: Some(2800.0),
            Ixz_kgm2: Some(0.0),
            ..Default::default()
        }
    }

    /// A sample whose measured Cm follows `cm(α, q̂, δe)` exactly (p = r = 0).
    fn pitch_sample(t: f64, alpha: f64, q: f64, de: f64, cm: f64) -> AirDataSample {
        let qbar = 3000.0;
        AirDataSample {
            t_s: t,
            vt_mps: 60.0,
            alpha_rad: alpha,
            qbar_pa: qbar,
            p_rad_s: Some(0.0),
            q_rad_s: Some(q),
            r_rad_s: Some(0.0),
            qdot_rad_s2: Some(cm * qbar * 10.0 * 1.5 / 2000.0),
            de_rad: Some(de),
            constants: constants(),
            ..Default::default()
        }
    }

    /// The recursive transform equals a directly summed DFT of the same samples.
    #[test]
    fn analytic_recursive_transform_matches_direct_sum() {
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Alpha]);
        let mut ftr = Ftr::new(st, FtrConfig::default()).unwrap();
        let dt = 0.02;
        let alpha = |t: f64| 0.05 + 0.01 * (2.0 * t).sin() + 0.003 * (7.0 * t).cos();
        let n = 2500; // > 1,000: crosses an exact phasor refresh
        for i in 0..n {
            let t = 0.3 + i as f64 * dt;
            ftr.update(&pitch_sample(t, alpha(t), 0.0, 0.0, -0.5 * alpha(t))).unwrap();
        }
        let a0 = alpha(0.3);
        for m in [0usize, 7, 35] {
            let w = ftr.frequencies_rad_s()[m];
            let (mut re, mut im) = (0.0, 0.0);
            for i in 1..n {
                let t = 0.3 + i as f64 * dt;
                re += (alpha(t) - a0) * (w * t).cos() * dt;
                im -= (alpha(t) - a0) * (w * t).sin() * dt;
            }
            let got = ftr.x.terms[Term::Alpha.index()][m];
            assert!(
                (got.0 - re).abs() < 1e-10 && (got.1 - im).abs() < 1e-10,
                "m={m} {got:?} {re} {im}"
            );
        }
    }

    /// An exactly linear pitching moment with a bias and a trim offset: the slopes are recovered
    /// to rounding, the bias is not identified (drops out), σ is tiny.
    #[test]
    fn analytic_recovers_slopes_and_drops_the_bias() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let cfg = FtrConfig { solve_interval_s: 0.5, ..Default::default() };
        let mut ftr = Ftr::new(st, cfg).unwrap();
        let (cm0, cma, cmq, cmde) = (0.04, -0.8, -12.0, -1.1);
        for i in 0..1500 {
            let t = i as f64 * 0.02;
            let alpha = 0.06 + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin();
            let q = 0.1 * (2.1 * t).cos() + 0.05 * (6.0 * t).sin();
            let de = -0.02 + 0.03 * (0.9 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
            let cm = cm0 + cma * alpha + cmq * q * 1.5 / 120.0 + cmde * de;
            ftr.update(&pitch_sample(t, alpha, q, de, cm)).unwrap();
        }
        let e = ftr.estimates();
        assert!(e.value(0).is_none(), "bias must drop out");
        for (i, want) in [(1, cma), (2, cmq), (3, cmde)] {
            let got = e.value(i).unwrap();
            assert!((got - want).abs() < 1e-7 * want.abs(), "{i}: {got} vs {want}");
            assert!(e.sigma(i).unwrap() < 1e-6 * want.abs());
        }
        assert!(ftr.covariance(1, 2).is_some() && ftr.covariance(0, 1).is_none());
    }

    /// Two manoeuvres 30 s apart whose trim and bias differ (Cm_0 0.04 then 0.06, as a trim or
    /// sensor-bias change between manoeuvres): with `new_manoeuvre` at the gap each manoeuvre's
    /// signals are referenced to its own first sample and the gap interval carries no weight,
    /// so the summed transforms relate exactly and the slopes are recovered to rounding;
    /// without it the bias step, weighted by the 30 s interval, either biases them by more than
    /// 1 % or (with the offset column) leaves them not identified.
    #[test]
    fn analytic_new_manoeuvre_restarts_the_trim_reference() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let (cma, cmq, cmde) = (-0.8, -12.0, -1.1);
        let run = |restart: bool| {
            let mut ftr = Ftr::new(st, FtrConfig::default()).unwrap();
            for (k, (t_start, cm0, trim)) in
                [(0.0, 0.04, 0.06), (50.0, 0.06, 0.09)].into_iter().enumerate()
            {
                if k == 1 && restart {
                    ftr.new_manoeuvre();
                }
                for i in 0..1000 {
                    let t = t_start + i as f64 * 0.02;
                    let alpha = trim + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin();
                    let q = 0.1 * (2.1 * t).cos() + 0.05 * (6.0 * t).sin();
                    let de = -0.02 + 0.03 * (0.9 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
                    let cm = cm0 + cma * alpha + cmq * q * 1.5 / 120.0 + cmde * de;
                    ftr.update(&pitch_sample(t, alpha, q, de, cm)).unwrap();
                }
            }
            [1, 2, 3].map(|i| ftr.estimates().value(i).unwrap_or(f64::NAN))
        };
        let with = run(true);
        let without = run(false);
        let want = [cma, cmq, cmde];
        for i in 0..3 {
            assert!((with[i] - want[i]).abs() < 1e-7 * want[i].abs(), "{i}: {}", with[i]);
        }
        // Without the restart the step is either refused by the identifiability test (NaN: not
        // identified) or biases a slope by more than 1 %.
        assert!(
            (0..3).any(|i| without[i].is_nan() || (without[i] - want[i]).abs() > 0.01 * want[i].abs()),
            "{without:?}"
        );
    }

    #[test]
    fn rejects_bad_configuration_and_backward_time() {
        let st = ModelStructure::longitudinal();
        assert!(Ftr::new(st, FtrConfig { f_step_hz: 0.0, ..Default::default() }).is_err());
        assert!(Ftr::new(st, FtrConfig { f_step_hz: 0.001, ..Default::default() }).is_err());
        assert!(Ftr::new(st, FtrConfig { forgetting: 1.5, ..Default::default() }).is_err());
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Alpha]);
        let mut ftr = Ftr::new(st, FtrConfig::default()).unwrap();
        ftr.update(&pitch_sample(1.0, 0.1, 0.0, 0.0, 0.0)).unwrap();
        let before = ftr.x.terms[1][0];
        assert!(ftr.update(&pitch_sample(0.5, 0.2, 0.0, 0.0, 0.0)).is_err());
        assert_eq!(ftr.x.terms[1][0], before);
    }
    /// Monte Carlo of FTR on an exactly linear pitching moment plus equation-error noise
    /// `v` (AR(1) with coefficient `a`, stationary σ 0.01), fixed multisine regressors,
    /// 30 s at 50 Hz: (scatter of Cm_α, mean reported σ, coverage of ±2σ), over `runs` seeds.
    fn noisy_campaign(runs: u64, a: f64, forgetting: f64) -> (f64, f64, f64) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let cfg = FtrConfig { forgetting, ..Default::default() };
        let (cm0, cma, cmq, cmde) = (0.04, -0.8, -12.0, -1.1);
        let innov = 0.01 * (1.0 - a * a).sqrt();
        let mut est = std::vec::Vec::new();
        let (mut sig, mut covered) = (0.0, 0);
        for seed in 0..runs {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
            let n01 = Normal::new(0.0, 1.0).unwrap();
            let mut ftr = Ftr::new(st, cfg).unwrap();
            let mut v = 0.01 * n01.sample(&mut rng);
            for i in 0..1500 {
                let t = i as f64 * 0.02;
                let alpha = 0.06 + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin();
                let q = 0.1 * (2.1 * t).cos() + 0.05 * (6.0 * t).sin() + 0.03 * (8.3 * t).sin();
                let de = -0.02 + 0.03 * (0.9 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
                v = a * v + innov * n01.sample(&mut rng);
                let cm = cm0 + cma * alpha + cmq * q * 1.5 / 120.0 + cmde * de + v;
                ftr.update(&pitch_sample(t, alpha, q, de, cm)).unwrap();
            }
            let e = ftr.estimates();
            let (val, s) = (e.value(1).unwrap(), e.sigma(1).unwrap());
            est.push(val);
            sig += s;
            covered += usize::from((val - cma).abs() <= 2.0 * s);
        }
        let m = est.iter().sum::<f64>() / runs as f64;
        let var = est.iter().map(|e| (e - m) * (e - m)).sum::<f64>() / (runs - 1) as f64;
        (var.sqrt(), sig / runs as f64, covered as f64 / runs as f64)
    }

    /// The memory of the estimate is `Δt/(1 − λ²)`, not RLS's `Δt/(1 − λ)` (module doc,
    /// "Memory"): the normal equations are products of two transforms, each weighting sample
    /// `i` by `λ^{n−i}`. Cm_α steps from −0.8 to −0.4 at 10 s on a white α regressor (no noise
    /// in Cm); `k = 200` samples after the step, the mean share of the old value left in the
    /// estimate over 40 records must be `λ^{2k}` = 0.135 (within 25 %), not `λ^k` = 0.37.
    #[test]
    fn analytic_memory_is_the_squared_forgetting() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Alpha]);
        let lambda: f64 = 0.995;
        let cfg = FtrConfig { forgetting: lambda, solve_interval_s: 0.0, ..Default::default() };
        let (old, new, n_step, k) = (-0.8, -0.4, 1000usize, 200usize);
        let mut share = 0.0;
        let runs = 40;
        for seed in 0..runs {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
            let n01 = Normal::new(0.0, 1.0).unwrap();
            let mut ftr = Ftr::new(st, cfg).unwrap();
            for i in 0..=n_step + k {
                let t = i as f64 * 0.01;
                let alpha = 0.06 + 0.02 * n01.sample(&mut rng);
                let cma = if i < n_step { old } else { new };
                ftr.update(&pitch_sample(t, alpha, 0.0, 0.0, cma * alpha)).unwrap();
            }
            share += (ftr.estimates().value(0).unwrap() - new) / (old - new);
        }
        share /= runs as f64;
        let want = lambda.powi(2 * k as i32);
        std::println!("old share {share:.4}, λ^2k {want:.4}, λ^k {:.4}", lambda.powi(k as i32));
        assert!((share / want - 1.0).abs() < 0.25, "share {share} vs λ^2k {want}");
    }

    /// The reported σ match the Monte Carlo scatter (within 20 %, ≥ 90 % coverage) for white
    /// noise without forgetting, and for strongly coloured noise (AR(1), a = 0.95: a
    /// correlation time of 0.4 s) with a 4-s memory, where neighbouring frequencies of the grid
    /// are far from independent.
    #[test]
    fn sigma_matches_monte_carlo_scatter_white_and_coloured() {
        for (a, lambda) in [(0.0, 1.0), (0.95, 0.995)] {
            let (scatter, sigma, coverage) = noisy_campaign(200, a, lambda);
            std::println!("a {a} λ {lambda}: scatter {scatter:.3e} σ {sigma:.3e} cov {coverage}");
            assert!((sigma / scatter - 1.0).abs() < 0.2, "a {a}: σ {sigma} vs scatter {scatter}");
            assert!(coverage >= 0.9, "a {a}: coverage {coverage}");
        }
    }

    /// Weights of a 21-point parabolic window (the shape of the matched smoother of
    /// `aeroident_signals::differentiate`; the same as in `rls::tests`), normalised to unit
    /// output variance for unit white input.
    fn smoother() -> [f64; 21] {
        let mut w = [0.0; 21];
        for (k, wk) in w.iter_mut().enumerate() {
            let c = k as f64 - 10.0;
            *wk = 1.0 - (c / 11.0) * (c / 11.0);
        }
        let norm = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        w.map(|x| x / norm)
    }

    /// Monte Carlo of FTR with λ = 0.995 at 100 Hz (transforms over 2 s; the estimate's memory
    /// `Δt/(1 − λ²)` is 1 s, module doc "Memory and grid") on an
    /// exactly linear pitching moment plus equation-error noise (0.01 × unit white noise, or
    /// through [`smoother`]), three multisine regressors and the offset, `n` samples:
    /// `[(scatter, mean σ, coverage of ±2σ); 3]` for Cm_α, Cm_q, Cm_δe over `runs` seeds.
    fn short_memory_campaign(runs: u64, smoothed: bool, n: usize) -> [(f64, f64, f64); 3] {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let cfg = FtrConfig { forgetting: 0.995, ..Default::default() };
        let truth = [-0.8, -12.0, -1.1];
        let w: std::vec::Vec<f64> = if smoothed { smoother().to_vec() } else { std::vec![1.0] };
        let mut est = [(); 3].map(|_| std::vec::Vec::new());
        let mut sig = [0.0; 3];
        let mut covered = [0usize; 3];
        for seed in 0..runs {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(1000 + seed);
            let n01 = Normal::new(0.0, 1.0).unwrap();
            let mut ftr = Ftr::new(st, cfg).unwrap();
            let mut buf: std::vec::Vec<f64> = w.iter().map(|_| n01.sample(&mut rng)).collect();
            for i in 0..n {
                let t = i as f64 * 0.01;
                buf.rotate_left(1);
                *buf.last_mut().unwrap() = n01.sample(&mut rng);
                let v: f64 = 0.01 * buf.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>();
                let alpha = 0.06 + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin();
                let q = 0.1 * (2.1 * t).cos() + 0.05 * (6.0 * t).sin() + 0.03 * (8.3 * t).sin();
                let de = -0.02 + 0.03 * (0.9 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
                let cm = 0.04 + truth[0] * alpha + truth[1] * q * 1.5 / 120.0 + truth[2] * de + v;
                ftr.update(&pitch_sample(t, alpha, q, de, cm)).unwrap();
            }
            let e = ftr.estimates();
            for k in 0..3 {
                let (val, s) = (e.value(k + 1).unwrap(), e.sigma(k + 1).unwrap());
                est[k].push(val);
                sig[k] += s;
                covered[k] += usize::from((val - truth[k]).abs() <= 2.0 * s);
            }
        }
        let r = runs as f64;
        [0, 1, 2].map(|k| {
            let m = est[k].iter().sum::<f64>() / r;
            let var = est[k].iter().map(|e| (e - m) * (e - m)).sum::<f64>() / (r - 1.0);
            (var.sqrt(), sig[k] / r, covered[k] as f64 / r)
        })
    }

    /// With λ = 0.995 (transforms over 2 s) the 36 grid frequencies carry only a few independent noise
    /// observations, and the fit removes a large share of the noise exactly where the
    /// regressors have power, so the raw residual periodogram understates the noise there
    /// (σ / scatter was 0.77–0.88 here). With the fitted-share correction of the residual
    /// spectrum (module doc) σ matches the scatter of 200 fits within [0.9, 1.15] for white
    /// and for smoothed noise, on records of 30 s and 31 s (different noise, different
    /// solve times).
    #[test]
    fn short_memory_sigma_matches_scatter_white_and_smoothed() {
        for (smoothed, n) in [(false, 3000), (true, 3000), (false, 3100), (true, 3100)] {
            let res = short_memory_campaign(200, smoothed, n);
            for (k, (scatter, sigma, coverage)) in res.into_iter().enumerate() {
                let ratio = sigma / scatter;
                std::println!(
                    "smoothed {smoothed} n {n} term {k}: scatter {scatter:.3e} σ {sigma:.3e} σ/scatter {ratio:.3} cov {coverage}"
                );
                assert!((0.9..=1.15).contains(&ratio), "smoothed {smoothed} n {n} {k}: {ratio}");
                assert!(coverage >= 0.9, "smoothed {smoothed} n {n} {k}: coverage {coverage}");
            }
        }
    }

    /// The window algebra of the σ is exact: for white noise of unit variance per sample, the
    /// sandwich `A⁻¹ M A⁻¹` built from the recursive `W(ω_f ∓ ω_g)` with a flat level equals the
    /// covariance `Σ_i g_i g_iᵀ` of the estimate computed directly from its time-domain
    /// weights `g_i = A⁻¹ Re(X̃ₐ† e_i)`, `e_i(ω_f) = λ^{n−i} Δt e^{−jω_f t_i}` (θ̂ is linear in
    /// the noise), with λ = 0.995 at 100 Hz. So the σ shortfall of the raw periodogram is the level,
    /// not the window's cross terms.
    #[test]
    fn analytic_white_noise_sandwich_equals_exact_covariance() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let lambda = 0.995;
        let mut ftr = Ftr::new(st, FtrConfig { forgetting: lambda, ..Default::default() }).unwrap();
        let (n, dt) = (3000usize, 0.01);
        for i in 0..n {
            let t = i as f64 * dt;
            let alpha = 0.06 + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin();
            let q = 0.1 * (2.1 * t).cos() + 0.05 * (6.0 * t).sin() + 0.03 * (8.3 * t).sin();
            let de = -0.02 + 0.03 * (0.9 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
            ftr.update(&pitch_sample(t, alpha, q, de, -0.8 * alpha - 1.1 * de)).unwrap();
        }
        let mut terms = [Term::Bias; N_TERMS];
        terms[..3].copy_from_slice(&[Term::Alpha, Term::Q, Term::De]);
        let (p, q, m) = (3, 4, ftr.n_freq);
        let mut a = [[0.0; N_TERMS]; N_TERMS];
        for i in 0..q {
            for j in 0..q {
                let (xi, xj) = (ftr.column(&terms, p, i), ftr.column(&terms, p, j));
                a[i][j] = (0..m).map(|f| xi[f].0 * xj[f].0 + xi[f].1 * xj[f].1).sum();
            }
        }
        let mut l = [[0.0; N_TERMS]; N_TERMS];
        assert!(cholesky(&a, q, &mut l));
        let mut inv = [[0.0; N_TERMS]; N_TERMS];
        cholesky_inverse(&l, q, &mut inv);
        let mid = sigma_job(&ftr, &terms, p, &inv).flat_moment();
        let model = sigma::sandwich_product(&inv, &mid, q);
        let mut exact = [[0.0; 4]; 4];
        for i in 1..n {
            let (t, wt) = (i as f64 * dt, lambda.powi((n - 1 - i) as i32) * dt);
            let mut u = [0.0; 4];
            for (k, uk) in u.iter_mut().enumerate() {
                let x = ftr.column(&terms, p, k);
                // Re(x̄ e) with e = wt (cos ωt − j sin ωt)
                *uk = (0..m)
                    .map(|f| {
                        let w = ftr.omega[f] * t;
                        wt * (x[f].0 * w.cos() - x[f].1 * w.sin())
                    })
                    .sum();
            }
            let g: [f64; 4] = core::array::from_fn(|r| (0..q).map(|c| inv[r][c] * u[c]).sum());
            for r in 0..4 {
                for c in 0..4 {
                    exact[r][c] += g[r] * g[c];
                }
            }
        }
        for r in 0..p {
            for c in 0..p {
                let scale = (exact[r][r] * exact[c][c]).sqrt();
                assert!(
                    (model[r][c] - exact[r][c]).abs() < 1e-6 * scale,
                    "({r},{c}): {} vs {}",
                    model[r][c],
                    exact[r][c]
                );
            }
        }
    }

    /// A σ job over `ftr`'s current columns of `terms` (`p` of them, then the offset), with
    /// `inv` as `A⁻¹` and a unit residual.
    fn sigma_job(ftr: &Ftr, terms: &[Term; N_TERMS], p: usize, inv: &Square<N_TERMS>) -> SigmaJob {
        let cols = core::array::from_fn(|i| ftr.column(terms, p, i.min(p)));
        let resid = core::array::from_fn(|f| (0.1 + 0.01 * f as f64, -0.05));
        let start = SigmaStart {
            m: ftr.n_freq,
            p,
            cols,
            w_diff: &ftr.w_diff,
            w_sum: &ftr.w_sum,
            inv,
            resid: &resid,
            rss: 2.0,
        };
        let mut job = SigmaJob::idle();
        assert!(job.start(0, &[0.0; N_TERMS], &start));
        job
    }

    /// The σ spread over updates is the σ computed at once, bit for bit, however the work is
    /// split (budgets of 1, 97 and 5,000 inner-sum terms per step against all at once), and a
    /// budget of 1 takes one step per call: `(1 + passes) · (m + q)` row and column steps
    /// and one level correction per pass.
    #[test]
    fn the_sigma_does_not_depend_on_the_split() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let mut ftr = Ftr::new(st, FtrConfig { forgetting: 0.995, ..Default::default() }).unwrap();
        for i in 0..1500 {
            let t = i as f64 * 0.01;
            let alpha = 0.06 + 0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin();
            let q = 0.1 * (2.1 * t).cos() + 0.05 * (6.0 * t).sin();
            let de = -0.02 + 0.03 * (0.9 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
            ftr.update(&pitch_sample(t, alpha, q, de, -0.8 * alpha - 1.1 * de)).unwrap();
        }
        let mut terms = [Term::Bias; N_TERMS];
        terms[..3].copy_from_slice(&[Term::Alpha, Term::Q, Term::De]);
        let (p, m) = (3, ftr.n_freq);
        let mut inv = [[0.0; N_TERMS]; N_TERMS];
        for (i, row) in inv.iter_mut().enumerate().take(p + 1) {
            row[i] = 1.0 / (1.0 + i as f64);
        }
        let whole = sigma_job(&ftr, &terms, p, &inv).advance(usize::MAX).unwrap().unwrap();
        for budget in [1, 97, 5000] {
            let mut job = sigma_job(&ftr, &terms, p, &inv);
            let mut calls = 1;
            let split = loop {
                match job.advance(budget) {
                    Some(cov) => break cov.unwrap(),
                    None => calls += 1,
                }
            };
            assert_eq!(split, whole, "budget {budget}");
            if budget == 1 {
                let steps = (1 + FITTED_SHARE_ITERATIONS) * (m + p + 1) + FITTED_SHARE_ITERATIONS;
                assert_eq!(calls, steps + 1, "one step per call, and the last that finishes");
            }
        }
    }
}
