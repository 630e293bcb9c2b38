//! Monte Carlo campaigns of the closed-loop `run` experiment: `N` seeded noisy
//! flights of one scenario in parallel (rayon), and per estimator and parameter the statistics
//! of the final estimates: bias, scatter, mean reported σ, ±2σ coverage, the predicted
//! Cramér–Rao σ of the flight's inputs, and the median time to within ±10 %.
//!
//! # Seed rule
//!
//! Run `i` (0-based) of a campaign with seed `S` flies the scenario with its sensor-noise seed
//! and each seeded wind's (Dryden turbulence) seed replaced by
//! `seed(S, i, stream) = splitmix64(S + 0x9E37_79B9_7F4A_7C15 · (1 + 64 i + stream))`
//! (wrapping arithmetic; [`run_seed`]), stream 0 for the sensors and stream `1 + j` for the
//! `j`-th `[[wind]]` entry. Everything else (trim, pilot inputs, damage, estimators) is the
//! scenario's own. A run depends only on `(S, i)`, so its result is bit-identical whatever the
//! number of threads or the order in which the runs finish.
//!
//! # Statistics (per estimator and parameter; [`statistics`])
//!
//! Over the runs in which the estimator neither failed nor diverged (`runs_ok`; a failed run of
//! the whole experiment or of one estimator is counted and listed, never averaged in; a run in
//! which it restarted from its priors and then ran to the end is listed in `restarted_runs` and
//! kept):
//! - `reference`: the reference aircraft's true value at the end (after the damage, if any);
//! - `bias`: mean of the final estimates − `reference`;
//! - `scatter`: sample standard deviation (`n − 1`) of the final estimates;
//! - `mean_std_error`: mean of the final reported σ (`null` when the method reports none);
//! - `coverage_2sigma`: fraction of `runs_ok` whose final `|estimate − reference| ≤ 2σ` (a run with
//!   no estimate or no σ for the parameter does not cover); `null` for methods without σ;
//! - `median_time_to_10pct_s`: median over `runs_ok` of the time from the start of the
//!   excitation until the estimate stays within ±10 % of the truth up to the damage (or the end)
//!   ([`crate::aircraft::summary`]); a run that never settles counts as +∞, and the median is
//!   `null` when at least half never settle; always `null` for a batch estimator (output
//!   error, [`crate::aircraft::batch`]: no estimate before the end of the flight), which
//!   reports `mean_iterations` and `mean_fit_wall_s` instead;
//! - `crb_std_error`: [`crb_sigmas`], the Cramér–Rao σ of the experiment flown, for the data since
//!   the last change of the truth: with the scenario's Dryden turbulence as process noise
//!   ([`aeroident_estimators::output_error::design::predict_crb_turbulent`]) when it has one
//!   `dryden` wind entry, else the calm-air bound (module docs there; Klein & Morelli 2006
//!   ch. 6); `crb_notes` say which;
//! - `crb_std_error_calm`: the calm-air bound of the same flight, white sensor noise only
//!   ([`aeroident_estimators::output_error::design::predict_crb`]; the bound reported as
//!   `crb_std_error` before the turbulent one existed).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use aeroident_estimators::flight_model::Output;
use aeroident_estimators::output_error::design::frequency::{GustModel, ShapingFilter};
use aeroident_estimators::output_error::design::{
    DesignPlan, FlightCondition, PlannedInputs, Sensor, predict_crb, predict_crb_turbulent,
    trim_biases,
};
use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_io::ParameterResult;
use aeroident_models::f16::{self, AeroIncrements, F16};
use aeroident_signals::config::WindConfig;
use aeroident_signals::turbulence::{DrydenComponent, DrydenParameters, dryden_shaping_filter};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::aircraft::air_data::f16_constants;
use crate::aircraft::scenario::EstimatorSpec;
use crate::aircraft::summary::{self, PRIMARY_DERIVATIVES};
use crate::aircraft::{RunOutput, Scenario, run};
use crate::metrics::ZERO_THRESHOLD;
use aeroident_physics::units::{M_PER_FT, N_PER_LBF, PA_PER_PSF};

pub mod aircraft;
mod from_json;
pub use from_json::run_result_from_json;

/// The golden-ratio increment of SplitMix64 (Steele, Lea & Flood, OOPSLA 2014).
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// Seed streams per run: 0 = sensors, `1 + j` = the `j`-th wind entry (at most 63 winds).
pub const STREAMS_PER_RUN: u64 = 64;

/// SplitMix64's output function (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of `stream` in run `run` of a campaign with seed `campaign_seed` (module doc).
pub fn run_seed(campaign_seed: u64, run: u64, stream: u64) -> u64 {
    let k = 1u64.wrapping_add(run.wrapping_mul(STREAMS_PER_RUN)).wrapping_add(stream);
    splitmix64(campaign_seed.wrapping_add(GOLDEN.wrapping_mul(k)))
}

/// The scenario of run `run`: `sc` with the sensor and wind seeds of the seed rule.
pub fn seeded_scenario(sc: &Scenario, campaign_seed: u64, run: u64) -> Scenario {
    let mut s = sc.clone();
    s.sensors.seed = run_seed(campaign_seed, run, 0);
    for (j, w) in s.wind.iter_mut().enumerate() {
        if let WindConfig::Dryden { seed, .. } = w {
            *seed = run_seed(campaign_seed, run, 1 + j as u64);
        }
    }
    s
}

/// One parameter's final result in one run: the common keys ([`ParameterResult`]: `name`,
/// `estimate` (`null`: not identified), `std_error`, `reference` (the true value at the end),
/// status, flags …) and the run's own.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamRun {
    /// The run's result of the parameter, as its `summary.json` gives it.
    #[serde(flatten)]
    pub result: ParameterResult,
    /// Whether it is one of [`PRIMARY_DERIVATIVES`].
    pub primary: bool,
    /// True value before the damage.
    pub truth_before: Option<f64>,
    /// True value after the damage.
    pub truth_after: Option<f64>,
    /// Time from the excitation until within ±10 % to the damage (or the end), s.
    pub time_to_10pct_s: Option<f64>,
    /// Time from the damage until within ±10 % of the new truth to the end, s.
    pub reconvergence_10pct_s: Option<f64>,
}

impl std::ops::Deref for ParamRun {
    type Target = ParameterResult;

    fn deref(&self) -> &ParameterResult {
        &self.result
    }
}

/// One estimator's result in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimatorRun {
    /// Estimator label.
    pub name: String,
    /// Failure or divergence (time and message); its estimates are not used.
    pub failure: Option<String>,
    /// Final mean normalised innovation squared (filters only; ≈ 1 when consistent).
    pub nis: Option<f64>,
    /// How many times the estimator restarted from its priors
    /// ([`aeroident_estimators::EventKind::Restart`]); its estimates are still used. Read back
    /// as 0 where a result of an older version lacks it.
    #[serde(default)]
    pub restarts: u32,
    /// Batch estimators ([`crate::aircraft::batch`]): Gauss–Newton iterations of the fit
    /// (`null` for real-time estimators and failed fits).
    pub iterations: Option<usize>,
    /// Batch estimators: wall time of the post-flight fit, s (`null` otherwise).
    pub fit_wall_s: Option<f64>,
    /// Batch estimators: the candidate σ of the parameters by kind
    /// ([`crate::aircraft::batch::BatchFit::sigma_candidates`]; empty otherwise).
    #[serde(default)]
    pub sigma_candidates: Vec<(String, Vec<f64>)>,
    /// `oe` with `bootstrap_refits`: the bootstrap replicas that failed
    /// ([`crate::aircraft::batch::BatchFit::bootstrap_failed`]; `null` otherwise).
    pub bootstrap_failed: Option<usize>,
    /// `oe` with `bootstrap_refits`: the bootstrap's bias estimate per parameter, structure
    /// order ([`crate::aircraft::batch::BatchFit::bootstrap_bias`]; `null` otherwise).
    pub bootstrap_bias: Option<Vec<f64>>,
    /// Per parameter, in the structure's order.
    pub params: Vec<ParamRun>,
}

impl EstimatorRun {
    /// The result of the estimator `name` before anything is known: no failure, no restart,
    /// no batch statistics, no parameter.
    pub fn named(name: &str) -> Self {
        Self {
            name: name.to_string(),
            failure: None,
            nis: None,
            restarts: 0,
            iterations: None,
            fit_wall_s: None,
            sigma_candidates: Vec::new(),
            bootstrap_failed: None,
            bootstrap_bias: None,
            params: Vec::new(),
        }
    }
}

/// One run of a campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// Run index.
    pub index: u64,
    /// Sensor-noise seed (stream 0).
    pub sensor_seed: u64,
    /// Per estimator; `Err`: the whole experiment failed (message).
    pub outcome: Result<Vec<EstimatorRun>, String>,
}

/// The final results of one finished experiment (`outcome` is `Err` with a message when the
/// summary cannot be formed: inconsistent logs, a bug).
pub fn run_result(index: u64, sensor_seed: u64, out: &RunOutput) -> RunResult {
    let outcome = summary::summarize(out).map_err(|e| e.to_string()).map(|sm| {
        let mut ests: Vec<EstimatorRun> = Vec::new();
        for p in &sm.parameters {
            if ests.last().is_none_or(|e| e.name != p.estimator) {
                let diverged = p.estimator_status == Some("diverged");
                let ch = out.channels.iter().find(|c| c.label == p.estimator);
                let nis = ch.and_then(|c| c.nis).filter(|v| v.is_finite());
                let fit = ch.and_then(|c| c.batch.as_ref());
                // A batch fit's last iterate is not an estimate of the campaign's statistics.
                let unconverged = fit
                    .filter(|f| f.status == "not_converged")
                    .map(|f| f.status_reason.clone().unwrap_or_else(|| "not converged".into()));
                let failure = p
                    .failure
                    .clone()
                    .or_else(|| diverged.then(|| "diverged".into()))
                    .or(unconverged);
                let restarts =
                    ch.map_or(0, |c| c.events.count(aeroident_estimators::EventKind::Restart));
                ests.push(EstimatorRun {
                    name: p.estimator.clone(),
                    failure,
                    nis,
                    restarts,
                    iterations: fit.and_then(|f| f.iterations),
                    fit_wall_s: fit.map(|f| f.wall_s),
                    sigma_candidates: fit.map(|f| f.sigma_candidates.clone()).unwrap_or_default(),
                    bootstrap_failed: fit.and_then(|f| f.bootstrap_failed),
                    bootstrap_bias: fit.and_then(|f| f.bootstrap_bias.clone()),
                    params: Vec::new(),
                });
            }
            let e = ests.last_mut().expect("pushed above");
            if let Some(f) = p.estimate.filter(|f| !f.is_finite()) {
                e.failure
                    .get_or_insert_with(|| format!("{}: non-finite final estimate {f}", p.name));
            }
            e.params.push(ParamRun {
                result: p.result.clone(),
                primary: PRIMARY_DERIVATIVES.contains(&p.name.as_str())
                    && p.quantity == "derivative",
                truth_before: p.truth_before,
                truth_after: p.truth_after,
                time_to_10pct_s: p.time_to_10pct_s,
                reconvergence_10pct_s: p.reconvergence_10pct_s,
            });
        }
        ests
    });
    RunResult { index, sensor_seed, outcome }
}

/// The most runs one campaign (or one chunk of a distributed campaign, [`run_range`]) takes.
///
/// Every run's final results are kept until the statistics are formed (the medians need them
/// all) and `runs.json` is written: about 55 kB a run in `runs.json` for the built-in default
/// scenario's six-axis estimators with each parameter's verdict and flags (measured:
/// `aeroident montecarlo --runs 4` writes 221 kB), 550 MB at the limit. More runs buy nothing
/// measurable: the sampling error of a scatter or σ over `N` runs is about `1/√(2N)` (0.7 % at
/// the limit) and that of a ±2σ coverage near 95 % `√(p(1−p)/N)` (0.2 %), below the other
/// errors of a campaign, while each run is a whole closed-loop flight (1–2 s of one core).
pub const MAX_RUNS: u64 = 10_000;

/// Checks a campaign's number of runs, before anything is allocated for them: 1 to
/// [`MAX_RUNS`].
///
/// # Errors
/// A message naming `option` (the argument's name where it was given: `--runs`, `runs`).
pub fn check_runs(runs: u64, option: &str) -> Result<(), String> {
    if runs == 0 {
        return Err(format!("{option} must be at least 1"));
    }
    if runs > MAX_RUNS {
        return Err(format!(
            "{option} = {runs} is more than the {MAX_RUNS} runs a campaign takes (every run's results are kept for the statistics; the sampling error at {MAX_RUNS} runs is already 0.7 % of a σ)"
        ));
    }
    Ok(())
}

/// Runs the seeded flights `runs` (run indices, seed rule of the module doc) of `sc` on the
/// current rayon pool; results in run order. A distributed campaign runs its chunks with it.
///
/// # Errors
/// More than [`MAX_RUNS`] indices ([`check_runs`]), before any run; an empty range is no error.
pub fn run_range(
    sc: &Scenario,
    campaign_seed: u64,
    runs: std::ops::Range<u64>,
) -> Result<Vec<RunResult>, String> {
    let n = runs.end.saturating_sub(runs.start);
    if n > 0 {
        check_runs(n, "runs")?;
    }
    Ok(run_range_until(sc, campaign_seed, runs, None, &|| {}))
}

/// [`run_range`] (its count checked by the caller) that starts no run once `stop` is set: the
/// runs started before it finish, the others are left out. Results in run order.
fn run_range_until(
    sc: &Scenario,
    campaign_seed: u64,
    runs: std::ops::Range<u64>,
    stop: Option<&AtomicBool>,
    on_run: &(dyn Fn() + Sync),
) -> Vec<RunResult> {
    runs.into_par_iter()
        .filter_map(|i| {
            if stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
                return None;
            }
            let s = seeded_scenario(sc, campaign_seed, i);
            let result = match run(&s) {
                Ok(out) => run_result(i, s.sensors.seed, &out),
                Err(e) => {
                    RunResult { index: i, sensor_seed: s.sensors.seed, outcome: Err(e.to_string()) }
                }
            };
            on_run();
            Some(result)
        })
        .collect()
}

/// A failed run of one estimator (or of the whole experiment).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FailedRun {
    /// Run index.
    pub run: u64,
    /// Why.
    pub reason: String,
}

/// Statistics of one parameter over a campaign (module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamStats {
    /// Vocabulary name.
    pub name: String,
    /// Whether it is one of [`PRIMARY_DERIVATIVES`].
    pub primary: bool,
    /// True value at the end.
    pub reference: Option<f64>,
    /// True value before the damage.
    pub truth_before: Option<f64>,
    /// True value after the damage.
    pub truth_after: Option<f64>,
    /// Runs with a final estimate.
    pub n_estimates: usize,
    /// Mean final estimate − truth.
    pub bias: Option<f64>,
    /// Sample standard deviation of the final estimates.
    pub scatter: Option<f64>,
    /// Mean final reported σ.
    pub mean_std_error: Option<f64>,
    /// Fraction of the estimator's good runs whose ±2σ covers the truth.
    pub coverage_2sigma: Option<f64>,
    /// Predicted Cramér–Rao σ of the experiment flown, turbulence included ([`crb_sigmas`]).
    pub crb_std_error: Option<f64>,
    /// Predicted Cramér–Rao σ in calm air, white sensor noise only ([`crb_sigmas`]).
    pub crb_std_error_calm: Option<f64>,
    /// Median time to within ±10 %, s (module doc).
    pub median_time_to_10pct_s: Option<f64>,
    /// Median time from the damage to within ±10 % of the new truth, s.
    pub median_reconvergence_10pct_s: Option<f64>,
}

/// Statistics of one estimator over a campaign.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EstimatorStats {
    /// Estimator label.
    pub name: String,
    /// Runs in which it neither failed nor diverged (the statistics' sample).
    pub runs_ok: usize,
    /// Runs excluded from the statistics, with the reason.
    pub failed_runs: Vec<FailedRun>,
    /// Runs in which the estimator restarted from its priors and then ran to the end: counted
    /// apart, and kept in the statistics (their estimates and σ come from the samples after the
    /// restart).
    pub restarted_runs: Vec<u64>,
    /// Mean over `runs_ok` of the final normalised innovation squared (`null` for methods
    /// without innovations); ≈ 1 for a consistent filter.
    pub mean_nis: Option<f64>,
    /// Batch estimators: mean Gauss–Newton iterations over `runs_ok` (`null` otherwise).
    pub mean_iterations: Option<f64>,
    /// Batch estimators: mean wall time of the post-flight fit over `runs_ok`, s (`null`
    /// otherwise; single-thread time of one fit, measured while the other runs share the
    /// cores).
    pub mean_fit_wall_s: Option<f64>,
    /// Per parameter.
    pub parameters: Vec<ParamStats>,
}

/// The Cramér–Rao σ per estimator label and parameter name, or why there is none.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CrbTable {
    /// `label → (parameter name → σ)` of the experiment flown (turbulence included when the
    /// scenario has Dryden wind); absent entries are `null`.
    pub sigma: BTreeMap<String, BTreeMap<String, f64>>,
    /// The same for the calm-air bound (white sensor noise only).
    pub calm: BTreeMap<String, BTreeMap<String, f64>>,
    /// Notes on estimators or parameters without a bound.
    pub notes: Vec<String>,
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn sample_std(v: &[f64]) -> Option<f64> {
    let m = mean(v)?;
    (v.len() >= 2)
        .then(|| (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt())
}

/// Median with `None` as +∞; `None` when the median itself is +∞ or there is no value.
pub fn median_with_never(v: &[Option<f64>]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s: Vec<f64> = v.iter().map(|x| x.unwrap_or(f64::INFINITY)).collect();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    let m = if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) };
    m.is_finite().then_some(m)
}

/// The campaign statistics of `runs` (module doc), with the estimators in `names` order.
pub fn statistics(runs: &[RunResult], names: &[String], crb: &CrbTable) -> Vec<EstimatorStats> {
    names
        .iter()
        .map(|name| {
            let mut failed = Vec::new();
            let mut restarted = Vec::new();
            let mut ok: Vec<&EstimatorRun> = Vec::new();
            for r in runs {
                match &r.outcome {
                    Err(e) => failed.push(FailedRun { run: r.index, reason: e.clone() }),
                    Ok(ests) => match ests.iter().find(|e| &e.name == name) {
                        None => failed
                            .push(FailedRun { run: r.index, reason: "estimator absent".into() }),
                        Some(e) => match &e.failure {
                            Some(f) => failed.push(FailedRun { run: r.index, reason: f.clone() }),
                            None => {
                                if e.restarts > 0 {
                                    restarted.push(r.index);
                                }
                                ok.push(e);
                            }
                        },
                    },
                }
            }
            let parameters = ok
                .first()
                .map(|first| {
                    first
                        .params
                        .iter()
                        .enumerate()
                        .map(|(k, p0)| {
                            let ps: Vec<&ParamRun> =
                                ok.iter().filter_map(|e| e.params.get(k)).collect();
                            let of = |t: &BTreeMap<String, BTreeMap<String, f64>>| {
                                t.get(name).and_then(|m| m.get(&p0.name)).copied()
                            };
                            param_stats(p0, &ps, of(&crb.sigma), of(&crb.calm))
                        })
                        .collect()
                })
                .unwrap_or_default();
            let nis: Vec<f64> = ok.iter().filter_map(|e| e.nis).collect();
            let iterations: Vec<f64> =
                ok.iter().filter_map(|e| e.iterations.map(|i| i as f64)).collect();
            let fit_wall: Vec<f64> = ok.iter().filter_map(|e| e.fit_wall_s).collect();
            EstimatorStats {
                name: name.clone(),
                runs_ok: ok.len(),
                mean_nis: mean(&nis),
                mean_iterations: mean(&iterations),
                mean_fit_wall_s: mean(&fit_wall),
                failed_runs: failed,
                restarted_runs: restarted,
                parameters,
            }
        })
        .collect()
}

fn param_stats(
    p0: &ParamRun,
    ps: &[&ParamRun],
    crb: Option<f64>,
    crb_calm: Option<f64>,
) -> ParamStats {
    let finals: Vec<f64> = ps.iter().filter_map(|p| p.estimate).collect();
    let sigmas: Vec<f64> = ps.iter().filter_map(|p| p.std_error).collect();
    let truth = p0.reference;
    let coverage = (!sigmas.is_empty() && truth.is_some()).then(|| {
        let covered = ps
            .iter()
            .filter(|p| match (p.estimate, p.std_error, p.reference) {
                (Some(f), Some(s), Some(t)) => (f - t).abs() <= 2.0 * s,
                _ => false,
            })
            .count();
        covered as f64 / ps.len() as f64
    });
    let times: Vec<Option<f64>> = ps.iter().map(|p| p.time_to_10pct_s).collect();
    let reconv: Vec<Option<f64>> = ps.iter().map(|p| p.reconvergence_10pct_s).collect();
    let changes = p0.truth_before != p0.truth_after;
    ParamStats {
        name: p0.name.clone(),
        primary: p0.primary,
        reference: truth,
        truth_before: p0.truth_before,
        truth_after: p0.truth_after,
        n_estimates: finals.len(),
        bias: mean(&finals).zip(truth).map(|(m, t)| m - t),
        scatter: sample_std(&finals),
        mean_std_error: mean(&sigmas),
        coverage_2sigma: coverage,
        crb_std_error: crb,
        crb_std_error_calm: crb_calm,
        median_time_to_10pct_s: median_with_never(&times),
        median_reconvergence_10pct_s: if changes { median_with_never(&reconv) } else { None },
    }
}

/// [`crb_sensors`] restricted to the outputs `structure`'s flight model predicts: the
/// longitudinal ones (V, α, q, θ, ax, az) if it has a longitudinal coefficient (CL, CD, Cm, CX,
/// CZ), the lateral ones (β, p, r, φ, ay) if it has CY, Cl or Cn.
pub fn crb_sensors_for(structure: &ModelStructure, scale: f64) -> Vec<Sensor> {
    use aeroident_estimators::vocabulary::Coefficient as C;
    let lon = [C::CL, C::CD, C::Cm, C::CX, C::CZ].into_iter().any(|c| structure.has(c));
    let lat = [C::CY, C::Cl, C::Cn].into_iter().any(|c| structure.has(c));
    crb_sensors(scale)
        .into_iter()
        .filter(|s| match s.output {
            Output::Vt | Output::Alpha | Output::Q | Output::Theta | Output::Ax | Output::Az => lon,
            Output::Beta | Output::P | Output::R | Output::Phi | Output::Ay => lat,
            _ => false,
        })
        .collect()
}

/// Outputs of the Cramér–Rao prediction and their white-noise σ at the scenario's sensor
/// scale: the raw sensor levels the air-data path flies with
/// ([`crate::aircraft::sensors::sensed_channels`]: airspeed 11 ft/s, vanes 0.1°, gyros
/// 0.14°/s, attitude 0.573°, accelerometers 0.98 ft/s²) before the matched smoother, which
/// cannot add information; ψ, which no flight-model output predicts, is left out.
pub fn crb_sensors(scale: f64) -> Vec<Sensor> {
    crate::aircraft::sensors::sensed_channels()
        .into_iter()
        .filter_map(|(name, sigma)| {
            let output = Output::ALL.into_iter().find(|o| o.name() == name)?;
            Some(Sensor { output, sigma: sigma * scale })
        })
        .collect()
}

/// The predicted Cramér–Rao σ of every sample-driven estimator's parameters for the scenario's
/// flight: an output-error fit of the estimator's structure ([`predict_crb`]) to the data from
/// the last change of the truth (the damage) to the end, starting from the trim condition, with
/// `θ` = the reference's true local derivatives in that interval (biases re-trimmed for the
/// estimators' flight model, [`trim_biases`]), the flown control perturbations about trim, and
/// white sensor noise of [`crb_sensors`] on the outputs the structure predicts. Two bounds:
/// `calm`, white sensor noise only ([`predict_crb`]), and `sigma`, the experiment flown: when
/// the scenario has one `dryden` wind entry, its gusts as process noise ([`gust_model`],
/// [`predict_crb_turbulent`]: linearised about trim, frozen turbulence), else the calm bound.
/// Both ignore the F-16's nonlinearity beyond the local derivatives. `notes` say which bound
/// `sigma` is. Two-aircraft estimators (increments) get no bound (a note).
///
/// # Errors
/// A message when the noise-free flight fails; per-structure failures of the prediction are
/// notes and leave the σ `null`.
pub fn crb_sigmas(sc: &Scenario) -> Result<CrbTable, String> {
    let mut table = CrbTable::default();
    let gusts = match gust_model(sc) {
        Ok(Some(g)) => {
            table.notes.push(
                "crb_std_error: the bound of the experiment flown, the scenario's Dryden turbulence as process noise (linearised about trim, frozen turbulence); crb_std_error_calm: white sensor noise only".into(),
            );
            Some(g)
        }
        Ok(None) => {
            table.notes.push(
                "crb_std_error: no Dryden turbulence in the scenario, the calm-air bound (= crb_std_error_calm)".into(),
            );
            None
        }
        Err(e) => {
            table
                .notes
                .push(format!("crb_std_error: the calm-air bound (= crb_std_error_calm): {e}"));
            None
        }
    };
    if sc.wind.iter().any(|w| matches!(w, WindConfig::OneMinusCosine { .. })) {
        table.notes.push(
            "the deterministic 1-cos gusts of the scenario are in neither Cramér–Rao bound".into(),
        );
    }
    let mut clean = sc.clone();
    clean.estimator.clear();
    let out = run(&clean).map_err(|e| format!("noise-free flight for the CRB: {e}"))?;
    let mut done: Vec<(ModelStructure, Result<CrbOfStructure, String>)> = Vec::new();
    for spec in &sc.estimator {
        let EstimatorSpec::Sample(s) = spec else {
            table.notes.push(format!(
                "{}: two-aircraft estimator (increments), no Cramér–Rao bound",
                spec.label()
            ));
            continue;
        };
        let r = match done.iter().find(|(st, _)| *st == s.model) {
            Some((_, r)) => r.clone(),
            None => {
                let r = crb_for(sc, &out, &s.model, gusts.as_ref());
                done.push((s.model, r.clone()));
                r
            }
        };
        match r {
            Ok((flown, calm)) => {
                match flown {
                    Ok(m) => {
                        table.sigma.insert(spec.label(), m);
                    }
                    Err(e) => table
                        .notes
                        .push(format!("{}: no turbulent Cramér–Rao bound: {e}", spec.label())),
                }
                table.calm.insert(spec.label(), calm);
            }
            Err(e) => table.notes.push(format!("{}: no Cramér–Rao bound: {e}", spec.label())),
        }
    }
    Ok(table)
}

/// Cramér–Rao σ of one structure by parameter name: (the experiment flown, or why not; calm).
type CrbOfStructure = (Result<BTreeMap<String, f64>, String>, BTreeMap<String, f64>);

/// The gusts of the scenario's `dryden` wind entry as shaping filters in SI (m/s), frozen at
/// the entry's airspeed (as the simulator generates them: MIL-F-8785C Dryden, the signals
/// crate's realisation, [`dryden_shaping_filter`]); `None` without one.
///
/// # Errors
/// Several `dryden` entries (their sum is not one filter per axis), or a bad entry.
pub fn gust_model(sc: &Scenario) -> Result<Option<GustModel>, String> {
    let dryden: Vec<(f64, &WindConfig)> = sc
        .wind
        .iter()
        .filter_map(|w| match w {
            WindConfig::Dryden { vt_fps, .. } => Some((*vt_fps, w)),
            _ => None,
        })
        .collect();
    let (vt_fps, w) = match dryden.as_slice() {
        [] => return Ok(None),
        [d] => *d,
        _ => return Err("several Dryden wind entries: the turbulent bound takes one".into()),
    };
    let params = w.dryden_parameters().map_err(|e| e.to_string())?;
    Ok(params.map(|p| dryden_gust_model(&p, vt_fps)))
}

/// The Dryden gusts of `params` frozen at `vt_fps` as shaping filters in SI (m/s): the
/// simulator's realisation ([`dryden_shaping_filter`]) with the output scaled from ft/s.
pub fn dryden_gust_model(params: &DrydenParameters, vt_fps: f64) -> GustModel {
    let filter = |c: DrydenComponent| {
        let (a, b, cv) = dryden_shaping_filter(params, c, vt_fps);
        ShapingFilter { a, b, c: cv * M_PER_FT }
    };
    GustModel {
        filters: [
            filter(DrydenComponent::U),
            filter(DrydenComponent::V),
            filter(DrydenComponent::W),
        ],
    }
}

fn crb_for(
    sc: &Scenario,
    out: &RunOutput,
    structure: &ModelStructure,
    gusts: Option<&GustModel>,
) -> Result<CrbOfStructure, String> {
    let f16m = F16::new(sc.trim.xcg).map_err(|e| e.to_string())?;
    let x0 = out.trim.state;
    let u0 = out.trim.controls;
    let (_, outs) = f16m.evaluate(&x0, &u0, &AeroIncrements::zero()).map_err(|e| e.to_string())?;
    let vt = x0[f16::VT] * M_PER_FT;
    let rho = 2.0 * outs.qbar_psf * PA_PER_PSF / (vt * vt);
    let condition = FlightCondition {
        vt_mps: vt,
        alpha_rad: x0[f16::ALPHA],
        theta_rad: x0[f16::THETA],
        rho_kgpm3: rho,
        thrust_n: outs.thrust_lbf * N_PER_LBF,
        de_rad: u0.elevator_rad,
        da_rad: u0.aileron_rad,
        dr_rad: u0.rudder_rad,
    };
    let last = out.epochs.last().ok_or("no truth epoch")?;
    let theta: Vec<f64> = structure
        .params()
        .map(|p| {
            last.derivatives
                .truth(structure, p)
                .ok_or(format!("no single true value of {}", p.name()))
        })
        .collect::<Result<_, _>>()?;
    let constants = f16_constants(&f16m, sc.trim.vt_fps * M_PER_FT);
    let theta =
        trim_biases(structure, &theta, &constants, &condition).map_err(|e| e.to_string())?;
    let k0 = out.t_s.partition_point(|&t| t < last.from_s);
    let c = &out.controls[k0..];
    let u0v = [u0.elevator_rad, u0.aileron_rad, u0.rudder_rad];
    let col = |j: usize| c.iter().map(|u| u[1 + j] - u0v[j]).collect::<Vec<f64>>();
    let inputs = PlannedInputs { dt_s: sc.dt_s, de_rad: col(0), da_rad: col(1), dr_rad: col(2) };
    let sensors = crb_sensors_for(structure, sc.sensors.scale);
    let plan = DesignPlan::new(*structure, theta, constants, condition, vec![inputs], sensors);
    let by_name = |r: &aeroident_estimators::output_error::design::DesignResult| {
        r.names
            .iter()
            .take(r.n_params)
            .zip(&r.sigma)
            .filter_map(|(n, s)| s.map(|s| (n.clone(), s)))
            .collect::<BTreeMap<String, f64>>()
    };
    let calm = by_name(&predict_crb(&plan).map_err(|e| e.to_string())?);
    let flown = match gusts {
        None => Ok(calm.clone()),
        Some(g) => predict_crb_turbulent(&plan, g).map(|r| by_name(&r)).map_err(|e| e.to_string()),
    };
    Ok((flown, calm))
}

/// A finished campaign.
#[derive(Debug, Clone, Serialize)]
pub struct Campaign {
    /// The key set's version, [`aeroident_io::SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Scenario name.
    pub scenario: String,
    /// Number of runs done (the statistics are over them).
    pub runs: u64,
    /// Number of runs asked for: more than [`Campaign::runs`] when a stop ended the campaign
    /// early ([`campaign_until`]).
    pub runs_requested: u64,
    /// `complete`; `interrupted` when a stop ended the campaign before every run was done;
    /// `failed` when every run failed, `no_estimates` when no run gave an estimate (then the
    /// statistics are empty, not a result).
    pub status: &'static str,
    /// Why the campaign is not `complete`, else `null`.
    pub status_reason: Option<String>,
    /// Campaign seed.
    pub seed: u64,
    /// The seed rule, in words.
    pub seed_rule: &'static str,
    /// Runs whose whole experiment failed.
    pub failed_runs: Vec<FailedRun>,
    /// Per estimator.
    pub estimators: Vec<EstimatorStats>,
    /// Why some `crb_std_error` are `null`.
    pub crb_notes: Vec<String>,
    /// Wall-clock time of the runs (parallel), s.
    pub wall_s: f64,
    /// Threads of the rayon pool.
    pub threads: usize,
    /// Per-run results.
    #[serde(skip)]
    pub results: Vec<RunResult>,
}

/// The seed rule of the module doc, in words (written into `montecarlo.json`).
pub const SEED_RULE: &str = "run i, stream s (0 = sensors, 1 + j = wind j): splitmix64(seed + 0x9E3779B97F4A7C15 * (1 + 64 i + s)), wrapping";

/// Runs a campaign: the Cramér–Rao prediction, `runs` seeded flights in parallel, statistics.
///
/// # Errors
/// `runs` = 0 or above [`MAX_RUNS`] ([`check_runs`]), before any run.
pub fn campaign(sc: &Scenario, runs: u64, seed: u64) -> Result<Campaign, String> {
    campaign_until(sc, runs, seed, None)
}

/// [`campaign`] that starts no further run once `stop` is set (a signal, from another
/// thread): the runs started finish, and the statistics are over the runs done, the campaign
/// `interrupted` with [`Campaign::runs`] of [`Campaign::runs_requested`] done.
///
/// # Errors
/// As [`campaign`].
pub fn campaign_until(
    sc: &Scenario,
    runs: u64,
    seed: u64,
    stop: Option<&AtomicBool>,
) -> Result<Campaign, String> {
    campaign_watched(sc, runs, seed, stop, &|| {})
}

/// [`campaign_until`] that calls `on_run` as each run ends (from the worker that ran it), so a
/// face can count the runs done.
///
/// # Errors
/// As [`campaign`].
pub fn campaign_watched(
    sc: &Scenario,
    runs: u64,
    seed: u64,
    stop: Option<&AtomicBool>,
    on_run: &(dyn Fn() + Sync),
) -> Result<Campaign, String> {
    check_runs(runs, "runs")?;
    let start = Instant::now();
    let results = run_range_until(sc, seed, 0..runs, stop, on_run);
    let wall_s = start.elapsed().as_secs_f64();
    let mut c = assemble(sc, seed, results, wall_s, rayon::current_num_threads());
    c.asked_for(runs);
    Ok(c)
}

/// [`Campaign::status`] of a campaign a stop ended early.
pub const STATUS_INTERRUPTED: &str = "interrupted";

/// [`Campaign::status`] of a campaign whose every run ran and at least one estimate came of it.
pub const STATUS_COMPLETE: &str = "complete";

/// [`Campaign::status`] of a campaign whose every run failed as a whole (no trim, no
/// simulation): its statistics are empty, not a result.
pub const STATUS_FAILED: &str = "failed";

/// [`Campaign::status`] of a campaign whose runs ran but no estimator gave an estimate in any of
/// them (every one failed, diverged, or identified nothing): its statistics are empty.
pub const STATUS_NO_ESTIMATES: &str = "no_estimates";

/// The status and its reason of a campaign of `runs` runs that is not a result (every run
/// failed, or no estimate in any), `None` for one that is; the reason quotes the first
/// failure and counts the others.
fn outcome_status(
    runs: usize,
    failed: &[FailedRun],
    estimators: &[EstimatorStats],
) -> Option<(&'static str, String)> {
    if runs == 0 {
        return None;
    }
    if failed.len() == runs {
        let first = &failed[0];
        return Some((
            STATUS_FAILED,
            format!("every one of the {runs} runs failed (run {}: {})", first.run, first.reason),
        ));
    }
    let estimated =
        estimators.iter().any(|e| e.runs_ok > 0 && e.parameters.iter().any(|p| p.n_estimates > 0));
    if estimated {
        return None;
    }
    let first = estimators.iter().find_map(|e| e.failed_runs.first().map(|f| (e, f)));
    let why = match first {
        Some((e, f)) => format!(" (`{}` in run {}: {})", e.name, f.run, f.reason),
        None => " (no parameter was identified by the end of any run)".to_string(),
    };
    Some((
        STATUS_NO_ESTIMATES,
        format!("none of the {runs} runs gave an estimate of any estimator{why}"),
    ))
}

/// The campaign document from per-run results (any order of computation; `results` sorted by
/// index, one per run): the Cramér–Rao prediction, [`statistics`] and the failed runs. Shared
/// by [`campaign`] and the Python bindings' distributed reduce.
pub fn assemble(
    sc: &Scenario,
    seed: u64,
    results: Vec<RunResult>,
    wall_s: f64,
    threads: usize,
) -> Campaign {
    let crb = crb_sigmas(sc).unwrap_or_else(|e| CrbTable { notes: vec![e], ..Default::default() });
    let names: Vec<String> = sc.estimator.iter().map(EstimatorSpec::label).collect();
    let ran = Ran { name: sc.name.clone(), seed, wall_s, threads };
    document(ran, results, &names, crb)
}

/// What a campaign's document says of how it ran.
pub(crate) struct Ran {
    /// The scenario's (or aircraft's) name.
    pub name: String,
    /// The campaign seed.
    pub seed: u64,
    /// Wall time of the runs, s.
    pub wall_s: f64,
    /// Threads they ran on.
    pub threads: usize,
}

/// The campaign document of `results` (sorted by index, one per run) of the estimators
/// `names` with the bound `crb`: [`statistics`], the failed runs and the status.
pub(crate) fn document(
    ran: Ran,
    results: Vec<RunResult>,
    names: &[String],
    crb: CrbTable,
) -> Campaign {
    let estimators = statistics(&results, names, &crb);
    let failed_runs: Vec<FailedRun> = results
        .iter()
        .filter_map(|r| {
            r.outcome.as_ref().err().map(|e| FailedRun { run: r.index, reason: e.clone() })
        })
        .collect();
    let (status, status_reason) = match outcome_status(results.len(), &failed_runs, &estimators) {
        Some((status, why)) => (status, Some(why)),
        None => (STATUS_COMPLETE, None),
    };
    Campaign {
        schema_version: aeroident_io::SCHEMA_VERSION,
        scenario: ran.name,
        runs: results.len() as u64,
        runs_requested: results.len() as u64,
        status,
        status_reason,
        seed: ran.seed,
        seed_rule: SEED_RULE,
        failed_runs,
        estimators,
        crb_notes: crb.notes,
        wall_s: ran.wall_s,
        threads: ran.threads,
        results,
    }
}

/// The `--json` document: exactly `{"schema_version", "status", "status_reason", "runs", "runs_requested",
/// "estimators": [{"name", "parameters": [{"name",
/// "reference", "bias", "scatter", "mean_std_error", "coverage_2sigma", "crb_std_error",
/// "crb_std_error_calm", "median_time_to_10pct_s"}]}]}` (`reference`: the truth at the end;
/// `crb_std_error`: the bound of the experiment flown; `crb_std_error_calm`: white sensor noise
/// only, [`crb_sigmas`]). `status` is `complete`, `interrupted` when a stop ended the campaign
/// after `runs` of `runs_requested`, `failed` or `no_estimates` ([`Campaign::status`]).
pub fn json_summary(c: &Campaign) -> serde_json::Value {
    serde_json::json!({
        "schema_version": c.schema_version,
        "status": c.status,
        "status_reason": c.status_reason,
        "runs": c.runs,
        "runs_requested": c.runs_requested,
        "estimators": c.estimators.iter().map(|e| serde_json::json!({
            "name": e.name,
            "parameters": e.parameters.iter().map(|p| serde_json::json!({
                "name": p.name,
                "reference": p.reference,
                "bias": p.bias,
                "scatter": p.scatter,
                "mean_std_error": p.mean_std_error,
                "coverage_2sigma": p.coverage_2sigma,
                "crb_std_error": p.crb_std_error,
                "crb_std_error_calm": p.crb_std_error_calm,
                "median_time_to_10pct_s": p.median_time_to_10pct_s,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

impl ParamStats {
    /// The bias of the mean estimate in percent of |truth| (`100 · bias / |truth|`); `None`
    /// without a bias or a truth, or when |truth| is below
    /// [`ZERO_THRESHOLD`] (round-off of an exact zero).
    pub fn bias_percent_of_truth(&self) -> Option<f64> {
        match (self.bias, self.reference) {
            (Some(b), Some(tr)) if tr.abs() > ZERO_THRESHOLD => Some(100.0 * b / tr.abs()),
            _ => None,
        }
    }

    /// The truth with a magnitude below [`ZERO_THRESHOLD`]
    /// (round-off of an exact zero) as 0.
    pub fn truth_or_zero(&self) -> Option<f64> {
        self.reference.map(|x| if x.abs() < ZERO_THRESHOLD { 0.0 } else { x })
    }

    /// The scatter over the Cramér–Rao σ of the experiment flown (`scatter / crb_std_error`, –;
    /// ≈ 1 for an efficient estimator); `None` without either.
    pub fn scatter_over_crb(&self) -> Option<f64> {
        self.scatter.zip(self.crb_std_error).map(|(a, b)| a / b)
    }
}

impl EstimatorStats {
    /// Whether the estimator is a post-flight (batch) fit: it has no estimate before the end,
    /// so no time to ±10 % ([`EstimatorStats::mean_fit_wall_s`] is set).
    pub fn is_batch(&self) -> bool {
        self.mean_fit_wall_s.is_some()
    }
}

impl Campaign {
    /// Records that `runs` were asked for: a campaign that did fewer (a stop ended it) is
    /// `interrupted`, its statistics over the runs done.
    pub fn asked_for(&mut self, runs: u64) {
        self.runs_requested = runs;
        if self.runs < runs {
            self.status = STATUS_INTERRUPTED;
            self.status_reason = Some(format!(
                "stopped on request after {} of {runs} runs: the statistics are over those {}",
                self.runs, self.runs
            ));
        }
    }

    /// The final estimates of the parameter named `param` of the estimator named `estimator`
    /// over the runs whose experiment succeeded and in which that estimator neither failed
    /// nor diverged, in run order (the sample of [`ParamStats::bias`] and
    /// [`ParamStats::scatter`]; the parameter's position is its first in the estimator's
    /// [`EstimatorStats::parameters`]). Empty for an unknown name.
    pub fn final_estimates(&self, estimator: &str, param: &str) -> Vec<f64> {
        let Some(j) = self
            .estimators
            .iter()
            .find(|e| e.name == estimator)
            .and_then(|e| e.parameters.iter().position(|q| q.name == param))
        else {
            return Vec::new();
        };
        self.results
            .iter()
            .filter_map(|r| r.outcome.as_ref().ok())
            .filter_map(|ests| ests.iter().find(|x| x.name == estimator))
            .filter(|x| x.failure.is_none())
            .filter_map(|x| x.params.get(j).and_then(|q| q.estimate))
            .collect()
    }

    /// The names of the primary derivatives ([`ParamStats::primary`]) any estimator has, in
    /// the order they first appear (estimators in order).
    pub fn primary_parameters(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for p in self.estimators.iter().flat_map(|e| &e.parameters).filter(|p| p.primary) {
            if !names.contains(&p.name) {
                names.push(p.name.clone());
            }
        }
        names
    }

    /// Per estimator with at least one ±2σ coverage, its name and its
    /// [`ParamStats::coverage_2sigma`] (fraction of runs, 0–1) of each of `params` (`None`
    /// where it has no such parameter or no coverage).
    pub fn coverage_by_estimator(&self, params: &[String]) -> Vec<(String, Vec<Option<f64>>)> {
        self.estimators
            .iter()
            .filter(|e| e.parameters.iter().any(|p| p.coverage_2sigma.is_some()))
            .map(|e| {
                let vals = params
                    .iter()
                    .map(|n| {
                        e.parameters.iter().find(|p| &p.name == n).and_then(|p| p.coverage_2sigma)
                    })
                    .collect();
                (e.name.clone(), vals)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
