//! Parameter covariance corrected for coloured (autocorrelated) residuals.
//!
//! The Cramér–Rao bound `M⁻¹` assumes white residuals. Real output-error residuals are
//! coloured by model error and turbulence, and `M⁻¹` is then too small. Morelli & Klein,
//! "Accuracy of aerodynamic model parameters estimated from flight test data", *J. Guidance,
//! Control, and Dynamics* 20(1), 1997, and Klein & Morelli, *Aircraft System Identification*,
//! AIAA 2006, ch. 6 (maximum likelihood, accuracy with coloured residuals; ch. 5 gives the same
//! correction for equation error), SIDPAC `m_colores.m`, give the covariance of the estimate as
//!
//! ```text
//! Cov(θ̂) = M⁻¹ [ Σ_i Σ_j S_iᵀ R⁻¹ r̂(i − j) R⁻¹ S_j ] M⁻¹,   M = Σ_i S_iᵀ R⁻¹ S_i
//! r̂(k) = (1/N) Σ_i e_i e_{i−k}ᵀ   (ny × ny, r̂(−k) = r̂(k)ᵀ)
//! ```
//!
//! with `S_i = ∂y_i/∂θ` the output sensitivities and `e` the residuals at the estimate. The
//! full residual auto- and cross-correlation matrix is used, not only an AR(1) factor.
//!
//! **Truncation.** The sum over lags stops at the first lag `K` at which every output's
//! normalised autocorrelation `r̂_jj(k)/r̂_jj(0)` lies inside the 95 % band of a white sequence,
//! `±2/√N` (the lags beyond are estimation noise, and summing them only adds variance), and at
//! most at a configured maximum lag. Lags are taken within a manoeuvre only; `r̂` is pooled
//! over the manoeuvres.
//!
//! # Prewhitening (`prewhitened`, what output error reports)
//!
//! The truncated sum fails when the residual correlation outlasts the window's statistics: in
//! the F-16 campaign's Dryden turbulence the sum ran to its cap (a quarter of the 20-s window)
//! on every run with the residuals still correlated, and σ came out 0.5–0.8 of the scatter
//! (docs/uncertainty.md). The parametric form of the same correction (Andrews & Monahan,
//! "An improved heteroskedasticity and autocorrelation consistent covariance matrix
//! estimator", *Econometrica* 60(4), 1992: prewhiten with a VAR, sum the few remaining lags,
//! recolour) has no lag truncation:
//!
//! 1. **Model.** A vector autoregression `e_i = Σ_{j=1..p} A_j e_{i−j} + u_i` of all outputs'
//!    residuals together (the turbulence moves β, p, r and a_y together, so their
//!    cross-correlation matters: per-output models lost it and gave Cn_β σ 0.24 of the
//!    scatter), fitted by least squares, order `p ≤ 12` (`MAX_AR_ORDER`) by AIC, stability
//!    enforced (module `ar`).
//! 2. **Exact middle term for that model.** With `v = (I − Σ A_j q^{−j})⁻¹ u`,
//!    `Σ_i T_iᵀ v_i = Σ_m U_mᵀ u_m`, where `U_m = T_m + Σ_j A_jᵀ U_{m+j}` is `T = R⁻¹ S`
//!    filtered by the time-reversed impulse response of the model, run back from the end of
//!    each manoeuvre and on before its start (the innovations before the window still reach
//!    it). So `F = Σ_m Σ_m' U_mᵀ Γ_u(m − m') U_m'`: the Morelli & Klein sum on `(U, u)` with
//!    the whitened residuals `u`, whose autocovariance `Γ_u` is short; its lag sum (the
//!    truncation rule above) is the nonparametric correction of what the VAR misses.
//! 3. **Fitted share.** The residuals are the noise minus the part the fit took into `θ̂`,
//!    `e = v − S δθ`, and are orthogonal to the sensitivities, so their autocovariance lacks
//!    that part's, `d(k) = (1/N) Σ_i S_i C S_{i−k}ᵀ` with `C = Cov(θ̂)`, most at low
//!    frequency, where the sensitivities and turbulence are (first order, as for a projection
//!    orthogonal in the noise metric: `E[ê ê(k)ᵀ] ≈ R_v(k) − d(k)`; the recursive form's
//!    "Lag dependence of the fitted share" is the same correction). The VAR's normal equations
//!    and `Γ_u` (with `Z_i = S_i − Σ_j A_j S_{i−j}` for `S`) get `d` back, and the covariance is
//!    recomputed: two (`FITTED_SHARE_PASSES`) passes of this fixed point. On AR(1) noise with
//!    `a = 0.98` and a constant regressor it moves σ from 0.91 to 1.00 of the exact value.
//!
//! Tested against the exact covariance of least squares on AR(1)/AR(2) noise and for white
//! noise, where it equals the Cramér–Rao σ.
//!
//! # Spectral form (`spectral`, what output error reports)
//!
//! The same middle term as an integral over frequency, `(1/2π) ∫ T̃ᴴ Φ T̃ dω`, with the
//! residuals' cross-spectral matrix `Φ` from a multitaper estimate (sine tapers) and the
//! fitted share added back as above: no model of the noise, so no lag truncation and no
//! autoregressive order (module `spectral`). The prewhitened form is exact for
//! autoregressive noise and the better one on slow AR noise; the spectral form is the robust
//! one when the noise is not autoregressive (a resonance driven by slow noise plus white sensor
//! noise: prewhitened 0.71–12.5 × the exact σ, spectral 0.77–1.36; tests in `spectral`).

mod ar;
mod lags;
mod spectral;

pub(crate) use spectral::TAPERS as SPECTRAL_TAPERS;
pub(crate) use spectral::covariance as spectral;
pub(crate) use spectral::covariance_until as spectral_until;
pub(crate) use spectral::{padded, taper, tapered};

/// Half-spectrum transforms of the `ncol` real columns of `x` (`len × ncol` row-major),
/// zero-padded to `p` (even): `[c][j]` for `j = 0..=p/2`. For the compatibility check's
/// spectral sandwich by manoeuvre blocks (`crate::compat`), which must transform as the
/// general form does.
pub(crate) fn half_spectra(
    planner: &mut rustfft::FftPlanner<f64>,
    x: &[f64],
    ncol: usize,
    p: usize,
) -> Vec<Vec<rustfft::num_complex::Complex64>> {
    lags::half_spectra(planner, x, ncol, p)
}

use nalgebra::DMatrix;
use std::vec;
use std::vec::Vec;

/// A caller's request to give up (a user's stop of a long fit), looked at between the passes
/// and manoeuvres of a computation here: each piece between two looks costs a fraction of a
/// second on a 60,000-sample manoeuvre. A computation that sees it raised returns `None`.
pub(crate) type Stop<'a> = &'a (dyn Fn() -> bool + Sync);

/// Never asks to stop.
pub(crate) const NEVER: Stop<'static> = &|| false;

/// Result of the correction.
pub(crate) struct Coloured {
    /// The corrected covariance, `None` when a diagonal element came out non-positive (a
    /// truncated autocorrelation sum need not be positive definite).
    pub covariance: Option<DMatrix<f64>>,
    /// The corrected covariance whatever its diagonal (for callers that need only a block).
    pub full: DMatrix<f64>,
    /// The lag `K` at which the sum was truncated (0 for the spectral form: no lag sum).
    pub lag: usize,
}

impl Coloured {
    /// From a covariance `M⁻¹FM⁻¹` as computed: symmetrised, and `covariance` set only when
    /// every diagonal element is positive and finite.
    fn new(cov: DMatrix<f64>, lag: usize) -> Self {
        let full = 0.5 * (&cov + cov.transpose());
        let ok = (0..full.nrows()).all(|i| full[(i, i)] > 0.0 && full[(i, i)].is_finite());
        Coloured { covariance: ok.then(|| full.clone()), full, lag }
    }
}

/// The coloured-residual covariance (module doc).
///
/// `s`: sensitivities, `N × ny × n` row-major; `e`: residuals `N × ny`; `w`: `R⁻¹` diagonal;
/// `lengths`: samples per manoeuvre (summing to `N`); `minv`: `M⁻¹`; `max_lag`: cap on `K`.
#[cfg(test)]
pub(crate) fn covariance(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
    max_lag: usize,
) -> Coloured {
    covariance_until(s, e, w, lengths, minv, max_lag, NEVER).unwrap_or_else(|| unreachable!())
}

/// [`covariance`], given up (`None`) once `stop` asks.
pub(crate) fn covariance_until(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
    max_lag: usize,
    stop: Stop,
) -> Option<Coloured> {
    let ny = w.len();
    let n = minv.nrows();
    let max_lag = max_lag.min(lengths.iter().copied().min().unwrap_or(1).saturating_sub(1));
    let (r, lag) = lagged_covariances(e, ny, lengths, 0, max_lag);
    // T_i = R⁻¹ S_i (ny × n).
    let t = weighted_sensitivities(s, w, n);
    let f = middle(&t, ny, n, lengths, &r, &[], stop)?;
    Some(Coloured::new(minv * f * minv, lag))
}

/// Most vector-autoregressive order tried by [`prewhitened`].
pub(crate) const MAX_AR_ORDER: usize = 12;

/// Passes of the fitted-share correction in [`prewhitened`] (module doc): the covariance is
/// the fixed point of a linear map whose contraction is the fitted share, a few per cent on
/// flight records, so two passes leave an error of the order of its cube.
pub(crate) const FITTED_SHARE_PASSES: usize = 2;

/// Result of [`prewhitened`].
pub(crate) struct Prewhitened {
    /// The covariance, as [`Coloured`].
    pub coloured: Coloured,
    /// The order of the residuals' vector autoregression (0: white).
    pub order: usize,
}

/// The prewhitened coloured-residual covariance (module doc, "Prewhitening").
///
/// Same arguments as [`covariance`]; `max_lag` caps the lag sum on the whitened residuals.
#[cfg(test)]
pub(crate) fn prewhitened(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
    max_lag: usize,
) -> Prewhitened {
    prewhitened_until(s, e, w, lengths, minv, max_lag, NEVER).unwrap_or_else(|| unreachable!())
}

/// [`prewhitened`], given up (`None`) once `stop` asks.
pub(crate) fn prewhitened_until(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
    max_lag: usize,
    stop: Stop,
) -> Option<Prewhitened> {
    let ny = w.len();
    let n = minv.nrows();
    let n_total: usize = lengths.iter().sum();
    let shortest = lengths.iter().copied().min().unwrap_or(1);
    // Orders with at least ten samples per coefficient of an equation (p·ny) and within a
    // tenth of the shortest manoeuvre.
    let p_cap = MAX_AR_ORDER.min(shortest / 10).min(n_total / (10 * ny.max(1)));
    let to_blocks = |r: &[Vec<f64>]| -> Vec<DMatrix<f64>> {
        r.iter().map(|rk| DMatrix::from_row_slice(ny, ny, rk)).collect()
    };
    let sample = to_blocks(&lagged_raw(e, ny, lengths, 0, p_cap));
    let order = ar::aic_order_ls(e, ny, lengths, p_cap);
    let max_lag = max_lag.min(shortest.saturating_sub(order + 1));
    let t = weighted_sensitivities(s, w, n);
    let mut fitted: Option<DMatrix<f64>> = None;
    let mut out = None;
    for pass in 0..=FITTED_SHARE_PASSES {
        if stop() {
            return None;
        }
        // Noise autocovariance = residual autocovariance + that of the fitted part S δθ.
        let mut r = sample[..=order].to_vec();
        let d_raw: Vec<DMatrix<f64>> = match &fitted {
            Some(c) => to_blocks(&fitted_autocovariance(s, c, ny, lengths, &[], 0, order)),
            None => Vec::new(),
        };
        for (rk, dk) in r.iter_mut().zip(&d_raw) {
            *rk += dk;
        }
        let mut var = match ar::least_squares(e, ny, lengths, order, order, &d_raw) {
            Some((a, _)) => a,
            None => ar::whittle(&r, order).0,
        };
        var.resize(order, DMatrix::zeros(ny, ny));
        let var: Vec<Vec<f64>> = var.iter().map(|m| m.transpose().as_slice().to_vec()).collect();
        let u = whiten(e, ny, 1, lengths, &var, order);
        let (mut ru, lag) = lagged_covariances(&u, ny, lengths, order, max_lag);
        if let Some(c) = &fitted {
            let d = fitted_autocovariance(s, c, ny, lengths, &var, order, lag);
            for (rk, dk) in ru.iter_mut().zip(&d) {
                rk.iter_mut().zip(dk).for_each(|(x, y)| *x += y);
            }
        }
        let f = middle(&t, ny, n, lengths, &ru, &var, stop)?;
        let col = Coloured::new(minv * f * minv, lag);
        if pass < FITTED_SHARE_PASSES {
            fitted = Some(col.full.clone());
        }
        out = Some(col);
    }
    Some(Prewhitened { coloured: out.expect("at least one pass"), order })
}

/// `u_i = x_i − Σ_j A_j x_{i−j}` for `x` of `N × ny × ncol` (each of the `ncol` columns of
/// an `ny × ncol` sample filtered alike), `A_j` `ny × ny` row-major (`var[j − 1]`); defined
/// from sample `skip` of each manoeuvre on (zero before).
fn whiten(
    x: &[f64],
    ny: usize,
    ncol: usize,
    lengths: &[usize],
    var: &[Vec<f64>],
    skip: usize,
) -> Vec<f64> {
    let row = ny * ncol;
    let mut u = vec![0.0; x.len()];
    let mut start = 0;
    for &len in lengths {
        for i in start + skip.min(len)..start + len {
            let ui = &mut u[i * row..(i + 1) * row];
            ui.copy_from_slice(&x[i * row..(i + 1) * row]);
            for (j, aj) in var.iter().enumerate() {
                let xj = &x[(i - j - 1) * row..(i - j) * row];
                for a in 0..ny {
                    for b in 0..ny {
                        let c = aj[a * ny + b];
                        if c != 0.0 {
                            for (uv, xv) in ui[a * ncol..(a + 1) * ncol]
                                .iter_mut()
                                .zip(&xj[b * ncol..(b + 1) * ncol])
                            {
                                *uv -= c * xv;
                            }
                        }
                    }
                }
            }
        }
        start += len;
    }
    u
}

/// The expected lagged covariances `d(k) = (1/N') Σ_i Z_i C Z_{i−k}ᵀ`, `k = 0..=max_lag`
/// (`ny × ny` row-major, within manoeuvres, from sample `skip` on, `N'` those samples), of the
/// fitted part `S δθ` of the residuals whitened by `var` ([`whiten`]: `Z_i = S_i − Σ_j A_j
/// S_{i−j}`), for a parameter error `δθ` of covariance `C` (`n × n`). With empty `var` and
/// `skip = 0` it is the fitted part's own autocovariance.
fn fitted_autocovariance(
    s: &[f64],
    c: &DMatrix<f64>,
    ny: usize,
    lengths: &[usize],
    var: &[Vec<f64>],
    skip: usize,
    max_lag: usize,
) -> Vec<Vec<f64>> {
    let n = c.nrows();
    let z = whiten(s, ny, n, lengths, var, skip);
    // Y_i = Z_i C (ny × n).
    let cs = c.as_slice(); // column-major; C symmetric, so row q is column q.
    let mut y = vec![0.0; z.len()];
    for (zi, yi) in z.chunks_exact(n).zip(y.chunks_exact_mut(n)) {
        for (q, yv) in yi.iter_mut().enumerate() {
            *yv = zi.iter().zip(&cs[q * n..(q + 1) * n]).map(|(a, b)| a * b).sum();
        }
    }
    pooled_lags(&y, &z, ny, n, lengths, skip, max_lag)
}

/// The pooled lagged covariances `r̂(k)` of [`lagged_covariances`] for every `k = 0..=max_lag`
/// (no truncation).
fn lagged_raw(
    x: &[f64],
    ny: usize,
    lengths: &[usize],
    skip: usize,
    max_lag: usize,
) -> Vec<Vec<f64>> {
    pooled_lags(x, x, ny, 1, lengths, skip, max_lag)
}

/// `(1/N') Σ_i Σ_q y_i[a, q] z_{i−k}[b, q]` for `k = 0..=max_lag` (`ny × ny` row-major; `y`,
/// `z`: `N × ny × ncol` row-major), pooled over the manoeuvres of `lengths`, pairs within a
/// manoeuvre and from its sample `skip` on, `N'` the samples kept ([`lags::cross_lags`]).
fn pooled_lags(
    y: &[f64],
    z: &[f64],
    ny: usize,
    ncol: usize,
    lengths: &[usize],
    skip: usize,
    max_lag: usize,
) -> Vec<Vec<f64>> {
    let row = ny * ncol;
    let n_kept: usize = lengths.iter().map(|l| l.saturating_sub(skip)).sum();
    let mut d = vec![vec![0.0; ny * ny]; max_lag + 1];
    let mut start = 0;
    for &len in lengths {
        let rows = (start + skip.min(len)) * row..(start + len) * row;
        let seg = lags::cross_lags(&y[rows.clone()], &z[rows], ny, ncol, max_lag);
        for (dk, sk) in d.iter_mut().zip(&seg) {
            dk.iter_mut().zip(sk).for_each(|(a, b)| *a += b);
        }
        start += len;
    }
    d.iter_mut().flatten().for_each(|v| *v /= n_kept.max(1) as f64);
    d
}

/// The pooled residual auto/cross-covariances `r̂(k) = (1/N') Σ x_i x_{i−k}ᵀ` (`ny × ny`
/// row-major per lag, within manoeuvres, the first `skip` samples of each manoeuvre left out,
/// `N'` the samples kept), up to the truncation lag `K` of the module doc (first lag at which
/// every output's `|r̂_jj(k)/r̂_jj(0)|` is inside `2/√N'`, minus one; at most `max_lag`).
/// Returns `r̂(0..=K)` and `K`.
fn lagged_covariances(
    x: &[f64],
    ny: usize,
    lengths: &[usize],
    skip: usize,
    max_lag: usize,
) -> (Vec<Vec<f64>>, usize) {
    let n_kept: usize = lengths.iter().map(|l| l.saturating_sub(skip)).sum();
    let band = 2.0 / (n_kept.max(1) as f64).sqrt();
    let mut r = pooled_lags(x, x, ny, 1, lengths, skip, max_lag);
    let white = |k: usize| {
        (0..ny).all(|j| {
            let r0 = r[0][j * ny + j];
            r0 <= 0.0 || (r[k][j * ny + j] / r0).abs() < band
        })
    };
    let lag = (1..=max_lag).find(|&k| white(k)).map_or(max_lag, |k| k - 1);
    r.truncate(lag + 1);
    (r, lag)
}

/// `T_i = R⁻¹ S_i`: the sensitivities (`N × ny × n` row-major) times the weights `w` per output.
fn weighted_sensitivities(s: &[f64], w: &[f64], n: usize) -> Vec<f64> {
    let ny = w.len();
    s.iter().enumerate().map(|(idx, v)| v * w[(idx / n) % ny]).collect()
}

/// The middle term `F = Σ_m Σ_m' U_mᵀ r(m − m') U_m'` of the sandwich, `r(k)` for
/// `k = 0..r.len()−1` (`ny × ny` row-major, `r(−k) = r(k)ᵀ`, zero beyond), within manoeuvres.
///
/// `U` is `T` (`N × ny × n`, manoeuvres concatenated) filtered by the time-reversed impulse
/// response of the vector autoregression `(I − Σ_j A_j q^{−j})⁻¹` (`var[j − 1]` = `A_j`,
/// `ny × ny` row-major; empty for none): `U_m = T_m + Σ_j A_jᵀ U_{m+j}` run backwards from the
/// end of each manoeuvre, with `T_m = 0` outside it. Before a manoeuvre's first sample `U`
/// keeps going (pre-sample innovations of a stationary process still reach the window) until
/// its energy has died out (10⁻¹² of the total) or for at most four manoeuvre lengths.
/// Without an autoregression `U = T` and `F` is the Morelli & Klein sum of the module doc.
/// The double sum itself is [`lags::sandwich`] (through the FFT when the lags are many).
/// `None` when `stop` asks (looked at before each manoeuvre and between its two steps).
fn middle(
    t: &[f64],
    ny: usize,
    n: usize,
    lengths: &[usize],
    r: &[Vec<f64>],
    var: &[Vec<f64>],
    stop: Stop,
) -> Option<DMatrix<f64>> {
    let row = ny * n;
    let mut f = DMatrix::<f64>::zeros(n, n);
    let mut start = 0;
    for &len in lengths {
        if stop() {
            return None;
        }
        let own = &t[start * row..(start + len) * row];
        f += if var.is_empty() {
            lags::sandwich(own, ny, n, r)
        } else {
            let u = recoloured(own, ny, n, var);
            if stop() {
                return None;
            }
            lags::sandwich(&u, ny, n, r)
        };
        start += len;
    }
    Some(f)
}

/// `U` of [`middle`] for one manoeuvre's `T` (`len × ny × n`), in time order, its pre-sample
/// rows first.
fn recoloured(t: &[f64], ny: usize, n: usize, var: &[Vec<f64>]) -> Vec<f64> {
    let row = ny * n;
    let len = t.len() / row;
    let p_max = var.len();
    // Rows from the last sample backwards; row m + j is `back[back.len() − j·row ..]`.
    let mut back: Vec<f64> = Vec::with_capacity(t.len());
    let mut total = 0.0;
    let mut recent = std::collections::VecDeque::with_capacity(p_max + 1);
    let mut u = vec![0.0; row];
    for m_rel in (-(4 * len as isize)..len as isize).rev() {
        if m_rel < 0 && recent.iter().sum::<f64>() <= 1e-12 * total {
            break;
        }
        if m_rel >= 0 {
            u.copy_from_slice(&t[m_rel as usize * row..][..row]);
        } else {
            u.iter_mut().for_each(|v| *v = 0.0);
        }
        let done = back.len() / row;
        for (j, aj) in var.iter().enumerate().take(done) {
            let later = &back[(done - j - 1) * row..][..row];
            // U_m[b] += Σ_a A_j[a][b] U_{m+j}[a].
            for a in 0..ny {
                for b in 0..ny {
                    let c = aj[a * ny + b];
                    for (uv, lv) in u[b * n..][..n].iter_mut().zip(&later[a * n..][..n]) {
                        *uv += c * lv;
                    }
                }
            }
        }
        let energy: f64 = u.iter().map(|v| v * v).sum();
        total += energy;
        if recent.len() == p_max.max(1) {
            recent.pop_front();
        }
        recent.push_back(energy);
        back.extend_from_slice(&u);
    }
    // Time order: reverse the rows.
    back.chunks_exact(row).rev().flatten().copied().collect()
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Least squares `y = Xθ + v` with `N = 2000` samples in two manoeuvres (1200, 800) and
    /// three regressors (a constant, a slow and a faster sinusoid, all within manoeuvres).
    /// Returns the regressors `N × 3` (the sensitivities of a one-output fit) and `(XᵀX)⁻¹`.
    pub(super) fn regression() -> (Vec<f64>, [usize; 2], DMatrix<f64>) {
        let lengths = [1200, 800];
        let mut x = Vec::new();
        for &len in &lengths {
            for i in 0..len {
                let t = i as f64 * 0.01;
                x.extend([1.0, (0.6 * t).sin(), (5.0 * t).cos()]);
            }
        }
        let xm = DMatrix::from_row_slice(x.len() / 3, 3, &x);
        let minv = (xm.transpose() * &xm).try_inverse().unwrap();
        (x, lengths, minv)
    }

    /// The exact covariance `(XᵀX)⁻¹ Xᵀ Γ X (XᵀX)⁻¹` of the least-squares estimate for noise
    /// with autocovariance `gamma(k)` (independent between manoeuvres).
    pub(super) fn exact(
        x: &[f64],
        lengths: &[usize],
        minv: &DMatrix<f64>,
        gamma: &[f64],
    ) -> DMatrix<f64> {
        let mut f = DMatrix::<f64>::zeros(3, 3);
        let mut start = 0;
        for &len in lengths {
            for i in start..start + len {
                for j in start..start + len {
                    let g = gamma.get(i.abs_diff(j)).copied().unwrap_or(0.0);
                    for p in 0..3 {
                        for q in 0..3 {
                            f[(p, q)] += x[i * 3 + p] * g * x[j * 3 + q];
                        }
                    }
                }
            }
            start += len;
        }
        minv * f * minv
    }

    /// Mean prewhitened and lag-truncated σ over 150 realisations of the noise
    /// `v_i = φ1 v_{i−1} + φ2 v_{i−2} + w_i` (stationary start), each from its own residuals.
    fn mean_sigmas(phi: [f64; 2], seed: u64) -> ([f64; 3], [f64; 3], Vec<f64>) {
        let (x, lengths, minv) = regression();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let n01 = Normal::new(0.0, 1.0).unwrap();
        let n = x.len() / 3;
        let xm = DMatrix::from_row_slice(n, 3, &x);
        let (mut pre, mut trunc) = ([0.0; 3], [0.0; 3]);
        let runs = 150;
        for _ in 0..runs {
            let mut v = Vec::with_capacity(n);
            for &len in &lengths {
                let (mut v1, mut v2) = (0.0, 0.0);
                for i in 0..len + 3000 {
                    let vi = phi[0] * v1 + phi[1] * v2 + n01.sample(&mut rng);
                    (v2, v1) = (v1, vi);
                    if i >= 3000 {
                        v.push(vi);
                    }
                }
            }
            let y = nalgebra::DVector::from_vec(v);
            let theta = &minv * xm.transpose() * &y;
            let e: Vec<f64> = (&y - &xm * theta).iter().copied().collect();
            let p = prewhitened(&x, &e, &[1.0], &lengths, &minv, 200).coloured.full;
            let c = covariance(&x, &e, &[1.0], &lengths, &minv, 200).full;
            for i in 0..3 {
                pre[i] += p[(i, i)].max(0.0).sqrt() / runs as f64;
                trunc[i] += c[(i, i)].max(0.0).sqrt() / runs as f64;
            }
        }
        // Autocovariance of the AR(2) from its impulse response (long enough to converge).
        let mut h = vec![0.0; 20_000];
        for k in 0..h.len() {
            h[k] = if k == 0 { 1.0 } else { 0.0 }
                + if k >= 1 { phi[0] * h[k - 1] } else { 0.0 }
                + if k >= 2 { phi[1] * h[k - 2] } else { 0.0 };
        }
        let gamma: Vec<f64> =
            (0..1200).map(|k| h.iter().zip(&h[k..]).map(|(a, b)| a * b).sum()).collect();
        let ex = exact(&x, &lengths, &minv, &gamma);
        (pre, trunc, (0..3).map(|i| ex[(i, i)].sqrt()).collect())
    }

    /// The prewhitened σ of a regression on AR(1) and AR(2)-coloured noise match the exact σ
    /// of the least-squares estimate, `sqrt diag (XᵀX)⁻¹ XᵀΓX (XᵀX)⁻¹`, within 6 % on average
    /// over 150 realisations (correlation times of 50 samples and a resonance), and within
    /// 12 % for a correlation time of 200 samples, a sixth of the manoeuvre (measured 0.91:
    /// the least-squares estimate of a pole that near 1 is biased towards 0 by O(1/N), and σ of the
    /// constant's coefficient goes as 1/(1 − a); the lag-truncated sum gives 0.61 there); for
    /// white noise they equal the Cramér–Rao σ `sqrt diag (XᵀX)⁻¹` within 5 %.
    #[test]
    fn prewhitened_sigma_matches_exact_covariance_of_ar_coloured_regression() {
        for (phi, label, tol) in [
            ([0.0, 0.0], "white", 0.05),
            ([0.98, 0.0], "AR(1) 0.98", 0.06),
            ([1.9, -0.91], "AR(2) poles 0.95 ± 0.1i", 0.06),
            ([0.995, 0.0], "AR(1) 0.995", 0.12),
        ] {
            let (pre, trunc, ex) = mean_sigmas(phi, 7);
            for i in 0..3 {
                let ratio = pre[i] / ex[i];
                std::println!(
                    "{label} θ{i}: prewhitened/exact {ratio:.3}, truncated/exact {:.3}",
                    trunc[i] / ex[i]
                );
                assert!((ratio - 1.0).abs() < tol, "{label} θ{i}: prewhitened σ / exact σ {ratio}");
            }
        }
    }

    /// A stop raised at any look of the three coloured forms ends that form with `None`; each
    /// looks more than once per pass over the two manoeuvres (so a long record's σ ends within
    /// a piece of one manoeuvre's work); never raised, each gives the value it gives without a
    /// stop, bit for bit.
    #[test]
    fn a_stop_at_any_look_ends_each_coloured_form() {
        use core::sync::atomic::{AtomicUsize, Ordering};
        let (x, lengths, minv) = regression();
        let e: Vec<f64> =
            (0..x.len() / 3).map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0).collect();
        let w = [1.0];
        let looks = |form: &dyn Fn(Stop) -> Option<DMatrix<f64>>| {
            let seen = AtomicUsize::new(0);
            let whole = form(&|| {
                seen.fetch_add(1, Ordering::SeqCst);
                false
            })
            .unwrap();
            let n = seen.load(Ordering::SeqCst);
            for k in 0..n {
                let count = AtomicUsize::new(0);
                let stopped = form(&|| count.fetch_add(1, Ordering::SeqCst) >= k);
                assert!(stopped.is_none(), "look {k} of {n}");
            }
            (n, whole)
        };
        let (n, c) =
            looks(&|stop| Some(covariance_until(&x, &e, &w, &lengths, &minv, 50, stop)?.full));
        assert!(n >= lengths.len(), "{n}");
        assert_eq!(c, covariance(&x, &e, &w, &lengths, &minv, 50).full);
        let (n, p) = looks(&|stop| {
            Some(prewhitened_until(&x, &e, &w, &lengths, &minv, 50, stop)?.coloured.full)
        });
        assert!(n >= (FITTED_SHARE_PASSES + 1) * (1 + lengths.len()), "{n}");
        assert_eq!(p, prewhitened(&x, &e, &w, &lengths, &minv, 50).coloured.full);
        let (n, sp) = looks(&|stop| Some(spectral_until(&x, &e, &w, &lengths, &minv, stop)?.full));
        assert!(n >= 2 * (FITTED_SHARE_PASSES + 1) * lengths.len(), "{n}");
        assert_eq!(sp, spectral(&x, &e, &w, &lengths, &minv).full);
    }
}
