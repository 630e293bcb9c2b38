//! The state of one derivative in the live view, from its estimate and σ over time.
//!
//! - **waiting** (for excitation): the estimator has no estimate yet. A recursive estimator
//!   gives none until the inputs have excited the parameter enough to separate it from the
//!   others (RLS: until its information matrix has full rank).
//! - **converging**: an estimate, but its σ is above the set fraction of its magnitude, or it
//!   has been below it for less than the hold time, or the estimator gives no σ.
//! - **identified**: σ ≤ `sigma_fraction` × |estimate| continuously for `hold_s`, and over that
//!   time the estimate stayed within a band of width `sigma_fraction` × |estimate| (it is
//!   stable, not merely confident while it drifts).
//! - **flagged**, with the reason: while running, the estimate lies outside the aircraft's
//!   plausible range by more than 2σ ([`crate::plausibility::implausible`]), or the methods
//!   following the feed split on it ([`super::panel`]).
//!
//! The σ rule is the running view's preview of how far a derivative has come. At the end the
//! final verdict ([`crate::verdict`], the summary's status and flags) replaces it, so the page
//! ends on the same verdict as `summary.json`.
//!
//! A flag overlays the other three states without resetting them: the σ rule and its hold
//! are followed throughout, so a derivative whose flag clears shows at once where it stands.

/// The thresholds of the states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseRule {
    /// Largest σ / |estimate| of an identified derivative (default 0.1: 10 %).
    pub sigma_fraction: f64,
    /// How long the σ must stay below the fraction, and the estimate in its band, s
    /// (default 2 s).
    pub hold_s: f64,
}

impl Default for PhaseRule {
    fn default() -> Self {
        Self { sigma_fraction: 0.1, hold_s: 2.0 }
    }
}

/// One derivative's state (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// No estimate yet: waiting for excitation.
    Waiting,
    /// An estimate, not yet precise or stable enough.
    Converging,
    /// Precise and stable for the hold time.
    Identified,
    /// Flagged; the reason is beside it.
    Flagged,
}

/// Since when a derivative has met the σ rule, and the band its estimate spanned since.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Since {
    t_s: f64,
    lo: f64,
    hi: f64,
}

/// The state machine of one derivative (module doc).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tracker {
    since: Option<Since>,
    /// The state without the flag (none before the first step: waiting).
    phase: Option<Phase>,
    /// The flag's reason.
    reason: Option<String>,
}

impl Tracker {
    /// The state now (waiting before the first step).
    pub fn phase(&self) -> Phase {
        if self.reason.is_some() { Phase::Flagged } else { self.phase.unwrap_or(Phase::Waiting) }
    }

    /// Why it is flagged (`None` unless [`Phase::Flagged`]).
    pub fn reason(&self) -> Option<&str> {
        self.reason.as_deref()
    }

    /// One sample at `t_s`: the estimate, its σ and the flag of that estimate now (the
    /// reasons joined), which holds until the next step.
    pub fn step(
        &mut self,
        rule: &PhaseRule,
        t_s: f64,
        value: Option<f64>,
        sigma: Option<f64>,
        flag: Option<String>,
    ) {
        let Some(v) = value.filter(|v| v.is_finite()) else {
            self.reason = None;
            self.since = None;
            self.phase = Some(Phase::Waiting);
            return;
        };
        self.reason = flag;
        let limit = rule.sigma_fraction * v.abs();
        let tight = sigma.is_some_and(|s| s.is_finite() && s <= limit);
        if !tight {
            self.since = None;
            self.phase = Some(Phase::Converging);
            return;
        }
        let since = match self.since {
            Some(s) if s.hi.max(v) - s.lo.min(v) <= limit => {
                Since { t_s: s.t_s, lo: s.lo.min(v), hi: s.hi.max(v) }
            }
            // First time within the rule, or the estimate left its band: the hold restarts.
            _ => Since { t_s, lo: v, hi: v },
        };
        self.since = Some(since);
        let held = t_s - since.t_s >= rule.hold_s;
        self.phase = Some(if held { Phase::Identified } else { Phase::Converging });
    }

    /// A flag set between steps (a judgement of the running cross-check), until the next
    /// step; none while there is no estimate.
    pub fn flag(&mut self, reason: Option<String>) {
        if self.phase.is_some_and(|p| p != Phase::Waiting) {
            self.reason = reason;
        }
    }

    /// The end of the run: the final verdict ([`crate::verdict`]) replaces the running state.
    /// `identified` is identified whatever the σ rule said (σ above its fraction is a note,
    /// not a doubt); `flagged` is flagged with its flags; a parameter without an estimate is
    /// waiting; any other status (`diverged`, `not converged`) is flagged with it.
    pub fn conclude(&mut self, status: &str, flags: &[String]) {
        use aeroident_io::parameter::{STATUS_IDENTIFIED, STATUS_NOT_IDENTIFIED};
        self.since = None;
        (self.phase, self.reason) = match status {
            STATUS_IDENTIFIED => (Some(Phase::Identified), None),
            STATUS_NOT_IDENTIFIED => (Some(Phase::Waiting), None),
            _ if flags.is_empty() => (Some(Phase::Flagged), Some(status.to_string())),
            _ => (Some(Phase::Flagged), Some(flags.join("; "))),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RULE: PhaseRule = PhaseRule { sigma_fraction: 0.1, hold_s: 2.0 };

    /// Waiting without an estimate; converging while σ is above 10 % of |estimate|; identified
    /// only once σ ≤ 10 % has held for 2 s with the estimate inside a band of 10 % of its
    /// magnitude; a jump out of that band restarts the hold.
    #[test]
    fn states_follow_the_sigma_rule_and_the_hold_time() {
        let mut k = Tracker::default();
        assert_eq!(k.phase(), Phase::Waiting);
        k.step(&RULE, 0.0, None, None, None);
        assert_eq!(k.phase(), Phase::Waiting);
        // σ = 0.2 on an estimate of −1: 20 % > 10 %.
        k.step(&RULE, 0.1, Some(-1.0), Some(0.2), None);
        assert_eq!(k.phase(), Phase::Converging);
        // No σ: never identified.
        k.step(&RULE, 0.2, Some(-1.0), None, None);
        assert_eq!(k.phase(), Phase::Converging);
        // σ 5 % from t = 1 s: identified at t = 3 s, not before.
        for i in 0..20 {
            let t = 1.0 + 0.1 * f64::from(i);
            k.step(&RULE, t, Some(-1.0 + 0.001 * f64::from(i)), Some(0.05), None);
            assert_eq!(k.phase(), Phase::Converging, "t = {t}");
        }
        k.step(&RULE, 3.0, Some(-0.98), Some(0.05), None);
        assert_eq!(k.phase(), Phase::Identified);
        // A jump by 0.15 (> 10 % of 0.83) restarts the hold although σ stays small.
        k.step(&RULE, 3.1, Some(-0.83), Some(0.05), None);
        assert_eq!(k.phase(), Phase::Converging);
        k.step(&RULE, 5.0, Some(-0.83), Some(0.05), None);
        assert_eq!(k.phase(), Phase::Converging);
        k.step(&RULE, 5.2, Some(-0.83), Some(0.05), None);
        assert_eq!(k.phase(), Phase::Identified);
    }

    /// A running flag flags the derivative with its reason while it holds, without resetting
    /// the σ rule's hold underneath; the final verdict replaces the running state: identified
    /// even where the σ rule still said converging, flagged with its flags, or with its status.
    #[test]
    fn flags_carry_their_reason() {
        let mut k = Tracker::default();
        k.step(&RULE, 0.0, Some(5.0), Some(0.1), Some("outside".into()));
        assert_eq!((k.phase(), k.reason()), (Phase::Flagged, Some("outside")));
        k.step(&RULE, 0.1, Some(-1.0), Some(0.01), None);
        assert_eq!((k.phase(), k.reason()), (Phase::Converging, None));
        // Flagged from 1 s to 2.1 s while σ stays at 1 %: identified at once when it clears,
        // the hold having run from 0.1 s underneath.
        for i in 0..=11 {
            let t = 1.0 + 0.1 * f64::from(i);
            k.step(&RULE, t, Some(-1.0), Some(0.01), Some("cross-check: split".into()));
            assert_eq!(k.phase(), Phase::Flagged, "t = {t}");
        }
        k.step(&RULE, 2.2, Some(-1.0), Some(0.01), None);
        assert_eq!((k.phase(), k.reason()), (Phase::Identified, None));
        k.step(&RULE, 2.3, Some(-1.0), Some(0.01), Some("cross-check: split".into()));
        k.conclude("identified", &[]);
        assert_eq!((k.phase(), k.reason()), (Phase::Identified, None));
        k.conclude("flagged", &["cross-check: a".into(), "b".into()]);
        assert_eq!((k.phase(), k.reason()), (Phase::Flagged, Some("cross-check: a; b")));
        // σ 20 % (converging by the σ rule) but identified by the verdict: identified.
        k.step(&RULE, 2.4, Some(-1.0), Some(0.2), None);
        assert_eq!(k.phase(), Phase::Converging);
        k.conclude("identified", &[]);
        assert_eq!(k.phase(), Phase::Identified);
        k.conclude("diverged", &[]);
        assert_eq!((k.phase(), k.reason()), (Phase::Flagged, Some("diverged")));
        k.conclude("not identified", &[]);
        assert_eq!(k.phase(), Phase::Waiting);
    }
}
