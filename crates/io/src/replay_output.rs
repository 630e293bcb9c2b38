//! Writers for `aeroident replay` results: the per-sample `estimates.csv` and `summary.json`.
//!
//! `estimates.csv` header: `t_s,<name>...,sigma_<name>...` (one line per estimate). An empty
//! field means the value is not identified yet, or the method gives no standard error there —
//! never a made-up number.
//!
//! `summary.json` keys: `schema_version, estimator, model, status, samples_read,
//! samples_rejected, rejections[{row, reason}], throughput_samples_per_s, parameters[{name,
//! estimate, std_error, std_error_source, crb_std_error, reference, status, flags,
//! settle_time_s}] ([`crate::parameter`]), coefficients[{name, condition_number}], correlations[{a, b, rho}],
//! events{listed[{t_s, kind, subject, statistic?}], counts{restart, reanchor, change_detected},
//! not_listed}, warnings[]`.
//! `estimate`, `std_error`, `settle_time_s` and `condition_number` are `null` where undefined
//! (not identified, no covariance from the method).

use crate::flight_data::Rejection;
use crate::parameter::ParameterResult;
use aeroident_estimators::{EventKind, EventLog};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;

/// One parameter's final result: the common keys ([`ParameterResult`]) and its settling time,
/// in one `summary.json` object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterSummary {
    /// Name, estimate (`null` until identified and after a divergence), σ (the estimator's
    /// covariance, where it gives one), reference (the model file's), status and flags.
    #[serde(flatten)]
    pub result: ParameterResult,
    /// Settling time, s (see `aeroident_pipelines::replay::settle_time_s` for the definition).
    pub settle_time_s: Option<f64>,
}

impl std::ops::Deref for ParameterSummary {
    type Target = ParameterResult;

    fn deref(&self) -> &ParameterResult {
        &self.result
    }
}

/// One modelled coefficient's diagnostics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CoefficientSummary {
    /// Coefficient name (`CL`, `Cm`, `Cn` …).
    pub name: String,
    /// 2-norm condition number of the correlation matrix of the coefficient's parameters
    /// (the estimator's covariance scaled to unit diagonal); large values (> 10³) flag terms
    /// the data cannot separate. `null` where the estimator gives no covariance.
    pub condition_number: Option<f64>,
}

/// A pair of parameters whose estimates are strongly correlated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Correlation {
    /// First parameter.
    pub a: String,
    /// Second parameter.
    pub b: String,
    /// Correlation coefficient `cov(a,b)/(σ_a σ_b)`, |ρ| > 0.9.
    pub rho: f64,
}

/// One thing an estimator did to itself ([`aeroident_estimators::Event`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventSummary {
    /// Time of the sample at which it happened, s.
    pub t_s: f64,
    /// `restart`, `reanchor` or `change_detected` ([`EventKind::name`]).
    pub kind: String,
    /// The output (its sample field: `p_rad_s`, `alpha_rad` …), parameter (`Cl_p` …),
    /// coefficient equation (`Cm` …) or rule it concerns.
    pub subject: String,
    /// The test statistic that raised it, where there is one (the equation-error change test's
    /// CUSUM `g`, `aeroident_estimators::change`); the key is absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statistic: Option<f64>,
}

/// An estimator's events ([`aeroident_estimators::Estimator::events`]): the listed ones in
/// time order, the exact count of each kind (every kind present, 0 included), and how many
/// were not listed because the estimator's list was full.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct EventsSummary {
    /// The listed events, in time order.
    pub listed: Vec<EventSummary>,
    /// Per kind name, how many happened (listed or not).
    pub counts: BTreeMap<String, u32>,
    /// How many happened but are not listed.
    pub not_listed: u32,
}

impl EventsSummary {
    /// The summary of `log`.
    pub fn from_log(log: &EventLog) -> Self {
        Self {
            listed: log
                .listed()
                .iter()
                .map(|e| EventSummary {
                    t_s: e.t_s,
                    kind: e.kind.name().into(),
                    subject: e.subject.into(),
                    statistic: e.statistic,
                })
                .collect(),
            counts: EventKind::ALL.iter().map(|k| (k.name().to_string(), log.count(*k))).collect(),
            not_listed: log.unlisted(),
        }
    }

    /// How many events of `kind` happened.
    pub fn count(&self, kind: EventKind) -> u32 {
        self.counts.get(kind.name()).copied().unwrap_or(0)
    }

    /// One warning per listed restart (time and the output that failed); empty without one.
    pub fn restart_warnings(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .listed
            .iter()
            .filter(|e| e.kind == EventKind::Restart.name())
            .map(|e| {
                format!(
                    "estimator restarted from its priors at t = {:.3} s (its divergence rule fired on `{}`); its estimates come from the samples after that only",
                    e.t_s, e.subject
                )
            })
            .collect();
        let unlisted = (self.count(EventKind::Restart) as usize).saturating_sub(out.len());
        if unlisted > 0 {
            out.push(format!(
                "estimator restarted from its priors {unlisted} more time(s), not listed; its estimates come from the samples after the last restart only"
            ));
        }
        out
    }

    /// The other events in one readable line, `None` without any: the first
    /// [`NOTE_EVENTS`] as `change detected in Cl_p at 22.12 s` or `re-anchored output p_rad_s at
    /// 20.51 s`, then how many more there were.
    pub fn note(&self) -> Option<String> {
        let others: Vec<&EventSummary> =
            self.listed.iter().filter(|e| e.kind != EventKind::Restart.name()).collect();
        let total = self.count(EventKind::Reanchor) + self.count(EventKind::ChangeDetected);
        if total == 0 {
            return None;
        }
        let mut items: Vec<String> = others
            .iter()
            .take(NOTE_EVENTS)
            .map(|e| {
                let what = if e.kind == EventKind::Reanchor.name() {
                    "re-anchored output"
                } else {
                    "change detected in"
                };
                format!("{what} {} at {:.2} s", e.subject, e.t_s)
            })
            .collect();
        let shown = items.len() as u32;
        if total > shown {
            items.push(format!("{} more (counted in summary.json `events`)", total - shown));
        }
        Some(format!("events: {}", items.join("; ")))
    }
}

/// How many events [`EventsSummary::note`] names before it counts the rest.
pub const NOTE_EVENTS: usize = 6;

/// What a sign test found for one surface or accelerometer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SignVerdict {
    /// The record's response has the sign the mapping's convention gives.
    Consistent,
    /// The record's response has the opposite sign, by more than the test's σ margin.
    Reversed,
    /// The record cannot decide: too little excitation or too much noise against the response.
    Undecided,
    /// An accelerometer whose gain against the force equations is decided and far from ±1: it
    /// does not read the specific force as mapped (gravity removed, another unit, a load
    /// factor); the evidence names the likely form.
    NotASpecificForce,
}

/// One sign test of a surface or accelerometer channel from the record's own kinematics and
/// responses (computed by `aeroident_pipelines::replay::sign_tests`, which documents each test).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SignTest {
    /// The mapping key tested (`de`, `da`, `dr`, `ax`, `ay`, `az`).
    pub channel: String,
    /// Consistent, reversed or undecided.
    pub verdict: SignVerdict,
    /// The measured response (a surface's angular acceleration per rad, rad/s² per rad; an
    /// accelerometer's gain against the kinematics, 1 when consistent); `null` when the test
    /// could not be run (the evidence says why).
    pub gain: Option<f64>,
    /// Its σ (least squares, widened for coloured residuals); `null` with the gain.
    pub sigma: Option<f64>,
    /// The evidence in words: what was regressed, the value and what was expected.
    pub evidence: String,
    /// A surface whose sign is decided: the time the recorded surface leads the response it
    /// drives, s (> 0: a commanded surface, or one recorded early; < 0: recorded late); `null`
    /// for an accelerometer or an undecided surface.
    pub lead_s: Option<f64>,
    /// Its 95 % interval `[lo, hi]`, s (at the search's edge, ±0.3 s, when not closed there).
    pub lead_interval_s: Option<(f64, f64)>,
}

impl SignTest {
    /// `de consistent`, `dr reversed`, `ay cannot be decided from this record`.
    pub fn short(&self) -> String {
        let v = match self.verdict {
            SignVerdict::Consistent => "consistent",
            SignVerdict::Reversed => "REVERSED",
            SignVerdict::Undecided => "cannot be decided from this record",
            SignVerdict::NotASpecificForce => "NOT A SPECIFIC FORCE as mapped",
        };
        format!("{} {v}", self.channel)
    }
}

/// The one-line account of `tests` the faces print (`None` when there are none):
/// `sign tests (the record's own responses): de consistent, ay cannot be decided …`.
pub fn sign_tests_line(tests: &[SignTest]) -> Option<String> {
    if tests.is_empty() {
        return None;
    }
    let items: Vec<String> = tests.iter().map(SignTest::short).collect();
    Some(format!(
        "sign tests (from the record's own kinematics and responses; summary.json `sign_tests`): {}",
        items.join(", ")
    ))
}

/// The `summary.json` document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySummary {
    /// The key set's version, [`crate::SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Estimator name (`rls`, `ekf`, …).
    pub estimator: String,
    /// The model: a preset name (`longitudinal`, `lateral`, `six-axis`) or the model file.
    pub model: String,
    /// The model's α knots of its spline terms, rad (absent when it has none): the JSBSim
    /// export forms the splines from them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub alpha_knots_rad: Vec<f64>,
    /// How the run ended: `complete` (the estimator ran to the end of the record with every
    /// parameter identified), `initialising` (some never were) or `diverged`; `interrupted`
    /// when a signal stopped the replay before the end of its record (the warnings give the
    /// estimator's own status then). Each parameter's own `status` says whether to trust it.
    pub status: String,
    /// Data rows read (accepted + rejected).
    pub samples_read: usize,
    /// Rows rejected.
    pub samples_rejected: usize,
    /// The rejected rows and gaps (gap entries reject nothing; their reason starts with
    /// `gap`): the first [`crate::RejectionLog::DEFAULT_LIMIT`] and always the last; the
    /// others are counted per kind in `warnings` ([`crate::RejectionLog`]).
    pub rejections: Vec<Rejection>,
    /// Samples per second through the estimation stage (estimator update; CSV parsing,
    /// differentiation, pacing and output excluded), one core.
    pub throughput_samples_per_s: f64,
    /// Final parameter estimates.
    pub parameters: Vec<ParameterSummary>,
    /// Per modelled coefficient: the condition number.
    pub coefficients: Vec<CoefficientSummary>,
    /// Every pair of parameters with |ρ| > 0.9 (where the estimator gives covariances).
    pub correlations: Vec<Correlation>,
    /// What the estimator did to itself (restarts, re-anchored outputs, detected changes):
    /// restarts are also in `warnings`.
    pub events: EventsSummary,
    /// Warnings about the record or the run (e.g. the mapping's `nominal_dt_s` disagrees with
    /// the measured interval; a time jump not slept across in real-time pacing), each with its
    /// kind ([`crate::warning`]); `summary.json` lists their texts.
    pub warnings: crate::warning::Warnings,
    /// Per surface and accelerometer mapped, its sign as the record's own responses decide it
    /// ([`SignTest`]); empty when the record maps none.
    pub sign_tests: Vec<SignTest>,
}

impl ReplaySummary {
    /// Writes the summary as pretty JSON.
    ///
    /// # Errors
    /// I/O errors of `w`.
    pub fn write_json<W: Write>(&self, w: W) -> std::io::Result<()> {
        serde_json::to_writer_pretty(w, self).map_err(std::io::Error::other)
    }
}

/// Writes the CSV header `t_s,<names>,sigma_<names>`.
///
/// # Errors
/// I/O errors of `w`.
pub fn write_estimates_header<W: Write>(w: &mut W, names: &[&str]) -> std::io::Result<()> {
    write!(w, "t_s")?;
    for n in names {
        write!(w, ",{n}")?;
    }
    for n in names {
        write!(w, ",sigma_{n}")?;
    }
    writeln!(w)
}

/// Significant digits of each σ in an estimates line. A σ estimated from `N` samples is itself
/// uncertain by about `1/√(2N)` of itself (0.3 % at 50,000 samples), so digits beyond the
/// fourth (a rounding of at most 0.05 %) say nothing; GUM (JCGM 100:2008, 7.2.6) quotes an
/// uncertainty to two. Written so, the σ columns of a long replay's `estimates.csv` take 40 %
/// of the space the shortest round-trip text took. `summary.json` keeps every σ whole.
pub const SIGMA_DIGITS: usize = 4;

/// Writes one estimates line: the time and each value as `{}` (`Display`) writes it
/// ([`crate::decimal::push_f64`]), each σ to [`SIGMA_DIGITS`] significant digits
/// ([`crate::decimal::push_significant`]), `None` as an empty field.
///
/// # Errors
/// I/O errors of `w`.
pub fn write_estimates_row<W: Write>(
    w: &mut W,
    t_s: f64,
    values: &[Option<f64>],
    sigmas: &[Option<f64>],
) -> std::io::Result<()> {
    // The row is formed in one buffer and written once: the per-number `write!` calls were
    // most of a long replay's writing time.
    let mut line = String::with_capacity(24 * (1 + values.len() + sigmas.len()));
    let mut digits = ryu::Buffer::new();
    crate::decimal::push_f64(&mut line, &mut digits, t_s);
    for v in values {
        line.push(',');
        if let Some(v) = v {
            crate::decimal::push_f64(&mut line, &mut digits, *v);
        }
    }
    for s in sigmas {
        line.push(',');
        if let Some(s) = s {
            crate::decimal::push_significant(&mut line, &mut digits, *s, SIGMA_DIGITS);
        }
    }
    line.push('\n');
    w.write_all(line.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row is the time and each value as `Display` writes it, then each σ to four
    /// significant digits, joined by commas, an empty field for `None`: tiny, huge, negative,
    /// integral and NaN numbers alike.
    #[test]
    fn an_estimates_row_is_the_display_text_of_its_values_and_four_digits_of_its_sigmas() {
        let values = [Some(-0.000_012_5), None, Some(1.5e20), Some(3.0)];
        let sigmas = [Some(f64::NAN), Some(0.1 + 0.2), None, Some(7.254_9e-9)];
        let mut out = Vec::new();
        write_estimates_row(&mut out, 12.34, &values, &sigmas).unwrap();
        let field = |v: &Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
        let mut expected: Vec<String> =
            std::iter::once("12.34".to_string()).chain(values.iter().map(field)).collect();
        expected.extend(["NaN", "0.3", "", "7.255e-9"].map(String::from));
        assert_eq!(String::from_utf8(out).unwrap(), format!("{}\n", expected.join(",")));
    }

    /// A log with one restart and eight other events: the restart is a warning naming its time
    /// and output; the note names the first [`NOTE_EVENTS`] others and counts the two left;
    /// every kind is counted in `counts`, 0 included.
    #[test]
    fn events_summary_warns_of_restarts_and_notes_the_rest() {
        let mut log = EventLog::new();
        log.push(1.5, EventKind::Restart, "az_mps2");
        for k in 0..8 {
            let kind = if k < 3 { EventKind::Reanchor } else { EventKind::ChangeDetected };
            log.push(10.0 + f64::from(k), kind, if k < 3 { "p_rad_s" } else { "Cl_p" });
        }
        let s = EventsSummary::from_log(&log);
        assert_eq!(s.listed.len(), 9);
        assert_eq!(s.count(EventKind::Restart), 1);
        assert_eq!(s.count(EventKind::Reanchor), 3);
        assert_eq!(s.count(EventKind::ChangeDetected), 5);
        let w = s.restart_warnings();
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("t = 1.500 s") && w[0].contains("`az_mps2`"), "{}", w[0]);
        let note = s.note().unwrap();
        assert!(note.starts_with("events: re-anchored output p_rad_s at 10.00 s;"), "{note}");
        assert!(note.contains("change detected in Cl_p at 15.00 s"), "{note}");
        assert!(
            !note.contains("16.00 s")
                && note.ends_with("2 more (counted in summary.json `events`)")
        );
        let json = serde_json::to_value(&s).unwrap();
        assert_eq!(json["counts"]["change_detected"], 5);
        assert_eq!(json["listed"][0]["kind"], "restart");
        // Without events: no warning, no note, every count 0.
        let none = EventsSummary::from_log(&EventLog::new());
        assert!(none.restart_warnings().is_empty() && none.note().is_none());
        assert_eq!(none.counts.len(), 3);
    }
}
