//! The one aircraft estimator interface: consume an [`AirDataSample`], give [`Estimates`] of
//! the parameters of a [`ModelStructure`].
//!
//! Every aircraft estimator (recursive least squares, the Kalman filters, the sliding-mode and
//! gradient estimators) implements [`Estimator`]; the replay pipeline, the closed-loop
//! experiment and the bindings drive them through it and nothing else. An estimator that needs
//! a model state (the EKF, the sliding-mode and gradient estimators) carries and integrates it
//! itself from the samples' inputs, so it can be embedded in a flight computer fed only with
//! samples.

use crate::EstimatorError;
use crate::sample::AirDataSample;
use crate::vocabulary::{MAX_PARAMS, ModelStructure};

/// What state an estimator is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Not every parameter is identified yet (too few or too little informative samples).
    Initialising,
    /// Running; the identified parameters are usable.
    Running,
    /// The estimator diverged (non-finite or runaway state); its numbers are not a result.
    Diverged,
}

impl Status {
    /// `initialising`, `running` or `diverged` (the string in summaries).
    pub fn name(self) -> &'static str {
        match self {
            Status::Initialising => "initialising",
            Status::Running => "running",
            Status::Diverged => "diverged",
        }
    }
}

/// What an estimator did to itself that changes how its numbers must be read
/// ([`Event`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// The estimator restarted from its priors after a divergence rule fired (the `subject`
    /// names what failed): its estimates and σ from then on come from the samples after the
    /// event only.
    Restart,
    /// A run of innovation-gate rejections of one output (the `subject`) was re-anchored: the
    /// predicted variance of what it sees was raised to the gate's bound and the output used
    /// again.
    Reanchor,
    /// A change of one parameter (the `subject`) was detected and its variance inflated so the
    /// estimate can follow.
    ChangeDetected,
}

impl EventKind {
    /// Every kind, in [`EventLog::count`] order.
    pub const ALL: [EventKind; 3] =
        [EventKind::Restart, EventKind::Reanchor, EventKind::ChangeDetected];

    /// `restart`, `reanchor` or `change_detected` (the string in summaries).
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Restart => "restart",
            EventKind::Reanchor => "reanchor",
            EventKind::ChangeDetected => "change_detected",
        }
    }

    fn index(self) -> usize {
        match self {
            EventKind::Restart => 0,
            EventKind::Reanchor => 1,
            EventKind::ChangeDetected => 2,
        }
    }
}

/// One [`EventKind`] at a time: the sample time it happened at (s) and what it concerns (an
/// output or parameter name, or the rule that fired).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// Time of the sample at which it happened, s.
    pub t_s: f64,
    /// What happened.
    pub kind: EventKind,
    /// The output (its sample field, e.g. `p_rad_s`), parameter (e.g. `Cl_p`), coefficient
    /// equation (e.g. `Cm`) or rule it concerns.
    pub subject: &'static str,
    /// The test statistic that raised it, where there is one (the normalised drift `d/m₁` of
    /// the equation-error change test, `crate::change`); `None` otherwise.
    pub statistic: Option<f64>,
}

/// Capacity of an [`EventLog`]'s list: the first this many events are kept.
pub const EVENT_LOG_CAPACITY: usize = 32;

/// Places of an [`EventLog`]'s list kept for [`EventKind::Restart`] events: the other kinds
/// are listed only while more than this many places are free, so the first
/// `EVENT_LOG_RESTART_RESERVE` restarts are always listed.
pub const EVENT_LOG_RESTART_RESERVE: usize = 4;

/// The events of an estimator, in time order, without allocating: the first events are listed
/// ([`EventLog::listed`]; [`EVENT_LOG_CAPACITY`] places, of which
/// [`EVENT_LOG_RESTART_RESERVE`] only for restarts), and every event is counted by kind
/// ([`EventLog::count`]), so counts stay exact when the list is full.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventLog {
    events: [Event; EVENT_LOG_CAPACITY],
    len: usize,
    counts: [u32; 3],
}

impl Default for EventLog {
    fn default() -> Self {
        Self::new()
    }
}

/// The log of an estimator that has no events.
static NO_EVENTS: EventLog = EventLog::new();

impl EventLog {
    /// An empty log.
    pub const fn new() -> Self {
        Self {
            events: [Event { t_s: 0.0, kind: EventKind::Restart, subject: "", statistic: None };
                EVENT_LOG_CAPACITY],
            len: 0,
            counts: [0; 3],
        }
    }

    /// Records `kind` at `t_s` about `subject`: listed while there is room, always counted.
    pub fn push(&mut self, t_s: f64, kind: EventKind, subject: &'static str) {
        self.push_event(Event { t_s, kind, subject, statistic: None });
    }

    /// Records `kind` at `t_s` about `subject` raised by a test statistic `statistic`, as
    /// [`Self::push`].
    pub fn push_with_statistic(
        &mut self,
        t_s: f64,
        kind: EventKind,
        subject: &'static str,
        statistic: f64,
    ) {
        self.push_event(Event { t_s, kind, subject, statistic: Some(statistic) });
    }

    fn push_event(&mut self, event: Event) {
        let kind = event.kind;
        let room = match kind {
            EventKind::Restart => EVENT_LOG_CAPACITY,
            _ => EVENT_LOG_CAPACITY - EVENT_LOG_RESTART_RESERVE,
        };
        if self.len < room {
            self.events[self.len] = event;
            self.len += 1;
        }
        let c = &mut self.counts[kind.index()];
        *c = c.saturating_add(1);
    }

    /// The listed events, in time order.
    pub fn listed(&self) -> &[Event] {
        &self.events[..self.len]
    }

    /// How many events of `kind` happened (listed or not).
    pub fn count(&self, kind: EventKind) -> u32 {
        self.counts[kind.index()]
    }

    /// How many events happened and were not listed (the list was full).
    pub fn unlisted(&self) -> u32 {
        let total: u64 = self.counts.iter().map(|&c| u64::from(c)).sum();
        u32::try_from(total.saturating_sub(self.len as u64)).unwrap_or(u32::MAX)
    }

    /// Where the log stands now, for a later [`Self::absorb`] of what it gains after.
    pub(crate) fn mark(&self) -> EventMark {
        EventMark { len: self.len, counts: self.counts }
    }

    /// Adds what `other` gained since `since` (its earlier [`Self::mark`]): its newly listed
    /// events, listed here while there is room, and every event it counted, listed or not. The
    /// one log of estimators run as one (`crate::ekf::EkfBlocks`), exact in its counts as a
    /// log of its own.
    pub(crate) fn absorb(&mut self, other: &EventLog, since: EventMark) {
        let mut counted = since.counts;
        for &e in &other.events[since.len.min(other.len)..other.len] {
            self.push_event(e);
            counted[e.kind.index()] = counted[e.kind.index()].saturating_add(1);
        }
        for (c, (now, seen)) in self.counts.iter_mut().zip(other.counts.iter().zip(counted)) {
            *c = c.saturating_add(now.saturating_sub(seen));
        }
    }
}

/// Where an [`EventLog`] stood: its listed length and its counts ([`EventLog::mark`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct EventMark {
    len: usize,
    counts: [u32; 3],
}

/// The current estimates of a structure's parameters: value and standard error of each, and
/// whether it is identified. Fixed capacity, parameter order of the structure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimates {
    /// Time of the last sample used, s.
    pub t_s: f64,
    /// Number of parameters (`structure.n_params()`).
    pub n: usize,
    /// Estimator state.
    pub status: Status,
    value: [f64; MAX_PARAMS],
    sigma: [Option<f64>; MAX_PARAMS],
    identified: [bool; MAX_PARAMS],
}

impl Estimates {
    /// `n` parameters, none identified.
    pub fn new(n: usize) -> Self {
        Self {
            t_s: 0.0,
            n: n.min(MAX_PARAMS),
            status: Status::Initialising,
            value: [0.0; MAX_PARAMS],
            sigma: [None; MAX_PARAMS],
            identified: [false; MAX_PARAMS],
        }
    }

    /// Value of parameter `i`: `None` until it is identified (never a placeholder 0).
    pub fn value(&self, i: usize) -> Option<f64> {
        (i < self.n && self.identified[i]).then(|| self.value[i])
    }

    /// Standard error of parameter `i`, where the method gives one and the value is identified.
    pub fn sigma(&self, i: usize) -> Option<f64> {
        if i < self.n && self.identified[i] { self.sigma[i] } else { None }
    }

    /// Whether parameter `i` is identified.
    pub fn is_identified(&self, i: usize) -> bool {
        i < self.n && self.identified[i]
    }

    /// The estimator's internal value of parameter `i` even before identification (its prior
    /// or running value), for diagnostics only.
    pub fn raw_value(&self, i: usize) -> f64 {
        self.value[i.min(MAX_PARAMS - 1)]
    }

    /// Sets parameter `i` (value, σ, identified). Out-of-range `i` is ignored.
    pub fn set(&mut self, i: usize, value: f64, sigma: Option<f64>, identified: bool) {
        if i < self.n {
            self.value[i] = value;
            self.sigma[i] = sigma;
            self.identified[i] = identified;
        }
    }

    /// Whether all parameters are identified.
    pub fn all_identified(&self) -> bool {
        self.identified[..self.n].iter().all(|b| *b)
    }
}

/// An online aircraft estimator over one [`ModelStructure`]: consumes one [`AirDataSample`] at
/// a time and gives the current [`Estimates`]. Object-safe (`Box<dyn Estimator>`).
///
/// Implementations must not allocate or do I/O in [`Estimator::update`], and must leave their
/// state unchanged when they refuse a sample (an input error: a missing or non-finite channel,
/// time not increasing). A numerical failure on valid input is a divergence: the estimator sets
/// [`Status::Diverged`], returns the error, and its numbers are no longer a result.
pub trait Estimator {
    /// The method's name as used on the command line and in summaries (`rls`, `ekf` …).
    fn method(&self) -> &'static str;

    /// The model structure whose parameters are estimated.
    fn structure(&self) -> &ModelStructure;

    /// Consumes one sample.
    ///
    /// # Errors
    /// [`EstimatorError::NonFiniteInput`] for a non-finite or missing channel the structure
    /// needs, [`EstimatorError::Numerical`] when the update fails; the state is unchanged.
    fn update(&mut self, sample: &AirDataSample) -> Result<&Estimates, EstimatorError>;

    /// The current estimates.
    fn estimates(&self) -> &Estimates;

    /// Estimation-error covariance of parameters `i` and `j` where the method gives one (units
    /// of the parameters' product); `None` where it does not (e.g. between independently
    /// fitted coefficients, or for sliding-mode estimators).
    fn covariance(&self, _i: usize, _j: usize) -> Option<f64> {
        None
    }

    /// Mean normalised innovation squared `e²/S` over every accepted scalar innovation so far
    /// (Bar-Shalom, Li & Kirubarajan 2001, §5.4: 1 for a consistent filter, > 1 when its
    /// covariance is optimistic); `None` for methods without innovations.
    fn nis(&self) -> Option<f64> {
        None
    }

    /// What the estimator did to itself so far ([`EventKind`]: restarts, re-anchored outputs,
    /// detected parameter changes): every one is to be shown with its results, never hidden.
    /// Empty for methods without such events.
    fn events(&self) -> &EventLog {
        &NO_EVENTS
    }

    /// A new manoeuvre starts with the next sample (a gap in the record, a second run):
    /// re-initialise the model state from the next sample and keep the parameters, as
    /// multi-run estimation does. Estimators without a model state ignore it.
    fn new_manoeuvre(&mut self) {}
}

/// Checks a sample before any estimator uses it: every present value finite
/// ([`EstimatorError::NonFiniteInput`] naming the first that is not) and within the physical
/// limits of [`crate::sample::PLAUSIBILITY`] ([`EstimatorError::ImplausibleInput`]).
///
/// # Errors
/// As described.
pub fn check_finite(s: &AirDataSample) -> Result<(), EstimatorError> {
    if let Some((field, value)) = s.first_non_finite() {
        return Err(EstimatorError::NonFiniteInput { field, value, t_s: s.t_s });
    }
    if let Some((field, value, limit)) = s.first_implausible() {
        return Err(EstimatorError::ImplausibleInput { field, value, t_s: s.t_s, limit });
    }
    Ok(())
}

/// The measured value of coefficient `c` from `measured` (sample `s`'s
/// [`AirDataSample::measured_coefficients`]), present and plausible: the dependent variable of
/// the equation-error estimators (RLS, FTR).
///
/// # Errors
/// [`EstimatorError::NonFiniteInput`] naming the channel or constant of `s` the coefficient
/// needs and lacks ([`crate::vocabulary::Coefficient::missing_field`]; the coefficient itself only if none is);
/// [`EstimatorError::ImplausibleInput`] beyond the coefficient limit.
pub fn measured_coefficient(
    s: &AirDataSample,
    measured: &crate::sample::CoefficientValues,
    c: crate::vocabulary::Coefficient,
) -> Result<f64, EstimatorError> {
    let y = measured[c.index()].ok_or_else(|| EstimatorError::NonFiniteInput {
        field: c.missing_field(s).unwrap_or(c.name()),
        value: f64::NAN,
        t_s: s.t_s,
    })?;
    check_coefficient(c.name(), y, s.t_s)
}

/// The regressor of term `t` at sample `s` with the structure's α knots `knots`
/// ([`crate::vocabulary::Term::value`]), present.
///
/// # Errors
/// [`EstimatorError::NonFiniteInput`] naming the channel or constant the term needs and `s`
/// lacks ([`crate::vocabulary::Term::missing_field`]).
pub fn regressor(
    t: crate::vocabulary::Term,
    s: &AirDataSample,
    knots: &crate::vocabulary::AlphaKnots,
) -> Result<f64, EstimatorError> {
    t.value(s, knots).ok_or_else(|| EstimatorError::NonFiniteInput {
        field: t.missing_field(s).unwrap_or("regressor (a term's channel is absent)"),
        value: f64::NAN,
        t_s: s.t_s,
    })
}

/// A measured coefficient checked against [`crate::sample::PLAUSIBILITY`]`.coefficient`.
///
/// # Errors
/// [`EstimatorError::ImplausibleInput`] naming the coefficient.
pub fn check_coefficient(field: &'static str, value: f64, t_s: f64) -> Result<f64, EstimatorError> {
    let limit = crate::sample::PLAUSIBILITY.coefficient;
    if value.is_finite() && value.abs() <= limit {
        Ok(value)
    } else {
        Err(EstimatorError::ImplausibleInput { field, value, t_s, limit })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two logs taken in step by step as one: every event counted, listed or not, and the
    /// first listed in the order they were taken in.
    #[test]
    fn absorbed_logs_count_every_event_of_both() {
        let (mut a, mut b, mut one) = (EventLog::new(), EventLog::new(), EventLog::new());
        let (mut seen_a, mut seen_b) = (a.mark(), b.mark());
        for k in 0..40 {
            let t = f64::from(k);
            a.push(t, EventKind::ChangeDetected, "Cl_p");
            b.push(t, EventKind::ChangeDetected, "Cm_alpha");
            if k % 3 == 0 {
                b.push(t, EventKind::Reanchor, "q_rad_s");
            }
            if k % 5 == 0 {
                one.absorb(&a, seen_a);
                one.absorb(&b, seen_b);
                (seen_a, seen_b) = (a.mark(), b.mark());
            }
        }
        one.absorb(&a, seen_a);
        one.absorb(&b, seen_b);
        assert_eq!(one.count(EventKind::ChangeDetected), 80);
        assert_eq!(one.count(EventKind::Reanchor), 14);
        assert_eq!(one.count(EventKind::Restart), 0);
        let listed = one.listed();
        assert_eq!(listed.len(), EVENT_LOG_CAPACITY - EVENT_LOG_RESTART_RESERVE);
        assert_eq!((listed[0].subject, listed[1].subject), ("Cl_p", "Cm_alpha"));
        assert_eq!(one.unlisted(), 94 - listed.len() as u32);
    }

    /// Past the capacity, events are no longer listed but every one is still counted by kind;
    /// restarts keep their reserved places after the other kinds have filled theirs.
    #[test]
    fn event_log_lists_the_first_events_and_counts_all() {
        let mut log = EventLog::new();
        assert!(log.listed().is_empty());
        for k in 0..EVENT_LOG_CAPACITY + 5 {
            let kind = if k % 2 == 0 { EventKind::Reanchor } else { EventKind::ChangeDetected };
            log.push(k as f64, kind, "p_rad_s");
        }
        let others = EVENT_LOG_CAPACITY - EVENT_LOG_RESTART_RESERVE;
        assert_eq!(log.listed().len(), others);
        log.push(99.0, EventKind::Restart, "alpha_rad");
        assert_eq!(log.listed().len(), others + 1);
        assert_eq!(log.listed()[others].kind, EventKind::Restart);
        assert_eq!(log.listed()[3].t_s, 3.0);
        assert_eq!(log.listed()[3].kind, EventKind::ChangeDetected);
        assert_eq!(log.count(EventKind::Reanchor), 19);
        assert_eq!(log.count(EventKind::ChangeDetected), 18);
        assert_eq!(log.count(EventKind::Restart), 1);
        assert_eq!(log.unlisted(), 37 - others as u32);
        for _ in 0..10 {
            log.push(100.0, EventKind::Restart, "alpha_rad");
        }
        assert_eq!(log.listed().len(), EVENT_LOG_CAPACITY);
        assert_eq!(log.count(EventKind::Restart), 11);
    }
}
