//! The spectral form of the coloured-residual covariance: the sandwich's middle term as an
//! integral over frequency of the weighted sensitivities' transforms and a multitaper
//! estimate of the residuals' cross-spectral matrix.
//!
//! For noise `v` with autocovariance `Γ(k) = E[v_i v_{i−k}ᵀ]` and spectral density
//! `Φ(ω) = Σ_k Γ(k) e^{−iωk}`, the middle term of the sandwich is exactly
//!
//! ```text
//! F = Σ_i Σ_j T_iᵀ Γ(i − j) T_j = (1/2π) ∫ T̃(ω)ᴴ Φ(ω) T̃(ω) dω,   T̃(ω) = Σ_i T_i e^{−iωi}
//! ```
//!
//! (`T = R⁻¹S`, within a manoeuvre). `Φ` is estimated with `K` sine tapers (Riedel &
//! Sidorenko, "Minimum bias multiple taper spectral estimation", *IEEE Trans. Signal
//! Processing* 43(1), 1995; Percival & Walden, *Spectral Analysis for Physical Applications*,
//! 1993, ch. 7):
//!
//! ```text
//! h_k(i) = √(2/(L+1)) sin(π k (i+1)/(L+1)),   Φ̂(ω) = (1/K) Σ_k ẽ_k(ω) ẽ_k(ω)ᴴ,   ẽ_k = DFT(h_k e)
//! ```
//!
//! an average of `K` nearly independent tapered periodograms, smoothing over a half-bandwidth
//! of `(K + 1)/(2(L + 1))` cycles per sample, with no model of the noise. Its autocovariance has
//! lags below `L`, so with the transforms zero-padded to `P ≥ 2L` samples the sum over the `P`
//! frequencies is the integral exactly (no circular wrap); real signals need only `ω ∈ [0, π]`.
//! `P` is the power of two at or above `2L`: `2L` itself often has a large prime factor (a
//! 600,001-sample record: 2·19·23·1373), where the FFT falls back to far slower algorithms.
//!
//! **Fitted share.** The residuals are the noise minus the part the fit took into `θ̂`,
//! `e = v − S δθ`; their tapered periodograms lack that part's, `(h_k S)~ C (h_k S)~ᴴ` for a
//! parameter covariance `C`, which is added back and the covariance recomputed
//! ([`super::FITTED_SHARE_PASSES`] passes of the fixed point, as in the prewhitened form).
//!
//! **Why it is there** (docs/uncertainty.md, "Output error: the spectral coloured-residual
//! σ"): the prewhitening vector autoregression (`super::prewhitened`) is exact for
//! autoregressive noise but not robust to noise that is not: on a least-squares fit with a
//! lightly damped resonance driven by slow noise, with or without white sensor noise (the kind
//! of residual output error leaves in turbulence), its σ came out 0.71–12.5 times the exact
//! value, the multitaper one 0.77–1.36 (tests below). On slow autoregressive noise the
//! multitaper form is the one that is short (a correlation time of a sixth of the window,
//! `a = 0.995`: 0.66–1.03 against 0.92–1.00), as its bandwidth cannot resolve a spectral peak
//! narrower than itself, and at 0 Hz it has only `K` degrees of freedom.
//!
//! Frequencies where every parameter's weighted sensitivity is below `10⁻⁹/(P/2+1)` of its own
//! largest value are skipped (they carry less than 10⁻⁹ of its sensitivity energy).
//!
//! Memory: one manoeuvre at a time. The fitted share of each pass needs the covariance of the
//! pass before over every manoeuvre, so the passes run outside the manoeuvres and a
//! manoeuvre's transforms are made anew in each pass (two real columns per complex FFT, as in
//! `lags`); what is held is one manoeuvre's transforms, four to eight times its sensitivities'
//! own storage (complex, half spectrum of a `P`-point transform, `2L ≤ P < 4L`). A record of
//! many manoeuvres costs no more than its longest one.

use super::lags::half_spectra;
use nalgebra::DMatrix;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex64 as C64;
use std::vec;
use std::vec::Vec;

/// Number `K` of sine tapers: 2K degrees of freedom per frequency and a half-bandwidth of
/// `(K + 1)/(2(L + 1))` cycles per sample (a 20-s window at 100 Hz: 0.1 Hz). In the 200-run
/// output-error campaign K = 2, 3 and 5 each gave 6 of 11 primary derivatives at ≥ 90 %
/// coverage, per derivative within 4 points of each other (docs/uncertainty.md); 3 is the
/// usual compromise of bias and variance (Percival & Walden §7.1).
pub(crate) const TAPERS: usize = 3;

/// Skipped frequencies: below this fraction, divided by `P/2 + 1`, of every parameter's largest
/// weighted-sensitivity energy.
const NEGLIGIBLE: f64 = 1e-9;

/// The transforms of one manoeuvre at the frequencies kept, frequency-major.
struct Transforms {
    /// The manoeuvre's samples.
    samples: core::ops::Range<usize>,
    /// The kept frequencies, indices into the `P`-point DFT (`0..=P/2`, [`padded`]).
    kept: Vec<usize>,
    /// Weight of each kept frequency in the sum (`2/P` inside `(0, π)`, `1/P` at the ends).
    weight: Vec<f64>,
    /// The residuals' multitaper cross-spectral matrix `Φ̂`, `[j][a·ny + b]`.
    phi: Vec<C64>,
    /// Weighted sensitivities, `[j][a·n + p]`.
    t: Vec<C64>,
}

/// Sine taper `k` (from 0) of a manoeuvre of `len` samples at sample `i` (module doc).
pub(crate) fn taper(k: usize, i: usize, len: usize) -> f64 {
    let l1 = len as f64 + 1.0;
    (2.0 / l1).sqrt() * (core::f64::consts::PI * (k + 1) as f64 * (i + 1) as f64 / l1).sin()
}

/// The transform length `P` for a manoeuvre of `len` samples: the power of two at or above
/// `2·len` (module doc).
pub(crate) fn padded(len: usize) -> usize {
    (2 * len).max(2).next_power_of_two()
}

/// The [`TAPERS`] tapered copies of `x` (`len × ncol` row-major) side by side:
/// `len × (TAPERS·ncol)`, column `k·ncol + c` = `h_k(i) x[i, c]`.
pub(crate) fn tapered(x: &[f64], ncol: usize) -> Vec<f64> {
    let len = x.len() / ncol.max(1);
    let mut out = Vec::with_capacity(x.len() * TAPERS);
    for (i, xi) in x.chunks_exact(ncol).enumerate() {
        for k in 0..TAPERS {
            let h = taper(k, i, len);
            out.extend(xi.iter().map(|v| h * v));
        }
    }
    out
}

/// The transforms of the manoeuvre `samples` (`t` the weighted sensitivities `N × ny × n`,
/// `e` residuals `N × ny`) at the frequencies kept, and the residuals' `Φ̂` (module doc).
fn transforms(
    planner: &mut FftPlanner<f64>,
    t: &[f64],
    e: &[f64],
    (ny, n): (usize, usize),
    samples: core::ops::Range<usize>,
) -> Transforms {
    let len = samples.len();
    let p = padded(len);
    let n_freq = p / 2 + 1;
    let row = ny * n;
    // Weighted sensitivities first: they decide which frequencies are kept. `[a·n + p][m]`.
    let t_all = half_spectra(planner, &t[samples.start * row..samples.end * row], row, p);
    let energy = |m: usize, q: usize| (0..ny).map(|a| t_all[a * n + q][m].norm_sqr()).sum::<f64>();
    let peak: Vec<f64> =
        (0..n).map(|q| (0..n_freq).map(|m| energy(m, q)).fold(0.0, f64::max)).collect();
    let cut = NEGLIGIBLE / n_freq as f64;
    let kept: Vec<usize> = (0..n_freq)
        .filter(|&m| (0..n).any(|q| peak[q] > 0.0 && energy(m, q) > cut * peak[q]))
        .collect();
    let weight =
        kept.iter().map(|&m| if m == 0 || m == p / 2 { 1.0 } else { 2.0 } / p as f64).collect();
    // Sized up front: collected from a `flat_map` the vector grows by doubling, to twice the
    // kept transforms and a copy of them at each growth.
    let mut t_kept: Vec<C64> = Vec::with_capacity(kept.len() * t_all.len());
    t_kept.extend(kept.iter().flat_map(|&m| t_all.iter().map(move |c| c[m])));
    drop(t_all);
    // Φ̂ = (1/K) Σ_k ẽ_k ẽ_kᴴ, all tapers' transforms at once (`[k·ny + a][m]`).
    let e_all = half_spectra(
        planner,
        &tapered(&e[samples.start * ny..samples.end * ny], ny),
        TAPERS * ny,
        p,
    );
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
    Transforms { samples, kept, weight, phi, t: t_kept }
}

/// A square root `L` of the covariance `C = L Lᵀ` (`L = V √Λ` from the eigenvectors of `C`,
/// negative rounding clipped), for [`fitted_share`].
fn square_root(c: &DMatrix<f64>) -> DMatrix<f64> {
    let eig = c.clone().symmetric_eigen();
    let mut l = eig.eigenvectors;
    for (q, lam) in eig.eigenvalues.iter().enumerate() {
        let r = lam.max(0.0).sqrt();
        l.column_mut(q).iter_mut().for_each(|v| *v *= r);
    }
    l
}

/// The fitted share `(1/K) Σ_k (h_k S)~ C (h_k S)~ᴴ` at the kept frequencies of `tr`
/// (`[j][a·ny + b]`, `s` the sensitivities `N × ny × n`), one taper at a time. With
/// `C = L Lᵀ` ([`square_root`]) it is `(1/K) Σ_k G_k G_kᴴ` with `G_k` the transform of
/// `h_k S L`: `ny²·n` per frequency and taper instead of `ny·n² + ny²·n`.
fn fitted_share(
    planner: &mut FftPlanner<f64>,
    s: &[f64],
    tr: &Transforms,
    (ny, n): (usize, usize),
    l: &DMatrix<f64>,
) -> Vec<C64> {
    let (start, len) = (tr.samples.start, tr.samples.len());
    // S_i L (ny × n) for the manoeuvre's samples.
    let mut sl = vec![0.0; len * ny * n];
    for i in 0..len {
        for a in 0..ny {
            let row = &s[((start + i) * ny + a) * n..][..n];
            for q in 0..n {
                sl[(i * ny + a) * n + q] =
                    row.iter().zip(l.column(q).iter()).map(|(x, y)| x * y).sum();
            }
        }
    }
    let p = padded(len);
    let mut d = vec![C64::new(0.0, 0.0); tr.kept.len() * ny * ny];
    for k in 0..TAPERS {
        let h: Vec<f64> =
            sl.iter().enumerate().map(|(idx, v)| taper(k, idx / (ny * n), len) * v).collect();
        let g = half_spectra(planner, &h, ny * n, p); // `[a·n + q][m]`
        for (dj, &m) in d.chunks_exact_mut(ny * ny).zip(&tr.kept) {
            for a in 0..ny {
                for b in 0..ny {
                    let acc: C64 = (0..n).map(|q| g[a * n + q][m] * g[b * n + q][m].conj()).sum();
                    dj[a * ny + b] += acc / TAPERS as f64;
                }
            }
        }
    }
    d
}

/// Adds one manoeuvre's share of the middle term, `Σ_j w_j Re(T̃ᴴ (Φ̂ + D) T̃)` over its kept
/// frequencies, to `f`; `D` its fitted share (`None`: none).
fn add_middle(f: &mut DMatrix<f64>, man: &Transforms, d: Option<&[C64]>, (ny, n): (usize, usize)) {
    let mut phi = vec![C64::new(0.0, 0.0); ny * ny];
    let mut g = vec![C64::new(0.0, 0.0); ny * n];
    for (j, &wm) in man.weight.iter().enumerate() {
        let t = &man.t[j * ny * n..(j + 1) * ny * n];
        phi.copy_from_slice(&man.phi[j * ny * ny..(j + 1) * ny * ny]);
        if let Some(d) = d {
            for (pv, dv) in phi.iter_mut().zip(&d[j * ny * ny..(j + 1) * ny * ny]) {
                *pv += dv;
            }
        }
        // G = Φ T̃ (ny × n); F += w Re(T̃ᴴ G).
        for a in 0..ny {
            for p in 0..n {
                g[a * n + p] = (0..ny).map(|b| phi[a * ny + b] * t[b * n + p]).sum();
            }
        }
        for p in 0..n {
            for q in p..n {
                let acc: f64 = (0..ny).map(|a| (t[a * n + p].conj() * g[a * n + q]).re).sum();
                f[(p, q)] += wm * acc;
            }
        }
    }
}

/// The spectral coloured-residual covariance (module doc), arguments as
/// [`super::covariance`]: `s` sensitivities `N × ny × n`, `e` residuals `N × ny`, `w` the
/// weights `R⁻¹` (diagonal), `lengths` samples per manoeuvre, `minv` = `M⁻¹`. The `lag` of
/// the result is 0 (no lag sum).
///
/// Each pass of the fitted share needs the covariance of the pass before over all
/// manoeuvres, so the passes run outside the manoeuvres and each manoeuvre's transforms are
/// made anew in every pass: memory is that of one manoeuvre, not of the record.
pub(crate) fn covariance(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
) -> super::Coloured {
    covariance_until(s, e, w, lengths, minv, super::NEVER).unwrap_or_else(|| unreachable!())
}

/// [`covariance`], given up (`None`) once `stop` asks (looked at before each manoeuvre's
/// transforms and its fitted share, in every pass).
pub(crate) fn covariance_until(
    s: &[f64],
    e: &[f64],
    w: &[f64],
    lengths: &[usize],
    minv: &DMatrix<f64>,
    stop: super::Stop,
) -> Option<super::Coloured> {
    let ny = w.len();
    let n = minv.nrows();
    let t = super::weighted_sensitivities(s, w, n);
    let mut planner = FftPlanner::<f64>::new();
    let mut one_pass = |root: Option<&DMatrix<f64>>| {
        let mut f = DMatrix::<f64>::zeros(n, n);
        let mut start = 0;
        for &len in lengths {
            if len > 0 {
                if stop() {
                    return None;
                }
                let tr = transforms(&mut planner, &t, e, (ny, n), start..start + len);
                if stop() {
                    return None;
                }
                let d = root.map(|l| fitted_share(&mut planner, s, &tr, (ny, n), l));
                add_middle(&mut f, &tr, d.as_deref(), (ny, n));
            }
            start += len;
        }
        for p in 0..n {
            for q in 0..p {
                f[(p, q)] = f[(q, p)];
            }
        }
        Some(super::Coloured::new(minv * f * minv, 0))
    };
    let mut col = one_pass(None)?;
    for _ in 0..super::FITTED_SHARE_PASSES {
        let root = square_root(&col.full);
        col = one_pass(Some(&root))?;
    }
    Some(col)
}

#[cfg(test)]
mod tests {
    use super::super::tests::{exact, regression};
    use nalgebra::{DMatrix, DVector};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use std::vec::Vec;

    /// Noise `v = x + σ_w w`: `x` a resonance (natural frequency `omega` rad/s, damping
    /// `zeta`, at 100 Hz) driven by AR(1) noise of pole `a_g` (the turbulence), `w` white with
    /// `σ_w` a fraction `white` of `x`'s standard deviation (sensor noise). Returns the
    /// impulse response of `x` to the driving noise, the two resonance coefficients and the
    /// white standard deviation.
    fn resonance(a_g: f64, omega: f64, zeta: f64, white: f64) -> (Vec<f64>, [f64; 2], f64) {
        let dt = 0.01;
        let r = (-zeta * omega * dt).exp();
        let th = omega * (1.0 - zeta * zeta).sqrt() * dt;
        let phi = [2.0 * r * th.cos(), -r * r];
        let mut g = 0.0;
        let mut h = vec![0.0; 40_000];
        for k in 0..h.len() {
            g = if k == 0 { 1.0 } else { a_g * g };
            h[k] = g
                + if k >= 1 { phi[0] * h[k - 1] } else { 0.0 }
                + if k >= 2 { phi[1] * h[k - 2] } else { 0.0 };
        }
        let var_x: f64 = h.iter().map(|v| v * v).sum();
        (h, phi, white * var_x.sqrt())
    }

    /// Mean spectral and prewhitened σ over `runs` realisations of [`resonance`] noise on the
    /// regression of `super::super::tests::regression`, each from its own residuals, as
    /// ratios to the exact σ `sqrt diag (XᵀX)⁻¹ XᵀΓX (XᵀX)⁻¹`.
    fn ratios(a_g: f64, omega: f64, zeta: f64, white: f64, runs: usize) -> [[f64; 3]; 2] {
        let (x, lengths, minv) = regression();
        let n = x.len() / 3;
        let xm = DMatrix::from_row_slice(n, 3, &x);
        let (h, phi, sw) = resonance(a_g, omega, zeta, white);
        let mut gamma: Vec<f64> =
            (0..1200).map(|k| h.iter().zip(&h[k..]).map(|(a, b)| a * b).sum()).collect();
        gamma[0] += sw * sw;
        let ex = exact(&x, &lengths, &minv, &gamma);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let n01 = Normal::new(0.0, 1.0).unwrap();
        let mut out = [[0.0; 3]; 2];
        for _ in 0..runs {
            let mut v = Vec::with_capacity(n);
            for &len in &lengths {
                let (mut g1, mut x1, mut x2) = (0.0, 0.0, 0.0);
                for i in 0..len + 20_000 {
                    let g = a_g * g1 + n01.sample(&mut rng);
                    let xi = phi[0] * x1 + phi[1] * x2 + g;
                    (g1, x2, x1) = (g, x1, xi);
                    if i >= 20_000 {
                        v.push(xi + sw * n01.sample(&mut rng));
                    }
                }
            }
            let y = DVector::from_vec(v);
            let theta = &minv * xm.transpose() * &y;
            let e: Vec<f64> = (&y - &xm * theta).iter().copied().collect();
            let sp = super::covariance(&x, &e, &[1.0], &lengths, &minv).full;
            let pw = super::super::prewhitened(&x, &e, &[1.0], &lengths, &minv, 200).coloured.full;
            for i in 0..3 {
                out[0][i] += sp[(i, i)].max(0.0).sqrt() / ex[(i, i)].sqrt() / runs as f64;
                out[1][i] += pw[(i, i)].max(0.0).sqrt() / ex[(i, i)].sqrt() / runs as f64;
            }
        }
        out
    }

    /// The multitaper σ against the exact σ of least squares (a constant, a 0.1-Hz and a
    /// 0.8-Hz sinusoid; manoeuvres of 1,200 and 800 samples at 100 Hz) on noise of the kind
    /// output error leaves in turbulence: a lightly damped resonance driven by slow noise,
    /// plus white sensor noise, and a pure resonance. The mean over 60 realisations lies in
    /// 0.75–1.4 of the exact σ for every coefficient (measured 0.77–1.36: the taper bandwidth,
    /// 0.19–0.28 Hz on these short manoeuvres, smooths a sharp peak into its neighbours, high
    /// next to it and low under it), and closer to it than the prewhitened form in every case
    /// (measured 0.71–12.5: near-unit resonance poles make its recolouring `1/|A(e^{iω})|²`
    /// amplify small coefficient errors, and an autoregression cannot carry a resonance and a
    /// white floor together).
    #[test]
    fn spectral_sigma_matches_exact_covariance_of_resonance_plus_white_noise() {
        for (a_g, omega, zeta, white, label) in [
            (0.0, 2.5, 0.2, 0.0, "resonance 2.5 rad/s, ζ 0.2, white drive"),
            (0.99, 2.5, 0.1, 0.3, "resonance 2.5 rad/s, ζ 0.1, AR(1) 0.99 drive, white 0.3"),
            (0.98, 2.5, 0.2, 1.0, "resonance 2.5 rad/s, ζ 0.2, AR(1) 0.98 drive, white 1.0"),
            (0.98, 1.0, 0.5, 0.3, "resonance 1 rad/s, ζ 0.5, AR(1) 0.98 drive, white 0.3"),
        ] {
            let [sp, pw] = ratios(a_g, omega, zeta, white, 60);
            std::println!(
                "{label}: spectral/exact {:.3} {:.3} {:.3}; prewhitened/exact {:.3} {:.3} {:.3}",
                sp[0],
                sp[1],
                sp[2],
                pw[0],
                pw[1],
                pw[2]
            );
            for (i, r) in sp.iter().enumerate() {
                assert!((0.75..1.4).contains(r), "{label} θ{i}: spectral σ / exact σ {r}");
            }
            let worst = |v: &[f64; 3]| v.iter().map(|r| r.ln().abs()).fold(0.0, f64::max);
            assert!(
                worst(&sp) < worst(&pw),
                "{label}: spectral worst ratio {sp:?} not closer than prewhitened {pw:?}"
            );
        }
    }

    /// White noise: the multitaper σ is the Cramér–Rao σ `sqrt diag (XᵀX)⁻¹` within 6 % on
    /// average (its spectrum is flat; the Jensen bias of a square root of an average over six
    /// degrees of freedom per frequency is about 2 % at the constant, whose transform sits in
    /// one frequency).
    #[test]
    fn spectral_sigma_of_white_noise_is_the_cramer_rao_sigma() {
        let [sp, _] = ratios(0.0, 2.5, 0.2, 1e6, 60);
        for (i, r) in sp.iter().enumerate() {
            assert!((r - 1.0).abs() < 0.06, "white θ{i}: spectral σ / exact σ {r}");
        }
    }
}

#[cfg(test)]
mod cross_tests {
    use nalgebra::DMatrix;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use std::vec::Vec;

    /// Two outputs whose noise shares an AR(1) component with a lag between them (so the
    /// cross-covariance is not symmetric in the lag: `Γ₁₂(k) ≠ Γ₁₂(−k)`, which a conjugated
    /// cross-spectrum would get wrong), plus independent white noise of different variances,
    /// fitted by weighted least squares with unequal weights. The coefficient whose regressors
    /// are a sine on one output and a cosine on the other depends on the cross-spectrum's
    /// phase: its mean multitaper σ over 40 realisations is within 10 % of the exact
    /// `sqrt diag M⁻¹ (Σ_ij T_iᵀ Γ(i−j) T_j) M⁻¹` (measured 0.94), while the same sum with the
    /// cross-covariance mirrored in the lag (what a transposed cross-spectrum would estimate)
    /// is 37 % off, so the test sees the orientation. The two constants: 0.78–1.1 (measured
    /// 0.83, 0.85; below).
    #[test]
    fn spectral_sigma_of_two_outputs_with_lagged_cross_correlation() {
        let (len, lag, a, c2) = (2000usize, 40usize, 0.98f64, -0.8f64);
        let (s1, s2) = (0.3f64, 0.2f64);
        let w = [1.0 / 1.0, 1.0 / 0.5];
        let (ny, n) = (2usize, 3usize);
        // S_i (ny × n), row-major per sample.
        let mut s = Vec::with_capacity(len * ny * n);
        for i in 0..len {
            let t = i as f64 * 0.01;
            s.extend([1.0, (1.3 * t).sin(), (2.0 * t).cos(), 0.0, (1.3 * t).cos(), 1.0]);
        }
        let sm = |i: usize| DMatrix::from_row_slice(ny, n, &s[i * ny * n..(i + 1) * ny * n]);
        let wm = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&w));
        let mut m = DMatrix::<f64>::zeros(n, n);
        for i in 0..len {
            m += sm(i).transpose() * &wm * sm(i);
        }
        let minv = m.clone().try_inverse().unwrap();
        // Γ(k) = E[v_i v_{i−k}ᵀ], v₁ = g_i + s1 w, v₂ = c2 g_{i−lag} + s2 w'.
        let gamma_g = |k: isize| a.powi(k.unsigned_abs() as i32) / (1.0 - a * a);
        let gamma = |k: isize, mirrored: bool| {
            let l = lag as isize;
            let (g12, g21) = (c2 * gamma_g(k + l), c2 * gamma_g(k - l));
            let (g12, g21) = if mirrored { (g21, g12) } else { (g12, g21) };
            let white = if k == 0 { [s1 * s1, s2 * s2] } else { [0.0, 0.0] };
            DMatrix::from_row_slice(
                2,
                2,
                &[gamma_g(k) + white[0], g12, g21, c2 * c2 * gamma_g(k) + white[1]],
            )
        };
        let exact_sigma = |mirrored: bool| {
            let t: Vec<DMatrix<f64>> = (0..len).map(|i| &wm * sm(i)).collect();
            let mut f = DMatrix::<f64>::zeros(n, n);
            for i in 0..len {
                for j in 0..len {
                    f += t[i].transpose() * gamma(i as isize - j as isize, mirrored) * &t[j];
                }
            }
            let c = &minv * f * &minv;
            (0..n).map(|p| c[(p, p)].sqrt()).collect::<Vec<_>>()
        };
        let exact = exact_sigma(false);
        let mirrored = exact_sigma(true);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let n01 = Normal::new(0.0, 1.0).unwrap();
        let runs = 40;
        let mut mean = [0.0; 3];
        for _ in 0..runs {
            let mut g = vec![0.0; len + lag];
            let mut prev = n01.sample(&mut rng) / (1.0 - a * a).sqrt();
            for gv in g.iter_mut() {
                prev = a * prev + n01.sample(&mut rng);
                *gv = prev;
            }
            // v₁(i) = g(i + lag) (index shift so that v₂ sees g lag samples earlier).
            let mut y = Vec::with_capacity(len * ny);
            for i in 0..len {
                y.push(g[i + lag] + s1 * n01.sample(&mut rng));
                y.push(c2 * g[i] + s2 * n01.sample(&mut rng));
            }
            // θ = 0: the data are the noise; fit and form residuals.
            let mut b = nalgebra::DVector::<f64>::zeros(n);
            for i in 0..len {
                b += sm(i).transpose()
                    * &wm
                    * nalgebra::DVector::from_column_slice(&y[i * 2..i * 2 + 2]);
            }
            let theta = &minv * b;
            let e: Vec<f64> = (0..len)
                .flat_map(|i| {
                    let r =
                        nalgebra::DVector::from_column_slice(&y[i * 2..i * 2 + 2]) - sm(i) * &theta;
                    [r[0], r[1]]
                })
                .collect();
            let cov = super::covariance(&s, &e, &w, &[len], &minv).full;
            for p in 0..n {
                mean[p] += cov[(p, p)].max(0.0).sqrt() / runs as f64;
            }
        }
        std::println!("exact {exact:?}, mirrored {mirrored:?}, spectral mean {mean:?}");
        // θ1 (sin on output 1, cos on output 2) carries the cross-spectrum's phase.
        let r1 = mean[1] / exact[1];
        assert!((r1 - 1.0).abs() < 0.1, "θ1: spectral / exact {r1}");
        assert!(
            (mirrored[1] / exact[1] - 1.0).abs() > 0.3,
            "the lagged cross-covariance does not matter here: {mirrored:?} vs {exact:?}"
        );
        // The constants (θ0 on output 1, θ2 on output 2) sit at the AR(1) noise's spectral
        // peak at 0 Hz, which the tapers' bandwidth flattens and the fitted share (a first-order
        // correction) only partly restores: measured 0.83 and 0.85.
        for p in [0, 2] {
            let r = mean[p] / exact[p];
            assert!((0.78..1.1).contains(&r), "θ{p}: spectral / exact {r}");
        }
    }
}
