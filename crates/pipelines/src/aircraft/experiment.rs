//! The estimation experiment of thesis Figure 3.2, for any increments and any estimator.
//!
//! Per sample `k` (interval `dt`, RK4 with the pilot inputs evaluated at the stage times):
//! 1. the pilot command (trim + inputs) and the wind at `t_k`;
//! 2. the **reference aircraft** (the F-16 plus the true increments of the scenario, the wind)
//!    gives `x_ref`, `ẋ_ref` and its outputs;
//! 3. the **sensor models** turn them into what the estimators see:
//!    - two-aircraft estimators: the measured state and derivative `z_m`, `ż_m`
//!      ([`super::sensors`]); each updates from `(z_est, z_m, ż_m, u)`, where `z_est` is the
//!      state of its own **estimated aircraft** ([`super::two_aircraft`]);
//!    - sample-driven estimators: ONE [`AirDataSample`] per step ([`super::air_data`]: SI units,
//!      noise, differentiated angular accelerations, all channels delayed by the
//!      differentiator's lag), passed to each `Box<dyn Estimator>`;
//! 4. both aircraft advance one RK4 step, the pilot's controls evaluated at the stage times
//!    (they are continuous functions of time, as a real surface's position is;
//!    [`aeroident_models::integrate::rk4_step_varying`]), the wind of `t_k` held over the step.
//!    Holding the controls of `t_k` instead (a staircase) flies the recorded surface positions
//!    `dt/2` late on average, and the batch fits, which interpolate the recorded inputs
//!    linearly between samples, read that lag as smaller damping and control derivatives
//!    (docs/uncertainty.md, "Bias: the staircase inputs").
//!
//! After the flight, each batch estimator (`kind = "oe"`, [`super::batch`]) fits the samples
//! it recorded in step 3 on the window after the last change of the truth; its estimate is
//! logged at the last sample only.
//!
//! Truth: the two-aircraft estimators estimate **increments** (their truth is the scenario's
//! increment); the sample-driven estimators estimate the reference aircraft's **total local
//! derivatives** (their truth is [`super::truth::local_derivatives`] at the trim point, before
//! and after each sudden change of an increment).

use std::time::Instant;

use aeroident_estimators::Estimator;
use aeroident_estimators::sample::AirDataSample;
use aeroident_estimators::vocabulary::{ModelStructure, Param};
use aeroident_models::f16::{self, AeroIncrements, F16, F16Controls, F16State, IncrementReference};
use aeroident_models::integrate::rk4_step_varying;
use aeroident_models::trim::{F16Trim, TrimCondition, trim};
use aeroident_signals::{Input, InputSignal, WindField, config::build_wind};

use super::air_data::AirDataSampler;
use super::batch::{BatchFit, fit_window};
use super::increments::increment_matrix;
use super::scenario::{AerodynamicsSpec, Channel, EstimatorSpec, EstimatorWind, Scenario};
use super::sensors::SensorNoise;
use super::truth::{LocalDerivatives, local_derivatives};
pub use super::two_aircraft::PublishedDiagnostics;
use super::two_aircraft::{self, TwoAircraft};
use aeroident_physics::units::M_PER_FT;

mod stepping;

/// Errors of an experiment run.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// Trim failed.
    #[error("trim at {vt_fps} ft/s, {alt_ft} ft: {source}")]
    Trim {
        /// Airspeed, ft/s.
        vt_fps: f64,
        /// Altitude, ft.
        alt_ft: f64,
        /// Cause.
        source: aeroident_models::ModelError,
    },
    /// Building an input, noise or estimator failed.
    #[error("setting up `{what}`: {reason}")]
    Setup {
        /// What was being built.
        what: String,
        /// Why it failed.
        reason: String,
    },
    /// The reference aircraft left the model's domain.
    #[error("reference aircraft at t = {t_s} s: {source}")]
    Reference {
        /// Time, s.
        t_s: f64,
        /// Cause.
        source: aeroident_models::ModelError,
    },
}

/// Logged sliding-state vector: `[vt_fps, alpha_rad, beta_rad, p_rad_s, q_rad_s, r_rad_s]`.
pub type TrackedStates = [f64; 6];

/// Names of [`TrackedStates`] (CSV suffixes).
pub const TRACKED_NAMES: [&str; 6] =
    ["vt_fps", "alpha_rad", "beta_rad", "p_rad_s", "q_rad_s", "r_rad_s"];

/// The sliding states `[V_T, α, β, p, q, r]` of a full F-16 state.
pub fn tracked(x: &F16State) -> TrackedStates {
    [x[f16::VT], x[f16::ALPHA], x[f16::BETA], x[f16::P], x[f16::Q], x[f16::R]]
}

/// What an estimator's numbers stand for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// An increment over the F-16 (two-aircraft estimators): truth = the scenario's increment.
    Increment,
    /// The reference aircraft's total local derivative (sample-driven estimators).
    Derivative,
}

impl Quantity {
    /// `increment` or `derivative` (the string in summaries).
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Increment => "increment",
            Quantity::Derivative => "derivative",
        }
    }
}

/// One parameter's history in one channel.
#[derive(Debug, Clone)]
pub struct ParamLog {
    /// The parameter.
    pub param: Param,
    /// Estimate per sample (`None` while not identified, or after a divergence).
    pub estimate: Vec<Option<f64>>,
    /// Standard error per sample, where the method gives one.
    pub sigma: Vec<Option<f64>>,
    /// Truth per sample (`None` where no single true value exists).
    pub truth: Vec<Option<f64>>,
    /// Truth in each of [`RunOutput::epochs`] (known even for an epoch after the run's end).
    pub truth_epochs: Vec<Option<f64>>,
}

/// What one estimator channel logged.
#[derive(Debug, Clone)]
pub struct ChannelLog {
    /// Label (`published-implicit`, `corrected`, `rls` …).
    pub label: String,
    /// Kind: `published`, `corrected`, `mr-gradient` or the sample-driven method (`rls` …).
    pub kind: &'static str,
    /// Increments (two-aircraft) or total derivatives (sample-driven).
    pub quantity: Quantity,
    /// Per parameter, in the channel's order.
    pub params: Vec<ParamLog>,
    /// Estimated aircraft's full state per sample (two-aircraft channels; empty otherwise).
    pub states: Vec<F16State>,
    /// Published groups only: per sample, one entry per group (moments, then each force).
    pub diagnostics: Vec<Vec<PublishedDiagnostics>>,
    /// First estimator or estimated-aircraft error (or divergence), with its time; estimates
    /// are held from then on (a diverged estimator's are dropped), never NaN.
    pub failure: Option<(f64, String)>,
    /// Solver counters or the sample estimator's final status, human-readable.
    pub stats: String,
    /// Sample-driven estimators: the final [`Status`](aeroident_estimators::Status) name.
    pub status: Option<&'static str>,
    /// Sample-driven estimators: the final mean normalised innovation squared
    /// ([`aeroident_estimators::Estimator::nis`]; ≈ 1 for a consistent filter), `None` for
    /// methods without innovations.
    pub nis: Option<f64>,
    /// Sample-driven estimators: what the estimator did to itself
    /// ([`aeroident_estimators::Estimator::events`]: restarts, re-anchored outputs, detected
    /// changes); empty for the others.
    pub events: aeroident_io::replay_output::EventsSummary,
    /// Batch estimators ([`super::batch`]): how the post-flight fit went (`None` for the
    /// real-time estimators, and for a batch fit that failed before iterating).
    pub batch: Option<BatchFit>,
}

impl ChannelLog {
    /// Whether the channel is a batch (post-flight) estimator: its estimate exists only at the
    /// end, so it has no time-history metrics.
    pub fn is_batch(&self) -> bool {
        crate::estimators::is_batch_kind(self.kind)
    }
}

impl ChannelLog {
    /// The log of parameter `p`, if the channel estimates it.
    pub fn param(&self, p: Param) -> Option<&ParamLog> {
        self.params.iter().find(|l| l.param == p)
    }
}

/// One true increment with its schedule, resolved (a `step_to_fraction` turned into a value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResolvedIncrement {
    /// The parameter.
    pub param: Param,
    /// Value before any change.
    pub truth: f64,
    /// `(t0_s, value)`: the sudden change, if any.
    pub step: Option<(f64, f64)>,
}

impl ResolvedIncrement {
    /// The increment at `t_s`.
    pub fn at(&self, t_s: f64) -> f64 {
        match self.step {
            Some((t0, v)) if t_s >= t0 => v,
            _ => self.truth,
        }
    }
}

/// The reference aircraft's truth over one interval of constant increments.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthEpoch {
    /// Start of the interval, s (0 for the first).
    pub from_s: f64,
    /// The increments acting.
    pub increments: AeroIncrements,
    /// Local derivatives at the trim point with those increments.
    pub derivatives: LocalDerivatives,
}

/// Everything a run produced.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// The scenario that ran.
    pub scenario: Scenario,
    /// Trim point of both aircraft.
    pub trim: F16Trim,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Pilot controls `[throttle, elevator_rad, aileron_rad, rudder_rad]` per sample.
    pub controls: Vec<[f64; 4]>,
    /// Wind on the reference aircraft, NED, ft/s, per sample.
    pub wind_ned_fps: Vec<[f64; 3]>,
    /// Reference aircraft's full state per sample (true, before the sensors).
    pub reference: Vec<F16State>,
    /// The true increments and their schedules.
    pub increments: Vec<ResolvedIncrement>,
    /// The reference's truth per interval of constant increments (first from t = 0).
    pub epochs: Vec<TruthEpoch>,
    /// First time a pilot command differs from trim, s (`None`: no pilot input).
    pub excitation_start_s: Option<f64>,
    /// Delay of the air-data samples behind the truth (differentiator lag), s; `None` without
    /// sample-driven estimators.
    pub sample_lag_s: Option<f64>,
    /// One log per estimator.
    pub channels: Vec<ChannelLog>,
    /// Wall-clock time of the simulation loop (no I/O), s: the channels step on a second
    /// thread beside the flight where one is free (`stepping`).
    pub wall_s: f64,
}

impl RunOutput {
    /// Simulated time / wall-clock time of the loop.
    pub fn realtime_factor(&self) -> f64 {
        self.scenario.duration_s / self.wall_s.max(1e-12)
    }

    /// The epoch whose interval contains `t_s`.
    pub fn epoch_at(&self, t_s: f64) -> &TruthEpoch {
        let k = self.epochs.iter().rposition(|e| t_s >= e.from_s).unwrap_or(0);
        &self.epochs[k]
    }
}

fn setup_err(what: &str, e: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Setup { what: what.into(), reason: e.to_string() }
}

/// A sample-driven channel.
struct SampleChannel {
    est: Box<dyn Estimator + Send>,
    structure: ModelStructure,
    /// Feed the unsmoothed samples without the differentiated `ṗ q̇ ṙ`
    /// ([`SampleEstimatorSpec::raw_samples`]).
    raw_samples: bool,
}

/// A batch channel: the recorded samples, fitted after the flight.
struct BatchChannel {
    config: super::batch::BatchConfig,
    /// Record the unsmoothed samples ([`AirDataSampler::raw`]) instead of the smoothed ones.
    raw_samples: bool,
    structure: ModelStructure,
    samples: Vec<AirDataSample>,
}

enum Channelled {
    Two(Box<TwoAircraft>),
    Sample(SampleChannel),
    Batch(Box<BatchChannel>),
}

struct ChannelRun {
    log: ChannelLog,
    ch: Channelled,
}

/// Body → NED rotation of a body-axis vector at the attitude of `x`: the transpose of the one
/// rotation matrix of the rigid body ([`aeroident_models::rigid_body::body_from_ned`]).
fn body_to_ned(x: &F16State, v: [f64; 3]) -> [f64; 3] {
    let c = aeroident_models::rigid_body::body_from_ned(x[f16::PHI], x[f16::THETA], x[f16::PSI]);
    let w = c.transpose() * nalgebra::Vector3::new(v[0], v[1], v[2]);
    [w[0], w[1], w[2]]
}

/// Resolves the scenario's increments (a `step_to_fraction` × the nominal derivative).
fn resolve_increments(
    sc: &Scenario,
    nominal: &LocalDerivatives,
) -> Result<Vec<ResolvedIncrement>, ExperimentError> {
    sc.increments
        .iter()
        .map(|(p, e)| {
            let step = match (e.step_at_s, e.step_to, e.step_to_fraction) {
                (Some(t0), Some(v), _) => Some((t0, v)),
                (Some(t0), None, Some(f)) => {
                    let d = nominal.derivative(*p).ok_or_else(|| {
                        setup_err(
                            &format!("increments.{}.step_to_fraction", p.name()),
                            "no single local derivative for this term; give step_to",
                        )
                    })?;
                    Some((t0, f * d))
                }
                _ => None,
            };
            Ok(ResolvedIncrement { param: *p, truth: e.truth, step })
        })
        .collect()
}

/// Runs a scenario: trim, fly the aircraft, sense, estimate, log.
///
/// # Errors
/// [`ExperimentError`] when the trim fails, a signal/estimator cannot be built, or the
/// reference aircraft leaves the model's domain. Estimator failures are not errors: they are
/// logged in [`ChannelLog::failure`] and that channel's estimates are held.
pub fn run(sc: &Scenario) -> Result<RunOutput, ExperimentError> {
    run_with(sc, stepping::second_thread_free())
}

/// [`run`], its channels stepped on a second thread of rayon's pool or not.
fn run_with(sc: &Scenario, second_thread: bool) -> Result<RunOutput, ExperimentError> {
    let wind = build_wind(&sc.wind).map_err(|e| setup_err("wind", e))?;
    let (f16, trim) = trimmed_reference(sc)?;
    let reference = IncrementReference {
        alpha_rad: trim.state[f16::ALPHA],
        elevator_rad: trim.controls.elevator_rad,
        ..Default::default()
    };
    let (increments, epochs) = truth_epochs(sc, &f16, &trim, reference)?;
    let inputs = pilot_inputs(sc)?;
    let mut noise = if sc.sensors.noise {
        Some(
            SensorNoise::new(sc.sensors.scale, sc.dt_s, sc.sensors.seed)
                .map_err(|e| setup_err("sensors", e))?,
        )
    } else {
        None
    };
    let n = (sc.duration_s / sc.dt_s).round() as usize;
    let mut channels = sc
        .estimator
        .iter()
        .enumerate()
        .map(|(k, spec)| build_channel(sc, k, spec, &f16, reference, &trim, n))
        .collect::<Result<Vec<_>, _>>()?;
    let truths = attach_truths(&mut channels, &epochs);
    let mut sampler = air_data_sampler(sc, &f16, &channels)?;
    let mut out = RunOutput {
        scenario: sc.clone(),
        trim: trim.clone(),
        t_s: Vec::with_capacity(n + 1),
        controls: Vec::with_capacity(n + 1),
        wind_ned_fps: Vec::with_capacity(n + 1),
        reference: Vec::with_capacity(n + 1),
        increments,
        epochs: epochs.clone(),
        excitation_start_s: None,
        sample_lag_s: sampler.as_ref().map(AirDataSampler::lag_s),
        channels: Vec::new(),
        wall_s: 0.0,
    };
    let flight = Flight {
        sc,
        f16: &f16,
        trim: &trim,
        u_trim: trim.controls.to_vector(),
        epochs: &epochs,
        inputs: &inputs,
        wind: &wind,
        truths: &truths,
    };
    let start = Instant::now();
    let sensors = Sensing { noise: noise.as_mut(), sampler: sampler.as_mut() };
    let split = stepping::Split::new(channels.len(), second_thread);
    flight.fly(n, &mut channels, sensors, split, &mut out)?;
    out.wall_s = start.elapsed().as_secs_f64();
    fit_batches(&mut channels, &epochs, &out);
    out.channels = channels.into_iter().map(finish_channel).collect();
    Ok(out)
}

/// The reference F-16 trimmed level at the scenario's condition; with the matched-truth
/// option, its tables replaced by their first-order expansion at this trim (same value at
/// the trim, so the trim holds).
fn trimmed_reference(sc: &Scenario) -> Result<(F16, F16Trim), ExperimentError> {
    let (vt_fps, alt_ft) = (sc.trim.vt_fps, sc.trim.alt_ft);
    let f16 =
        F16::new(sc.trim.xcg).map_err(|source| ExperimentError::Trim { vt_fps, alt_ft, source })?;
    let trim = trim(&f16, &TrimCondition::level(alt_ft, vt_fps))
        .map_err(|source| ExperimentError::Trim { vt_fps, alt_ft, source })?;
    let f16 = match sc.aerodynamics {
        AerodynamicsSpec::Tables => f16,
        AerodynamicsSpec::Linear => {
            let ld = local_derivatives(&f16, &trim.state, &trim.controls, &AeroIncrements::zero())
                .map_err(|e| setup_err("linear aerodynamics at trim", e))?;
            f16.with_linear_aero(super::truth::linearised(&ld, &trim.state, &trim.controls))
        }
    };
    Ok((f16, trim))
}

/// The scenario's increments resolved, and the truth epochs: one from 0 and one from each
/// increment step, each with its increment matrix and the local derivatives at trim.
fn truth_epochs(
    sc: &Scenario,
    f16: &F16,
    trim: &F16Trim,
    reference: IncrementReference,
) -> Result<(Vec<ResolvedIncrement>, Vec<TruthEpoch>), ExperimentError> {
    let truth_at = |inc: &AeroIncrements| {
        local_derivatives(f16, &trim.state, &trim.controls, inc)
            .map_err(|e| setup_err("truth derivatives at trim", e))
    };
    let nominal = truth_at(&AeroIncrements::zero())?;
    let increments = resolve_increments(sc, &nominal)?;
    let values_at =
        |t: f64| -> Vec<(Param, f64)> { increments.iter().map(|r| (r.param, r.at(t))).collect() };
    let mut starts: Vec<f64> = increments.iter().filter_map(|r| r.step.map(|s| s.0)).collect();
    starts.push(0.0);
    starts.sort_by(f64::total_cmp);
    starts.dedup();
    let mut epochs = Vec::new();
    for &from_s in &starts {
        let inc = increment_matrix(reference, &values_at(from_s));
        epochs.push(TruthEpoch { from_s, increments: inc, derivatives: truth_at(&inc)? });
    }
    Ok((increments, epochs))
}

/// The pilot's input signals per control: throttle, elevator, aileron, rudder.
fn pilot_inputs(sc: &Scenario) -> Result<[Vec<Input>; 4], ExperimentError> {
    let mut inputs: [Vec<Input>; 4] = Default::default();
    for (k, i) in sc.input.iter().enumerate() {
        let sig = i.signal.build().map_err(|e| setup_err(&format!("input[{k}]"), e))?;
        let slot = match i.channel {
            Channel::Throttle => 0,
            Channel::Elevator => 1,
            Channel::Aileron => 2,
            Channel::Rudder => 3,
        };
        inputs[slot].push(sig);
    }
    Ok(inputs)
}

/// The estimator of entry `k` of the scenario and its empty log, for a run of `n` steps.
fn build_channel(
    sc: &Scenario,
    k: usize,
    spec: &EstimatorSpec,
    f16: &F16,
    reference: IncrementReference,
    trim: &F16Trim,
    n: usize,
) -> Result<ChannelRun, ExperimentError> {
    let what = format!("estimator[{k}] `{}`", spec.label());
    let (ch, kind, quantity, params, status) = match spec {
        EstimatorSpec::Sample(s) if crate::estimators::is_batch_kind(&s.kind) => {
            let config = super::batch::config(s).map_err(|e| setup_err(&what, e))?;
            let structure = config.oe().structure;
            let kind = config.kind();
            let samples = Vec::with_capacity(n + 1);
            let b = BatchChannel { config, raw_samples: s.raw_samples(), structure, samples };
            let params = structure.params().collect();
            (Channelled::Batch(Box::new(b)), kind, Quantity::Derivative, params, Some("recording"))
        }
        EstimatorSpec::Sample(s) => {
            let est =
                crate::estimators::build_sample_estimator(s).map_err(|e| setup_err(&what, e))?;
            let structure = *est.structure();
            let params: Vec<Param> = structure.params().collect();
            let kind = est.method();
            let c = SampleChannel { est, structure, raw_samples: s.raw_samples() };
            (Channelled::Sample(c), kind, Quantity::Derivative, params, Some("initialising"))
        }
        _ => {
            let two = two_aircraft::build(sc, spec, f16, reference, &trim.state)
                .map_err(|e| setup_err(&what, e))?;
            let (kind, params) = (two.kind, two.params.clone());
            (Channelled::Two(Box::new(two)), kind, Quantity::Increment, params, None)
        }
    };
    let logs = params
        .iter()
        .map(|p| ParamLog {
            param: *p,
            estimate: Vec::with_capacity(n + 1),
            sigma: Vec::with_capacity(n + 1),
            truth: Vec::with_capacity(n + 1),
            truth_epochs: Vec::new(),
        })
        .collect();
    let is_two = matches!(ch, Channelled::Two(_));
    let log = ChannelLog {
        label: spec.label(),
        kind,
        quantity,
        params: logs,
        states: Vec::with_capacity(if is_two { n + 1 } else { 0 }),
        diagnostics: Vec::new(),
        failure: None,
        stats: String::new(),
        status,
        nis: None,
        events: Default::default(),
        batch: None,
    };
    Ok(ChannelRun { log, ch })
}

/// Per channel and parameter, the truth in each epoch (an increment for the two-aircraft
/// estimators, the local derivative for the others), also kept in the logs.
fn attach_truths(channels: &mut [ChannelRun], epochs: &[TruthEpoch]) -> Vec<Vec<Vec<Option<f64>>>> {
    let truth = |ch: &Channelled, e: &TruthEpoch, p: Param| match ch {
        Channelled::Two(_) => Some(super::increments::get(&e.increments, p)),
        Channelled::Sample(s) => e.derivatives.truth(&s.structure, p),
        Channelled::Batch(b) => e.derivatives.truth(&b.structure, p),
    };
    let truths: Vec<Vec<Vec<Option<f64>>>> = channels
        .iter()
        .map(|c| {
            let of = |l: &ParamLog| epochs.iter().map(|e| truth(&c.ch, e, l.param)).collect();
            c.log.params.iter().map(of).collect()
        })
        .collect();
    for (c, tr) in channels.iter_mut().zip(&truths) {
        for (l, t) in c.log.params.iter_mut().zip(tr) {
            l.truth_epochs = t.clone();
        }
    }
    truths
}

/// The air-data sensor path, when a channel is fed samples.
fn air_data_sampler(
    sc: &Scenario,
    f16: &F16,
    channels: &[ChannelRun],
) -> Result<Option<AirDataSampler>, ExperimentError> {
    let fed = |c: &ChannelRun| matches!(c.ch, Channelled::Sample(_) | Channelled::Batch(_));
    if !channels.iter().any(fed) {
        return Ok(None);
    }
    AirDataSampler::new(f16, sc.trim.vt_fps * M_PER_FT, sc.dt_s, &sc.sensors)
        .map(Some)
        .map_err(|e| setup_err("air-data sensors", e))
}

/// What the flight needs, set up.
struct Flight<'a> {
    sc: &'a Scenario,
    f16: &'a F16,
    trim: &'a F16Trim,
    /// The trim controls as a vector (throttle, elevator, aileron, rudder).
    u_trim: nalgebra::SVector<f64, 4>,
    epochs: &'a [TruthEpoch],
    inputs: &'a [Vec<Input>; 4],
    wind: &'a aeroident_signals::Wind,
    truths: &'a [Vec<Vec<Option<f64>>>],
}

/// The two sensor paths of the flight (module doc, step 3), each read once per step.
struct Sensing<'a> {
    /// The two-aircraft estimators' measured states and derivatives; `None`: exact.
    noise: Option<&'a mut SensorNoise>,
    /// The sample-driven estimators' air-data samples, when a channel is fed them.
    sampler: Option<&'a mut AirDataSampler>,
}

impl Flight<'_> {
    /// The pilot's controls at time `t`: trim + inputs, continuous in time (module doc,
    /// step 4).
    fn pilot(&self, t: f64) -> nalgebra::SVector<f64, 4> {
        let mut uv = self.u_trim;
        for (slot, sigs) in self.inputs.iter().enumerate() {
            uv[slot] += sigs.iter().map(|s| s.value(t)).sum::<f64>();
        }
        uv
    }

    /// Flies `n` steps, a block at a time: at each step the reference's outputs and the
    /// sensors, then RK4 of the reference; the channels take each block on two threads while
    /// the next is flown ([`stepping`]), each two-aircraft estimator's own aircraft
    /// integrated after its update.
    fn fly(
        &self,
        n: usize,
        channels: &mut [ChannelRun],
        sensors: Sensing<'_>,
        mut split: stepping::Split,
        out: &mut RunOutput,
    ) -> Result<(), ExperimentError> {
        let (f16, x) = (self.f16.clone(), self.trim.state);
        let mut reference = Reference { flight: self, sensors, f16, x, k: 0, n };
        let (mut ready, mut next) = (Vec::new(), Vec::new());
        reference.fly(&mut ready, out)?;
        // The pilot's controls at the RK4 stage times, the wind of the step held (its
        // field is sampled at the step).
        let controls = |ts: f64, c: F16Controls| c.with_vector(&self.pilot(ts));
        while !ready.is_empty() {
            let fly_next = || reference.fly(&mut next, out);
            split.step(channels, &ready, self.truths, &controls, self.sc.dt_s, fly_next)?;
            std::mem::swap(&mut ready, &mut next);
        }
        Ok(())
    }
}

/// The reference aircraft and its sensors, flown a block at a time.
struct Reference<'f, 'a> {
    flight: &'f Flight<'a>,
    sensors: Sensing<'f>,
    /// The reference, with the increments of the current epoch.
    f16: F16,
    /// Its state at step `k`.
    x: F16State,
    /// The next step to fly.
    k: usize,
    /// The last step.
    n: usize,
}

impl Reference<'_, '_> {
    /// Flies up to [`stepping::BLOCK_STEPS`] steps into `steps` (cleared first), logging the
    /// flight in `out`; `steps` stays empty once the flight is over.
    fn fly(
        &mut self,
        steps: &mut Vec<stepping::SensedStep>,
        out: &mut RunOutput,
    ) -> Result<(), ExperimentError> {
        steps.clear();
        while steps.len() < stepping::BLOCK_STEPS && self.k <= self.n {
            steps.push(self.step(out)?);
            self.k += 1;
        }
        Ok(())
    }

    /// Step `k`: the pilot and the wind, the reference's outputs, the sensors; then RK4 to
    /// the next step unless it is the last.
    fn step(&mut self, out: &mut RunOutput) -> Result<stepping::SensedStep, ExperimentError> {
        let fl = self.flight;
        let t = self.k as f64 * fl.sc.dt_s;
        let uv = fl.pilot(t);
        if out.excitation_start_s.is_none() && uv != fl.u_trim {
            out.excitation_start_s = Some(t);
        }
        let mut u = fl.trim.controls.with_vector(&uv);
        let wb = fl.wind.wind_body_fps(t);
        let wind_ned = body_to_ned(&self.x, [wb[0], wb[1], wb[2]]);
        let u_est = match fl.sc.estimator_wind {
            EstimatorWind::Known => F16Controls { wind_ned_fps: wind_ned, ..u },
            EstimatorWind::Unknown => u,
        };
        u.wind_ned_fps = wind_ned;
        let epoch = fl.epochs.iter().rposition(|e| t >= e.from_s).unwrap_or(0);
        self.f16.increments = fl.epochs[epoch].increments;
        let failed = |e| ExperimentError::Reference { t_s: t, source: e };
        let (xdot, outputs) =
            self.f16.evaluate(&self.x, &u, &self.f16.increments).map_err(failed)?;
        let (z_m, zdot_m) = match self.sensors.noise.as_mut() {
            Some(nz) => nz.measure(t, &self.x, &xdot),
            None => (self.x, xdot),
        };
        let air = self.sensors.sampler.as_mut().and_then(|s| s.push(t, &self.x, &outputs, &u));
        let raw = air.and(self.sensors.sampler.as_ref().and_then(|s| s.raw()).copied());
        out.t_s.push(t);
        out.controls.push([uv[0], uv[1], uv[2], uv[3]]);
        out.wind_ned_fps.push(wind_ned);
        out.reference.push(self.x);
        let last = self.k == self.n;
        if !last {
            let at_stage = move |ts: f64| u.with_vector(&fl.pilot(ts));
            self.x =
                rk4_step_varying(&self.f16, t, &self.x, at_stage, fl.sc.dt_s).map_err(failed)?;
        }
        Ok(stepping::SensedStep { t_s: t, epoch, z_m, zdot_m, u_est, air, raw, last })
    }
}

/// The batch fits, after the flight, on the window after the last change of the truth
/// (module doc of super::batch).
fn fit_batches(channels: &mut [ChannelRun], epochs: &[TruthEpoch], out: &RunOutput) {
    let lag_s = out.sample_lag_s.unwrap_or(0.0);
    let window_from_s = match epochs.last() {
        Some(e) if e.from_s > 0.0 => e.from_s + lag_s,
        _ => f64::NEG_INFINITY,
    };
    let t_end = out.t_s.last().copied().unwrap_or(0.0);
    for c in channels {
        let Channelled::Batch(b) = &c.ch else { continue };
        match fit_window(&c.log.label, &b.samples, window_from_s, &b.config) {
            Ok((values, log)) => {
                for (l, (v, s)) in c.log.params.iter_mut().zip(values) {
                    if let (Some(e), Some(sg)) = (l.estimate.last_mut(), l.sigma.last_mut()) {
                        *e = Some(v).filter(|v| v.is_finite());
                        *sg = Some(s).filter(|s| s.is_finite());
                    }
                }
                c.log.status = Some(log.status);
                c.log.stats = format!(
                    "{}: {} samples from t = {:.2} s, {} iterations, {:.2} s",
                    match b.config.kind() {
                        "fem" => "filter error",
                        _ => "output error",
                    },
                    log.samples,
                    log.from_s,
                    log.iterations.unwrap_or(0),
                    log.wall_s
                );
                if let Some(why) = &log.status_reason {
                    c.log.stats.push_str(&format!("; {why}"));
                }
                c.log.batch = Some(log);
            }
            Err(e) => {
                c.log.status = Some("failed");
                c.log.failure = Some((t_end, e));
            }
        }
    }
}

/// A channel's log, completed with its estimator's final statistics, NIS and events.
fn finish_channel(mut c: ChannelRun) -> ChannelLog {
    c.log.stats = match &c.ch {
        Channelled::Two(two) => two
            .engines
            .iter()
            .map(|e| e.stats())
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join("; "),
        Channelled::Sample(s) => format!("status {}", s.est.estimates().status.name()),
        Channelled::Batch(_) => c.log.stats.clone(),
    };
    if let Channelled::Sample(s) = &c.ch {
        c.log.nis = s.est.nis();
        c.log.events = aeroident_io::replay_output::EventsSummary::from_log(s.est.events());
    }
    c.log
}
