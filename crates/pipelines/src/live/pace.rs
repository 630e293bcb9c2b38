//! Pacing of a recorded file for a live view: the wall clock follows the record's time at
//! `speed` × real time.

use std::time::{Duration, Instant};

/// A record-time step longer than this is not slept across (a gap, a jump of the clock): the
/// wall clock restarts at the next sample.
pub const JUMP_S: f64 = 5.0;

/// Holds a replay at `speed` × real time (module doc).
#[derive(Debug, Clone)]
pub struct Pace {
    speed: f64,
    clock: Option<(Instant, f64)>,
    prev_t_s: Option<f64>,
}

impl Pace {
    /// A pace of `speed` × real time; `None` unless `speed` is finite and > 0.
    pub fn new(speed: f64) -> Option<Self> {
        (speed.is_finite() && speed > 0.0).then_some(Self { speed, clock: None, prev_t_s: None })
    }

    /// How long to wait, from `now`, before the sample at record time `t_s` is due.
    pub fn wait(&mut self, t_s: f64, now: Instant) -> Duration {
        let jumped = self.prev_t_s.is_some_and(|p| !(t_s - p).is_finite() || t_s - p > JUMP_S);
        if jumped {
            self.clock = None;
        }
        self.prev_t_s = Some(t_s);
        let (start, t0) = *self.clock.get_or_insert((now, t_s));
        let due_s = (t_s - t0) / self.speed;
        let elapsed = now.saturating_duration_since(start).as_secs_f64();
        Duration::try_from_secs_f64(due_s - elapsed).unwrap_or(Duration::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At 10× a record step of 0.1 s waits 10 ms of wall time; a jump longer than 5 s is not
    /// slept across; a non-positive speed is refused.
    #[test]
    fn waits_the_record_step_divided_by_the_speed() {
        let now = Instant::now();
        let mut p = Pace::new(10.0).unwrap();
        assert_eq!(p.wait(100.0, now), Duration::ZERO);
        let w = p.wait(100.1, now).as_secs_f64();
        assert!((w - 0.01).abs() < 1e-9, "{w}");
        // 4 ms already passed: 6 ms are left of the second step's 20 ms.
        let w = p.wait(100.2, now + Duration::from_millis(14)).as_secs_f64();
        assert!((w - 0.006).abs() < 1e-9, "{w}");
        assert_eq!(p.wait(1e9, now), Duration::ZERO);
        assert_eq!(p.wait(f64::INFINITY, now), Duration::ZERO);
        assert!(Pace::new(0.0).is_none() && Pace::new(f64::NAN).is_none());
    }
}
