//! Commanded surfaces through their actuators: a surface the mapping declares as a command
//! (`actuator = { … }`, [`aeroident_io::mapping::Actuator`]) is replaced, sample by sample, by
//! the deflection its actuator gives (first-order lag with rate and position limits, the command
//! held over each interval), so every estimator sees the modelled surface, not the command.
//!
//! The actuator starts at the command of the first sample of the record and after each gap
//! (a trimmed surface), and is not stepped across rejected rows (the next good sample's interval
//! covers them). Without this, the command leads the surface by about the actuator's time
//! constant and every method's control and damping derivatives come out low.
//!
//! An actuator that holds its surface at a position limit, or at its rate limit, over most of
//! the record ([`PINNED_SHARE`]) is named ([`Actuated::saturation`]): the estimators then see a
//! surface that barely moves, whose derivatives the record cannot give however converged the
//! fit (a rate limit of 1e-9 rad/s gave Cm_δe −42,565 ± 5e9, "converged").

use aeroident_estimators::AirDataSample;
use aeroident_io::mapping::{Actuator, Channel};
use aeroident_io::{FlightDataError, RecordEvent};
use std::sync::{Arc, Mutex, PoisonError};

/// The share of a surface's steps at a position or rate limit above which the actuator is
/// named as holding it: a real servo saturates in the peaks of a large input, not through most
/// of a record.
pub const PINNED_SHARE: f64 = 0.5;

/// How often one actuator held its surface: steps taken, steps ending at a position limit,
/// steps cut by the rate limit.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Saturation {
    /// Samples of the surface (its first after a start or gap included).
    pub samples: usize,
    /// Samples whose deflection lies at a position limit.
    pub at_limit: usize,
    /// Steps the rate limit cut short.
    pub rate_limited: usize,
}

impl Saturation {
    /// The warning for channel `ch` with actuator `a` when most of its samples were held
    /// ([`PINNED_SHARE`]); `None` otherwise.
    pub fn warning(&self, ch: Channel, a: &Actuator) -> Option<String> {
        use aeroident_io::message::short;
        let share = |k: usize| k as f64 / self.samples.max(1) as f64;
        let (lo, hi) = a.position_limits_rad;
        let why = if share(self.at_limit) > PINNED_SHARE {
            format!(
                "at a position limit ({} … {} rad) in {:.0} % of its samples",
                short(lo),
                short(hi),
                100.0 * share(self.at_limit)
            )
        } else if share(self.rate_limited) > PINNED_SHARE {
            format!(
                "at its rate limit ({} rad/s) in {:.0} % of its steps",
                short(a.rate_limit_rad_s),
                100.0 * share(self.rate_limited)
            )
        } else {
            return None;
        };
        Some(format!(
            "the actuator declared for `{}` held the modelled surface {why}: every estimator sees a surface that barely follows its command, so its derivatives are not given by this record; check the mapping's `actuator` of `{}`",
            ch.key(),
            ch.key()
        ))
    }
}

/// The surface field of channel `ch` (`de`, `da`, `dr`; any other is taken as `dr`: callers
/// pass a surface, [`is_surface`]).
pub(super) fn surface(s: &mut AirDataSample, ch: Channel) -> &mut Option<f64> {
    match ch {
        Channel::De => &mut s.de_rad,
        Channel::Da => &mut s.da_rad,
        _ => &mut s.dr_rad,
    }
}

/// The value of surface `ch` in `s` (the field [`surface`] names). Read per sample by the
/// time-shift stage, so it reads the field rather than cloning the sample to borrow it.
pub(super) fn surface_value(s: &AirDataSample, ch: Channel) -> Option<f64> {
    match ch {
        Channel::De => s.de_rad,
        Channel::Da => s.da_rad,
        _ => s.dr_rad,
    }
}

/// Whether `ch` is a control surface (`de`, `da`, `dr`).
pub(super) fn is_surface(ch: Channel) -> bool {
    matches!(ch, Channel::De | Channel::Da | Channel::Dr)
}

/// The note a summary carries for commanded surface `ch`: what every estimator sees instead.
pub fn note(ch: Channel, a: &Actuator) -> String {
    let (lo, hi) = a.position_limits_rad;
    let limits =
        if lo.is_finite() { format!(", position {lo:.4} … {hi:.4} rad") } else { String::new() };
    let rate = if a.rate_limit_rad_s.is_finite() {
        format!(", rate limit {:.4} rad/s", a.rate_limit_rad_s)
    } else {
        String::new()
    };
    format!(
        "`{}` is mapped as a command: every estimator sees the deflection of its declared actuator (first-order lag τ {} s{rate}{limits}), not the command",
        ch.key(),
        a.tau_s
    )
}

/// One actuated surface: its actuator and its last (time, command, deflection).
#[derive(Debug, Clone)]
struct Surface {
    channel: Channel,
    actuator: Actuator,
    last: Option<(f64, f64, f64)>,
}

/// Each actuated surface's channel, actuator and [`Saturation`] so far, shared with whoever
/// reads the notes after the events ([`Actuated::saturation`]). Counted as the samples pass,
/// so a replay that stops early (a signal, a divergence) still reports what it saw.
pub type SaturationCounts = Arc<Mutex<Vec<(Channel, Actuator, Saturation)>>>;

/// The events of `inner` with each commanded surface replaced by its actuator's deflection.
pub struct Actuated<I> {
    inner: I,
    surfaces: Vec<Surface>,
    counts: SaturationCounts,
}

impl<I> Actuated<I> {
    /// The events of `inner` through the actuators `actuators` (channel, actuator).
    pub fn new(inner: I, actuators: impl IntoIterator<Item = (Channel, Actuator)>) -> Self {
        let surfaces: Vec<Surface> = actuators
            .into_iter()
            .map(|(channel, actuator)| Surface { channel, actuator, last: None })
            .collect();
        let counts =
            surfaces.iter().map(|a| (a.channel, a.actuator, Saturation::default())).collect();
        Self { inner, surfaces, counts: Arc::new(Mutex::new(counts)) }
    }

    /// How often each actuator held its surface so far, shared: read it after the events.
    pub fn saturation(&self) -> SaturationCounts {
        self.counts.clone()
    }

    fn actuate(&mut self, s: &mut AirDataSample) {
        let t_s = s.t_s;
        let mut counts = self.counts.lock().unwrap_or_else(PoisonError::into_inner);
        for (a, (_, _, n)) in self.surfaces.iter_mut().zip(counts.iter_mut()) {
            let field = surface(s, a.channel);
            let Some(command) = *field else {
                a.last = None;
                continue;
            };
            let (lo, hi) = a.actuator.position_limits_rad;
            let (deflection, rate_limited) = match a.last {
                Some((t, held, d)) if t_s > t => a.actuator.step_limited(d, held, t_s - t),
                Some((_, _, d)) => (d, false),
                None => (command.clamp(lo, hi), false),
            };
            n.samples += 1;
            n.rate_limited += usize::from(rate_limited);
            n.at_limit += usize::from(deflection <= lo || deflection >= hi);
            *field = Some(deflection);
            a.last = Some((t_s, command, deflection));
        }
    }
}

impl<I: Iterator<Item = Result<RecordEvent, FlightDataError>>> Iterator for Actuated<I> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        let mut event = self.inner.next()?;
        match &mut event {
            Ok(RecordEvent::Sample { sample, .. }) => self.actuate(sample),
            Ok(RecordEvent::Gap { .. }) => self.surfaces.iter_mut().for_each(|a| a.last = None),
            _ => {}
        }
        Some(event)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn actuator(tau_s: f64, rate: f64) -> Actuator {
        Actuator {
            tau_s,
            rate_limit_rad_s: rate,
            position_limits_rad: (f64::NEG_INFINITY, f64::INFINITY),
        }
    }

    fn sample(t_s: f64, de: f64) -> Result<RecordEvent, FlightDataError> {
        let sample = AirDataSample { t_s, de_rad: Some(de), ..Default::default() };
        Ok(RecordEvent::Sample { row: (t_s * 100.0) as u64, sample })
    }

    fn deflections(events: Vec<Result<RecordEvent, FlightDataError>>, a: Actuator) -> Vec<f64> {
        Actuated::new(events.into_iter(), [(Channel::De, a)])
            .filter_map(|e| match e {
                Ok(RecordEvent::Sample { sample, .. }) => sample.de_rad,
                _ => None,
            })
            .collect()
    }

    /// A unit step of the command through τ = 0.05 s, sampled at 100 Hz: the deflection is
    /// `1 − e^{−t/τ}` exactly (the command held over each interval), starting at the first
    /// command (0).
    #[test]
    fn analytic_step_response_of_the_lag() {
        let events =
            (0..50).map(|k| sample(k as f64 * 0.01, if k == 0 { 0.0 } else { 1.0 })).collect();
        let d = deflections(events, actuator(0.05, f64::INFINITY));
        for (k, d) in d.iter().enumerate().skip(1) {
            let t = (k - 1) as f64 * 0.01;
            let want = 1.0 - (-t / 0.05_f64).exp();
            assert!((d - want).abs() < 1e-12, "k {k}: {d} vs {want}");
        }
    }

    /// With a rate limit of 2 rad/s the same step moves 0.02 rad per 0.01 s while the lag asks
    /// for more; a gap restarts the actuator at the command.
    #[test]
    fn rate_limit_and_gap() {
        let mut events: Vec<_> =
            (0..20).map(|k| sample(k as f64 * 0.01, if k == 0 { 0.0 } else { 1.0 })).collect();
        events.push(Ok(RecordEvent::Gap { row: 999, dt_s: 5.0, nominal_dt_s: 0.01 }));
        events.push(sample(5.2, 0.3));
        let d = deflections(events, actuator(0.05, 2.0));
        assert!((d[1] - 0.0).abs() < 1e-12 && (d[2] - 0.02).abs() < 1e-12, "{d:?}");
        assert!((d[5] - 0.08).abs() < 1e-12, "{d:?}");
        assert_eq!(*d.last().unwrap(), 0.3);
    }

    /// The saturation counts of `actuator` driven by `commands` at 50 Hz.
    fn held(a: Actuator, commands: impl Iterator<Item = f64>) -> Saturation {
        let events: Vec<_> =
            commands.enumerate().map(|(k, u)| sample(k as f64 * 0.02, u)).collect();
        let actuated = Actuated::new(events.into_iter(), [(Channel::De, a)]);
        let counts = actuated.saturation();
        actuated.for_each(drop);
        counts.lock().unwrap()[0].2
    }

    /// A 0.05-rad square wave of 1 s period for 10 s.
    fn square() -> impl Iterator<Item = f64> {
        (0..500).map(|k| if (k / 25) % 2 == 0 { 0.05 } else { -0.05 })
    }

    /// An actuator that pins its surface is named, by what holds it: a rate limit of 1e-9
    /// rad/s (every step cut), position limits of ±0.001 rad (every sample at one); a real
    /// servo (τ 0.05 s, 1 rad/s, ±0.4 rad) on the same square wave is not.
    #[test]
    fn an_actuator_that_pins_its_surface_is_named() {
        let a = |tau_s, rate, lim: f64| Actuator {
            tau_s,
            rate_limit_rad_s: rate,
            position_limits_rad: (-lim, lim),
        };
        let slow = a(0.05, 1e-9, 0.4);
        let n = held(slow, square());
        // Stuck at its first deflection, it is cut whenever the command is away from that.
        assert!(n.samples == 500 && n.rate_limited > 450, "{n:?}");
        let w = n.warning(Channel::De, &slow).unwrap();
        assert!(w.contains("`de`") && w.contains("rate limit (1.000e-9 rad/s) in 9"), "{w}");
        let narrow = a(0.05, 1.0, 0.001);
        let n = held(narrow, square());
        assert_eq!(n.at_limit, 500, "{n:?}");
        let w = n.warning(Channel::De, &narrow).unwrap();
        assert!(w.contains("position limit (-0.001 … 0.001 rad) in 100 %"), "{w}");
        let servo = a(0.05, 1.0, 0.4);
        let n = held(servo, square());
        assert!(n.warning(Channel::De, &servo).is_none(), "{n:?}");
    }

    /// The share at its edge: half the samples held is a servo in a hard manoeuvre, more is
    /// named.
    #[test]
    fn the_pinned_share_at_its_edge() {
        let a = actuator(0.05, 1.0);
        let of = |at_limit, rate_limited| {
            Saturation { samples: 100, at_limit, rate_limited }.warning(Channel::Da, &a)
        };
        assert!(of(50, 0).is_none() && of(0, 50).is_none());
        assert!(of(51, 0).is_some() && of(0, 51).is_some());
    }
}
