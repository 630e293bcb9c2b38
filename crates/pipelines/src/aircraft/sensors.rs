//! The sensor model between the reference aircraft and the two-aircraft estimators: additive,
//! zero-mean, white Gaussian noise per measured state and per measured state derivative, seeded
//! and reproducible (Simulink-style band-limited white noise of `aeroident_signals`, held for one
//! sample). The sample-driven estimators' sensors ([`super::air_data`]) use the same levels but
//! differentiate the noisy rates themselves.
//!
//! # Levels (σ at `scale = 1`) and their source
//! States, from "Designing Stipulated Gains of Aircraft Stability and Control Augmentation
//! Systems for Semiglobal Trajectories Tracking", ISRN Aerospace Engineering 2014, article
//! 409408, Table 3 ("magnitude of sensor noise standard deviations",
//! hindawi.com/journals/isrn/2014/409408/tab3): rate gyros 0.14 deg/s, angle of
//! attack and sideslip vanes 0.1 deg, attitude 0.573 deg, altitude 10 ft, airspeed 11 ft/s,
//! accelerometers 0.98 ft/s².
//!
//! Derivatives: no flight sensor measures `ṗ, q̇, ṙ, α̇, β̇` directly; flight-test practice
//! differentiates the rate and vane signals with a smoothing differentiator (Klein & Morelli
//! 2006 §11.2). An `n`-point least-squares slope of white noise σ at interval `dt` has
//! `σ_slope = σ·√(12 / (n(n² − 1))) / dt`; with `n = 11` and `dt = 0.01 s` that is `9.53 σ`.
//! `V̇` is taken from the longitudinal accelerometer (σ = 0.98 ft/s²). The differentiator's
//! lag `(n − 1)dt/2` is NOT modelled (the noise level is, the delay is not): optimistic.
//! Engine power is not measured; the estimators use the reference's value (thrust known from
//! the engine model).

use aeroident_models::f16::{self, F16State, N_STATES};
use aeroident_signals::{BandLimitedWhiteNoise, InputSignal};

/// Window of the smoothing differentiator assumed for the derivative noise, samples.
pub const DIFFERENTIATOR_WINDOW: usize = 11;

/// σ of the measured states at `scale = 1`, state units (module docs give the source).
pub fn state_sigma() -> F16State {
    let mut s = F16State::zeros();
    s[f16::VT] = 11.0;
    s[f16::ALPHA] = 0.1f64.to_radians();
    s[f16::BETA] = 0.1f64.to_radians();
    s[f16::PHI] = 0.573f64.to_radians();
    s[f16::THETA] = 0.573f64.to_radians();
    s[f16::PSI] = 0.573f64.to_radians();
    s[f16::P] = 0.14f64.to_radians();
    s[f16::Q] = 0.14f64.to_radians();
    s[f16::R] = 0.14f64.to_radians();
    s[f16::ALT] = 10.0;
    s
}

/// Gain from white noise σ to the σ of an `n`-point least-squares slope at interval `dt_s`.
pub fn slope_noise_gain(n: usize, dt_s: f64) -> f64 {
    let n = n as f64;
    (12.0 / (n * (n * n - 1.0))).sqrt() / dt_s
}

/// σ of the measured derivatives of the sliding states at `scale = 1` for sample interval
/// `dt_s` (zero for derivatives no estimator reads).
pub fn derivative_sigma(dt_s: f64) -> F16State {
    let s = state_sigma();
    let g = slope_noise_gain(DIFFERENTIATOR_WINDOW, dt_s);
    let mut d = F16State::zeros();
    d[f16::VT] = 0.98;
    for i in [f16::ALPHA, f16::BETA, f16::P, f16::Q, f16::R] {
        d[i] = g * s[i];
    }
    d
}

/// Noise generators for the 13 states and 13 derivatives.
#[derive(Debug, Clone)]
pub struct SensorNoise {
    states: Vec<Option<BandLimitedWhiteNoise>>,
    derivatives: Vec<Option<BandLimitedWhiteNoise>>,
}

impl SensorNoise {
    /// Noise at `scale` × the default levels, held for `dt_s`, from `seed`. `None` where σ = 0.
    ///
    /// # Errors
    /// The signal crate's error for a non-finite level or interval.
    pub fn new(scale: f64, dt_s: f64, seed: u64) -> Result<Self, aeroident_signals::SignalError> {
        let make = |sig: F16State, offset: u64| {
            (0..N_STATES)
                .map(|i| {
                    let s = sig[i] * scale;
                    if s > 0.0 {
                        BandLimitedWhiteNoise::new(
                            s * s * dt_s,
                            dt_s,
                            seed.wrapping_mul(1_000).wrapping_add(offset + i as u64),
                        )
                        .map(Some)
                    } else {
                        Ok(None)
                    }
                })
                .collect::<Result<Vec<_>, _>>()
        };
        Ok(Self {
            states: make(state_sigma(), 0)?,
            derivatives: make(derivative_sigma(dt_s), 100)?,
        })
    }

    /// Measured states and derivatives at `t_s` from the true ones.
    pub fn measure(&self, t_s: f64, x: &F16State, xdot: &F16State) -> (F16State, F16State) {
        let mut z = *x;
        let mut zd = *xdot;
        for i in 0..N_STATES {
            if let Some(n) = &self.states[i] {
                z[i] += n.value(t_s);
            }
            if let Some(n) = &self.derivatives[i] {
                zd[i] += n.value(t_s);
            }
        }
        (z, zd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_slope_noise_gain_11_points() {
        // Σ(k − c)² for n = 11 is 110: gain = 1/(dt·√110) = 9.5346 at dt = 0.01.
        assert!((slope_noise_gain(11, 0.01) - 1.0 / (0.01 * 110f64.sqrt())).abs() < 1e-12);
    }
}
