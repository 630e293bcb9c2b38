//! # aeroident-signals
//!
//! Signals that drive and observe a simulation: pilot inputs, gusts and turbulence, sensor
//! models, and causal signal tools (filters, differentiators) an estimator can run in real time.
//! All randomness comes from seeded generators so every run is reproducible bit for bit.
//!
//! Build signals with the validating constructors of each type, or from a scenario file with
//! [`config::InputConfig`] (the one place where `_deg` / `_hz` keys become radians and rad/s).

/// A scalar time signal, e.g. a pilot input on one control. Units are the caller's (radians for
/// surface deflections in the API). Signals superpose by summation.
pub trait InputSignal {
    /// Value at time `t_s` (s).
    fn value(&self, t_s: f64) -> f64;
}

impl<S: InputSignal + ?Sized> InputSignal for &S {
    fn value(&self, t_s: f64) -> f64 {
        (**self).value(t_s)
    }
}

impl<S: InputSignal + ?Sized> InputSignal for Box<S> {
    fn value(&self, t_s: f64) -> f64 {
        (**self).value(t_s)
    }
}

/// A wind field: the velocity of the air mass relative to the earth, resolved in BODY axes
/// (x forward, y right wing, z down), in ft/s, as a function of time.
///
/// Frame choice: the thesis applies its 1-cos gust per body axis (eq. 2.32, figure 2.2 "Wind-Gust
/// Along x_b") and MIL-F-8785C defines Dryden turbulence components u_g, v_g, w_g along the
/// aircraft axes, so both disturbances are body-axis quantities and no attitude is needed to
/// evaluate them. Sign: the aircraft's air-relative velocity is `v_body − wind_body`, so a
/// positive x component is a tailwind (it reduces airspeed) and a positive z component is a
/// downdraft. A model that wants NED wind rotates with its own DCM.
pub trait WindField {
    /// Air-mass velocity in body axes (ft/s) at time `t_s` (s).
    fn wind_body_fps(&self, t_s: f64) -> nalgebra::Vector3<f64>;
}

impl<W: WindField + ?Sized> WindField for &W {
    fn wind_body_fps(&self, t_s: f64) -> nalgebra::Vector3<f64> {
        (**self).wind_body_fps(t_s)
    }
}

impl<W: WindField + ?Sized> WindField for Box<W> {
    fn wind_body_fps(&self, t_s: f64) -> nalgebra::Vector3<f64> {
        (**self).wind_body_fps(t_s)
    }
}

/// Two wind fields superpose by vector addition (e.g. a gust plus turbulence).
impl<A: WindField, B: WindField> WindField for (A, B) {
    fn wind_body_fps(&self, t_s: f64) -> nalgebra::Vector3<f64> {
        self.0.wind_body_fps(t_s) + self.1.wind_body_fps(t_s)
    }
}

/// Serde configuration of inputs and winds (TOML shapes, unit conversion in one place).
pub mod config;
/// Causal numerical differentiation (least-squares slope, linear phase, stated lag).
pub mod differentiate;
/// Error type of the crate.
pub mod error;
/// Small causal ZOH-exact filters (first- and second-order low-pass).
pub mod filters;
/// The thesis's 1-cos gust per body axis (eq. 2.32).
pub mod gust;
/// Deterministic pilot inputs: step, pulse, doublet, 3-2-1-1, sine, sweeps, multisine, sum.
pub mod inputs;
/// Lag products `Σ x_t x_{t+k}` by direct sums or by the transform (Wiener–Khinchin).
pub mod lag_products;
/// Simulink-style band-limited white noise.
pub mod noise;
/// Orthogonal phase-optimised multisines for simultaneous multi-surface excitation (Morelli).
pub mod orthogonal;
/// Recorded input replayed from a CSV file (time, value).
pub mod recorded;
/// Per-channel sensor models: ZOH sampling, lag, bias, Gauss–Markov, noise, quantisation, delay.
pub mod sensors;
/// Frequency responses by composite-window spectral estimation (Tischler & Remple, CIFER).
pub mod spectral;
/// Low-order equivalent systems: transfer functions with delay fitted to frequency responses.
pub mod tf_fit;
/// Continuous Dryden turbulence (MIL-F-8785C), exactly discretised, seeded.
pub mod turbulence;

pub use config::{InputConfig, Wind, WindConfig};
pub use error::SignalError;
pub use gust::{BodyAxis, BodyAxisGust, OneMinusCosineGust};
pub use inputs::{
    Doublet, Input, Multisine, Pulse, Sine, Step, Sum, Sweep, SweepLaw, ThreeTwoOneOne,
};
pub use noise::BandLimitedWhiteNoise;
pub use orthogonal::{orthogonal_harmonics, orthogonal_multisine};
pub use recorded::{RecordedInput, ValueUnit};
pub use sensors::{Sensor, SensorConfig, SensorModel, SensorParameters};
pub use turbulence::{DrydenGenerator, DrydenParameters, DrydenTurbulence, TurbulenceSeverity};

#[cfg(test)]
mod tests {
    /// Everything a scenario builds can be moved to and shared between threads (rayon runs).
    #[test]
    fn built_types_are_send_and_sync() {
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<crate::Input>();
        assert_send_sync::<crate::Wind>();
        assert_send_sync::<crate::SensorModel>();
        assert_send_sync::<crate::turbulence::DrydenGenerator>();
    }

    /// A signal behind a reference or a box is the signal itself: the same value at every
    /// time (a step whose value is known by hand, and one time on each side of it).
    #[test]
    fn a_borrowed_or_boxed_signal_is_the_signal() {
        use crate::InputSignal;
        struct Step;
        impl InputSignal for Step {
            fn value(&self, t_s: f64) -> f64 {
                if t_s >= 1.0 { 0.05 } else { -0.02 }
            }
        }
        fn through(s: impl InputSignal, t_s: f64) -> f64 {
            s.value(t_s)
        }
        let boxed: Box<dyn InputSignal> = Box::new(Step);
        for (t, want) in [(0.5, -0.02), (1.0, 0.05), (2.0, 0.05)] {
            assert_eq!(through(&Step, t), want);
            assert_eq!(through(&boxed, t), want);
            assert_eq!(through(boxed.as_ref(), t), want);
        }
    }
}
