//! Commanded surfaces through their actuators: a surface the mapping declares as a command
//! (`actuator = { … }`, [`aeroident_io::mapping::Actuator`]) is replaced, sample by sample, by
//! the deflection its actuator gives (first-order lag with rate and position limits, the command
//! held over each interval), so every estimator sees the modelled surface, not the command.
//!
//! The actuator starts at the command of the first sample of the record and after each gap
//! (a trimmed surface), and is not stepped across rejected rows (the next good sample's interval
//! covers them). Without this, the command leads the surface by about the actuator's time
//! constant and every method's control and damping derivatives come out low.

use aeroident_estimators::AirDataSample;
use aeroident_io::mapping::{Actuator, Channel};
use aeroident_io::{FlightDataError, RecordEvent};

/// The surface field of channel `ch` (`de`, `da`, `dr`).
fn surface(s: &mut AirDataSample, ch: Channel) -> &mut Option<f64> {
    match ch {
        Channel::De => &mut s.de_rad,
        Channel::Da => &mut s.da_rad,
        _ => &mut s.dr_rad,
    }
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

/// The events of `inner` with each commanded surface replaced by its actuator's deflection.
pub struct Actuated<I> {
    inner: I,
    surfaces: Vec<Surface>,
}

impl<I> Actuated<I> {
    /// The events of `inner` through the actuators `actuators` (channel, actuator).
    pub fn new(inner: I, actuators: impl IntoIterator<Item = (Channel, Actuator)>) -> Self {
        let surfaces = actuators
            .into_iter()
            .map(|(channel, actuator)| Surface { channel, actuator, last: None })
            .collect();
        Self { inner, surfaces }
    }

    fn actuate(&mut self, s: &mut AirDataSample) {
        let t_s = s.t_s;
        for a in &mut self.surfaces {
            let field = surface(s, a.channel);
            let Some(command) = *field else {
                a.last = None;
                continue;
            };
            let deflection = match a.last {
                Some((t, held, d)) if t_s > t => a.actuator.step(d, held, t_s - t),
                Some((_, _, d)) => d,
                None => command
                    .clamp(a.actuator.position_limits_rad.0, a.actuator.position_limits_rad.1),
            };
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
}
