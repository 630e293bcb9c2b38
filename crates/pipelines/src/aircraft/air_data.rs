//! From the reference F-16's truth to the ONE air-data sample per step that the sample-driven
//! estimators see: unit conversion (the F-16 is in ft, slug, lbf; the sample is SI), the sensor
//! noise of [`super::sensors`] (one white-noise [`SensorModel`] per sensed channel, read at the
//! step's time `k·dt`), and angular accelerations as a real system forms them.
//!
//! # Channels (truth → sample)
//! - `vt_mps`, `alpha_rad`, `beta_rad`: **air-relative** airspeed and flow angles (pitot and
//!   vanes measure the air, so turbulence is seen by them), + noise (11 ft/s, 0.1°, 0.1°).
//! - `qbar_pa`: from the measured airspeed with the known density, `q̄_m = q̄ (V_m/V)²` (so its
//!   relative noise is twice the airspeed's).
//! - `p q r`: body rates + gyro noise (0.14°/s). `φ θ ψ`: attitude + 0.573°.
//! - `ax ay az`: specific force at the CG from the model's load factors (`nx`, `ny`, −`nz`) ×
//!   the model's g, + accelerometer noise (0.98 ft/s²); level flight reads `az ≈ −g`.
//! - Any of these twelve sensed channels ([`sensed_channels`]) may carry more sensor errors
//!   from a `[[sensors.channel]]` entry of the scenario (bias, lag, Gauss–Markov drift,
//!   transport delay, quantisation; [`channel_sensors`]), on top of the same white draws.
//! - `de da dr`: the surface positions (the model has no actuators; no surface sensor noise is
//!   cited, none is added). `thrust_n`: the engine model's thrust (as the thesis experiment,
//!   thrust is known from the engine model; F-16 thrust acts along body x through the CG).
//! - **`ṗ q̇ ṙ` and `α̇`: the causal least-squares differentiator of the shared conditioning
//!   stage** ([`crate::condition`], `N` = `[sensors] differentiator_window` points, default 11)
//!   **applied to the noisy gyro and vane signals**, exactly as a flight computer would. Its output is the derivative at the window
//!   centre, `(N−1)·dt/2` old (0.05 s at 11 points and 100 Hz), so every other channel is
//!   brought to the same instant and the sample is emitted with that older time stamp:
//!   - `alignment = "matched"` (default): every other channel passes the smoother matched to the
//!     differentiator ([`aeroident_signals::differentiate::MatchedSmoother`]: the same parabolic
//!     weighting and lag), so both sides of the equation-error regression see the same filter.
//!     The surfaces and throttle get the same weights as the states: the experiment flies them
//!     as continuous functions of time ([`super::experiment`], step 4), and the matched weights
//!     are those of a continuous signal (trapezoidal over each step). Until the staircase
//!     inputs were replaced they took the smoother's held weights, exact for a command held
//!     over the step (docs/uncertainty.md, "Bias: the staircase inputs").
//!     Without it the differentiator's smoothing (a sinusoid's derivative is attenuated by
//!     `G(ω)`, 0.988 at 1 Hz for 11 points at 100 Hz) faces unfiltered regressors, and
//!     turbulence content above the differentiator's band acts like regressor noise: the
//!     estimates of the β and rate derivatives are biased towards zero.
//!   - `alignment = "delay"`: every other channel is only delayed by the lag.
//!
//! Constants: mass, S, c̄, b and the inertias of the F-16 data converted to SI, `Ixz` = the
//! data's `Jxz` (Stevens & Lewis sign, as [`AirDataSample`] wants), no thrust arm or
//! inclination, `v0_mps` the trim airspeed. Two small model mismatches remain in the measured
//! moment coefficients: the F-16's moment equations use SLJ's rounded constants `c₁ … c₉` (e.g.
//! `c₇ = 1.792e-5` against `1/Iyy = 1.7917e-5`, +0.02 % on Cm) and its engine angular momentum
//! `h_x` (a gyroscopic moment `q h_x`, `−r h_x` of order 1e-5 in Cn, Cm), which the sample's
//! rigid-body equations do not carry.

use aeroident_estimators::sample::{AirDataSample, AircraftConstants};
use aeroident_models::f16::{self, F16, F16Controls, F16Outputs, F16State};
use aeroident_signals::SensorModel;
use aeroident_signals::differentiate::CausalDifferentiator;

use super::scenario::SensorSpec;
use super::sensors::{channel_seed, sensed_channels, white_noise_sensors};
use crate::condition::{Conditioner, Conditioning, Derivative};
use aeroident_physics::units::{KG_PER_SLUG, KGM2_PER_SLUGFT2, M_PER_FT, N_PER_LBF, PA_PER_PSF};

/// The F-16's constants in the sample's SI form; `v0_mps` the reference airspeed of `V/V0`.
pub fn f16_constants(f16: &F16, v0_mps: f64) -> AircraftConstants {
    let d = f16.data();
    let (m, g) = (&d.mass, &d.geometry);
    AircraftConstants {
        mass_kg: KG_PER_SLUG / m.inverse_mass_per_slug,
        S_m2: g.wing_area_ft2 * M_PER_FT * M_PER_FT,
        cbar_m: Some(g.cbar_ft * M_PER_FT),
        b_m: Some(g.span_ft * M_PER_FT),
        Ixx_kgm2: Some(m.ixx_slug_ft2 * KGM2_PER_SLUGFT2),
        Iyy_kgm2: Some(m.iyy_slug_ft2 * KGM2_PER_SLUGFT2),
        Izz_kgm2: Some(m.izz_slug_ft2 * KGM2_PER_SLUGFT2),
        Ixz_kgm2: Some(m.ixz_slug_ft2 * KGM2_PER_SLUGFT2),
        thrust_arm_m: 0.0,
        thrust_incidence_rad: 0.0,
        v0_mps: Some(v0_mps),
    }
}

/// The exact (noise-free, undelayed) sample of the F-16 at `t_s`: state `x`, its derivative
/// `xdot` (for `ṗ q̇ ṙ α̇`), the evaluation's outputs `out` and the controls `u`. The
/// reference of the conversion tests; the closed loop uses [`AirDataSampler`].
pub fn exact_sample(
    f16: &F16,
    constants: AircraftConstants,
    t_s: f64,
    x: &F16State,
    xdot: &F16State,
    out: &F16Outputs,
    u: &F16Controls,
) -> AirDataSample {
    let mut s = measured_channels(f16, constants, t_s, x, out, u, |_, v| v);
    s.pdot_rad_s2 = Some(xdot[f16::P]);
    s.qdot_rad_s2 = Some(xdot[f16::Q]);
    s.rdot_rad_s2 = Some(xdot[f16::R]);
    s.alphadot_rad_s = Some(xdot[f16::ALPHA]);
    s
}

/// All channels except the angular accelerations and α̇ (set by the caller); each of the
/// [`sensed_channels`] passes through `sense(index, truth)`, and `q̄` follows the sensed
/// airspeed.
fn measured_channels(
    f16: &F16,
    constants: AircraftConstants,
    t_s: f64,
    x: &F16State,
    out: &F16Outputs,
    u: &F16Controls,
    mut sense: impl FnMut(usize, f64) -> f64,
) -> AirDataSample {
    let g_fps2 = f16.data().mass.g_ft_per_s2;
    let truth = [
        out.vt_air_fps * M_PER_FT,
        out.alpha_air_rad,
        out.beta_air_rad,
        x[f16::P],
        x[f16::Q],
        x[f16::R],
        x[f16::PHI],
        x[f16::THETA],
        x[f16::PSI],
        out.nx_g * g_fps2 * M_PER_FT,
        out.ny_g * g_fps2 * M_PER_FT,
        -out.nz_g * g_fps2 * M_PER_FT,
    ];
    let m: [f64; 12] = core::array::from_fn(|i| sense(i, truth[i]));
    let qbar = out.qbar_psf * PA_PER_PSF * (m[0] / truth[0]).powi(2);
    AirDataSample {
        t_s,
        vt_mps: m[0],
        alpha_rad: m[1],
        qbar_pa: qbar,
        beta_rad: Some(m[2]),
        p_rad_s: Some(m[3]),
        q_rad_s: Some(m[4]),
        r_rad_s: Some(m[5]),
        pdot_rad_s2: None,
        qdot_rad_s2: None,
        rdot_rad_s2: None,
        alphadot_rad_s: None,
        phi_rad: Some(m[6]),
        theta_rad: Some(m[7]),
        psi_rad: Some(m[8]),
        ax_mps2: Some(m[9]),
        ay_mps2: Some(m[10]),
        az_mps2: Some(m[11]),
        de_rad: Some(u.elevator_rad),
        da_rad: Some(u.aileron_rad),
        dr_rad: Some(u.rudder_rad),
        thrust_n: Some(out.thrust_lbf * N_PER_LBF),
        throttle: Some(u.throttle),
        thrust_moment_nm: None,
        rho_kgpm3: None,
        constants,
    }
}

/// The sensors of the [`sensed_channels`]: white noise at `scale` × the cited levels when
/// `noise` is on, channel `i` keyed with [`channel_seed`]`(seed, 200, i)`, and on the channels
/// of `[[sensors.channel]]` their bias, lag, drift, delay and quantisation on top (same seed, so
/// the same white draws); `None` = an exact channel.
///
/// # Errors
/// A message naming the sensor setting for a bad level, channel name or channel entry.
pub fn channel_sensors(spec: &SensorSpec, dt_s: f64) -> Result<Vec<Option<SensorModel>>, String> {
    let channels = sensed_channels();
    let levels = channels.map(|(_, sg)| if spec.noise { sg * spec.scale } else { 0.0 });
    let mut sensors =
        white_noise_sensors(levels, dt_s, spec.seed, 200).map_err(|e| format!("sensors: {e}"))?;
    for c in &spec.channel {
        let Some(i) = channels.iter().position(|(n, _)| *n == c.channel) else {
            return Err(format!("sensors.channel: unknown channel `{}`", c.channel));
        };
        let white = levels[i].max(0.0);
        let sensor = c
            .build(white, dt_s, channel_seed(spec.seed, 200, i))
            .map_err(|e| format!("sensors.channel `{}`: {e}", c.channel))?;
        sensors[i] = Some(sensor);
    }
    Ok(sensors)
}

/// The sensor chain of the sample-driven estimators (module doc): noise, the causal
/// differentiator and the matching alignment. One per run; feed it every step.
#[derive(Debug, Clone)]
pub struct AirDataSampler {
    f16: F16,
    constants: AircraftConstants,
    /// One sensor per channel of [`sensed_channels`]; `None` = noise-free.
    sensors: Vec<Option<SensorModel>>,
    /// The shared conditioning stage: `ṗ q̇ ṙ α̇` differentiated, the other channels aligned.
    stage: Conditioner,
    /// Differentiator lag `(N−1)·dt/2`, s.
    lag_s: f64,
    /// Samples pushed (the stage's row numbers).
    pushed: u64,
    /// The stage's output buffers (at most one sample per push; warm-up rows are not kept).
    ready: Vec<(u64, AirDataSample)>,
    unused: Vec<u64>,
}

impl AirDataSampler {
    /// A sampler for the F-16 `f16` at step `dt_s`, `v0_mps` the reference airspeed, with the
    /// scenario's `[sensors]`: noise at `scale` × the cited levels from `seed` (`noise =
    /// false`: exact channels) plus the `[[sensors.channel]]` errors ([`channel_sensors`]), a
    /// differentiator of `differentiator_window` samples (odd) and the other channels
    /// `alignment`: matched to it (smoothed with the same weighting) or only delayed.
    ///
    /// # Errors
    /// A message naming the sensor setting for a bad window, level, channel entry or interval.
    pub fn new(f16: &F16, v0_mps: f64, dt_s: f64, spec: &SensorSpec) -> Result<Self, String> {
        let window = spec.differentiator_window;
        if window < 3 || window.is_multiple_of(2) {
            return Err(format!("sensors.differentiator_window must be odd and ≥ 3, got {window}"));
        }
        // Checked here, not at the first interval: a bad window or step is a setup error.
        let lag_s = CausalDifferentiator::new(window, dt_s).map_err(|e| e.to_string())?.lag_s();
        // Every channel, the surfaces and throttle included, is a continuous signal (the
        // experiment flies the pilot's controls at the RK4 stage times, not held over the
        // step), so the matched smoother's one weighting serves all.
        let stage = Conditioner::new(Conditioning {
            derivatives: Derivative::ALL.to_vec(),
            window,
            nominal_dt_s: Some(dt_s),
            alignment: spec.alignment,
        });
        let sensors = channel_sensors(spec, dt_s)?;
        Ok(Self {
            f16: f16.clone(),
            constants: f16_constants(f16, v0_mps),
            sensors,
            stage,
            lag_s,
            pushed: 0,
            ready: Vec::with_capacity(1),
            unused: Vec::new(),
        })
    }

    /// The delay of every emitted sample behind the newest truth, s.
    pub fn lag_s(&self) -> f64 {
        self.lag_s
    }

    /// Feeds the truth at `t_s` (state, evaluation outputs, controls) and returns the sample of
    /// `t_s − lag` once the window is filled (`None` before).
    pub fn push(
        &mut self,
        t_s: f64,
        x: &F16State,
        out: &F16Outputs,
        u: &F16Controls,
    ) -> Option<AirDataSample> {
        let sensors = &mut self.sensors;
        let s = measured_channels(&self.f16, self.constants, t_s, x, out, u, |i, v| {
            sensors[i].as_mut().map_or(v, |sensor| sensor.measure(t_s, v))
        });
        self.ready.clear();
        self.unused.clear();
        // The step is checked at construction and the simulator's times advance by it.
        self.stage.push(self.pushed, s, &mut self.ready, &mut self.unused).ok()?;
        self.pushed += 1;
        self.ready.pop().map(|(_, s)| s)
    }

    /// The **unsmoothed** sample behind the last one [`AirDataSampler::push`] emitted: the same
    /// time stamp (`t − lag`), every channel with its sensor noise but without the matched
    /// smoother (so its measurement errors are white, as a batch maximum-likelihood method
    /// assumes), the differentiated `ṗ q̇ ṙ α̇` as emitted. `None` before the first emission.
    pub fn raw(&self) -> Option<&AirDataSample> {
        self.stage.raw()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aircraft::scenario::ChannelSensorSpec;
    use crate::condition::Alignment;
    use aeroident_models::f16::AeroIncrements;
    use aeroident_models::trim::{TrimCondition, trim};

    /// Level trim: the accelerometer reads the specific force −g along the normal (az ≈ −g cos θ,
    /// ax ≈ g sin θ), and the sample's measured coefficients equal the F-16's own (CL to 1e-6;
    /// moments zero at trim).
    #[test]
    fn analytic_level_trim_sample_units_and_signs() {
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(20_000.0, 675.0)).unwrap();
        let (xd, o) = f.evaluate(&t.state, &t.controls, &AeroIncrements::zero()).unwrap();
        let k = f16_constants(&f, 675.0 * M_PER_FT);
        let s = exact_sample(&f, k, 0.0, &t.state, &xd, &o, &t.controls);
        let g = f.data().mass.g_ft_per_s2 * M_PER_FT;
        let th = t.state[f16::THETA];
        assert!((s.az_mps2.unwrap() + g * th.cos()).abs() < 1e-6 * g, "az {}", s.az_mps2.unwrap());
        assert!((s.ax_mps2.unwrap() - g * th.sin()).abs() < 1e-6 * g, "ax {}", s.ax_mps2.unwrap());
        assert!((s.vt_mps - 675.0 * 0.3048).abs() < 1e-9);
        let c = s.measured_coefficients();
        let want = o.coefficients;
        assert!((c[3].unwrap() - want.CL).abs() < 1e-6, "CL {} vs {}", c[3].unwrap(), want.CL);
        assert!((c[4].unwrap() - want.CD).abs() < 1e-6, "CD {} vs {}", c[4].unwrap(), want.CD);
        assert!((c[0].unwrap() - want.CX).abs() < 1e-6 && (c[2].unwrap() - want.CZ).abs() < 1e-6);
        for i in [5, 6, 7] {
            assert!(c[i].unwrap().abs() < 1e-9, "moment {i}: {}", c[i].unwrap());
        }
    }

    /// In motion (rates, sideslip, accelerations): forces to 1e-6, moments to the model's own
    /// rounding of its inertia constants (module doc: 2e-4 relative + the gyroscopic 1e-5).
    #[test]
    fn analytic_manoeuvring_sample_matches_model_coefficients() {
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(20_000.0, 675.0)).unwrap();
        let mut x = t.state;
        x[f16::BETA] = 0.03;
        x[f16::P] = 0.4;
        x[f16::Q] = 0.1;
        x[f16::R] = -0.08;
        x[f16::ALPHA] += 0.02;
        let mut u = t.controls;
        u.aileron_rad = 0.02;
        u.rudder_rad = -0.03;
        let (xd, o) = f.evaluate(&x, &u, &AeroIncrements::zero()).unwrap();
        let s = exact_sample(&f, f16_constants(&f, 205.74), 0.0, &x, &xd, &o, &u);
        let c = s.measured_coefficients();
        let want = crate::aircraft::truth::coefficient_vector(&o.coefficients);
        for i in 0..5 {
            assert!(
                (c[i].unwrap() - want[i]).abs() < 1e-6,
                "force {i}: {} vs {}",
                c[i].unwrap(),
                want[i]
            );
        }
        for i in 5..8 {
            let tol = 3e-4 * want[i].abs() + 3e-5;
            assert!(
                (c[i].unwrap() - want[i]).abs() < tol,
                "moment {i}: {} vs {}",
                c[i].unwrap(),
                want[i]
            );
        }
    }

    /// The sampler delays every channel by the differentiator's lag and stamps the sample with
    /// that older time: on a ramp in q the derivative is exact and the rates are the old ones.
    #[test]
    fn analytic_sampler_aligns_derivatives_with_delayed_channels() {
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(20_000.0, 675.0)).unwrap();
        let dt = 0.01;
        let spec = SensorSpec {
            differentiator_window: 11,
            alignment: Alignment::Delay,
            ..SensorSpec::default()
        };
        let mut smp = AirDataSampler::new(&f, 205.74, dt, &spec).unwrap();
        let lag = 5;
        assert!((smp.lag_s() - lag as f64 * dt).abs() < 1e-15);
        let mut got = Vec::new();
        for k in 0..40 {
            let tk = k as f64 * dt;
            let mut x = t.state;
            x[f16::Q] = 0.3 * tk; // ramp: q̇ = 0.3 exactly
            let (_, o) = f.evaluate(&x, &t.controls, &AeroIncrements::zero()).unwrap();
            if let Some(s) = smp.push(tk, &x, &o, &t.controls) {
                got.push((k, s));
            }
        }
        assert_eq!(got.first().unwrap().0, 10);
        for (k, s) in got {
            let t_old = (k - lag) as f64 * dt;
            assert!((s.t_s - t_old).abs() < 1e-12);
            assert!((s.q_rad_s.unwrap() - 0.3 * t_old).abs() < 1e-12);
            assert!((s.qdot_rad_s2.unwrap() - 0.3).abs() < 1e-9, "{}", s.qdot_rad_s2.unwrap());
        }
    }

    /// A `[[sensors.channel]]` entry adds its errors on top of the same white draws: with the
    /// channels only delayed, an α vane with bias 0.01 rad and a 2-step transport delay reads
    /// the plain noisy sampler's α of two steps before plus 0.01, while every other channel
    /// keeps its bits.
    #[test]
    fn analytic_channel_entry_adds_bias_and_delay_on_the_same_noise() {
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(20_000.0, 675.0)).unwrap();
        let dt = 0.01;
        let plain = SensorSpec {
            noise: true,
            seed: 3,
            differentiator_window: 5,
            alignment: Alignment::Delay,
            ..SensorSpec::default()
        };
        let toml = "channel = \"alpha_rad\"\nbias = 0.01\ndelay_samples = 2\n";
        let entry: ChannelSensorSpec = toml::from_str(toml).unwrap();
        let vane = SensorSpec { channel: vec![entry], ..plain.clone() };
        let mut a = AirDataSampler::new(&f, 205.74, dt, &plain).unwrap();
        let mut b = AirDataSampler::new(&f, 205.74, dt, &vane).unwrap();
        let mut plain_alpha = Vec::new();
        for k in 0..60 {
            let tk = k as f64 * dt;
            let mut x = t.state;
            x[f16::ALPHA] += 0.02 * (3.0 * tk).sin(); // a moving truth makes the delay visible
            let (_, o) = f.evaluate(&x, &t.controls, &AeroIncrements::zero()).unwrap();
            let (sa, sb) = (a.push(tk, &x, &o, &t.controls), b.push(tk, &x, &o, &t.controls));
            let (Some(sa), Some(sb)) = (sa, sb) else { continue };
            plain_alpha.push(sa.alpha_rad);
            assert_eq!((sa.vt_mps, sa.q_rad_s, sa.az_mps2), (sb.vt_mps, sb.q_rad_s, sb.az_mps2));
            let n = plain_alpha.len();
            if n > 2 {
                let want = plain_alpha[n - 3] + 0.01;
                assert!((sb.alpha_rad - want).abs() < 1e-12, "k {k}: {} vs {want}", sb.alpha_rad);
            }
        }
        assert_eq!(plain_alpha.len(), 56);
    }

    /// The surfaces are continuous signals (the experiment flies them at the RK4 stage times), so
    /// the matched smoother gives a ramp in a surface back at the sample's time stamp, exactly
    /// (the weights are symmetric and sum to 1), as it does a ramp in q. The held weights of a
    /// zero-order-hold command (used until the staircase inputs were replaced) give the ramp
    /// `dt/2` older: 0.5 · 0.2 rad/s · 0.01 s = 1e-3 rad off.
    #[test]
    fn analytic_matched_sampler_smooths_surfaces_as_continuous_signals() {
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(20_000.0, 675.0)).unwrap();
        let dt = 0.01;
        let spec = SensorSpec { differentiator_window: 21, ..SensorSpec::default() };
        let mut smp = AirDataSampler::new(&f, 205.74, dt, &spec).unwrap();
        let rate = 0.2; // rad/s on every surface
        let mut n = 0;
        for k in 0..60 {
            let tk = k as f64 * dt;
            let mut u = t.controls;
            u.elevator_rad += rate * tk;
            u.aileron_rad += rate * tk;
            u.rudder_rad += rate * tk;
            let (_, o) = f.evaluate(&t.state, &u, &AeroIncrements::zero()).unwrap();
            let Some(s) = smp.push(tk, &t.state, &o, &u) else { continue };
            let ramp = rate * s.t_s;
            for (got, trim) in [
                (s.de_rad.unwrap(), t.controls.elevator_rad),
                (s.da_rad.unwrap(), t.controls.aileron_rad),
                (s.dr_rad.unwrap(), t.controls.rudder_rad),
            ] {
                assert!(
                    (got - trim - ramp).abs() < 1e-12,
                    "t {}: {} vs {}",
                    s.t_s,
                    got - trim,
                    ramp
                );
            }
            n += 1;
        }
        assert_eq!(n, 40);
    }
}
