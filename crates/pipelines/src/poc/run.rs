//! The proof-of-concept simulation loop (thesis Figure 3.2 / 4.19): reference system and
//! estimated model integrated side by side with fixed-step RK4, the estimator in between.
//!
//! Per step `k` (t = k·dt): `u = input(t)`; measured `z_m = z_true + n_z(t)`,
//! `ż_m = f(t, z_true, u; θ) + n_ż(t)` (noise only in table 4.6 cases; `n_ż` optional); the estimator consumes
//! `(t, z_est, z_m, ż_m, u)` and returns θ̂; then both systems advance one RK4 step with `u`
//! held (zero-order hold), the estimated model with θ̂ held.

use super::adapter::ModelAdapter;
use super::scenario::{GainConfig, NoiseTarget, PocScenario, SystemConfig};
use aeroident_estimators::ParametricEstimator;
use aeroident_estimators::smpe::{
    CorrectedConfig, CorrectedSmpe, GainForm, ParamSpec, PublishedSmpe, Reading, SlidingSurface,
    SmpeConfig, SmpeSample, SolveStats,
};
use aeroident_models::Dynamics;
use aeroident_models::integrate::rk4_step;
use aeroident_models::parametric::Parameterized;
use aeroident_models::small::{FirstOrder, FirstOrderNonlinear, SecondOrder, SecondOrderNonlinear};
use aeroident_signals::{BandLimitedWhiteNoise, InputSignal};
use nalgebra::SVector;
use std::time::Instant;

/// Which estimator to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorKind {
    /// The thesis's estimator (3.20)–(3.99).
    Published,
    /// The corrected estimator of `docs/smpe-corrected.md`.
    Corrected,
}

/// Reading of the published estimator's implicit equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverReading {
    /// Solve for θ̂ at every sample (default).
    Implicit,
    /// Previous sample's θ̂ on the right-hand side.
    Explicit,
}

impl crate::Named for EstimatorKind {
    const ALL: &'static [Self] = &[EstimatorKind::Published, EstimatorKind::Corrected];

    fn name(self) -> &'static str {
        match self {
            EstimatorKind::Published => "published",
            EstimatorKind::Corrected => "corrected",
        }
    }
}

impl crate::Named for SolverReading {
    const ALL: &'static [Self] = &[SolverReading::Implicit, SolverReading::Explicit];

    fn name(self) -> &'static str {
        match self {
            SolverReading::Implicit => "implicit",
            SolverReading::Explicit => "explicit",
        }
    }
}

impl SolverReading {
    fn reading(self) -> Reading {
        match self {
            Self::Implicit => Reading::Implicit,
            Self::Explicit => Reading::Explicit,
        }
    }
}

/// Errors of a run. Each names the scenario.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The estimator configuration was rejected.
    #[error("scenario `{scenario}`: estimator configuration: {source}")]
    Config {
        /// Scenario name.
        scenario: String,
        /// Cause.
        source: aeroident_estimators::EstimatorError,
    },
    /// The estimator failed at a sample.
    #[error("scenario `{scenario}`: estimator failed: {source}")]
    Estimator {
        /// Scenario name.
        scenario: String,
        /// Cause.
        source: aeroident_estimators::EstimatorError,
    },
    /// A model evaluation failed.
    #[error("scenario `{scenario}`: model failed at t = {t_s} s: {source}")]
    Model {
        /// Scenario name.
        scenario: String,
        /// Time, s.
        t_s: f64,
        /// Cause.
        source: aeroident_models::ModelError,
    },
    /// The input or noise could not be built.
    #[error("scenario `{scenario}`: signal: {source}")]
    Signal {
        /// Scenario name.
        scenario: String,
        /// Cause.
        source: aeroident_signals::SignalError,
    },
}

/// Everything a run produced, sample by sample (index k ↔ `t_s[k]`).
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// Scenario name.
    pub scenario: String,
    /// Estimator used.
    pub estimator: EstimatorKind,
    /// Reading used (`None` for the corrected estimator, which has no implicit equation).
    pub solver: Option<SolverReading>,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// State names (`x`, `y`, `xdot`).
    pub state_names: Vec<&'static str>,
    /// Reference states, `[state][k]`.
    pub states_true: Vec<Vec<f64>>,
    /// Estimated-model states, `[state][k]`.
    pub states_est: Vec<Vec<f64>>,
    /// Parameter names.
    pub param_names: Vec<&'static str>,
    /// True parameter values.
    pub truth: Vec<f64>,
    /// Estimates, `[param][k]`.
    pub estimates: Vec<Vec<f64>>,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall time of the simulation loop, s.
    pub wall_s: f64,
    /// Why the run stopped before `duration_s`, if it did.
    pub stopped_early: Option<String>,
    /// Solver counters of the published estimator.
    pub stats: Option<SolveStats>,
}

impl RunOutput {
    /// Simulated seconds per wall-clock second of the simulation loop.
    pub fn realtime_factor(&self) -> f64 {
        if self.wall_s > 0.0 { self.simulated_s / self.wall_s } else { f64::INFINITY }
    }
}

/// Runs one scenario with the chosen estimator and reading.
///
/// # Errors
/// [`RunError`] when the estimator rejects its configuration or fails, a model evaluation
/// fails, or the input cannot be built.
pub fn run(
    sc: &PocScenario,
    estimator: EstimatorKind,
    solver: SolverReading,
) -> Result<RunOutput, RunError> {
    match sc.system {
        SystemConfig::FirstOrder { a, initial_state } => {
            let x0 = SVector::from(initial_state.unwrap_or([0.0]));
            dispatch(
                sc,
                FirstOrder { a },
                x0,
                ["x"],
                SlidingSurface::first_order(&[0]),
                estimator,
                solver,
            )
        }
        SystemConfig::FirstOrderNonlinear { a, B, C, omega_rad_s, initial_state } => {
            let x0 = SVector::from(initial_state.unwrap_or([0.0; 2]));
            let m = FirstOrderNonlinear { a, B, C, omega_rad_s };
            dispatch(sc, m, x0, ["x", "y"], SlidingSurface::first_order(&[0, 1]), estimator, solver)
        }
        SystemConfig::SecondOrder { a1, a2, initial_state } => {
            second_order(sc, SecondOrder { a1, a2 }, initial_state, estimator, solver)
        }
        SystemConfig::SecondOrderNonlinear { a1, a2, initial_state } => {
            second_order(sc, SecondOrderNonlinear { a1, a2 }, initial_state, estimator, solver)
        }
    }
}

fn param_specs<const P: usize>(sc: &PocScenario, names: [&'static str; P]) -> [ParamSpec; P] {
    core::array::from_fn(|j| {
        let p = &sc.parameters[j];
        ParamSpec {
            name: names[j],
            lower: p.lower,
            upper: p.upper,
            lambda: p.lambda,
            initial: p
                .initial
                .or_else(|| ParamSpec::geometric_mean(p.lower, p.upper))
                .unwrap_or(0.5 * (p.lower + p.upper)),
        }
    })
}

/// A second-order system (states `x`, `ẋ`, the second-order sliding surface over them)
/// through [`dispatch`].
fn second_order<D, const P: usize>(
    sc: &PocScenario,
    truth: D,
    initial_state: Option<[f64; 2]>,
    estimator: EstimatorKind,
    solver: SolverReading,
) -> Result<RunOutput, RunError>
where
    D: Dynamics<2, Input = f64> + Parameterized<P> + Clone,
{
    let x0 = SVector::from(initial_state.unwrap_or([0.0; 2]));
    let surface = SlidingSurface::second_order(0, 1);
    dispatch(sc, truth, x0, ["x", "xdot"], surface, estimator, solver)
}

fn dispatch<D, const N: usize, const P: usize>(
    sc: &PocScenario,
    truth: D,
    x0: SVector<f64, N>,
    state_names: [&'static str; N],
    surface: Result<SlidingSurface<N>, aeroident_estimators::EstimatorError>,
    estimator: EstimatorKind,
    solver: SolverReading,
) -> Result<RunOutput, RunError>
where
    D: Dynamics<N, Input = f64> + Parameterized<P> + Clone,
{
    let name = sc.case.name.clone();
    let cfg_err = |source| RunError::Config { scenario: name.clone(), source };
    let surface = surface.map_err(cfg_err)?;
    let params = param_specs::<P>(sc, truth.param_names());
    let lambda_max = params.iter().map(|p| p.lambda).fold(0.0, f64::max);
    match estimator {
        EstimatorKind::Published => {
            let cfg = SmpeConfig {
                params,
                eta: sc.estimator.eta,
                surface,
                gain: match sc.estimator.gain {
                    GainConfig::Shared => GainForm::Shared,
                    GainConfig::PerParameter => GainForm::PerParameter,
                },
                reading: solver.reading(),
            };
            let est = PublishedSmpe::new(ModelAdapter(truth.clone()), cfg).map_err(cfg_err)?;
            let (mut out, est) = simulate(sc, truth, x0, state_names, est)?;
            out.estimator = estimator;
            out.solver = Some(solver);
            out.stats = Some(est.stats());
            Ok(out)
        }
        EstimatorKind::Corrected => {
            let cfg = CorrectedConfig {
                params,
                sliding: surface.rate,
                lambda_per_s: lambda_max,
                information_per_s: sc.estimator.corrected_information_per_s,
                tracking_weight: sc.estimator.corrected_tracking_weight,
                forgetting_per_s: sc.estimator.corrected_forgetting_per_s,
            };
            let est = CorrectedSmpe::new(ModelAdapter(truth.clone()), cfg).map_err(cfg_err)?;
            let (mut out, _) = simulate(sc, truth, x0, state_names, est)?;
            out.estimator = estimator;
            out.solver = None;
            Ok(out)
        }
    }
}

fn simulate<D, E, const N: usize, const P: usize>(
    sc: &PocScenario,
    truth: D,
    x0: SVector<f64, N>,
    state_names: [&'static str; N],
    mut est: E,
) -> Result<(RunOutput, E), RunError>
where
    D: Dynamics<N, Input = f64> + Parameterized<P> + Clone,
    E: ParametricEstimator<P, Sample = SmpeSample<N, f64>>,
{
    let name = sc.case.name.clone();
    let sig_err = |source| RunError::Signal { scenario: name.clone(), source };
    let input = sc.input.build().map_err(sig_err)?;
    let dt = sc.simulation.dt_s;
    let steps = (sc.simulation.duration_s / dt).round() as usize;
    // 2N noise channels: z_m[i] uses seed + i, ż_m[i] uses seed + N + i.
    let noise: Option<Vec<BandLimitedWhiteNoise>> = match &sc.noise {
        None => None,
        Some(n) => Some(
            (0..2 * N)
                .map(|k| {
                    BandLimitedWhiteNoise::new(
                        n.noise_power,
                        n.sample_time_s.unwrap_or(dt),
                        n.seed.wrapping_add(k as u64),
                    )
                })
                .collect::<Result<_, _>>()
                .map_err(sig_err)?,
        ),
    };
    let model_err = |t_s, source| RunError::Model { scenario: name.clone(), t_s, source };
    let theta_true = truth.params();
    let mut out = RunOutput {
        scenario: name.clone(),
        estimator: EstimatorKind::Published,
        solver: None,
        t_s: Vec::with_capacity(steps + 1),
        state_names: state_names.to_vec(),
        states_true: vec![Vec::with_capacity(steps + 1); N],
        states_est: vec![Vec::with_capacity(steps + 1); N],
        param_names: truth.param_names().to_vec(),
        truth: theta_true.iter().copied().collect(),
        estimates: vec![Vec::with_capacity(steps + 1); P],
        simulated_s: 0.0,
        wall_s: 0.0,
        stopped_early: None,
        stats: None,
    };
    let start = Instant::now();
    let mut x = x0;
    let mut z = x0;
    let max_abs = sc.simulation.max_abs_state;
    for k in 0..=steps {
        let t = k as f64 * dt;
        let u = input.value(t);
        let xdot = truth.derivatives(t, &x, &u).map_err(|e| model_err(t, e))?;
        let (mut z_m, mut zdot_m) = (x, xdot);
        if let (Some(ch), Some(cfg)) = (&noise, &sc.noise) {
            for i in 0..N {
                z_m[i] += ch[i].value(t);
                if cfg.apply_to == NoiseTarget::StatesAndDerivatives {
                    zdot_m[i] += ch[N + i].value(t);
                }
            }
        }
        let sample = SmpeSample { t_s: t, z, z_m, zdot_m, u };
        let theta = est
            .update(&sample)
            .map_err(|source| RunError::Estimator { scenario: name.clone(), source })?
            .theta;
        out.t_s.push(t);
        for i in 0..N {
            out.states_true[i].push(x[i]);
            out.states_est[i].push(z[i]);
        }
        for j in 0..P {
            out.estimates[j].push(theta[j]);
        }
        out.simulated_s = t;
        if k == steps {
            break;
        }
        let x_next = rk4_step(&truth, t, &x, &u, dt).map_err(|e| model_err(t, e))?;
        let estimated = truth.with_params(&theta);
        let z_next = rk4_step(&estimated, t, &z, &u, dt).map_err(|e| model_err(t, e))?;
        let out_of_range = |v: &SVector<f64, N>| v.iter().any(|s| s.is_nan() || s.abs() > max_abs);
        if out_of_range(&x_next) {
            out.stopped_early =
                Some(format!("reference system left |state| ≤ {max_abs:e} at t = {:.3} s", t + dt));
            break;
        }
        if out_of_range(&z_next) {
            out.stopped_early =
                Some(format!("estimated model left |state| ≤ {max_abs:e} at t = {:.3} s", t + dt));
            break;
        }
        x = x_next;
        z = z_next;
    }
    out.wall_s = start.elapsed().as_secs_f64();
    Ok((out, est))
}
