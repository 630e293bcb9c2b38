//! The held-out judgement of a check's corrections as `compat.json` carries it, and the
//! refusal of each correction that fails it ([`aeroident_estimators::compat::held_out`]).

use super::Entry;
use aeroident_estimators::compat::{self, Channel, HeldOut, Unknown};
use serde::{Deserialize, Serialize};

/// `compat.json` `held_out`: each correction applied to data it was not fitted on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutSummary {
    /// What was held out in turn: `manoeuvre` or `half` (of a record with one manoeuvre).
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

    /// The reason a failed row gives in `compat refused: …`.
    fn why(&self, r: &HeldOutRow) -> String {
        format!(
            "{}: applied to the {} held out in turn ({} of {}) it worsens their fit (their −ln L rises by {:.1}, where a true correction of its size would change it by {:+.1} ± {:.1}): the rest of the record contradicts it",
            r.label(),
            if self.by == "half" { "halves" } else { "manoeuvres" },
            r.pieces,
            self.pieces,
            r.change_neg_log_likelihood,
            r.expected,
            r.spread
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
