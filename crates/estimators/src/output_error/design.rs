//! Experiment design before flight: the predicted Cramér–Rao σ of every derivative for a
//! planned input at a flight condition, so that an engineer can choose amplitudes, durations
//! and sensors before flying.
//!
//! Sources: Klein & Morelli, *Aircraft System Identification*, AIAA 2006, ch. 6 (the
//! Cramér–Rao bound, the Fisher information of output error) and ch. 9 (input design, the
//! information matrix as the design criterion); Jategaonkar, *Flight Vehicle System
//! Identification*, 2nd ed., AIAA 2015, ch. 2 (input design, 3-2-1-1 and doublets) and ch. 4
//! (`M = Σ Sᵀ R⁻¹ S`). Section and equation numbers are not quoted: they were not checked
//! against the books.
//!
//! # Method
//!
//! 1. The plan's flight condition ([`FlightCondition`]: wings-level straight flight, `β = p =
//!    q = r = φ = 0`) gives a sample for every planned time step: the states at the condition,
//!    the controls at their trim values plus the planned perturbations ([`PlannedInputs`]),
//!    thrust and density constant.
//! 2. The model is simulated from the condition under the planned controls with the assumed
//!    parameters `θ` by the output-error simulation itself ([`super::fit`]'s RK4 with inputs
//!    linear between samples and its exact sensitivities `S = ∂y/∂β`, the discrete RK4 map
//!    differentiated through the flight model's dual partials): no second simulator.
//! 3. `M = repeats · Σ_i S_iᵀ R⁻¹ S_i` with `R = diag(σ_j²)` the sensor noise of the planned
//!    outputs ([`Sensor`]); identical repeats from the same condition add their information.
//!    The unknowns `β` are those a fit with the same configuration estimates: the structure's
//!    parameters, the planned output biases and the free initial states
//!    ([`DesignPlan::initial_states`]; [`InitialStates::FirstSample`] here means the initial
//!    state is known, the condition itself).
//! 4. **Identifiability** (never inverting a singular `M`): an unknown with `M_ii = 0` does not
//!    affect any planned output. The others are Jacobi-scaled (`M̃ = D M D`,
//!    `D = diag(M_ii^−½)`, unit diagonal) and decomposed, `M̃ = V Λ Vᵀ`; eigenvalues below
//!    [`DesignPlan::singular_tolerance`] · `λ_max` span the null space. An unknown whose unit
//!    vector has a squared projection on that null space above [`NULL_LOADING_TOL`] is **not
//!    identifiable** (its variance is unbounded). Every other unknown is an estimable function:
//!    its bound is `σ_i² = D_i² (M̃⁺)_ii` with the pseudo-inverse `M̃⁺ = Σ_{λ>tol} v vᵀ/λ`, equal
//!    to `(M⁻¹)_ii` when `M` is regular (Klein & Morelli 2006 ch. 6). The condition number is
//!    `λ_max/λ_min` of `M̃` (infinite when an unknown is not identifiable).
//! 5. `σ/|θ|` per unknown makes amplitude and duration trade-offs readable; the largest output
//!    excursion from the condition shows whether the planned input keeps the response small
//!    (the bound assumes the model holds over it); the state rates at the condition with the
//!    trim controls show whether `θ` trims the aircraft there ([`trim_biases`] makes it so).
//!
//! The bound is a prediction for white Gaussian sensor noise of the stated σ and a correct
//! model; on flight data with turbulence and model error the achieved σ are larger (the
//! coloured-residual σ of [`super::OeResult::sigma_coloured`]). The tests check the prediction
//! against the scatter of [`super::fit`] over seeded noisy simulations of the plan. For an
//! experiment flown in turbulence, [`predict_crb_turbulent`] ([`frequency`]) counts the gusts
//! as process noise.
//!
//! # Inputs
//!
//! Planned control perturbations are sampled arrays (rad) with a constant interval. The
//! estimators crate does not build them: the application does (e.g. from the
//! `aeroident_signals` crate's 3-2-1-1, doublets and multisines), so that this core stays free
//! of a dependency on signal generation.
//!
//! # Errors
//!
//! [`EstimatorError::InvalidConfig`] naming the field: `theta` of the wrong length or not
//! finite; no manoeuvre; `dt_s` not finite and positive; planned arrays of different lengths,
//! fewer than two samples or all empty; no sensor, a sensor σ not finite and positive, an
//! output the structure's state set does not predict or selected twice; `repeats` = 0;
//! `singular_tolerance` outside (0, 1); a structure without a state set; an absent aircraft
//! constant the model needs. [`EstimatorError::NonFiniteInput`] /
//! [`EstimatorError::ImplausibleInput`] naming a condition or planned value that is not finite
//! or not physical. [`EstimatorError::Numerical`] when the simulated response leaves the
//! physical domain (the planned input is too large or `θ` is unstable there).

use super::simulation::Problem;
use super::{InitialStates, normal_equations, unknown_names};
use crate::EstimatorError;
use crate::flight_model::{FlightModel, G0_MPS2, N_STATES, Output, STATE_NAMES, StateSet, state};
use crate::sample::{AirDataSample, AircraftConstants};
use crate::vocabulary::{Coefficient, ModelStructure, Param, Term};
use core::fmt;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::format;
use std::string::String;
use std::vec;
use std::vec::Vec;

/// An unknown whose unit vector has a squared projection on the null space of the scaled
/// information matrix above this is not identifiable (module doc).
pub const NULL_LOADING_TOL: f64 = 1e-6;

/// The flight condition of a plan: wings-level straight flight (`β = p = q = r = φ = 0`) at
/// airspeed, angle of attack and pitch attitude (`θ = α` is level flight), with constant
/// density and thrust, and the trim control deflections the planned perturbations are added to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightCondition {
    /// True airspeed, m/s.
    pub vt_mps: f64,
    /// Angle of attack, rad.
    pub alpha_rad: f64,
    /// Pitch attitude, rad.
    pub theta_rad: f64,
    /// Air density, kg/m³ (`q̄ = ½ ρ V²`).
    pub rho_kgpm3: f64,
    /// Thrust, N (along the thrust line of [`AircraftConstants::thrust_incidence_rad`]).
    pub thrust_n: f64,
    /// Trim elevator, rad.
    pub de_rad: f64,
    /// Trim aileron, rad.
    pub da_rad: f64,
    /// Trim rudder, rad.
    pub dr_rad: f64,
}

impl FlightCondition {
    /// Level flight (`θ = α`) with the controls at 0.
    pub fn level(vt_mps: f64, alpha_rad: f64, rho_kgpm3: f64, thrust_n: f64) -> Self {
        Self {
            vt_mps,
            alpha_rad,
            theta_rad: alpha_rad,
            rho_kgpm3,
            thrust_n,
            de_rad: 0.0,
            da_rad: 0.0,
            dr_rad: 0.0,
        }
    }

    /// Dynamic pressure `½ ρ V²`, Pa.
    pub fn qbar_pa(&self) -> f64 {
        0.5 * self.rho_kgpm3 * self.vt_mps * self.vt_mps
    }
}

/// The planned control perturbations of one manoeuvre (added to the trim deflections of the
/// [`FlightCondition`]), sampled every `dt_s` from `t = 0`. An empty array is a control held
/// at trim; the non-empty ones must have the same length (≥ 2), which sets the duration
/// `(n − 1) dt`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlannedInputs {
    /// Sample interval, s.
    pub dt_s: f64,
    /// Elevator perturbation, rad.
    pub de_rad: Vec<f64>,
    /// Aileron perturbation, rad.
    pub da_rad: Vec<f64>,
    /// Rudder perturbation, rad.
    pub dr_rad: Vec<f64>,
}

impl PlannedInputs {
    /// Number of samples.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] for arrays of different lengths, all empty or shorter
    /// than two samples, or a `dt_s` that is not finite and positive.
    pub fn n_samples(&self) -> Result<usize, EstimatorError> {
        if !(self.dt_s > 0.0 && self.dt_s.is_finite()) {
            return Err(invalid("dt_s", self.dt_s, "must be finite and > 0"));
        }
        let mut n = None;
        for (field, v) in
            [("de_rad", &self.de_rad), ("da_rad", &self.da_rad), ("dr_rad", &self.dr_rad)]
        {
            if v.is_empty() {
                continue;
            }
            match n {
                None => n = Some(v.len()),
                Some(m) if m != v.len() => {
                    return Err(invalid(
                        field,
                        v.len() as f64,
                        "planned input arrays must have the same length",
                    ));
                }
                Some(_) => {}
            }
        }
        match n {
            None => {
                Err(invalid("de_rad", 0.0, "no planned input (de_rad, da_rad, dr_rad all empty)"))
            }
            Some(m) if m < 2 => {
                Err(invalid("de_rad", m as f64, "a planned manoeuvre needs at least two samples"))
            }
            Some(m) => Ok(m),
        }
    }

    /// Duration `(n − 1) dt`, s (0 when [`PlannedInputs::n_samples`] fails).
    pub fn duration_s(&self) -> f64 {
        self.n_samples().map_or(0.0, |n| (n - 1) as f64 * self.dt_s)
    }

    fn at(v: &[f64], i: usize) -> f64 {
        v.get(i).copied().unwrap_or(0.0)
    }
}

/// A planned measured output and its white sensor noise σ (output units: m/s, rad, rad/s,
/// m/s², rad/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensor {
    /// The output.
    pub output: Output,
    /// Noise standard deviation, units of the output.
    pub sigma: f64,
}

/// A planned experiment (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignPlan {
    /// The model structure to be identified.
    pub structure: ModelStructure,
    /// Assumed parameter values, structure order (a prior or a previous identification; the
    /// bias terms should trim the aircraft at the condition, see [`trim_biases`]).
    pub theta: Vec<f64>,
    /// Aircraft constants (those the structure's flight model needs).
    pub constants: AircraftConstants,
    /// The flight condition every manoeuvre starts from.
    pub condition: FlightCondition,
    /// The planned manoeuvres (each from the condition; their information adds).
    pub manoeuvres: Vec<PlannedInputs>,
    /// The measured outputs and their noise.
    pub sensors: Vec<Sensor>,
    /// Identical repeats of the whole set of manoeuvres (≥ 1).
    pub repeats: usize,
    /// Outputs whose constant bias the fit will estimate (nuisance unknowns).
    pub output_biases: Vec<Output>,
    /// Initial states the fit will estimate per manoeuvre (nuisance unknowns);
    /// [`InitialStates::FirstSample`]: the initial state is known.
    pub initial_states: InitialStates,
    /// Relative eigenvalue of the scaled information matrix below which a direction is
    /// singular (module doc; default 10⁻¹⁰).
    pub singular_tolerance: f64,
}

impl DesignPlan {
    /// A plan with one repeat, no output biases, the initial state known and the default
    /// singular tolerance 10⁻¹⁰.
    pub fn new(
        structure: ModelStructure,
        theta: Vec<f64>,
        constants: AircraftConstants,
        condition: FlightCondition,
        manoeuvres: Vec<PlannedInputs>,
        sensors: Vec<Sensor>,
    ) -> Self {
        Self {
            structure,
            theta,
            constants,
            condition,
            manoeuvres,
            sensors,
            repeats: 1,
            output_biases: Vec::new(),
            initial_states: InitialStates::FirstSample,
            singular_tolerance: 1e-10,
        }
    }
}

/// The predicted accuracy of a plan (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignResult {
    /// Names of the unknowns: the structure's parameters (`Cm_alpha` …), then the output
    /// biases (`bias_<output>`), then the free initial states (`x0_m<k>_<state>`).
    pub names: Vec<String>,
    /// Number of structure parameters (the first entries of `names`).
    pub n_params: usize,
    /// The assumed values (θ, biases 0, initial states at the condition).
    pub values: Vec<f64>,
    /// Predicted Cramér–Rao σ; `None`: not identifiable from this plan.
    pub sigma: Vec<Option<f64>>,
    /// `σ / |value|`; `None` when not identifiable or the value is 0.
    pub relative_sigma: Vec<Option<f64>>,
    /// Predicted correlation, row-major `n × n`; `None` where an unknown is not identifiable.
    pub correlation: Vec<Option<f64>>,
    /// The information matrix `M` (including the repeats), row-major `n × n`, in the units of
    /// `1 / (unknown_i · unknown_j)`. Information of independent plans adds.
    pub information: Vec<f64>,
    /// `λ_max / λ_min` of the Jacobi-scaled `M`; `f64::INFINITY` when an unknown is not
    /// identifiable.
    pub condition_number: f64,
    /// Names of the unknowns that are not identifiable.
    pub not_identifiable: Vec<String>,
    /// The planned outputs.
    pub outputs: Vec<Output>,
    /// Largest `|y − y(t₀)|` per output over the manoeuvres, noise free, output units.
    pub output_excursion: Vec<f64>,
    /// State rates at the condition with the trim controls, `(state field name, rate)` for
    /// the integrated states (rad/s, m/s², rad/s²); all ≈ 0 when `θ` trims the aircraft.
    pub trim_rates: Vec<(&'static str, f64)>,
    /// Samples of one repeat (all manoeuvres).
    pub n_samples: usize,
    /// Repeats.
    pub repeats: usize,
}

impl DesignResult {
    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.names.len()
    }

    /// Index of an unknown by name.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Predicted σ of an unknown by name (`None`: unknown name, or not identifiable).
    pub fn sigma_of(&self, name: &str) -> Option<f64> {
        self.index_of(name).and_then(|i| self.sigma[i])
    }

    /// Predicted correlation of unknowns `i` and `j`.
    pub fn correlation(&self, i: usize, j: usize) -> Option<f64> {
        self.correlation[i * self.n() + j]
    }
}

impl fmt::Display for DesignResult {
    /// A printable table: unknown, assumed value, predicted σ, σ/|value|.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "predicted Cramér–Rao bounds: {} unknowns, {} outputs, {} samples × {} repeat(s), condition number {:.3e}",
            self.n(),
            self.outputs.len(),
            self.n_samples,
            self.repeats,
            self.condition_number
        )?;
        writeln!(f, "{:<22} {:>12} {:>12} {:>10}", "unknown", "assumed", "σ_CRB", "σ/|θ|")?;
        for i in 0..self.n() {
            let s = self.sigma[i].map_or("not identif.".into(), |v| format!("{v:.5}"));
            let r = self.relative_sigma[i].map_or("—".into(), |v| format!("{:.1} %", 100.0 * v));
            writeln!(f, "{:<22} {:>12.5} {:>12} {:>10}", self.names[i], self.values[i], s, r)?;
        }
        writeln!(f, "{:<14} {:>12}", "output", "excursion")?;
        for (o, e) in self.outputs.iter().zip(&self.output_excursion) {
            writeln!(f, "{:<14} {:>12.5}", o.name(), e)?;
        }
        Ok(())
    }
}

fn invalid(field: &'static str, value: f64, reason: &'static str) -> EstimatorError {
    EstimatorError::InvalidConfig { field, value, reason }
}

/// The sample at the condition at time `t_s` with controls `(δe, δa, δr)` (absolute, rad):
/// the state set's states and outputs at their trim values, the other states as inputs
/// (trim), the specific force that balances gravity (`ax = g sin θ`, `ay = 0`,
/// `az = −g cos θ`).
fn condition_sample(
    constants: &AircraftConstants,
    c: &FlightCondition,
    set: StateSet,
    t_s: f64,
    controls: [f64; 3],
) -> AirDataSample {
    let lat = set.lat().then_some(0.0);
    AirDataSample {
        t_s,
        vt_mps: c.vt_mps,
        alpha_rad: c.alpha_rad,
        qbar_pa: c.qbar_pa(),
        // The longitudinal set takes β, p, r, φ as absent (symmetric flight) so that it does
        // not need the lateral inertias.
        beta_rad: lat,
        p_rad_s: lat,
        r_rad_s: lat,
        phi_rad: lat,
        pdot_rad_s2: lat,
        rdot_rad_s2: lat,
        ay_mps2: lat,
        q_rad_s: Some(0.0),
        qdot_rad_s2: Some(0.0),
        theta_rad: Some(c.theta_rad),
        alphadot_rad_s: Some(0.0),
        ax_mps2: Some(G0_MPS2 * c.theta_rad.sin()),
        az_mps2: Some(-G0_MPS2 * c.theta_rad.cos()),
        de_rad: Some(controls[0]),
        da_rad: Some(controls[1]),
        dr_rad: Some(controls[2]),
        thrust_n: Some(c.thrust_n),
        rho_kgpm3: Some(c.rho_kgpm3),
        constants: *constants,
        ..Default::default()
    }
}

/// The samples of one planned manoeuvre (module doc, step 1).
fn planned_samples(
    plan: &DesignPlan,
    set: StateSet,
    m: &PlannedInputs,
) -> Result<Vec<AirDataSample>, EstimatorError> {
    let n = m.n_samples()?;
    let c = &plan.condition;
    Ok((0..n)
        .map(|i| {
            let controls = [
                c.de_rad + PlannedInputs::at(&m.de_rad, i),
                c.da_rad + PlannedInputs::at(&m.da_rad, i),
                c.dr_rad + PlannedInputs::at(&m.dr_rad, i),
            ];
            condition_sample(&plan.constants, c, set, i as f64 * m.dt_s, controls)
        })
        .collect())
}

fn check_theta(structure: &ModelStructure, theta: &[f64]) -> Result<(), EstimatorError> {
    if theta.len() != structure.n_params() {
        return Err(invalid("theta", theta.len() as f64, "one value per structure parameter"));
    }
    if let Some(v) = theta.iter().find(|v| !v.is_finite()) {
        return Err(invalid("theta", *v, "must be finite"));
    }
    Ok(())
}

/// The prepared output-error problem of a plan, its nominal unknowns and the noise weights.
struct Prepared {
    problem: Problem,
    beta: Vec<f64>,
    weights: Vec<f64>,
}

fn prepare(plan: &DesignPlan) -> Result<Prepared, EstimatorError> {
    check_theta(&plan.structure, &plan.theta)?;
    if plan.manoeuvres.is_empty() {
        return Err(invalid("manoeuvres", 0.0, "at least one planned manoeuvre is needed"));
    }
    if plan.sensors.is_empty() {
        return Err(invalid("sensors", 0.0, "at least one planned output is needed"));
    }
    for s in &plan.sensors {
        if !(s.sigma > 0.0 && s.sigma.is_finite()) {
            return Err(invalid(s.output.name(), s.sigma, "sensor noise σ must be finite and > 0"));
        }
    }
    if plan.repeats == 0 {
        return Err(invalid("repeats", 0.0, "at least one repeat"));
    }
    if !(plan.singular_tolerance > 0.0 && plan.singular_tolerance < 1.0) {
        return Err(invalid("singular_tolerance", plan.singular_tolerance, "must be in (0, 1)"));
    }
    let model = FlightModel::new(plan.structure)?;
    let set = model.state_set();
    let records: Vec<Vec<AirDataSample>> =
        plan.manoeuvres.iter().map(|m| planned_samples(plan, set, m)).collect::<Result<_, _>>()?;
    let slices: Vec<&[AirDataSample]> = records.iter().map(Vec::as_slice).collect();
    let outputs: Vec<Output> = plan.sensors.iter().map(|s| s.output).collect();
    let x0_free = match plan.initial_states {
        InitialStates::FirstSample => [false; N_STATES],
        InitialStates::Estimate(mask) => mask,
    };
    let problem = Problem::new(model, &slices, outputs, &plan.output_biases, &x0_free)?;
    let mut beta = vec![0.0; problem.n_unknowns];
    beta[..problem.np].copy_from_slice(&plan.theta);
    for (m, man) in problem.man.iter().enumerate() {
        for (q, &k) in problem.x0_free.iter().enumerate() {
            beta[problem.x0_index(m, q)] = man.x0_meas[k];
        }
    }
    let weights = plan.sensors.iter().map(|s| 1.0 / (s.sigma * s.sigma)).collect();
    Ok(Prepared { problem, beta, weights })
}

/// Identifiability analysis of an information matrix (module doc, step 4).
struct Analysis {
    sigma: Vec<Option<f64>>,
    correlation: Vec<Option<f64>>,
    condition_number: f64,
}

fn analyse(m: &DMatrix<f64>, tolerance: f64) -> Analysis {
    let n = m.nrows();
    let active: Vec<usize> = (0..n).filter(|&i| m[(i, i)] > 0.0 && m[(i, i)].is_finite()).collect();
    let na = active.len();
    let d: Vec<f64> = active.iter().map(|&i| 1.0 / m[(i, i)].sqrt()).collect();
    let scaled = DMatrix::from_fn(na, na, |a, b| m[(active[a], active[b])] * d[a] * d[b]);
    let mut sigma = vec![None; n];
    let mut correlation = vec![None; n * n];
    if na == 0 {
        return Analysis { sigma, correlation, condition_number: f64::INFINITY };
    }
    let eig = SymmetricEigen::new(scaled);
    let lambda = &eig.eigenvalues;
    let v = &eig.eigenvectors;
    let lmax = lambda.max();
    let regular: Vec<bool> = lambda.iter().map(|&l| l > tolerance * lmax).collect();
    let identifiable: Vec<bool> = (0..na)
        .map(|a| {
            let loading: f64 =
                (0..na).filter(|&k| !regular[k]).map(|k| v[(a, k)] * v[(a, k)]).sum();
            loading <= NULL_LOADING_TOL
        })
        .collect();
    let pinv = |a: usize, b: usize| -> f64 {
        (0..na).filter(|&k| regular[k]).map(|k| v[(a, k)] * v[(b, k)] / lambda[k]).sum()
    };
    let diag: Vec<f64> = (0..na).map(|a| pinv(a, a)).collect();
    for a in 0..na {
        if !identifiable[a] {
            continue;
        }
        sigma[active[a]] = Some(d[a] * diag[a].sqrt());
        for b in 0..na {
            if identifiable[b] {
                correlation[active[a] * n + active[b]] =
                    Some(if a == b { 1.0 } else { pinv(a, b) / (diag[a] * diag[b]).sqrt() });
            }
        }
    }
    let condition_number =
        if na == n && regular.iter().all(|r| *r) { lmax / lambda.min() } else { f64::INFINITY };
    Analysis { sigma, correlation, condition_number }
}

/// Predicts the Cramér–Rao σ of every unknown of a planned experiment (module doc): simulates
/// the model from the condition under the planned inputs with the output-error simulation and
/// its exact sensitivities, forms `M = repeats · Σ Sᵀ R⁻¹ S`, and reports σ, correlation,
/// condition number and the unknowns that are not identifiable.
///
/// # Errors
/// As in the module doc.
pub fn predict_crb(plan: &DesignPlan) -> Result<DesignResult, EstimatorError> {
    let Prepared { problem: p, beta, weights } = prepare(plan)?;
    let nb = p.n_unknowns;
    let (mut y, mut s) = (Vec::new(), Vec::new());
    p.simulate(&beta, &mut y, Some(&mut s))?;
    let zeros = vec![0.0; y.len()];
    let (mut m, _, _) = normal_equations(&s, &zeros, &weights, nb);
    m *= plan.repeats as f64;
    analyse_and_report(plan, &p, beta, &y, m)
}

/// The [`DesignResult`] of an information matrix `m` (repeats included) of the prepared
/// problem `p` of `plan` at unknowns `beta`, with the noise-free simulated outputs `y`.
fn analyse_and_report(
    plan: &DesignPlan,
    p: &Problem,
    beta: Vec<f64>,
    y: &[f64],
    m: DMatrix<f64>,
) -> Result<DesignResult, EstimatorError> {
    let ny = p.ny();
    let a = analyse(&m, plan.singular_tolerance);
    let names = unknown_names(p, &plan.structure);
    let not_identifiable =
        names.iter().zip(&a.sigma).filter(|(_, s)| s.is_none()).map(|(n, _)| n.clone()).collect();
    let relative_sigma = a
        .sigma
        .iter()
        .zip(&beta)
        .map(|(s, v)| s.filter(|_| *v != 0.0).map(|s| s / v.abs()))
        .collect();
    // Largest excursion of each output from its value at the start of its manoeuvre.
    let mut output_excursion = vec![0.0_f64; ny];
    let mut row0 = 0;
    for man in &p.man {
        let n = man.u.len();
        for i in 0..n {
            for j in 0..ny {
                let dy = (y[(row0 + i) * ny + j] - y[row0 * ny + j]).abs();
                output_excursion[j] = output_excursion[j].max(dy);
            }
        }
        row0 += n;
    }
    let model = p.model;
    let set = model.state_set();
    let c = &plan.condition;
    let trim = condition_sample(&plan.constants, c, set, 0.0, [c.de_rad, c.da_rad, c.dr_rad]);
    let u = model.inputs(&trim)?;
    let active = condition_states(c, set);
    let f = model.derivatives(&plan.theta, &u, &active[..set.states().len()])?;
    let trim_rates =
        set.states().iter().enumerate().map(|(k, &i)| (STATE_NAMES[i], f[k])).collect();
    Ok(DesignResult {
        names,
        n_params: p.np,
        values: beta,
        sigma: a.sigma,
        relative_sigma,
        correlation: a.correlation,
        information: m.transpose().as_slice().to_vec(),
        condition_number: a.condition_number,
        not_identifiable,
        outputs: p.outputs.clone(),
        output_excursion,
        trim_rates,
        n_samples: p.n_samples,
        repeats: plan.repeats,
    })
}

/// The integrated states at the condition, filter order.
fn condition_states(c: &FlightCondition, set: StateSet) -> [f64; N_STATES] {
    let mut full = [0.0; N_STATES];
    full[state::V] = c.vt_mps;
    full[state::ALPHA] = c.alpha_rad;
    full[state::THETA] = c.theta_rad;
    let mut active = [0.0; N_STATES];
    for (k, &i) in set.states().iter().enumerate() {
        active[k] = full[i];
    }
    active
}

/// `θ` with the bias terms set so that the model is in equilibrium at the condition with the
/// trim controls: `V̇ = α̇ = q̇ = 0` by the force pair's and `Cm`'s biases (`CL_0, CD_0` or
/// `CX_0, CZ_0`, and `Cm_0`) and `β̇ = ṗ = ṙ = 0` by `CY_0, Cl_0, Cn_0`, whichever the
/// structure's state set integrates (`θ̇ = φ̇ = 0` follow from `p = q = r = φ = 0`). The
/// rates are affine in the biases; Newton's method with the flight model's exact partials
/// ([`FlightModel::linearise`]) converges in one step and is run to `|ẋ| ≤ 10⁻⁹`.
///
/// # Errors
/// [`EstimatorError::InvalidConfig`] naming a bias term the structure lacks (e.g. `Cm_0`) or a
/// wrong `theta`; errors of the model's inputs as [`predict_crb`];
/// [`EstimatorError::Numerical`] when the biases cannot trim the aircraft (singular system).
pub fn trim_biases(
    structure: &ModelStructure,
    theta: &[f64],
    constants: &AircraftConstants,
    condition: &FlightCondition,
) -> Result<Vec<f64>, EstimatorError> {
    use Coefficient as C;
    check_theta(structure, theta)?;
    let model = FlightModel::new(*structure)?;
    let set = model.state_set();
    let c = condition;
    let sample = condition_sample(constants, c, set, 0.0, [c.de_rad, c.da_rad, c.dr_rad]);
    crate::estimator::check_finite(&sample)?;
    let u = model.inputs(&sample)?;
    let mut coefs: Vec<Coefficient> = Vec::new();
    let mut dynamic: Vec<usize> = Vec::new();
    if set.lon() {
        coefs.extend(if structure.has(C::CL) { [C::CL, C::CD] } else { [C::CX, C::CZ] });
        coefs.push(C::Cm);
        dynamic.extend([state::V, state::ALPHA, state::Q]);
    }
    if set.lat() {
        coefs.extend([C::CY, C::Cl, C::Cn]);
        dynamic.extend([state::BETA, state::P, state::R]);
    }
    let states = set.states();
    let rows: Vec<usize> =
        dynamic.iter().map(|d| states.iter().position(|s| s == d).unwrap_or(0)).collect();
    let cols: Vec<usize> = coefs
        .iter()
        .map(|&k| {
            let p = Param::new(k, Term::Bias);
            structure.index_of(p).ok_or(invalid(
                p.name(),
                f64::NAN,
                "the structure has no bias term for this coefficient: it cannot be trimmed",
            ))
        })
        .collect::<Result<_, _>>()?;
    let active = condition_states(c, set);
    let nx = states.len();
    let mut th = theta.to_vec();
    let mut lin = crate::flight_model::Linearisation::default();
    let n = rows.len();
    for _ in 0..4 {
        model.linearise(&th, &u, &active[..nx], &mut lin)?;
        if rows.iter().all(|&r| lin.f[r].abs() <= 1e-9) {
            return Ok(th);
        }
        let j = DMatrix::from_fn(n, n, |a, b| lin.dfdtheta[rows[a]][cols[b]]);
        let f = DVector::from_fn(n, |a, _| -lin.f[rows[a]]);
        let step = j.lu().solve(&f).filter(|s| s.iter().all(|v| v.is_finite())).ok_or(
            EstimatorError::Numerical {
                what: "trim: the biases do not control the state rates",
                t_s: 0.0,
            },
        )?;
        for (b, &col) in cols.iter().enumerate() {
            th[col] += step[b];
        }
    }
    Err(EstimatorError::Numerical { what: "trim: the state rates did not vanish", t_s: 0.0 })
}

pub mod frequency;
pub use frequency::predict_crb_turbulent;

#[cfg(test)]
mod tests;

/// The records a plan predicts: per planned manoeuvre, the samples of step 1 (module doc) with
/// every planned output replaced by the model's simulated response under the assumed `θ` plus
/// `noise(j)` for sensor `j` (return 0 for the noise-free response). With white noise of the
/// sensors' σ these are the data whose output-error estimates scatter as [`predict_crb`] says:
/// the Monte Carlo check of a design (each manoeuvre simulated from the condition, initial
/// states as measured at the condition).
///
/// # Errors
/// As [`predict_crb`].
pub fn simulate_plan(
    plan: &DesignPlan,
    noise: &mut dyn FnMut(usize) -> f64,
) -> Result<Vec<Vec<AirDataSample>>, EstimatorError> {
    let Prepared { problem, beta, .. } = prepare(plan)?;
    let mut y = Vec::new();
    problem.simulate(&beta, &mut y, None)?;
    let set = problem.model.state_set();
    let ny = problem.ny();
    let mut offset = 0;
    let mut out = Vec::with_capacity(plan.manoeuvres.len());
    for m in &plan.manoeuvres {
        let mut data = planned_samples(plan, set, m)?;
        for s in data.iter_mut() {
            for (j, sensor) in plan.sensors.iter().enumerate() {
                sensor.output.set_measured(s, y[offset + j] + noise(j));
            }
            offset += ny;
        }
        out.push(data);
    }
    Ok(out)
}
