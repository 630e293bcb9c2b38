//! What a surface's measured lead moves: the record fitted again with the lead undone.
//!
//! A timing test that finds a surface leading its response ([`super::timing`]) says the data
//! are inconsistent with a prompt, measured surface; it cannot say which estimates that moves.
//! Every parameter of a least-squares or output-error fit is correlated with the input's
//! regressor, so a timing error biases the whole moment equation (a lagged elevator is taken
//! up by `Cm_q` and `Cm_δe`, and through their correlation by `Cm_α`), and some estimates not
//! at all. The refit asks the record: the same estimator, model and options, the surface read
//! its lead earlier ([`crate::record::Corrections::with_input_shift`]); an estimate that moves
//! beyond its own ±2σ depends on the input's timing more than its σ says, and is flagged with
//! both values (Klein & Morelli 2006, §10.2: the time delay as a model parameter; the refit is
//! that model at the measured delay). The control and damping derivatives keep the timing
//! test's own flag whether or not they move ([`moved`]).
//!
//! The own σ, not the combined σ of the two fits: both read the same samples, so their noise
//! is shared and a difference beyond ±2σ of one of them is not noise.

use super::derivative_of;
use crate::record::Corrections;
use crate::replay::cross_check::MethodEstimates;
use aeroident_io::replay_output::SignTest;
use aeroident_io::warning::{Warning, WarningKind, Warnings};

/// How many σ of its own an estimate may move in the refit and not be flagged (the ±2σ its
/// interval claims).
pub const MOVE_SIGMAS: f64 = 2.0;

/// The surfaces whose lead a timing warning named, `(key, lead_s)`: each surface test with a
/// lead and a [`WarningKind::InputTiming`] warning about its control derivative.
pub fn warned_leads(tests: &[SignTest], warnings: &Warnings) -> Vec<(String, f64)> {
    let warned = |d: &str| {
        warnings
            .iter()
            .any(|w| w.kind == WarningKind::InputTiming && w.parameter.as_deref() == Some(d))
    };
    tests
        .iter()
        .filter_map(|t| {
            let lead = t.lead_s?;
            warned(derivative_of(&t.channel)?).then(|| (t.channel.clone(), lead))
        })
        .collect()
}

/// `base` (no corrections: none) with every surface of `leads` read its lead earlier.
///
/// # Errors
/// A lead beyond what a shift may undo, in words ([`Corrections::with_input_shift`]).
pub fn undone(base: Option<&Corrections>, leads: &[(String, f64)]) -> Result<Corrections, String> {
    let mut c = base.cloned().unwrap_or_default();
    for (key, lead) in leads {
        c = c.with_input_shift(key, -lead)?;
    }
    Ok(c)
}

/// The surfaces and their leads in words: `` `de` +0.080 s, `da` -0.050 s``.
fn describe(leads: &[(String, f64)]) -> String {
    let each = leads.iter().map(|(k, l)| format!("`{k}` {l:+.3} s"));
    each.collect::<Vec<_>>().join(", ")
}

/// One warning about each estimate of `own` that `refit` moves beyond [`MOVE_SIGMAS`] of its
/// own σ, with both values. They are added beside the timing test's own flags on the control
/// and damping derivatives, which stay: a commanded surface also carries its actuator's gain
/// and rate limit, which a shift does not undo (on the calibration corpus's tune half, 62 of
/// the estimates a shift left within ±2σ on records with a rate-limited servo were more than
/// 10 % off).
pub fn moved(
    own: &MethodEstimates,
    refit: &MethodEstimates,
    leads: &[(String, f64)],
) -> Vec<Warning> {
    let surfaces = describe(leads);
    own.estimates
        .iter()
        .filter_map(|mine| {
            let (name, value, sigma) = (&mine.name, mine.estimate, mine.std_error);
            let r = refit.row(name)?.estimate;
            let shift = r - value;
            (shift.abs() > MOVE_SIGMAS * sigma).then(|| {
                let text = format!(
                    "input timing: refitted with the measured lead undone ({surfaces}), {name} moves from {value:.4} to {r:.4} ({:+.0} %, {:.1}σ): the estimate depends on the input's timing beyond its σ",
                    100.0 * shift / value.abs().max(f64::MIN_POSITIVE),
                    shift.abs() / sigma
                );
                Warning::new(WarningKind::InputTiming, text).about(name)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::replay::cross_check::ParameterEstimate;
    use aeroident_io::replay_output::SignVerdict;

    fn test(channel: &str, lead: Option<f64>) -> SignTest {
        SignTest {
            channel: channel.into(),
            verdict: SignVerdict::Consistent,
            gain: Some(-10.0),
            sigma: Some(0.1),
            evidence: String::new(),
            lead_s: lead,
            lead_interval_s: lead.map(|l| (l - 0.01, l + 0.01)),
        }
    }

    /// Only a surface the timing test warned about is refitted: `de` has its warning about
    /// Cm_de; `da` has a lead but no warning; `dr` a warning but no lead.
    #[test]
    fn only_warned_leads_are_refitted() {
        let tests = [test("de", Some(0.08)), test("da", Some(0.01)), test("dr", None)];
        let warnings: Warnings = [
            Warning::new(WarningKind::InputTiming, "de leads").about("Cm_de"),
            Warning::new(WarningKind::InputTiming, "dr leads").about("Cn_dr"),
            Warning::new(WarningKind::Sign, "da").about("Cl_da"),
        ]
        .into_iter()
        .collect();
        assert_eq!(warned_leads(&tests, &warnings), [("de".to_string(), 0.08)]);
    }

    /// The refit's corrections are the run's own with each warned surface read its lead
    /// earlier (a shift of minus the lead); a lead beyond what a shift may undo is refused.
    #[test]
    fn the_refit_keeps_the_runs_corrections_and_undoes_each_lead() {
        let base = Corrections::default().with_input_shift("dr", 0.01).unwrap();
        let leads = [("de".to_string(), 0.08), ("da".to_string(), -0.03)];
        let c = undone(Some(&base), &leads).unwrap();
        let applied: Vec<&str> = c.applied.iter().map(String::as_str).collect();
        assert_eq!(
            applied,
            [
                "dr: read +0.010 s later (its measured lead undone)",
                "de: read -0.080 s later (its measured lead undone)",
                "da: read +0.030 s later (its measured lead undone)",
            ]
        );
        assert_eq!(undone(None, &leads[..1]).unwrap().applied.len(), 1);
        assert!(undone(None, &[("de".to_string(), 0.7)]).unwrap_err().contains("beyond"));
    }

    /// The move rule at its edge: σ 0.1, a move of 0.199 is not flagged, 0.201 is, either way;
    /// the text gives both values, the percentage and the σ count; a parameter the refit lacks
    /// is not judged.
    #[test]
    fn the_move_rule_at_its_edge() {
        let own = MethodEstimates::new(
            "oe",
            "converged",
            [
                ParameterEstimate::new("Cm_alpha", -1.0, 0.1),
                ParameterEstimate::new("Cm_q", -10.0, 0.1),
                ParameterEstimate::new("Cm_de", -2.0, 0.1),
                ParameterEstimate::new("Cm_0", 0.05, 0.1),
            ],
        );
        let refit = MethodEstimates::new(
            "oe",
            "converged",
            [
                ParameterEstimate::new("Cm_alpha", -1.199, 0.1),
                ParameterEstimate::new("Cm_q", -10.201, 0.1),
                ParameterEstimate::new("Cm_de", -1.799, 0.1),
            ],
        );
        let leads = [("de".to_string(), 0.08)];
        let w = moved(&own, &refit, &leads);
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(w[0].parameter.as_deref(), Some("Cm_q"));
        assert!(
            w[0].text
                .contains("(`de` +0.080 s), Cm_q moves from -10.0000 to -10.2010 (-2 %, 2.0σ)"),
            "{}",
            w[0].text
        );
        assert_eq!(w[1].parameter.as_deref(), Some("Cm_de"));
        assert!(w[1].text.contains("+10 %"), "{}", w[1].text);
        // Exactly 2σ (−1.0 → −1.5 at σ 0.25, exact in floating point) is not beyond it.
        let own = MethodEstimates::new(
            "oe",
            "converged",
            [ParameterEstimate::new("Cm_alpha", -1.0, 0.25)],
        );
        let refit = MethodEstimates::new(
            "oe",
            "converged",
            [ParameterEstimate::new("Cm_alpha", -1.5, 0.25)],
        );
        assert!(moved(&own, &refit, &leads).is_empty());
    }

    /// The refit's warnings go beside the timing test's: a parameter the refit moves carries
    /// both, one it does not keeps the timing test's alone; other kinds untouched.
    #[test]
    fn the_refit_flags_go_beside_the_timing_tests() {
        let mut warnings: Warnings = [
            Warning::new(WarningKind::InputTiming, "de leads").about("Cm_de"),
            Warning::new(WarningKind::Sign, "dr reversed").about("Cn_dr"),
        ]
        .into_iter()
        .collect();
        let own = MethodEstimates::new(
            "oe",
            "converged",
            [
                ParameterEstimate::new("Cm_alpha", -1.0, 0.01),
                ParameterEstimate::new("Cm_de", -2.0, 0.1),
            ],
        );
        let refit = MethodEstimates::new(
            "oe",
            "converged",
            [
                ParameterEstimate::new("Cm_alpha", -1.2, 0.01),
                ParameterEstimate::new("Cm_de", -2.05, 0.1),
            ],
        );
        warnings.extend(moved(&own, &refit, &[("de".to_string(), 0.08)]));
        assert_eq!(warnings.about("Cm_de"), ["de leads"]);
        let alpha = warnings.about("Cm_alpha");
        assert!(alpha.len() == 1 && alpha[0].contains("Cm_alpha moves from -1.0000 to -1.2000"));
        assert_eq!(warnings.about("Cn_dr"), ["dr reversed"]);
    }
}
