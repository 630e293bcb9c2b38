//! One coefficient's σ (the parent module's "σ" and "The level"), computed in steps of bounded
//! work so that a solve's cost can be spread over the updates that follow it (the parent
//! module's "Cost per update").
//!
//! Its inputs — the coefficient's columns, the noise windows, `A⁻¹` and the residual — are
//! copied when the coefficient is solved, so the σ is that of the solve's data however many
//! updates it takes. A step is one row `f` of one column `k` of the noise moment (`m` terms of
//! its inner sum), one column's reduction (`q m`), or the level's correction between passes
//! (`2 m q²`); the steps are the arithmetic of one pass through in the same order, so the σ
//! does not depend on how the work is split (`tests::the_sigma_does_not_depend_on_the_split`).

use super::{C64, FITTED_SHARE_ITERATIONS, MAX_FREQUENCIES, SPECTRUM_HALF_WIDTH};
use crate::linalg::Square;
use crate::vocabulary::N_TERMS;

/// A σ in progress (module doc). `active` is false between jobs; the arrays are reused in
/// place (no allocation, no copy of the whole job per update).
#[derive(Debug, Clone, Copy)]
pub(super) struct SigmaJob {
    pub(super) active: bool,
    /// The coefficient (its index) and its estimate, published with the σ.
    pub(super) coefficient: usize,
    pub(super) theta: [f64; N_TERMS],
    m: usize,
    p: usize,
    /// Columns `0..p` the terms' transforms, column `p` the offset's.
    cols: [[C64; MAX_FREQUENCIES]; N_TERMS],
    w_diff: [C64; MAX_FREQUENCIES],
    w_sum: [C64; 2 * MAX_FREQUENCIES],
    inv: Square<N_TERMS>,
    rss: f64,
    w0: f64,
    observed: [f64; MAX_FREQUENCIES],
    level: [f64; MAX_FREQUENCIES],
    v: [[C64; MAX_FREQUENCIES]; N_TERMS],
    mid: Square<N_TERMS>,
    pass: usize,
    k: usize,
    f: usize,
}

/// What [`SigmaJob::start`] copies: the grid size `m`, the `p` terms' columns then the offset's
/// (`cols[..=p]`), the noise windows, `A⁻¹`, the residual transforms and their sum of squares.
pub(super) struct SigmaStart<'a> {
    pub(super) m: usize,
    pub(super) p: usize,
    pub(super) cols: [&'a [C64; MAX_FREQUENCIES]; N_TERMS],
    pub(super) w_diff: &'a [C64; MAX_FREQUENCIES],
    pub(super) w_sum: &'a [C64; 2 * MAX_FREQUENCIES],
    pub(super) inv: &'a Square<N_TERMS>,
    pub(super) resid: &'a [C64; MAX_FREQUENCIES],
    pub(super) rss: f64,
}

impl SigmaJob {
    /// No job.
    pub(super) const fn idle() -> Self {
        Self {
            active: false,
            coefficient: 0,
            theta: [0.0; N_TERMS],
            m: 0,
            p: 0,
            cols: [[(0.0, 0.0); MAX_FREQUENCIES]; N_TERMS],
            w_diff: [(0.0, 0.0); MAX_FREQUENCIES],
            w_sum: [(0.0, 0.0); 2 * MAX_FREQUENCIES],
            inv: [[0.0; N_TERMS]; N_TERMS],
            rss: 0.0,
            w0: 0.0,
            observed: [0.0; MAX_FREQUENCIES],
            level: [0.0; MAX_FREQUENCIES],
            v: [[(0.0, 0.0); MAX_FREQUENCIES]; N_TERMS],
            mid: [[0.0; N_TERMS]; N_TERMS],
            pass: 0,
            k: 0,
            f: 0,
        }
    }

    /// Starts the σ of `coefficient`'s solve `theta` from `s` (copied); `false` (and idle)
    /// when the window has no weight yet (`W(0)` not positive): no σ can be formed.
    pub(super) fn start(
        &mut self,
        coefficient: usize,
        theta: &[f64; N_TERMS],
        s: &SigmaStart,
    ) -> bool {
        let (m, q) = (s.m, s.p + 1);
        let w0 = s.w_diff[0].0;
        self.active = false;
        if w0.is_nan() || w0 <= 0.0 {
            return false;
        }
        for (dst, src) in self.cols.iter_mut().zip(&s.cols).take(q) {
            dst[..m].copy_from_slice(&src[..m]);
        }
        self.w_diff[..m].copy_from_slice(&s.w_diff[..m]);
        self.w_sum[..2 * m - 1].copy_from_slice(&s.w_sum[..2 * m - 1]);
        self.inv = *s.inv;
        (self.coefficient, self.theta, self.m, self.p, self.rss, self.w0) =
            (coefficient, *theta, m, s.p, s.rss, w0);
        // Residual periodogram, Daniell-smoothed over ±SPECTRUM_HALF_WIDTH.
        let mut raw = [0.0; MAX_FREQUENCIES];
        for f in 0..m {
            let r = s.resid[f];
            raw[f] = (r.0 * r.0 + r.1 * r.1) / w0;
        }
        self.observed = daniell(&raw, m);
        self.level = self.observed;
        self.mid = [[0.0; N_TERMS]; N_TERMS];
        (self.pass, self.k, self.f, self.active) = (0, 0, 0, true);
        true
    }

    /// Does at least one step and then steps until `budget` inner-sum terms are spent
    /// (`usize::MAX`: to the end); `Some(σ)` when the job is done (the covariance `κ A⁻¹ M A⁻¹`
    /// of the parent module, or `None` when the residual has no degrees of freedom left or a
    /// variance is not positive), `None` while it goes on.
    pub(super) fn advance(&mut self, budget: usize) -> Option<Option<Square<N_TERMS>>> {
        let (m, q) = (self.m, self.p + 1);
        let mut spent = 0usize;
        loop {
            if self.k < q {
                if self.f < m {
                    self.v[self.k][self.f] = self.moment_row(self.k, self.f);
                    self.f += 1;
                    spent += m;
                } else {
                    self.moment_column(self.k);
                    (self.k, self.f) = (self.k + 1, 0);
                    spent += q * m;
                }
            } else {
                symmetrise(&mut self.mid, q);
                if self.pass == FITTED_SHARE_ITERATIONS {
                    self.active = false;
                    return Some(self.finish());
                }
                self.refine_level();
                (self.pass, self.k, self.f) = (self.pass + 1, 0, 0);
                spent += 2 * m * q * q;
            }
            if spent >= budget {
                return None;
            }
        }
    }

    /// `v_kf = Σ_g (C_fg X̃_kg + P_fg X̃_kg*)`, `C_fg = ½(S_f + S_g) W(f − g)`,
    /// `P_fg = ½(S_f + S_g) W⁺(f + g)`, `W(−d) = W(d)*` (parent module, σ), in real arithmetic
    /// with the `g ≤ f` and `g > f` halves as separate loops: the hot loop of a solve.
    fn moment_row(&self, k: usize, f: usize) -> C64 {
        let (xk, level, lf) = (&self.cols[k], &self.level, self.level[f]);
        let (mut re, mut im) = (0.0, 0.0);
        for g in 0..=f {
            let (x, wd, ws) = (xk[g], self.w_diff[f - g], self.w_sum[f + g]);
            let s = lf + level[g];
            re += s * (x.0 * (wd.0 + ws.0) + x.1 * (ws.1 - wd.1));
            im += s * (x.0 * (wd.1 + ws.1) + x.1 * (wd.0 - ws.0));
        }
        for g in f + 1..self.m {
            // W(f − g) = W(g − f)*.
            let (x, wd, ws) = (xk[g], self.w_diff[g - f], self.w_sum[f + g]);
            let s = lf + level[g];
            re += s * (x.0 * (wd.0 + ws.0) + x.1 * (ws.1 + wd.1));
            im += s * (x.0 * (ws.1 - wd.1) + x.1 * (wd.0 - ws.0));
        }
        (0.5 * re, 0.5 * im)
    }

    /// Column `k` of `M = E[u uᵀ]`: `M_jk = ½ Re Σ_f X̃_jf* v_kf`.
    fn moment_column(&mut self, k: usize) {
        for j in 0..=self.p {
            let (xj, vk) = (&self.cols[j], &self.v[k]);
            let mut s = 0.0;
            for f in 0..self.m {
                // Re(x* v) = x.re v.re + x.im v.im
                s += xj[f].0 * vk[f].0 + xj[f].1 * vk[f].1;
            }
            self.mid[j][k] = 0.5 * s;
        }
    }

    /// One pass of the fitted-share correction (parent module, "The level"): the level whose
    /// expected smoothed residual periodogram matches the observed one.
    fn refine_level(&mut self) {
        let (m, q, inv) = (self.m, self.p + 1, &self.inv);
        let cov_all = sandwich_product(inv, &self.mid, q);
        let mut expected = [0.0; MAX_FREQUENCIES];
        for f in 0..m {
            let mut cross = 0.0;
            let mut fitted = 0.0;
            for j in 0..q {
                let xj = self.cols[j][f];
                for k in 0..q {
                    let vk = self.v[k][f];
                    cross += inv[j][k] * (xj.0 * vk.0 + xj.1 * vk.1);
                    let xk = self.cols[k][f];
                    fitted += cov_all[j][k] * (xj.0 * xk.0 + xj.1 * xk.1);
                }
            }
            expected[f] = (self.level[f] - (cross - fitted) / self.w0).max(0.0);
        }
        let expected = daniell(&expected, m);
        for f in 0..m {
            let ratio = self.observed[f] / expected[f];
            let ratio = if ratio.is_finite() { ratio.clamp(0.2, 5.0) } else { 1.0 };
            self.level[f] *= ratio;
        }
    }

    /// `κ A⁻¹ M A⁻¹` with `κ = RSS / (tr C − tr A⁻¹M)` (parent module, σ): the scale that makes
    /// the plug-in model reproduce the observed residual sum of squares.
    fn finish(&self) -> Option<Square<N_TERMS>> {
        let (m, p, q) = (self.m, self.p, self.p + 1);
        let tr_c: f64 = (0..m).map(|f| self.level[f] * self.w0).sum();
        let mut tr_am = 0.0;
        for j in 0..q {
            for k in 0..q {
                tr_am += self.inv[j][k] * self.mid[k][j];
            }
        }
        let dof = tr_c - tr_am;
        if !(dof > 0.0 && tr_c > 0.0) {
            return None;
        }
        let kappa = self.rss / dof;
        let mut cov = sandwich_product(&self.inv, &self.mid, q);
        for row in cov.iter_mut().take(p) {
            for c in row.iter_mut().take(p) {
                *c *= kappa;
            }
        }
        let ok = (0..p).all(|i| cov[i][i] > 0.0 && cov[i][i].is_finite());
        ok.then_some(cov)
    }

    /// The noise moment `M` for a flat unit level over the copied columns (for the window
    /// algebra's test).
    #[cfg(test)]
    pub(super) fn flat_moment(&mut self) -> Square<N_TERMS> {
        self.level = [1.0; MAX_FREQUENCIES];
        for k in 0..=self.p {
            for f in 0..self.m {
                self.v[k][f] = self.moment_row(k, f);
            }
            self.moment_column(k);
        }
        symmetrise(&mut self.mid, self.p + 1);
        self.mid
    }
}

/// Symmetrises the first `q` rows and columns (the pseudo-covariance term is symmetric only up
/// to rounding).
fn symmetrise(mid: &mut Square<N_TERMS>, q: usize) {
    for j in 0..q {
        for k in 0..j {
            let a = 0.5 * (mid[j][k] + mid[k][j]);
            mid[j][k] = a;
            mid[k][j] = a;
        }
    }
}

/// Daniell smoothing over ±[`SPECTRUM_HALF_WIDTH`] of the first `m` values (fewer at the ends).
fn daniell(x: &[f64; MAX_FREQUENCIES], m: usize) -> [f64; MAX_FREQUENCIES] {
    let mut out = [0.0; MAX_FREQUENCIES];
    for (f, o) in out.iter_mut().enumerate().take(m) {
        let lo = f.saturating_sub(SPECTRUM_HALF_WIDTH);
        let hi = (f + SPECTRUM_HALF_WIDTH).min(m - 1);
        *o = x[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
    }
    out
}

/// `A⁻¹ M A⁻¹` over the first `q` rows and columns.
pub(super) fn sandwich_product(
    inv: &Square<N_TERMS>,
    mid: &Square<N_TERMS>,
    q: usize,
) -> Square<N_TERMS> {
    let mut cov = [[0.0; N_TERMS]; N_TERMS];
    for i in 0..q {
        for j in 0..q {
            let mut s = 0.0;
            for a in 0..q {
                let mut row = 0.0;
                for b in 0..q {
                    row += mid[a][b] * inv[b][j];
                }
                s += inv[i][a] * row;
            }
            cov[i][j] = s;
        }
    }
    cov
}
