//! Band-limited white noise, exactly as Simulink's "Band-Limited White Noise" block that the
//! thesis used for the sensor-noise cases of table 4.6 (thesis §4.1.5, figure 4.19).
//!
//! # Semantics of `noise_power` and `sample_time_s`
//! The Simulink block approximates continuous white noise of two-sided power spectral density
//! `noise_power` (units²·s, the block's "Noise power" parameter, i.e. the height of the PSD)
//! by a sequence of independent Gaussian samples with zero mean and
//!
//! ```text
//!     variance σ² = noise_power / sample_time_s          (std. dev. √(noise_power / Ts))
//! ```
//!
//! each held constant for one `sample_time_s` (zero-order hold). Sample `k` is the value on
//! `k·Ts ≤ t < (k+1)·Ts`, i.e. sample hits at `t = 0, Ts, 2Ts, …` (the block's default offset 0).
//! The `1/Ts` scaling keeps the low-frequency PSD equal to `noise_power` whatever the sample time,
//! which is what makes the output "white noise of power P" band-limited to about `1/(2Ts)` Hz.
//! So halving `Ts` doubles the variance of the samples; choose `Ts` faster than the fastest
//! dynamics of interest (MathWorks suggests `Ts ≈ 1/(100·f_max)`).
//!
//! # Reproducibility
//! Sample `k` is drawn from its own `rand_pcg::Pcg64Mcg` generator seeded from a 64-bit mix of
//! `(seed, k)` (SplitMix64 finaliser), with `rand_distr::StandardNormal`. The value at any time is
//! therefore a pure function of `(seed, noise_power, sample_time_s, t)`: bit-for-bit reproducible,
//! independent of the order or number of calls, and safe to evaluate from `&self` (the reference
//! and the estimated model may both query the same noise). Different seeds give unrelated
//! sequences; give each noisy channel its own seed. The sequence is NOT the one MATLAB produces
//! for the same seed (MATLAB's generator is not reimplemented), only its statistics are.

use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rand_pcg::Pcg64Mcg;

use crate::InputSignal;
use crate::error::{SignalError, non_negative, positive};

/// Simulink-style band-limited white noise: zero-mean Gaussian samples of variance
/// `noise_power / sample_time_s`, held for `sample_time_s`, seeded (see the module docs for the
/// exact semantics and the source).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandLimitedWhiteNoise {
    noise_power: f64,
    sample_time_s: f64,
    seed: u64,
    sigma: f64,
}

impl BandLimitedWhiteNoise {
    /// Noise of two-sided PSD height `noise_power` (signal units² · s), sample time
    /// `sample_time_s` (s) and generator `seed`.
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] if `noise_power < 0` or not finite, or if
    /// `sample_time_s ≤ 0` or not finite.
    pub fn new(noise_power: f64, sample_time_s: f64, seed: u64) -> Result<Self, SignalError> {
        let noise_power = non_negative("noise_power", noise_power)?;
        let sample_time_s = positive("sample_time_s", sample_time_s)?;
        let sigma = (noise_power / sample_time_s).sqrt();
        if !sigma.is_finite() {
            return Err(SignalError::InvalidParameter {
                field: "noise_power",
                value: noise_power,
                reason: "noise_power / sample_time_s overflows",
            });
        }
        Ok(Self { noise_power, sample_time_s, seed, sigma })
    }

    /// Standard deviation of the held samples, `√(noise_power / sample_time_s)` (signal units).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Variance of the held samples, `noise_power / sample_time_s` (signal units²).
    pub fn variance(&self) -> f64 {
        self.sigma * self.sigma
    }

    /// Sample time `Ts` (s).
    pub fn sample_time_s(&self) -> f64 {
        self.sample_time_s
    }

    /// Two-sided PSD height `noise_power` (signal units² · s).
    pub fn noise_power(&self) -> f64 {
        self.noise_power
    }

    /// The generator seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Index of the sample held at `t_s`: `floor(t_s / Ts)`, with a 1e-9·Ts tolerance so that a
    /// time computed as `k·Ts` in floating point (e.g. `3 × 0.1`) lands on sample `k`, as
    /// Simulink's integer sample-hit counter does. Saturates for huge or non-finite times.
    pub fn sample_index(&self, t_s: f64) -> i64 {
        (t_s / self.sample_time_s + 1e-9).floor() as i64
    }

    /// The `k`-th held sample (signal units). Pure function of `(seed, k)` and `sigma`.
    pub fn sample(&self, k: i64) -> f64 {
        standard_normal_keyed(self.seed, k as u64) * self.sigma
    }
}

impl InputSignal for BandLimitedWhiteNoise {
    fn value(&self, t_s: f64) -> f64 {
        self.sample(self.sample_index(t_s))
    }
}

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mix with full avalanche.
pub(crate) fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// One standard-normal draw that depends only on `(seed, key)`.
pub(crate) fn standard_normal_keyed(seed: u64, key: u64) -> f64 {
    let mut rng = Pcg64Mcg::seed_from_u64(splitmix64(splitmix64(seed) ^ key));
    rng.sample(StandardNormal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_variance_is_power_over_sample_time_and_mean_zero() {
        // P = 0.01, Ts = 0.01 -> sigma^2 = 1. N = 200_000 samples: the standard error of the
        // mean is 1/sqrt(N) = 0.0022 and of the variance sqrt(2/N) = 0.0032; test at ~5 sigma.
        let n = BandLimitedWhiteNoise::new(0.01, 0.01, 42).unwrap();
        assert!((n.variance() - 1.0).abs() < 1e-15);
        let count = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for k in 0..count {
            let x = n.value(k as f64 * 0.01);
            s1 += x;
            s2 += x * x;
        }
        let mean = s1 / count as f64;
        let var = s2 / count as f64 - mean * mean;
        assert!(mean.abs() < 0.011, "mean {mean}");
        assert!((var - 1.0).abs() < 0.016, "variance {var}");
        // Scaling: variance = P / Ts for another pair (P = 2e-4, Ts = 1e-3 -> 0.2).
        let m = BandLimitedWhiteNoise::new(2e-4, 1e-3, 42).unwrap();
        assert!((m.variance() - 0.2).abs() < 1e-12);
        // Same seed -> same underlying standard normals, scaled by sigma.
        assert_eq!(m.value(0.0), n.sample(0) * 0.2f64.sqrt());
    }

    #[test]
    fn analytic_samples_are_uncorrelated_lag_one() {
        // Independent samples: lag-1 autocorrelation ~ N(0, 1/N); |r1| < 5/sqrt(N).
        let n = BandLimitedWhiteNoise::new(1.0, 1.0, 7).unwrap();
        let count = 100_000i64;
        let xs: Vec<f64> = (0..count).map(|k| n.sample(k)).collect();
        let c0: f64 = xs.iter().map(|x| x * x).sum();
        let c1: f64 = xs.windows(2).map(|w| w[0] * w[1]).sum();
        let r1 = c1 / c0;
        assert!(r1.abs() < 5.0 / (count as f64).sqrt(), "lag-1 r = {r1}");
    }

    #[test]
    fn analytic_held_constant_over_sample_time() {
        let n = BandLimitedWhiteNoise::new(1.0, 0.1, 3).unwrap();
        let v = n.value(0.3);
        // 3 * 0.1 = 0.30000000000000004 and 0.3 both land on sample 3.
        assert_eq!(n.value(3.0 * 0.1), v);
        assert_eq!(n.value(0.3999), v);
        assert_ne!(n.value(0.4), v);
        assert_ne!(n.value(0.2999), v);
        assert_eq!(n.sample_index(0.3), 3);
    }

    #[test]
    fn repro_bit_for_bit_from_seed_and_seeds_differ() {
        let a = BandLimitedWhiteNoise::new(0.5, 0.01, 1234).unwrap();
        let b = BandLimitedWhiteNoise::new(0.5, 0.01, 1234).unwrap();
        let c = BandLimitedWhiteNoise::new(0.5, 0.01, 1235).unwrap();
        let ta: Vec<u64> = (0..1000).map(|i| a.value(i as f64 * 0.01).to_bits()).collect();
        // Evaluated in reverse order: order of calls must not matter.
        let mut tb: Vec<u64> =
            (0..1000).rev().map(|i| b.value(i as f64 * 0.01).to_bits()).collect();
        tb.reverse();
        assert_eq!(ta, tb);
        let same = (0..1000).filter(|&i| c.value(i as f64 * 0.01).to_bits() == ta[i]).count();
        assert_eq!(same, 0, "seeds 1234 and 1235 share {same} samples");
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(BandLimitedWhiteNoise::new(-1.0, 0.1, 0).is_err());
        let e = BandLimitedWhiteNoise::new(1.0, 0.0, 0).unwrap_err();
        assert!(e.to_string().contains("sample_time_s"), "{e}");
        assert!(BandLimitedWhiteNoise::new(1.0, f64::NAN, 0).is_err());
        // Zero power is a valid (silent) noise.
        assert_eq!(BandLimitedWhiteNoise::new(0.0, 0.1, 0).unwrap().value(5.0), 0.0);
    }
}
