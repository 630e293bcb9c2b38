//! Data compatibility check and flight-path reconstruction: are a record's accelerations,
//! rates, attitudes and air data consistent with each other, and what biases, scale factors
//! and time shifts make them so (Jategaonkar 2015 ch. 10; Klein & Morelli 2006 ch. 10;
//! Mulder, Chu, Sridhar & Breeman, "Non-linear aircraft flight path reconstruction review and
//! new advances", Prog. Aerospace Sci. 1999).
//!
//! # Model
//! The kinematic equations of a rigid body over a flat, non-rotating earth in still air (SLJ
//! §2.5), driven by the corrected inertial channels, states `x = [u, v, w, φ, θ, ψ]`:
//!
//! ```text
//! [u̇ v̇ ẇ] = body_acceleration([u v w], ω, g_b(φ, θ), a)      a = (a_m − b_a) / (1 + k_a)
//! [φ̇ θ̇ ψ̇] = euler_rates(ω, φ, θ)                              ω = (ω_m − b_ω) / (1 + k_ω)
//! ```
//!
//! `a_m` the measured specific forces (`ax, ay, az`, m/s²), `ω_m` the measured rates (`p, q,
//! r`, rad/s), `b` their biases, `k` their scale-factor errors (estimated on request,
//! [`CompatConfig::inertial_scale_factors`]). The inputs are interpolated linearly between
//! samples and the equations integrated by RK4 from each manoeuvre's initial state; each gyro
//! is read at its own time shift, `ω(t) = ω_m(t + τ_ω)` ("Time shifts").
//!
//! The outputs, each measured channel at its own time shift `τ` (a measurement that lags the
//! kinematics by `τ > 0` reads at `t` what the kinematics had at `t − τ`):
//!
//! ```text
//! V_m = V + b_V          α_m = (1 + k_α) α + b_α          β_m = (1 + k_β) β + b_β
//! φ_m = φ                θ_m = θ                          ψ_m = ψ
//! ```
//!
//! with `V = |[u v w]|`, `α = atan2(w, u)`, `β = asin(v/V)`. There is no wind model, and a
//! steady wind needs none: a constant NED velocity seen in body axes obeys the same transport
//! terms as the body velocity (`d/dt (C_bn W) = −ω × C_bn W`), so the estimated initial
//! velocity absorbs it exactly, in a turn too (`tests::a_steady_wind_leaves_no_trace_in_the_check`).
//! For the same reason a steady wind cannot be identified without a measured inertial
//! velocity (GPS). A wind that changes during a manoeuvre (turbulence, shear, a climb through
//! a wind gradient) shows as residual and, when slow, as air-data biases.
//!
//! # Estimation
//! Output error with the noise covariance estimated (diagonal `R`, maximum likelihood;
//! Jategaonkar ch. 4): Gauss–Newton with Levenberg–Marquardt damping on central-difference
//! sensitivities. Converged when the relative change of `det R` is below
//! [`CompatConfig::cost_tolerance`] and the largest step below
//! [`CompatConfig::step_tolerance_sigma`] σ (or, when no damped step lowers the cost, the
//! Gauss–Newton step is below 0.01 σ, the precision of the central differences); a fit
//! stopped earlier reports its last iterate
//! ([`Termination`]). σ is the Cramér–Rao bound `sqrt(diag M⁻¹)` and, where formed, the
//! coloured-residual σ of output error's spectral sandwich (`crate::coloured::batch`), which
//! the residuals of a real record (turbulence, model error, sample-and-hold) call for. Each
//! initial state moves its own manoeuvre alone, so `M`, its solves and the sandwich are formed
//! by manoeuvre blocks (`blocks`, `coloured`): a joint check costs time linear in its
//! manoeuvres, not cubic in its unknowns.
//!
//! Without a `β` channel, `β` is reconstructed from the integrated `v`. The initial `v` and the
//! `ay` bias are still estimated when the record rolls (`v` enters `ẇ` through `p v`, so `α`
//! sees them); when it does not roll enough for that (the information matrix is singular),
//! both are fixed at 0 and [`CompatResult::notes`] says so. Without a heading the `ψ` state is
//! dropped (it enters no other output in still air). A time shift is estimated only where the
//! channel varies enough to determine it (its Cramér–Rao σ alone below 0.05 s at the start); a
//! scale factor only where the record determines it with the other unknowns (σ below 0.02, at
//! the start and again after the fit, with its residuals; else left out and the fit redone):
//! without a sideslip channel the `ay` scale factor trades with the `ay` bias and the initial
//! side velocity (`determined`).
//!
//! # Time shifts
//! Every output but the airspeed gets one ([`CompatConfig::time_shifts`]); on request each gyro
//! too ([`CompatConfig::gyro_time_shifts`]): the rates of an AHRS come through its filter
//! 0.1–0.2 s late, with its attitudes. A gyro that lags by `τ > 0` is read `τ` later, linearly
//! interpolated between samples as the outputs are (held at the record's ends). The
//! accelerometers are the time reference: shifting every channel by one amount changes the
//! kinematics only at the record's ends, so only shifts relative to the accelerometers can be
//! seen, and theirs is not estimated.
//!
//! `θ̇ = q cos φ − r sin φ` ties the shifts of `θ` and `q` together (the attitude sees their
//! difference); `α̇ ≈ q + (a_z + g cos θ cos φ)/V` with an unlagged `a_z` separates them, and
//! `V` and the roll do the rest. On the information matrix of the synthetic record of the
//! tests, the correlation of the two estimates is 0.35 with `a_z` varying and 0.92 with `a_z`
//! balancing gravity alone (`α̇ = q`), when the σ of `q`'s shift is 5.8 times larger. What ties
//! the shifts to the accelerometers (the airspeed, the vanes, `a_z` through `α`) is weak, and
//! at a coarse sample rate the cost has local minima a whole sample apart in the common shift
//! of the AHRS (the linear interpolation is exact at whole samples and smooths between them):
//! on a 10 Hz F-16 record with the gyros and attitudes 0.1 s late, the fit from zero ends a
//! further 0.05 s (pitch) to 0.12 s (roll and yaw) late on all of them, vanes included. With
//! a gyro's shift the fit therefore starts from common AHRS shifts of 0, 0.1, 0.2 and 0.3 s
//! (whole samples) and keeps the lowest `det R`, a converged fit before one that is not
//! within half a unit of log-likelihood.
//!
//! Off by default: on the HFB-320 record (Jategaonkar test case 4) the shift of `q` trades
//! with the slow misfit of the airspeed (its residual falls from 0.88 to 0.69 m/s as `q`, `θ`
//! and `α` move 0.7 s late together) and the fit does not converge, where without it the α
//! vane is found 0.22 s late; on the degraded F-16 record the `p` bias goes from within 1σ of
//! the truth to 12σ (3 %) off, though every shift is right there (`r` and `ψ`, recorded at
//! 100 Hz, lead the accelerometers' 10 Hz hold by half a sample, 0.050 s).
//!
//! **What decides the common AHRS shift, and why a coarse record may not.** Only `α` ties the
//! gyros to the accelerometers on a record without a sideslip vane (the attitudes share the
//! gyros' shift, the airspeed varies slowly), and the α vane's own shift and scale factor are
//! unknowns too: the timing of `a_z` against `q` shows in the fast part of the response (a
//! control step). Measured on the F-16 flying its linear aerodynamics in calm air, every rate
//! and attitude and the α vane 0.2 s late (pure delays), biases and 2–5 % scale factors on
//! every accelerometer and gyro, no β vane (`--gyro-time-shifts --inertial-scale-factors`;
//! `scenarios/sim/degraded_raw.toml` without its turbulence, the AHRS lag replaced by the
//! delay, sensors at 100 Hz and the record kept at every 1st, 2nd, 5th and 10th row): at 100
//! and 50 Hz every shift is 0.189–0.205 ± 0.010 s; at 20 Hz 0.243–0.255 ± 0.010 s with the α
//! scale factor 0.962 taking up the difference, the residuals at the noise level; at 10 Hz
//! p, r, φ, ψ 0.189–0.200 s but q, θ, α 0.249–0.254 ± 0.012 s (α scale 0.966);
//! `scenarios/sim/ahrs_delay_nobeta.toml` at 10 Hz the other way round (q, θ, α 0.215 s;
//! p, r, φ, ψ 0.250–0.255 ± 0.015 s); a like record measured before put the 10 and 20 Hz
//! shifts 0.11 s late. Without the
//! inertial scale factors the 100 Hz record's shift is 0.29 s: the gyros' scale errors pass
//! for a lag. So at coarse sample rates without a β vane the common AHRS shift can be off by
//! several times its Cramér–Rao σ, and nothing in the residuals shows it; a note says so
//! ([`CompatResult::notes`]).
//!
//! **A filter's lag is not a delay.** An AHRS's first-order lag (τ = 0.1 s, sensors at 100 Hz:
//! a low-frequency delay of 0.105 s) on the same calm record is read as 0.18–0.20 s at 100 and
//! 10 Hz, the α vane's pure 0.2 s delay as 0.29–0.30 s: the differences between channels are
//! right (0.10 s for 0.095 s), the common part 0.08 s late, as with a β vane
//! (`compat_gyro_shift`, 0.06 s). The check is for calm air, but light turbulence does not
//! change this picture: `degraded_raw.toml` itself (sensors at 10 Hz, every 10th row) reads
//! the gyros 0.17–0.20 s for the lag's 0.158 s and the α vane 0.26 s for 0.2 s (before the
//! scale factors were held to σ 0.02, the same flight kept at every row read every shift
//! 0.58–0.63 s, the accelerometers' scale factors having run off). A delay has the gain 1 at
//! every frequency and a lag does not (0.8 at 5 rad/s for τ = 0.15 s): on the synthetic
//! record of the tests with fast pitch and roll content the shifts read the lag's delay about
//! right (0.145–0.150 s for τ = 0.15 s) but leave α's residual 1.6 times its noise. Hence the
//! lag as its own unknown (next section).
//!
//! # The AHRS's lag
//! On request ([`CompatConfig::ahrs_lag`], `aeroident compat --ahrs-lag`) the gyros and the
//! attitudes come through one first-order filter `L(τ)`, `τ ẏ + y = u`, whose time constant
//! is an unknown ([`Unknown::AhrsLag`]) in place of the gyros' time shifts. The kinematics are
//! driven by the gyros as measured (lagged) and by the accelerometers passed through the same
//! filter ([`lag_step`], exact for their linear interpolation, from steady state at each
//! manoeuvre's start). For a linear system that makes the integrated state the lagged state
//! `x_L = L(τ) x`; the kinematics are not linear (products `q w`, `g sin θ`), so it is that to
//! first order in the motion. The attitudes compare with `x_L` directly, and the air data with
//! the unlagged state `x = x_L + τ ẋ_L` (`L⁻¹ = 1 + τ s`), `ẋ_L` from the state equation at
//! each sample, so nothing measured is differentiated or filtered (filtering the measured
//! outputs would colour their noise and bias the likelihood towards a large τ). The vanes keep
//! their own time shifts, biases and scale factors, against the unlagged kinematics; the
//! attitudes keep their shifts too, which then measure only how much later than the gyros they
//! come (0 for one filter). A negative τ, which no filter has but which the central
//! differences at 0 visit, reads the accelerometers `|τ|` later instead: the same to first
//! order, so the cost is smooth through 0. The fit starts from τ = 0, 0.1 and 0.2 s and keeps
//! the best (`Problem::solve`). `replay --compat` then passes every other channel through
//! the same filter rather than undoing it (`aeroident_pipelines::record::corrections`).
//!
//! Measured (`cargo test --release -p aeroident-estimators compat::tests::an_ahrs` and
//! `cargo test --release -p aeroident --test all compat_ahrs_lag:: -- --nocapture`):
//! - the synthetic record of the tests, τ = 0.15 s on the gyros and attitudes filtered on the
//!   generator's fine steps: 0.1495 ± 0.0004 s at 50 Hz with a β vane, 0.1511 ± 0.0008 s at
//!   10 Hz without, α's residual at its noise; the second-order error of the model leaves the
//!   accelerometer biases up to 0.003 m/s² and a gyro's 5·10⁻⁵ rad/s off (a few σ there);
//! - `scenarios/sim/ahrs_lag_degraded.toml` (τ = 0.15 s, AHRS at 100 Hz, so a low-frequency
//!   delay of 0.155 s; the α vane 0.2 s late; biases and 2–5 % scale factors; no β vane; light
//!   turbulence) with the inertial scale factors: 0.168 ± 0.017 s kept at 10 Hz, 0.163 ± 0.016 s
//!   at 20 Hz, the α vane 0.236 and 0.227 ± 0.021 s; without the scale factors 0.182 and
//!   0.186 s (their 3–5 % pass for a lag, as for the shifts). The gyros' shifts on the same 10 Hz
//!   record: p, q, φ, θ 0.200 s, r, ψ 0.154 s, α 0.279 s.
//!
//! Off by default: on that record the corrected six-axis output error gets the longitudinal
//! primary derivatives and Cl_p, Cl_δa, Cn_β, Cn_δr within 10 % (uncorrected up to 35 % off),
//! but the reconstructed sideslip it then fits puts CY_β 24 %, Cl_β 12 % and Cn_r 19 % off,
//! where the uncorrected fit, β a state, had them within 4.3, 4.8 and 19.5 %; so it is not
//! never worse than no correction, which `--compat auto` must be. With a β vane added to the
//! same flight CY_β still goes from 4.6 % to 11.3 % off. The check without the lag therefore
//! redoes itself with it and names a determined lag, with the command that models it
//! (`aeroident_pipelines::compat`; docs/real-data.md).
//!
//! # Held out
//! [`held_out`] judges each correction on data it was not fitted on: each manoeuvre (or each
//! half of a single one, or each of [`MAX_FOLDS`] folds of consecutive manoeuvres when there
//! are more) held out in turn, the check redone on the others, and each of their corrections
//! applied to the held-out piece with only its initial states fitted. One the rest
//! of the record contradicts beyond the noise fails (the `held_out` module doc, "When it
//! fails"); `replay --compat` refuses it.

use crate::EstimatorError;
use crate::flight_model::{G0_MPS2, Output};
use crate::output_error::{NotConverged, Termination};
use crate::sample::AirDataSample;
use aeroident_physics::rigid_body::{self as rb, SinCos};
use nalgebra::{DMatrix, DVector};

mod blocks;
mod coloured;
mod determined;
mod held_out;
mod inputs;
mod starts;

pub use held_out::{
    FAIL_SPREADS, HeldOut, HeldOutCorrection, MAX_FOLDS, MIN_FAILING_RISE, PIECE_TOO_SHORT, fails,
    folds, held_out,
};

use blocks::{Partition, Schur, Sensitivities};
use inputs::Inputs;

/// A measured channel the check corrects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// Body x specific force, m/s².
    Ax,
    /// Body y specific force, m/s².
    Ay,
    /// Body z specific force, m/s².
    Az,
    /// Roll rate, rad/s.
    P,
    /// Pitch rate, rad/s.
    Q,
    /// Yaw rate, rad/s.
    R,
    /// True airspeed, m/s.
    Vt,
    /// Angle of attack, rad.
    Alpha,
    /// Sideslip, rad.
    Beta,
    /// Bank angle, rad.
    Phi,
    /// Pitch attitude, rad.
    Theta,
    /// Heading, rad.
    Psi,
}

impl Channel {
    /// The inertial channels, in the order of `a` then `ω`.
    pub const INERTIAL: [Channel; 6] =
        [Channel::Ax, Channel::Ay, Channel::Az, Channel::P, Channel::Q, Channel::R];
    /// The output channels, in model order.
    pub const OUTPUTS: [Channel; 6] =
        [Channel::Vt, Channel::Alpha, Channel::Beta, Channel::Phi, Channel::Theta, Channel::Psi];

    /// The flight model's output this channel is (every one but the heading, which the flight
    /// model does not carry): its name, reading and writing are [`Output`]'s.
    pub fn output(self) -> Option<Output> {
        Some(match self {
            Channel::Ax => Output::Ax,
            Channel::Ay => Output::Ay,
            Channel::Az => Output::Az,
            Channel::P => Output::P,
            Channel::Q => Output::Q,
            Channel::R => Output::R,
            Channel::Vt => Output::Vt,
            Channel::Alpha => Output::Alpha,
            Channel::Beta => Output::Beta,
            Channel::Phi => Output::Phi,
            Channel::Theta => Output::Theta,
            Channel::Psi => return None,
        })
    }

    /// The sample field's name (`ax_mps2`, `alpha_rad` …; [`Output::name`]).
    pub fn name(self) -> &'static str {
        self.output().map_or("psi_rad", Output::name)
    }

    /// The channel's unit (`m/s^2`, `rad/s`, `m/s`, `rad`).
    pub fn unit(self) -> &'static str {
        match self {
            Channel::Ax | Channel::Ay | Channel::Az => "m/s^2",
            Channel::P | Channel::Q | Channel::R => "rad/s",
            Channel::Vt => "m/s",
            _ => "rad",
        }
    }

    /// Sets the channel's value in sample `s` to `v` ([`Output::set_measured`]).
    pub fn set(self, s: &mut AirDataSample, v: f64) {
        match self.output() {
            Some(o) => o.set_measured(s, v),
            None => s.psi_rad = Some(v),
        }
    }

    /// The channel of a sample field's name (`alpha_rad` …), if it is one.
    pub fn from_name(name: &str) -> Option<Channel> {
        Channel::INERTIAL.into_iter().chain(Channel::OUTPUTS).find(|c| c.name() == name)
    }

    /// The channel's value in sample `s` (`None` when not recorded; [`Output::measured`]).
    pub fn of(self, s: &AirDataSample) -> Option<f64> {
        match self.output() {
            Some(o) => o.measured(s),
            None => s.psi_rad,
        }
    }
}

/// What the check estimates and when it stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompatConfig {
    /// Estimate a time shift of every measured output but the airspeed (default true).
    pub time_shifts: bool,
    /// Estimate a time shift of each gyro, `p, q, r`, against the accelerometers (default
    /// false: on the HFB-320 record it trades with the airspeed's slow model error and moves
    /// the α lag from 0.22 s to 0.8 s; module doc, "Time shifts").
    pub gyro_time_shifts: bool,
    /// Estimate the scale-factor errors of the accelerometers and gyros too (default false:
    /// they need large, varied manoeuvres to separate from the biases).
    pub inertial_scale_factors: bool,
    /// Model the AHRS's first-order filter on the gyros and attitudes, its time constant an
    /// unknown ([`Unknown::AhrsLag`]; module doc, "The AHRS's lag"); the gyros then get no
    /// time shift of their own, whatever [`CompatConfig::gyro_time_shifts`] says (default
    /// false).
    pub ahrs_lag: bool,
    /// Most Gauss–Newton iterations (default 50).
    pub max_iterations: usize,
    /// Convergence: relative change of `det R` (default 10⁻⁶).
    pub cost_tolerance: f64,
    /// Convergence: largest step in Cramér–Rao σ (default 10⁻³).
    pub step_tolerance_sigma: f64,
}

impl Default for CompatConfig {
    fn default() -> Self {
        Self {
            time_shifts: true,
            gyro_time_shifts: false,
            inertial_scale_factors: false,
            ahrs_lag: false,
            max_iterations: 50,
            cost_tolerance: 1e-6,
            step_tolerance_sigma: 1e-3,
        }
    }
}

/// One kind of unknown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unknown {
    /// Additive bias of a channel (channel units).
    Bias(Channel),
    /// Scale-factor error `k` of a channel (measured = (1 + k) · true).
    Scale(Channel),
    /// Time shift of an output or a gyro, s (> 0: the measurement lags the kinematics).
    TimeShift(Channel),
    /// Time constant of the AHRS's first-order filter on the gyros and attitudes, s
    /// (`τ ẏ + y = u`; module doc, "The AHRS's lag").
    AhrsLag,
    /// An initial state of a manoeuvre.
    Initial {
        /// The manoeuvre, from 0.
        manoeuvre: usize,
        /// The state, 0–5: u, v, w (m/s), φ, θ, ψ (rad).
        state: usize,
    },
}

impl Unknown {
    /// A name for tables: `bias_ax_mps2`, `scale_alpha_rad`, `time_shift_alpha_rad`,
    /// `ahrs_lag_tau_s`, `x0_m1_u_mps` ….
    pub fn name(self) -> String {
        const STATES: [&str; 6] = ["u_mps", "v_mps", "w_mps", "phi_rad", "theta_rad", "psi_rad"];
        match self {
            Unknown::Bias(c) => format!("bias_{}", c.name()),
            Unknown::Scale(c) => format!("scale_{}", c.name()),
            Unknown::TimeShift(c) => format!("time_shift_{}", c.name()),
            Unknown::AhrsLag => "ahrs_lag_tau_s".into(),
            Unknown::Initial { manoeuvre, state } => {
                format!("x0_m{}_{}", manoeuvre + 1, STATES[state])
            }
        }
    }
}

/// The reconstructed air data of one manoeuvre at its sample times (from the fitted states).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Reconstructed {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Airspeed `|[u v w]|`, m/s.
    pub vt_mps: Vec<f64>,
    /// Angle of attack `atan2(w, u)`, rad.
    pub alpha_rad: Vec<f64>,
    /// Sideslip `asin(v/V)`, rad.
    pub beta_rad: Vec<f64>,
}

/// The result of [`check`].
#[derive(Debug, Clone, PartialEq)]
pub struct CompatResult {
    /// The unknowns, in the order of `values`.
    pub unknowns: Vec<Unknown>,
    /// Estimates.
    pub values: Vec<f64>,
    /// Cramér–Rao σ.
    pub sigma: Vec<f64>,
    /// The coloured-residual σ (output error's spectral sandwich, `crate::coloured::batch`),
    /// where formed: it allows for coloured residuals, as a real record has (not yet checked
    /// against the scatter of repeated records: the degraded test finds q's bias 4.9σ off).
    pub sigma_coloured: Option<Vec<f64>>,
    /// The fitted outputs.
    pub outputs: Vec<Channel>,
    /// Residual RMS per output (its unit).
    pub residual_rms: Vec<f64>,
    /// Residual mean per output (its unit).
    pub residual_mean: Vec<f64>,
    /// The modelled outputs at the estimate (what each sensor should read from the
    /// reconstructed flight path with its bias, scale and time shift), `N × ny` row-major, the
    /// manoeuvres' samples concatenated in order; the measured value is this plus the residual.
    pub predicted: Vec<f64>,
    /// The residuals measured − `predicted`, same layout (heading wrapped into (−π, π]).
    pub residuals: Vec<f64>,
    /// Per manoeuvre, the reconstructed air data.
    pub reconstructed: Vec<Reconstructed>,
    /// How the iterations ended.
    pub termination: Termination,
    /// Gauss–Newton iterations done.
    pub iterations: usize,
    /// What the check could not determine and fixed instead.
    pub notes: Vec<String>,
}

impl CompatResult {
    /// Estimate and Cramér–Rao σ of `u`, if it was estimated.
    pub fn get(&self, u: Unknown) -> Option<(f64, f64)> {
        let i = self.unknowns.iter().position(|&v| v == u)?;
        Some((self.values[i], self.sigma[i]))
    }

    /// The reported σ of every unknown: the coloured-residual σ where formed, else the
    /// Cramér–Rao σ.
    pub fn reported_sigma(&self) -> &[f64] {
        self.sigma_coloured.as_deref().unwrap_or(&self.sigma)
    }

    /// Estimate and reported σ ([`CompatResult::reported_sigma`]) of `u`, if it was estimated.
    pub fn reported(&self, u: Unknown) -> Option<(f64, f64)> {
        let i = self.unknowns.iter().position(|&v| v == u)?;
        Some((self.values[i], self.reported_sigma()[i]))
    }
}

/// Checks the compatibility of `manoeuvres` (each a gap-free run of samples with `ax, ay, az,
/// p, q, r`, `θ` and `φ`; a longitudinal record with none of `ay, p, r, φ` is checked in the
/// vertical plane) and reconstructs the flight path (module doc).
///
/// # Errors
/// [`EstimatorError::InvalidConfig`] naming a missing channel or an empty or too short
/// manoeuvre; [`EstimatorError::Numerical`] when the information matrix is singular at the
/// start (an unknown the record cannot determine) or the kinematics leave the physical domain.
pub fn check(
    manoeuvres: &[&[AirDataSample]],
    config: &CompatConfig,
) -> Result<CompatResult, EstimatorError> {
    in_plane(manoeuvres, |m| check_as_given(m, config))
}

/// `fit` of the manoeuvres as the check takes them: a record without `ay` that flies wings
/// level in the vertical plane, with [`VERTICAL_PLANE_NOTE`] (module doc), else as they are.
fn in_plane(
    manoeuvres: &[&[AirDataSample]],
    fit: impl Fn(&[&[AirDataSample]]) -> Result<CompatResult, EstimatorError>,
) -> Result<CompatResult, EstimatorError> {
    match wings_level_without_ay(manoeuvres)? {
        Some(planar) => {
            let slices: Vec<&[AirDataSample]> = planar.iter().map(Vec::as_slice).collect();
            let mut r = fit(&slices)?;
            r.notes.insert(0, VERTICAL_PLANE_NOTE.into());
            Ok(r)
        }
        None => fit(manoeuvres),
    }
}

/// [`check`] with the AHRS lag and the inertial scale factors as unknowns
/// ([`CompatConfig::ahrs_lag`], [`CompatConfig::inertial_scale_factors`]), started once from
/// `from`'s corrections (a check of the same manoeuvres under `config`) and a time constant of
/// [`AHRS_LAG_PROBE_START_S`], instead of from the usual three time constants: the check
/// without the lag has fitted the biases already, so one start costs a third.
///
/// For naming a lag `config` does not model. Measured on `scenarios/sim/ahrs_lag_degraded.toml`
/// at 10 Hz: the same τ as the three starts, 0.168 ± 0.017 s
/// (`crates/aeroident/tests/all/compat_ahrs_lag.rs`).
///
/// # Errors
/// As [`check`].
pub fn check_with_ahrs_lag(
    manoeuvres: &[&[AirDataSample]],
    config: &CompatConfig,
    from: &CompatResult,
) -> Result<CompatResult, EstimatorError> {
    let lagged = CompatConfig { ahrs_lag: true, inertial_scale_factors: true, ..*config };
    let mut warm: Vec<(Unknown, f64)> =
        from.unknowns.iter().copied().zip(from.values.iter().copied()).collect();
    warm.push((Unknown::AhrsLag, AHRS_LAG_PROBE_START_S));
    in_plane(manoeuvres, |m| check_warm(m, &lagged, &warm))
}

/// The time constant [`check_with_ahrs_lag`] starts from, s: the middle of an AHRS's 0.05–0.2 s.
pub const AHRS_LAG_PROBE_START_S: f64 = 0.1;

/// Largest bank angle, rad, and roll and yaw rates, rad/s, of a record without `ay` that is
/// still checked in the vertical plane: there `θ̇ = q cosφ − r sinφ` is off by at most
/// `r sinφ` < 0.005 rad/s and gravity's share along `z` by `1 − cos 5°` = 0.4 % (0.04 m/s²,
/// mostly taken up by the `az` bias). ATTAS's elevator records stay within 4.4° and 2°/s.
const WINGS_LEVEL_PHI_RAD: f64 = 5.0 * core::f64::consts::PI / 180.0;
const WINGS_LEVEL_RATE_RAD_S: f64 = 3.0 * core::f64::consts::PI / 180.0;

/// The note of a record checked in the vertical plane although it maps some lateral channels.
pub const VERTICAL_PLANE_NOTE: &str = "no ay channel and the record flies wings level (|φ| within 5°, |p| and |r| within 3°/s): checked in the vertical plane, the p, r and φ channels left out";

/// A record without `ay` that maps some of `p, r, φ`: copies of its manoeuvres without them
/// when it flies wings level ([`WINGS_LEVEL_PHI_RAD`]), to be checked in the vertical plane;
/// `None` for a record with `ay` or with none of them.
///
/// # Errors
/// [`EstimatorError::InvalidConfig`] on `ay` when the record rolls: the side motion then enters
/// `α` through `p v`, which needs `ay`.
fn wings_level_without_ay(
    manoeuvres: &[&[AirDataSample]],
) -> Result<Option<Vec<Vec<AirDataSample>>>, EstimatorError> {
    let samples = || manoeuvres.iter().flat_map(|m| m.iter());
    let lateral = [Channel::P, Channel::R, Channel::Phi];
    if samples().any(|s| s.ay_mps2.is_some())
        || samples().all(|s| lateral.iter().all(|c| c.of(s).is_none()))
    {
        return Ok(None);
    }
    let within =
        |c: Channel, bound: f64| samples().all(|s| c.of(s).is_none_or(|v| v.abs() <= bound));
    if !(within(Channel::Phi, WINGS_LEVEL_PHI_RAD)
        && within(Channel::P, WINGS_LEVEL_RATE_RAD_S)
        && within(Channel::R, WINGS_LEVEL_RATE_RAD_S))
    {
        return Err(EstimatorError::InvalidConfig {
            field: "ay_mps2",
            value: f64::NAN,
            reason: "the record rolls (|φ| above 5° or |p|, |r| above 3°/s) and maps no ay: the side motion then enters α through p v, so the check needs ay; map it, or check a wings-level window",
        });
    }
    let planar = manoeuvres
        .iter()
        .map(|m| {
            m.iter()
                .map(|s| AirDataSample { p_rad_s: None, r_rad_s: None, phi_rad: None, ..*s })
                .collect()
        })
        .collect();
    Ok(Some(planar))
}

/// [`check`] of manoeuvres as they are.
fn check_as_given(
    manoeuvres: &[&[AirDataSample]],
    config: &CompatConfig,
) -> Result<CompatResult, EstimatorError> {
    check_warm(manoeuvres, config, &[])
}

/// [`check_as_given`] started from the corrections `warm` ([`Problem::warm`]; none: the usual
/// starts).
fn check_warm(
    manoeuvres: &[&[AirDataSample]],
    config: &CompatConfig,
    warm: &[(Unknown, f64)],
) -> Result<CompatResult, EstimatorError> {
    let first = Problem::new(manoeuvres, config, Vec::new())?;
    let (mut exclude, mut notes) = first.undetermined()?;
    loop {
        let fit = Fit { manoeuvres, config, warm };
        let mut r = fit.solve_without_beta_fallback(&mut exclude, &mut notes)?;
        match r.undetermined_scale() {
            Some((u, sigma)) => {
                notes.push(determined::scale_note(u, sigma));
                exclude.push(u);
            }
            None => {
                if let Some(note) = lag_beyond_manoeuvres(&r, manoeuvres) {
                    notes.push(note);
                    exclude.push(Unknown::AhrsLag);
                    continue;
                }
                notes.extend(gyro_shift_caveats(&r, config, manoeuvres));
                r.notes = notes;
                return Ok(r);
            }
        }
    }
}

/// Why the AHRS lag of `r` is not a result when its time constant exceeds a quarter of the
/// shortest manoeuvre (`None` otherwise, or without a lag): a first-order lag settles in about
/// four time constants, so in a shorter manoeuvre its response never shows apart from a slow
/// drift, which the biases and initial states fit as well. The check is then redone without
/// it. (A 0.9-s record read 1.7 ± 0.6 s, "converged".)
fn lag_beyond_manoeuvres(r: &CompatResult, manoeuvres: &[&[AirDataSample]]) -> Option<String> {
    let (tau, sigma) = r.get(Unknown::AhrsLag)?;
    let shortest =
        manoeuvres.iter().map(|m| m[m.len() - 1].t_s - m[0].t_s).fold(f64::INFINITY, f64::min);
    (tau > shortest / 4.0).then(|| {
        format!(
            "AHRS lag not estimated: its time constant came out {tau:.3} ± {sigma:.3} s, more than a quarter of the shortest manoeuvre ({shortest:.2} s), which cannot show a lag settle (about four time constants) apart from a drift; give manoeuvres of at least {:.1} s to estimate it",
            4.0 * tau.min(LAG_PLAUSIBLE_MAX_S)
        )
    })
}

/// The longest AHRS time constant the advice asks manoeuvres for, s: attitude filters of
/// flight-control AHRSs are below it.
const LAG_PLAUSIBLE_MAX_S: f64 = 0.5;

/// Sample interval above which the gyros' common shift was not always measured to 0.03 s
/// without a sideslip vane, s (module doc, "What decides the common AHRS shift").
const COARSE_FOR_GYRO_SHIFT_S: f64 = 0.015;

/// What the estimated gyro shifts or AHRS lag of `r` cannot be trusted for (module doc, "What
/// decides the common AHRS shift", "The AHRS's lag"): a record without a sideslip vane sampled
/// coarser than [`COARSE_FOR_GYRO_SHIFT_S`], and gyro scale factors left unestimated.
fn gyro_shift_caveats(
    r: &CompatResult,
    config: &CompatConfig,
    manoeuvres: &[&[AirDataSample]],
) -> Vec<String> {
    let shifted =
        r.unknowns.iter().any(|u| matches!(u, Unknown::TimeShift(c) if GYROS.contains(c)));
    let mut out = Vec::new();
    if r.unknowns.contains(&Unknown::AhrsLag) && !config.inertial_scale_factors {
        out.push("the AHRS lag was estimated without the gyros' scale factors: on a simulated 10 Hz record their 3–5 % made a 0.155-s lag read 0.182 s (0.168 s with them); estimate the inertial scale factors too".into());
    }
    if !shifted {
        return out;
    }
    let m = manoeuvres[0];
    let dt = (m[m.len() - 1].t_s - m[0].t_s) / (m.len() - 1) as f64;
    if !r.outputs.contains(&Channel::Beta) && dt > COARSE_FOR_GYRO_SHIFT_S {
        out.push(format!("the gyros' time shifts rest on the α vane alone at a {dt:.3} s sample interval: on simulated records at 10–20 Hz they came out between on time and 0.11 s late with σ 0.01–0.02 s, the α scale factor taking up the difference; check them against a record with a sideslip vane or a known vane delay before applying them"));
    }
    if !config.inertial_scale_factors {
        out.push("the gyros' time shifts were estimated without their scale factors: on a simulated 100 Hz record 3–5 % scale errors passed for 0.09 s of lag; estimate the inertial scale factors too".into());
    }
    out
}

/// A check's record, configuration and starting corrections ([`check_warm`]).
#[derive(Clone, Copy)]
struct Fit<'a> {
    manoeuvres: &'a [&'a [AirDataSample]],
    config: &'a CompatConfig,
    warm: &'a [(Unknown, f64)],
}

impl Fit<'_> {
    /// The fit without the unknowns in `exclude`. Without a `β` channel, when the record does not
    /// determine the initial side velocities (or the fit fails), it is redone with them and the
    /// `ay` bias and scale factor fixed, which `exclude` and `notes` then record.
    fn solve_without_beta_fallback(
        self,
        exclude: &mut Vec<Unknown>,
        notes: &mut Vec<String>,
    ) -> Result<CompatResult, EstimatorError> {
        let Fit { manoeuvres, config, warm } = self;
        let problem = |exclude: &[Unknown]| -> Result<Problem<'_>, EstimatorError> {
            let mut p = Problem::new(manoeuvres, config, exclude.to_vec())?;
            p.warm = warm.to_vec();
            Ok(p)
        };
        let full = problem(exclude)?;
        let has_beta = full.outputs.contains(&Channel::Beta);
        match full.solve(config) {
            Ok(r) if has_beta || (r.termination.is_converged() && lateral_determined(&r)) => Ok(r),
            Err(e) if has_beta => Err(e),
            _ => {
                let v0 = (0..manoeuvres.len()).map(|m| Unknown::Initial { manoeuvre: m, state: 1 });
                let ay = [Unknown::Bias(Channel::Ay), Unknown::Scale(Channel::Ay)];
                for u in ay.into_iter().chain(v0) {
                    if !exclude.contains(&u) {
                        exclude.push(u);
                    }
                }
                let note = SIDESLIP_PINNED_NOTE;
                if !notes.iter().any(|n| n == note) {
                    notes.push(note.into());
                }
                problem(exclude)?.solve(config)
            }
        }
    }
}

/// The note of a check without a sideslip channel whose record does not determine the initial
/// side velocity and the `ay` bias: both are fixed at 0, so its reconstructed sideslip is not
/// a measurement (the corrections do not use it).
pub const SIDESLIP_PINNED_NOTE: &str = "no sideslip channel and too little roll to determine the initial side velocity and the ay bias: both fixed at 0 (and the ay scale factor at 1), so the reconstructed sideslip carries their error";

/// The largest Gauss–Newton step, in Cramér–Rao σ, that counts as converged when no damped step
/// lowers the cost: the central-difference sensitivities leave steps of order 10⁻³–10⁻² σ at
/// the optimum (measured: 0.0032 σ on the synthetic record of the tests), far below anything
/// that moves an estimate.
const NO_DESCENT_STEP_SIGMA: f64 = 0.01;

/// Largest Cramér–Rao σ of a time shift, alone, that the record determines, s.
const MAX_SHIFT_SIGMA_S: f64 = 0.05;

/// Largest Cramér–Rao σ of an initial side velocity that still determines it, as a fraction of
/// the airspeed (1°·V of sideslip).
const V0_SIGMA_OF_V: f64 = 0.0175;

/// Whether a fit without a sideslip channel determined the initial side velocities (σ below
/// [`V0_SIGMA_OF_V`] of the first airspeed).
fn lateral_determined(r: &CompatResult) -> bool {
    r.unknowns.iter().zip(&r.sigma).zip(&r.reconstructed_v0()).all(|((u, s), v)| {
        !matches!(u, Unknown::Initial { state: 1, .. }) || *s < V0_SIGMA_OF_V * v
    })
}

impl CompatResult {
    /// Per unknown, the first reconstructed airspeed of its manoeuvre (0 for the others).
    fn reconstructed_v0(&self) -> Vec<f64> {
        self.unknowns
            .iter()
            .map(|u| match *u {
                Unknown::Initial { manoeuvre, .. } => {
                    self.reconstructed[manoeuvre].vt_mps.first().copied().unwrap_or(0.0)
                }
                _ => 0.0,
            })
            .collect()
    }
}

impl Problem<'_> {
    /// Per output, the white measurement-noise variance from the second differences of its
    /// samples, `mean((z₊ − 2z + z₋)²)/6` (exact for white noise on a signal that is linear
    /// over three samples), floored at 10⁻¹² of its mean square.
    fn noise_variances(&self) -> Vec<f64> {
        self.outputs
            .iter()
            .map(|&c| {
                let (mut sum, mut n, mut ms) = (0.0, 0usize, 0.0);
                for m in self.man {
                    let z: Vec<f64> = m.iter().map(|s| c.of(s).unwrap_or(0.0)).collect();
                    ms += z.iter().map(|v| v * v).sum::<f64>();
                    for w in z.windows(3) {
                        let d = wrap(w[2] - w[1]) - wrap(w[1] - w[0]);
                        sum += d * d;
                        n += 1;
                    }
                }
                let floor = 1e-12 * ms / self.n_samples() as f64;
                (sum / (6.0 * n.max(1) as f64)).max(floor).max(1e-300)
            })
            .collect()
    }
}

/// The gyros, whose time shifts [`CompatConfig::gyro_time_shifts`] estimates.
const GYROS: [Channel; 3] = [Channel::P, Channel::Q, Channel::R];

/// The record and the unknowns, set up.
struct Problem<'a> {
    man: &'a [&'a [AirDataSample]],
    outputs: Vec<Channel>,
    unknowns: Vec<Unknown>,
    /// Unknowns held at given values, not estimated (a held-out manoeuvre's corrections,
    /// `held_out`); the other unknowns left out hold their starting values.
    fixed: Vec<(Unknown, f64)>,
    /// Starting values of corrections (a related check's estimates, `held_out`): the fit
    /// then starts there alone, not from the several starts of [`Problem::starts`].
    warm: Vec<(Unknown, f64)>,
}

/// Smallest samples in a manoeuvre: the initial state and a few steps beyond it.
const MIN_SAMPLES: usize = 10;

impl<'a> Problem<'a> {
    /// The problem of `man` without the unknowns in `exclude` (held at their starting values:
    /// no error, the initial states measured).
    fn new(
        man: &'a [&'a [AirDataSample]],
        config: &CompatConfig,
        exclude: Vec<Unknown>,
    ) -> Result<Self, EstimatorError> {
        if man.is_empty() {
            return Err(EstimatorError::InvalidConfig {
                field: "manoeuvres",
                value: 0.0,
                reason: "at least one manoeuvre is needed",
            });
        }
        for (i, m) in man.iter().enumerate() {
            if m.len() < MIN_SAMPLES {
                return Err(EstimatorError::InvalidConfig {
                    field: "manoeuvre",
                    value: i as f64,
                    reason: "a manoeuvre needs at least 10 samples",
                });
            }
        }
        let samples = || man.iter().flat_map(|m| m.iter());
        let recorded = |c: Channel| samples().all(|s| c.of(s).is_some());
        let longitudinal = LATERAL.iter().all(|&c| samples().all(|s| c.of(s).is_none()));
        let needed = [Channel::Ax, Channel::Az, Channel::Q, Channel::Theta];
        let lateral = if longitudinal { &[][..] } else { &LATERAL[..] };
        for &c in needed.iter().chain(lateral) {
            if !recorded(c) {
                return Err(EstimatorError::InvalidConfig {
                    field: c.name(),
                    value: f64::NAN,
                    reason: "the compatibility check needs this channel in every sample (a longitudinal record: none of ay, p, r, phi)",
                });
            }
        }
        let outputs: Vec<Channel> = Channel::OUTPUTS
            .into_iter()
            .filter(|&c| recorded(c) && !(longitudinal && c == Channel::Psi))
            .collect();
        let mut unknowns = unknowns_of(&outputs, man.len(), config);
        let dropped = |u: &Unknown| exclude.contains(u) || (longitudinal && is_lateral(*u));
        unknowns.retain(|u| !dropped(u));
        Ok(Self { man, outputs, unknowns, fixed: Vec::new(), warm: Vec::new() })
    }
}

/// The lateral channels; a record with none of them is checked as longitudinal (`v, φ, ψ`
/// and the lateral rates and force zero).
const LATERAL: [Channel; 4] = [Channel::Ay, Channel::P, Channel::R, Channel::Phi];

/// Whether `u` belongs to the lateral motion.
fn is_lateral(u: Unknown) -> bool {
    match u {
        Unknown::Bias(c) | Unknown::Scale(c) | Unknown::TimeShift(c) => {
            matches!(
                c,
                Channel::Ay | Channel::P | Channel::R | Channel::Beta | Channel::Phi | Channel::Psi
            )
        }
        Unknown::Initial { state, .. } => matches!(state, 1 | 3 | 5),
        Unknown::AhrsLag => false,
    }
}

/// The unknowns in order: inertial biases, inertial scale factors on request, air-data biases
/// and scale factors, time shifts, initial states (without `ψ₀` without a heading).
fn unknowns_of(outputs: &[Channel], n_man: usize, config: &CompatConfig) -> Vec<Unknown> {
    let heading = outputs.contains(&Channel::Psi);
    let beta = outputs.contains(&Channel::Beta);
    let inertial = Channel::INERTIAL.into_iter();
    let mut u: Vec<Unknown> = inertial.clone().map(Unknown::Bias).collect();
    if config.inertial_scale_factors {
        u.extend(inertial.map(Unknown::Scale));
    }
    u.push(Unknown::Bias(Channel::Vt));
    u.extend([Unknown::Scale(Channel::Alpha), Unknown::Bias(Channel::Alpha)]);
    if beta {
        u.extend([Unknown::Scale(Channel::Beta), Unknown::Bias(Channel::Beta)]);
    }
    if config.ahrs_lag {
        // It replaces the gyros' shifts (module doc, "The AHRS's lag").
        u.push(Unknown::AhrsLag);
    } else if config.gyro_time_shifts {
        // Against the accelerometers, the time reference (module doc, "Time shifts").
        u.extend(GYROS.map(Unknown::TimeShift));
    }
    if config.time_shifts {
        // Not the airspeed's: it varies slowly, so its shift would absorb a changing wind and
        // the slow model errors (the HFB-320 record: −2.7 s) instead of measuring a lag.
        u.extend(outputs.iter().filter(|&&c| c != Channel::Vt).map(|&c| Unknown::TimeShift(c)));
    }
    for m in 0..n_man {
        for state in 0..6 {
            let fixed = state == 5 && !heading;
            if !fixed {
                u.push(Unknown::Initial { manoeuvre: m, state });
            }
        }
    }
    u
}

/// The unknowns decoded: per channel (index `Channel as usize`) bias, scale-factor error and
/// time shift, the AHRS's time constant (s, 0 without one), and each manoeuvre's initial state.
struct Corrections {
    bias: [f64; 12],
    scale: [f64; 12],
    shift: [f64; 12],
    lag: f64,
    x0: Vec<[f64; 6]>,
}

/// The kinematic state rates (module doc) at state `x` under corrected specific force `a`
/// (m/s²) and rates `w` (rad/s).
fn kinematics(x: &[f64; 6], a: [f64; 3], w: [f64; 3]) -> [f64; 6] {
    let (phi, theta) = (SinCos::of(x[3]), SinCos::of(x[4]));
    let g = rb::gravity_body(G0_MPS2, phi, theta);
    let vd = rb::body_acceleration([x[0], x[1], x[2]], w, g, a);
    let e = rb::euler_rates(w, phi, theta);
    [vd[0], vd[1], vd[2], e[0], e[1], e[2]]
}

/// `V, α, β, φ, θ, ψ` of state `x`.
fn air_data(x: &[f64; 6]) -> [f64; 6] {
    let v = libm::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    [v, libm::atan2(x[2], x[0]), libm::asin(x[1] / v), x[3], x[4], x[5]]
}

/// An angle (or angle difference) wrapped into (−π, π] (heading residuals and interpolation).
pub fn wrap(d: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    let r = libm::remainder(d, TAU);
    if r <= -PI { r + TAU } else { r }
}

/// The first-order lag `τ ẏ + y = u` (unit gain) over one step of `h` s from output `y0`,
/// for an input linear from `u0` to `u1` over the step: exact,
/// `y1 = a y0 + (1 − a) u0 + (u1 − u0)(1 − τ(1 − a)/h)`, `a = e^{−h/τ}`. The AHRS's filter of
/// the check (module doc, "The AHRS's lag") and the one `replay --compat` passes the other
/// channels through. `h > 0` and `tau > 0` (s); `tau` → 0 gives `u1`.
pub fn lag_step(y0: f64, u0: f64, u1: f64, h: f64, tau: f64) -> f64 {
    let one_minus_a = -(-h / tau).exp_m1();
    (1.0 - one_minus_a) * y0 + one_minus_a * u0 + (u1 - u0) * (1.0 - tau / h * one_minus_a)
}

/// Value of series `y` (one per sample at the increasing times `t`, s) at time `at`, linearly
/// interpolated, held at the ends. `t` and `y` must be of one, non-zero length.
pub fn interpolate(t: &[f64], y: &[f64], at: f64) -> f64 {
    let k = t.partition_point(|&ti| ti <= at);
    if k == 0 {
        return y[0];
    }
    if k >= t.len() {
        return y[t.len() - 1];
    }
    let (t0, t1) = (t[k - 1], t[k]);
    let f = (at - t0) / (t1 - t0);
    y[k - 1] + f * (y[k] - y[k - 1])
}

impl Problem<'_> {
    fn ny(&self) -> usize {
        self.outputs.len()
    }

    fn n_samples(&self) -> usize {
        self.man.iter().map(|m| m.len()).sum()
    }

    /// Starting values: no errors (or the warm ones, [`Problem::warm`]), each initial state
    /// from its manoeuvre's first sample.
    fn start(&self) -> Vec<f64> {
        let warm = |u: &Unknown| self.warm.iter().find(|w| w.0 == *u).map_or(0.0, |w| w.1);
        self.unknowns
            .iter()
            .map(|u| match *u {
                Unknown::Initial { manoeuvre, state } => {
                    measured_state(&self.man[manoeuvre][0])[state]
                }
                _ => warm(u),
            })
            .collect()
    }

    fn decode(&self, beta: &[f64]) -> Corrections {
        let mut c = Corrections {
            bias: [0.0; 12],
            scale: [0.0; 12],
            shift: [0.0; 12],
            lag: 0.0,
            x0: self.man.iter().map(|m| measured_state(&m[0])).collect(),
        };
        let fixed = self.fixed.iter().map(|(u, v)| (u, v));
        for (u, &b) in fixed.chain(self.unknowns.iter().zip(beta)) {
            match *u {
                Unknown::Bias(ch) => c.bias[ch as usize] = b,
                Unknown::Scale(ch) => c.scale[ch as usize] = b,
                Unknown::TimeShift(ch) => c.shift[ch as usize] = b,
                Unknown::AhrsLag => c.lag = b,
                Unknown::Initial { manoeuvre, state } => c.x0[manoeuvre][state] = b,
            }
        }
        c
    }

    /// The states of manoeuvre `m` at its sample times (RK4, the inputs of [`Inputs`]: linear
    /// between samples, each gyro read at its time shift, the accelerometers through the AHRS's
    /// filter when it has one), and the air data and attitudes each sample's outputs are
    /// formed from ([`Problem::sensed`]).
    fn states(&self, c: &Corrections, m: usize) -> Result<Vec<[f64; 6]>, EstimatorError> {
        let man = self.man[m];
        let inputs = Inputs::of(c, man);
        let mut x = c.x0[m];
        let mut out = Vec::with_capacity(man.len());
        for k in 0..man.len() {
            let v2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
            if !(v2 > 0.0 && x.iter().all(|v| v.is_finite())) {
                return Err(EstimatorError::Numerical {
                    what: "compatibility check: the kinematics left the physical domain (V = 0 or non-finite)",
                    t_s: man[k].t_s,
                });
            }
            out.push(Self::sensed(&x, c.lag, inputs.at_samples[k]));
            if k + 1 == man.len() {
                break;
            }
            let u = [inputs.at_samples[k], inputs.at_midpoints[k], inputs.at_samples[k + 1]];
            x = rk4(&x, man[k + 1].t_s - man[k].t_s, u);
        }
        Ok(out)
    }

    /// What the sensors see of the integrated state `x` under the inputs `u` at one sample:
    /// `V, α, β, φ, θ, ψ`. Without an AHRS lag (`tau` 0) the air data and attitudes of `x`.
    /// With one, `x` is the lagged state `x_L` (module doc, "The AHRS's lag"): the attitudes
    /// are its own, the air data those of the unlagged `x_L + τ ẋ_L`, `ẋ_L` from the state
    /// equation.
    fn sensed(x: &[f64; 6], tau: f64, u: ([f64; 3], [f64; 3])) -> [f64; 6] {
        if tau == 0.0 {
            return air_data(x);
        }
        let d = kinematics(x, u.0, u.1);
        let unlagged: [f64; 6] = core::array::from_fn(|i| x[i] + tau * d[i]);
        let a = air_data(&unlagged);
        [a[0], a[1], a[2], x[3], x[4], x[5]]
    }

    /// The model outputs (module doc) of every sample, `N × ny` row-major, manoeuvres
    /// concatenated.
    fn simulate(&self, beta: &[f64], y: &mut Vec<f64>) -> Result<(), EstimatorError> {
        let c = self.decode(beta);
        y.clear();
        for m in 0..self.man.len() {
            self.simulate_manoeuvre(&c, m, y)?;
        }
        Ok(())
    }

    /// The model outputs of manoeuvre `m` under the corrections `c`, appended to `y` (`N_m ×
    /// ny` row-major).
    fn simulate_manoeuvre(
        &self,
        c: &Corrections,
        m: usize,
        y: &mut Vec<f64>,
    ) -> Result<(), EstimatorError> {
        let raw = self.states(c, m)?;
        self.outputs_of(c, m, &raw, y);
        Ok(())
    }

    /// The model outputs of manoeuvre `m` under the corrections `c` from its sensed states
    /// `raw` ([`Problem::states`] under `c`, or under any corrections that differ from `c` only
    /// in the outputs' own: those move no state), appended to `y`.
    fn outputs_of(&self, c: &Corrections, m: usize, raw: &[[f64; 6]], y: &mut Vec<f64>) {
        let t: Vec<f64> = self.man[m].iter().map(|s| s.t_s).collect();
        let series: Vec<Vec<f64>> = (0..6).map(|j| raw.iter().map(|r| r[j]).collect()).collect();
        for &tk in &t {
            for &ch in &self.outputs {
                let j = output_index(ch);
                let i = ch as usize;
                let h = interpolate(&t, &series[j], tk - c.shift[i]);
                y.push((1.0 + c.scale[i]) * h + c.bias[i]);
            }
        }
    }

    /// Residuals `z − y` (heading wrapped) into `e`; returns the per-output variances.
    fn residuals(&self, y: &[f64], e: &mut Vec<f64>) -> Vec<f64> {
        let ny = self.ny();
        e.clear();
        let mut r = vec![0.0; ny];
        for (k, s) in self.man.iter().flat_map(|m| m.iter()).enumerate() {
            for (j, &ch) in self.outputs.iter().enumerate() {
                let d = ch.of(s).unwrap_or(0.0) - y[k * ny + j];
                let d = if ch == Channel::Psi { wrap(d) } else { d };
                e.push(d);
                r[j] += d * d;
            }
        }
        let n = self.n_samples() as f64;
        r.iter().map(|v| (v / n).max(1e-300)).collect()
    }
}

/// Index of an output channel in [`air_data`]'s order.
fn output_index(c: Channel) -> usize {
    Channel::OUTPUTS.iter().position(|&o| o == c).unwrap_or(0)
}

/// The kinematic state `[u v w φ θ ψ]` the sample measures (`β`, `ψ` 0 when not recorded).
fn measured_state(s: &AirDataSample) -> [f64; 6] {
    let (a, b) = (s.alpha_rad, s.beta_rad.unwrap_or(0.0));
    let uvw = rb::body_velocity(s.vt_mps, SinCos::of(a), SinCos::of(b));
    [
        uvw[0],
        uvw[1],
        uvw[2],
        s.phi_rad.unwrap_or(0.0),
        s.theta_rad.unwrap_or(0.0),
        s.psi_rad.unwrap_or(0.0),
    ]
}

/// One RK4 step of [`kinematics`] over `h` with the inputs at the start, middle and end.
fn rk4(x: &[f64; 6], h: f64, u: [([f64; 3], [f64; 3]); 3]) -> [f64; 6] {
    let add = |x: &[f64; 6], d: &[f64; 6], f: f64| core::array::from_fn(|i| x[i] + f * d[i]);
    let k1 = kinematics(x, u[0].0, u[0].1);
    let k2 = kinematics(&add(x, &k1, 0.5 * h), u[1].0, u[1].1);
    let k3 = kinematics(&add(x, &k2, 0.5 * h), u[1].0, u[1].1);
    let k4 = kinematics(&add(x, &k3, h), u[2].0, u[2].1);
    core::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// The perturbation of unknown `u` for its central difference (a small fraction of its
/// natural size, well above rounding).
fn delta(u: Unknown) -> f64 {
    match u {
        Unknown::Bias(Channel::Ax | Channel::Ay | Channel::Az | Channel::Vt) => 1e-3,
        Unknown::Bias(_) => 1e-5,
        Unknown::Scale(_) => 1e-4,
        Unknown::TimeShift(_) | Unknown::AhrsLag => 1e-3,
        Unknown::Initial { state, .. } if state < 3 => 1e-3,
        Unknown::Initial { .. } => 1e-5,
    }
}

/// The normal equations at `beta`: `(M, g)` with `M = Σ Sᵀ W S`, `g = Σ Sᵀ W e`, `W = R⁻¹`,
/// `S` by central differences, formed by manoeuvre blocks (`blocks`).
fn normal_equations(
    p: &Problem<'_>,
    beta: &[f64],
    e: &[f64],
    r: &[f64],
) -> Result<(DMatrix<f64>, DVector<f64>), EstimatorError> {
    if beta.len() <= DENSE_MAX_UNKNOWNS {
        return Ok(information(&sensitivities(p, beta)?, e, r));
    }
    Ok(Sensitivities::of(p, beta)?.information(e, r))
}

/// Most unknowns whose normal equations, solves and σ are formed densely, as they always were
/// (a check of up to about eight manoeuvres): at the optimum a Gauss–Newton step is rounding,
/// and whether a damped one lowers `det R` there is decided by the last bits; the blocks sum
/// in another order, which turned a simulated record's converged check into one that ended
/// without a descent a hair from the same estimates. Beyond this the blocks' linear cost
/// matters more than those bits.
const DENSE_MAX_UNKNOWNS: usize = 64;

/// `(M, g)` of dense sensitivities `s` (`N·ny × nβ`), residuals `e` and output variances `r`:
/// what the blocks must equal.
fn information(s: &DMatrix<f64>, e: &[f64], r: &[f64]) -> (DMatrix<f64>, DVector<f64>) {
    let ny = r.len();
    let sw = DMatrix::from_fn(s.nrows(), s.ncols(), |row, i| s[(row, i)] / r[row % ny]);
    (sw.transpose() * s, sw.transpose() * DVector::from_column_slice(e))
}

/// `S = ∂y/∂β` at `beta` by central differences, `N·ny × nβ`, dense: what the blocks hold.
fn sensitivities(p: &Problem<'_>, beta: &[f64]) -> Result<DMatrix<f64>, EstimatorError> {
    Ok(Sensitivities::of(p, beta)?.dense())
}

/// `∂y/∂β_i` at `beta` by a central difference of [`delta`], `N·ny` row-major.
fn sensitivity(p: &Problem<'_>, beta: &[f64], i: usize) -> Result<Vec<f64>, EstimatorError> {
    if let Unknown::Initial { manoeuvre, .. } = p.unknowns[i] {
        let own = manoeuvre_sensitivity(p, beta, i, manoeuvre)?;
        let before = p.man[..manoeuvre].iter().map(|s| s.len()).sum::<usize>() * p.ny();
        let mut column = vec![0.0; p.n_samples() * p.ny()];
        column[before..before + own.len()].copy_from_slice(&own);
        return Ok(column);
    }
    let d = delta(p.unknowns[i]);
    let (mut yp, mut ym) = (Vec::new(), Vec::new());
    let mut trial = beta.to_vec();
    trial[i] = beta[i] + d;
    p.simulate(&trial, &mut yp)?;
    trial[i] = beta[i] - d;
    p.simulate(&trial, &mut ym)?;
    Ok(yp.iter().zip(&ym).map(|(a, b)| (a - b) / (2.0 * d)).collect())
}

/// Whether `u` is an output's own correction (its bias, scale factor or time shift): it enters
/// the outputs' formation alone, not the kinematics.
fn moves_no_state(u: Unknown) -> bool {
    matches!(u, Unknown::Bias(c) | Unknown::Scale(c) | Unknown::TimeShift(c) if Channel::OUTPUTS.contains(&c))
}

/// [`sensitivity`] of an output's own correction `beta[i]` ([`moves_no_state`]) from the
/// sensed states `sensed` of every manoeuvre at `beta`: the outputs are formed anew at
/// `beta[i] ± δ` from the same states, the same numbers as integrating the kinematics again for
/// each, at a small part of the cost (seven of a check's dozen global unknowns are of this
/// kind).
fn output_sensitivity(
    p: &Problem<'_>,
    beta: &[f64],
    i: usize,
    sensed: &[Vec<[f64; 6]>],
) -> Vec<f64> {
    let d = delta(p.unknowns[i]);
    let (mut yp, mut ym) = (Vec::new(), Vec::new());
    let mut trial = beta.to_vec();
    trial[i] = beta[i] + d;
    let plus = p.decode(&trial);
    trial[i] = beta[i] - d;
    let minus = p.decode(&trial);
    for (m, raw) in sensed.iter().enumerate() {
        p.outputs_of(&plus, m, raw, &mut yp);
        p.outputs_of(&minus, m, raw, &mut ym);
    }
    yp.iter().zip(&ym).map(|(a, b)| (a - b) / (2.0 * d)).collect()
}

/// The rows of manoeuvre `m` of [`sensitivity`] of its initial state `beta[i]`, which moves
/// that manoeuvre's outputs alone: only it is simulated (every other row is the 0 that the
/// central difference of their unchanged outputs gives exactly). Simulating every manoeuvre
/// for each of the six initial states of each made a joint check of `M` manoeuvres cost `M`
/// times a whole-record pass per state, quadratic in the windows of a flight.
fn manoeuvre_sensitivity(
    p: &Problem<'_>,
    beta: &[f64],
    i: usize,
    m: usize,
) -> Result<Vec<f64>, EstimatorError> {
    let d = delta(p.unknowns[i]);
    let (mut yp, mut ym) = (Vec::new(), Vec::new());
    let mut trial = beta.to_vec();
    trial[i] = beta[i] + d;
    p.simulate_manoeuvre(&p.decode(&trial), m, &mut yp)?;
    trial[i] = beta[i] - d;
    p.simulate_manoeuvre(&p.decode(&trial), m, &mut ym)?;
    Ok(yp.iter().zip(&ym).map(|(a, b)| (a - b) / (2.0 * d)).collect())
}

/// `(M + λ diag M)⁻¹ g`, Jacobi-scaled (Cholesky by the blocks of `part`, [`Schur`]); `None`
/// when not positive definite.
fn damped(
    m: &DMatrix<f64>,
    g: &DVector<f64>,
    lambda: f64,
    part: &Partition,
) -> Option<DVector<f64>> {
    let n = m.nrows();
    let d: Vec<f64> = (0..n).map(|i| 1.0 / m[(i, i)].sqrt()).collect();
    if d.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let ms =
        DMatrix::from_fn(n, n, |i, j| m[(i, j)] * d[i] * d[j] + if i == j { lambda } else { 0.0 });
    let gs = DVector::from_fn(n, |i, _| g[i] * d[i]);
    let sol = if n <= DENSE_MAX_UNKNOWNS {
        ms.cholesky()?.solve(&gs)
    } else {
        Schur::of(&ms, part)?.solve(&gs)
    };
    Some(DVector::from_fn(n, |i, _| sol[i] * d[i]))
}

fn ln_det(r: &[f64]) -> f64 {
    r.iter().map(|v| v.ln()).sum()
}

/// What one iteration did: the accepted unknowns, their residuals and variances, the step in
/// σ; `None` when no damping lowered the cost.
type Accepted = Option<(Vec<f64>, Vec<f64>, Vec<f64>, f64)>;

impl Problem<'_> {
    /// Gauss–Newton iterations from `beta` (module doc, "Estimation"); `beta` is left at the
    /// last accepted iterate.
    fn iterate(
        &self,
        beta: &mut Vec<f64>,
        config: &CompatConfig,
    ) -> Result<(Termination, usize), EstimatorError> {
        let (mut y, mut e) = (Vec::new(), Vec::new());
        self.simulate(beta, &mut y)?;
        let mut r = self.residuals(&y, &mut e);
        let mut lambda = 0.0;
        let part = Partition::of(&self.unknowns, self.man.len());
        // Relative change of det R over the last accepted iteration (None before one).
        let mut last_rel = None;
        for iteration in 1..=config.max_iterations {
            let (m, g) = normal_equations(self, beta, &e, &r)?;
            if iteration == 1 && damped(&m, &g, 0.0, &part).is_none() {
                return Err(EstimatorError::Numerical {
                    what: "compatibility check: the information matrix is singular at the start (an unknown the record does not determine)",
                    t_s: self.man[0][0].t_s,
                });
            }
            let descent = self.descend(beta, (&m, &g, &part), &r, &mut lambda);
            let Some((b, e_new, r_new, step_sigma)) = descent else {
                // At the optimum the central-difference sensitivities leave a step no damping
                // can turn into a descent (the cost is flat to its rounding there).
                let floor = config.step_tolerance_sigma.max(NO_DESCENT_STEP_SIGMA);
                let tiny =
                    damped(&m, &g, 0.0, &part).is_some_and(|st| max_sigma(&m, &st, &part) < floor);
                let why = NotConverged::NoDescent;
                let t = Termination::after(tiny, last_rel, why, config.cost_tolerance);
                return Ok((t, iteration - 1));
            };
            let rel = (ln_det(&r_new) - ln_det(&r)).exp_m1().abs();
            last_rel = Some(rel);
            (*beta, e, r) = (b, e_new, r_new);
            if rel < config.cost_tolerance && step_sigma < config.step_tolerance_sigma {
                return Ok((Termination::Converged, iteration));
            }
        }
        let why = NotConverged::MaxIterations;
        Ok((Termination::after(false, last_rel, why, config.cost_tolerance), config.max_iterations))
    }

    /// A damped step from `beta` that lowers `ln det R` (λ raised ×10 from 10⁻³ up to 10¹⁰
    /// until one does; lowered ×10 after an accepted one); `(m, g, part)` the normal equations
    /// and the partition of the unknowns.
    fn descend(
        &self,
        beta: &[f64],
        (m, g, part): (&DMatrix<f64>, &DVector<f64>, &Partition),
        r: &[f64],
        lambda: &mut f64,
    ) -> Accepted {
        let (mut y, mut e) = (Vec::new(), Vec::new());
        loop {
            if let Some(step) = damped(m, g, *lambda, part) {
                let trial: Vec<f64> = beta.iter().zip(step.iter()).map(|(b, d)| b + d).collect();
                if self.simulate(&trial, &mut y).is_ok() {
                    let r_try = self.residuals(&y, &mut e);
                    if ln_det(&r_try) < ln_det(r) {
                        *lambda = if *lambda < 1e-6 { 0.0 } else { *lambda / 10.0 };
                        return Some((trial, e, r_try, max_sigma(m, &step, part)));
                    }
                }
            }
            *lambda = if *lambda == 0.0 { 1e-3 } else { *lambda * 10.0 };
            if *lambda > 1e10 {
                return None;
            }
        }
    }

    /// The result at `beta`: Cramér–Rao σ, residual statistics, the reconstructed air data.
    fn finish(
        &self,
        beta: Vec<f64>,
        termination: Termination,
        iterations: usize,
    ) -> Result<CompatResult, EstimatorError> {
        let (mut y, mut e) = (Vec::new(), Vec::new());
        self.simulate(&beta, &mut y)?;
        let r = self.residuals(&y, &mut e);
        let s = Sensitivities::of(self, &beta)?;
        let (m, _) = if beta.len() <= DENSE_MAX_UNKNOWNS {
            information(&s.dense(), &e, &r)
        } else {
            s.information(&e, &r)
        };
        let n = m.nrows();
        let part = Partition::of(&self.unknowns, self.man.len());
        let inv = if n <= DENSE_MAX_UNKNOWNS {
            m.clone().cholesky().map(|c| c.inverse())
        } else {
            Schur::of(&m, &part).map(|c| c.inverse())
        };
        let inv = inv.ok_or(EstimatorError::Numerical {
            what: "compatibility check: the information matrix is singular at the estimate, so the record does not determine every bias, scale factor, time shift and initial state asked for (too short, or too little motion in some axis); give longer or more varied manoeuvres, or ask for fewer unknowns (--no-time-shifts, no --inertial-scale-factors)",
            t_s: self.man[0][0].t_s,
        })?;
        // The residuals of a real record are coloured (turbulence, model error, sample-and-hold):
        // the spectral sandwich of output error (crate::coloured::batch, "Spectral form"), by
        // the manoeuvres' blocks (`coloured`).
        let w: Vec<f64> = r.iter().map(|v| 1.0 / v).collect();
        let coloured = if n <= DENSE_MAX_UNKNOWNS {
            // Column-major storage of Sᵀ is S row-major, the layout the sandwich takes.
            let s_rows = s.dense().transpose();
            let lengths: Vec<usize> = self.man.iter().map(|m| m.len()).collect();
            crate::coloured::batch::spectral(s_rows.as_slice(), &e, &w, &lengths, &inv).covariance
        } else {
            coloured::spectral(&s, &e, &w, &inv)
        };
        let sigma_coloured = coloured.map(|c| (0..n).map(|i| c[(i, i)].max(0.0).sqrt()).collect());
        let ny = self.ny();
        let ns = self.n_samples() as f64;
        let residual_mean =
            (0..ny).map(|j| e.iter().skip(j).step_by(ny).sum::<f64>() / ns).collect();
        let c = self.decode(&beta);
        let reconstructed =
            (0..self.man.len()).map(|k| self.reconstruct(&c, k)).collect::<Result<Vec<_>, _>>()?;
        Ok(CompatResult {
            unknowns: self.unknowns.clone(),
            sigma: (0..n).map(|i| inv[(i, i)].max(0.0).sqrt()).collect(),
            sigma_coloured,
            values: beta,
            outputs: self.outputs.clone(),
            residual_rms: r.iter().map(|v| v.sqrt()).collect(),
            residual_mean,
            predicted: y,
            residuals: e,
            reconstructed,
            termination,
            iterations,
            notes: Vec::new(),
        })
    }

    fn reconstruct(&self, c: &Corrections, m: usize) -> Result<Reconstructed, EstimatorError> {
        let sensed = self.states(c, m)?;
        let mut out = Reconstructed::default();
        for (a, s) in sensed.iter().zip(self.man[m]) {
            out.t_s.push(s.t_s);
            out.vt_mps.push(a[0]);
            out.alpha_rad.push(a[1]);
            out.beta_rad.push(a[2]);
        }
        Ok(out)
    }
}

/// The largest `|step_i| / sqrt((M⁻¹)_ii)` (∞ when `M` is singular); only the diagonal of
/// `M⁻¹` is formed, by the blocks of `part` ([`Schur::inverse_diagonal`]).
fn max_sigma(m: &DMatrix<f64>, step: &DVector<f64>, part: &Partition) -> f64 {
    if m.nrows() <= DENSE_MAX_UNKNOWNS {
        return match m.clone().cholesky() {
            Some(c) => {
                let inv = c.inverse();
                (0..step.len()).map(|i| step[i].abs() / inv[(i, i)].sqrt()).fold(0.0, f64::max)
            }
            None => f64::INFINITY,
        };
    }
    match Schur::of(m, part) {
        Some(c) => {
            let inv = c.inverse_diagonal();
            (0..step.len()).map(|i| step[i].abs() / inv[i].sqrt()).fold(0.0, f64::max)
        }
        None => f64::INFINITY,
    }
}

#[cfg(test)]
mod tests;
