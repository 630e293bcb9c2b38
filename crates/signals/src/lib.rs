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

/// Serde configuration of inputs (TOML shapes, unit conversion in one place).
pub mod config;
/// Causal numerical differentiation (least-squares slope, linear phase, stated lag).
pub mod differentiate;
/// Error type of the crate.
pub mod error;
/// Deterministic pilot inputs: step, pulse, doublet, 3-2-1-1, sine, sweeps, multisine, sum.
pub mod inputs;
/// Simulink-style band-limited white noise.
pub mod noise;
/// Recorded input replayed from a CSV file (time, value).
pub mod recorded;

pub use config::InputConfig;
pub use error::SignalError;
pub use inputs::{
    Doublet, Input, Multisine, Pulse, Sine, Step, Sum, Sweep, SweepLaw, ThreeTwoOneOne,
};
pub use noise::BandLimitedWhiteNoise;
pub use recorded::{RecordedInput, ValueUnit};
