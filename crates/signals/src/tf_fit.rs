//! Low-order equivalent systems: a transfer function with a time delay fitted to a measured
//! frequency response (MIL-STD-1797A appendix, "equivalent systems"; Tischler & Remple,
//! *Aircraft and Rotorcraft System Identification*, 2nd ed., 2012, ch. 11).
//!
//! **Model.** `T(s) = K · N(s)/D(s) · e^{−τs}` with `N`, `D` monic of the given orders, each a
//! product of quadratic factors `s² + b₁s + b₀` and, for an odd order, one first-order factor
//! `s + a`. A quadratic factor with `b₀ > 0` is a mode of natural frequency `ωn = √b₀` and
//! damping `ζ = b₁/(2√b₀)` (`ζ > 1`: two real roots). Frequencies are in rad/s, the
//! aeronautical convention for equivalent systems.
//!
//! **Cost** (MIL-STD-1797A; Tischler & Remple eq. 11.12):
//! `J = (20/n) Σ W_γ [W_g (|Ĥ| − |T|)²_dB + W_p (∠Ĥ − ∠T)²_deg]` over the `n` grid frequencies
//! in the band whose coherence is at least `min_coherence` (default 0.6, Tischler & Remple's
//! guideline), with `W_g = 1`, `W_p = 0.01745` and `W_γ = [1.58 (1 − e^{−γ²})]²`; the phase
//! difference is taken in (−180°, 180°]. `J ≤ 100` is a good fit by Tischler & Remple's
//! guideline (≤ 50 excellent).
//!
//! **Minimisation.** Levenberg–Marquardt on the `2n` weighted residuals whose squares sum to
//! `J`, Jacobian by central differences, from several starts (modes spread over the band, both
//! gain signs); the lowest cost wins. A start that stops at the iteration limit is reported
//! with its last iterate and `status = "max_iterations"`.
//!
//! **σ.** From the Gauss–Newton Hessian of the cost, `Cov = s² (JᵣᵀJᵣ)⁻¹` with `Jᵣ` the
//! residuals' Jacobian and `s² = J/(2n − p)` the residual variance per residual: the
//! least-squares covariance with the misfit as the noise level. (Tischler & Remple's
//! Cramér–Rao bound `√[(Hessian⁻¹)ᵢᵢ]` assumes the weights are the inverse noise variances;
//! the coherence weighting is not, so the misfit sets the scale here.) σ of ωn, ζ, roots and
//! the gain are propagated through their gradients. Checked against scatter on independent
//! magnitude and phase errors of equal weighted variance: ωn 1.02, ζ 1.06 × σ over 100 draws
//! (test `sigma_of_the_modes_matches_their_scatter_over_noise_draws`). Errors correlated across
//! frequency (a composite response's neighbouring points share data) are not covered.

use crate::spectral::PairResponse;
use nalgebra::{DMatrix, DVector};
use rustfft::num_complex::Complex64;

/// What to fit: `output/input:num/den[+delay][@lo:hi]`, e.g. `q/de:1/2+delay@1:10` (band in
/// rad/s).
#[derive(Debug, Clone, PartialEq)]
pub struct TfSpec {
    /// The text as given.
    pub text: String,
    /// Output channel.
    pub output: String,
    /// Input channel.
    pub input: String,
    /// Numerator order.
    pub num_order: usize,
    /// Denominator order (≥ 1).
    pub den_order: usize,
    /// Whether a time delay is fitted.
    pub delay: bool,
    /// Frequency band of the fit, rad/s; `None`: the whole response.
    pub band_rad_s: Option<(f64, f64)>,
}

impl TfSpec {
    /// Parses `output/input:num/den[+delay][@lo:hi]`.
    ///
    /// # Errors
    /// A message naming the text and the part that is wrong.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = |why: &str| {
            format!(
                "`{text}`: {why} (form: output/input:num/den[+delay][@lo:hi], e.g. q/de:1/2+delay@1:10)"
            )
        };
        let (pair, rest) = text.split_once(':').ok_or_else(|| bad("no `:`"))?;
        let (output, input) =
            pair.split_once('/').ok_or_else(|| bad("no `/` between output and input"))?;
        let (model, band) = match rest.split_once('@') {
            Some((m, b)) => (m, Some(b)),
            None => (rest, None),
        };
        let (orders, delay) = match model.strip_suffix("+delay") {
            Some(o) => (o, true),
            None => (model, false),
        };
        let (n, d) = orders.split_once('/').ok_or_else(|| bad("no `/` between the orders"))?;
        let num_order: usize =
            n.trim().parse().map_err(|_| bad("numerator order is not a number"))?;
        let den_order: usize =
            d.trim().parse().map_err(|_| bad("denominator order is not a number"))?;
        if den_order == 0 || den_order > 8 || num_order > den_order {
            return Err(bad("orders must satisfy 0 ≤ num ≤ den, 1 ≤ den ≤ 8"));
        }
        let band_rad_s = match band {
            None => None,
            Some(b) => {
                let (lo, hi) = b.split_once(':').ok_or_else(|| bad("band is not lo:hi"))?;
                let (lo, hi): (f64, f64) = (
                    lo.trim().parse().map_err(|_| bad("band start is not a number"))?,
                    hi.trim().parse().map_err(|_| bad("band end is not a number"))?,
                );
                if !(lo > 0.0 && hi > lo && hi.is_finite()) {
                    return Err(bad("band must satisfy 0 < lo < hi (rad/s)"));
                }
                Some((lo, hi))
            }
        };
        if output.trim().is_empty() || input.trim().is_empty() {
            return Err(bad("empty channel name"));
        }
        Ok(Self {
            text: text.to_string(),
            output: output.trim().to_string(),
            input: input.trim().to_string(),
            num_order,
            den_order,
            delay,
            band_rad_s,
        })
    }
}

/// Options of the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Lowest coherence of a frequency used.
    pub min_coherence: f64,
    /// Most Levenberg–Marquardt iterations per start.
    pub max_iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self { min_coherence: 0.6, max_iterations: 300 }
    }
}

/// One factor of the fitted numerator or denominator, with σ (`None` where not defined).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Factor {
    /// `first_order` (`s + a`) or `second_order` (`s² + 2ζωn s + ωn²`).
    pub kind: &'static str,
    /// Roots `[re, im]` (1/s): one for a first-order factor, two for a second-order one.
    pub roots: Vec<[f64; 2]>,
    /// Natural frequency, rad/s (`|root|` of a first-order factor; `√b₀` of a second-order one
    /// with `b₀ > 0`).
    pub wn_rad_s: Option<f64>,
    /// Its σ.
    pub wn_sigma_rad_s: Option<f64>,
    /// Damping ratio (second-order factors with `b₀ > 0`).
    pub zeta: Option<f64>,
    /// Its σ.
    pub zeta_sigma: Option<f64>,
    /// Time constant `1/a`, s (first-order factors with `a ≠ 0`).
    pub time_constant_s: Option<f64>,
}

/// The fitted transfer function (module doc) and how well it matches.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TfFit {
    /// Gain `K` of `K N(s)/D(s)` (output SI unit per input SI unit, times rad/s to the power
    /// `den − num`).
    pub gain: f64,
    /// Its σ.
    pub gain_sigma: Option<f64>,
    /// Time delay, s (`0` and σ `null` without `+delay`).
    pub delay_s: f64,
    /// Its σ, s.
    pub delay_sigma_s: Option<f64>,
    /// Numerator factors (zeros).
    pub zeros: Vec<Factor>,
    /// Denominator factors (poles).
    pub poles: Vec<Factor>,
    /// Mismatch cost `J` (module doc); ≤ 100 good.
    pub cost: f64,
    /// Frequencies used (`n`).
    pub frequencies_used: usize,
    /// Coherence threshold used.
    pub min_coherence: f64,
    /// Band used, rad/s.
    pub band_rad_s: (f64, f64),
    /// `converged` or `max_iterations` (the last iterate).
    pub status: &'static str,
    /// Iterations of the winning start.
    pub iterations: usize,
    /// The fitted model on the response's grid: magnitude, dB.
    pub model_magnitude_db: Vec<f64>,
    /// The fitted model on the response's grid: phase, deg.
    pub model_phase_deg: Vec<f64>,
}

/// Why a fit could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    /// Too few coherent frequencies in the band.
    #[error(
        "{used} frequencies in the band with coherence ≥ {min_coherence}: fewer than the {needed} the fit needs"
    )]
    TooFewFrequencies {
        /// Frequencies available.
        used: usize,
        /// Threshold.
        min_coherence: f64,
        /// Needed.
        needed: usize,
    },
}

/// The parameter layout of a spec: `[K, a (first-order num), b₁ b₀ … (num quadratics),
/// a (den), b₁ b₀ … (den), τ]`.
#[derive(Debug, Clone, Copy)]
struct Layout {
    num: usize,
    den: usize,
    delay: bool,
}

impl Layout {
    fn len(&self) -> usize {
        1 + self.num + self.den + usize::from(self.delay)
    }

    /// `K N(jω)/D(jω) e^{−jωτ}` at `w` rad/s.
    fn eval(&self, p: &[f64], w: f64) -> Complex64 {
        let s = Complex64::new(0.0, w);
        let poly = |order: usize, c: &[f64]| -> Complex64 {
            let mut v = Complex64::new(1.0, 0.0);
            let mut i = 0;
            if order % 2 == 1 {
                v *= s + c[0];
                i = 1;
            }
            while i < order {
                v *= s * s + s * c[i] + c[i + 1];
                i += 2;
            }
            v
        };
        let n = poly(self.num, &p[1..1 + self.num]);
        let d = poly(self.den, &p[1 + self.num..1 + self.num + self.den]);
        let tau = if self.delay { p[self.len() - 1] } else { 0.0 };
        p[0] * n / d * Complex64::from_polar(1.0, -w * tau)
    }
}

/// The measured points of the fit: `(ω rad/s, |Ĥ| dB, ∠Ĥ deg, √W_γ)`.
type Points = Vec<(f64, f64, f64, f64)>;

fn points(p: &PairResponse, band: (f64, f64), min_coherence: f64) -> Points {
    (0..p.frequency_hz.len())
        .filter_map(|k| {
            let w = 2.0 * std::f64::consts::PI * p.frequency_hz[k];
            let g = p.coherence[k];
            let ok = w >= band.0 * (1.0 - 1e-12)
                && w <= band.1 * (1.0 + 1e-12)
                && g >= min_coherence
                && p.re[k].is_finite()
                && p.im[k].is_finite();
            let h = Complex64::new(p.re[k], p.im[k]);
            ok.then(|| {
                (w, 20.0 * h.norm().log10(), h.arg().to_degrees(), 1.58 * (1.0 - (-g).exp()))
            })
        })
        .collect()
}

/// The weighted residuals whose squares sum to `J`.
fn residuals(l: &Layout, p: &[f64], pts: &Points) -> Vec<f64> {
    let scale = (20.0 / pts.len() as f64).sqrt();
    let wp = 0.01745f64.sqrt();
    let mut r = Vec::with_capacity(2 * pts.len());
    for &(w, db, deg, wg) in pts {
        let t = l.eval(p, w);
        let dphase = (deg - t.arg().to_degrees() + 180.0).rem_euclid(360.0) - 180.0;
        r.push(scale * wg * (db - 20.0 * t.norm().log10()));
        r.push(scale * wg * wp * dphase);
    }
    r
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

fn jacobian(l: &Layout, p: &[f64], pts: &Points) -> DMatrix<f64> {
    let r0 = residuals(l, p, pts);
    let mut j = DMatrix::zeros(r0.len(), p.len());
    for c in 0..p.len() {
        let h = 1e-6 * p[c].abs().max(1e-3);
        let (mut a, mut b) = (p.to_vec(), p.to_vec());
        a[c] += h;
        b[c] -= h;
        let (ra, rb) = (residuals(l, &a, pts), residuals(l, &b, pts));
        for i in 0..r0.len() {
            j[(i, c)] = (ra[i] - rb[i]) / (2.0 * h);
        }
    }
    j
}

/// Levenberg–Marquardt from `p0`: the parameters, cost, iterations and whether it converged.
fn levenberg_marquardt(
    l: &Layout,
    p0: Vec<f64>,
    pts: &Points,
    max_it: usize,
) -> (Vec<f64>, f64, usize, bool) {
    let mut p = p0;
    let mut r = residuals(l, &p, pts);
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    for it in 1..=max_it {
        let j = jacobian(l, &p, pts);
        let jtj = j.transpose() * &j;
        let g = j.transpose() * DVector::from_vec(r.clone());
        let mut improved = false;
        while lambda < 1e12 {
            let mut a = jtj.clone();
            for d in 0..a.nrows() {
                a[(d, d)] += lambda * jtj[(d, d)].max(1e-12);
            }
            let Some(mut step) = a.clone().lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let k = p.len() - 1;
            if l.delay && p[k] + step[k] < 0.0 {
                // The delay's bound is active: move it to 0 and solve for the others with it
                // held there (clamping the free step instead crawls along the bound).
                step = match bounded_step(&a, &g, k, -p[k]) {
                    Some(s) => s,
                    None => {
                        lambda *= 10.0;
                        continue;
                    }
                };
            }
            let trial: Vec<f64> = p.iter().zip(step.iter()).map(|(x, d)| x + d).collect();
            let rt = residuals(l, &trial, pts);
            let ct = cost(&rt);
            if ct.is_finite() && ct < c {
                let small = (c - ct) <= 1e-8 * c.max(1e-12);
                let tiny = step.iter().zip(&p).all(|(d, x)| d.abs() <= 1e-9 * x.abs().max(1e-6));
                p = trial;
                r = rt;
                c = ct;
                lambda = (lambda / 10.0).max(1e-12);
                improved = true;
                if small || tiny {
                    return (p, c, it, true);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            return (p, c, it, true);
        }
    }
    (p, c, max_it, false)
}

/// The damped Gauss–Newton step `a δ = −g` with component `k` held at `d_k`.
fn bounded_step(a: &DMatrix<f64>, g: &DVector<f64>, k: usize, d_k: f64) -> Option<DVector<f64>> {
    let n = g.len();
    let mut a2 = a.clone();
    let mut rhs = -g.clone();
    for i in 0..n {
        rhs[i] -= a[(i, k)] * d_k;
        a2[(i, k)] = 0.0;
        a2[(k, i)] = 0.0;
    }
    a2[(k, k)] = 1.0;
    rhs[k] = d_k;
    a2.lu().solve(&rhs)
}

/// The starts: modes spread over the band, zeros a decade lower, both gain signs; the gain
/// set so the mean magnitude matches.
fn starts(l: &Layout, pts: &Points) -> Vec<Vec<f64>> {
    let (lo, hi) = (pts[0].0, pts[pts.len() - 1].0);
    let mut out = Vec::new();
    let fill = |order: usize, w: f64, zeta: f64, v: &mut Vec<f64>| {
        if order % 2 == 1 {
            v.push(w);
        }
        for _ in 0..order / 2 {
            v.push(2.0 * zeta * w);
            v.push(w * w);
        }
    };
    for frac in [0.2, 0.4, 0.6, 0.8] {
        let w = lo * (hi / lo).powf(frac);
        for zeta in [0.3, 0.7] {
            for zw in [0.3, 1.0] {
                for sign in [1.0, -1.0] {
                    let mut p = vec![sign];
                    fill(l.num, w * zw, zeta, &mut p);
                    fill(l.den, w, zeta, &mut p);
                    if l.delay {
                        p.push(0.01);
                    }
                    let mean: f64 = pts
                        .iter()
                        .map(|&(w, db, _, _)| db - 20.0 * l.eval(&p, w).norm().log10())
                        .sum::<f64>()
                        / pts.len() as f64;
                    p[0] = sign * 10f64.powf(mean / 20.0);
                    out.push(p);
                }
            }
        }
    }
    out
}

/// Fits `spec` to the response `resp` (module doc).
///
/// # Errors
/// [`FitError::TooFewFrequencies`] when the band holds fewer coherent frequencies than twice
/// the parameters.
pub fn fit_transfer_function(
    resp: &PairResponse,
    spec: &TfSpec,
    opts: &FitOptions,
) -> Result<TfFit, FitError> {
    let l = Layout { num: spec.num_order, den: spec.den_order, delay: spec.delay };
    let band = spec.band_rad_s.unwrap_or((0.0, f64::INFINITY));
    let pts = points(resp, band, opts.min_coherence);
    let needed = 2 * l.len();
    if pts.len() < needed {
        return Err(FitError::TooFewFrequencies {
            used: pts.len(),
            min_coherence: opts.min_coherence,
            needed,
        });
    }
    let best = starts(&l, &pts)
        .into_iter()
        .map(|p0| levenberg_marquardt(&l, p0, &pts, opts.max_iterations))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("at least one start");
    let (p, c, iterations, converged) = best;
    let cov = covariance(&l, &p, &pts, c);
    let sig = |f: &dyn Fn(&[f64]) -> f64| propagate(&p, cov.as_ref(), f);
    let model: Vec<Complex64> =
        resp.frequency_hz.iter().map(|f| l.eval(&p, 2.0 * std::f64::consts::PI * f)).collect();
    let re: Vec<f64> = model.iter().map(|z| z.re).collect();
    let im: Vec<f64> = model.iter().map(|z| z.im).collect();
    Ok(TfFit {
        gain: p[0],
        gain_sigma: sig(&|q| q[0]),
        delay_s: if l.delay { p[l.len() - 1] } else { 0.0 },
        delay_sigma_s: if l.delay { sig(&|q| q[q.len() - 1]) } else { None },
        zeros: factors(&p, 1, l.num, cov.as_ref()),
        poles: factors(&p, 1 + l.num, l.den, cov.as_ref()),
        cost: c,
        frequencies_used: pts.len(),
        min_coherence: opts.min_coherence,
        band_rad_s: (pts[0].0, pts[pts.len() - 1].0),
        status: if converged { "converged" } else { "max_iterations" },
        iterations,
        model_magnitude_db: model.iter().map(|z| 20.0 * z.norm().log10()).collect(),
        model_phase_deg: on_branch_of(crate::spectral::unwrap_deg(&re, &im), &resp.phase_deg),
    })
}

/// `model` shifted by whole turns so that it starts on the branch of `data` (both unwrapped
/// phases, deg): the model is drawn over the response, not 360° away from it.
fn on_branch_of(mut model: Vec<f64>, data: &[f64]) -> Vec<f64> {
    if let Some((m, d)) = model.iter().zip(data).find(|(m, d)| m.is_finite() && d.is_finite()) {
        let shift = 360.0 * ((d - m) / 360.0).round();
        model.iter_mut().for_each(|v| *v += shift);
    }
    model
}

/// `s² (JᵣᵀJᵣ)⁻¹` at the optimum (module doc); `None` when singular.
fn covariance(l: &Layout, p: &[f64], pts: &Points, c: f64) -> Option<DMatrix<f64>> {
    let j = jacobian(l, p, pts);
    let dof = (j.nrows() as f64 - p.len() as f64).max(1.0);
    (j.transpose() * &j).try_inverse().map(|inv| inv * (c / dof))
}

/// σ of `f(p)` by its central-difference gradient.
fn propagate(p: &[f64], cov: Option<&DMatrix<f64>>, f: &dyn Fn(&[f64]) -> f64) -> Option<f64> {
    let cov = cov?;
    let g: Vec<f64> = (0..p.len())
        .map(|c| {
            let h = 1e-6 * p[c].abs().max(1e-6);
            let (mut a, mut b) = (p.to_vec(), p.to_vec());
            a[c] += h;
            b[c] -= h;
            (f(&a) - f(&b)) / (2.0 * h)
        })
        .collect();
    let g = DVector::from_vec(g);
    let v = (g.transpose() * cov * &g)[(0, 0)];
    (v.is_finite() && v >= 0.0).then(|| v.sqrt())
}

/// The factors of the polynomial of `order` whose coefficients start at `p[at]`.
fn factors(p: &[f64], at: usize, order: usize, cov: Option<&DMatrix<f64>>) -> Vec<Factor> {
    let mut out = Vec::new();
    let mut i = at;
    if order % 2 == 1 {
        let a = p[i];
        out.push(Factor {
            kind: "first_order",
            roots: vec![[-a, 0.0]],
            wn_rad_s: Some(a.abs()),
            wn_sigma_rad_s: propagate(p, cov, &|q| q[i].abs()),
            zeta: None,
            zeta_sigma: None,
            time_constant_s: (a != 0.0).then(|| 1.0 / a),
        });
        i += 1;
    }
    for _ in 0..order / 2 {
        let (b1, b0) = (p[i], p[i + 1]);
        let disc = b1 * b1 - 4.0 * b0;
        let roots = if disc < 0.0 {
            vec![[-b1 / 2.0, (-disc).sqrt() / 2.0], [-b1 / 2.0, -(-disc).sqrt() / 2.0]]
        } else {
            vec![[(-b1 + disc.sqrt()) / 2.0, 0.0], [(-b1 - disc.sqrt()) / 2.0, 0.0]]
        };
        let k = i;
        let osc = b0 > 0.0;
        out.push(Factor {
            kind: "second_order",
            roots,
            wn_rad_s: osc.then(|| b0.sqrt()),
            wn_sigma_rad_s: if osc { propagate(p, cov, &|q| q[k + 1].sqrt()) } else { None },
            zeta: osc.then(|| b1 / (2.0 * b0.sqrt())),
            zeta_sigma: if osc {
                propagate(p, cov, &|q| q[k] / (2.0 * q[k + 1].sqrt()))
            } else {
                None
            },
            time_constant_s: None,
        });
        i += 2;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A response sampled from a known transfer function, coherence 1 (no noise).
    fn exact(l: &Layout, p: &[f64]) -> PairResponse {
        let f: Vec<f64> = (0..80).map(|k| 0.01 * 10f64.powf(k as f64 / 30.0)).collect();
        let h: Vec<Complex64> = f.iter().map(|f| l.eval(p, 2.0 * PI * f)).collect();
        let re: Vec<f64> = h.iter().map(|z| z.re).collect();
        let im: Vec<f64> = h.iter().map(|z| z.im).collect();
        PairResponse {
            input: "de".into(),
            output: "q".into(),
            frequency_hz: f.clone(),
            magnitude_db: vec![],
            phase_deg: crate::spectral::unwrap_deg(&re, &im),
            coherence: vec![1.0; f.len()],
            multiple_coherence: vec![1.0; f.len()],
            random_error: vec![0.0; f.len()],
            magnitude_error_db: vec![],
            phase_error_deg: vec![],
            re,
            im,
        }
    }

    /// The cost at the true parameters of a response 1 dB above them everywhere, coherence 0.7:
    /// every point contributes `(20/n) W_γ (1 dB)²` with `W_γ = [1.58 (1 − e^{−0.7})]²`
    /// (MIL-STD-1797A; Tischler & Remple eq. 11.12), so `J = 20 W_γ` = 13.0, where an unweighted
    /// cost would be 20.
    #[test]
    fn analytic_cost_weights_each_point_by_its_coherence() {
        let l = Layout { num: 0, den: 2, delay: false };
        let truth = [4.0, 2.0 * 0.3 * 2.0, 4.0];
        let mut resp = exact(&l, &truth);
        let up = 10f64.powf(1.0 / 20.0);
        resp.re.iter_mut().chain(resp.im.iter_mut()).for_each(|v| *v *= up);
        resp.coherence.iter_mut().for_each(|g| *g = 0.7);
        let pts = points(&resp, (0.0, f64::INFINITY), 0.6);
        assert_eq!(pts.len(), 80);
        let w_gamma = (1.58 * (1.0 - (-0.7f64).exp())).powi(2);
        let j = cost(&residuals(&l, &truth, &pts));
        assert!((j - 20.0 * w_gamma).abs() < 1e-9, "J {j} vs {}", 20.0 * w_gamma);
    }

    #[test]
    fn short_period_form_with_delay_is_recovered_exactly() {
        // q/de = K (s + 1/Tθ2) e^{−τs} / (s² + 2ζω s + ω²): ω = 3 rad/s, ζ = 0.45, 1/Tθ2 = 1.2,
        // τ = 0.06 s, K = −9 (a nose-down elevator gives a negative pitch rate).
        let l = Layout { num: 1, den: 2, delay: true };
        let truth = [-9.0, 1.2, 2.0 * 0.45 * 3.0, 9.0, 0.06];
        let resp = exact(&l, &truth);
        let spec = TfSpec::parse("q/de:1/2+delay").unwrap();
        let fit = fit_transfer_function(&resp, &spec, &FitOptions::default()).unwrap();
        assert!(fit.cost < 1e-6, "J = {}", fit.cost);
        let pole = &fit.poles[0];
        assert!((pole.wn_rad_s.unwrap() - 3.0).abs() < 1e-4, "{pole:?}");
        assert!((pole.zeta.unwrap() - 0.45).abs() < 1e-4, "{pole:?}");
        assert!((fit.delay_s - 0.06).abs() < 1e-5, "τ {}", fit.delay_s);
        assert!((fit.gain + 9.0).abs() < 1e-3, "K {}", fit.gain);
        assert!((fit.zeros[0].roots[0][0] + 1.2).abs() < 1e-4, "{:?}", fit.zeros);
        // The fitted curve drawn over the data is the transfer function at each frequency of
        // the response, written out here: K (jω + 1.2) e^{−jωτ} / ((jω)² + 2.7 jω + 9).
        for (k, f) in resp.frequency_hz.iter().enumerate() {
            let jw = Complex64::new(0.0, 2.0 * PI * f);
            let h = -9.0 * (jw + 1.2) * (-jw * 0.06).exp() / (jw * jw + 2.7 * jw + 9.0);
            let db = 20.0 * h.norm().log10();
            assert!((fit.model_magnitude_db[k] - db).abs() < 1e-3, "{f} Hz: {db} dB");
            let turns = (fit.model_phase_deg[k] - h.arg().to_degrees()) / 360.0;
            assert!((turns - turns.round()).abs() * 360.0 < 1e-2, "{f} Hz: {turns} turns");
        }
    }

    #[test]
    fn noise_on_the_response_gives_a_sigma_that_covers_the_error() {
        // Perturb the exact response by a smooth, known ripple; the fitted ωn must stay within
        // 3σ of the truth and σ must be positive.
        let l = Layout { num: 0, den: 2, delay: false };
        let truth = [4.0, 2.0 * 0.3 * 2.0, 4.0];
        let mut resp = exact(&l, &truth);
        for k in 0..resp.re.len() {
            let e = Complex64::from_polar(
                1.0 + 0.03 * (7.3 * k as f64).sin(),
                0.02 * (3.1 * k as f64).cos(),
            );
            let z = Complex64::new(resp.re[k], resp.im[k]) * e;
            resp.re[k] = z.re;
            resp.im[k] = z.im;
        }
        let fit = fit_transfer_function(
            &resp,
            &TfSpec::parse("y/u:0/2").unwrap(),
            &FitOptions::default(),
        )
        .unwrap();
        let p = &fit.poles[0];
        let (wn, s) = (p.wn_rad_s.unwrap(), p.wn_sigma_rad_s.unwrap());
        assert!(s > 0.0 && (wn - 2.0).abs() < 3.0 * s + 1e-3, "ωn {wn} ± {s}");
        assert!(fit.cost > 0.0 && fit.cost < 10.0, "J {}", fit.cost);
    }

    /// σ against scatter: the exact second-order response with independent Gaussian errors of
    /// 0.3 dB in magnitude and 0.3/√0.01745 = 2.27° in phase at every frequency (equal weighted
    /// variance in the mismatch cost, coherence 1, so the least-squares covariance is the exact
    /// one to first order). Over 100 draws the scatter of the fitted ωn and ζ is within 0.75–1.33
    /// of the mean reported σ (the sample σ of 100 draws has ≈ 7 % standard error).
    #[test]
    fn sigma_of_the_modes_matches_their_scatter_over_noise_draws() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let l = Layout { num: 0, den: 2, delay: false };
        let clean = exact(&l, &[4.0, 2.0 * 0.3 * 2.0, 4.0]);
        let (sd_db, sd_deg) = (0.3, 0.3 / 0.01745f64.sqrt());
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let spec = TfSpec::parse("y/u:0/2").unwrap();
        let (mut wn, mut zeta, mut s_wn, mut s_zeta) = (vec![], vec![], 0.0, 0.0);
        let draws = 100;
        for _ in 0..draws {
            let mut resp = clean.clone();
            for k in 0..resp.re.len() {
                let g: f64 = StandardNormal.sample(&mut rng);
                let ph: f64 = StandardNormal.sample(&mut rng);
                let e =
                    Complex64::from_polar(10f64.powf(sd_db * g / 20.0), (sd_deg * ph).to_radians());
                let z = Complex64::new(resp.re[k], resp.im[k]) * e;
                (resp.re[k], resp.im[k]) = (z.re, z.im);
            }
            resp.phase_deg = crate::spectral::unwrap_deg(&resp.re, &resp.im);
            let fit = fit_transfer_function(&resp, &spec, &FitOptions::default()).unwrap();
            let p = &fit.poles[0];
            wn.push(p.wn_rad_s.unwrap());
            zeta.push(p.zeta.unwrap());
            s_wn += p.wn_sigma_rad_s.unwrap() / draws as f64;
            s_zeta += p.zeta_sigma.unwrap() / draws as f64;
        }
        let sd = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        for (name, scatter, sigma) in [("ωn", sd(&wn), s_wn), ("ζ", sd(&zeta), s_zeta)] {
            let r = scatter / sigma;
            assert!(
                (0.75..=1.33).contains(&r),
                "{name}: scatter {scatter:.3e} / σ {sigma:.3e} = {r:.3}"
            );
        }
    }

    #[test]
    fn specs_parse_and_bad_ones_are_named() {
        let s = TfSpec::parse("r/dr:3/4+delay@0.5:12").unwrap();
        assert_eq!(
            (s.output.as_str(), s.input.as_str(), s.num_order, s.den_order, s.delay),
            ("r", "dr", 3, 4, true)
        );
        assert_eq!(s.band_rad_s, Some((0.5, 12.0)));
        for bad in ["q-de:1/2", "q/de:3/2", "q/de:1/0", "q/de:1/2@5:1", "q/de:x/2"] {
            let e = TfSpec::parse(bad).unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
        // Each order bound on its own: no denominator, and one past the largest.
        for bad in ["q/de:0/0", "q/de:1/9"] {
            let e = TfSpec::parse(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("1 ≤ den ≤ 8"), "{e}");
        }
        assert_eq!(TfSpec::parse("q/de:0/8").unwrap().den_order, 8);
    }

    #[test]
    fn too_few_coherent_points_is_an_error() {
        let l = Layout { num: 0, den: 2, delay: false };
        let mut resp = exact(&l, &[4.0, 1.2, 4.0]);
        resp.coherence.iter_mut().for_each(|g| *g = 0.3);
        let e = fit_transfer_function(
            &resp,
            &TfSpec::parse("y/u:0/2").unwrap(),
            &FitOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("coherence ≥ 0.6"), "{e}");
    }
}
