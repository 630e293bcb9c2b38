//! Model validation metrics of one output: how well a model's prediction `ŷ` matches the
//! measurement `y`, and whether what is left over looks like white noise unrelated to the
//! inputs. This is the residual analysis of flight-test practice (Jategaonkar, *Flight Vehicle
//! System Identification*, 2nd ed. 2015, ch. 10 "model validation": residual statistics,
//! Theil's inequality coefficient; Klein & Morelli, *Aircraft System Identification* 2006,
//! §5.5 and ch. 11: fit error, R², residual autocorrelation and prediction intervals) and of the
//! Python peer `aeroid.validate`.
//!
//! With residuals `e_t = y_t − ŷ_t`, `t = 1…N`, means `ȳ`, `ē`:
//!
//! | key | definition |
//! |---|---|
//! | `rmse` | `sqrt(Σ e² / N)` |
//! | `bias`, `bias_ci95` | `ē ± 1.96 σ_ē`, `σ_ē² = (s²/N) (1 + 2 Σ_{k=1}^{K} (1 − k/N) ρ_k)` with `s² = Σ(e−ē)²/N` and the residual autocorrelation `ρ_k` summed while positive (initial positive sequence, Geyer 1992), so coloured residuals widen the interval |
//! | `fit_percent` | `100 (1 − ‖e‖ / ‖y − ȳ‖)` (NRMSE fit, as MATLAB `compare` and `aeroid`; 100 = perfect, 0 = no better than the mean) |
//! | `r_squared` | `1 − Σe² / Σ(y − ȳ)²` |
//! | `theil_u` | `sqrt(mean e²) / (sqrt(mean y²) + sqrt(mean ŷ²))` (Theil's inequality coefficient U1; 0 perfect, 1 worst; Jategaonkar ch. 10 takes < 0.3 as adequate) |
//! | `ljung_box` | `Q = N (N+2) Σ_{k=1}^{h} ρ_k² / (N − k)`, `p = P(χ²_h > Q)`; `h = min(20, ⌊N/4⌋)` lags (Ljung & Box, Biometrika 65, 1978; Box & Jenkins). `white` = `p ≥ 0.05` |
//! | `input_correlation` | per input `u`: `max_{|k|≤L} |ρ_eu(k)|`, `ρ_eu(k) = Σ_t (e_t−ē)(u_{t+k}−ū) / sqrt(Σ(e−ē)² Σ(u−ū)²)`, `L = min(20, ⌊N/4⌋)`, against the 95 % white-noise band `1.96/√N`; `within_band` when below it |
//! | `prediction_interval` | `ŷ_t ± 2 sqrt(x_tᵀ P x_t + s²)` (parameter covariance `P` and residual variance `s²` — on a second record the fitted record's mean square residual; Klein & Morelli §5.5); `fraction_inside` of the samples (≈ 0.954 for a correct model with Gaussian white residuals) |
//!
//! Lagged sums (`ρ_k`, `ρ_eu`) never cross a segment boundary (a gap between manoeuvres).

use aeroident_signals::lag_products::lag_products;
use serde::Serialize;

/// Largest number of lags in the Ljung–Box test and the residual–input cross-correlation.
pub const MAX_LAGS: usize = 20;

/// Two-sided 95 % normal quantile.
pub const Z95: f64 = 1.959_963_984_540_054;

/// Ljung–Box portmanteau test of residual whiteness.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LjungBox {
    /// Number of lags `h` summed (also the χ² degrees of freedom).
    pub lags: usize,
    /// The statistic `Q`.
    pub q: f64,
    /// `P(χ²_h > Q)`: small values reject whiteness.
    pub p_value: f64,
    /// `p_value ≥ 0.05`: whiteness not rejected at 5 %.
    pub white: bool,
}

/// Residual–input cross-correlation of one input.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputCorrelation {
    /// Input name (`de`, `da`, `dr`).
    pub input: String,
    /// `max |ρ_eu(k)|` over `|k| ≤ max_lag`.
    pub max_abs_rho: f64,
    /// The lag `k` (samples; positive: the input follows the residual) of the maximum.
    pub at_lag: i64,
    /// Lags searched each side.
    pub max_lag: usize,
    /// The 95 % band `1.96/√N`.
    pub band: f64,
    /// `max_abs_rho < band`.
    pub within_band: bool,
}

/// The ±2σ prediction interval check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PredictionInterval {
    /// Half-width multiple of σ (2).
    pub k_sigma: f64,
    /// Fraction of the samples whose measurement lies inside `ŷ ± 2σ_pred`.
    pub fraction_inside: f64,
    /// Mean half-width `2 σ_pred`, units of the output.
    pub mean_half_width: f64,
    /// Fraction of `σ_pred²` due to the parameter covariance (mean over samples); the rest is
    /// residual variance.
    pub parameter_share: f64,
}

/// Validation metrics of one output (module doc for the definitions).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputValidation {
    /// Output name: a coefficient (`CL`, `Cm` …) or an output-error channel (`alpha`, `q` …).
    pub name: String,
    /// How `ŷ` was formed: `equation-error` (coefficient predicted from the regressors with
    /// the final estimates) or `simulated` (output-error model integrated from the first
    /// sample).
    pub prediction: String,
    /// Samples compared.
    pub n: usize,
    /// Root-mean-square residual, units of the output.
    pub rmse: f64,
    /// Mean residual `ē` (measured − predicted).
    pub bias: f64,
    /// 95 % confidence interval of the mean residual `[lo, hi]`.
    pub bias_ci95: [f64; 2],
    /// NRMSE fit, %; `null` when `y` is constant.
    pub fit_percent: Option<f64>,
    /// Coefficient of determination; `null` when `y` is constant.
    pub r_squared: Option<f64>,
    /// Theil's inequality coefficient U1; `null` when `y` and `ŷ` are both zero.
    pub theil_u: Option<f64>,
    /// Residual whiteness; `null` below 8 samples.
    pub ljung_box: Option<LjungBox>,
    /// Residual–input cross-correlation, per input given.
    pub input_correlation: Vec<InputCorrelation>,
    /// Prediction interval check; `null` without a residual variance.
    pub prediction_interval: Option<PredictionInterval>,
}

/// One output's data for [`validate`].
#[derive(Debug, Clone, Copy)]
pub struct OutputData<'a> {
    /// Output name.
    pub name: &'a str,
    /// Prediction kind (`equation-error` or `simulated`).
    pub prediction: &'a str,
    /// Measurements `y`, length `N`.
    pub y: &'a [f64],
    /// Predictions `ŷ`, length `N`.
    pub y_hat: &'a [f64],
    /// Per-sample variance of `ŷ` from the parameter covariance (`x_tᵀ P x_t`), length `N`;
    /// `None` when the method gives no covariance (the interval then has the residual
    /// variance only).
    pub y_hat_var: Option<&'a [f64]>,
    /// The residual variance the interval uses: the fit's own (mean square residual of the
    /// fitted record) when validating on a second record; `None`: this record's `s²`.
    pub residual_var: Option<f64>,
    /// Segment lengths (sum `N`); lagged sums stay within a segment. Empty: one segment.
    pub segments: &'a [usize],
    /// Inputs `(name, u)`, each length `N`.
    pub inputs: &'a [(&'a str, &'a [f64])],
}

/// Why an output cannot be validated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValidationError {
    /// Lengths differ.
    #[error("output `{name}`: {what} has {got} samples, expected {expected}")]
    Length {
        /// Output.
        name: String,
        /// Which series.
        what: String,
        /// Its length.
        got: usize,
        /// `N`.
        expected: usize,
    },
    /// Too few samples.
    #[error("output `{name}`: {n} samples, at least 3 are needed")]
    TooFew {
        /// Output.
        name: String,
        /// Samples.
        n: usize,
    },
    /// A value is not finite.
    #[error("output `{name}`: non-finite {what} at sample {index}")]
    NonFinite {
        /// Output.
        name: String,
        /// Which series.
        what: String,
        /// Sample index.
        index: usize,
    },
}

/// Lag pairs `(t, t + k)` within the same segment: calls `f(t, t+k)`.
fn for_lag(segments: &[usize], n: usize, k: usize, mut f: impl FnMut(usize, usize)) {
    let mut start = 0;
    let one = [n];
    let segs = if segments.is_empty() { &one[..] } else { segments };
    for &len in segs {
        for t in start..(start + len).saturating_sub(k) {
            f(t, t + k);
        }
        start += len;
    }
}

/// Normalised autocorrelation `ρ_k`, `k = 0…max_lag`, of `e` (mean removed; `ρ_0 = 1`), lags
/// within segments, normalised by the lag-0 sum over all samples (the standard biased
/// estimate). All zeros when `e` is constant.
///
/// The lag sums are formed per segment by [`aeroident_signals::lag_products`] (by the
/// transform beyond its direct range), so a quarter-record of lags costs `O(n log n)`.
pub fn autocorrelation(e: &[f64], segments: &[usize], max_lag: usize) -> Vec<f64> {
    let n = e.len();
    let mean = e.iter().sum::<f64>() / n.max(1) as f64;
    let centred: Vec<f64> = e.iter().map(|v| v - mean).collect();
    let c0: f64 = centred.iter().map(|v| v * v).sum();
    if c0 <= 0.0 {
        return vec![0.0; max_lag + 1];
    }
    let whole = [n];
    let lengths = if segments.is_empty() { &whole[..] } else { segments };
    let mut sums = vec![0.0; max_lag + 1];
    let mut start = 0;
    for &len in lengths {
        let end = (start + len).min(n);
        let products = lag_products(&centred[start.min(end)..end], max_lag);
        sums.iter_mut().zip(products).for_each(|(s, p)| *s += p);
        start = end;
    }
    sums.iter().map(|s| s / c0).collect()
}

/// The Ljung–Box test on residuals `e` with `h` lags (module doc).
pub fn ljung_box(e: &[f64], segments: &[usize], h: usize) -> LjungBox {
    let n = e.len() as f64;
    let rho = autocorrelation(e, segments, h);
    let q = n * (n + 2.0) * (1..=h).map(|k| rho[k] * rho[k] / (n - k as f64)).sum::<f64>();
    let p_value = chi2_sf(q, h as f64);
    LjungBox { lags: h, q, p_value, white: p_value >= 0.05 }
}

/// `P(χ²_k > x)`, the upper tail of the chi-squared distribution with `k` degrees of freedom:
/// the regularised upper incomplete gamma function `Q(k/2, x/2)` (series for `x < a + 1`,
/// Lentz continued fraction otherwise; Press et al., *Numerical Recipes* 3rd ed. §6.2).
pub fn chi2_sf(x: f64, k: f64) -> f64 {
    if x.is_nan() || k <= 0.0 {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    let (a, x) = (0.5 * k, 0.5 * x);
    let ln_pre = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) by its series.
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * ln_pre.exp()).clamp(0.0, 1.0)
    } else {
        // Q(a, x) by its continued fraction (modified Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (ln_pre.exp() * h).clamp(0.0, 1.0)
    }
}

/// `ln Γ(x)`, `x > 0` (Lanczos, g = 7, 9 coefficients; relative error < 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Residual–input cross-correlation of `e` and `u` over `|k| ≤ max_lag` (module doc). `None`
/// when either is constant.
pub fn input_correlation(
    name: &str,
    e: &[f64],
    u: &[f64],
    segments: &[usize],
    max_lag: usize,
) -> Option<InputCorrelation> {
    let n = e.len();
    let me = e.iter().sum::<f64>() / n as f64;
    let mu = u.iter().sum::<f64>() / n as f64;
    let see: f64 = e.iter().map(|v| (v - me) * (v - me)).sum();
    let suu: f64 = u.iter().map(|v| (v - mu) * (v - mu)).sum();
    if !(see > 0.0 && suu > 0.0) {
        return None;
    }
    let norm = (see * suu).sqrt();
    let mut best = (0.0f64, 0i64);
    for k in 0..=max_lag {
        // k ≥ 0: ρ(k) pairs e_t with u_{t+k}; ρ(−k) pairs u_t with e_{t+k}.
        let (mut fwd, mut back) = (0.0, 0.0);
        for_lag(segments, n, k, |a, b| {
            fwd += (e[a] - me) * (u[b] - mu);
            back += (u[a] - mu) * (e[b] - me);
        });
        for (v, lag) in [(fwd, k as i64), (back, -(k as i64))] {
            let r = (v / norm).abs();
            if r > best.0 {
                best = (r, lag);
            }
        }
    }
    let band = Z95 / (n as f64).sqrt();
    Some(InputCorrelation {
        input: name.to_string(),
        max_abs_rho: best.0,
        at_lag: best.1,
        max_lag,
        band,
        within_band: best.0 < band,
    })
}

/// The fit statistics of a prediction `ŷ` against a measurement `y` (module doc): the part of
/// [`OutputValidation`] that needs no residual analysis, shared with the console fit table
/// ([`crate::results::fit_quality`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitStatistics {
    /// `sqrt(Σ e² / N)`, units of the output.
    pub rmse: f64,
    /// NRMSE fit, %; `None` when `y` is constant.
    pub fit_percent: Option<f64>,
    /// Coefficient of determination; `None` when `y` is constant.
    pub r_squared: Option<f64>,
    /// Theil's inequality coefficient U1; `None` when `y` and `ŷ` are both zero.
    pub theil_u: Option<f64>,
}

/// [`FitStatistics`] of `y_hat` against `y` (same length `N ≥ 1`, all finite: the caller
/// checks or filters; extra elements of the longer slice are ignored).
pub fn fit_statistics(y: &[f64], y_hat: &[f64]) -> FitStatistics {
    let nf = y.len().min(y_hat.len()) as f64;
    let sse: f64 = y.iter().zip(y_hat).map(|(y, p)| (y - p) * (y - p)).sum();
    let rmse = (sse / nf).sqrt();
    let y_mean = y.iter().sum::<f64>() / nf;
    let sst: f64 = y.iter().map(|v| (v - y_mean) * (v - y_mean)).sum();
    let (fit_percent, r_squared) = if sst > 0.0 {
        (Some(100.0 * (1.0 - (sse / sst).sqrt())), Some(1.0 - sse / sst))
    } else {
        (None, None)
    };
    let rms = |s: &[f64]| (s.iter().map(|v| v * v).sum::<f64>() / nf).sqrt();
    let denom = rms(y) + rms(y_hat);
    let theil_u = (denom > 0.0).then(|| rmse / denom);
    FitStatistics { rmse, fit_percent, r_squared, theil_u }
}

/// Number of lags used for `N` samples: `min(20, ⌊N/4⌋)`.
pub fn lags_for(n: usize) -> usize {
    MAX_LAGS.min(n / 4)
}

/// The validation metrics of one output (module doc).
///
/// # Errors
/// [`ValidationError`] for mismatched lengths, fewer than 3 samples or a non-finite value.
pub fn validate(d: &OutputData<'_>) -> Result<OutputValidation, ValidationError> {
    let n = d.y.len();
    let name = d.name.to_string();
    let len_err = |what: &str, got: usize| ValidationError::Length {
        name: name.clone(),
        what: what.into(),
        got,
        expected: n,
    };
    if d.y_hat.len() != n {
        return Err(len_err("the prediction", d.y_hat.len()));
    }
    if let Some(v) = d.y_hat_var
        && v.len() != n
    {
        return Err(len_err("the prediction variance", v.len()));
    }
    for (u_name, u) in d.inputs {
        if u.len() != n {
            return Err(len_err(&format!("input `{u_name}`"), u.len()));
        }
    }
    if !d.segments.is_empty() && d.segments.iter().sum::<usize>() != n {
        return Err(len_err("the segment list", d.segments.iter().sum()));
    }
    if n < 3 {
        return Err(ValidationError::TooFew { name, n });
    }
    let series: [(&str, &[f64]); 3] =
        [("measurement", d.y), ("prediction", d.y_hat), ("variance", d.y_hat_var.unwrap_or(&[]))];
    for (what, s) in series {
        if let Some(index) = s.iter().position(|v| !v.is_finite()) {
            return Err(ValidationError::NonFinite { name, what: what.into(), index });
        }
    }
    for (u_name, u) in d.inputs {
        if let Some(index) = u.iter().position(|v| !v.is_finite()) {
            return Err(ValidationError::NonFinite {
                name,
                what: format!("input `{u_name}`"),
                index,
            });
        }
    }
    let nf = n as f64;
    let e: Vec<f64> = d.y.iter().zip(d.y_hat).map(|(y, p)| y - p).collect();
    let FitStatistics { rmse, fit_percent, r_squared, theil_u } = fit_statistics(d.y, d.y_hat);
    let bias = e.iter().sum::<f64>() / nf;
    let s2 = e.iter().map(|v| (v - bias) * (v - bias)).sum::<f64>() / nf;
    // σ of the mean with the residual autocorrelation, summed while positive.
    let rho = autocorrelation(&e, d.segments, n / 4);
    let mut inflation = 1.0;
    for (k, r) in rho.iter().enumerate().skip(1) {
        if *r <= 0.0 {
            break;
        }
        inflation += 2.0 * (1.0 - k as f64 / nf) * r;
    }
    let half = Z95 * (s2 / nf * inflation).sqrt();
    let h = lags_for(n);
    let ljung_box = (n >= 8 && h >= 1).then(|| ljung_box(&e, d.segments, h));
    let input_correlation = d
        .inputs
        .iter()
        .filter_map(|(u_name, u)| input_correlation(u_name, &e, u, d.segments, h))
        .collect();
    let s2_interval = d.residual_var.filter(|v| v.is_finite() && *v >= 0.0).unwrap_or(s2);
    let prediction_interval = (s2_interval > 0.0).then(|| {
        let var_p = |t: usize| d.y_hat_var.map_or(0.0, |v| v[t].max(0.0));
        let (mut inside, mut width, mut share) = (0usize, 0.0, 0.0);
        for (t, et) in e.iter().enumerate() {
            let var = var_p(t) + s2_interval;
            let hw = 2.0 * var.sqrt();
            inside += usize::from(et.abs() <= hw);
            width += hw;
            share += var_p(t) / var;
        }
        PredictionInterval {
            k_sigma: 2.0,
            fraction_inside: inside as f64 / nf,
            mean_half_width: width / nf,
            parameter_share: share / nf,
        }
    });
    Ok(OutputValidation {
        name,
        prediction: d.prediction.to_string(),
        n,
        rmse,
        bias,
        bias_ci95: [bias - half, bias + half],
        fit_percent,
        r_squared,
        theil_u,
        ljung_box,
        input_correlation,
        prediction_interval,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Standard normal draws by Box–Muller (independent of the code under test).
    fn normals(seed: u64, n: usize) -> Vec<f64> {
        let mut rng = Pcg64::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
            })
            .collect()
    }

    fn data<'a>(y: &'a [f64], y_hat: &'a [f64]) -> OutputData<'a> {
        OutputData {
            name: "Cm",
            prediction: "equation-error",
            y,
            y_hat,
            y_hat_var: None,
            residual_var: None,
            segments: &[],
            inputs: &[],
        }
    }

    /// χ² upper tail against closed forms: for even k = 2m, `Q = e^{−x/2} Σ_{i<m} (x/2)^i/i!`;
    /// and the tabulated 5 % points of χ²₁ (3.841459) and χ²₂₀ (31.410433).
    #[test]
    fn analytic_chi2_tail() {
        for m in 1..=12usize {
            for x in [0.3, 1.0, 4.0, 10.0, 25.0, 60.0] {
                let h = x / 2.0;
                let mut term = 1.0;
                let mut sum = 0.0;
                for i in 0..m {
                    if i > 0 {
                        term *= h / i as f64;
                    }
                    sum += term;
                }
                let exact = (-h).exp() * sum;
                let got = chi2_sf(x, 2.0 * m as f64);
                assert!((got - exact).abs() < 1e-12 * exact.max(1e-300) + 1e-15, "{m} {x}");
            }
        }
        assert!((chi2_sf(3.841_458_820_694_124, 1.0) - 0.05).abs() < 1e-9);
        assert!((chi2_sf(31.410_432_844_230_918, 20.0) - 0.05).abs() < 1e-9);
        assert_eq!(chi2_sf(0.0, 3.0), 1.0);
    }

    /// A perfect model: fit 100 %, R² 1, Theil U 0, RMSE and bias 0.
    #[test]
    fn analytic_perfect_model() {
        let y: Vec<f64> = (0..200).map(|k| (0.1 * k as f64).sin() + 0.2).collect();
        let v = validate(&data(&y, &y)).unwrap();
        assert_eq!(v.fit_percent, Some(100.0));
        assert_eq!(v.r_squared, Some(1.0));
        assert_eq!(v.theil_u, Some(0.0));
        assert_eq!((v.rmse, v.bias), (0.0, 0.0));
        assert!(v.prediction_interval.is_none(), "no residual variance");
    }

    /// The mean as the model: fit 0 %, R² 0; a constant offset c: RMSE = |bias| = c, and
    /// Theil U = c / (rms y + rms ŷ) by hand.
    #[test]
    fn analytic_mean_model_and_offset() {
        let y: Vec<f64> = (0..100).map(|k| (0.3 * k as f64).cos()).collect();
        let m = y.iter().sum::<f64>() / 100.0;
        let v = validate(&data(&y, &vec![m; 100])).unwrap();
        assert!(v.fit_percent.unwrap().abs() < 1e-12 && v.r_squared.unwrap().abs() < 1e-12);
        let c = 0.25;
        let y_hat: Vec<f64> = y.iter().map(|v| v - c).collect();
        let v = validate(&data(&y, &y_hat)).unwrap();
        assert!((v.rmse - c).abs() < 1e-12 && (v.bias - c).abs() < 1e-12);
        let rms = |s: &[f64]| (s.iter().map(|v| v * v).sum::<f64>() / 100.0).sqrt();
        assert!((v.theil_u.unwrap() - c / (rms(&y) + rms(&y_hat))).abs() < 1e-12);
    }

    /// Ljung–Box on white noise: p-values are uniform, so over 200 independent series about
    /// 5 % reject at 5 % (binomial 99.9 % range 2 … 20); on AR(1) with ρ = 0.5, N = 2000, the
    /// lag-1 autocorrelation estimates ρ and Q ≈ N Σ ρ^{2k} ≈ 2000/3 rejects always.
    #[test]
    fn analytic_ljung_box_white_versus_ar1() {
        let mut rejected = 0;
        for seed in 0..200 {
            let e = normals(seed, 500);
            let lb = ljung_box(&e, &[], lags_for(500));
            assert_eq!(lb.lags, 20);
            rejected += usize::from(!lb.white);
        }
        assert!((2..=20).contains(&rejected), "{rejected} of 200 rejected");
        let w = normals(999, 2000);
        let mut x = vec![0.0; 2000];
        for t in 1..2000 {
            x[t] = 0.5 * x[t - 1] + w[t];
        }
        let rho = autocorrelation(&x, &[], 3);
        assert!((rho[1] - 0.5).abs() < 0.05 && (rho[2] - 0.25).abs() < 0.06, "{rho:?}");
        let lb = ljung_box(&x, &[], 20);
        let expect = 2000.0 * (1..=20).map(|k| 0.25f64.powi(k)).sum::<f64>();
        assert!(lb.q > 0.7 * expect && lb.q < 1.3 * expect, "{} vs {expect}", lb.q);
        assert!(lb.p_value < 1e-12 && !lb.white);
    }

    /// Segments: an AR(1) series cut into two halves whose residuals are independent: lag
    /// sums do not cross the cut (a step at the boundary contributes nothing).
    #[test]
    fn analytic_lags_stay_within_segments() {
        let e = [1.0, 1.0, -1.0, -1.0];
        // Whole: ρ_1 = (1 − 1 + 1)/4; in two segments [1, 1] and [−1, −1]: (1 + 1)/4.
        assert!((autocorrelation(&e, &[], 1)[1] - 0.25).abs() < 1e-15);
        assert!((autocorrelation(&e, &[2, 2], 1)[1] - 0.5).abs() < 1e-15);
    }

    /// Residuals that contain a delayed copy of the input are found at that lag, far outside
    /// the band; residuals independent of the input stay inside the band in ≥ 80 % of 50
    /// series (the max over 41 lags exceeds 1.96/√N more often than 5 %).
    #[test]
    fn analytic_input_correlation() {
        let u = normals(7, 1000);
        let noise = normals(8, 1000);
        let e: Vec<f64> =
            (0..1000).map(|t| noise[t] + if t >= 3 { 2.0 * u[t - 3] } else { 0.0 }).collect();
        let c = input_correlation("de", &e, &u, &[], 20).unwrap();
        assert_eq!(c.at_lag, -3, "e_t follows u_(t−3)");
        assert!(c.max_abs_rho > 0.8 && !c.within_band, "{c:?}");
        let mut inside = 0;
        for seed in 0..50 {
            let e = normals(100 + seed, 1000);
            let c = input_correlation("de", &e, &u, &[], 20).unwrap();
            assert!((c.band - Z95 / 1000f64.sqrt()).abs() < 1e-15);
            inside += usize::from(c.max_abs_rho < 1.5 * c.band);
        }
        assert!(inside >= 40, "{inside}");
    }

    /// Gaussian white residuals: ±2σ covers ≈ 95.4 % and the bias interval covers the true
    /// mean 0 in ≈ 95 % of 200 series; for AR(1) residuals (ρ = 0.8) the naive interval would
    /// cover far less, ours still ≥ 85 %.
    #[test]
    fn analytic_prediction_interval_and_bias_coverage() {
        let n = 400;
        let y_hat = vec![0.0; n];
        let (mut cover_white, mut cover_ar) = (0, 0);
        let mut frac = 0.0;
        for seed in 0..200 {
            let e = normals(1000 + seed, n);
            let v = validate(&data(&e, &y_hat)).unwrap();
            cover_white += usize::from(v.bias_ci95[0] <= 0.0 && 0.0 <= v.bias_ci95[1]);
            frac += v.prediction_interval.unwrap().fraction_inside;
            let mut x = vec![0.0; n];
            x[0] = e[0] / (1.0f64 - 0.64).sqrt();
            for t in 1..n {
                x[t] = 0.8 * x[t - 1] + e[t];
            }
            let v = validate(&data(&x, &y_hat)).unwrap();
            cover_ar += usize::from(v.bias_ci95[0] <= 0.0 && 0.0 <= v.bias_ci95[1]);
        }
        assert!((178..=198).contains(&cover_white), "{cover_white}");
        assert!(cover_ar >= 170, "{cover_ar}");
        let frac = frac / 200.0;
        assert!((frac - 0.9545).abs() < 0.01, "{frac}");
        // The parameter variance widens the interval: all of it, share → 1 as it dominates.
        let e = normals(5, n);
        let var = vec![1e6; n];
        let d = OutputData { y_hat_var: Some(&var), ..data(&e, &y_hat) };
        let p = validate(&d).unwrap().prediction_interval.unwrap();
        assert_eq!(p.fraction_inside, 1.0);
        assert!(p.parameter_share > 0.999);
    }

    #[test]
    fn errors_lengths_and_non_finite_are_named() {
        let y = [1.0, 2.0, 3.0, 4.0];
        let e = validate(&data(&y, &[1.0, 2.0])).unwrap_err().to_string();
        assert!(e.contains("`Cm`") && e.contains("2 samples, expected 4"), "{e}");
        let e = validate(&data(&y, &[1.0, f64::NAN, 3.0, 4.0])).unwrap_err().to_string();
        assert!(e.contains("non-finite prediction at sample 1"), "{e}");
        let e = validate(&data(&y[..2], &y[..2])).unwrap_err().to_string();
        assert!(e.contains("at least 3"), "{e}");
    }
}
