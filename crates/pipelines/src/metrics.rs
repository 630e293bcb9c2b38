//! Scalar metrics of an estimate history: convergence time, re-convergence after a change in
//! truth, relative error. Used by `aeroident poc` and the aircraft reports.
//!
//! Definition: the *convergence time* is the first time after which the estimate
//! stays within ±`tol_rel` (5 % in the reports) of the truth until the end of the record;
//! `None` if the last sample is outside that band. A non-finite estimate counts as outside.

/// Values of magnitude below this are numerical noise around 0 (a reference that small is
/// round-off of an exact zero; a figure panel that small everywhere is drawn as 0).
pub use aeroident_io::parameter::ZERO_THRESHOLD;

/// Errors of the metric functions.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    /// The slices have different lengths.
    #[error("length mismatch: `{what}` has {found} samples, expected {need}")]
    LengthMismatch {
        /// Which slice is wrong.
        what: &'static str,
        /// Expected length (that of `t_s`).
        need: usize,
        /// Length found.
        found: usize,
    },
    /// A tolerance or time argument was not usable.
    #[error("invalid `{field}` = {value}: {reason}")]
    InvalidArgument {
        /// Argument name.
        field: &'static str,
        /// Value received.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
}

/// Default tolerance of the convergence time, ±5 % of truth.
pub const CONVERGENCE_TOL_REL: f64 = 0.05;

/// Half-width of the acceptance band around `truth`: `tol_rel·|truth|`, or `tol_rel` itself
/// (absolute) when the truth is exactly zero, where a relative band would be empty.
pub fn band_half_width(truth: f64, tol_rel: f64) -> f64 {
    if truth == 0.0 { tol_rel } else { tol_rel * truth.abs() }
}

fn inside(est: f64, truth: f64, tol_rel: f64) -> bool {
    est.is_finite() && (est - truth).abs() <= band_half_width(truth, tol_rel)
}

/// Convergence time, s: the first sample time `t_s[k]` such that `estimate[i]` is within
/// ±`tol_rel`·|`truth[i]`| for every `i ≥ k`, considering only samples with `t_s ≥ from_s`.
/// `Ok(None)` if the last sample is outside the band (never converged), or no sample is at or
/// after `from_s`. `truth` is a time series so a step change in truth can be handled; see
/// [`reconvergence_time_s`].
///
/// # Errors
/// [`MetricsError::LengthMismatch`] when the slices differ in length;
/// [`MetricsError::InvalidArgument`] when `tol_rel` is not finite and positive.
pub fn convergence_time_series_s(
    t_s: &[f64],
    estimate: &[f64],
    truth: &[f64],
    tol_rel: f64,
    from_s: f64,
) -> Result<Option<f64>, MetricsError> {
    check_len("estimate", t_s.len(), estimate.len())?;
    check_len("truth", t_s.len(), truth.len())?;
    if !(tol_rel.is_finite() && tol_rel > 0.0) {
        return Err(MetricsError::InvalidArgument {
            field: "tol_rel",
            value: tol_rel,
            reason: "must be finite and > 0",
        });
    }
    let start = t_s.iter().position(|&t| t >= from_s);
    let Some(start) = start else { return Ok(None) };
    let mut first_in: Option<usize> = None;
    for k in (start..t_s.len()).rev() {
        if inside(estimate[k], truth[k], tol_rel) {
            first_in = Some(k);
        } else {
            break;
        }
    }
    Ok(first_in.map(|k| t_s[k]))
}

/// Convergence time, s, for a constant truth (see [`convergence_time_series_s`]), from the
/// start of the record.
///
/// # Errors
/// As [`convergence_time_series_s`].
pub fn convergence_time_s(
    t_s: &[f64],
    estimate: &[f64],
    truth: f64,
    tol_rel: f64,
) -> Result<Option<f64>, MetricsError> {
    check_len("estimate", t_s.len(), estimate.len())?;
    let truth_series = vec![truth; t_s.len()];
    convergence_time_series_s(t_s, estimate, &truth_series, tol_rel, f64::NEG_INFINITY)
}

/// Re-convergence time after a step change in truth at `change_s`, s, measured FROM the change:
/// the convergence time of the samples at or after `change_s`, minus `change_s`.
/// `Ok(None)` if the estimate is outside the band at the end.
///
/// # Errors
/// As [`convergence_time_series_s`]; also [`MetricsError::InvalidArgument`] when `change_s`
/// is not finite.
pub fn reconvergence_time_s(
    t_s: &[f64],
    estimate: &[f64],
    truth: &[f64],
    tol_rel: f64,
    change_s: f64,
) -> Result<Option<f64>, MetricsError> {
    if !change_s.is_finite() {
        return Err(MetricsError::InvalidArgument {
            field: "change_s",
            value: change_s,
            reason: "must be finite",
        });
    }
    Ok(convergence_time_series_s(t_s, estimate, truth, tol_rel, change_s)?.map(|t| t - change_s))
}

/// Relative error `(estimate − truth)/|truth|`; the absolute error when `truth` is zero.
pub fn rel_error(estimate: f64, truth: f64) -> f64 {
    if truth == 0.0 { estimate - truth } else { (estimate - truth) / truth.abs() }
}

fn check_len(what: &'static str, need: usize, found: usize) -> Result<(), MetricsError> {
    if need == found { Ok(()) } else { Err(MetricsError::LengthMismatch { what, need, found }) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Analytic: e(t) = truth·(1 + 2·exp(−t)) enters the ±5 % band exactly when
    /// 2·exp(−t) = 0.05, i.e. t* = ln 40 ≈ 3.6889 s, and stays there (monotone decay).
    #[test]
    fn analytic_exponential_decay_convergence_time() {
        let dt = 1e-3;
        let t: Vec<f64> = (0..8000).map(|k| k as f64 * dt).collect();
        let truth = 3.0;
        let est: Vec<f64> = t.iter().map(|&t| truth * (1.0 + 2.0 * (-t).exp())).collect();
        let tc = convergence_time_s(&t, &est, truth, 0.05).unwrap().unwrap();
        let exact = 40f64.ln();
        assert!((tc - exact).abs() <= dt, "tc = {tc}, exact = {exact}");
    }

    /// Analytic: a damped oscillation truth·(1 + exp(−t)·cos(2πt)) leaves the band on its
    /// last excursion; the answer is the first time after the last |exp(−t) cos(2πt)| > 0.05.
    #[test]
    fn analytic_oscillation_counts_last_exit() {
        let dt = 1e-4;
        let t: Vec<f64> = (0..60000).map(|k| k as f64 * dt).collect();
        let est: Vec<f64> =
            t.iter().map(|&t| 1.0 + (-t).exp() * (2.0 * std::f64::consts::PI * t).cos()).collect();
        // Independent computation on the continuous signal: the last root of
        // f(t) = e^{-t}|cos 2πt| − 0.05 in (0, 6), located by a 10× finer backward scan and
        // refined by bisection. (It lies just before t = 3, where the peak of
        // e^{-t}cos 2πt is 0.0504: the envelope alone, ln 20 = 2.996, is not the answer.)
        let f = |t: f64| (-t).exp() * (2.0 * std::f64::consts::PI * t).cos().abs() - 0.05;
        let h = 1e-5;
        let mut hi = 6.0;
        while f(hi - h) <= 0.0 {
            hi -= h;
        }
        let mut lo = hi - h;
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > 0.0 { lo = mid } else { hi = mid }
        }
        let tc = convergence_time_s(&t, &est, 1.0, 0.05).unwrap().unwrap();
        assert!((tc - hi).abs() <= 2.0 * dt, "tc = {tc}, exact = {hi}");
    }

    #[test]
    fn analytic_never_converges_is_none() {
        let t = [0.0, 1.0, 2.0];
        assert_eq!(convergence_time_s(&t, &[0.0, 0.0, 2.0], 1.0, 0.05).unwrap(), None);
        assert_eq!(convergence_time_s(&t, &[1.0, f64::NAN, 1.0], 1.0, 0.05).unwrap(), Some(2.0));
        assert_eq!(convergence_time_s(&t, &[1.0, 1.0, f64::NAN], 1.0, 0.05).unwrap(), None);
    }

    /// A truth stepping from 2 to 4 at t = 5 s, estimate following as 4 − 2·exp(−(t − 5)):
    /// re-enters the ±5 % band when 2 exp(−τ) = 0.2, i.e. τ = ln 10 after the change.
    #[test]
    fn analytic_reconvergence_after_truth_step() {
        let dt = 1e-3;
        let t: Vec<f64> = (0..10000).map(|k| k as f64 * dt).collect();
        let truth: Vec<f64> = t.iter().map(|&t| if t < 5.0 { 2.0 } else { 4.0 }).collect();
        let est: Vec<f64> =
            t.iter().map(|&t| if t < 5.0 { 2.0 } else { 4.0 - 2.0 * (-(t - 5.0)).exp() }).collect();
        let tr = reconvergence_time_s(&t, &est, &truth, 0.05, 5.0).unwrap().unwrap();
        assert!((tr - 10f64.ln()).abs() <= 2.0 * dt, "tr = {tr}");
        // Over the whole record the convergence time is the same instant.
        let tc = convergence_time_series_s(&t, &est, &truth, 0.05, 0.0).unwrap().unwrap();
        assert!((tc - (5.0 + 10f64.ln())).abs() <= 2.0 * dt);
    }

    #[test]
    fn bad_arguments_are_errors() {
        assert!(matches!(
            convergence_time_s(&[0.0, 1.0], &[1.0], 1.0, 0.05),
            Err(MetricsError::LengthMismatch { what: "estimate", need: 2, found: 1 })
        ));
        assert!(convergence_time_s(&[0.0], &[1.0], 1.0, 0.0).is_err());
    }
}
