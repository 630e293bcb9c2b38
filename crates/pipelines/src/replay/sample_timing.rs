//! The sample-timing test: what a skew of half a sample between the rate gyros and the other
//! channels moves.
//!
//! A record stamps each row with one time, but its channels are not sampled at one instant:
//! an IMU and an air-data computer on separate clocks, a logger that samples its inputs in
//! turn, a simulator whose integrator updates the rates half a step from the forces. Within
//! a sample interval the record cannot tell those instants apart, so a skew of up to half a
//! sample between the gyros and the flow angles and surfaces is always possible, and a
//! compatibility check cannot resolve less than that either (Jategaonkar 2015, §10.3: time
//! shifts are estimated to a fraction of the sample time, at best). The damping derivatives
//! are the ones it moves: a small phase error of `r` against `β` projects the large stiffness
//! term `Cn_β β` onto `r` (on a clean simulated A-4 record, a skew of 4 ms, a quarter sample
//! at 60 Hz, moves the least-squares `Cn_r` from −0.15 to −0.02, the output-error one to
//! −0.10).
//!
//! The test fits the record twice more by the run's own method, with the gyros read half a
//! sample later and half a sample earlier ([`crate::record::Corrections::with_rate_skew`]).
//! Half the difference of the two is what a half-sample skew moves each estimate. One it moves
//! by more than [`MOVE_FRACTION`] of its value is flagged with the three values: `identified`
//! claims more than the record's timing supports. The threshold is the precision an
//! identified estimate claims, not fitted (decided on the calibration corpus's tune half
//! against 5 % and ±2σ, docs/validation.md). The move also enters every estimate's σ, as a
//! uniform error over ± the move ([`spreads`]): the σ then covers the timing the record cannot
//! resolve, not only its noise.

use crate::replay::cross_check::MethodEstimates;
use aeroident_io::ParameterResult;
use aeroident_io::warning::{Warning, WarningKind};

/// The skew asked about, as a fraction of the record's sample interval: half a sample, the
/// most a row's one time stamp hides.
pub const SKEW_SAMPLES: f64 = 0.5;

/// The largest move under the skew, as a fraction of the estimate, that is not flagged.
pub const MOVE_FRACTION: f64 = 0.10;

/// Only an estimate beyond this many of its σ from zero is judged: one whose ±2σ spans zero is
/// flagged for that already ([`crate::replay::precision::insignificant`]), and a relative move
/// of a value indistinguishable from zero says nothing.
pub const SIGNIFICANT_SIGMAS: f64 = 2.0;

/// One flag about each estimate of `own` that the skew of `skew_s` (s) moves by more than
/// [`MOVE_FRACTION`] of its value: half the difference between `late` (the gyros read
/// `skew_s` later) and `early` (`skew_s` earlier). An estimate within [`SIGNIFICANT_SIGMAS`]
/// of zero, or a parameter either refit lacks, is not judged.
pub fn moved(
    own: &MethodEstimates,
    late: &MethodEstimates,
    early: &MethodEstimates,
    skew_s: f64,
) -> Vec<Warning> {
    moves(own, late, early)
        .filter(|m| m.value.abs() > SIGNIFICANT_SIGMAS * m.sigma)
        .filter(|m| m.half.abs() > MOVE_FRACTION * m.value.abs())
        .map(|m| {
            let text = format!(
                "sample timing: a skew of ±{:.1} ms (half a sample) between the rate gyros and the other channels, which the record's time stamps cannot rule out, moves {} from {} to {} (gyros early) and {} (gyros late), ±{:.0} % of its value: more than the {:.0} % an identified estimate claims",
                1e3 * skew_s,
                m.name,
                number(m.value),
                number(m.early),
                number(m.late),
                100.0 * m.half.abs() / m.value.abs().max(f64::MIN_POSITIVE),
                100.0 * MOVE_FRACTION
            );
            Warning::new(WarningKind::SampleTiming, text).about(m.name)
        })
        .collect()
}

/// The sample-timing σ of each estimate of `own` that both refits give, `(parameter, σ)`:
/// the skew is anywhere within ±half a sample, equally likely, so the estimate's error from
/// it is uniform over ± the half-difference of the refits, whose σ is that half-difference
/// over √3 (GUM 4.3.7).
pub fn spreads(
    own: &MethodEstimates,
    late: &MethodEstimates,
    early: &MethodEstimates,
) -> Vec<(String, f64)> {
    moves(own, late, early).map(|m| (m.name.to_string(), m.half.abs() / 3f64.sqrt())).collect()
}

/// Adds each parameter's sample-timing σ of `spreads` to its `std_error` in quadrature
/// ([`ParameterResult::add_timing_std_error`]); a parameter without one is left as it is.
pub fn widen<'a>(
    results: impl IntoIterator<Item = &'a mut ParameterResult>,
    spreads: &[(String, f64)],
) {
    for r in results {
        if let Some((_, s)) = spreads.iter().find(|(n, _)| *n == r.name) {
            r.add_timing_std_error(*s);
        }
    }
}

/// One estimate under the skew.
struct Move<'a> {
    name: &'a str,
    value: f64,
    sigma: f64,
    early: f64,
    late: f64,
    /// Half the difference late − early: the move under a skew of half a sample.
    half: f64,
}

/// Each estimate of `own` with both refits' values of it.
fn moves<'a>(
    own: &'a MethodEstimates,
    late: &'a MethodEstimates,
    early: &'a MethodEstimates,
) -> impl Iterator<Item = Move<'a>> + 'a {
    let value_in = |m: &MethodEstimates, name: &str| m.row(name).map(|r| r.estimate);
    own.estimates.iter().filter_map(move |r| {
        let (late, early) = (value_in(late, &r.name)?, value_in(early, &r.name)?);
        let half = 0.5 * (late - early);
        let (name, value, sigma) = (&r.name, r.estimate, r.std_error);
        Some(Move { name, value, sigma, early, late, half })
    })
}

/// `v` to four significant figures, fixed-point where that reads well.
fn number(v: f64) -> String {
    if v == 0.0 || (1e-2..1e4).contains(&v.abs()) { format!("{v:.4}") } else { format!("{v:.3e}") }
}

/// The skew the test asks about for a record sampled every `interval_s`, s ([`SKEW_SAMPLES`]
/// of it); `None` for an interval that is not finite and positive.
pub fn skew_s(interval_s: f64) -> Option<f64> {
    (interval_s.is_finite() && interval_s > 0.0).then_some(SKEW_SAMPLES * interval_s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::replay::cross_check::ParameterEstimate;

    fn method(rows: &[(&str, f64)]) -> MethodEstimates {
        MethodEstimates::new(
            "oe",
            "converged",
            rows.iter().map(|&(n, v)| ParameterEstimate::new(n, v, 0.001)),
        )
    }

    /// The rule at its edge: Cn_r −0.15 moved ±0.0149 (9.9 %) is not flagged, ±0.0151 (10.1 %)
    /// is, whichever way the skew moves it; a parameter a refit lacks is not judged; the text
    /// gives the skew in ms and the three values.
    #[test]
    fn the_move_rule_at_its_edge() {
        let own = method(&[("Cn_r", -0.15), ("Cn_beta", 0.12), ("Cl_p", -0.4), ("Cn_dr", -0.1)]);
        let late = method(&[("Cn_r", -0.15 + 0.0149), ("Cn_beta", 0.12 - 0.0121), ("Cl_p", -0.5)]);
        let early = method(&[("Cn_r", -0.15 - 0.0149), ("Cn_beta", 0.12 + 0.0121), ("Cl_p", -0.3)]);
        let w = moved(&own, &late, &early, 0.008_333);
        let about: Vec<_> = w.iter().map(|w| w.parameter.as_deref().unwrap()).collect();
        assert_eq!(about, ["Cn_beta", "Cl_p"], "{w:?}");
        assert!(w.iter().all(|w| w.kind == WarningKind::SampleTiming));
        assert!(
            w[1].text.contains("±8.3 ms (half a sample)")
                && w[1].text.contains("moves Cl_p from -0.4000 to -0.3000 (gyros early) and -0.5000 (gyros late), ±25 % of its value"),
            "{}",
            w[1].text
        );
        let late = method(&[("Cn_r", -0.15 + 0.0151)]);
        let early = method(&[("Cn_r", -0.15 - 0.0151)]);
        assert_eq!(moved(&own, &late, &early, 0.008_333).len(), 1);
        assert_eq!(moved(&own, &early, &late, 0.008_333).len(), 1);
        // A move of exactly 10 % (0.5 · (0.2 − 0) against 0.1 · 1, equal in floating point) is
        // not beyond it.
        let one = method(&[("Cl_da", 1.0)]);
        assert!(
            moved(&one, &method(&[("Cl_da", 0.2)]), &method(&[("Cl_da", 0.0)]), 0.01).is_empty()
        );
    }

    /// An estimate within 2σ of zero is not judged (its own flag says it is not told from
    /// zero), one just beyond is; a small value is written in exponent form.
    #[test]
    fn an_estimate_not_told_from_zero_is_not_judged() {
        let own = |sigma| {
            MethodEstimates::new("oe", "converged", [ParameterEstimate::new("Cl_0", 2e-4, sigma)])
        };
        let late = method(&[("Cl_0", 4e-4)]);
        let early = method(&[("Cl_0", 0.0)]);
        assert!(moved(&own(1e-4), &late, &early, 0.01).is_empty());
        let w = moved(&own(0.99e-4), &late, &early, 0.01);
        assert_eq!(w.len(), 1);
        assert!(
            w[0].text.contains("from 2.000e-4 to 0.0000 (gyros early) and 4.000e-4"),
            "{}",
            w[0].text
        );
    }

    /// The σ of a uniform error over ± the half-difference: Cl_p early −0.3, late −0.5, σ
    /// 0.1/√3; added to a σ of 0.1 in quadrature it gives 0.1·√(4/3), and a second widening
    /// replaces the first's share; a parameter a refit lacks has no spread.
    #[test]
    fn the_spread_is_a_uniform_error_over_the_move() {
        let own = method(&[("Cl_p", -0.4), ("Cn_r", -0.15)]);
        let s = spreads(&own, &method(&[("Cl_p", -0.5)]), &method(&[("Cl_p", -0.3)]));
        assert_eq!(s.len(), 1);
        assert!((s[0].1 - 0.1 / 3f64.sqrt()).abs() < 1e-15, "{s:?}");
        let mut r = ParameterResult::new("Cl_p", Some(-0.4), Some(0.1), None, None);
        let mut none = ParameterResult::new("Cn_r", Some(-0.15), Some(0.01), None, None);
        widen([&mut r, &mut none], &s);
        assert!((r.std_error.unwrap() - 0.1 * (4.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert_eq!(r.timing_std_error, Some(s[0].1));
        assert_eq!((none.std_error, none.timing_std_error), (Some(0.01), None));
        r.add_timing_std_error(0.0);
        assert!((r.std_error.unwrap() - 0.1).abs() < 1e-15, "{:?}", r.std_error);
        let mut bare = ParameterResult::new("Cl_p", Some(-0.4), None, None, None);
        bare.add_timing_std_error(0.05);
        assert_eq!((bare.std_error, bare.timing_std_error), (None, None));
    }

    /// Half a sample of the interval; nothing for an interval that is not one.
    #[test]
    fn the_skew_is_half_the_sample_interval() {
        assert_eq!(skew_s(0.02), Some(0.01));
        assert_eq!(skew_s(0.0), None);
        assert_eq!(skew_s(f64::NAN), None);
        assert_eq!(skew_s(-0.01), None);
    }
}
