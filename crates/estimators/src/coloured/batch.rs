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

use nalgebra::DMatrix;
use std::vec;
use std::vec::Vec;

/// Result of the correction.
pub(crate) struct Coloured {
    /// The corrected covariance, `None` when a diagonal element came out non-positive (a
    /// truncated autocorrelation sum need not be positive definite).
    pub covariance: Option<DMatrix<f64>>,
    /// The corrected covariance whatever its diagonal (for callers that need only a block).
    pub full: DMatrix<f64>,
    /// The lag `K` at which the sum was truncated.
    pub lag: usize,
}

/// The coloured-residual covariance (module doc).
///
/// `s`: sensitivities, `N × ny × n` row-major; `e`: residuals `N × ny`; `w`: `R⁻¹` diagonal;
/// `lengths`: samples per manoeuvre (summing to `N`); `minv`: `M⁻¹`; `max_lag`: cap on `K`.
pub(crate) fn covariance(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
    max_lag: usize,
) -> Coloured {
    let ny = w.len();
    let n = minv.nrows();
    let n_total: usize = lengths.iter().sum();
    let max_lag = max_lag.min(lengths.iter().copied().min().unwrap_or(1).saturating_sub(1));
    // r̂(k) for k = 0..=max_lag, each ny × ny row-major: r[k][a*ny + b] = Σ e_i[a] e_{i−k}[b] / N.
    let mut r: Vec<Vec<f64>> = Vec::new();
    let band = 2.0 / (n_total as f64).sqrt();
    let mut lag = max_lag;
    for k in 0..=max_lag {
        let mut rk = vec![0.0; ny * ny];
        let mut start = 0;
        for &len in lengths {
            for i in (start + k)..(start + len) {
                let ei = &e[i * ny..(i + 1) * ny];
                let ej = &e[(i - k) * ny..(i - k + 1) * ny];
                for a in 0..ny {
                    for b in 0..ny {
                        rk[a * ny + b] += ei[a] * ej[b];
                    }
                }
            }
            start += len;
        }
        rk.iter_mut().for_each(|v| *v /= n_total as f64);
        let insignificant = k > 0
            && (0..ny).all(|j| {
                let r0 = r[0][j * ny + j];
                r0 <= 0.0 || (rk[j * ny + j] / r0).abs() < band
            });
        if insignificant {
            lag = k - 1;
            break;
        }
        r.push(rk);
    }
    // T_i = R⁻¹ S_i (ny × n).
    let t: Vec<f64> = s.iter().enumerate().map(|(idx, v)| v * w[(idx / n) % ny]).collect();
    // F = Σ_i Σ_j T_iᵀ r̂(i−j) T_j = F₊ + F₊ᵀ − A₀ with F₊ = Σ_i T_iᵀ G_i, the causal
    // convolution G_i = Σ_{k=0..K} r̂(k) T_{i−k}, and A₀ = Σ_i T_iᵀ r̂(0) T_i.
    let mut fplus = DMatrix::<f64>::zeros(n, n);
    let mut a0 = DMatrix::<f64>::zeros(n, n);
    let mut g = vec![0.0; ny * n];
    let mut g0 = vec![0.0; ny * n];
    let mut start = 0;
    for &len in lengths {
        for i in start..start + len {
            g.iter_mut().for_each(|v| *v = 0.0);
            for (k, rk) in r.iter().enumerate().take((lag + 1).min(i - start + 1)) {
                let tj = &t[(i - k) * ny * n..(i - k + 1) * ny * n];
                for a in 0..ny {
                    let ga = &mut g[a * n..(a + 1) * n];
                    for b in 0..ny {
                        let rab = rk[a * ny + b];
                        for (gv, tv) in ga.iter_mut().zip(&tj[b * n..(b + 1) * n]) {
                            *gv += rab * tv;
                        }
                    }
                }
                if k == 0 {
                    g0.copy_from_slice(&g);
                }
            }
            let ti = &t[i * ny * n..(i + 1) * ny * n];
            for a in 0..ny {
                for p in 0..n {
                    let tip = ti[a * n + p];
                    if tip != 0.0 {
                        for q in 0..n {
                            fplus[(p, q)] += tip * g[a * n + q];
                            a0[(p, q)] += tip * g0[a * n + q];
                        }
                    }
                }
            }
        }
        start += len;
    }
    let f = &fplus + fplus.transpose() - a0;
    let cov = minv * f * minv;
    let cov = 0.5 * (&cov + cov.transpose());
    let ok = (0..n).all(|i| cov[(i, i)] > 0.0 && cov[(i, i)].is_finite());
    Coloured { covariance: ok.then(|| cov.clone()), full: cov, lag }
}
