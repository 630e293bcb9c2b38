//! One coefficient's σ (the parent module's "σ" and "The level"), computed in steps of bounded
//! work so that a solve's cost can be spread over the updates that follow it (the parent
//! module's "Cost per update").
//!
//! Its inputs — the coefficient's columns, the noise windows, `A⁻¹` and the residual — are
//! copied when the coefficient is solved, so the σ is that of the solve's data however many
//! updates it takes. A step is one row `f` of the noise moment for every column (`q m` terms of
//! its inner sums), one column's reduction (`q m`), or the level's correction between passes
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
    /// `W(f − g)` along a row: `w_line[m − 1 − f + g]`, so that every row reads one forward
    /// slice (`W(−d) = W(d)*` written out once per job instead of branching per term).
    w_line: [C64; 2 * MAX_FREQUENCIES],
    w_sum: [C64; 2 * MAX_FREQUENCIES],
    inv: Square<N_TERMS>,
    rss: f64,
    w0: f64,
    observed: [f64; MAX_FREQUENCIES],
    level: [f64; MAX_FREQUENCIES],
    v: [[C64; MAX_FREQUENCIES]; N_TERMS],
    /// Scratch of [`Self::moment_rows`] (a field, not a local: zeroing two arrays per row
    /// cost a tenth of an update): the row's operator from `Re X̃` and from `Im X̃`.
    from_re: [C64; MAX_FREQUENCIES],
    from_im: [C64; MAX_FREQUENCIES],
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
            w_line: [(0.0, 0.0); 2 * MAX_FREQUENCIES],
            w_sum: [(0.0, 0.0); 2 * MAX_FREQUENCIES],
            inv: [[0.0; N_TERMS]; N_TERMS],
            rss: 0.0,
            w0: 0.0,
            observed: [0.0; MAX_FREQUENCIES],
            level: [0.0; MAX_FREQUENCIES],
            v: [[(0.0, 0.0); MAX_FREQUENCIES]; N_TERMS],
            from_re: [(0.0, 0.0); MAX_FREQUENCIES],
            from_im: [(0.0, 0.0); MAX_FREQUENCIES],
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
        for d in 0..m {
            // Index m − 1 + d holds W(−d) = W(d)*, index m − 1 − d holds W(d) (written last:
            // at d = 0 it is the one the row reads, as recorded).
            let w = s.w_diff[d];
            self.w_line[m - 1 + d] = (w.0, -w.1);
            self.w_line[m - 1 - d] = w;
        }
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
            if self.f < m {
                self.moment_rows(self.f);
                self.f += 1;
                spent += q * m;
            } else if self.k < q {
                self.moment_column(self.k);
                self.k += 1;
                spent += q * m;
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

    /// Row `f` of `v_kf = Σ_g (C_fg X̃_kg + P_fg X̃_kg*)` for every column `k`, with
    /// `C_fg = ½(S_f + S_g) W(f − g)`, `P_fg = ½(S_f + S_g) W⁺(f + g)` (parent module, σ): the
    /// hot loop of a solve. In real arithmetic each `(f, g)` is a 2 × 2 operator on
    /// `(Re X̃_kg, Im X̃_kg)` that does not depend on `k`, so it is formed once for the row, and
    /// two columns are summed at a time: two independent chains the processor runs side by side.
    fn moment_rows(&mut self, f: usize) {
        let (m, q) = (self.m, self.p + 1);
        let lf = self.level[f];
        let w_diff = &self.w_line[m - 1 - f..2 * m - 1 - f];
        let w_sum = &self.w_sum[f..f + m];
        // The operator's rows: (Re, Im) of the term from Re X̃ and from Im X̃.
        let rows = self.from_re.iter_mut().zip(self.from_im.iter_mut());
        for (((wd, ws), lg), (r, i)) in w_diff.iter().zip(w_sum).zip(&self.level[..m]).zip(rows) {
            let s = lf + lg;
            *r = (s * (wd.0 + ws.0), s * (wd.1 + ws.1));
            *i = (s * (ws.1 - wd.1), s * (wd.0 - ws.0));
        }
        let (from_re, from_im) = (&self.from_re[..m], &self.from_im[..m]);
        let mut k = 0;
        while k < q {
            let (x0, x1) = (&self.cols[k][..m], &self.cols[(k + 1).min(q - 1)][..m]);
            let (mut s0, mut s1) = ((0.0, 0.0), (0.0, 0.0));
            for (((a, b), r), i) in x0.iter().zip(x1).zip(from_re).zip(from_im) {
                s0.0 += a.0 * r.0 + a.1 * i.0;
                s0.1 += a.0 * r.1 + a.1 * i.1;
                s1.0 += b.0 * r.0 + b.1 * i.0;
                s1.1 += b.0 * r.1 + b.1 * i.1;
            }
            self.v[k][f] = (0.5 * s0.0, 0.5 * s0.1);
            if k + 1 < q {
                self.v[k + 1][f] = (0.5 * s1.0, 0.5 * s1.1);
            }
            k += 2;
        }
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
        for f in 0..self.m {
            self.moment_rows(f);
        }
        for k in 0..=self.p {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `v_kf` summed straight from its definition in complex arithmetic (parent module, σ):
    /// `Σ_g ½(S_f + S_g) (W(f − g) X̃_kg + W⁺(f + g) X̃_kg*)` with `W(−d) = W(d)*`.
    fn direct(job: &SigmaJob, w_diff: &[C64], k: usize, f: usize) -> C64 {
        let mul = |a: C64, b: C64| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let mut v = (0.0, 0.0);
        for g in 0..job.m {
            let w = if g <= f { w_diff[f - g] } else { (w_diff[g - f].0, -w_diff[g - f].1) };
            let x = job.cols[k][g];
            let t = mul(w, x);
            let u = mul(job.w_sum[f + g], (x.0, -x.1));
            let s = 0.5 * (job.level[f] + job.level[g]);
            v = (v.0 + s * (t.0 + u.0), v.1 + s * (t.1 + u.1));
        }
        v
    }

    /// The row-at-a-time moment (two columns per chain, the operator formed once per row)
    /// equals the definition summed term by term, for an odd and an even number of columns and
    /// a level that is not flat: to rounding.
    #[test]
    fn the_moment_rows_equal_the_definition() {
        let m = 13;
        let z = |a: f64, b: f64| (a.sin(), (1.7 * b).cos());
        let cols: [[C64; MAX_FREQUENCIES]; N_TERMS] =
            core::array::from_fn(|k| core::array::from_fn(|f| z((k * 31 + f) as f64, f as f64)));
        let w_diff: [C64; MAX_FREQUENCIES] =
            core::array::from_fn(|d| if d == 0 { (3.0, 0.0) } else { z(d as f64, 0.3 * d as f64) });
        let w_sum: [C64; 2 * MAX_FREQUENCIES] =
            core::array::from_fn(|s| z(0.7 * s as f64, s as f64));
        let inv = core::array::from_fn(|i| core::array::from_fn(|j| f64::from(u8::from(i == j))));
        let resid: [C64; MAX_FREQUENCIES] = core::array::from_fn(|f| z(f as f64 + 0.5, 2.0));
        for p in [2, 3] {
            let start = SigmaStart {
                m,
                p,
                cols: core::array::from_fn(|k| &cols[k]),
                w_diff: &w_diff,
                w_sum: &w_sum,
                inv: &inv,
                resid: &resid,
                rss: 1.0,
            };
            let mut job = SigmaJob::idle();
            assert!(job.start(0, &[0.0; N_TERMS], &start));
            job.level = core::array::from_fn(|f| 1.0 + 0.1 * f as f64);
            for f in 0..m {
                job.moment_rows(f);
            }
            for k in 0..=p {
                for f in 0..m {
                    let (got, want) = (job.v[k][f], direct(&job, &w_diff, k, f));
                    let scale = want.0.hypot(want.1).max(1.0);
                    assert!((got.0 - want.0).abs() < 1e-12 * scale, "p {p} k {k} f {f}");
                    assert!((got.1 - want.1).abs() < 1e-12 * scale, "p {p} k {k} f {f}");
                }
            }
        }
    }
}
