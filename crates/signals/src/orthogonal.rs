//! Orthogonal phase-optimised multisines: one multisine per control surface, mutually
//! orthogonal over the base period, so the surfaces can be excited **simultaneously** and their
//! effects still separated (E. A. Morelli, "Multiple input design for real-time parameter
//! estimation in the frequency domain", 13th IFAC Symposium on System Identification, 2003;
//! Klein & Morelli, *Aircraft System Identification*, AIAA 2006, §9.3 "orthogonal
//! phase-optimized multisine inputs").
//!
//! # Design (for a set of `n` inputs)
//! 1. **Disjoint harmonic sets.** The pool of harmonics `k₁ < k₂ < … < k_M` of the base
//!    frequency `ω₀ = 2π/T` is dealt out in turn: input `j` (0-based) gets `k_i` for every
//!    `i ≡ j (mod n)`, so each input spans the whole band and no two share a frequency.
//!    Sinusoids of different harmonics are orthogonal over `T`, hence so are the inputs:
//!    `∫₀ᵀ u_i u_j dt = 0` for `i ≠ j`, whatever the phases.
//! 2. **Equal power** in each of an input's `N_j` components, **Schroeder phases**
//!    `φ_m = −π m(m−1)/N_j` (Schroeder 1970) as the start of the phase optimisation.
//! 3. **Phase optimisation** for a low relative peak factor
//!    `RPF = (max u − min u)/(2√2 rms u)`: the time–frequency swapping ("clipping") iteration of
//!    P. Guillaume, J. Schoukens, R. Pintelon, I. Kollár, "Crest-factor minimization using
//!    nonlinear Chebyshev approximation methods", IEEE Trans. Instrum. Meas. 40(6), 1991
//!    (after Van der Ouderaa, Schoukens, Renneboog 1988): sample one period, clip the peaks,
//!    keep the phases of the clipped signal's components at the input's harmonics, restore the
//!    equal amplitudes; the phases of lowest RPF found are kept ([`CLIPPING_ITERATIONS`](crate::orthogonal::CLIPPING_ITERATIONS)
//!    iterations, deterministic). This is the role of Morelli's simplex phase optimisation.
//! 4. **Zero start**: each input is shifted in time (which keeps its spectrum, RPF and the
//!    orthogonality) so that it starts at 0, as Morelli does, to avoid a step at switch-on.
//! 5. **Peak scaling**: the per-component amplitude is chosen so that `max_t |u_j(t)|` equals the
//!    requested **peak** amplitude of input `j` (the deflection limit a flight-test engineer
//!    sets), measured on a grid of at least 64 points per period of the highest harmonic.

use crate::error::{SignalError, positive};
use crate::inputs::Multisine;

/// Iterations of the clipping phase optimisation (step 3 of the module doc).
pub const CLIPPING_ITERATIONS: usize = 60;

/// Grid points per base period used for peak, RPF and phase computations: at least 64 per
/// period of the highest harmonic, and at least 1024.
fn grid_points(k_max: u32) -> usize {
    (64 * k_max as usize).max(1024)
}

/// The harmonics of member `index` of an `inputs`-member orthogonal set drawn from `pool`
/// (sorted ascending first): every `inputs`-th entry starting at `index`.
///
/// # Errors
/// [`SignalError::InvalidList`] for an empty pool, a zero or repeated harmonic, one above
/// [`MAX_HARMONIC`](crate::inputs::MAX_HARMONIC), `inputs = 0`, `index ≥ inputs`, or a member
/// left without any harmonic.
pub fn orthogonal_harmonics(
    pool: &[u32],
    inputs: usize,
    index: usize,
) -> Result<Vec<u32>, SignalError> {
    let bad = |field: &'static str, reason: String| SignalError::InvalidList { field, reason };
    if inputs == 0 {
        return Err(bad("inputs", "an orthogonal set needs at least one input".into()));
    }
    if index >= inputs {
        return Err(bad("index", format!("{index} is not below inputs = {inputs}")));
    }
    if let Some((i, &k)) = pool.iter().enumerate().find(|(_, k)| **k > crate::inputs::MAX_HARMONIC)
    {
        return Err(bad("harmonics", crate::inputs::harmonic_too_high(i, k)));
    }
    let mut sorted = pool.to_vec();
    sorted.sort_unstable();
    if sorted.first() == Some(&0) {
        return Err(bad("harmonics", "harmonic 0 (a constant) is not an excitation".into()));
    }
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(bad("harmonics", format!("harmonic {} repeated", w[0])));
    }
    let mine: Vec<u32> = sorted.iter().copied().skip(index).step_by(inputs).collect();
    if mine.is_empty() {
        return Err(bad(
            "harmonics",
            format!("{} harmonics cannot give input {index} of {inputs} any", sorted.len()),
        ));
    }
    Ok(mine)
}

/// `cos(2π m/n)`, `sin(2π m/n)` for `m = 0 … n−1`: every grid value of every harmonic is a
/// lookup, `k·i mod n`.
struct Grid {
    cos: Vec<f64>,
    sin: Vec<f64>,
}

impl Grid {
    fn new(n: usize) -> Self {
        let (sin, cos) =
            (0..n).map(|m| (core::f64::consts::TAU * m as f64 / n as f64).sin_cos()).unzip();
        Self { cos, sin }
    }

    fn n(&self) -> usize {
        self.cos.len()
    }

    /// `Σ_m cos(k_m ω₀ t_i + φ_m)` on the grid `t_i = i T/n` (unit amplitude per component).
    fn sample(&self, harmonics: &[u32], phases: &[f64]) -> Vec<f64> {
        let n = self.n();
        let cs: Vec<(f64, f64)> = phases.iter().map(|p| p.sin_cos()).collect();
        (0..n)
            .map(|i| {
                harmonics
                    .iter()
                    .zip(&cs)
                    .map(|(&k, &(sp, cp))| {
                        let m = (k as usize * i) % n;
                        // cos(a + φ) = cos a cos φ − sin a sin φ
                        self.cos[m] * cp - self.sin[m] * sp
                    })
                    .sum()
            })
            .collect()
    }

    /// Phases of `u`'s components at `harmonics` (direct DFT at those bins).
    fn phases_of(&self, u: &[f64], harmonics: &[u32]) -> Vec<f64> {
        let n = self.n();
        harmonics
            .iter()
            .map(|&k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (i, v) in u.iter().enumerate() {
                    let m = (k as usize * i) % n;
                    re += v * self.cos[m];
                    im -= v * self.sin[m];
                }
                // u ≈ Σ cos(k x + φ) has DFT bin (N/2)·e^{iφ}.
                im.atan2(re)
            })
            .collect()
    }
}

/// Relative peak factor `(max − min)/(2√2 rms)` of a sampled period.
fn rpf(u: &[f64]) -> f64 {
    let (lo, hi) =
        u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let rms = (u.iter().map(|v| v * v).sum::<f64>() / u.len() as f64).sqrt();
    (hi - lo) / (2.0 * core::f64::consts::SQRT_2 * rms)
}

/// Step 3 of the module doc: phases of minimum RPF found by the clipping iteration, starting
/// from Schroeder's phases.
fn optimised_phases(harmonics: &[u32]) -> Vec<f64> {
    let n_h = harmonics.len();
    let mut phases: Vec<f64> =
        (1..=n_h).map(|m| -core::f64::consts::PI * (m * (m - 1)) as f64 / n_h as f64).collect();
    if n_h == 1 {
        return phases;
    }
    let grid = Grid::new(grid_points(*harmonics.iter().max().unwrap_or(&1)));
    let mut best = phases.clone();
    let mut best_rpf = rpf(&grid.sample(harmonics, &phases));
    for it in 0..CLIPPING_ITERATIONS {
        let u = grid.sample(harmonics, &phases);
        let peak = u.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // Clip progressively less hard as the iteration proceeds (0.8 → 0.95 of the peak).
        let level = peak * (0.8 + 0.15 * it as f64 / CLIPPING_ITERATIONS as f64);
        let clipped: Vec<f64> = u.iter().map(|v| v.clamp(-level, level)).collect();
        phases = grid.phases_of(&clipped, harmonics);
        let r = rpf(&grid.sample(harmonics, &phases));
        if r < best_rpf {
            best_rpf = r;
            best = phases.clone();
        }
    }
    best
}

/// Step 4 of the module doc: the phases of `u(t + τ₀)`, where `τ₀` is the first zero crossing
/// of `u` in the period (found on the grid, refined by bisection).
fn zero_start(harmonics: &[u32], phases: &[f64]) -> Vec<f64> {
    let f = |x: f64| -> f64 {
        harmonics.iter().zip(phases).map(|(&k, &p)| (k as f64 * x + p).cos()).sum()
    };
    let n = grid_points(*harmonics.iter().max().unwrap_or(&1));
    let dx = core::f64::consts::TAU / n as f64;
    let mut x0 = 0.0;
    for i in 0..n {
        let (a, b) = (i as f64 * dx, (i + 1) as f64 * dx);
        if f(a) == 0.0 {
            x0 = a;
            break;
        }
        if f(a) * f(b) < 0.0 {
            let (mut lo, mut hi) = (a, b);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if f(lo) * f(mid) <= 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            x0 = 0.5 * (lo + hi);
            break;
        }
    }
    harmonics.iter().zip(phases).map(|(&k, &p)| p + k as f64 * x0).collect()
}

/// Member `index` of an orthogonal phase-optimised multisine set (module doc): `inputs`
/// members share the harmonic `pool` of base period `base_period_s` (s); this one has **peak**
/// amplitude `peak_amplitude` (caller's units, e.g. rad; its sign flips the signal), starts at
/// `start_s` (s) with value 0 and lasts `duration_s` (s; `None` = forever, repeating with period
/// `base_period_s`).
///
/// Every member depends only on `(pool, inputs, index)` and its own amplitude, so the members
/// can be built independently (e.g. one per scenario input entry) and stay orthogonal as long as
/// they share `base_period_s`, `pool`, `inputs` and `start_s`.
///
/// # Errors
/// [`SignalError::InvalidParameter`] for a non-finite amplitude or start, a non-positive
/// period or duration; the errors of [`orthogonal_harmonics`].
pub fn orthogonal_multisine(
    peak_amplitude: f64,
    base_period_s: f64,
    pool: &[u32],
    inputs: usize,
    index: usize,
    start_s: f64,
    duration_s: Option<f64>,
) -> Result<Multisine, SignalError> {
    positive("base_period_s", base_period_s)?;
    if !peak_amplitude.is_finite() {
        return Err(SignalError::InvalidParameter {
            field: "amplitude",
            value: peak_amplitude,
            reason: "must be finite",
        });
    }
    let harmonics = orthogonal_harmonics(pool, inputs, index)?;
    let phases = zero_start(&harmonics, &optimised_phases(&harmonics));
    let grid = Grid::new(grid_points(*harmonics.iter().max().unwrap_or(&1)));
    let unit_peak = grid.sample(&harmonics, &phases).iter().fold(0.0f64, |a, v| a.max(v.abs()));
    // unit_peak ≥ 1 for any non-empty set (the mean square is N/2 > 0), so the division is safe.
    Multisine::with_phases(
        peak_amplitude / unit_peak,
        base_period_s,
        &harmonics,
        &phases,
        start_s,
        duration_s,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InputSignal;

    fn set() -> Vec<Multisine> {
        let pool: Vec<u32> = (2..=16).collect();
        [1.0f64, 1.5, 2.0]
            .iter()
            .enumerate()
            .map(|(j, a)| {
                orthogonal_multisine(a.to_radians(), 10.0, &pool, 3, j, 0.0, None).unwrap()
            })
            .collect()
    }

    /// The three members are orthogonal over the base period: the discrete inner product on a
    /// grid finer than twice the highest harmonic equals the integral exactly (harmonics below
    /// the Nyquist bin are orthogonal on the grid), so it must vanish to rounding.
    #[test]
    fn analytic_members_are_mutually_orthogonal_over_the_period() {
        let s = set();
        let n = 4000;
        let u: Vec<Vec<f64>> = s
            .iter()
            .map(|m| (0..n).map(|i| m.value(10.0 * i as f64 / n as f64)).collect())
            .collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        for i in 0..3 {
            for j in 0..3 {
                let c = dot(&u[i], &u[j]) / (dot(&u[i], &u[i]) * dot(&u[j], &u[j])).sqrt();
                if i == j {
                    assert!((c - 1.0).abs() < 1e-12);
                } else {
                    assert!(c.abs() < 1e-10, "members {i}, {j}: normalised inner product {c:e}");
                }
            }
        }
        // Disjoint harmonic sets dealt out in turn.
        assert_eq!(
            orthogonal_harmonics(&(2..=16).collect::<Vec<_>>(), 3, 1).unwrap(),
            vec![3, 6, 9, 12, 15]
        );
    }

    /// Each member reaches exactly its requested peak deflection (checked on an independent,
    /// much finer grid), starts at zero, and keeps a low peak factor.
    #[test]
    fn analytic_members_have_the_requested_peak_and_start_at_zero() {
        for (m, want_deg) in set().iter().zip([1.0f64, 1.5, 2.0]) {
            let want = want_deg.to_radians();
            let peak = (0..200_000)
                .map(|i| m.value(10.0 * i as f64 / 200_000.0).abs())
                .fold(0.0f64, f64::max);
            assert!((peak - want).abs() < 2e-3 * want, "peak {peak} vs {want}");
            assert!(m.value(0.0).abs() < 1e-9 * want, "starts at {}", m.value(0.0));
            let u: Vec<f64> = (0..4000).map(|i| m.value(10.0 * i as f64 / 4000.0)).collect();
            eprintln!("member peak {want_deg}°: RPF {:.3}", rpf(&u));
            assert!(rpf(&u) < 1.3, "RPF {}", rpf(&u));
        }
    }

    /// The phase optimisation never returns a worse peak factor than Schroeder's phases.
    #[test]
    fn optimised_phases_no_worse_than_schroeder() {
        let h: Vec<u32> = vec![2, 5, 8, 11, 14];
        let grid = Grid::new(grid_points(14));
        let sch: Vec<f64> =
            (1..=5).map(|m| -core::f64::consts::PI * (m * (m - 1)) as f64 / 5.0).collect();
        let r0 = rpf(&grid.sample(&h, &sch));
        let r1 = rpf(&grid.sample(&h, &optimised_phases(&h)));
        eprintln!("RPF Schroeder {r0:.3}, optimised {r1:.3}");
        assert!(r1 <= r0, "optimised {r1} vs Schroeder {r0}");
    }

    #[test]
    fn bad_sets_are_errors_naming_the_field() {
        let e = orthogonal_harmonics(&[2, 3], 3, 2).unwrap_err().to_string();
        assert!(e.contains("harmonics"), "{e}");
        let e = orthogonal_harmonics(&[2, 3, 3], 2, 0).unwrap_err().to_string();
        assert!(e.contains("repeated"), "{e}");
        let e = orthogonal_harmonics(&[2, 3], 2, 2).unwrap_err().to_string();
        assert!(e.contains("index"), "{e}");
        assert!(orthogonal_multisine(f64::NAN, 10.0, &[1, 2], 2, 0, 0.0, None).is_err());
        assert!(orthogonal_multisine(1.0, 0.0, &[1, 2], 2, 0, 0.0, None).is_err());
    }
}
