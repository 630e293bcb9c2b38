//! The two lag sums of the time-domain coloured-residual forms, in time `O(L log L)` instead of
//! `O(L·K)` for `K` lags of a manoeuvre of `L` samples.
//!
//! Both forms truncate their lag sum at the first lag where the residuals look white, at most
//! a quarter of the shortest manoeuvre. On a long record whose residuals stay coloured the sum
//! runs to that cap, so a direct sum costs `O(L²)`: a 6,000-sample output-error fit spent 29 of
//! its 30 s here, a 30,000-sample one about five minutes. Through the FFT (zero-padded so the
//! circular correlation is the linear one) both sums take a time nearly linear in `L`,
//! whatever the lag; small lag counts keep the direct sum, which is then cheaper.
//!
//! - [`cross_lags`]: `d(k) = Σ_i Σ_q y_i[a, q] z_{i−k}[b, q]` for `k = 0..=K` (the lagged
//!   (cross-)covariances of residuals and of the fitted share, unnormalised).
//! - [`sandwich`]: `F = Σ_m Σ_m' U_mᵀ r(m − m') U_m'` with `r(−k) = r(k)ᵀ`, zero beyond `K`
//!   (the middle term of the sandwich), by Parseval: `F = (1/P) Σ_j Ũ_jᴴ Φ_j Ũ_j` with
//!   `Φ_j = Σ_{|k|≤K} r(k) e^{−iω_j k}` and the transforms of length `P ≥ L + K`.
//!
//! Real signals: the transforms of two real columns come from one complex FFT (the pair trick
//! `X = (Z_j + conj Z_{P−j})/2`, `Y = (Z_j − conj Z_{P−j})/2i`), and only `j = 0..=P/2` is kept
//! (the rest are conjugates), so memory is about `1.25` times the columns' own (`P/2 + 1`
//! complex numbers per column of `L` reals, `P` the power of two at or above `L + K`).

use nalgebra::DMatrix;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex64 as C64;
use std::vec;
use std::vec::Vec;

/// At or below this many lags the direct sums are used: each lag costs one pass over the
/// samples, and below about this count that is cheaper than the transforms.
const DIRECT_MAX_LAG: usize = 16;

/// Half-spectrum transforms of the `ncol` real columns of `x` (`len × ncol` row-major),
/// zero-padded to `p` (even): `[c][j]` for `j = 0..=p/2`.
pub(super) fn half_spectra(
    planner: &mut FftPlanner<f64>,
    x: &[f64],
    ncol: usize,
    p: usize,
) -> Vec<Vec<C64>> {
    let len = x.len() / ncol.max(1);
    let fft = planner.plan_fft_forward(p);
    let half = p / 2 + 1;
    let mut out = Vec::with_capacity(ncol);
    let mut z = vec![C64::new(0.0, 0.0); p];
    for c in (0..ncol).step_by(2) {
        let pair = c + 1 < ncol;
        z.iter_mut().for_each(|v| *v = C64::new(0.0, 0.0));
        for i in 0..len {
            z[i] = C64::new(x[i * ncol + c], if pair { x[i * ncol + c + 1] } else { 0.0 });
        }
        fft.process(&mut z);
        let split = |j: usize| (z[j], z[(p - j) % p].conj());
        out.push((0..half).map(&split).map(|(a, b)| (a + b) * 0.5).collect());
        if pair {
            let minus_i_half = C64::new(0.0, -0.5);
            out.push((0..half).map(split).map(|(a, b)| (a - b) * minus_i_half).collect());
        }
    }
    out
}

/// The padded transform length: the power of two at or above `len + max_lag` (at least 2).
fn padded(len: usize, max_lag: usize) -> usize {
    (len + max_lag).max(2).next_power_of_two()
}

/// `d(k)[a·ny + b] = Σ_i Σ_q y_i[a, q] z_{i−k}[b, q]`, `k = 0..=max_lag`, over the rows of one
/// segment (`y`, `z`: `len × ny × ncol` row-major; terms with `i − k < 0` absent).
pub(super) fn cross_lags(
    y: &[f64],
    z: &[f64],
    ny: usize,
    ncol: usize,
    max_lag: usize,
) -> Vec<Vec<f64>> {
    let row = ny * ncol;
    let len = y.len() / row.max(1);
    let max_lag = max_lag.min(len.saturating_sub(1));
    if max_lag <= DIRECT_MAX_LAG {
        return (0..=max_lag)
            .map(|k| {
                let mut dk = vec![0.0; ny * ny];
                for i in k..len {
                    let (yi, zj) = (&y[i * row..][..row], &z[(i - k) * row..][..row]);
                    for a in 0..ny {
                        for b in 0..ny {
                            let (ya, zb) = (&yi[a * ncol..][..ncol], &zj[b * ncol..][..ncol]);
                            dk[a * ny + b] += ya.iter().zip(zb).map(|(p, q)| p * q).sum::<f64>();
                        }
                    }
                }
                dk
            })
            .collect();
    }
    let p = padded(len, max_lag);
    let mut planner = FftPlanner::new();
    let ys = half_spectra(&mut planner, y, row, p);
    let zs = if core::ptr::eq(y, z) { None } else { Some(half_spectra(&mut planner, z, row, p)) };
    let zs = zs.as_ref().unwrap_or(&ys);
    let inverse = planner.plan_fft_inverse(p);
    let mut buf = vec![C64::new(0.0, 0.0); p];
    let mut d = vec![vec![0.0; ny * ny]; max_lag + 1];
    for a in 0..ny {
        for b in 0..ny {
            // Σ_q Y_aq(ω) conj Z_bq(ω): the transform of the correlation, conjugate-symmetric.
            for j in 0..=p / 2 {
                let s: C64 =
                    (0..ncol).map(|q| ys[a * ncol + q][j] * zs[b * ncol + q][j].conj()).sum();
                buf[j] = s;
                if j > 0 && j < p / 2 {
                    buf[p - j] = s.conj();
                }
            }
            inverse.process(&mut buf);
            for (k, dk) in d.iter_mut().enumerate() {
                dk[a * ny + b] = buf[k].re / p as f64;
            }
        }
    }
    d
}

/// `F = Σ_m Σ_m' U_mᵀ r(m − m') U_m'` over the rows of one segment (`u`: `len × ny × n`
/// row-major; `r[k]`: `ny × ny` row-major for `k = 0..r.len()`, `r(−k) = r(k)ᵀ`, zero beyond).
pub(super) fn sandwich(u: &[f64], ny: usize, n: usize, r: &[Vec<f64>]) -> DMatrix<f64> {
    let row = ny * n;
    let len = u.len() / row.max(1);
    let max_lag = r.len().saturating_sub(1).min(len.saturating_sub(1));
    let mut f = DMatrix::<f64>::zeros(n, n);
    if r.is_empty() || len == 0 {
        return f;
    }
    if max_lag <= DIRECT_MAX_LAG {
        // F₊ = Σ_m G_mᵀ U_m with G_m = Σ_k r(k)ᵀ U_{m+k}; F = F₊ + F₊ᵀ − Σ_m U_mᵀ r(0) U_m.
        let mut g = vec![0.0; row];
        let mut g0 = vec![0.0; row];
        let mut a0 = DMatrix::<f64>::zeros(n, n);
        for m in 0..len {
            g.iter_mut().for_each(|v| *v = 0.0);
            for (k, rk) in r.iter().enumerate().take(max_lag + 1) {
                if m + k >= len {
                    break;
                }
                let uk = &u[(m + k) * row..][..row];
                for b in 0..ny {
                    for a in 0..ny {
                        let rab = rk[a * ny + b];
                        for (gv, uv) in g[b * n..][..n].iter_mut().zip(&uk[a * n..][..n]) {
                            *gv += rab * uv;
                        }
                    }
                }
                if k == 0 {
                    g0.copy_from_slice(&g);
                }
            }
            let um = &u[m * row..][..row];
            for b in 0..ny {
                for p in 0..n {
                    let (gp, g0p) = (g[b * n + p], g0[b * n + p]);
                    for q in 0..n {
                        f[(p, q)] += gp * um[b * n + q];
                        a0[(p, q)] += g0p * um[b * n + q];
                    }
                }
            }
        }
        return &f + f.transpose() - a0;
    }
    let p = padded(len, max_lag);
    let mut planner = FftPlanner::new();
    let us = half_spectra(&mut planner, u, row, p);
    let phi = lag_window_spectrum(&mut planner, r, ny, max_lag, p);
    let mut g = vec![C64::new(0.0, 0.0); row];
    for j in 0..=p / 2 {
        let weight = if j == 0 || j == p / 2 { 1.0 } else { 2.0 };
        // G[a, q] = Σ_b Φ_ab U[b, q]; F[p', q] += w Re Σ_a conj(U[a, p']) G[a, q].
        for a in 0..ny {
            for q in 0..n {
                g[a * n + q] = (0..ny).map(|b| phi[a * ny + b][j] * us[b * n + q][j]).sum();
            }
        }
        for pp in 0..n {
            for q in 0..n {
                let s: C64 = (0..ny).map(|a| us[a * n + pp][j].conj() * g[a * n + q]).sum();
                f[(pp, q)] += weight * s.re;
            }
        }
    }
    f / p as f64
}

/// `Φ_ab(ω_j) = Σ_{|k|≤K} r(k)[a, b] e^{−iω_j k}` (`r(−k)[a, b] = r(k)[b, a]`) at the `p`-point
/// frequencies `j = 0..=p/2`, `[a·ny + b][j]`.
fn lag_window_spectrum(
    planner: &mut FftPlanner<f64>,
    r: &[Vec<f64>],
    ny: usize,
    max_lag: usize,
    p: usize,
) -> Vec<Vec<C64>> {
    let fft = planner.plan_fft_forward(p);
    let mut h = vec![C64::new(0.0, 0.0); p];
    let mut out = Vec::with_capacity(ny * ny);
    for a in 0..ny {
        for b in 0..ny {
            h.iter_mut().for_each(|v| *v = C64::new(0.0, 0.0));
            h[0] = C64::new(r[0][a * ny + b], 0.0);
            for k in 1..=max_lag {
                h[k] = C64::new(r[k][a * ny + b], 0.0);
                h[p - k] = C64::new(r[k][b * ny + a], 0.0);
            }
            fft.process(&mut h);
            out.push(h[..=p / 2].to_vec());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random(len: usize, seed: u64) -> Vec<f64> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        (0..len).map(|_| rng.random_range(-1.0..1.0)).collect()
    }

    /// The defining double sum, term by term.
    fn naive_sandwich(u: &[f64], ny: usize, n: usize, r: &[Vec<f64>]) -> DMatrix<f64> {
        let len = u.len() / (ny * n);
        let mut f = DMatrix::zeros(n, n);
        for m in 0..len {
            for mp in 0..len {
                let k = m as isize - mp as isize;
                if k.unsigned_abs() >= r.len() {
                    continue;
                }
                let rab = |a: usize, b: usize| {
                    if k >= 0 { r[k as usize][a * ny + b] } else { r[(-k) as usize][b * ny + a] }
                };
                for p in 0..n {
                    for q in 0..n {
                        for a in 0..ny {
                            for b in 0..ny {
                                f[(p, q)] +=
                                    u[(m * ny + a) * n + p] * rab(a, b) * u[(mp * ny + b) * n + q];
                            }
                        }
                    }
                }
            }
        }
        f
    }

    #[test]
    fn the_transformed_sandwich_is_the_double_sum_at_every_lag_count() {
        let (ny, n, len) = (3, 2, 97);
        let u = random(len * ny * n, 1);
        for lags in [1, 5, 17, 40, 96, 150] {
            let mut r: Vec<Vec<f64>> = (0..lags).map(|k| random(ny * ny, 100 + k as u64)).collect();
            // An autocovariance at lag 0 is symmetric.
            let r0 = r[0].clone();
            for a in 0..ny {
                for b in 0..ny {
                    r[0][a * ny + b] = 0.5 * (r0[a * ny + b] + r0[b * ny + a]);
                }
            }
            let fast = sandwich(&u, ny, n, &r);
            let slow = naive_sandwich(&u, ny, n, &r);
            let err = (&fast - &slow).abs().max();
            assert!(
                err < 1e-9 * slow.abs().max(),
                "{lags} lags: {err:e} of {:e}",
                slow.abs().max()
            );
        }
    }

    #[test]
    fn the_transformed_cross_lags_are_the_direct_sums() {
        let (ny, ncol, len) = (2, 3, 83);
        let (y, z) = (random(len * ny * ncol, 7), random(len * ny * ncol, 8));
        let direct = |k: usize, a: usize, b: usize| -> f64 {
            (k..len)
                .map(|i| {
                    (0..ncol)
                        .map(|q| y[(i * ny + a) * ncol + q] * z[((i - k) * ny + b) * ncol + q])
                        .sum::<f64>()
                })
                .sum()
        };
        for lags in [3, 30, 82] {
            let d = cross_lags(&y, &z, ny, ncol, lags);
            assert_eq!(d.len(), lags + 1);
            for (k, dk) in d.iter().enumerate() {
                for a in 0..ny {
                    for b in 0..ny {
                        let want = direct(k, a, b);
                        assert!(
                            (dk[a * ny + b] - want).abs() < 1e-9,
                            "k {k} ({a},{b}): {} vs {want}",
                            dk[a * ny + b]
                        );
                    }
                }
            }
        }
    }
}
