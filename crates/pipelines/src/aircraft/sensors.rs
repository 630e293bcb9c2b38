//! The sensor model between the reference aircraft and the two-aircraft estimators: additive,
//! zero-mean, white Gaussian noise per measured state and per measured state derivative, seeded
//! and reproducible: one [`SensorModel`] per channel (the one sensor chain of
//! `aeroident_signals`, also behind `f16 sim`), white noise only, sampled every step. Its
//! samples are the Simulink-style band-limited white noise of the thesis, draw for draw
//! (`aeroident_signals::sensors`, reproducibility). The sample-driven estimators' sensors
//! ([`super::air_data`]) use the same levels and the same chain but differentiate the noisy
//! rates themselves.
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
use aeroident_physics::units::M_PER_FT;
use aeroident_signals::{SensorModel, SensorParameters, SignalError};

/// Window of the smoothing differentiator assumed for the derivative noise, samples.
pub const DIFFERENTIATOR_WINDOW: usize = 11;

/// σ of the accelerometers, ft/s² (ISRN 2014 Table 3, as the other levels here).
pub const ACCEL_SIGMA_FPS2: f64 = 0.98;

/// The twelve sensed channels of a sample, in the order of their sensors: the name of
/// [`AirDataSample`](aeroident_estimators::AirDataSample)'s field and the white-noise σ at `scale = 1` (SI units and rad; the cited
/// levels of this module converted, the accelerometers [`ACCEL_SIGMA_FPS2`]).
pub fn sensed_channels() -> [(&'static str, f64); 12] {
    let s = state_sigma();
    let accel = ACCEL_SIGMA_FPS2 * M_PER_FT;
    [
        ("vt_mps", s[f16::VT] * M_PER_FT),
        ("alpha_rad", s[f16::ALPHA]),
        ("beta_rad", s[f16::BETA]),
        ("p_rad_s", s[f16::P]),
        ("q_rad_s", s[f16::Q]),
        ("r_rad_s", s[f16::R]),
        ("phi_rad", s[f16::PHI]),
        ("theta_rad", s[f16::THETA]),
        ("psi_rad", s[f16::PSI]),
        ("ax_mps2", accel),
        ("ay_mps2", accel),
        ("az_mps2", accel),
    ]
}

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

/// Seed of channel `i` of a sensor path whose channels start at `offset`:
/// `1000·seed + offset + i` (wrapping), the experiment's `[sensors] seed` being `seed`.
pub fn channel_seed(seed: u64, offset: u64, i: usize) -> u64 {
    seed.wrapping_mul(1_000).wrapping_add(offset).wrapping_add(i as u64)
}

/// White-noise-only sensors sampled every `dt_s` (s), one per level of `sigma` (σ per sample,
/// channel units, already scaled); channel `i` is keyed with [`channel_seed`]`(seed, offset,
/// i)`, and is `None` (noise-free) where its level is not > 0. Read at `t = k·dt_s`, a sensor
/// gives `truth + σ·ξ_k` with `ξ_k` the draw of sample `k` (module docs).
///
/// # Errors
/// The signal crate's error for a non-finite level or a non-positive or non-finite interval.
pub fn white_noise_sensors(
    sigma: impl IntoIterator<Item = f64>,
    dt_s: f64,
    seed: u64,
    offset: u64,
) -> Result<Vec<Option<SensorModel>>, SignalError> {
    sigma
        .into_iter()
        .enumerate()
        .map(|(i, s)| {
            if s > 0.0 {
                let p = SensorParameters { white_sigma: s, ..SensorParameters::ideal(1.0 / dt_s) };
                SensorModel::new(p, channel_seed(seed, offset, i)).map(Some)
            } else {
                Ok(None)
            }
        })
        .collect()
}

/// The sensors of the 13 states and 13 derivatives.
#[derive(Debug, Clone)]
pub struct SensorNoise {
    states: Vec<Option<SensorModel>>,
    derivatives: Vec<Option<SensorModel>>,
}

impl SensorNoise {
    /// Noise at `scale` × the default levels, sampled every `dt_s`, from `seed` (states at
    /// offset 0, derivatives at offset 100 of [`white_noise_sensors`]). `None` where σ = 0.
    ///
    /// # Errors
    /// The signal crate's error for a non-finite level or interval.
    pub fn new(scale: f64, dt_s: f64, seed: u64) -> Result<Self, SignalError> {
        let levels = |sig: F16State| (0..N_STATES).map(move |i| sig[i] * scale);
        Ok(Self {
            states: white_noise_sensors(levels(state_sigma()), dt_s, seed, 0)?,
            derivatives: white_noise_sensors(levels(derivative_sigma(dt_s)), dt_s, seed, 100)?,
        })
    }

    /// Measured states and derivatives at `t_s` from the true ones. Call once per step at
    /// `t = k·dt` (later calls within a step return the held readings).
    pub fn measure(&mut self, t_s: f64, x: &F16State, xdot: &F16State) -> (F16State, F16State) {
        let mut z = *x;
        let mut zd = *xdot;
        for i in 0..N_STATES {
            if let Some(s) = &mut self.states[i] {
                z[i] = s.measure(t_s, x[i]);
            }
            if let Some(s) = &mut self.derivatives[i] {
                zd[i] = s.measure(t_s, xdot[i]);
            }
        }
        (z, zd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Read once per step at `t = k·dt`, the sensors give the truth plus the thesis's
    /// band-limited white noise of power `σ²·dt` at step `dt` with the channel's seed
    /// `1000·seed + offset + i`, sample for sample (the block is an independent computation of
    /// the same keyed draws; its σ = √(σ²·dt/dt) may differ from σ in the last bit, hence the
    /// few-ulp tolerance). σ = 0 channels (e.g. engine power) read the truth exactly.
    #[test]
    fn analytic_readings_are_truth_plus_band_limited_white_noise() {
        use aeroident_signals::{BandLimitedWhiteNoise, InputSignal};
        let (scale, dt, seed) = (1.7, 0.01, 42_u64);
        let mut sensors = SensorNoise::new(scale, dt, seed).unwrap();
        let block = |sig: f64, offset: u64, i: usize| {
            let s = sig * scale;
            BandLimitedWhiteNoise::new(s * s * dt, dt, seed * 1000 + offset + i as u64).unwrap()
        };
        let (ss, ds) = (state_sigma(), derivative_sigma(dt));
        for k in 0..400 {
            let t = k as f64 * dt;
            let x = F16State::from_fn(|i, _| 100.0 * (i as f64 + 1.0) + (t * i as f64).sin());
            let xd = F16State::from_fn(|i, _| (t * (i as f64 + 0.5)).cos());
            let (z, zd) = sensors.measure(t, &x, &xd);
            for i in 0..N_STATES {
                for (got, truth, sig, offset) in [(z, x, ss, 0), (zd, xd, ds, 100)] {
                    let want = if sig[i] > 0.0 {
                        truth[i] + block(sig[i], offset, i).value(t)
                    } else {
                        truth[i]
                    };
                    let tol = 4.0 * f64::EPSILON * want.abs().max(1.0);
                    assert!((got[i] - want).abs() <= tol, "k {k}, channel {offset}+{i}");
                }
            }
        }
    }

    #[test]
    fn analytic_slope_noise_gain_11_points() {
        // Σ(k − c)² for n = 11 is 110: gain = 1/(dt·√110) = 9.5346 at dt = 0.01.
        assert!((slope_noise_gain(11, 0.01) - 1.0 / (0.01 * 110f64.sqrt())).abs() < 1e-12);
    }
}
