//! The two-aircraft estimation experiment of thesis Figure 3.2.
//!
//! Per sample `k` (interval `dt`, RK4 with the inputs held over the step):
//! 1. the pilot command (trim + inputs) and the wind at `t_k`;
//! 2. the **reference aircraft** (true increments, the wind) gives `x_ref`, `ẋ_ref`;
//! 3. the **sensor model** turns them into `z_m`, `ż_m` — the only thing estimators see;
//! 4. each estimator channel updates from `(z_est, z_m, ż_m, u)`, where `z_est` is the state of
//!    its own **estimated aircraft** (same trim, same pilot command, the current estimates,
//!    still air unless `estimator_wind = "known"`);
//! 5. both aircraft advance one RK4 step.
//!
//! In a combined published run the three coefficient groups (C_m: p, q, r; C_L and C_D:
//! α, V_T, β) are three engines that share one estimated aircraft; within a sample each sees
//! the other groups' estimates of the previous sample.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Instant;

use aeroident_estimators::mrac::{GradientConfig, ModelReferenceGradient};
use aeroident_estimators::smpe::{
    CorrectedConfig, CorrectedSmpe, GainForm, ParamSpec, ParametricModel, PublishedSmpe, Reading,
    SlidingSurface, SmpeConfig, SmpeSample,
};
use aeroident_estimators::{EstimatorError, ParametricEstimator};
use aeroident_models::f16::{self, F16, F16Controls, F16State, IncrementReference, N_STATES};
use aeroident_models::integrate::rk4_step;
use aeroident_models::trim::{F16Trim, TrimCondition, trim};
use aeroident_signals::{Input, InputSignal, WindField, config::build_wind};

use super::model::{F16IncrementModel, Increment, thesis_increments};
use super::scenario::{Channel, EstimatorSpec, EstimatorWind, ReadingSpec, Scenario};
use super::sensors::{SensorNoise, derivative_sigma};

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

/// Diagnostics of one published-SMPE group at one sample (after its update).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PublishedDiagnostics {
    /// Lyapunov gain K (3.128)/(3.153)/(3.159) at the new estimate.
    pub K: f64,
    /// Sliding-surface derivative ṡ of the group's first parameter, (3.106)/(3.134), at the
    /// new estimate.
    pub sdot: f64,
}

/// What one estimator channel logged.
#[derive(Debug, Clone)]
pub struct ChannelLog {
    /// Label (`published-implicit`, `corrected`, …).
    pub label: String,
    /// Kind: `published`, `corrected` or `gradient`.
    pub kind: &'static str,
    /// The increments it estimates.
    pub params: Vec<Increment>,
    /// Estimates `[ΔCm_α, ΔCm_q, ΔCL_α, ΔCD_α]` per sample (non-estimated entries are the
    /// estimated aircraft's fixed values, zero).
    pub estimates: Vec<[f64; 4]>,
    /// Estimated aircraft's full state per sample (sliding states: [`tracked`]).
    pub states: Vec<F16State>,
    /// Published groups only: per sample, one entry per group (C_m, C_L, C_D order).
    pub diagnostics: Vec<Vec<PublishedDiagnostics>>,
    /// First estimator or estimated-aircraft error, with its time; estimates are held from
    /// then on (never NaN).
    pub failure: Option<(f64, String)>,
    /// Solver counters, human-readable.
    pub stats: String,
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
    /// True increments per sample.
    pub truth: Vec<[f64; 4]>,
    /// One log per estimator.
    pub channels: Vec<ChannelLog>,
    /// Wall-clock time of the simulation loop (no I/O), s.
    pub wall_s: f64,
}

impl RunOutput {
    /// Simulated time / wall-clock time of the loop.
    pub fn realtime_factor(&self) -> f64 {
        self.scenario.duration_s / self.wall_s.max(1e-12)
    }
}

type Sample = SmpeSample<N_STATES, F16Controls>;

/// One estimation engine over some of the increments.
trait Engine {
    fn update(&mut self, s: &Sample) -> Result<(), EstimatorError>;
    fn write(&self, out: &mut [f64; 4]);
    fn diagnostics(&self, _s: &Sample) -> Option<PublishedDiagnostics> {
        None
    }
    fn stats(&self) -> String {
        String::new()
    }
}

struct Published<const P: usize> {
    est: PublishedSmpe<F16IncrementModel<P>, N_STATES, P>,
    model: F16IncrementModel<P>,
}

impl<const P: usize> Engine for Published<P> {
    fn update(&mut self, s: &Sample) -> Result<(), EstimatorError> {
        self.est.update(s).map(|_| ())
    }
    fn write(&self, out: &mut [f64; 4]) {
        for (j, inc) in self.model.estimated().iter().enumerate() {
            out[inc.index()] = self.est.estimate().theta[j];
        }
    }
    fn diagnostics(&self, s: &Sample) -> Option<PublishedDiagnostics> {
        published_diagnostics(&self.model, self.est.config(), &self.est.estimate().theta, s).ok()
    }
    fn stats(&self) -> String {
        let st = self.est.stats();
        format!(
            "{:?}: samples {}, no_root {}, clamped {}, guarded {}",
            self.model.estimated().map(|i| i.name()),
            st.samples,
            st.no_root,
            st.clamped,
            st.guarded
        )
    }
}

/// K and ṡ of a published-SMPE group at `theta` for sample `s`, computed from the engine's
/// definitions (3.36)/(3.128) and (3.106): `φ_j = Σ_i rate_i z_i ∂ż_i/∂θ_j`,
/// `K = |Σ_j θ_j (μ_j⁻¹ − 1) φ_j| − η`, `ṡ = Σ_i rate_i (z_i ż_i − z_m,i ż_m,i) + λ_0 Σ_i
/// ½ w_i (z_i² − z_m,i²)` (first-order surface).
///
/// # Errors
/// The model's errors.
pub fn published_diagnostics<M: ParametricModel<N_STATES, P>, const P: usize>(
    model: &M,
    cfg: &SmpeConfig<N_STATES, P>,
    theta: &nalgebra::SVector<f64, P>,
    s: &SmpeSample<N_STATES, M::Input>,
) -> Result<PublishedDiagnostics, EstimatorError> {
    let zdot = model.derivatives(s.t_s, &s.z, &s.u, theta)?;
    let sens = model.sensitivity(s.t_s, &s.z, &s.u, theta)?;
    let sf = &cfg.surface;
    let mut k_sum = 0.0;
    for j in 0..P {
        let phi: f64 = (0..N_STATES).map(|i| sf.rate[i] * s.z[i] * sens[(i, j)]).sum();
        let mu = cfg.params[j].gain_margin().unwrap_or(1.0);
        k_sum += theta[j] * (1.0 / mu - 1.0) * phi;
    }
    let mut sdot = 0.0;
    for i in 0..N_STATES {
        let e_dot = s.z[i] * zdot[i] - s.z_m[i] * s.zdot_m[i];
        let e = 0.5 * (s.z[i] * s.z[i] - s.z_m[i] * s.z_m[i]);
        sdot += sf.rate[i] * e_dot
            + cfg.params[0].lambda * (sf.lambda_energy[i] * e_dot + sf.lambda_integral[i] * e);
    }
    Ok(PublishedDiagnostics { K: k_sum.abs() - cfg.eta, sdot })
}

struct Generic<E, const P: usize> {
    est: E,
    incs: [Increment; P],
}

impl<E: ParametricEstimator<P, Sample = Sample>, const P: usize> Engine for Generic<E, P> {
    fn update(&mut self, s: &Sample) -> Result<(), EstimatorError> {
        self.est.update(s).map(|_| ())
    }
    fn write(&self, out: &mut [f64; 4]) {
        for (j, inc) in self.incs.iter().enumerate() {
            out[inc.index()] = self.est.estimate().theta[j];
        }
    }
}

fn setup_err(what: &str, e: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Setup { what: what.into(), reason: e.to_string() }
}

struct Ctx<'a> {
    sc: &'a Scenario,
    f16: F16,
    reference: IncrementReference,
    current: Rc<Cell<[f64; 4]>>,
}

impl Ctx<'_> {
    fn spec(&self, inc: Increment) -> ParamSpec {
        // Validated: every estimated increment has a [params] table.
        let p = self.sc.param(inc).cloned().unwrap_or(super::scenario::ParamEntry {
            truth: 0.0,
            lower: -1.0,
            upper: 1.0,
            lambda_per_s: 1.0,
            eta: 1e-9,
            gradient_gain: None,
            initial: None,
            step_to: None,
            step_at_s: None,
            thesis_convergence_time_s: None,
            thesis_note: None,
        });
        ParamSpec {
            name: inc.name(),
            lower: p.lower,
            upper: p.upper,
            lambda: p.lambda_per_s,
            initial: p.initial_estimate(),
        }
    }

    fn model<const P: usize>(&self, incs: [Increment; P]) -> F16IncrementModel<P> {
        F16IncrementModel::new(self.f16.clone(), self.reference, incs, self.current.clone())
    }

    fn published<const P: usize>(
        &self,
        incs: [Increment; P],
        reading: Reading,
    ) -> Result<Box<dyn Engine>, ExperimentError> {
        let surface = SlidingSurface::first_order(&incs[0].sliding_states())
            .map_err(|e| setup_err("published surface", e))?;
        let eta = incs
            .iter()
            .filter_map(|i| self.sc.param(*i).map(|p| p.eta))
            .fold(f64::INFINITY, f64::min);
        let cfg = SmpeConfig {
            params: incs.map(|i| self.spec(i)),
            eta,
            surface,
            gain: GainForm::Shared,
            reading,
        };
        let model = self.model(incs);
        let est = PublishedSmpe::new(model.clone(), cfg)
            .map_err(|e| setup_err(&format!("published SMPE {:?}", incs.map(|i| i.name())), e))?;
        Ok(Box::new(Published { est, model }))
    }

    fn corrected<const P: usize>(
        &self,
        incs: [Increment; P],
        spec: &EstimatorSpec,
    ) -> Result<Box<dyn Engine>, ExperimentError> {
        let EstimatorSpec::Corrected {
            lambda_per_s,
            information_per_s,
            tracking_weight,
            forgetting_per_s,
            ..
        } = *spec
        else {
            return Err(setup_err("corrected", "not a corrected spec"));
        };
        // Rows weighted by 1/σ² of the nominal derivative noise (unit-free information).
        let sig = derivative_sigma(self.sc.dt_s);
        let mut sliding = [0.0; N_STATES];
        for inc in incs {
            for i in inc.sliding_states() {
                sliding[i] = 1.0 / (sig[i] * sig[i]);
            }
        }
        let cfg = CorrectedConfig {
            params: incs.map(|i| self.spec(i)),
            sliding,
            lambda_per_s,
            information_per_s,
            tracking_weight,
            forgetting_per_s,
        };
        let est = CorrectedSmpe::new(self.model(incs), cfg)
            .map_err(|e| setup_err("corrected SMPE", e))?;
        Ok(Box::new(Generic { est, incs }))
    }

    fn gradient<const P: usize>(
        &self,
        incs: [Increment; P],
    ) -> Result<Box<dyn Engine>, ExperimentError> {
        let mut params = incs.map(|i| self.spec(i));
        for (p, inc) in params.iter_mut().zip(incs) {
            p.lambda = self.sc.param(inc).and_then(|e| e.gradient_gain).unwrap_or(1.0);
        }
        let states = incs.map(|inc| {
            let mut w = [0.0; N_STATES];
            for i in inc.sliding_states() {
                w[i] = 1.0;
            }
            w
        });
        let est = ModelReferenceGradient::new(self.model(incs), GradientConfig { params, states })
            .map_err(|e| setup_err("gradient estimator", e))?;
        Ok(Box::new(Generic { est, incs }))
    }
}

fn incs_array<const P: usize>(v: &[Increment]) -> [Increment; P] {
    core::array::from_fn(|j| v[j])
}

/// One estimator channel: its engines and its estimated aircraft.
struct ChannelRun {
    log: ChannelLog,
    engines: Vec<Box<dyn Engine>>,
    current: Rc<Cell<[f64; 4]>>,
    x: F16State,
    f16: F16,
}

fn build_channel(
    sc: &Scenario,
    spec: &EstimatorSpec,
    f16: &F16,
    reference: IncrementReference,
    x0: &F16State,
) -> Result<ChannelRun, ExperimentError> {
    let mut incs: Vec<Increment> =
        spec.param_names().iter().filter_map(|n| Increment::from_name(n)).collect();
    incs.sort();
    let current = Rc::new(Cell::new([0.0; 4]));
    let ctx = Ctx { sc, f16: f16.clone(), reference, current: current.clone() };
    let mut init = [0.0; 4];
    for inc in &incs {
        init[inc.index()] = ctx.spec(*inc).initial;
    }
    current.set(init);
    let mut engines: Vec<Box<dyn Engine>> = Vec::new();
    let kind;
    match spec {
        EstimatorSpec::Published { reading, .. } => {
            kind = "published";
            let reading = match reading {
                ReadingSpec::Implicit => Reading::Implicit,
                ReadingSpec::Explicit => Reading::Explicit,
            };
            let cm: Vec<Increment> = incs
                .iter()
                .copied()
                .filter(|i| matches!(i, Increment::CmAlpha | Increment::CmQ))
                .collect();
            match cm.len() {
                1 => engines.push(ctx.published::<1>(incs_array(&cm), reading)?),
                2 => engines.push(ctx.published::<2>(incs_array(&cm), reading)?),
                _ => {}
            }
            for inc in [Increment::CLAlpha, Increment::CDAlpha] {
                if incs.contains(&inc) {
                    engines.push(ctx.published::<1>([inc], reading)?);
                }
            }
        }
        EstimatorSpec::Corrected { .. } => {
            kind = "corrected";
            engines.push(match incs.len() {
                1 => ctx.corrected::<1>(incs_array(&incs), spec)?,
                2 => ctx.corrected::<2>(incs_array(&incs), spec)?,
                3 => ctx.corrected::<3>(incs_array(&incs), spec)?,
                _ => ctx.corrected::<4>(incs_array(&incs), spec)?,
            });
        }
        EstimatorSpec::Gradient { .. } => {
            kind = "gradient";
            engines.push(match incs.len() {
                1 => ctx.gradient::<1>(incs_array(&incs))?,
                2 => ctx.gradient::<2>(incs_array(&incs))?,
                3 => ctx.gradient::<3>(incs_array(&incs))?,
                _ => ctx.gradient::<4>(incs_array(&incs))?,
            });
        }
    }
    let n = (sc.duration_s / sc.dt_s).round() as usize + 1;
    Ok(ChannelRun {
        log: ChannelLog {
            label: spec.label(),
            kind,
            params: incs,
            estimates: Vec::with_capacity(n),
            states: Vec::with_capacity(n),
            diagnostics: Vec::new(),
            failure: None,
            stats: String::new(),
        },
        engines,
        current,
        x: *x0,
        f16: f16.clone(),
    })
}

/// Body → NED rotation of a body-axis vector at the attitude of `x` (SLJ (1.3-20)).
fn body_to_ned(x: &F16State, v: [f64; 3]) -> [f64; 3] {
    let (sph, cph) = x[f16::PHI].sin_cos();
    let (sth, cth) = x[f16::THETA].sin_cos();
    let (sps, cps) = x[f16::PSI].sin_cos();
    // Rows of C_body←NED; C_NED←body is its transpose.
    let r1 = [cth * cps, cth * sps, -sth];
    let r2 = [sph * sth * cps - cph * sps, sph * sth * sps + cph * cps, sph * cth];
    let r3 = [cph * sth * cps + sph * sps, cph * sth * sps - sph * cps, cph * cth];
    [0, 1, 2].map(|k| r1[k] * v[0] + r2[k] * v[1] + r3[k] * v[2])
}

/// Runs a scenario: trim, fly both aircraft, sense, estimate, log.
///
/// # Errors
/// [`ExperimentError`] when the trim fails, a signal/estimator cannot be built, or the
/// reference aircraft leaves the model's domain. Estimator failures are not errors: they are
/// logged in [`ChannelLog::failure`] and that channel's estimates are held.
pub fn run(sc: &Scenario) -> Result<RunOutput, ExperimentError> {
    let wind = build_wind(&sc.wind).map_err(|e| setup_err("wind", e))?;
    let f16 = F16::new(sc.trim.xcg).map_err(|e| ExperimentError::Trim {
        vt_fps: sc.trim.vt_fps,
        alt_ft: sc.trim.alt_ft,
        source: e,
    })?;
    let trim = trim(&f16, &TrimCondition::level(sc.trim.alt_ft, sc.trim.vt_fps)).map_err(|e| {
        ExperimentError::Trim { vt_fps: sc.trim.vt_fps, alt_ft: sc.trim.alt_ft, source: e }
    })?;
    let reference = IncrementReference {
        alpha_rad: trim.state[f16::ALPHA],
        elevator_rad: trim.controls.elevator_rad,
        ..Default::default()
    };
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
    let noise = if sc.sensors.noise {
        Some(
            SensorNoise::new(sc.sensors.scale, sc.dt_s, sc.sensors.seed)
                .map_err(|e| setup_err("sensors", e))?,
        )
    } else {
        None
    };
    let mut channels = sc
        .estimator
        .iter()
        .map(|e| build_channel(sc, e, &f16, reference, &trim.state))
        .collect::<Result<Vec<_>, _>>()?;

    let n = (sc.duration_s / sc.dt_s).round() as usize;
    let mut out = RunOutput {
        scenario: sc.clone(),
        trim: trim.clone(),
        t_s: Vec::with_capacity(n + 1),
        controls: Vec::with_capacity(n + 1),
        wind_ned_fps: Vec::with_capacity(n + 1),
        reference: Vec::with_capacity(n + 1),
        truth: Vec::with_capacity(n + 1),
        channels: Vec::new(),
        wall_s: 0.0,
    };
    let mut f16_ref = f16.clone();
    let mut x_ref = trim.state;
    let u0 = trim.controls.to_vector();
    let start = Instant::now();
    for k in 0..=n {
        let t = k as f64 * sc.dt_s;
        let mut uv = u0;
        for (slot, sigs) in inputs.iter().enumerate() {
            uv[slot] += sigs.iter().map(|s| s.value(t)).sum::<f64>();
        }
        let mut u = trim.controls.with_vector(&uv);
        let wb = wind.wind_body_fps(t);
        let wind_ned = body_to_ned(&x_ref, [wb[0], wb[1], wb[2]]);
        let u_est = match sc.estimator_wind {
            EstimatorWind::Known => F16Controls { wind_ned_fps: wind_ned, ..u },
            EstimatorWind::Unknown => u,
        };
        u.wind_ned_fps = wind_ned;
        let truth = sc.truth_at(t);
        f16_ref.increments = thesis_increments(reference, &truth);
        let xdot_ref = f16_ref
            .derivatives_with_increments(&x_ref, &u, &f16_ref.increments)
            .map_err(|e| ExperimentError::Reference { t_s: t, source: e })?;
        let (z_m, zdot_m) = match &noise {
            Some(nz) => nz.measure(t, &x_ref, &xdot_ref),
            None => (x_ref, xdot_ref),
        };
        for ch in &mut channels {
            let sample = SmpeSample { t_s: t, z: ch.x, z_m, zdot_m, u: u_est };
            if ch.log.failure.is_none() {
                let mut next = ch.current.get();
                let mut diag = Vec::new();
                for e in &mut ch.engines {
                    match e.update(&sample) {
                        Ok(()) => {
                            e.write(&mut next);
                            if let Some(d) = e.diagnostics(&sample) {
                                diag.push(d);
                            }
                        }
                        Err(err) => {
                            ch.log.failure = Some((t, err.to_string()));
                            break;
                        }
                    }
                }
                if ch.log.failure.is_none() {
                    ch.current.set(next);
                }
                if !diag.is_empty() {
                    ch.log.diagnostics.push(diag);
                }
            }
            ch.log.estimates.push(ch.current.get());
            ch.log.states.push(ch.x);
        }
        out.t_s.push(t);
        out.controls.push([uv[0], uv[1], uv[2], uv[3]]);
        out.wind_ned_fps.push(wind_ned);
        out.reference.push(x_ref);
        out.truth.push(truth);
        if k == n {
            break;
        }
        x_ref = rk4_step(&f16_ref, t, &x_ref, &u, sc.dt_s)
            .map_err(|e| ExperimentError::Reference { t_s: t, source: e })?;
        for ch in &mut channels {
            ch.f16.increments = thesis_increments(reference, &ch.current.get());
            match rk4_step(&ch.f16, t, &ch.x, &u_est, sc.dt_s) {
                Ok(x) => ch.x = x,
                Err(e) => {
                    if ch.log.failure.is_none() {
                        ch.log.failure = Some((t, format!("estimated aircraft: {e}")));
                    }
                }
            }
        }
    }
    out.wall_s = start.elapsed().as_secs_f64();
    out.channels = channels
        .into_iter()
        .map(|mut ch| {
            ch.log.stats = ch
                .engines
                .iter()
                .map(|e| e.stats())
                .filter(|s| !s.is_empty())
                .collect::<Vec<_>>()
                .join("; ");
            ch.log
        })
        .collect();
    Ok(out)
}
