//! The thesis's discrete "1 − cosine" gust, applied per BODY axis (thesis eq. 2.32, §2.2.6;
//! `thesis-method.md` §5).
//!
//! ```text
//!     t′ = t − T_delay
//!     U(t) = 0                                   for t′ < 0
//!     U(t) = (U_wind / 2)·[1 − cos(π t′ / d)]    for 0 ≤ t′ ≤ d
//!     U(t) = U_wind                              for t′ > d
//! ```
//!
//! The gust ramps smoothly from 0 to `U_wind` in the rise time `d` and then HOLDS `U_wind` (the
//! thesis's figure 2.2, "Plot of Wind-Gust Along x_b Axis Over Time", with U_wind = 20 ft/s,
//! d = 6 s, T_delay = 2 s); it does not decay again as a JSBSim one-minus-cosine gust does.
//!
//! Frame and sign: see [`crate::WindField`] — the value is the air-mass velocity along the body
//! axis (ft/s); the aircraft's air-relative velocity is `v_body − wind_body`.

use nalgebra::Vector3;
use serde::Deserialize;

use crate::error::{SignalError, finite, non_negative, positive};
use crate::{InputSignal, WindField};

/// One 1-cos gust on one axis (thesis eq. 2.32). Also an [`InputSignal`] (ft/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneMinusCosineGust {
    amplitude_fps: f64,
    rise_time_s: f64,
    delay_s: f64,
}

impl OneMinusCosineGust {
    /// Gust of final magnitude `amplitude_fps` (U_wind, ft/s, any sign), rise time
    /// `rise_time_s` (d, s, > 0) and onset `delay_s` (T_delay, s, ≥ 0).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] naming the field for a non-finite value, `d ≤ 0` or
    /// `T_delay < 0`.
    pub fn new(amplitude_fps: f64, rise_time_s: f64, delay_s: f64) -> Result<Self, SignalError> {
        Ok(Self {
            amplitude_fps: finite("amplitude_fps", amplitude_fps)?,
            rise_time_s: positive("rise_time_s", rise_time_s)?,
            delay_s: non_negative("delay_s", delay_s)?,
        })
    }
}

impl InputSignal for OneMinusCosineGust {
    fn value(&self, t_s: f64) -> f64 {
        let tp = t_s - self.delay_s;
        if tp < 0.0 {
            0.0
        } else if tp <= self.rise_time_s {
            0.5 * self.amplitude_fps * (1.0 - (core::f64::consts::PI * tp / self.rise_time_s).cos())
        } else {
            self.amplitude_fps
        }
    }
}

/// A body axis (x forward, y right wing, z down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyAxis {
    /// x_b, forward (u component).
    X,
    /// y_b, right wing (v component).
    Y,
    /// z_b, down (w component).
    Z,
}

impl BodyAxis {
    /// Component index in a body vector: x → 0, y → 1, z → 2.
    pub fn index(self) -> usize {
        match self {
            BodyAxis::X => 0,
            BodyAxis::Y => 1,
            BodyAxis::Z => 2,
        }
    }
}

/// 1-cos gusts on any of the three body axes, each with its own U_wind, d and T_delay, as the
/// thesis's Simulink gust generator allows ("can be applied in any of the three axes").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyAxisGust {
    axes: [Option<OneMinusCosineGust>; 3],
}

impl BodyAxisGust {
    /// No gust on any axis.
    pub fn calm() -> Self {
        Self::default()
    }

    /// Returns `self` with `gust` on `axis` (replacing any previous gust on it).
    pub fn with(mut self, axis: BodyAxis, gust: OneMinusCosineGust) -> Self {
        self.axes[axis.index()] = Some(gust);
        self
    }
}

impl WindField for BodyAxisGust {
    fn wind_body_fps(&self, t_s: f64) -> Vector3<f64> {
        Vector3::from_fn(|i, _| self.axes[i].map_or(0.0, |g| g.value(t_s)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_one_minus_cos_gust_phase_by_phase() {
        // Thesis figure 2.2 example: U_wind = 20 ft/s, d = 6 s, T_delay = 2 s.
        let g = OneMinusCosineGust::new(20.0, 6.0, 2.0).unwrap();
        // Phase 1: before the delay, exactly zero.
        for t in [0.0, 1.0, 1.999_999] {
            assert_eq!(g.value(t), 0.0, "t = {t}");
        }
        // Phase 2: rise. At t' = 0: 0; t' = d/2: U/2; t' = d/3: U/2 (1 - cos(pi/3)) = U/4;
        // t' = d: U (continuity with phase 3).
        assert_eq!(g.value(2.0), 0.0);
        assert!((g.value(5.0) - 10.0).abs() < 1e-12);
        assert!((g.value(4.0) - 5.0).abs() < 1e-12);
        assert!((g.value(8.0) - 20.0).abs() < 1e-12);
        // Monotonic rise and zero slope at both ends (smooth onset).
        let slope = |t: f64| (g.value(t + 1e-6) - g.value(t - 1e-6)) / 2e-6;
        assert!(slope(2.0 + 1e-5).abs() < 1e-3);
        assert!(slope(8.0 - 1e-5).abs() < 1e-3);
        // Peak slope at mid-rise: U pi / (2 d).
        assert!((slope(5.0) - 20.0 * core::f64::consts::PI / 12.0).abs() < 1e-6);
        // Phase 3: hold U_wind.
        for t in [8.000_001, 10.0, 1000.0] {
            assert_eq!(g.value(t), 20.0);
        }
    }

    #[test]
    fn analytic_body_axis_gust_components() {
        let w = BodyAxisGust::calm()
            .with(BodyAxis::X, OneMinusCosineGust::new(20.0, 6.0, 2.0).unwrap())
            .with(BodyAxis::Z, OneMinusCosineGust::new(-5.0, 1.0, 0.0).unwrap());
        let v = w.wind_body_fps(5.0);
        assert!((v[0] - 10.0).abs() < 1e-12);
        assert_eq!(v[1], 0.0);
        assert_eq!(v[2], -5.0);
        assert_eq!(BodyAxisGust::calm().wind_body_fps(3.0), Vector3::zeros());
    }

    #[test]
    fn invalid_gust_parameters_are_errors() {
        let e = OneMinusCosineGust::new(20.0, 0.0, 2.0).unwrap_err();
        assert!(e.to_string().contains("rise_time_s"), "{e}");
        assert!(OneMinusCosineGust::new(20.0, 6.0, -1.0).is_err());
        assert!(OneMinusCosineGust::new(f64::NAN, 6.0, 1.0).is_err());
    }
}
