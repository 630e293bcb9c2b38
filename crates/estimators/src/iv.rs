//! Recursive instrumental variables (`rls-iv`): equation error over any [`ModelStructure`]
//! whose estimates are not pulled towards zero by noise on the regressors.
//!
//! **Why.** Least squares on measured regressors `φ = φ° + n` (α, β, p̂, q̂, r̂ … from noisy
//! sensors) is biased: for one regressor `θ_LS → θ σ²_φ°/(σ²_φ° + σ²_n)` (the attenuation of
//! errors in variables; Klein & Morelli, *Aircraft System Identification*, AIAA 2006, §5.1 on
//! equation error with noisy regressors; Söderström & Stoica, *System Identification*, 1989,
//! §8.1). Instrumental variables replace the normal equations `Σ φ φᵀ θ = Σ φ y` by
//! `Σ z φᵀ θ = Σ z y`, with instruments `z` correlated with the true regressors and not with
//! the residual `v = y − φᵀθ` (which holds `−nᵀθ`): then `θ̂ → θ` (Söderström & Stoica 1989,
//! ch. 8, consistency conditions `E[z φᵀ]` nonsingular, `E[z v] = 0`; Ljung, *System
//! Identification*, 2nd ed., 1999, §7.6).
//!
//! **Instruments.** Each state regressor's instrument is its own value [`IvConfig::delay_samples`]
//! samples earlier, `z_k = φ_{k−d}` (Ljung 1999 §7.6, delayed regressors; Söderström & Stoica
//! 1989 §8.2): sensor noise `d` samples apart is independent, the motion is not. The delay must
//! exceed the noise's correlation time, which in a replay includes the differentiator's span
//! (`q̇` at sample `k` is made of `q` at `k ± (N−1)/2`, so `q̂_{k−d}` must lie outside it).
//! The constant and the control surfaces ([`is_own_instrument`]) are their own instruments:
//! they carry no sensor noise of the states. (A control law that feeds the noisy sensors back
//! at once would put that noise into the surfaces; then they too should be delayed. The
//! records here are open loop or flown by a pilot.)
//!
//! **Recursion** (Ljung 1999 §11.3; Söderström & Stoica 1989 ch. 9), with forgetting `λ`:
//!
//! ```text
//! e_n = y_n − φ_nᵀ θ_{n−1}
//! K_n = P_{n−1} z_n / (λ + φ_nᵀ P_{n−1} z_n)
//! θ_n = θ_{n−1} + K_n e_n
//! P_n = (P_{n−1} − K_n φ_nᵀ P_{n−1}) / λ          (P_n = (Σ λ^{n−k} z_k φ_kᵀ)⁻¹, not symmetric)
//! ```
//!
//! **Exact initialisation**, as [`crate::rls`]: `A = Σ λ z φᵀ`, `b = Σ λ z y` are accumulated
//! until the regressors are excited ([`crate::rls::INIT_MIN_SCALED_PIVOT`] on `Σ φφᵀ`), the
//! instruments correlate with them (every pivot of `A` scaled to correlation units, i.e. by
//! `√(Σz_i²) √(Σφ_j²)`, at least [`IV_MIN_SCALED_PIVOT`]) and `init_samples` samples were seen;
//! then `θ = A⁻¹b`, `P = A⁻¹`, and from there the recursion equals the batch IV solution to
//! rounding. Until then, and for the first `d` samples (no instrument yet), the parameters are
//! **not identified** (`null`).
//!
//! **σ.** `θ̂ − θ = P Σ λ^{n−i} z_i v_i`, so (Söderström & Stoica 1989 §8.2, the IV covariance
//! with correlated residuals)
//!
//! ```text
//! cov θ̂ = σ̂² P M Pᵀ,   M = Σ_i Σ_j λ^{2n−i−j} ρ(i−j) z_i z_jᵀ
//! ```
//!
//! which for white residuals and `λ = 1` is `σ̂² (ZᵀΦ)⁻¹ ZᵀZ (ΦᵀZ)⁻¹`. `M` and the truncation of
//! the residual autocorrelation `ρ̂` are [`crate::coloured`]'s recursive form with the instrument
//! rows in place of the regressors; `σ̂² = RSS/(N_eff − p)`, the λ-weighted residual sum of
//! squares at the current `θ̂` (exact, from running sums). The residual `v` holds the regressor
//! noise `−nᵀθ`, so `σ̂²` and `ρ̂` include it. Should the truncated sum give a non-positive
//! variance, the white `σ̂² P (Σ λ² z zᵀ) Pᵀ` is reported.
//!
//! **Limits.**
//! - Only noise is removed. A time skew between channels (a lagging α vane), a bias or a scale
//!   error is a model error the instruments share: it stays (`aeroident compat` corrects it).
//! - The price is variance: the instruments correlate imperfectly with the regressors, so σ is
//!   larger than least squares' (how much depends on `d` against the motion's bandwidth).
//! - The finite-memory corrections of [`crate::coloured`] (fitted share, lag leverage, the
//!   degrees of freedom `N_eff − tr(PM)`) are derived for least squares and not applied: with
//!   a short memory (`λ` well below 1) σ̂² and ρ̂ understate the noise as they did for RLS
//!   before those corrections.
//! - A new manoeuvre (a gap) keeps the delay line: rows before the gap remain valid
//!   instruments (their noise is as independent of the later residuals as any).

// Index loops follow the recursion's equations line by line.
#![allow(clippy::needless_range_loop)]

use crate::EstimatorError;
use crate::coloured::ColouredCovariance;
use crate::estimator::{Estimates, Estimator, EventLog};
use crate::linalg::{Square, well_conditioned};
use crate::rls::{
    CoefficientFit, INIT_MIN_SCALED_PIVOT, Regression, covariance, update_fits, validated,
};
use crate::sample::AirDataSample;
use crate::vocabulary::{Coefficient, ModelStructure, N_TERMS, Term};

/// Longest instrument delay, samples (the delay line's capacity).
pub const MAX_INSTRUMENT_DELAY: usize = 64;

/// Smallest admissible pivot of the instrument–regressor matrix `Σ z φᵀ` scaled to correlation
/// units at initialisation. With `z = φ` the scaled matrix is the regressors' correlation
/// matrix, whose elimination pivots are the squared Cholesky pivots that least squares tests
/// against [`crate::rls::INIT_MIN_SCALED_PIVOT`]: the same threshold, so both start under the
/// same excitation (a constant-like term such as `V/V0` has pivots near `(σ_V/V)²`).
pub const IV_MIN_SCALED_PIVOT: f64 = INIT_MIN_SCALED_PIVOT;

/// Configuration of [`RlsIv`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IvConfig {
    /// Forgetting factor `λ ∈ (0, 1]`; 1: no forgetting. Memory ≈ `1/(1−λ)` samples.
    pub forgetting: f64,
    /// Minimum number of instrumented samples before the exact initialisation.
    pub init_samples: usize,
    /// Delay `d` of the state regressors' instruments, samples, in `1..=`[`MAX_INSTRUMENT_DELAY`]:
    /// beyond the correlation time of the regressor noise and of the differentiator's span.
    pub delay_samples: usize,
}

impl Default for IvConfig {
    fn default() -> Self {
        Self { forgetting: 1.0, init_samples: 0, delay_samples: DEFAULT_INSTRUMENT_DELAY }
    }
}

/// Default instrument delay, samples.
pub const DEFAULT_INSTRUMENT_DELAY: usize = 5;

/// Whether term `t` is its own instrument: the constant and the control surfaces, which carry
/// no noise of the measured states. Every other term (α, β, the rates, V, products) is
/// instrumented by its delayed value.
pub fn is_own_instrument(t: Term) -> bool {
    matches!(t, Term::Bias | Term::De | Term::Da | Term::Dr)
}

/// The last `delay` regressor rows, a ring: the slot at `head` holds the row `delay` samples
/// back once the line is full.
#[derive(Debug, Clone, Copy)]
struct DelayLine {
    rows: [[f64; N_TERMS]; MAX_INSTRUMENT_DELAY],
    head: usize,
    filled: usize,
    delay: usize,
}

impl DelayLine {
    fn new(delay: usize) -> Self {
        Self { rows: [[0.0; N_TERMS]; MAX_INSTRUMENT_DELAY], head: 0, filled: 0, delay }
    }

    /// The row `delay` samples before the next one, once there is one.
    fn delayed(&self) -> Option<&[f64; N_TERMS]> {
        (self.filled >= self.delay).then(|| &self.rows[self.head])
    }

    fn push(&mut self, phi: &[f64; N_TERMS]) {
        self.rows[self.head] = *phi;
        self.head = (self.head + 1) % self.delay;
        self.filled += 1;
    }
}

/// One coefficient's instrumental-variable fit.
#[derive(Debug, Clone, Copy)]
struct IvFit {
    reg: Regression,
    own: [bool; N_TERMS],
    line: DelayLine,
    /// `Σ λ z φᵀ`, `Σ λ z y` (the IV normal equations, for the exact initialisation).
    zphi: Square<N_TERMS>,
    zy: [f64; N_TERMS],
    /// `diag Σ λ z zᵀ` (scaling of the initialisation's pivot test).
    zz: [f64; N_TERMS],
    /// `Σ λ φφᵀ`, `Σ λ φ y`, `Σ λ y²`: the residual sum of squares at any `θ`.
    phiphi: Square<N_TERMS>,
    phiy: [f64; N_TERMS],
    yy: f64,
    /// `Σ λ² z zᵀ`: `M` of white residuals (the fallback covariance).
    white: Square<N_TERMS>,
    p: Square<N_TERMS>,
    theta: [f64; N_TERMS],
    initialised: bool,
    count: usize,
    n_eff: f64,
    coloured: ColouredCovariance<N_TERMS>,
}

/// `P = 0` given to [`ColouredCovariance::add`]: its fitted-share and lag-leverage corrections
/// are least squares' (module doc, "Limits"), so the instrumental fit turns them off.
const NO_LEVERAGE: Square<N_TERMS> = [[0.0; N_TERMS]; N_TERMS];

impl IvFit {
    fn new(structure: &ModelStructure, c: Coefficient, delay: usize) -> Self {
        let reg = Regression::new(structure, c);
        let mut own = [false; N_TERMS];
        for k in 0..reg.n {
            own[k] = is_own_instrument(reg.terms[k]);
        }
        let zero = [[0.0; N_TERMS]; N_TERMS];
        Self {
            reg,
            own,
            line: DelayLine::new(delay),
            zphi: zero,
            zy: [0.0; N_TERMS],
            zz: [0.0; N_TERMS],
            phiphi: zero,
            phiy: [0.0; N_TERMS],
            yy: 0.0,
            white: zero,
            p: zero,
            theta: [0.0; N_TERMS],
            initialised: false,
            count: 0,
            n_eff: 0.0,
            coloured: ColouredCovariance::new(reg.n),
        }
    }

    /// The instrument row of `phi` given the row `delayed` samples back.
    fn instruments(&self, phi: &[f64; N_TERMS], delayed: &[f64; N_TERMS]) -> [f64; N_TERMS] {
        let mut z = [0.0; N_TERMS];
        for k in 0..self.reg.n {
            z[k] = if self.own[k] { phi[k] } else { delayed[k] };
        }
        z
    }

    /// The running sums of one row with forgetting `λ`.
    fn accumulate(&mut self, z: &[f64; N_TERMS], phi: &[f64; N_TERMS], y: f64, lambda: f64) {
        let (n, l2) = (self.reg.n, lambda * lambda);
        for i in 0..n {
            for j in 0..n {
                self.zphi[i][j] = lambda * self.zphi[i][j] + z[i] * phi[j];
                self.phiphi[i][j] = lambda * self.phiphi[i][j] + phi[i] * phi[j];
                self.white[i][j] = l2 * self.white[i][j] + z[i] * z[j];
            }
            self.zy[i] = lambda * self.zy[i] + z[i] * y;
            self.zz[i] = lambda * self.zz[i] + z[i] * z[i];
            self.phiy[i] = lambda * self.phiy[i] + phi[i] * y;
        }
        self.yy = lambda * self.yy + y * y;
        self.n_eff = lambda * self.n_eff + 1.0;
        self.count += 1;
    }

    /// The exact initialisation once the regressors are excited and the instruments correlate
    /// with them (module doc).
    fn try_initialise(&mut self, init_samples: usize) {
        let n = self.reg.n;
        if self.count < init_samples.max(n)
            || !well_conditioned(&self.phiphi, n, self.n_eff, INIT_MIN_SCALED_PIVOT)
        {
            return;
        }
        let Some(p) = scaled_inverse(&self.zphi, &self.zz, &self.phiphi, n) else { return };
        let mut theta = [0.0; N_TERMS];
        for i in 0..n {
            theta[i] = (0..n).map(|j| p[i][j] * self.zy[j]).sum();
        }
        if theta[..n].iter().all(|v| v.is_finite()) {
            self.theta = theta;
            self.p = p;
            self.initialised = true;
        }
    }

    /// The recursion (module doc); returns the a-posteriori residual `y − φᵀθ_n = e λ/denom`.
    fn step(
        &mut self,
        z: &[f64; N_TERMS],
        phi: &[f64; N_TERMS],
        y: f64,
        lambda: f64,
        t_s: f64,
    ) -> Result<f64, EstimatorError> {
        let n = self.reg.n;
        let mut e = y;
        let (mut pz, mut phip) = ([0.0; N_TERMS], [0.0; N_TERMS]);
        for i in 0..n {
            e -= phi[i] * self.theta[i];
            for j in 0..n {
                pz[i] += self.p[i][j] * z[j];
                phip[i] += phi[j] * self.p[j][i];
            }
        }
        let denom = lambda + (0..n).map(|i| phi[i] * pz[i]).sum::<f64>();
        // Not ≥ λ as in least squares: φᵀPz may be negative; only a (near) zero is singular.
        if !(denom.is_finite() && denom.abs() > f64::EPSILON * lambda) {
            return Err(EstimatorError::Numerical { what: "RLS-IV gain denominator", t_s });
        }
        // In place, as least squares' update (`crate::rls`): a non-finite result on finite
        // inputs is an overflow, a divergence the caller reports, so no copy of `P` (26 × 26,
        // most of a sample's memory traffic) is kept to roll back.
        let mut check = 0.0;
        for i in 0..n {
            let ki = pz[i] / denom;
            self.theta[i] += ki * e;
            check += self.theta[i];
            for j in 0..n {
                self.p[i][j] = (self.p[i][j] - ki * phip[j]) / lambda;
                check += self.p[i][j];
            }
        }
        if !check.is_finite() {
            return Err(EstimatorError::Numerical { what: "RLS-IV update", t_s });
        }
        Ok(e * lambda / denom)
    }

    /// λ-weighted residual sum of squares at the current `θ`, from the running sums.
    fn rss(&self) -> f64 {
        let n = self.reg.n;
        let mut r = self.yy;
        for i in 0..n {
            r -= 2.0 * self.theta[i] * self.phiy[i];
            for j in 0..n {
                r += self.theta[i] * self.phiphi[i][j] * self.theta[j];
            }
        }
        r.max(0.0)
    }

    /// `(P W Pᵀ)_ij`, `W = Σ λ² z zᵀ`: the covariance of white residuals over σ².
    fn white_cov(&self, i: usize, j: usize) -> f64 {
        let n = self.reg.n;
        let mut s = 0.0;
        for a in 0..n {
            let row: f64 = (0..n).map(|b| self.white[a][b] * self.p[j][b]).sum();
            s += self.p[i][a] * row;
        }
        s
    }
}

impl CoefficientFit for IvFit {
    fn regression(&self) -> &Regression {
        &self.reg
    }

    /// One update; returns `Err` on a numerical failure: with the state unchanged when the
    /// gain's denominator fails, and after an overflow of the update, a divergence
    /// ([`update_fits`] marks the estimator diverged; nothing is rolled back).
    fn update(
        &mut self,
        phi: &[f64; N_TERMS],
        y: f64,
        lambda: f64,
        init_samples: usize,
        t_s: f64,
    ) -> Result<(), EstimatorError> {
        let Some(delayed) = self.line.delayed() else {
            self.line.push(phi);
            return Ok(());
        };
        let z = self.instruments(phi, delayed);
        if !self.initialised {
            self.accumulate(&z, phi, y, lambda);
            self.coloured.add(&z, None, lambda);
            self.try_initialise(init_samples);
            self.line.push(phi);
            return Ok(());
        }
        let eps = self.step(&z, phi, y, lambda, t_s)?;
        self.accumulate(&z, phi, y, lambda);
        self.coloured.add(&z, Some((eps, &NO_LEVERAGE)), lambda);
        self.line.push(phi);
        Ok(())
    }

    fn initialised(&self) -> bool {
        self.initialised
    }

    fn theta(&self) -> &[f64; N_TERMS] {
        &self.theta
    }

    fn residual_variance(&self) -> Option<f64> {
        let dof = self.n_eff - self.reg.n as f64;
        (self.initialised && dof > 0.0).then(|| self.rss() / dof)
    }

    /// The coloured sandwich `σ̂² P M Pᵀ` where both variances it involves are positive, else
    /// the white `σ̂² P W Pᵀ` (module doc).
    fn cov(&self, s2: f64, i: usize, j: usize) -> f64 {
        let ok = |k: usize| {
            let v = self.coloured.covariance(&self.p, s2, k, k);
            v > 0.0 && v.is_finite()
        };
        if ok(i) && (i == j || ok(j)) {
            self.coloured.covariance(&self.p, s2, i, j)
        } else {
            s2 * self.white_cov(i, j)
        }
    }

    /// `cov(s2, k, k)` with the sandwich formed once instead of twice (the same value).
    fn variance(&self, s2: f64, k: usize) -> f64 {
        let v = self.coloured.covariance(&self.p, s2, k, k);
        if v > 0.0 && v.is_finite() { v } else { s2 * self.white_cov(k, k) }
    }
}

/// `A⁻¹` of the leading `n × n` block of `a = Σ z φᵀ` by Gauss–Jordan elimination with
/// partial pivoting (Golub & Van Loan, *Matrix Computations*, 4th ed., §3.4), on `a` scaled to
/// correlation units `a_ij / √(zz_i φφ_jj)`; `None` if a scaled pivot is below
/// [`IV_MIN_SCALED_PIVOT`] or anything is not finite.
fn scaled_inverse(
    a: &Square<N_TERMS>,
    zz: &[f64; N_TERMS],
    phiphi: &Square<N_TERMS>,
    n: usize,
) -> Option<Square<N_TERMS>> {
    let (mut rs, mut cs) = ([0.0; N_TERMS], [0.0; N_TERMS]);
    for i in 0..n {
        let (r, c) = (libm::sqrt(zz[i]), libm::sqrt(phiphi[i][i]));
        if !(r > 0.0 && c > 0.0 && r.is_finite() && c.is_finite()) {
            return None;
        }
        (rs[i], cs[i]) = (r, c);
    }
    let mut m = [[0.0; N_TERMS]; N_TERMS];
    let mut inv = [[0.0; N_TERMS]; N_TERMS];
    for i in 0..n {
        for j in 0..n {
            m[i][j] = a[i][j] / (rs[i] * cs[j]);
        }
        inv[i][i] = 1.0;
    }
    for col in 0..n {
        let piv = (col..n).max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))?;
        let pivot = m[piv][col].abs();
        if pivot.is_nan() || pivot < IV_MIN_SCALED_PIVOT {
            return None;
        }
        m.swap(col, piv);
        inv.swap(col, piv);
        let d = m[col][col];
        for j in 0..n {
            m[col][j] /= d;
            inv[col][j] /= d;
        }
        for r in (0..n).filter(|&r| r != col) {
            let f = m[r][col];
            for j in 0..n {
                m[r][j] -= f * m[col][j];
                inv[r][j] -= f * inv[col][j];
            }
        }
    }
    // (D_r S D_c)⁻¹ = D_c⁻¹ S⁻¹ D_r⁻¹.
    let mut p = [[0.0; N_TERMS]; N_TERMS];
    for i in 0..n {
        for j in 0..n {
            p[i][j] = inv[i][j] / (cs[i] * rs[j]);
        }
    }
    p[..n].iter().all(|r| r[..n].iter().all(|v| v.is_finite())).then_some(p)
}

/// Recursive instrumental variables on every coefficient of a structure (module doc). No
/// allocation per update.
#[derive(Debug, Clone)]
pub struct RlsIv {
    structure: ModelStructure,
    fits: [Option<IvFit>; 8],
    lambda: f64,
    init_samples: usize,
    est: Estimates,
    /// Always empty: instrumental variables have no change test.
    events: EventLog,
}

impl RlsIv {
    /// A new estimator; nothing is identified until each fit's exact initialisation.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] if `forgetting ∉ (0, 1]`, the delay is outside
    /// `1..=`[`MAX_INSTRUMENT_DELAY`], or the structure is invalid (empty, over capacity, CX/CZ
    /// mixed with CL/CD).
    pub fn new(structure: ModelStructure, config: IvConfig) -> Result<Self, EstimatorError> {
        let structure = validated(structure, config.forgetting)?;
        let d = config.delay_samples;
        if !(1..=MAX_INSTRUMENT_DELAY).contains(&d) {
            return Err(EstimatorError::InvalidConfig {
                field: "instrument_delay",
                value: d as f64,
                reason: "must be 1 to 64 samples",
            });
        }
        // Built in place, as `Rls::new` (docs/reliability.md).
        let mut iv = Self {
            structure,
            fits: [None; 8],
            lambda: config.forgetting,
            init_samples: config.init_samples,
            est: Estimates::new(structure.n_params()),
            events: EventLog::new(),
        };
        for c in structure.coefficients() {
            iv.fits[c.index()] = Some(IvFit::new(&structure, c, d));
        }
        Ok(iv)
    }

    /// Residual variance `σ̂²` of coefficient `c`'s fit, once defined.
    pub fn residual_variance(&self, c: Coefficient) -> Option<f64> {
        self.fits[c.index()].as_ref().and_then(CoefficientFit::residual_variance)
    }

    /// Lag at which coefficient `c`'s coloured-residual sum was last truncated (0: white).
    pub fn coloured_lag(&self, c: Coefficient) -> Option<usize> {
        self.fits[c.index()].as_ref().map(|f| f.coloured.lag())
    }
}

impl Estimator for RlsIv {
    fn method(&self) -> &'static str {
        "rls-iv"
    }

    fn structure(&self) -> &ModelStructure {
        &self.structure
    }

    fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        let (lambda, init) = (self.lambda, self.init_samples);
        let what = "RLS-IV has diverged";
        update_fits(&mut self.fits, &mut self.est, &mut self.events, lambda, init, s, what)?;
        Ok(&self.est)
    }

    fn estimates(&self) -> &Estimates {
        &self.est
    }

    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        covariance(&self.structure, &self.fits, i, j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::AircraftConstants;
    use crate::vocabulary::Term;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// One errors-in-variables record: true regressor `x°` AR(1) (coefficient 0.95, unit
    /// variance), measured `x = x° + n` with white `n` of σ `sn`, `y = θ x° + e` with `e`
    /// AR(1) of coefficient `a` (unit innovations): the fit of `y` on `x` (one term, no
    /// constant) with delay `d`, and the ordinary least-squares slope `Σxy/Σx²` of the same
    /// samples (computed here, independently of the crate).
    fn eiv_fit(seed: u64, n: usize, theta: f64, sn: f64, a: f64, d: usize) -> (IvFit, f64) {
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Alpha]);
        let mut fit = IvFit::new(&st, Coefficient::Cm, d);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let n01 = Normal::new(0.0, 1.0).unwrap();
        let b: f64 = 0.95;
        let mut x0 = n01.sample(&mut rng);
        let mut e = n01.sample(&mut rng) / (1.0 - a * a).sqrt();
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for i in 0..n {
            x0 = b * x0 + (1.0 - b * b).sqrt() * n01.sample(&mut rng);
            e = a * e + n01.sample(&mut rng);
            let x = x0 + sn * n01.sample(&mut rng);
            let y = theta * x0 + e;
            let mut phi = [0.0; N_TERMS];
            phi[0] = x;
            fit.update(&phi, y, 1.0, 0, i as f64).unwrap();
            sxy += x * y;
            sxx += x * x;
        }
        (fit, sxy / sxx)
    }

    /// Errors in variables with one regressor: least squares converges to the attenuated
    /// `θ σ_x²/(σ_x² + σ_n²)` (here `2 / (1 + 0.49) = 1.342`), far outside any σ; the
    /// instrumental fit recovers `θ = 2` within 3 of its σ.
    #[test]
    fn analytic_iv_removes_the_attenuation_of_least_squares() {
        let (theta, sn) = (2.0, 0.7);
        let (fit, ols) = eiv_fit(5, 40_000, theta, sn, 0.0, 1);
        let attenuated = theta / (1.0 + sn * sn);
        let s2 = CoefficientFit::residual_variance(&fit).unwrap();
        let sigma = fit.cov(s2, 0, 0).sqrt();
        std::println!(
            "OLS {ols:.4} (attenuated {attenuated:.4}); IV {:.4} ± {sigma:.4}",
            fit.theta[0]
        );
        assert!((ols - attenuated).abs() < 0.02, "OLS {ols} vs {attenuated}");
        assert!((fit.theta[0] - theta).abs() < 3.0 * sigma, "IV {} ± {sigma}", fit.theta[0]);
        assert!((ols - theta).abs() > 20.0 * sigma, "the bias is not resolved by this record");
    }

    /// Monte Carlo of [`eiv_fit`]: (mean θ̂, scatter of θ̂, mean σ, coverage of ±2σ).
    fn campaign(runs: u64, n: usize, sn: f64, a: f64, d: usize) -> (f64, f64, f64, f64) {
        let mut est = std::vec::Vec::new();
        let (mut sig, mut covered) = (0.0, 0);
        for seed in 0..runs {
            let (f, _) = eiv_fit(100 + seed, n, 2.0, sn, a, d);
            let s2 = CoefficientFit::residual_variance(&f).unwrap();
            let s = f.cov(s2, 0, 0).sqrt();
            sig += s;
            covered += usize::from((f.theta[0] - 2.0).abs() <= 2.0 * s);
            est.push(f.theta[0]);
        }
        let r = runs as f64;
        let m = est.iter().sum::<f64>() / r;
        let var = est.iter().map(|e| (e - m) * (e - m)).sum::<f64>() / (r - 1.0);
        (m, var.sqrt(), sig / r, covered as f64 / r)
    }

    /// The reported σ against the scatter of 300 seeded records, white residuals and AR(1)
    /// residuals (a = 0.7, whose variance factor `(1 + a b')/(1 − a b')` on the instruments'
    /// colour the sandwich must supply): σ within 12 % of the scatter, coverage of ±2σ at least
    /// 90 %, and the mean within a fifth of the scatter of θ = 2.
    #[test]
    fn iv_sigma_matches_the_scatter_of_seeded_repeats() {
        for (a, d) in [(0.0, 1), (0.7, 3)] {
            let (mean, scatter, sigma, coverage) = campaign(300, 3000, 0.7, a, d);
            std::println!(
                "a {a} d {d}: mean {mean:.4} scatter {scatter:.4e} σ {sigma:.4e} coverage {coverage}"
            );
            assert!((sigma / scatter - 1.0).abs() < 0.12, "a {a}: σ {sigma} vs scatter {scatter}");
            assert!(coverage >= 0.9, "a {a}: coverage {coverage}");
            assert!((mean - 2.0).abs() < 0.2 * scatter, "a {a}: mean {mean}");
        }
    }

    /// The recursion after the exact initialisation equals the batch instrumental-variable
    /// solution `(ZᵀΦ)⁻¹ Zᵀy` (nalgebra's LU, on the rows kept here) to rounding, and the white
    /// covariance `P W Pᵀ` equals `(ZᵀΦ)⁻¹ ZᵀZ (ΦᵀZ)⁻¹`; the constant and the surface are their
    /// own instruments, α and q̂ their values 4 samples back.
    #[test]
    fn recursion_equals_the_batch_solution() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let mut fit = IvFit::new(&st, Coefficient::Cm, 4);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        let n01 = Normal::new(0.0, 1.0).unwrap();
        let mut rows: std::vec::Vec<[f64; 4]> = std::vec::Vec::new();
        let mut ys = std::vec::Vec::new();
        for i in 0..600 {
            let t = i as f64 * 0.02;
            let phi4 = [
                1.0,
                0.05 * (1.3 * t).sin() + 0.002 * n01.sample(&mut rng),
                0.01 * (2.1 * t).cos() + 0.001 * n01.sample(&mut rng),
                0.03 * (0.7 * t + 0.4).sin(),
            ];
            let y = 0.02 - 0.8 * phi4[1] - 12.0 * phi4[2] - 1.1 * phi4[3]
                + 0.001 * n01.sample(&mut rng);
            let mut phi = [0.0; N_TERMS];
            phi[..4].copy_from_slice(&phi4);
            fit.update(&phi, y, 1.0, 0, t).unwrap();
            rows.push(phi4);
            ys.push(y);
        }
        assert!(fit.initialised);
        let d = 4;
        let (mut zp, mut zz) = (nalgebra::Matrix4::<f64>::zeros(), nalgebra::Matrix4::zeros());
        let mut zy = nalgebra::Vector4::<f64>::zeros();
        for k in d..rows.len() {
            let phi = nalgebra::Vector4::from(rows[k]);
            let z = nalgebra::Vector4::new(1.0, rows[k - d][1], rows[k - d][2], rows[k][3]);
            zp += z * phi.transpose();
            zz += z * z.transpose();
            zy += z * ys[k];
        }
        let theta = zp.lu().solve(&zy).unwrap();
        let inv = zp.try_inverse().unwrap();
        let white = inv * zz * inv.transpose();
        for i in 0..4 {
            let scale = theta[i].abs().max(1e-3);
            assert!(
                (fit.theta[i] - theta[i]).abs() < 1e-8 * scale,
                "θ{i}: {} vs {}",
                fit.theta[i],
                theta[i]
            );
            for j in 0..4 {
                let w = white[(i, j)];
                let tol = 1e-7 * (white[(i, i)] * white[(j, j)]).sqrt();
                assert!((fit.white_cov(i, j) - w).abs() < tol, "W({i},{j})");
            }
        }
    }

    /// Samples whose measured Cm follows known derivatives exactly: recovered to rounding
    /// through the [`Estimator`] interface; nothing identified during the first `d` samples
    /// (no instrument yet); a sample missing a channel is refused without a change; invalid
    /// configurations are refused.
    #[test]
    fn analytic_recovers_exact_model_and_refuses_bad_input() {
        let st = ModelStructure::empty()
            .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De]);
        let k = AircraftConstants {
            mass_kg: 1000.0,
            S_m2: 10.0,
            cbar_m: Some(1.5),
            Iyy_kgm2: Some(2000.0),
            ..Default::default()
        };
        let want = [0.02, -0.8, -12.0, -1.1];
        let cfg = IvConfig { delay_samples: 6, ..IvConfig::default() };
        let mut iv = RlsIv::new(st, cfg).unwrap();
        let (qbar, v) = (3000.0, 60.0);
        for i in 0..300 {
            let t = i as f64 * 0.02;
            let alpha = 0.05 + 0.02 * (1.3 * t).sin();
            let q = 0.1 * (2.1 * t).cos();
            let de = 0.03 * (0.7 * t + 0.4).sin();
            let cm = want[0] + want[1] * alpha + want[2] * q * 1.5 / (2.0 * v) + want[3] * de;
            let s = AirDataSample {
                t_s: t,
                vt_mps: v,
                alpha_rad: alpha,
                qbar_pa: qbar,
                q_rad_s: Some(q),
                qdot_rad_s2: Some(cm * qbar * 10.0 * 1.5 / 2000.0),
                de_rad: Some(de),
                constants: k,
                ..Default::default()
            };
            let e = iv.update(&s).unwrap();
            if i < 6 {
                assert!(e.value(1).is_none(), "identified without an instrument at {i}");
            }
        }
        assert_eq!(iv.method(), "rls-iv");
        for (i, w) in want.iter().enumerate() {
            let got = iv.estimates().value(i).unwrap();
            assert!((got - w).abs() < 1e-8 * (1.0 + w.abs()), "{i}: {got} vs {w}");
        }
        let before = *iv.estimates();
        let missing = AirDataSample { vt_mps: 50.0, qbar_pa: 1000.0, ..Default::default() };
        assert!(iv.update(&missing).is_err());
        assert_eq!(*iv.estimates(), before);
        for bad in [
            IvConfig { delay_samples: 0, ..cfg },
            IvConfig { delay_samples: MAX_INSTRUMENT_DELAY + 1, ..cfg },
            IvConfig { forgetting: 0.0, ..cfg },
        ] {
            assert!(RlsIv::new(st, bad).is_err(), "{bad:?}");
        }
    }
}
