//! The estimation experiment of any [`FlyableAircraft`] ([`AircraftExperiment`]; the faces
//! load a model-file aircraft, [`crate::airframe::ModelFileAircraft`]: a model file's structure
//! with identified values and a mapping's constants), one run or a Monte Carlo campaign of
//! them (`aeroident run|montecarlo SCENARIO --aircraft MODEL.toml
//! --map M [--summary S] --estimator rls,oe`).
//!
//! # One run ([`ModelFileExperiment::fly`])
//! 1. The scenario (`kind = "sim"`, [`crate::sim::aircraft`]) is flown from its wings-level
//!    trim with its inputs and `[[sensor]]` noise.
//! 2. The record goes through the mapping of a flight record
//!    ([`crate::sim::aircraft::replay_mapping`]: the sensed columns where a sensor exists, the
//!    true ones elsewhere, no state derivative unless sensed) to every estimator asked for, as `aeroident replay` would take it
//!    with `--model MODEL.toml`: the real-time estimators sample by sample
//!    ([`crate::replay::replay`]), the batch fits over the whole record
//!    ([`crate::replay::fit::fit_records`], default options). No compatibility corrections and
//!    no cross-check: the record is what the scenario's sensors make of the true flight.
//! 3. Each parameter's truth is the value the aircraft flew
//!    ([`FlyableAircraft::flown_values`] about the scenario's trim; for a model-file aircraft the summary's estimate,
//!    or the model file's `[reference.<param>]`): the reference of the run's result.
//!
//! # A campaign ([`ModelFileExperiment::campaign_watched`])
//! Run `i` of a campaign with seed `S` flies the scenario with its run seed replaced by
//! [`super::run_seed`]`(S, i, 0)`, and every sensor's own `seed` dropped so that each sensor's
//! seed derives from the run's ([`aeroident_signals::SensorConfig::build`]): each run draws new
//! noise, and a run depends only on `(S, i)`. The statistics are [`super::statistics`]'s
//! (module doc of [`crate::montecarlo`]): bias, scatter, mean σ, ±2σ coverage, and the time
//! from the start of the record until a real-time estimate stays within ±10 % of the truth.
//!
//! # Cramér–Rao bound ([`ModelFileExperiment::crb`])
//! The output-error information of the noise-free flight
//! ([`aeroident_estimators::output_error::design::predict_crb`]): the model file's structure
//! at the flown values, from the trim condition
//! ([`FlyableAircraft::flight_condition`]), the flown surface
//! perturbations, the initial state known, and the outputs of the scenario's sensors with
//! their white-noise σ. Only a sensor with white noise and nothing else (no bias, scale,
//! Gauss–Markov, lag, delay or quantum) counts; an output the fit reads without noise is left
//! out of the bound (its information is unbounded); a throttle input is not in the bound (the
//! design's engine is held). Notes say what was left out.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use aeroident_estimators::flight_model::N_STATES;
use aeroident_estimators::flight_model::Output;
use aeroident_estimators::output_error::InitialStates;
use aeroident_estimators::output_error::design::{DesignPlan, PlannedInputs, Sensor, predict_crb};
use aeroident_io::{Mapping, ModelSpec, ParameterResult};
use aeroident_models::rigid_body as rb;
use rayon::prelude::*;

use super::{Campaign, CrbTable, EstimatorRun, ParamRun, Ran, RunResult, document, run_seed};
use crate::Named as _;
use crate::aircraft::summary::PRIMARY_DERIVATIVES;
use crate::airframe::{FlyableAircraft, ModelFileAircraft};
use crate::estimators::EstimatorKind;
use crate::replay::batch::FitOptions;
use crate::sim::aircraft::{AircraftSimRun, replay_mapping, run as fly_scenario};
use crate::sim::scenario::{Channel, SimScenario};

/// Tolerance of the time to converge, relative to the truth (the `run` experiment's ±10 %).
const TIME_TOL_REL: f64 = 0.10;

/// An aircraft of `N` states, the scenario it flies and the estimators that identify it.
#[derive(Debug, Clone)]
pub struct AircraftExperiment<const N: usize, A> {
    /// The aircraft flown (its [`FlyableAircraft::flown_values`] are the truth).
    pub aircraft: A,
    /// The model the estimators fit (the aircraft's model file, with its priors and ranges).
    pub model: ModelSpec,
    /// The scenario (`kind = "sim"`, without `[aircraft]`).
    pub scenario: SimScenario,
    /// Where the scenario's relative paths (recorded inputs) resolve.
    pub base_dir: PathBuf,
    /// The estimators, each run on every record.
    pub estimators: Vec<EstimatorKind>,
}

/// The experiment of a model-file aircraft, as the faces load it ([`Self::load`]).
pub type ModelFileExperiment = AircraftExperiment<{ crate::airframe::N_STATES }, ModelFileAircraft>;

/// One flown run: the record, the mapping that replays it, and each estimator's result.
#[derive(Debug, Clone)]
pub struct FlownRun {
    /// The simulated record.
    pub sim: AircraftSimRun,
    /// The mapping of the record ([`replay_mapping`]), TOML.
    pub mapping: String,
    /// Per estimator, in [`AircraftExperiment::estimators`] order.
    pub estimators: Vec<EstimatorRun>,
}

/// The files of a model-file experiment, as a face names them.
#[derive(Debug, Clone, Copy)]
pub struct ExperimentFiles<'a> {
    /// The model file (`models/*.toml`): the structure flown and fitted.
    pub model: &'a Path,
    /// A replay's `summary.json` giving the values flown (default: the model file's
    /// `[reference.<param>]` values).
    pub summary: Option<&'a Path>,
    /// The mapping whose constants give mass, inertia, geometry, thrust line and law.
    pub map: &'a Path,
    /// The scenario (`kind = "sim"`).
    pub scenario: &'a Path,
}

impl ModelFileExperiment {
    /// The experiment of `files` with the estimators named in `estimators` (e.g. `rls`, `oe`).
    ///
    /// # Errors
    /// Files that do not describe a flyable aircraft or a scenario (naming file and field),
    /// an unknown estimator (listing the known ones), and [`Self::check`]'s.
    pub fn load(files: ExperimentFiles<'_>, estimators: &[String]) -> crate::error::Result<Self> {
        let aircraft = crate::airframe::load(files.model, files.summary, files.map)?;
        let model = ModelSpec::from_path(files.model).map_err(|e| crate::err!("{e}"))?;
        let scenario = crate::sim::load_scenario(files.scenario)?;
        let base_dir = files.scenario.parent().unwrap_or(Path::new(".")).to_path_buf();
        let estimators = estimators
            .iter()
            .map(|e| {
                EstimatorKind::from_name(e).ok_or_else(|| {
                    crate::err!(
                        "--estimator `{e}`: no such estimator (known: {})",
                        EstimatorKind::names().join(", ")
                    )
                })
            })
            .collect::<crate::error::Result<Vec<_>>>()?;
        let x = Self { aircraft, model, scenario, base_dir, estimators };
        x.check()?;
        Ok(x)
    }
}

impl FlownRun {
    /// The run's `summary.json`: `{"schema_version", "aircraft", "run_seed", "trim": {"state",
    /// "controls"}, "estimators": [{"name", "failure", "restarts", "iterations",
    /// "fit_wall_s", "params": [{ParameterResult keys (`reference`: the value flown),
    /// "primary", "time_to_10pct_s", …}]}]}` (SI; the trim's state in
    /// [`crate::airframe::STATE_NAMES`] order, its controls engine command, elevator, aileron,
    /// rudder).
    pub fn document(&self, run_seed: u64) -> serde_json::Value {
        serde_json::json!({
            "schema_version": aeroident_io::SCHEMA_VERSION,
            "aircraft": self.sim.aircraft,
            "run_seed": run_seed,
            "trim": {"state": self.sim.trim.state, "controls": self.sim.trim.controls},
            "estimators": self.estimators,
        })
    }
}

impl<const N: usize, A: FlyableAircraft<N>> AircraftExperiment<N, A> {
    /// Refuses what cannot make an experiment before anything is flown.
    ///
    /// # Errors
    /// No estimator, or one named twice; a model whose structure is not the aircraft's (the
    /// truth of a parameter the aircraft does not fly is unknown).
    pub fn check(&self) -> crate::error::Result<()> {
        if self.estimators.is_empty() {
            crate::bail!("--estimator: name at least one estimator (e.g. rls,oe)");
        }
        for (i, e) in self.estimators.iter().enumerate() {
            if self.estimators[..i].contains(e) {
                crate::bail!("--estimator: `{}` is named twice", e.name());
            }
        }
        if self.model.structure != self.aircraft.flown_structure() {
            crate::bail!(
                "model `{}`: the estimators' structure is not the aircraft's: the truth of a term the aircraft does not fly is unknown",
                self.model.name
            );
        }
        Ok(())
    }

    /// The value the aircraft flies for the parameter named `name` about the scenario's trim
    /// (`None`: no such parameter, or no trim).
    pub fn truth(&self, name: &str) -> Option<f64> {
        self.truth_at(&self.scenario).ok()?.get(name)
    }

    /// The values the aircraft flies about the trim of `sc`
    /// ([`FlyableAircraft::flown_values`]).
    ///
    /// # Errors
    /// The trim's or the values'.
    fn truth_at(&self, sc: &SimScenario) -> crate::error::Result<Truth> {
        let (vt_mps, alt_m) = sc.trim.si()?;
        let trim = self.aircraft.trim_level(vt_mps, alt_m)?;
        let values = self.aircraft.flown_values(&trim)?;
        let names = self.aircraft.flown_structure().names().map(String::from).collect();
        Ok(Truth { names, values })
    }

    /// The scenario of run `run` of a campaign seeded `campaign_seed` (module doc).
    pub fn seeded(&self, campaign_seed: u64, run: u64) -> SimScenario {
        let mut sc = self.scenario.clone();
        sc.run.seed = run_seed(campaign_seed, run, 0);
        for s in &mut sc.sensor {
            s.seed = None;
        }
        sc
    }

    /// Flies `sc` and runs every estimator on its record (module doc).
    ///
    /// # Errors
    /// The flight itself fails (no trim, a bad input, a model error); an estimator's failure
    /// is in its [`EstimatorRun::failure`] instead.
    pub fn fly(&self, sc: &SimScenario) -> crate::error::Result<FlownRun> {
        let sim = fly_scenario(&self.aircraft, sc, &self.base_dir)?;
        let mapping = replay_mapping(&self.aircraft, &sim);
        let parsed = Mapping::from_toml_str(&mapping, "mapping.toml")
            .map_err(|e| crate::err!("the record's mapping: {e}"))?;
        let truth = self.truth_at(sc)?;
        let flown = Flown { sim: &sim, mapping: &parsed, truth: &truth };
        let estimators = self.estimators.iter().map(|k| self.estimate(*k, &flown)).collect();
        Ok(FlownRun { sim, mapping, estimators })
    }

    /// One estimator's result on the record `flown`.
    fn estimate(&self, kind: EstimatorKind, flown: &Flown<'_>) -> EstimatorRun {
        let mut run = EstimatorRun::named(kind.name());
        let done = if kind.is_batch() {
            self.fit(kind, flown, &mut run)
        } else {
            self.replay(kind, flown, &mut run)
        };
        if let Err(e) = done {
            run.failure = Some(e);
        }
        run
    }

    /// A real-time estimator through the record: its final estimates and the time each took
    /// to stay within ±10 % of the truth.
    fn replay(
        &self,
        kind: EstimatorKind,
        flown: &Flown<'_>,
        run: &mut EstimatorRun,
    ) -> Result<(), String> {
        let (mapping, truth) = (flown.mapping, flown.truth);
        let reader = reader_of(flown.sim, mapping)?;
        let opts = crate::replay::ReplayOptions {
            estimator: kind,
            model: Some(self.model.clone()),
            ..Default::default()
        };
        let out =
            crate::replay::replay(reader, mapping, &opts, &mut ()).map_err(|e| e.to_string())?;
        if let Some(e) = out.diverged_error(kind.name()) {
            return Err(e);
        }
        run.restarts = out.summary.events.counts.get("restart").copied().unwrap_or(0);
        let h = &out.history;
        run.params = out
            .summary
            .parameters
            .iter()
            .map(|p| {
                let i = h.names.iter().position(|n| *n == p.result.name);
                let t10 = i.and_then(|i| time_to_10pct(h, i, truth.get(&p.result.name)?));
                param_run(p.result.clone(), t10, truth)
            })
            .collect();
        Ok(())
    }

    /// A batch fit of the whole record: its estimates, iterations and wall time.
    fn fit(
        &self,
        kind: EstimatorKind,
        flown: &Flown<'_>,
        run: &mut EstimatorRun,
    ) -> Result<(), String> {
        let mapping = flown.mapping;
        let reader = reader_of(flown.sim, mapping)?;
        let estimate = [("initial_states", toml::Value::String("estimate".into()))];
        let pairs = if kind.options().contains(&"initial_states") { &estimate[..] } else { &[] };
        let options =
            FitOptions::from_pairs(kind, pairs.iter().cloned()).map_err(|e| e.to_string())?;
        let model = Some(self.model.clone());
        let out = crate::replay::fit::fit_records(vec![reader], mapping, model, options)
            .map_err(|e| e.to_string())?;
        let s = &out.summary;
        if s.still_moving() {
            return Err(format!(
                "the fit did not converge ({})",
                s.status_reason.as_deref().unwrap_or("iteration limit")
            ));
        }
        run.iterations = Some(s.iterations.len());
        run.fit_wall_s = Some(s.fit_wall_s);
        run.params =
            s.parameters.iter().map(|p| param_run(p.result.clone(), None, flown.truth)).collect();
        Ok(())
    }
}

/// A parameter's result with the flown value (`truth`) as its reference: the check beside the
/// verdict is made again against it (the model file's reference, if the fit saw one, is
/// another aircraft's value: its findings go with it).
fn param_run(mut result: ParameterResult, t10: Option<f64>, truth: &Truth) -> ParamRun {
    let truth = truth.get(&result.name);
    result.reference = truth;
    result.reference_check = None;
    result.check_reference();
    ParamRun {
        primary: PRIMARY_DERIVATIVES.contains(&result.name.as_str()),
        truth_before: truth,
        truth_after: truth,
        time_to_10pct_s: t10,
        reconvergence_10pct_s: None,
        result,
    }
}

/// Time from the record's start until parameter `i` of `h` stays within ±10 % of `truth` to
/// the end (`None`: it never does).
fn time_to_10pct(h: &crate::replay::History, i: usize, truth: f64) -> Option<f64> {
    let est: Vec<f64> = h.values.iter().map(|v| v[i].unwrap_or(f64::NAN)).collect();
    let t0 = *h.t_s.first()?;
    crate::metrics::convergence_time_s(&h.t_s, &est, truth, TIME_TOL_REL)
        .ok()
        .flatten()
        .map(|t| t - t0)
}

/// The values an aircraft flies about a trim, by parameter name.
#[derive(Debug, Clone)]
struct Truth {
    names: Vec<String>,
    values: Vec<f64>,
}

impl Truth {
    /// The value of the parameter named `name`.
    fn get(&self, name: &str) -> Option<f64> {
        self.names.iter().position(|n| n == name).map(|i| self.values[i])
    }
}

/// One flown record: the run, the mapping that reads it, the values flown.
struct Flown<'a> {
    sim: &'a AircraftSimRun,
    mapping: &'a Mapping,
    truth: &'a Truth,
}

/// The record of `sim` as a reader through `mapping` (in memory, as a file would be read).
fn reader_of(sim: &AircraftSimRun, mapping: &Mapping) -> Result<aeroident_io::LogReader, String> {
    let table = aeroident_io::table::Table {
        file: "simulated record".into(),
        names: sim.table.columns.clone(),
        columns: sim.table.data.clone(),
    };
    let source = aeroident_io::RecordSource::Table(table);
    aeroident_io::Record::open(source, None, mapping).map(|r| r.reader).map_err(|e| e.to_string())
}

impl<const N: usize, A: FlyableAircraft<N>> AircraftExperiment<N, A> {
    /// The Cramér–Rao σ of the model's parameters for the scenario's flight (module doc), for
    /// every estimator alike, with notes of what the bound leaves out.
    pub fn crb(&self) -> CrbTable {
        let mut table = CrbTable::default();
        match self.crb_sigmas(&mut table.notes) {
            Ok(sigmas) => {
                for e in &self.estimators {
                    table.sigma.insert(e.name().to_string(), sigmas.clone());
                    table.calm.insert(e.name().to_string(), sigmas.clone());
                }
                table.notes.push(
                    "crb_std_error: calm air (the model-file aircraft flies no turbulence), = crb_std_error_calm".into(),
                );
            }
            Err(e) => table.notes.push(format!("no Cramér–Rao bound: {e}")),
        }
        table
    }

    /// The bound by parameter name (module doc).
    fn crb_sigmas(&self, notes: &mut Vec<String>) -> Result<BTreeMap<String, f64>, String> {
        let sensors = crb_sensors(&self.scenario, notes);
        if sensors.is_empty() {
            return Err("no sensor of the scenario has white noise alone".into());
        }
        let mut clean = self.scenario.clone();
        clean.sensor.clear();
        let sim =
            fly_scenario(&self.aircraft, &clean, &self.base_dir).map_err(|e| e.to_string())?;
        if clean.input.iter().any(|i| i.channel == Channel::Throttle) {
            notes.push("the throttle inputs are not in the Cramér–Rao bound (engine held)".into());
        }
        let trim = self.aircraft.trim_level(sim.trim.state[rb::VT], sim.trim.state[rb::ALT]);
        let trim = trim.map_err(|e| e.to_string())?;
        let condition = self
            .aircraft
            .flight_condition(&trim.state, &trim.controls)
            .map_err(|e| e.to_string())?;
        let theta = self.aircraft.flown_values(&trim).map_err(|e| e.to_string())?;
        let mut plan = DesignPlan::new(
            self.aircraft.flown_structure(),
            theta,
            self.aircraft.constants(),
            condition,
            vec![planned_inputs(&sim, &clean)?],
            sensors,
        );
        plan.initial_states = InitialStates::Estimate([true; N_STATES]);
        let r = predict_crb(&plan).map_err(|e| e.to_string())?;
        Ok(r.names
            .iter()
            .take(r.n_params)
            .zip(&r.sigma)
            .filter_map(|(n, s)| s.map(|s| (n.clone(), s)))
            .collect())
    }
}

/// The surface perturbations of the noise-free flight `sim` about its trim.
fn planned_inputs(sim: &AircraftSimRun, sc: &SimScenario) -> Result<PlannedInputs, String> {
    let column = |name: &str, trim: f64| -> Result<Vec<f64>, String> {
        let c = sim.table.column(name).ok_or_else(|| format!("no column `{name}`"))?;
        Ok(c.iter().map(|v| v - trim).collect())
    };
    let u = &sim.trim.controls;
    Ok(PlannedInputs {
        dt_s: sc.run.dt_s,
        de_rad: column("elevator_rad", u[1])?,
        da_rad: column("aileron_rad", u[2])?,
        dr_rad: column("rudder_rad", u[3])?,
    })
}

/// The bound's outputs: each scenario sensor on an output the flight model predicts with
/// white noise and nothing else, its σ in SI. The others are named in `notes`.
fn crb_sensors(sc: &SimScenario, notes: &mut Vec<String>) -> Vec<Sensor> {
    let mut sensors: Vec<Sensor> = Vec::new();
    for s in &sc.sensor {
        let Some(output) = output_of(&s.channel) else { continue };
        let only_white = s.bias == 0.0
            && s.scale == 1.0
            && s.gauss_markov_sigma.is_none_or(|g| g == 0.0)
            && s.lag_tau_s.is_none()
            && s.delay_s.is_none_or(|d| d == 0.0)
            && s.delay_samples.is_none_or(|d| d == 0)
            && s.quantum.is_none();
        if s.white_sigma > 0.0 && only_white && !sensors.iter().any(|x| x.output == output) {
            sensors.push(Sensor { output, sigma: s.white_sigma });
        } else {
            notes.push(format!(
                "sensor `{}` is not in the Cramér–Rao bound (it counts white noise alone)",
                s.channel
            ));
        }
    }
    sensors
}

/// The flight-model output a simulated channel measures (the output's own name is the
/// simulation's column name, SI units in it).
fn output_of(channel: &str) -> Option<Output> {
    Output::ALL.into_iter().find(|o| o.name() == channel)
}

impl<const N: usize, A: FlyableAircraft<N>> AircraftExperiment<N, A> {
    /// Refuses a campaign that cannot be one before anything is flown.
    ///
    /// # Errors
    /// As [`Self::check`]; `runs` = 0 or above [`super::MAX_RUNS`]; a scenario with no sensor
    /// noise (every run would be the same flight).
    pub fn check_campaign(&self, runs: u64) -> Result<(), String> {
        self.check().map_err(|e| e.to_string())?;
        super::check_runs(runs, "runs")?;
        if !self.scenario.sensor.iter().any(|s| s.white_sigma > 0.0) {
            return Err("the scenario has no [[sensor]] with white noise: every run would fly the same record (add sensors, docs/aircraft.md)".into());
        }
        Ok(())
    }

    /// A campaign of `runs` seeded flights (module doc) in parallel, starting no further run
    /// once `stop` is set, calling `on_run` as each run ends.
    ///
    /// # Errors
    /// As [`Self::check_campaign`].
    pub fn campaign_watched(
        &self,
        runs: u64,
        seed: u64,
        stop: Option<&AtomicBool>,
        on_run: &(dyn Fn() + Sync),
    ) -> Result<Campaign, String> {
        self.check_campaign(runs)?;
        let start = Instant::now();
        let results: Vec<RunResult> = (0..runs)
            .into_par_iter()
            .filter_map(|i| {
                if stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
                    return None;
                }
                let sc = self.seeded(seed, i);
                let outcome = self.fly(&sc).map(|f| f.estimators).map_err(|e| e.to_string());
                on_run();
                Some(RunResult { index: i, sensor_seed: sc.run.seed, outcome })
            })
            .collect();
        let wall_s = start.elapsed().as_secs_f64();
        Ok(self.assemble(results, runs, seed, wall_s))
    }

    /// The campaign document of `results` (module doc of [`crate::montecarlo`]) of `runs`
    /// asked for.
    fn assemble(&self, results: Vec<RunResult>, runs: u64, seed: u64, wall_s: f64) -> Campaign {
        let names: Vec<String> = self.estimators.iter().map(|e| e.name().to_string()).collect();
        let name = self.aircraft.name();
        let ran = Ran { name, seed, wall_s, threads: rayon::current_num_threads() };
        let mut c = document(ran, results, &names, self.crb());
        c.asked_for(runs);
        c
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::airframe::tests::{ALT_FT, VT_FPS, as_model_file, f16_trim};
    use crate::montecarlo::{STATUS_COMPLETE, STATUS_INTERRUPTED};
    use aeroident_estimators::prior::Priors;
    use aeroident_io::ParamReference;

    /// White noise on every output the flight model predicts, SI: σ of a small air-data
    /// system and an AHRS.
    const SENSORS: [(&str, f64); 11] = [
        ("vt_mps", 0.3),
        ("alpha_rad", 0.0017),
        ("beta_rad", 0.0017),
        ("p_rad_s", 0.0025),
        ("q_rad_s", 0.0025),
        ("r_rad_s", 0.0025),
        ("phi_rad", 0.005),
        ("theta_rad", 0.005),
        ("ax_mps2", 0.1),
        ("ay_mps2", 0.1),
        ("az_mps2", 0.1),
    ];

    /// The F-16's local derivatives flown through a doublet on each surface, 10 s at 50 Hz,
    /// every output sensed with white noise.
    fn experiment(estimators: &[&str]) -> ModelFileExperiment {
        let (f, t) = f16_trim();
        experiment_with(as_model_file(&f, &t), estimators)
    }

    /// `aircraft` flown through [`experiment`]'s doublets and sensors, its own derivatives
    /// fitted.
    pub(crate) fn experiment_with<const N: usize, A: FlyableAircraft<N>>(
        aircraft: A,
        estimators: &[&str],
    ) -> AircraftExperiment<N, A> {
        let structure = aircraft.flown_structure();
        let model = ModelSpec {
            name: "f16-local".into(),
            description: String::new(),
            structure,
            priors: Priors::generic(&structure),
            references: Vec::new(),
            plausible: Vec::new(),
        };
        let doublet = |ch: &str, deg: f64, t0: f64| {
            format!(
                "[[input]]\nchannel = \"{ch}\"\nkind = \"doublet\"\namplitude_deg = {deg}\nstart_s = {t0}\npulse_width_s = 0.5\n"
            )
        };
        let mut text = format!(
            "kind = \"sim\"\n[trim]\nalt_ft = {ALT_FT}\nvt_fps = {VT_FPS}\n[run]\nduration_s = 10.0\ndt_s = 0.02\nseed = 1\n{}{}{}",
            doublet("elevator", 1.0, 1.0),
            doublet("aileron", 2.0, 4.0),
            doublet("rudder", 2.0, 7.0)
        );
        for (ch, sigma) in SENSORS {
            text.push_str(&format!(
                "[[sensor]]\nchannel = \"{ch}\"\nwhite_sigma = {sigma}\nsample_rate_hz = 50.0\n"
            ));
        }
        AircraftExperiment {
            aircraft,
            model,
            scenario: toml::from_str(&text).unwrap(),
            base_dir: PathBuf::from("."),
            estimators: estimators.iter().map(|e| EstimatorKind::from_name(e).unwrap()).collect(),
        }
    }

    /// Output error over 16 noisy flights of a model-file aircraft: for every parameter the
    /// scatter lies within [0.5, 1.6] × the Cramér–Rao σ computed from the noise-free flight
    /// (the sample σ of 16 draws has a relative standard error of 18 %; measured 0.70–1.33),
    /// the bias within 4 standard errors of the mean, the mean reported σ within [0.5, 2] × the
    /// scatter, and the reference is the value flown. The bound and the fits share only the
    /// flight model: a wrong sensor σ, input or trim in the bound, a wrong truth, or an exact
    /// channel in the record (the state derivatives once were: scatter 0.00–0.21 × the bound)
    /// fails it.
    #[test]
    fn output_error_scatter_over_noisy_flights_matches_the_bound_of_the_flight() {
        let x = experiment(&["oe", "rls"]);
        let runs = 16;
        let c = x.campaign_watched(runs, 5, None, &|| {}).unwrap();
        assert_eq!(c.status, STATUS_COMPLETE, "{:?}", c.status_reason);
        let oe = &c.estimators[0];
        assert_eq!((oe.name.as_str(), oe.runs_ok), ("oe", 16), "{:?}", oe.failed_runs);
        assert_eq!(c.estimators[1].runs_ok, 16, "{:?}", c.estimators[1].failed_runs);
        assert_eq!(oe.parameters.len(), x.aircraft.structure().n_params());
        assert!(c.crb_notes.iter().all(|n| !n.contains("throttle")), "{:?}", c.crb_notes);
        for p in &oe.parameters {
            let truth = x.truth(&p.name).unwrap();
            assert_eq!(p.reference, Some(truth), "{}", p.name);
            let (scatter, crb) = (p.scatter.unwrap(), p.crb_std_error.unwrap());
            let (bias, sigma) = (p.bias.unwrap(), p.mean_std_error.unwrap());
            let ratio = scatter / crb;
            eprintln!(
                "{:>9} truth {truth:10.4} bias {bias:+.2e} scatter {scatter:.2e} CRB {crb:.2e} ratio {ratio:.2} σ/scatter {:.2}",
                p.name,
                sigma / scatter
            );
            assert!((0.5..=1.6).contains(&ratio), "{}: scatter / σ_CRB {ratio}", p.name);
            let standard_error = scatter / (runs as f64).sqrt();
            assert!(
                bias.abs() <= 4.0 * standard_error,
                "{}: bias {bias}, scatter {scatter}",
                p.name
            );
            assert!((0.5..=2.0).contains(&(sigma / scatter)), "{}: σ {sigma}", p.name);
        }
    }

    /// The model file's references (here twice the values flown, as a published aircraft's
    /// would differ from a summary's) are neither the verdict's input nor the score: each
    /// parameter's check is against the value flown, and the statuses are those of the same
    /// fit without references.
    #[test]
    fn a_run_checks_against_the_values_flown_not_the_model_files_references() {
        let plain = experiment(&["oe"]);
        let mut x = experiment(&["oe"]);
        let s = x.aircraft.structure();
        x.model.references = s
            .params()
            .zip(x.aircraft.theta())
            .map(|(param, v)| ParamReference { param, value: 2.0 * v, source: "test".into() })
            .collect();
        let (with, without) = (x.fly(&x.scenario).unwrap(), plain.fly(&plain.scenario).unwrap());
        for (p, q) in with.estimators[0].params.iter().zip(&without.estimators[0].params) {
            let r = &p.result;
            let (e, truth, sigma) =
                (r.estimate.unwrap(), r.reference.unwrap(), r.std_error.unwrap());
            let check = r.reference_check.as_ref().unwrap();
            let distance = check.distance_sigma.unwrap();
            assert!((distance - (e - truth).abs() / sigma).abs() < 1e-9, "{}: {check:?}", r.name);
            assert_eq!(r.status, q.result.status, "{}", r.name);
        }
    }

    /// One flight, two real-time estimators: each scores every parameter of the model against
    /// the value flown (read here from the aircraft's structure and values), they are not the
    /// same estimator, and the lateral damping and stability derivatives reach ±10 % of the
    /// truth only after the aileron doublet at 4 s (before it the lateral regressors are zero:
    /// no estimate of them can be the data's) and before the end of the 10-s record.
    #[test]
    fn a_run_scores_each_real_time_estimator_against_the_values_flown() {
        let x = experiment(&["rls", "ekf"]);
        let flown = x.fly(&x.scenario).unwrap();
        let s = x.aircraft.structure();
        let truth: Vec<(&str, f64)> = s.names().zip(x.aircraft.theta().iter().copied()).collect();
        for e in &flown.estimators {
            assert_eq!(e.failure, None, "{}", e.name);
            assert_eq!(e.params.len(), truth.len(), "{}", e.name);
            for (p, (name, value)) in e.params.iter().zip(&truth) {
                assert_eq!((p.name.as_str(), p.reference), (*name, Some(*value)), "{}", e.name);
            }
            let late = ["Cl_beta", "Cl_p", "Cn_beta", "Cn_r"];
            let times: Vec<(&str, f64)> = e
                .params
                .iter()
                .filter_map(|p| p.time_to_10pct_s.map(|t| (p.name.as_str(), t)))
                .collect();
            assert!(times.len() >= 4, "{}: {times:?}", e.name);
            for (name, t) in times {
                let earliest = if late.contains(&name) { 4.0 } else { 0.0 };
                assert!((earliest..=10.0).contains(&t), "{} {name}: {t} s", e.name);
            }
        }
        let (rls, ekf) = (&flown.estimators[0], &flown.estimators[1]);
        assert!(rls.params.iter().zip(&ekf.params).any(|(a, b)| a.estimate != b.estimate));
    }

    /// Run `i` draws new noise (the sensors' own seeds are dropped) and depends only on the
    /// campaign seed and `i`.
    #[test]
    fn a_run_depends_on_the_campaign_seed_and_its_index_only() {
        let x = experiment(&["rls"]);
        let (a, b, c) = (x.seeded(5, 0), x.seeded(5, 1), x.seeded(5, 0));
        assert_eq!(a, c);
        assert_ne!(a.run.seed, b.run.seed);
        let fa = x.fly(&a).unwrap();
        let fb = x.fly(&b).unwrap();
        let q = |f: &FlownRun| f.sim.table.column("meas_q_rad_s").unwrap()[100];
        assert_ne!(q(&fa), q(&fb));
        assert_eq!(q(&fa), q(&x.fly(&c).unwrap()));
    }

    /// The bootstrap's replica count a face shows: after an output-error fit with a bootstrap of
    /// 6 replicas on a flown record, the counter has counted each of them, and the summary says
    /// 6 were refitted.
    #[test]
    fn a_bootstrap_counts_its_replicas_as_they_end() {
        let x = experiment(&["oe"]);
        let flown = x.fly(&x.scenario).unwrap();
        let mapping = Mapping::from_toml_str(&flown.mapping, "mapping.toml").unwrap();
        let counter = crate::replay::batch::ReplicaCounter::default();
        let options = FitOptions {
            bootstrap_refits: Some(6),
            bootstrap_done: Some(counter.clone()),
            ..FitOptions::default()
        };
        let reader = reader_of(&flown.sim, &mapping).unwrap();
        let model = Some(x.model.clone());
        let out = crate::replay::fit::fit_records(vec![reader], &mapping, model, options).unwrap();
        assert_eq!(out.summary.bootstrap.as_ref().map(|b| b.refits), Some(6));
        assert_eq!(counter.done(), 6);
    }

    /// The bound's outputs: every flight-model output of [`SENSORS`] once, with its σ; a
    /// sensor with anything but white noise (bias, scale, Gauss–Markov, lag, delay, quantum), a
    /// noise-free one and a second sensor on one output are left out with a note; a channel no
    /// output predicts (`psi_rad`) is passed over.
    #[test]
    fn the_bound_counts_each_output_s_white_sensor_once_and_notes_the_others() {
        let mut sc = experiment(&["oe"]).scenario;
        let mut notes = Vec::new();
        let sensors = crb_sensors(&sc, &mut notes);
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!(sensors.len(), SENSORS.len());
        for ((ch, sigma), s) in SENSORS.iter().zip(&sensors) {
            assert_eq!(s.sigma, *sigma, "{ch}");
            assert_eq!(sensors.iter().filter(|x| x.output == s.output).count(), 1, "{ch}");
            assert_eq!(s.output.name(), *ch);
        }
        let base = sc.sensor[0].clone();
        type Change = fn(&mut aeroident_signals::SensorConfig);
        let variants: [(&str, Change); 9] = [
            ("bias", |s| s.bias = 0.1),
            ("scale", |s| s.scale = 1.1),
            ("gauss_markov", |s| s.gauss_markov_sigma = Some(0.1)),
            ("lag", |s| s.lag_tau_s = Some(0.1)),
            ("delay", |s| s.delay_s = Some(0.1)),
            ("delay_samples", |s| s.delay_samples = Some(2)),
            ("quantum", |s| s.quantum = Some(0.01)),
            ("noise-free", |s| s.white_sigma = 0.0),
            ("second", |_| ()),
        ];
        for (what, change) in variants {
            let mut extra = base.clone();
            change(&mut extra);
            sc.sensor = vec![base.clone(), extra];
            let mut notes = Vec::new();
            assert_eq!(crb_sensors(&sc, &mut notes).len(), 1, "{what}");
            assert_eq!(notes.len(), 1, "{what}: {notes:?}");
        }
        sc.sensor[1].channel = "psi_rad".into();
        let mut notes = Vec::new();
        assert_eq!((crb_sensors(&sc, &mut notes).len(), notes.len()), (1, 0));
    }

    /// A campaign stopped before its first run is `interrupted` with no run done, not
    /// `complete`; replica counters are equal when shared.
    #[test]
    fn a_campaign_stopped_before_it_starts_is_interrupted() {
        let x = experiment(&["rls"]);
        let stop = AtomicBool::new(true);
        let c = x.campaign_watched(3, 1, Some(&stop), &|| {}).unwrap();
        assert_eq!((c.status, c.runs, c.runs_requested), (STATUS_INTERRUPTED, 0, 3));
        let a = crate::replay::batch::ReplicaCounter::default();
        assert!(a == a.clone() && a != crate::replay::batch::ReplicaCounter::default());
    }

    /// What cannot make an experiment is refused before a flight, naming the cause.
    #[test]
    fn no_estimator_a_repeated_one_or_a_noise_free_scenario_is_refused() {
        let mut x = experiment(&[]);
        assert!(x.campaign_watched(2, 1, None, &|| {}).unwrap_err().contains("--estimator"));
        x.estimators = vec![EstimatorKind::Rls, EstimatorKind::Rls];
        assert!(x.check().unwrap_err().to_string().contains("named twice"));
        x.estimators = vec![EstimatorKind::Rls];
        x.scenario.sensor.iter_mut().for_each(|s| s.white_sigma = 0.0);
        assert!(x.campaign_watched(2, 1, None, &|| {}).unwrap_err().contains("no [[sensor]]"));
    }
}
