//! The held-out judgement of a check's corrections as `compat.json` carries it, and the
//! refusal of each correction that fails it ([`aeroident_estimators::compat::held_out`]).

use super::Entry;
use aeroident_estimators::compat::{self, Channel, HeldOut, Unknown};
use serde::{Deserialize, Serialize};

/// `compat.json` `held_out`: each correction applied to data it was not fitted on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutSummary {
    /// What was held out in turn: `manoeuvre`, `fold` (runs of consecutive manoeuvres, when
    /// there are more than [`compat::MAX_FOLDS`]) or `half` (of a record with one manoeuvre).
    pub by: String,
    /// How many pieces.
    pub pieces: usize,
    /// Per correction, its judgement.
    pub corrections: Vec<HeldOutRow>,
    /// Pieces that could not be judged, with why.
    #[serde(default)]
    pub notes: Vec<String>,
}

/// One correction's held-out judgement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutRow {
    /// The channel (`alpha_rad` …); `null` for the AHRS lag.
    pub channel: Option<String>,
    /// `bias`, `scale`, `time_shift` or `ahrs_lag`.
    pub correction: String,
    /// Over the held-out pieces, the change of their negative log-likelihood when it is
    /// applied (`N/2 · Δ ln det R`); negative: it improves data it was not fitted on.
    pub change_neg_log_likelihood: f64,
    /// The pieces it was judged on (0: not judged).
    pub pieces: usize,
    /// The mean of that change were the correction true
    /// ([`aeroident_estimators::compat::HeldOutCorrection::expected`]).
    pub expected: f64,
    /// Its standard deviation then
    /// ([`aeroident_estimators::compat::HeldOutCorrection::spread`]).
    pub spread: f64,
    /// `improves` (the change is negative), `stands` (positive, within [`compat::FAIL_SPREADS`]
    /// spreads of what a true correction would do), `fails` (beyond: refused) or `not judged`.
    pub verdict: String,
}

impl HeldOutRow {
    /// Whether it was judged and failed (recomputed from the numbers, not the verdict's word).
    pub fn fails(&self) -> bool {
        compat::fails(self.change_neg_log_likelihood, self.expected, self.spread, self.pieces)
    }

    /// `alpha_rad time shift`, `AHRS lag`: the correction in words.
    pub fn label(&self) -> String {
        match &self.channel {
            Some(c) => format!("{c} {}", self.correction.replace('_', " ")),
            None => "AHRS lag".into(),
        }
    }
}

impl HeldOutSummary {
    /// The summary of an estimated judgement.
    pub fn of(h: &HeldOut) -> Self {
        let corrections = h
            .corrections
            .iter()
            .map(|c| {
                let (channel, correction) = names(c.unknown);
                let verdict = match (c.pieces, c.fails()) {
                    (0, _) => "not judged",
                    (_, true) => "fails",
                    _ if c.change < 0.0 => "improves",
                    _ => "stands",
                };
                HeldOutRow {
                    channel: channel.map(str::to_string),
                    correction: correction.into(),
                    change_neg_log_likelihood: c.change,
                    pieces: c.pieces,
                    expected: c.expected,
                    spread: c.spread,
                    verdict: verdict.into(),
                }
            })
            .collect();
        Self { by: h.by.into(), pieces: h.pieces, corrections, notes: h.notes.clone() }
    }

    /// The failed row of channel `ch`'s `correction`, if any.
    fn failed(&self, ch: Option<Channel>, correction: &str) -> Option<&HeldOutRow> {
        let name = ch.map(Channel::name);
        self.corrections
            .iter()
            .find(|r| r.channel.as_deref() == name && r.correction == correction && r.fails())
    }

    /// Why the AHRS lag is refused, if it failed.
    pub(super) fn lag_refusal(&self) -> Option<String> {
        self.failed(None, "ahrs_lag").map(|r| self.why(r))
    }

    /// The reason a failed row gives in `compat refused: …`. Where the held-out pieces had no
    /// curvature along the correction (`expected` and `spread` both 0), there is no true
    /// correction's change to compare with, and the reason says it fails on the rise alone.
    fn why(&self, r: &HeldOutRow) -> String {
        let pieces = match self.by.as_str() {
            "half" => "halves",
            "fold" => "folds of consecutive manoeuvres",
            _ => "manoeuvres",
        };
        let against = if r.expected == 0.0 && r.spread == 0.0 {
            format!(
                "beyond the {:.2} of a one-parameter likelihood-ratio test, and their cost does not curve along it, so no true correction's change could be formed to excuse it",
                compat::MIN_FAILING_RISE
            )
        } else {
            format!(
                "where a true correction of its size would change it by {:+.1} ± {:.1}",
                r.expected, r.spread
            )
        };
        format!(
            "{}: applied to the {pieces} held out in turn ({} of {}) it worsens their fit (their −ln L rises by {:.1}, {against}): the rest of the record contradicts it",
            r.label(),
            r.pieces,
            self.pieces,
            r.change_neg_log_likelihood,
        )
    }

    /// Clears each correction of `entries` that failed, returning why, and the channels whose
    /// time shift failed (their timing is then not checked).
    pub(super) fn refuse(&self, entries: &mut [Entry]) -> (Vec<String>, Vec<Channel>) {
        let (mut why, mut timing) = (Vec::new(), Vec::new());
        for e in entries.iter_mut() {
            let parts = [("bias", &mut e.1), ("scale", &mut e.2), ("time_shift", &mut e.3)];
            for (what, value) in parts {
                if value.is_some()
                    && let Some(r) = self.failed(Some(e.0), what)
                {
                    why.push(self.why(r));
                    *value = None;
                    if what == "time_shift" {
                        timing.push(e.0);
                    }
                }
            }
        }
        (why, timing)
    }
}

/// The channel's name and the correction's kind of `u` (`None` for the AHRS lag and initial
/// states).
fn names(u: Unknown) -> (Option<&'static str>, &'static str) {
    match u {
        Unknown::Bias(c) => (Some(c.name()), "bias"),
        Unknown::Scale(c) => (Some(c.name()), "scale"),
        Unknown::TimeShift(c) => (Some(c.name()), "time_shift"),
        Unknown::AhrsLag => (None, "ahrs_lag"),
        Unknown::Initial { .. } => (None, "initial_state"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(change: f64, expected: f64, spread: f64, pieces: usize) -> HeldOutRow {
        HeldOutRow {
            channel: Some("alpha_rad".into()),
            correction: "time_shift".into(),
            change_neg_log_likelihood: change,
            pieces,
            expected,
            spread,
            verdict: String::new(),
        }
    }

    /// The failure rule on both sides of each of its thresholds, hand-set: the rise floor
    /// (χ²₁ 95 % / 2 = 1.9207), the three spreads above the expectation, and judged pieces.
    #[test]
    fn the_failure_rule_at_each_edge() {
        let floor = compat::MIN_FAILING_RISE;
        assert!((floor - 1.920_729_410_347_062).abs() < 1e-12);
        let e = 1e-9;
        #[rustfmt::skip]
        let table: [(f64, f64, f64, usize, bool, &str); 9] = [
            (floor + e, 0.0, 0.0, 2, true, "0 ± 0: a rise past the floor fails"),
            (floor - e, 0.0, 0.0, 2, false, "0 ± 0: a rise below the floor stands"),
            (1e-12, 0.0, 0.0, 2, false, "0 ± 0: rounding is no rise"),
            (10.0 + 3.0 * 2.0 + 1e-6, 10.0, 2.0, 3, true, "just past 3 spreads"),
            (10.0 + 3.0 * 2.0 - 1e-6, 10.0, 2.0, 3, false, "just inside 3 spreads"),
            (-5.0, -20.0, 1.0, 3, false, "an improvement never fails"),
            (floor - e, -20.0, 0.1, 3, false, "far past 3 spreads, below the floor"),
            (floor + e, -20.0, 0.1, 3, true, "far past 3 spreads, past the floor"),
            (1e6, 0.0, 0.0, 0, false, "not judged"),
        ];
        for (change, expected, spread, pieces, failing, case) in table {
            assert_eq!(row(change, expected, spread, pieces).fails(), failing, "{case}");
        }
    }

    /// The reason of a row whose expectation could not be formed says so, and the others give
    /// the expectation they were compared with.
    #[test]
    fn the_reason_names_a_comparison_that_could_not_be_formed() {
        let summary = |r: HeldOutRow| HeldOutSummary {
            by: "manoeuvre".into(),
            pieces: 3,
            corrections: vec![r],
            notes: Vec::new(),
        };
        let s = summary(row(4506.0, 0.0, 0.0, 3));
        let why = s.why(&s.corrections[0]);
        assert!(why.contains("rises by 4506.0"), "{why}");
        assert!(why.contains("does not curve along it") && !why.contains("± 0.0"), "{why}");
        let s = summary(row(40.0, 2.0, 3.0, 3));
        let why = s.why(&s.corrections[0]);
        assert!(why.contains("would change it by +2.0 ± 3.0"), "{why}");
    }
}
