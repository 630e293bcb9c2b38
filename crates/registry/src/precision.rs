//! Whether the record determines an estimate at all: an estimate whose σ is a large share of
//! its own size cannot be trusted whatever it agrees with. Flight-test practice reads the
//! relative standard error `σ/|θ|` for this (Jategaonkar 2015 ch. 4 and Klein & Morelli 2006
//! ch. 5 report it beside every estimate); above [`RELATIVE_SIGMA_LIMIT`] the estimate is not
//! known to the accuracy a derivative is wanted to, and the replay table and warnings say so.
//!
//! Constant terms (`CY_0`, `Cm_0` …) are left out: their size is the trim's and the axes', not
//! a property the σ can be weighed against.

use aeroident_io::ParameterResult;

/// Relative standard error `σ/|θ|` above which an estimate is flagged as imprecise (10 %: the
/// accuracy a stability derivative is wanted to in a flight-test report).
pub const RELATIVE_SIGMA_LIMIT: f64 = 0.10;

/// `σ/|θ|` of an estimate when it exceeds [`RELATIVE_SIGMA_LIMIT`], else `None` (also for a
/// constant term, a missing estimate or σ, or an estimate of exactly 0 with σ 0).
pub fn imprecise(name: &str, estimate: Option<f64>, std_error: Option<f64>) -> Option<f64> {
    if name.ends_with("_0") {
        return None;
    }
    let (e, s) = (estimate?, std_error?);
    let relative = if e == 0.0 { (s > 0.0).then_some(f64::INFINITY)? } else { s / e.abs() };
    (relative > RELATIVE_SIGMA_LIMIT).then_some(relative)
}

/// The t-ratio `|θ|/σ` below which an estimate is not told from zero: its ±2σ (95 %) spans 0,
/// so the record does not fix even its sign (the significance test of every regression table,
/// Klein & Morelli 2006 ch. 5; the structure selection drops such a term).
pub const MIN_T_RATIO: f64 = 2.0;

/// `|θ|/σ` of an estimate when it is below [`MIN_T_RATIO`], else `None` (also for a constant
/// term, whose value 0 is a trim's, or a missing estimate or σ).
pub fn insignificant(name: &str, estimate: Option<f64>, std_error: Option<f64>) -> Option<f64> {
    if name.ends_with("_0") {
        return None;
    }
    let (e, s) = (estimate?, std_error?);
    let ratio = if s > 0.0 { e.abs() / s } else { f64::INFINITY };
    (ratio < MIN_T_RATIO).then_some(ratio)
}

/// The verdict's flag on an estimate not told from zero, of t-ratio `ratio`.
pub fn insignificant_flag(ratio: f64) -> String {
    format!(
        "not told from 0: |estimate|/σ = {ratio:.1} < {MIN_T_RATIO}, its ±2σ spans zero, so the record does not fix even its sign (excite it, or leave the term out)"
    )
}

/// The verdict's note on an imprecise estimate of σ/|θ| = `relative`: `σ 32 % of |estimate|:
/// the record does not determine it to 10 %`.
pub fn flag(relative: f64) -> String {
    format!(
        "{}: the record does not determine it to {:.0} %",
        status(relative),
        100.0 * RELATIVE_SIGMA_LIMIT
    )
}

/// The table status of an imprecise estimate: `σ 32 % of |estimate|`.
pub fn status(relative: f64) -> String {
    if relative.is_finite() {
        format!("σ {:.0} % of |estimate|", 100.0 * relative)
    } else {
        "σ > 0 at an estimate of 0".into()
    }
}

/// One summary warning listing every imprecise estimate of `parameters`, or none.
pub fn warning<'a>(parameters: impl IntoIterator<Item = &'a ParameterResult>) -> Option<String> {
    let list: Vec<String> = parameters
        .into_iter()
        .filter_map(|p| {
            let r = imprecise(&p.name, p.estimate, p.std_error)?;
            Some(format!(
                "{} {}",
                p.name,
                if r.is_finite() { format!("{:.0} %", 100.0 * r) } else { "∞".into() }
            ))
        })
        .collect();
    (!list.is_empty()).then(|| {
        format!(
            "imprecise (σ above {:.0} % of the estimate: the record does not determine them to that accuracy): {}",
            100.0 * RELATIVE_SIGMA_LIMIT,
            list.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(name: &str, estimate: Option<f64>, std_error: Option<f64>) -> ParameterResult {
        ParameterResult::new(name, estimate, std_error, None, None)
    }

    /// The rule by hand: −0.37 ± 0.18 is 49 %, −0.43 ± 0.02 is 4.7 %; constant terms, nulls
    /// and an estimate of 0 with σ > 0 as documented.
    #[test]
    fn analytic_relative_standard_error_and_the_warning() {
        let r = imprecise("Cn_r", Some(-0.37), Some(0.18)).unwrap();
        assert!((r - 0.18 / 0.37).abs() < 1e-12);
        assert_eq!(status(r), "σ 49 % of |estimate|");
        assert_eq!(imprecise("Cl_p", Some(-0.43), Some(0.02)), None);
        assert_eq!(imprecise("Cm_0", Some(-0.001), Some(0.01)), None);
        assert_eq!(imprecise("Cm_q", None, Some(1.0)), None);
        assert_eq!(imprecise("Cm_q", Some(-6.0), None), None);
        assert_eq!(imprecise("Cl_r", Some(0.0), Some(0.0)), None);
        assert_eq!(imprecise("Cl_r", Some(0.0), Some(0.1)), Some(f64::INFINITY));
        let w = warning(&[
            p("Cl_p", Some(-0.43), Some(0.02)),
            p("Cn_r", Some(-0.37), Some(0.18)),
            p("Cl_r", Some(0.0), Some(0.1)),
        ])
        .unwrap();
        assert!(w.ends_with(": Cn_r 49 %, Cl_r ∞"), "{w}");
        assert_eq!(warning(&[p("Cl_p", Some(-0.43), Some(0.02))]), None);
    }

    /// The limit at its edge, hand-set: σ/|θ| just below 10 % is not imprecise, just above
    /// is, for either sign of the estimate.
    #[test]
    fn the_limit_at_its_edge() {
        let d = 1e-9;
        for e in [-2.0, 2.0] {
            assert_eq!(imprecise("Cm_q", Some(e), Some(0.2 - d)), None, "{e}");
            let r = imprecise("Cm_q", Some(e), Some(0.2 + d)).unwrap();
            assert!((r - 0.1).abs() < 1e-8, "{r}");
            // Exactly at the limit (0.2/2 is 0.1 in floating point) is not above it.
            assert_eq!(imprecise("Cm_q", Some(e), Some(0.2)), None, "{e}");
        }
    }
}
