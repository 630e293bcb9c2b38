//! # aeroident-signals
//!
//! Signals that drive and observe a simulation: pilot inputs, gusts and turbulence, sensor
//! models, and causal signal tools (filters, differentiators) an estimator can run in real time.
//! All randomness comes from seeded generators so every run is reproducible bit for bit.

/// A scalar time signal, e.g. a pilot input on one control. Units are the caller's (radians for
/// surface deflections in the API). Signals superpose by summation.
pub trait InputSignal {
    /// Value at time `t_s` (s).
    fn value(&self, t_s: f64) -> f64;
}

/// Causal numerical differentiation (least-squares slope, linear phase, stated lag).
pub mod differentiate;
