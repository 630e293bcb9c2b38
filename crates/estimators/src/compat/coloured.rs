//! The check's coloured-residual covariance: output error's spectral sandwich
//! (`crate::coloured::batch`, module `spectral`) formed on the manoeuvre blocks of the
//! sensitivities ([`Sensitivities`]).
//!
//! The sandwich's middle term is a sum over manoeuvres, and a manoeuvre's share involves only
//! the columns its outputs depend on: the global unknowns and its own initial states. The
//! general form transforms and multiplies all `nβ` columns in every manoeuvre, `nβ²` per
//! frequency per manoeuvre, and takes a square root of the whole `nβ × nβ` covariance for the
//! fitted share: with `nβ` growing by six per manoeuvre, quadratic in the manoeuvres and more.
//! Here each manoeuvre's share is formed in its own `q` columns (the global unknowns plus six)
//! and added into place, and the fitted share `(h S)~ C (h S)~ᴴ` uses the block of `C` in those
//! columns directly, where the general form goes through `C = L Lᵀ` (the same but for the
//! negative rounding the square root clips). Everything else is the general form's: sine
//! tapers, zero padding, the frequencies kept, the passes of the fitted share; the unit test
//! `compat::tests::the_block_spectral_sandwich_is_the_dense_one` holds the two equal.

use super::blocks::Sensitivities;
use crate::coloured::batch::{
    FITTED_SHARE_PASSES, SPECTRAL_TAPERS as TAPERS, half_spectra, padded, taper, tapered,
};
use nalgebra::DMatrix;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex64 as C64;

/// Skipped frequencies: below this fraction, divided by `P/2 + 1`, of every column's largest
/// weighted-sensitivity energy (the general form's).
const NEGLIGIBLE: f64 = 1e-9;

/// One manoeuvre's transforms at the frequencies kept.
struct Transforms {
    len: usize,
    kept: Vec<usize>,
    weight: Vec<f64>,
    /// The residuals' multitaper cross-spectral matrix, `[j][a·ny + b]`.
    phi: Vec<C64>,
    /// Weighted sensitivities, `[j][a·q + c]`.
    t: Vec<C64>,
}

/// The transforms of one manoeuvre's weighted sensitivities `t` (`len × ny × q`) and residuals
/// `e` (`len × ny`).
fn transforms(
    planner: &mut FftPlanner<f64>,
    t: &[f64],
    e: &[f64],
    (ny, q): (usize, usize),
) -> Transforms {
    let len = e.len() / ny;
    let p = padded(len);
    let n_freq = p / 2 + 1;
    let t_all = half_spectra(planner, t, ny * q, p);
    let energy = |m: usize, c: usize| (0..ny).map(|a| t_all[a * q + c][m].norm_sqr()).sum::<f64>();
    let peak: Vec<f64> =
        (0..q).map(|c| (0..n_freq).map(|m| energy(m, c)).fold(0.0, f64::max)).collect();
    let cut = NEGLIGIBLE / n_freq as f64;
    let kept: Vec<usize> = (0..n_freq)
        .filter(|&m| (0..q).any(|c| peak[c] > 0.0 && energy(m, c) > cut * peak[c]))
        .collect();
    let weight =
        kept.iter().map(|&m| if m == 0 || m == p / 2 { 1.0 } else { 2.0 } / p as f64).collect();
    let t_kept: Vec<C64> = kept.iter().flat_map(|&m| t_all.iter().map(move |c| c[m])).collect();
    let e_all = half_spectra(planner, &tapered(e, ny), TAPERS * ny, p);
    let mut phi = vec![C64::new(0.0, 0.0); kept.len() * ny * ny];
    for (pj, &m) in phi.chunks_exact_mut(ny * ny).zip(&kept) {
        for k in 0..TAPERS {
            let ek = &e_all[k * ny..(k + 1) * ny];
            for a in 0..ny {
                for b in 0..ny {
                    pj[a * ny + b] += ek[a][m] * ek[b][m].conj() / TAPERS as f64;
                }
            }
        }
    }
    Transforms { len, kept, weight, phi, t: t_kept }
}

/// The fitted share `(1/K) Σ_k (h_k S)~ C (h_k S)~ᴴ` at the kept frequencies of `tr`, `s` the
/// manoeuvre's sensitivities (`len × ny × q`) and `c` the covariance's block in its columns.
fn fitted_share(
    planner: &mut FftPlanner<f64>,
    s: &[f64],
    tr: &Transforms,
    (ny, q): (usize, usize),
    c: &DMatrix<f64>,
) -> Vec<C64> {
    let p = padded(tr.len);
    let mut d = vec![C64::new(0.0, 0.0); tr.kept.len() * ny * ny];
    let mut h = vec![C64::new(0.0, 0.0); ny * q];
    let mut gm = vec![C64::new(0.0, 0.0); ny * q];
    for k in 0..TAPERS {
        let x: Vec<f64> =
            s.iter().enumerate().map(|(idx, v)| taper(k, idx / (ny * q), tr.len) * v).collect();
        let g = half_spectra(planner, &x, ny * q, p); // `[a·q + c][m]`
        for (dj, &m) in d.chunks_exact_mut(ny * ny).zip(&tr.kept) {
            // G at this frequency, contiguous; H = G C (ny × q), then D += H Gᴴ / K.
            for (gv, column) in gm.iter_mut().zip(&g) {
                *gv = column[m];
            }
            for (ga, ha) in gm.chunks_exact(q).zip(h.chunks_exact_mut(q)) {
                for (col, hv) in ha.iter_mut().enumerate() {
                    *hv = ga.iter().zip(c.column(col).iter()).map(|(x, y)| x * y).sum();
                }
            }
            for (a, ha) in h.chunks_exact(q).enumerate() {
                for (b, gb) in gm.chunks_exact(q).enumerate() {
                    let acc: C64 = ha.iter().zip(gb).map(|(x, y)| x * y.conj()).sum();
                    dj[a * ny + b] += acc / TAPERS as f64;
                }
            }
        }
    }
    d
}

/// The upper triangle of one manoeuvre's share of the middle term, `Σ_j w_j Re(T̃ᴴ (Φ̂ + D)
/// T̃)` (`q × q`).
fn middle(man: &Transforms, d: Option<&[C64]>, (ny, q): (usize, usize)) -> DMatrix<f64> {
    let mut f = DMatrix::zeros(q, q);
    let mut phi = vec![C64::new(0.0, 0.0); ny * ny];
    let mut g = vec![C64::new(0.0, 0.0); ny * q];
    for (j, &wm) in man.weight.iter().enumerate() {
        let t = &man.t[j * ny * q..(j + 1) * ny * q];
        phi.copy_from_slice(&man.phi[j * ny * ny..(j + 1) * ny * ny]);
        if let Some(d) = d {
            for (pv, dv) in phi.iter_mut().zip(&d[j * ny * ny..(j + 1) * ny * ny]) {
                *pv += dv;
            }
        }
        for a in 0..ny {
            for p in 0..q {
                g[a * q + p] = (0..ny).map(|b| phi[a * ny + b] * t[b * q + p]).sum();
            }
        }
        for p in 0..q {
            for r in p..q {
                let acc: f64 = (0..ny).map(|a| (t[a * q + p].conj() * g[a * q + r]).re).sum();
                f[(p, r)] += wm * acc;
            }
        }
    }
    f
}

/// One pass of the sandwich: `M⁻¹ F M⁻¹` symmetrised, `F` summed over the manoeuvres with the
/// fitted share of the covariance `c` (none on the first pass).
fn pass(
    planner: &mut FftPlanner<f64>,
    s: &Sensitivities,
    e: &[f64],
    w: &[f64],
    minv: &DMatrix<f64>,
    c: Option<&DMatrix<f64>>,
) -> DMatrix<f64> {
    let (n, ny) = (s.n, w.len());
    let mut f = DMatrix::<f64>::zeros(n, n);
    let mut start = 0;
    for (cols, block) in s.columns.iter().zip(&s.blocks) {
        let q = cols.len();
        let len = block.len() / (ny * q).max(1);
        if len == 0 {
            continue;
        }
        let t: Vec<f64> = block.iter().enumerate().map(|(idx, v)| v * w[(idx / q) % ny]).collect();
        let tr = transforms(planner, &t, &e[start * ny..(start + len) * ny], (ny, q));
        let d = c.map(|c| {
            let sub = DMatrix::from_fn(q, q, |i, j| c[(cols[i], cols[j])]);
            fitted_share(planner, block, &tr, (ny, q), &sub)
        });
        let local = middle(&tr, d.as_deref(), (ny, q));
        for a in 0..q {
            for b in a..q {
                f[(cols[a], cols[b])] += local[(a, b)];
                if a != b {
                    f[(cols[b], cols[a])] += local[(a, b)];
                }
            }
        }
        start += len;
    }
    let cov = minv * f * minv;
    0.5 * (&cov + cov.transpose())
}

/// The spectral coloured-residual covariance of the check (module doc): `s` the sensitivities,
/// `e` the residuals (`N × ny`), `w` the weights `R⁻¹` per output, `minv` = `M⁻¹`; `None` when
/// a diagonal element comes out non-positive or not finite.
pub(super) fn spectral(
    s: &Sensitivities,
    e: &[f64],
    w: &[f64],
    minv: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let mut planner = FftPlanner::<f64>::new();
    let mut c = pass(&mut planner, s, e, w, minv, None);
    for _ in 0..FITTED_SHARE_PASSES {
        c = pass(&mut planner, s, e, w, minv, Some(&c));
    }
    (0..c.nrows()).all(|i| c[(i, i)] > 0.0 && c[(i, i)].is_finite()).then_some(c)
}
