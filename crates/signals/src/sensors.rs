//! Per-channel sensor models (architecture §2 `SensorModel`, after JSBSim's FGSensor chain):
//! sampling at a fixed rate with zero-order hold, optional first-order lag, scale factor,
//! constant bias, first-order Gauss–Markov drift, white noise, quantisation and a transport delay. All
//! randomness is seeded and keyed by the sample index (reproducible bit for bit, whatever the
//! call pattern).
//!
//! # Chain, at each sample instant `t_k = k·Ts`
//! ```text
//!   x_k   = lag(truth(t_k))                       optional first-order lag, ZOH-exact at Ts
//!   m_k   = scale·x_k + bias + b_k + σ_w·ξ_k      b_k: Gauss–Markov drift, ξ_k ~ N(0, 1)
//!   q_k   = LSB·round(m_k / LSB)                  optional mid-tread quantiser
//!   out   = q_{k−N}                               transport delay of N = delay_s/Ts samples
//! ```
//! and the output is HELD between sample instants. The Gauss–Markov drift is the exact
//! discretisation of `ḃ = −b/τ + w` with stationary standard deviation σ_gm:
//! `b_{k+1} = e^{−Ts/τ} b_k + σ_gm √(1 − e^{−2Ts/τ}) ζ_k`, `b_0 ~ N(0, σ_gm²)`.
//!
//! # Calling convention
//! Call [`SensorModel::measure`] with non-decreasing times, at least once per sample period
//! (typically every integration step). Sample instants are `k·Ts` from `t = 0` (hit detection
//! with a 1e-9·Ts tolerance). If a call skips sample instants, one sample is taken for each
//! skipped instant using the truth of the current call (so the delay stays exact in time). The
//! first call fills the delay line with its sample, so during the first `delay` the output is
//! that first sample. A call with an earlier time than the previous one returns the held output.
//!
//! # Reproducibility
//! Every random number is keyed by the sample index, as in
//! [`BandLimitedWhiteNoise`](crate::noise::BandLimitedWhiteNoise), instead of being drawn from
//! a generator that advances with each call:
//! - the white noise of sample `k` is `ξ_k = standard_normal_keyed(seed, k)`, the very draw
//!   `BandLimitedWhiteNoise` of the same seed scales by its σ, so a white-noise-only sensor at
//!   `1/Ts` reads `truth + σ_w·ξ_k`, the block's sample `k` with σ = σ_w;
//! - the Gauss–Markov drift has a stream of its own, seeded with
//!   `splitmix64(seed ^ DRIFT_TAG)`: the drive `ζ_k` is its draw at key `2k` and the initial
//!   state `b_0/σ_gm` its draw at key 1 (odd, so never a drive). The white and the drift noise
//!   of one channel are therefore independent.
//!
//! A reading is thus a pure function of `(seed, sample index, truth history)`: calling at every
//! integration stage or only at the sample instants gives the same bits, and a sensor sampled
//! as the block is reproduces its numbers. When a call skips more sample instants than the
//! delay line holds, the samples that can no longer reach the output are not formed: the lag
//! and the drift jump over them with their exact many-step transitions, the drift driven by
//! the draw of the last skipped instant (the same distribution, other bits than a
//! sample-by-sample walk).

use serde::Deserialize;

use crate::error::{SignalError, non_negative, positive};
use crate::filters::FirstOrderLowPass;
use crate::noise::{splitmix64, standard_normal_keyed};

/// Mixed into a channel's seed to seed its Gauss–Markov stream ("GMdrift" in ASCII), so the
/// drift never reuses the white noise's draws.
const DRIFT_TAG: u64 = 0x0047_4d64_7269_6674;

/// A sensor: truth in, reading out, with the noise variance an estimator may use as R.
/// (Architecture §2; one job: turn a true value into a measurement.)
pub trait Sensor {
    /// Reading at time `t_s` (s) for the true value `truth` (channel units). Never NaN for a
    /// finite `truth`.
    fn measure(&mut self, t_s: f64, truth: f64) -> f64;
    /// Variance of the reading about the (biased, delayed) truth, channel units²; see
    /// [`SensorModel::noise_variance`].
    fn noise_variance(&self) -> f64;
}

/// Validated parameters of a [`SensorModel`]; all values in the channel's units (e.g. rad for
/// `alpha_rad`) and seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorParameters {
    /// White-noise standard deviation σ_w per sample (channel units), ≥ 0.
    pub white_sigma: f64,
    /// Constant bias (channel units).
    pub bias: f64,
    /// Scale factor on the (lagged) truth, finite and non-zero: `1.03` reads 3 % high, `−1`
    /// reads with the opposite sign (the convention of a compatibility check's `scale`).
    pub scale: f64,
    /// First-order Gauss–Markov drift `(σ_gm, τ_s)`: stationary standard deviation (channel
    /// units, ≥ 0) and correlation time (s, > 0).
    pub gauss_markov: Option<(f64, f64)>,
    /// Sample rate (Hz), > 0.
    pub sample_rate_hz: f64,
    /// Transport delay in whole samples.
    pub delay_samples: usize,
    /// First-order lag time constant (s), > 0, applied to the truth before the noise.
    pub lag_tau_s: Option<f64>,
    /// Quantisation step LSB (channel units), > 0.
    pub quantum: Option<f64>,
}

impl SensorParameters {
    /// An ideal sensor at `sample_rate_hz` (no noise, bias, lag, quantisation or delay).
    pub fn ideal(sample_rate_hz: f64) -> Self {
        Self {
            white_sigma: 0.0,
            bias: 0.0,
            scale: 1.0,
            gauss_markov: None,
            sample_rate_hz,
            delay_samples: 0,
            lag_tau_s: None,
            quantum: None,
        }
    }
}

/// The sensor chain of the module docs, its randomness keyed by seed and sample index.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorModel {
    p: SensorParameters,
    sample_time_s: f64,
    /// Seed of the white noise (the channel's seed).
    seed: u64,
    /// Seed of the Gauss–Markov stream (module docs, reproducibility).
    drift_seed: u64,
    gm_phi: f64,
    gm_drive: f64,
    gm_state: f64,
    lag: Option<FirstOrderLowPass>,
    /// Ring buffer of the last `delay_samples + 1` quantised samples.
    delay_line: Vec<f64>,
    head: usize,
    last_index: Option<i64>,
    output: f64,
}

/// Exact `steps`-sample transition of the Gauss–Markov drift of stationary σ `sigma` and
/// `Ts/τ = ts_over_tau`: `(φ, drive)` with `b' = φ·b + drive·ζ`, `φ = e^{−steps·Ts/τ}`,
/// `drive = σ·√(1 − φ²)` (so the stationary variance σ² is kept).
fn drift_transition(sigma: f64, ts_over_tau: f64, steps: f64) -> (f64, f64) {
    let a = steps * ts_over_tau;
    ((-a).exp(), sigma * (-(-2.0 * a).exp_m1()).sqrt())
}

impl SensorModel {
    /// Builds the chain; `seed` keys this channel's random numbers (module docs,
    /// reproducibility).
    ///
    /// # Errors
    /// [`SignalError::InvalidParameter`] naming the bad field (negative sigma, non-positive
    /// rate, τ or LSB, non-finite bias).
    pub fn new(params: SensorParameters, seed: u64) -> Result<Self, SignalError> {
        non_negative("white_sigma", params.white_sigma)?;
        crate::error::finite("bias", params.bias)?;
        if !(params.scale.is_finite() && params.scale != 0.0) {
            return Err(SignalError::InvalidParameter {
                field: "scale",
                value: params.scale,
                reason: "must be finite and non-zero",
            });
        }
        let fs = positive("sample_rate_hz", params.sample_rate_hz)?;
        let ts = 1.0 / fs;
        let (gm_phi, gm_drive, gm_sigma) = match params.gauss_markov {
            Some((sigma, tau)) => {
                let sigma = non_negative("gauss_markov_sigma", sigma)?;
                let tau = positive("gauss_markov_tau_s", tau)?;
                let (phi, drive) = drift_transition(sigma, ts / tau, 1.0);
                (phi, drive, sigma)
            }
            None => (0.0, 0.0, 0.0),
        };
        if let Some(q) = params.quantum {
            positive("quantum", q)?;
        }
        let lag =
            params.lag_tau_s.map(|tau| FirstOrderLowPass::new(tau, ts, 0.0)).transpose().map_err(
                |e| match e {
                    SignalError::InvalidParameter { value, reason, .. } => {
                        SignalError::InvalidParameter { field: "lag_tau_s", value, reason }
                    }
                    other => other,
                },
            )?;
        if params.delay_samples > 1_000_000 {
            return Err(SignalError::InvalidParameter {
                field: "delay_samples",
                value: params.delay_samples as f64,
                reason: "must be <= 1e6",
            });
        }
        let drift_seed = splitmix64(seed ^ DRIFT_TAG);
        let gm_state = if params.gauss_markov.is_some() {
            gm_sigma * standard_normal_keyed(drift_seed, 1)
        } else {
            0.0
        };
        Ok(Self {
            p: params,
            sample_time_s: ts,
            seed,
            drift_seed,
            gm_phi,
            gm_drive,
            gm_state,
            lag,
            delay_line: vec![0.0; params.delay_samples + 1],
            head: 0,
            last_index: None,
            output: 0.0,
        })
    }

    /// Sample period `Ts = 1 / sample_rate_hz` (s).
    pub fn sample_time_s(&self) -> f64 {
        self.sample_time_s
    }

    /// Transport delay (s) = `delay_samples · Ts`.
    pub fn delay_s(&self) -> f64 {
        self.p.delay_samples as f64 * self.sample_time_s
    }

    /// The parameters.
    pub fn parameters(&self) -> &SensorParameters {
        &self.p
    }

    /// Variance of the white noise alone, `σ_w²` (channel units²).
    pub fn white_variance(&self) -> f64 {
        self.p.white_sigma * self.p.white_sigma
    }

    /// Total random variance of a reading about `truth + bias` (channel units²):
    /// `σ_w² + σ_gm² + LSB²/12` — white noise, the stationary Gauss–Markov drift, and the
    /// uniform-quantisation approximation (valid when the signal spans many LSBs). This is
    /// the measurement-noise R an estimator may use; the drift part is correlated in time
    /// (correlation time τ), which a white-noise R ignores.
    pub fn noise_variance(&self) -> f64 {
        let gm = self.p.gauss_markov.map_or(0.0, |(s, _)| s * s);
        let q = self.p.quantum.map_or(0.0, |q| q * q / 12.0);
        self.white_variance() + gm + q
    }

    /// Takes sample `k` of `truth`, pushing it into the delay line. Draws are made only for
    /// the terms present, which changes no value (each is keyed, not sequential).
    fn take_sample(&mut self, k: i64, truth: f64) {
        let x = match self.lag.as_mut() {
            Some(f) => {
                let y = f.output();
                f.step(truth);
                y
            }
            None => truth,
        };
        let white = if self.p.white_sigma > 0.0 {
            self.p.white_sigma * standard_normal_keyed(self.seed, k as u64)
        } else {
            0.0
        };
        let mut m = self.p.scale * x + self.p.bias + self.gm_state + white;
        if self.p.gauss_markov.is_some() {
            let zeta = standard_normal_keyed(self.drift_seed, (k as u64).wrapping_mul(2));
            self.gm_state = self.gm_phi * self.gm_state + self.gm_drive * zeta;
        }
        if let Some(q) = self.p.quantum {
            m = q * (m / q).round();
        }
        let n = self.delay_line.len();
        self.head = (self.head + 1) % n;
        self.delay_line[self.head] = m;
        // Output = the sample pushed `delay_samples` pushes ago (the oldest in the ring).
        self.output = self.delay_line[(self.head + 1) % n];
    }

    /// Carries the lag and the drift from sample `from` to sample `to` over samples that are
    /// not formed (module docs), each with its exact many-step transition: the lag towards
    /// the held `truth`, the drift driven by the drive draw of the last skipped sample
    /// `to − 1`, which no formed sample uses.
    fn skip_unformed(&mut self, from: i64, to: i64, truth: f64) {
        if to <= from {
            return;
        }
        let steps = (to as f64) - (from as f64);
        if let (Some(f), Some(tau)) = (self.lag.as_mut(), self.p.lag_tau_s) {
            let decay = (-steps * self.sample_time_s / tau).exp();
            f.reset(truth + (f.output() - truth) * decay);
        }
        if let Some((sigma, tau)) = self.p.gauss_markov {
            let (phi, drive) = drift_transition(sigma, self.sample_time_s / tau, steps);
            let zeta = standard_normal_keyed(self.drift_seed, ((to - 1) as u64).wrapping_mul(2));
            self.gm_state = phi * self.gm_state + drive * zeta;
        }
    }

    /// Reading at `t_s` (s) for the true value `truth` (channel units), following the calling
    /// convention of the module docs; a pure function of the seed, the sample index and the
    /// truths passed at the sample instants.
    pub fn measure(&mut self, t_s: f64, truth: f64) -> f64 {
        let k = (t_s / self.sample_time_s + 1e-9).floor() as i64;
        match self.last_index {
            None => {
                if let Some(f) = self.lag.as_mut() {
                    f.reset(truth); // start the lag in steady state
                }
                self.take_sample(k, truth);
                // Fill the delay line with the first sample.
                let first = self.delay_line[self.head];
                self.delay_line.fill(first);
                self.output = first;
            }
            Some(last) if k > last => {
                // Only the last `delay + 1` samples can still reach the output.
                let reach = self.delay_line.len() as i64;
                let first = k.saturating_sub(reach).saturating_add(1).max(last.saturating_add(1));
                self.skip_unformed(last.saturating_add(1), first, truth);
                for j in first..=k {
                    self.take_sample(j, truth);
                }
            }
            Some(_) => return self.output,
        }
        self.last_index = Some(k);
        self.output
    }
}

impl Sensor for SensorModel {
    fn measure(&mut self, t_s: f64, truth: f64) -> f64 {
        SensorModel::measure(self, t_s, truth)
    }

    fn noise_variance(&self) -> f64 {
        SensorModel::noise_variance(self)
    }
}

/// One `[[sensor]]` entry of a scenario file; values in the channel's units.
///
/// ```
/// # use aeroident_signals::{Sensor, SensorConfig};
/// # #[derive(serde::Deserialize)]
/// # struct Scenario { sensor: Vec<SensorConfig> }
/// let text = r#"
/// [[sensor]]
/// channel = "alpha_rad"        # the measured quantity, named with its unit
/// white_sigma = 0.001          # default 0
/// bias = 0.0                   # default 0
/// scale = 1.0                  # default 1: reads scale·truth (1.03: 3 % high)
/// sample_rate_hz = 100.0       # required
/// delay_s = 0.02               # OR delay_samples = 2; must be a whole number of samples
/// quantum = 0.0001             # optional LSB
/// gauss_markov_sigma = 0.0005  # optional, together with gauss_markov_tau_s
/// gauss_markov_tau_s = 30.0
/// lag_tau_s = 0.01             # optional first-order lag
/// seed = 7                     # optional; default: derived from the run seed and the channel
/// "#;
/// let sc: Scenario = toml::from_str(text).unwrap();
/// let mut alpha = sc.sensor[0].build(1).unwrap();
/// let reading = alpha.measure(0.0, 0.05);
/// assert!((reading - 0.05).abs() < 0.01);
/// assert!((alpha.noise_variance() - (1e-6 + 2.5e-7 + 1e-8 / 12.0)).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    /// Measured channel name (e.g. `alpha_rad`, `q_rad_s`).
    pub channel: String,
    /// White-noise σ (channel units).
    #[serde(default)]
    pub white_sigma: f64,
    /// Constant bias (channel units).
    #[serde(default)]
    pub bias: f64,
    /// Scale factor on the truth (default 1; [`SensorParameters::scale`]).
    #[serde(default = "unit_scale")]
    pub scale: f64,
    /// Gauss–Markov stationary σ (channel units).
    pub gauss_markov_sigma: Option<f64>,
    /// Gauss–Markov correlation time (s).
    pub gauss_markov_tau_s: Option<f64>,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Transport delay (s), a whole number of sample periods.
    pub delay_s: Option<f64>,
    /// Transport delay (samples).
    pub delay_samples: Option<usize>,
    /// Quantisation LSB (channel units).
    pub quantum: Option<f64>,
    /// First-order lag time constant (s).
    pub lag_tau_s: Option<f64>,
    /// Seed of this channel's generator.
    pub seed: Option<u64>,
}

/// The default [`SensorConfig::scale`]: a sensor that reads the truth's size.
fn unit_scale() -> f64 {
    1.0
}

impl SensorConfig {
    /// Validated parameters.
    ///
    /// # Errors
    /// [`SignalError::UnitChoice`] if both `delay_s` and `delay_samples` are given;
    /// [`SignalError::InvalidParameter`] if `delay_s` is not a whole number of sample periods
    /// (within 1e-6 of a sample) or negative; [`SignalError::InvalidList`] if only one of the
    /// two Gauss–Markov keys is given.
    pub fn parameters(&self) -> Result<SensorParameters, SignalError> {
        let fs = positive("sample_rate_hz", self.sample_rate_hz)?;
        let delay_samples = match (self.delay_s, self.delay_samples) {
            (Some(_), Some(_)) => {
                return Err(SignalError::UnitChoice {
                    first: "delay_s",
                    second: "delay_samples",
                    problem: "both given",
                });
            }
            (Some(d), None) => {
                let n = non_negative("delay_s", d)? * fs;
                if (n - n.round()).abs() > 1e-6 {
                    return Err(SignalError::InvalidParameter {
                        field: "delay_s",
                        value: d,
                        reason: "must be a whole number of sample periods (1 / sample_rate_hz)",
                    });
                }
                n.round() as usize
            }
            (None, Some(n)) => n,
            (None, None) => 0,
        };
        let gauss_markov = match (self.gauss_markov_sigma, self.gauss_markov_tau_s) {
            (Some(s), Some(t)) => Some((s, t)),
            (None, None) => None,
            _ => {
                return Err(SignalError::InvalidList {
                    field: "gauss_markov",
                    reason: "give both gauss_markov_sigma and gauss_markov_tau_s, or neither"
                        .into(),
                });
            }
        };
        Ok(SensorParameters {
            white_sigma: self.white_sigma,
            bias: self.bias,
            scale: self.scale,
            gauss_markov,
            sample_rate_hz: fs,
            delay_samples,
            lag_tau_s: self.lag_tau_s,
            quantum: self.quantum,
        })
    }

    /// Builds the sensor. Its seed is `seed` if given, otherwise derived from `run_seed` and
    /// the channel name (so each channel of a run gets an independent, reproducible stream).
    ///
    /// # Errors
    /// As [`SensorConfig::parameters`] and [`SensorModel::new`].
    pub fn build(&self, run_seed: u64) -> Result<SensorModel, SignalError> {
        let seed = self.seed.unwrap_or_else(|| {
            // FNV-1a of the channel name, mixed with the run seed.
            let h = self.channel.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
                (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
            });
            splitmix64(run_seed ^ h)
        });
        SensorModel::new(self.parameters()?, seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ideal(fs: f64) -> SensorParameters {
        SensorParameters::ideal(fs)
    }

    #[test]
    fn analytic_zero_order_hold_at_sample_rate() {
        // 10 Hz sensor called at 1 kHz on truth = t: output = floor(t / 0.1) * 0.1.
        let mut s = SensorModel::new(ideal(10.0), 1).unwrap();
        for i in 0..1000 {
            let t = i as f64 * 1e-3;
            let y = s.measure(t, t);
            let k = (t / 0.1 + 1e-9).floor();
            assert!((y - k * 0.1).abs() < 1e-12, "t = {t}: {y}");
        }
    }

    #[test]
    fn analytic_delay_shifts_by_exactly_n_samples() {
        // 100 Hz, delay 0.03 s = 3 samples, truth = sample index: output at sample k is k - 3
        // (first sample value 0 held during the first 3 samples).
        let cfg: SensorConfig =
            toml::from_str("channel = \"q_rad_s\"\nsample_rate_hz = 100.0\ndelay_s = 0.03\n")
                .unwrap();
        let mut s = cfg.build(0).unwrap();
        assert!((s.delay_s() - 0.03).abs() < 1e-15);
        for k in 0..50 {
            let t = k as f64 * 0.01;
            let y = s.measure(t, k as f64);
            assert_eq!(y, (k as f64 - 3.0).max(0.0), "k = {k}");
        }
        // Skipped instants still count: jump 5 samples ahead with truth 100.
        let y = s.measure(0.54, 100.0);
        // pushes for k = 50..54 all see truth 100; output = value pushed 3 pushes before the
        // last = the k = 51 push = 100.
        assert_eq!(y, 100.0);
    }

    #[test]
    fn analytic_quantisation_to_multiples_of_lsb_and_bias() {
        let p = SensorParameters { bias: 0.25, quantum: Some(0.1), ..ideal(100.0) };
        let mut s = SensorModel::new(p, 3).unwrap();
        for k in 0..200 {
            let t = k as f64 * 0.01;
            let truth = (t * 3.0).sin();
            let y = s.measure(t, truth);
            let n = (y / 0.1).round();
            assert!((y - n * 0.1).abs() < 1e-12, "not a multiple of the LSB: {y}");
            assert!((y - (truth + 0.25)).abs() <= 0.05 + 1e-12, "{y} vs {truth}");
        }
        let mut b = SensorModel::new(SensorParameters { bias: -2.0, ..ideal(50.0) }, 0).unwrap();
        assert_eq!(b.measure(0.0, 1.0), -1.0);
    }

    #[test]
    fn analytic_scale_factor_multiplies_the_truth_before_the_bias() {
        // A sensor 4 % high with a bias: scale·truth + bias at every sample; a sign-flipped
        // one reads −truth.
        let p = SensorParameters { scale: 1.04, bias: 0.5, ..ideal(10.0) };
        let mut s = SensorModel::new(p, 0).unwrap();
        for k in 0..20 {
            let truth = (k as f64 * 0.3).cos();
            assert!((s.measure(k as f64 * 0.1, truth) - (1.04 * truth + 0.5)).abs() < 1e-12);
        }
        let mut flip =
            SensorModel::new(SensorParameters { scale: -1.0, ..ideal(10.0) }, 0).unwrap();
        assert_eq!(flip.measure(0.0, 9.81), -9.81);
        for bad in [0.0, f64::NAN, f64::INFINITY] {
            let e =
                SensorModel::new(SensorParameters { scale: bad, ..ideal(10.0) }, 0).unwrap_err();
            assert!(e.to_string().contains("scale"), "{e}");
        }
    }

    #[test]
    fn analytic_noise_statistics_and_variance() {
        // White sigma 0.01 and GM sigma 0.02 (tau = 0.05 s, Ts = 0.01): reading - truth has
        // variance 0.0001 + 0.0004. 200k samples: GM correlation ~5 samples, relative SE of the
        // variance ~ sqrt(2*5/200k) = 0.7 %; tolerance 4 %. Mean: SE ~ 0.02*sqrt(10/200k) =
        // 1.4e-4; tolerance 1e-3.
        let p = SensorParameters {
            white_sigma: 0.01,
            gauss_markov: Some((0.02, 0.05)),
            ..ideal(100.0)
        };
        let mut s = SensorModel::new(p, 99).unwrap();
        assert!((s.noise_variance() - 0.0005).abs() < 1e-15);
        let n = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for k in 0..n {
            let e = s.measure(k as f64 * 0.01, 1.0) - 1.0;
            s1 += e;
            s2 += e * e;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 1e-3, "mean {mean}");
        assert!((var / 0.0005 - 1.0).abs() < 0.04, "variance {var}");
        // Quantisation adds LSB^2 / 12 to R.
        let q = SensorModel::new(SensorParameters { quantum: Some(0.3), ..ideal(1.0) }, 0).unwrap();
        assert!((q.noise_variance() - 0.09 / 12.0).abs() < 1e-15);
    }

    #[test]
    fn analytic_lag_first_order_response() {
        // Lag tau = 0.1 s at 100 Hz starting in steady state at 0 and stepping to 1 at t = 0.1:
        // sample at t_k sees the lag's state, which follows 1 - e^{-(t_k - 0.1)/tau} exactly.
        let p = SensorParameters { lag_tau_s: Some(0.1), ..ideal(100.0) };
        let mut s = SensorModel::new(p, 0).unwrap();
        for k in 0..60 {
            let t = k as f64 * 0.01;
            let truth = if k >= 10 { 1.0 } else { 0.0 };
            let y = s.measure(t, truth);
            let expect = if k <= 10 { 0.0 } else { 1.0 - (-(t - 0.1) / 0.1_f64).exp() };
            assert!((y - expect).abs() < 1e-12, "k = {k}: {y} vs {expect}");
        }
    }

    #[test]
    fn repro_bit_for_bit_and_channels_differ() {
        let cfg: SensorConfig = toml::from_str(
            "channel = \"alpha_rad\"\nwhite_sigma = 0.001\nsample_rate_hz = 100\ndelay_s = 0.02\nquantum = 0.0001\n",
        )
        .unwrap();
        let mut other = cfg.clone();
        other.channel = "beta_rad".into();
        let run = |c: &SensorConfig| -> Vec<u64> {
            let mut s = c.build(42).unwrap();
            (0..500).map(|i| s.measure(i as f64 * 0.002, 0.1).to_bits()).collect()
        };
        assert_eq!(run(&cfg), run(&cfg));
        assert_ne!(run(&cfg), run(&other));
    }

    /// A white-noise-only sensor at `1/Ts` reads `truth + BandLimitedWhiteNoise::value(t)` of
    /// the same seed (σ = √(P/Ts)), sample for sample, at the sample instants `k·dt` and in
    /// between, for step sizes that are not binary fractions. The block is an independent
    /// computation of the same keyed draws.
    #[test]
    fn analytic_white_noise_reproduces_band_limited_white_noise() {
        use crate::InputSignal;
        use crate::noise::BandLimitedWhiteNoise;
        for (dt, sigma, seed) in [(0.01, 0.3, 7_u64), (0.02, 1.5, 1_000_213), (1e-3, 2e-4, 0)] {
            let block = BandLimitedWhiteNoise::new(sigma * sigma * dt, dt, seed).unwrap();
            let p = SensorParameters { white_sigma: block.sigma(), ..ideal(1.0 / dt) };
            let mut s = SensorModel::new(p, seed).unwrap();
            for k in 0..5_000 {
                let t = k as f64 * dt;
                let truth = (3.0 * t).sin();
                assert_eq!(s.measure(t, truth), truth + block.value(t), "dt {dt}, k {k}");
                // Half a step later the sample is held.
                let t_mid = t + 0.5 * dt;
                assert_eq!(s.measure(t_mid, 9.0), truth + block.value(t_mid), "dt {dt}, k {k}");
            }
        }
    }

    /// The readings do not depend on how often the sensor is called: RK4 stage calls with an
    /// integration step of Ts/4 (exact binary fractions, so the stage times hit the sample
    /// instants exactly) give the same bits at every sample instant as calls there only, with
    /// every term of the chain on.
    #[test]
    fn repro_readings_independent_of_the_call_pattern() {
        let p = SensorParameters {
            white_sigma: 0.01,
            bias: 0.2,
            scale: 1.03,
            gauss_markov: Some((0.02, 0.5)),
            sample_rate_hz: 64.0,
            delay_samples: 3,
            lag_tau_s: Some(0.05),
            quantum: Some(1e-3),
        };
        let truth = |t: f64| (2.0 * t).sin() + 0.1 * t;
        let mut sparse = SensorModel::new(p, 11).unwrap();
        let at_instants: Vec<u64> = (0..640)
            .map(|k| sparse.measure(k as f64 / 64.0, truth(k as f64 / 64.0)).to_bits())
            .collect();
        let mut dense = SensorModel::new(p, 11).unwrap();
        let h = 1.0 / 256.0;
        let mut at_steps = Vec::new();
        for n in 0..(4 * 640) {
            let t = n as f64 * h;
            let y = dense.measure(t, truth(t));
            if n % 4 == 0 {
                at_steps.push(y.to_bits());
            }
            for c in [0.5, 0.5, 1.0] {
                dense.measure(t + c * h, truth(t + c * h));
            }
        }
        assert_eq!(at_instants, at_steps);
        let moved = at_instants.iter().filter(|b| **b != at_instants[0]).count();
        assert!(moved > 600, "the chain must not be constant ({moved} samples moved)");
    }

    /// Pearson correlation of two equally long series.
    fn correlation(u: &[f64], v: &[f64]) -> f64 {
        let m = u.len() as f64;
        let (mu, mv) = (u.iter().sum::<f64>() / m, v.iter().sum::<f64>() / m);
        let (mut suv, mut suu, mut svv) = (0.0, 0.0, 0.0);
        for (a, b) in u.iter().zip(v) {
            suv += (a - mu) * (b - mv);
            suu += (a - mu) * (a - mu);
            svv += (b - mv) * (b - mv);
        }
        suv / (suu * svv).sqrt()
    }

    /// The drift is a first-order Gauss–Markov process driven by a stream of its own. From a
    /// drift-only sensor (σ = 1, τ = 0.1 s, Ts = 0.01 s) the innovations
    /// `ζ_k = (b_{k+1} − φ b_k)/√(1 − φ²)`, φ = e^{−Ts/τ} computed here, must be white and of
    /// unit variance, and uncorrelated with the white draws ξ of a white-only sensor of the same
    /// seed at the indices `k + L` and `2k + L` (|L| ≤ 2: where a shared stream would put them,
    /// given the drift's key 2k). N = 100k: |r| < 5/√N; variance within 5·√(2/N).
    #[test]
    fn analytic_drift_stream_is_markov_and_independent_of_white() {
        let n = 100_000;
        let white = SensorParameters { white_sigma: 1.0, ..ideal(100.0) };
        let drift = SensorParameters { gauss_markov: Some((1.0, 0.1)), ..ideal(100.0) };
        let mut a = SensorModel::new(white, 5).unwrap();
        let mut b = SensorModel::new(drift, 5).unwrap();
        let xi: Vec<f64> = (0..2 * n + 8).map(|k| a.measure(k as f64 * 0.01, 0.0)).collect();
        let bk: Vec<f64> = (0..=n).map(|k| b.measure(k as f64 * 0.01, 0.0)).collect();
        let phi = (-0.1_f64).exp();
        let drive = (1.0 - phi * phi).sqrt();
        let zeta: Vec<f64> = bk.windows(2).map(|w| (w[1] - phi * w[0]) / drive).collect();
        let tol = 5.0 / (n as f64).sqrt();
        let var = zeta.iter().map(|z| z * z).sum::<f64>() / n as f64;
        assert!((var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(), "innovation variance {var}");
        let r1 = correlation(&zeta[..n - 1], &zeta[1..]);
        assert!(r1.abs() < tol, "innovations lag-1 r = {r1}");
        for l in 0..5 {
            let same: Vec<f64> = (0..n).map(|k| xi[k + l]).collect();
            let doubled: Vec<f64> = (0..n).map(|k| xi[2 * k + l]).collect();
            let (r_same, r_doubled) = (correlation(&zeta, &same), correlation(&zeta, &doubled));
            assert!(r_same.abs() < tol && r_doubled.abs() < tol, "L {l}: {r_same}, {r_doubled}");
        }
    }

    /// A call far past the delay line jumps the drift with its exact transition: over 4000
    /// seeds, the drift after a 1e4 s gap (τ = 1 s) has variance σ² = 1 (standard error
    /// √(2/4000) = 0.022; tolerance 0.1) and is uncorrelated with the first reading
    /// (|r| < 0.08 = 5/√4000); the lag, with a constant truth, reaches it.
    #[test]
    fn analytic_gap_past_the_delay_line_keeps_drift_statistics() {
        let p = SensorParameters {
            gauss_markov: Some((1.0, 1.0)),
            lag_tau_s: Some(0.5),
            ..ideal(100.0)
        };
        let m = 4000;
        let (mut s0, mut s1, mut s11, mut s01) = (0.0, 0.0, 0.0, 0.0);
        let mut s00 = 0.0;
        for seed in 0..m {
            let mut s = SensorModel::new(p, seed).unwrap();
            let first = s.measure(0.0, 0.0);
            let later = s.measure(1e4, 3.0) - 3.0;
            s0 += first;
            s1 += later;
            s00 += first * first;
            s11 += later * later;
            s01 += first * later;
        }
        let mf = m as f64;
        let var1 = s11 / mf - (s1 / mf).powi(2);
        assert!((var1 - 1.0).abs() < 0.1, "variance after the gap {var1}");
        let cov = s01 / mf - s0 * s1 / (mf * mf);
        let r = cov / ((s00 / mf - (s0 / mf).powi(2)) * var1).sqrt();
        assert!(r.abs() < 0.08, "correlation across the gap {r}");
    }

    #[test]
    fn config_errors_name_the_field() {
        let bad = |s: &str| -> String {
            toml::from_str::<SensorConfig>(s)
                .map_err(|e| e.to_string())
                .and_then(|c| c.build(0).map(|_| ()).map_err(|e| e.to_string()))
                .unwrap_err()
        };
        assert!(bad("channel = \"a\"\nsample_rate_hz = 0.0\n").contains("sample_rate_hz"));
        assert!(
            bad("channel = \"a\"\nsample_rate_hz = 100.0\ndelay_s = 0.015\n").contains("delay_s")
        );
        assert!(
            bad("channel = \"a\"\nsample_rate_hz = 100.0\nwhite_sigma = -1.0\n")
                .contains("white_sigma")
        );
        assert!(
            bad("channel = \"a\"\nsample_rate_hz = 100.0\nquantum = 0.0\n").contains("quantum")
        );
        assert!(
            bad("channel = \"a\"\nsample_rate_hz = 100.0\ngauss_markov_sigma = 1.0\n")
                .contains("gauss_markov")
        );
        assert!(
            bad("channel = \"a\"\nsample_rate_hz = 100.0\nlag_tau_s = -1.0\n")
                .contains("lag_tau_s")
        );
        assert!(bad("channel = \"a\"\nsample_rate_hz = 100.0\nnoise = 1.0\n").contains("noise"));
    }

    #[test]
    fn no_panic_on_time_going_backwards_or_nan_time() {
        let mut s = SensorModel::new(ideal(100.0), 0).unwrap();
        let a = s.measure(1.0, 2.0);
        assert_eq!(s.measure(0.5, 3.0), a);
        assert_eq!(s.measure(f64::NAN, 3.0), a);
    }

    proptest::proptest! {
        #[test]
        fn prop_sensor_output_finite_for_finite_inputs(
            sigma in 0.0f64..10.0, bias in -10.0f64..10.0, gm in 0.0f64..5.0,
            tau in 1e-3f64..100.0, fs in 0.1f64..2000.0, delay in 0usize..20, scale in 0.5f64..1.5,
            lsb in 1e-6f64..1.0, lag in 1e-4f64..10.0, seed in 0u64..1000,
            truth in -1e6f64..1e6, dt in 1e-4f64..1.0,
        ) {
            let p = SensorParameters {
                white_sigma: sigma,
                bias,
                scale,
                gauss_markov: Some((gm, tau)),
                sample_rate_hz: fs,
                delay_samples: delay,
                lag_tau_s: Some(lag),
                quantum: Some(lsb),
            };
            let mut s = SensorModel::new(p, seed).unwrap();
            for i in 0..50 {
                let y = s.measure(i as f64 * dt, truth);
                proptest::prop_assert!(y.is_finite());
            }
            proptest::prop_assert!(s.noise_variance().is_finite());
        }
    }
}
