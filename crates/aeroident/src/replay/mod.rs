//! Replay of a recorded flight through an online estimator, sample by sample, causally.
//!
//! Pipeline per row: [`aeroident_io::FlightDataReader`] (CSV → SI sample, or a counted
//! rejection) → `q̇` (the record's, or the causal differentiator of
//! [`aeroident_signals::differentiate`] with the other channels delayed by its lag so the
//! regression stays aligned) → measured coefficients ([`coefficients`](crate::replay::coefficients)) → estimator update →
//! one estimates line (to `estimates.csv`, and to stdout in live mode).
//!
//! Nothing is dropped silently: every rejected row, every gap, every sample the differentiator
//! could not centre (its first and last `(N−1)/2` samples and those around a gap) and every
//! sample an estimator refused is listed in the summary's `rejections` and counted in
//! `samples_rejected` (gap entries are listed but count no sample).
//!
//! **settle_time_s** (summary): the first sample time after which the estimate stays, to the
//! end of the record, within `max(5 % of |final|, 2 σ_final)` of its final value (σ_final = 0
//! where the method gives none); `null` if the estimate is never defined.

pub mod coefficients;
pub mod online;
pub mod smpe;

use aeroident_estimators::EstimatorError;
use aeroident_estimators::regressors::CoefficientSample;
use aeroident_io::mapping::Mapping;
use aeroident_io::replay_output::{ParameterSummary, ReplaySummary};
use aeroident_io::{FlightDataError, FlightDataReader, FlightSample, RecordEvent, Rejection};
use aeroident_signals::differentiate::CausalDifferentiator;
use online::{EkfReplay, ModelTerms, OnlineEstimator, RlsSet};
use std::collections::VecDeque;
use std::io::{Read, Write};
use std::time::{Duration, Instant};

/// The estimator to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum EstimatorKind {
    /// Recursive least squares, equation error, for Cm, CL and CD.
    Rls,
    /// Augmented-state extended Kalman filter (states and parameters; recursive output error).
    Ekf,
    /// The thesis's sliding-mode estimator on the pitch equation.
    Smpe,
    /// The corrected sliding-mode estimator on the pitch equation.
    SmpeCorrected,
}

impl EstimatorKind {
    /// The name used on the command line and in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            EstimatorKind::Rls => "rls",
            EstimatorKind::Ekf => "ekf",
            EstimatorKind::Smpe => "smpe",
            EstimatorKind::SmpeCorrected => "smpe-corrected",
        }
    }
}

/// Where `q̇` comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum QdotSource {
    /// The record's `qdot` channel if mapped, else the causal differentiator.
    Auto,
    /// Always the causal differentiator of `q` (ignores a recorded `qdot`).
    Differentiate,
}

/// Replay pacing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pacing {
    /// As fast as possible.
    Unpaced,
    /// At the record's own rate (wall clock follows the time channel).
    Realtime,
}

/// Options of one replay.
#[derive(Debug, Clone, Copy)]
pub struct ReplayOptions {
    /// Estimator.
    pub estimator: EstimatorKind,
    /// Equation-error model structure (RLS, SMPE).
    pub terms: ModelTerms,
    /// RLS forgetting factor, (0, 1].
    pub forgetting: f64,
    /// `q̇` source.
    pub qdot: QdotSource,
    /// Differentiator window, samples (odd, ≥ 3).
    pub diff_window: usize,
    /// Pacing.
    pub pacing: Pacing,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        Self {
            estimator: EstimatorKind::Rls,
            terms: ModelTerms::Basic,
            forgetting: 1.0,
            qdot: QdotSource::Auto,
            diff_window: 5,
            pacing: Pacing::Unpaced,
        }
    }
}

/// Errors of a replay.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// Reading the record failed fatally.
    #[error(transparent)]
    Data(#[from] FlightDataError),
    /// The estimator could not be configured.
    #[error("estimator `{estimator}`: {source}")]
    Estimator {
        /// Estimator name.
        estimator: &'static str,
        /// The error.
        source: EstimatorError,
    },
    /// An option is invalid.
    #[error("option `{option}`: {reason}")]
    Option {
        /// Option name.
        option: &'static str,
        /// Why.
        reason: String,
    },
    /// Writing the live output failed.
    #[error("writing estimates: {0}")]
    Output(#[from] std::io::Error),
}

/// One sample ready for an estimator: the SI flight sample plus derived quantities.
#[derive(Debug, Clone, Copy)]
pub struct Prepared {
    /// The (possibly delayed) flight sample.
    pub flight: FlightSample,
    /// Line number of the sample in the file.
    pub row: u64,
    /// `q̇`, rad/s² (record or differentiator), when available.
    pub qdot_rad_s2: Option<f64>,
    /// Air density used by model-based estimators, kg/m³.
    pub rho_kgpm3: f64,
    /// α at the CG, rad.
    pub alpha_cg_rad: f64,
    /// Measured coefficients (needs `q̇`).
    pub coefficients: Option<CoefficientSample>,
}

/// The history of estimates over the record.
#[derive(Debug, Clone, Default)]
pub struct History {
    /// Parameter names.
    pub names: Vec<&'static str>,
    /// Times, s.
    pub t_s: Vec<f64>,
    /// `values[k][i]`: parameter `i` at time `k`.
    pub values: Vec<Vec<f64>>,
    /// `sigmas[k][i]`.
    pub sigmas: Vec<Vec<Option<f64>>>,
}

/// Result of a replay.
#[derive(Debug, Clone)]
pub struct ReplayOutcome {
    /// Estimates over time.
    pub history: History,
    /// The summary document.
    pub summary: ReplaySummary,
}

/// The causal `q̇` stage: passes the record's `q̇` through, or differentiates `q` and delays
/// the sample by the differentiator's lag. The sample interval is the mapping's
/// `nominal_dt_s`, else the first interval of the record.
struct QdotStage {
    differentiate: bool,
    window: usize,
    dt_s: Option<f64>,
    diff: Option<CausalDifferentiator>,
    delay: VecDeque<(u64, FlightSample)>,
}

impl QdotStage {
    /// Pushes a sample; appends the samples ready now to `ready` and the rows that can never
    /// get a centred `q̇` (warm-up) to `unused`.
    fn push(
        &mut self,
        row: u64,
        s: FlightSample,
        ready: &mut Vec<(u64, FlightSample, Option<f64>)>,
        unused: &mut Vec<u64>,
    ) -> Result<(), ReplayError> {
        if !self.differentiate {
            ready.push((row, s, s.qdot_rad_s2));
            return Ok(());
        }
        if self.diff.is_none() {
            // Until the interval is known, hold the first sample.
            let dt = match (self.dt_s, self.delay.front()) {
                (Some(dt), _) => dt,
                (None, Some((_, first))) => s.t_s - first.t_s,
                (None, None) => {
                    self.delay.push_back((row, s));
                    return Ok(());
                }
            };
            let mut d = CausalDifferentiator::new(self.window, dt).map_err(|e| {
                ReplayError::Option { option: "diff-window", reason: e.to_string() }
            })?;
            for (_, held) in &self.delay {
                d.update(held.q_rad_s);
            }
            self.diff = Some(d);
        }
        let half = self.window / 2;
        let Some(diff) = self.diff.as_mut() else { return Ok(()) };
        self.delay.push_back((row, s));
        let d = diff.update(s.q_rad_s);
        if self.delay.len() > half + 1 {
            // Only during warm-up can the delay line overflow: these never get a centred q̇.
            if let Some((r, _)) = self.delay.pop_front() {
                unused.push(r);
            }
        }
        if let Some(d) = d
            && let Some((r, c)) = self.delay.pop_front()
        {
            ready.push((r, FlightSample { qdot_rad_s2: Some(d), ..c }, Some(d)));
        }
        Ok(())
    }

    /// Restarts after a gap (or at the end): the delayed samples are unused.
    fn flush(&mut self, unused: &mut Vec<u64>) {
        if let Some(d) = self.diff.as_mut() {
            d.reset();
        }
        unused.extend(self.delay.drain(..).map(|(r, _)| r));
    }
}

/// Replays a record through the chosen estimator.
///
/// `live`: when given, one CSV line of estimates is written (and flushed) per sample as it is
/// produced, after a header line. `estimates`: the same lines to a second sink (the
/// `estimates.csv` file). Each line: `t_s, <names>, sigma_<names>`.
///
/// # Errors
/// [`ReplayError`] for fatal data errors (missing column, unreadable CSV), invalid options, an
/// estimator that cannot be configured, no usable sample, or a failed write.
pub fn replay<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
    mut sinks: Vec<&mut dyn Write>,
) -> Result<ReplayOutcome, ReplayError> {
    if opts.diff_window < 3 || opts.diff_window.is_multiple_of(2) {
        return Err(ReplayError::Option {
            option: "diff-window",
            reason: format!("must be odd and ≥ 3 (a whole-sample lag), got {}", opts.diff_window),
        });
    }
    let file = reader.file().to_string();
    let mut rejections: Vec<Rejection> = Vec::new();
    let mut samples_read = 0usize;
    let mut samples_rejected = 0usize;
    let mut estimator: Option<Box<dyn OnlineEstimator>> = None;
    let mut qdot_stage: Option<QdotStage> = None;
    let mut v0: Option<f64> = mapping_v0(mapping);
    let mut history = History::default();
    let mut busy = Duration::ZERO;
    let mut ready = Vec::new();
    let mut unused = Vec::new();
    let mut values = Vec::new();
    let mut sigmas = Vec::new();
    let mut clock: Option<(Instant, f64)> = None;
    let has_record_qdot = mapping.channels.contains_key(&aeroident_io::Channel::Qdot);
    for item in reader {
        let event = item?;
        ready.clear();
        unused.clear();
        match event {
            RecordEvent::Rejected { row, problem } => {
                samples_read += 1;
                samples_rejected += 1;
                rejections.push(Rejection { row, reason: problem.to_string() });
            }
            RecordEvent::Gap { row, dt_s, nominal_dt_s } => {
                rejections.push(Rejection {
                    row,
                    reason: format!("gap: {dt_s} s before this row (nominal {nominal_dt_s} s); not bridged, differentiator restarted"),
                });
                if let Some(q) = &mut qdot_stage {
                    q.flush(&mut unused);
                }
            }
            RecordEvent::Sample { row, sample } => {
                samples_read += 1;
                if estimator.is_none() {
                    let v0_mps = *v0.get_or_insert(sample.vt_mps);
                    let first = prepare(row, sample, sample.qdot_rad_s2, v0_mps);
                    let est = build_estimator(opts, &first, v0_mps, mapping).map_err(|source| {
                        ReplayError::Estimator { estimator: opts.estimator.name(), source }
                    })?;
                    let differentiate = est.needs_coefficients()
                        && (opts.qdot == QdotSource::Differentiate || !has_record_qdot);
                    qdot_stage = Some(QdotStage {
                        differentiate,
                        window: opts.diff_window,
                        dt_s: mapping.nominal_dt_s,
                        diff: None,
                        delay: VecDeque::with_capacity(opts.diff_window),
                    });
                    history.names = est.names();
                    values = vec![0.0; history.names.len()];
                    sigmas = vec![None; history.names.len()];
                    for s in sinks.iter_mut() {
                        aeroident_io::replay_output::write_estimates_header(s, &history.names)?;
                    }
                    estimator = Some(est);
                }
                if let Some(q) = &mut qdot_stage {
                    q.push(row, sample, &mut ready, &mut unused)?;
                }
            }
        }
        for r in unused.drain(..) {
            samples_rejected += 1;
            rejections.push(Rejection {
                row: r,
                reason: "not estimated: no centred q̇ (differentiator warm-up or gap)".into(),
            });
        }
        let (Some(est), Some(v0_mps)) = (estimator.as_mut(), v0) else {
            continue;
        };
        for (row, s, qdot) in ready.drain(..) {
            let t_in = Instant::now();
            let p = prepare(row, s, qdot, v0_mps);
            let result = est.update(&p);
            busy += t_in.elapsed();
            if let Err(e) = result {
                samples_rejected += 1;
                rejections
                    .push(Rejection { row, reason: format!("estimator refused sample: {e}") });
                continue;
            }
            est.current(&mut values, &mut sigmas);
            if opts.pacing == Pacing::Realtime {
                let (start, t_first) = *clock.get_or_insert((Instant::now(), s.t_s));
                let due = start + Duration::from_secs_f64((s.t_s - t_first).max(0.0));
                let now = Instant::now();
                if due > now {
                    std::thread::sleep(due - now);
                }
            }
            for sink in sinks.iter_mut() {
                aeroident_io::replay_output::write_estimates_row(sink, s.t_s, &values, &sigmas)?;
                sink.flush()?;
            }
            history.t_s.push(s.t_s);
            history.values.push(values.clone());
            history.sigmas.push(sigmas.clone());
        }
    }
    if let Some(q) = &mut qdot_stage {
        q.flush(&mut unused);
        for r in unused.drain(..) {
            samples_rejected += 1;
            rejections.push(Rejection {
                row: r,
                reason: "not estimated: no centred q̇ (end of record within the differentiator lag)"
                    .into(),
            });
        }
    }
    if history.t_s.is_empty() {
        return Err(FlightDataError::NoSamples { file, rejected: samples_rejected }.into());
    }
    // Throughput of the estimation stage: coefficient preparation and estimator update per
    // sample (CSV parsing, pacing and output are excluded).
    let secs = busy.as_secs_f64().max(1e-9);
    let parameters = history
        .names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let last = history.values.len() - 1;
            ParameterSummary {
                name: (*name).to_string(),
                estimate: history.values[last][i],
                std_error: history.sigmas[last][i],
                settle_time_s: settle_time_s(&history, i),
            }
        })
        .collect();
    let summary = ReplaySummary {
        estimator: opts.estimator.name().to_string(),
        samples_read,
        samples_rejected,
        rejections,
        throughput_samples_per_s: history.t_s.len() as f64 / secs,
        parameters,
    };
    Ok(ReplayOutcome { history, summary })
}

fn mapping_v0(mapping: &Mapping) -> Option<f64> {
    match mapping.channels.get(&aeroident_io::Channel::V0).map(|m| &m.source) {
        Some(aeroident_io::mapping::Source::Constant(v)) => Some(*v),
        _ => None,
    }
}

fn prepare(row: u64, s: FlightSample, qdot: Option<f64>, v0_mps: f64) -> Prepared {
    let rho = coefficients::rho_kgpm3(&s).unwrap_or(f64::NAN);
    Prepared {
        flight: s,
        row,
        qdot_rad_s2: qdot,
        rho_kgpm3: rho,
        alpha_cg_rad: coefficients::alpha_cg_rad(&s),
        coefficients: qdot
            .and_then(|qd| coefficients::coefficient_sample(&s, qd, s.v0_mps.unwrap_or(v0_mps))),
    }
}

fn build_estimator(
    opts: &ReplayOptions,
    first: &Prepared,
    v0_mps: f64,
    mapping: &Mapping,
) -> Result<Box<dyn OnlineEstimator>, EstimatorError> {
    Ok(match opts.estimator {
        EstimatorKind::Rls => Box::new(RlsSet::new(opts.terms, opts.forgetting)?),
        EstimatorKind::Ekf => Box::new(EkfReplay::new(first, v0_mps, &mapping.ekf)?),
        EstimatorKind::Smpe => Box::new(smpe::SmpeReplay::new(smpe::SmpeVariant::Published)?),
        EstimatorKind::SmpeCorrected => {
            Box::new(smpe::SmpeReplay::new(smpe::SmpeVariant::Corrected)?)
        }
    })
}

/// Settling time of parameter `i`, s (definition in the module doc).
pub fn settle_time_s(h: &History, i: usize) -> Option<f64> {
    let last = h.values.last()?;
    let fin = last[i];
    let sigma = h.sigmas.last().and_then(|s| s[i]).unwrap_or(0.0);
    let band = (0.05 * fin.abs()).max(2.0 * sigma);
    let mut first_in = None;
    for (k, v) in h.values.iter().enumerate().rev() {
        if (v[i] - fin).abs() <= band {
            first_in = Some(h.t_s[k]);
        } else {
            break;
        }
    }
    first_in
}
