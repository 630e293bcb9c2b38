//! One aircraft chosen at run time, for faces that cannot be generic over the state count
//! (Python): the F-16 (13 states, ft) or a model-file aircraft (12 states, SI) behind one type
//! with plain-vector states, so that a user closes their own loop around the simulator:
//! trim, the state derivative, one integration step, the linear model about a level trim, and
//! the exact air-data sample an estimator eats at a state.
//!
//! States are in the aircraft's own units ([`AnyAircraft::state_names`] names them, with their
//! units); controls are [`CONTROL_NAMES`] (engine command, elevator, aileron, rudder, rad).

use super::ModelFileAircraft;
use crate::aircraft::air_data::{exact_sample, f16_constants};
use crate::aircraft::increments::{increment_matrix, parse_increment};
use crate::error::{PipelineError, Result};
use aeroident_estimators::{AirDataSample, Param};
use aeroident_models::aircraft::{
    Aircraft, CONTROL_NAMES, ControlVector, LevelLinearization, N_CONTROLS, linearize_level,
};
use aeroident_models::f16::{self, F16, IncrementReference, IncrementSchedule};
use aeroident_models::integrate::rk4_step;
use aeroident_models::linearize::Mode;
use aeroident_physics::units::M_PER_FT;
use nalgebra::SVector;

/// The F-16 or a model-file aircraft (module doc).
#[derive(Debug, Clone)]
pub enum AnyAircraft {
    /// Stevens & Lewis's F-16, with its scheduled increments (damage).
    F16(Box<F16>),
    /// An aircraft flying identified derivatives ([`super::load`]).
    ModelFile(Box<ModelFileAircraft>),
}

/// A wings-level trim in plain vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct Trim {
    /// The state, the aircraft's units ([`AnyAircraft::state_names`]).
    pub state: Vec<f64>,
    /// The controls ([`CONTROL_NAMES`]).
    pub controls: [f64; N_CONTROLS],
    /// Largest absolute `[V̇, α̇, β̇, ṗ, q̇, ṙ]` at the solution, state units per second.
    pub max_abs_residual: f64,
}

/// A linear model `ẋ = A x + B u` of the perturbations about a wings-level trim.
#[derive(Debug, Clone, PartialEq)]
pub struct Linear {
    /// The trim it is taken about.
    pub trim: Trim,
    /// `A`, rows of `n` (state units).
    pub a: Vec<Vec<f64>>,
    /// `B`, `n` rows of [`N_CONTROLS`].
    pub b: Vec<Vec<f64>>,
    /// Eigenvalues of `A` as (real, imaginary), 1/s, sorted by real then imaginary part.
    pub eigenvalues: Vec<(f64, f64)>,
    /// The rigid-body modes of the longitudinal and lateral blocks (never an actuator's pole:
    /// those are [`Self::actuators`]).
    pub modes: Vec<Mode>,
    /// The `n` states' names with their units: the aircraft's, then one per actuator.
    pub states: Vec<String>,
    /// The [`N_CONTROLS`] inputs' names: the engine command (its unit,
    /// [`Aircraft::engine_command`]), then each surface's deflection (`elevator_rad` …), or its
    /// command (`elevator_cmd_rad` …) where an actuator lies between them.
    pub inputs: Vec<String>,
    /// The actuator states appended by [`Self::with_actuators`], in state order; empty when
    /// every surface is its command.
    pub actuators: Vec<ActuatorState>,
}

/// One surface's actuator as a state of a [`Linear`] model: the first-order lag
/// `τ δ̇ = u − δ` of [`aeroident_io::mapping::Actuator`] about the trim, so `ẋ = (u − x)/τ`
/// with the command `u` as the input, its pole `−1/τ`. The rate and position limits are not
/// in it: the linear model holds about the trim where neither acts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActuatorState {
    /// The surface: `de`, `da` or `dr`.
    pub surface: &'static str,
    /// The state's name: the deflection as `sim` records it (`elevator_rad`, `aileron_rad`,
    /// `rudder_rad`).
    pub state: &'static str,
    /// The input driving it: the command as `sim` records it (`elevator_cmd_rad` …).
    pub input: &'static str,
    /// Row and column of the state in `A`.
    pub index: usize,
    /// Column of the command in `B` (1 elevator, 2 aileron, 3 rudder).
    pub control: usize,
    /// The mapping's actuator (τ s, rate limit rad/s, position limits rad).
    pub actuator: aeroident_io::mapping::Actuator,
    /// The surface's trim deflection, rad.
    pub trim_rad: f64,
}

impl ActuatorState {
    /// The pole `−1/τ`, 1/s.
    pub fn pole(&self) -> f64 {
        -1.0 / self.actuator.tau_s
    }
}

/// The surfaces an actuator may drive: (name, deflection state, command input), in the order
/// of [`aeroident_models::aircraft::CONTROL_NAMES`]' surfaces and of the airframe's
/// actuators; the names are the columns `sim` records.
const SURFACES: [(&str, &str, &str); 3] = [
    ("de", "elevator_rad", "elevator_cmd_rad"),
    ("da", "aileron_rad", "aileron_cmd_rad"),
    ("dr", "rudder_rad", "rudder_cmd_rad"),
];

/// What a linear model with actuators leaves out, in words, for the faces to print.
pub const ACTUATOR_NOTE: &str = "actuators are first-order lag states about the trim (the input is the command): rate limits and position limits are not in a linear model, which holds while neither acts";

impl Linear {
    /// The same model with each surface that has an actuator in `actuators` (elevator,
    /// aileron, rudder: [`super::Airframe::actuators`]) driven through it: one state per
    /// actuator appended after the aircraft's (named as `sim` records the surface,
    /// `elevator_rad` …), `ẋ = (u − x)/τ` with the command `u` as the input (named
    /// `elevator_cmd_rad` …), the surface's column of `B` moved into `A` as that state's
    /// column. Rigid-body rows are unchanged, and the surfaces do not feed back, so the
    /// eigenvalues are the aircraft's and `−1/τ` per actuator (computed from the whole `A`),
    /// and [`Self::modes`] are unchanged. A model without actuators is returned as it is.
    pub fn with_actuators(
        mut self,
        actuators: &[Option<aeroident_io::mapping::Actuator>; 3],
    ) -> Self {
        let n0 = self.a.len();
        for (k, (act, (surface, state, input))) in actuators.iter().zip(SURFACES).enumerate() {
            let Some(actuator) = act else { continue };
            let (index, control) = (self.a.len(), 1 + k);
            for (row_a, row_b) in self.a.iter_mut().zip(self.b.iter_mut()) {
                row_a.push(std::mem::take(&mut row_b[control]));
            }
            let mut row = vec![0.0; index + 1];
            row[index] = -1.0 / actuator.tau_s;
            self.a.push(row);
            let mut b = vec![0.0; N_CONTROLS];
            b[control] = 1.0 / actuator.tau_s;
            self.b.push(b);
            self.states.push(state.to_string());
            self.inputs[control] = input.to_string();
            let trim_rad = self.trim.controls[control];
            self.actuators.push(ActuatorState {
                surface,
                state,
                input,
                index,
                control,
                actuator: *actuator,
                trim_rad,
            });
        }
        if self.a.len() > n0 {
            self.eigenvalues = eigenvalues_of(&self.a);
        }
        self
    }

    /// [`ACTUATOR_NOTE`], and a note per actuator whose trim deflection lies at or beyond
    /// its position limits (the surface is then held there, and the linear model does not
    /// hold); empty without actuators.
    pub fn actuator_notes(&self) -> Vec<String> {
        if self.actuators.is_empty() {
            return Vec::new();
        }
        let mut notes = vec![ACTUATOR_NOTE.to_string()];
        for s in &self.actuators {
            let (lo, hi) = s.actuator.position_limits_rad;
            if !(lo < s.trim_rad && s.trim_rad < hi) {
                notes.push(format!(
                    "{}: the trim deflection {:.4} rad is at or beyond the actuator's position limits [{lo}, {hi}] rad: the surface saturates there and the linear model does not hold",
                    s.surface, s.trim_rad
                ));
            }
        }
        notes
    }
}

/// Eigenvalues of the square `a` (rows) as (real, imaginary), sorted as
/// [`aeroident_models::linearize::eigenvalues`] sorts them.
fn eigenvalues_of(a: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let n = a.len();
    let m = nalgebra::DMatrix::from_fn(n, n, |i, j| a[i][j]);
    aeroident_models::linearize::eigenvalues_dyn(m).iter().map(|e| (e.re, e.im)).collect()
}

impl AnyAircraft {
    /// The F-16 at cg `xcg` (fraction of c̄).
    ///
    /// # Errors
    /// `xcg` outside the model's range.
    pub fn f16(xcg: f64) -> Result<Self> {
        Ok(Self::F16(Box::new(F16::new(xcg)?)))
    }

    /// The same F-16 with increments `values` (vocabulary names, `Cm_alpha`, `Cm_de`, `Cl_p` …,
    /// per rad or per unit hat-rate) about the trim `(state, controls)`, acting from `onset_s`
    /// (always when `None`): a sudden damage at `onset_s`.
    ///
    /// # Errors
    /// A model-file aircraft (it flies its own derivatives: change them in its summary), a
    /// name the increment matrix cannot express, a non-finite value or onset, or a state of
    /// the wrong length.
    pub fn with_increments(
        self,
        values: &[(String, f64)],
        state: &[f64],
        controls: &[f64; N_CONTROLS],
        onset_s: Option<f64>,
    ) -> Result<Self> {
        let Self::F16(f) = self else {
            return Err(PipelineError::msg(
                "increments act on the F-16 only: a model-file aircraft flies the derivatives of its summary; change them there",
            ));
        };
        let x = f16_state(state)?;
        let params = values
            .iter()
            .map(|(n, v)| {
                let p = parse_increment(n).map_err(|e| PipelineError::msg(format!("{n}: {e}")))?;
                finite(n, *v).map(|v| (p, v))
            })
            .collect::<Result<Vec<(Param, f64)>>>()?;
        let reference = IncrementReference {
            alpha_rad: x[f16::ALPHA],
            beta_rad: x[f16::BETA],
            p_rad_s: x[f16::P],
            q_rad_s: x[f16::Q],
            r_rad_s: x[f16::R],
            elevator_rad: controls[1],
            aileron_rad: controls[2],
            rudder_rad: controls[3],
        };
        let schedule = match onset_s {
            None => IncrementSchedule::Always,
            Some(t0) => IncrementSchedule::StepAt { t0_s: finite("onset_s", t0)? },
        };
        let inc = increment_matrix(reference, &params);
        Ok(Self::F16(Box::new((*f).with_increments(inc, schedule))))
    }

    /// A short name for reports.
    pub fn name(&self) -> String {
        match self {
            Self::F16(a) => a.name(),
            Self::ModelFile(a) => a.name(),
        }
    }

    /// The states' names with their units, in state order.
    pub fn state_names(&self) -> Vec<&'static str> {
        match self {
            Self::F16(a) => a.state_names().to_vec(),
            Self::ModelFile(a) => a.state_names().to_vec(),
        }
    }

    /// The controls' names ([`CONTROL_NAMES`]) and what the engine command is.
    pub fn control_names(&self) -> ([&'static str; N_CONTROLS], &'static str) {
        let engine = match self {
            Self::F16(a) => a.engine_command(),
            Self::ModelFile(a) => a.engine_command(),
        };
        (CONTROL_NAMES, engine)
    }

    /// Steady wings-level, level flight at `vt_mps` (m/s) and `alt_m` (m).
    ///
    /// # Errors
    /// An invalid condition or a trim that does not converge.
    pub fn trim_level(&self, vt_mps: f64, alt_m: f64) -> Result<Trim> {
        Ok(match self {
            Self::F16(a) => plain_trim(&a.trim_level(vt_mps, alt_m)?),
            Self::ModelFile(a) => plain_trim(&a.trim_level(vt_mps, alt_m)?),
        })
    }

    /// The state derivative at `t_s` (s; the F-16's damage onset reads it), state units per s.
    ///
    /// # Errors
    /// A state of the wrong length, or outside the model's domain.
    pub fn derivatives(
        &self,
        t_s: f64,
        state: &[f64],
        controls: &[f64; N_CONTROLS],
    ) -> Result<Vec<f64>> {
        match self {
            Self::F16(a) => xdot(a.as_ref(), t_s, state, controls),
            Self::ModelFile(a) => xdot(a.as_ref(), t_s, state, controls),
        }
    }

    /// The state `dt_s` later: one classical RK4 step with the controls held
    /// ([`rk4_step`]).
    ///
    /// # Errors
    /// As [`Self::derivatives`], or `dt_s` not positive and finite.
    pub fn step(
        &self,
        t_s: f64,
        state: &[f64],
        controls: &[f64; N_CONTROLS],
        dt_s: f64,
    ) -> Result<Vec<f64>> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(PipelineError::msg(format!(
                "dt_s = {dt_s}: a step must be positive and finite"
            )));
        }
        match self {
            Self::F16(a) => step_of(a.as_ref(), t_s, state, controls, dt_s),
            Self::ModelFile(a) => step_of(a.as_ref(), t_s, state, controls, dt_s),
        }
    }

    /// The linear model about the wings-level trim at `vt_mps`, `alt_m`
    /// ([`linearize_level`]).
    ///
    /// # Errors
    /// The trim's, or a model error at a perturbed point.
    pub fn linearize_level(&self, vt_mps: f64, alt_m: f64) -> Result<Linear> {
        match self {
            Self::F16(a) => linear_of(a.as_ref(), vt_mps, alt_m),
            Self::ModelFile(a) => linear_of(a.as_ref(), vt_mps, alt_m),
        }
    }

    /// [`Self::linearize_level`] with the mapping's actuators as states
    /// ([`Linear::with_actuators`]: the surfaces' inputs become their commands); the F-16's
    /// model, and a model-file aircraft without actuators, as [`Self::linearize_level`].
    ///
    /// # Errors
    /// As [`Self::linearize_level`].
    pub fn linearize_level_actuated(&self, vt_mps: f64, alt_m: f64) -> Result<Linear> {
        let l = self.linearize_level(vt_mps, alt_m)?;
        Ok(match self {
            Self::F16(_) => l,
            Self::ModelFile(a) => l.with_actuators(&a.airframe().actuators),
        })
    }

    /// The exact (noise-free) air-data sample of the F-16 at `t_s`, the one the sample-driven
    /// estimators take ([`exact_sample`]: SI, ṗ q̇ ṙ α̇ from the dynamics, thrust from the
    /// engine model); `v0_mps` is the reference airspeed of the `V/V0` term.
    ///
    /// # Errors
    /// A model-file aircraft (not yet), a state of the wrong length or outside the domain.
    pub fn sample(
        &self,
        t_s: f64,
        state: &[f64],
        controls: &[f64; N_CONTROLS],
        v0_mps: f64,
    ) -> Result<AirDataSample> {
        let Self::F16(f) = self else {
            return Err(PipelineError::msg("the air-data sample is written for the F-16 only"));
        };
        let x = f16_state(state)?;
        let u = f.input(&ControlVector::from_row_slice(controls));
        let (xd, out) = f.evaluate(&x, &u, &f.increments_at(t_s))?;
        Ok(exact_sample(f, f16_constants(f, v0_mps), t_s, &x, &xd, &out, &u))
    }

    /// Metres per length unit of the states (the F-16's ft: 0.3048).
    pub fn length_unit_m(&self) -> f64 {
        match self {
            Self::F16(_) => M_PER_FT,
            Self::ModelFile(a) => a.length_unit_m(),
        }
    }
}

fn finite(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() { Ok(v) } else { Err(PipelineError::msg(format!("{name} = {v}: not finite"))) }
}

fn f16_state(state: &[f64]) -> Result<SVector<f64, { f16::N_STATES }>> {
    vector(state)
}

fn vector<const N: usize>(state: &[f64]) -> Result<SVector<f64, N>> {
    if state.len() != N {
        return Err(PipelineError::msg(format!(
            "the state has {} values; this aircraft has {N} states",
            state.len()
        )));
    }
    Ok(SVector::from_column_slice(state))
}

pub(crate) fn plain_trim<const N: usize>(t: &aeroident_models::aircraft::AircraftTrim<N>) -> Trim {
    Trim {
        state: t.state.iter().copied().collect(),
        controls: core::array::from_fn(|i| t.controls[i]),
        max_abs_residual: t.max_abs_residual,
    }
}

fn xdot<const N: usize, A: Aircraft<N>>(
    a: &A,
    t_s: f64,
    state: &[f64],
    controls: &[f64; N_CONTROLS],
) -> Result<Vec<f64>> {
    let u = a.input(&ControlVector::from_row_slice(controls));
    Ok(a.derivatives(t_s, &vector::<N>(state)?, &u)?.iter().copied().collect())
}

fn step_of<const N: usize, A: Aircraft<N>>(
    a: &A,
    t_s: f64,
    state: &[f64],
    controls: &[f64; N_CONTROLS],
    dt_s: f64,
) -> Result<Vec<f64>> {
    let u = a.input(&ControlVector::from_row_slice(controls));
    let x = rk4_step(a, t_s, &vector::<N>(state)?, &u, dt_s)?;
    Ok(x.iter().copied().collect())
}

fn linear_of<const N: usize, A: Aircraft<N>>(a: &A, vt_mps: f64, alt_m: f64) -> Result<Linear> {
    Ok(Linear::of_level(a, &linearize_level(a, vt_mps, alt_m)?))
}

impl Linear {
    /// The plain-vector form of `l`, a linearization of `aircraft`: its state names, and the
    /// inputs named as `linearize` prints them (the engine command with its unit, then the
    /// surfaces of [`CONTROL_NAMES`]); no actuator ([`Self::with_actuators`] adds them).
    pub fn of_level<const N: usize, A: Aircraft<N>>(
        aircraft: &A,
        l: &LevelLinearization<N>,
    ) -> Self {
        let rows = |m: &dyn Fn(usize, usize) -> f64, cols: usize| -> Vec<Vec<f64>> {
            (0..N).map(|i| (0..cols).map(|j| m(i, j)).collect()).collect()
        };
        let mut inputs = vec![aircraft.engine_command().to_string()];
        inputs.extend(CONTROL_NAMES[1..].iter().map(|n| n.to_string()));
        Linear {
            trim: plain_trim(&l.trim),
            a: rows(&|i, j| l.linear.a[(i, j)], N),
            b: rows(&|i, j| l.linear.b[(i, j)], N_CONTROLS),
            eigenvalues: l.eigenvalues.iter().map(|e| (e.re, e.im)).collect(),
            modes: l.modes.clone(),
            states: aircraft.state_names().iter().map(|n| n.to_string()).collect(),
            inputs,
            actuators: Vec::new(),
        }
    }
}
