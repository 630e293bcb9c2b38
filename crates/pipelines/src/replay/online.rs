//! The online replay's loop, as named stages over one state: each record event is read
//! ([`Replay::event`]), the first sample fixes the model and builds the estimator
//! ([`Replay::start`]), samples are conditioned by the derivative stage, the conditioned ones
//! estimated ([`Replay::estimate`]), and the end of the record summarised
//! ([`Replay::finish`]). [`super::replay_with`] runs them in that order.

use super::prediction::{Recorder, validate_coefficients};
use super::{
    History, KIND_NOT_CENTRED, Pacer, Pacing, ReplayError, ReplayObserver, ReplayOptions,
    ReplayOutcome, choose_model, derivatives_to_supply, diagnostics, explain, model_line,
    settle_time_s,
};
use crate::condition::{Alignment, Conditioner, Conditioning};
use crate::estimators::{BuildError, EstimatorKind};
use crate::record::unsupported;
use crate::sample_log::SampleLog;
use aeroident_estimators::{AirDataSample, Estimator, Status};
use aeroident_io::mapping::{Channel, Mapping};
use aeroident_io::replay_output::{
    CoefficientSummary, Correlation, EventsSummary, ParameterSummary, ReplaySummary,
};
use aeroident_io::warning::{Warning, WarningKind};
use aeroident_io::{
    FlightDataError, ModelSpec, ParameterResult, RecordEvent, Rejection, RejectionLog,
    StdErrorSource,
};
use std::time::{Duration, Instant};

/// `rls-iv` on differentiated rates: the instruments must lie beyond the differentiator's
/// half-span `(N−1)/2`, or the rate's noise reaches both the instrument and the measured
/// moment and the estimate is biased (`aeroident_estimators::iv`, "Instruments").
fn check_instrument_delay(opts: &ReplayOptions, differentiates: bool) -> Result<(), ReplayError> {
    let given = opts.estimator_options.instrument_delay;
    let d = crate::estimators::instrument_delay(given, opts.diff_window);
    let half = (opts.diff_window - 1) / 2;
    if opts.estimator != EstimatorKind::RlsIv || !differentiates || d > half {
        return Ok(());
    }
    let max = aeroident_estimators::iv::MAX_INSTRUMENT_DELAY;
    let fix = if half < max {
        format!("use --instrument-delay above {half}")
    } else {
        format!("the delay is at most {max} samples: use --diff-window {} or less", 2 * max - 1)
    };
    Err(ReplayError::Option {
        option: "instrument-delay",
        reason: format!(
            "{d} samples is within the differentiator's half-window of {half} samples (--diff-window {}): the differentiated rates' noise would reach the instruments; {fix}",
            opts.diff_window
        ),
    })
}

/// The running state once the first sample has fixed the model.
struct Running {
    est: Box<dyn Estimator>,
    stage: Conditioner,
    v0_mps: f64,
    spec: ModelSpec,
    defaulted: bool,
}

/// Samples the sign tests keep of a long replay (about 20 MB), in contiguous blocks of
/// [`SIGN_TEST_BLOCK`] (5 s at 100 Hz: many central differences per block).
const SIGN_TEST_SAMPLES: usize = 32_768;
const SIGN_TEST_BLOCK: usize = 512;

/// One online replay in progress: what has been read, rejected, estimated and warned of.
pub(super) struct Replay<'a> {
    mapping: &'a Mapping,
    opts: &'a ReplayOptions,
    observer: &'a mut dyn ReplayObserver,
    file: String,
    uses_measured: bool,
    mapped_v0: Option<f64>,
    rejections: RejectionLog,
    samples_read: usize,
    samples_rejected: usize,
    run: Option<Running>,
    history: History,
    fed: SampleLog<AirDataSample>,
    /// Each regressor channel's range over the estimated samples ([`super::constant`]).
    spread: super::constant::Spread,
    kinematics: crate::kinematics::Kinematics,
    /// The samples of the sign tests: contiguous blocks, so a long record decimated to fit
    /// still has central differences ([`super::sign_tests`]).
    sign_log: SampleLog<AirDataSample>,
    recorder: Recorder,
    /// Time spent in the estimator's update (the throughput of the estimation stage).
    busy: Duration,
    pacer: Pacer,
    warnings: aeroident_io::warning::Warnings,
    diverged: bool,
    /// The observer asked the replay to stop before the end of the record.
    interrupted: bool,
    /// Restarts of the estimator seen so far: each is reported when it happens (on a live
    /// feed the estimates fall back to the priors then, not at the end).
    restarts_seen: u32,
    /// Change alarms of the estimator seen so far, reported likewise as they happen.
    changes_seen: u32,
    /// Samples the derivative stage released this event, and rows it could not centre.
    ready: Vec<(u64, AirDataSample)>,
    unused: Vec<u64>,
}

impl<'a> Replay<'a> {
    /// A replay of `file` (named in errors) through `mapping` with `opts`.
    pub(super) fn new(
        file: String,
        mapping: &'a Mapping,
        opts: &'a ReplayOptions,
        observer: &'a mut dyn ReplayObserver,
    ) -> Self {
        Self {
            mapping,
            opts,
            observer,
            file,
            uses_measured: opts.estimator.uses_measured_coefficients(),
            mapped_v0: mapping.channels.get(&Channel::V0).and_then(|m| m.constant()),
            rejections: RejectionLog::default(),
            samples_read: 0,
            samples_rejected: 0,
            run: None,
            history: History::default(),
            fed: SampleLog::new(crate::results::MAX_FIT_SAMPLES, 1),
            spread: super::constant::Spread::default(),
            kinematics: crate::kinematics::Kinematics::default(),
            sign_log: SampleLog::new(SIGN_TEST_SAMPLES, SIGN_TEST_BLOCK),
            recorder: Recorder::default(),
            busy: Duration::ZERO,
            pacer: Pacer::default(),
            warnings: Default::default(),
            diverged: false,
            interrupted: false,
            restarts_seen: 0,
            changes_seen: 0,
            ready: Vec::new(),
            unused: Vec::new(),
        }
    }

    /// Whether the estimator diverged (the replay stops).
    pub(super) fn diverged(&self) -> bool {
        self.diverged
    }

    /// Whether the observer asks the replay to stop (asked between events, so the sample in
    /// hand is finished); once asked, the replay stays interrupted.
    pub(super) fn stop_requested(&mut self) -> bool {
        self.interrupted = self.interrupted || self.observer.stop_requested();
        self.interrupted
    }

    /// Reads one record event: a rejected row is counted, a gap restarts the differentiator
    /// and starts a new manoeuvre, a sample goes through the derivative stage (the first one
    /// fixes the model); then the samples the stage released are estimated.
    pub(super) fn event(
        &mut self,
        event: RecordEvent,
        make: &impl Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError>,
    ) -> Result<(), ReplayError> {
        self.ready.clear();
        self.unused.clear();
        self.observer.record_event(&event);
        match event {
            RecordEvent::Rejected { row, problem } => {
                self.samples_read += 1;
                self.samples_rejected += 1;
                self.rejections.push_row(row, &problem);
            }
            RecordEvent::Gap { row, dt_s, nominal_dt_s } => self.gap(row, dt_s, nominal_dt_s),
            RecordEvent::Sample { row, sample } => {
                self.samples_read += 1;
                if self.run.is_none() {
                    self.start(&sample, make)?;
                }
                self.condition(row, sample)?;
            }
        }
        self.reject_uncentred(
            "not estimated: no centred derivative (differentiator warm-up or gap)",
        );
        self.estimate()
    }

    fn gap(&mut self, row: u64, dt_s: f64, nominal_dt_s: f64) {
        self.rejections.push("gap", Rejection {
            row,
            reason: format!(
                "gap: {dt_s} s before this row (nominal {nominal_dt_s} s); not bridged: differentiator restarted, new manoeuvre for the estimator"
            ),
        });
        if let Some(r) = &mut self.run {
            r.stage.flush(&mut self.unused);
            r.est.new_manoeuvre();
            self.recorder.new_segment();
        }
        self.kinematics.new_segment();
        self.sign_log.new_segment();
        self.spread.new_manoeuvre();
    }

    /// The first sample: chooses the model, checks the record supports it, builds the
    /// estimator and the derivative stage.
    fn start(
        &mut self,
        sample: &AirDataSample,
        make: &impl Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError>,
    ) -> Result<(), ReplayError> {
        let (opts, mapping) = (self.opts, self.mapping);
        let (spec, defaulted) = choose_model(opts, mapping, sample, self.uses_measured)?;
        let spec = if self.uses_measured {
            spec
        } else {
            let (spec, note) = super::sideslip_level(spec, sample);
            if let Some(n) = note {
                self.observer.warning(&n);
                self.warnings.push(n);
            }
            spec
        };
        let supply =
            derivatives_to_supply(&spec.structure, opts.estimator, mapping, opts.derivatives);
        check_instrument_delay(opts, !supply.is_empty())?;
        let missing = unsupported(&spec.structure, sample, self.uses_measured, &supply);
        if !missing.is_empty() {
            return Err(ReplayError::Model(format!(
                "model `{}` is not supported by {} with {}: {}",
                spec.name,
                self.file,
                mapping.file,
                missing.join("; ")
            )));
        }
        let est = make(&spec)?;
        self.observer.model(&model_line(&spec, defaulted, &supply, opts.diff_window));
        self.history.names = spec.structure.names().collect();
        self.recorder = Recorder::for_structure(&spec.structure);
        self.observer.start(&self.history.names)?;
        self.run = Some(Running {
            est,
            stage: Conditioner::new(Conditioning {
                derivatives: supply,
                window: opts.diff_window,
                nominal_dt_s: mapping.nominal_dt_s,
                alignment: Alignment::Delay,
            }),
            v0_mps: self.mapped_v0.unwrap_or(sample.vt_mps),
            spec,
            defaulted,
        });
        Ok(())
    }

    /// Pushes one sample through the derivative stage (V0 filled in where unmapped).
    fn condition(&mut self, row: u64, sample: AirDataSample) -> Result<(), ReplayError> {
        let Some(r) = &mut self.run else { return Ok(()) };
        let mut s = sample;
        s.constants.v0_mps.get_or_insert(r.v0_mps);
        r.stage
            .push(row, s, &mut self.ready, &mut self.unused)
            .map_err(|e| ReplayError::Option { option: "diff-window", reason: e.to_string() })?;
        if let Some(w) = r.stage.take_warning() {
            self.observer.warning(&w);
            self.warnings.push(w);
        }
        Ok(())
    }

    /// Lists the rows the derivative stage could not centre, with `reason`.
    fn reject_uncentred(&mut self, reason: &str) {
        for row in self.unused.drain(..) {
            self.samples_rejected += 1;
            self.rejections.push(KIND_NOT_CENTRED, Rejection { row, reason: reason.into() });
        }
    }

    /// Feeds the released samples to the estimator, in order, until one diverges.
    fn estimate(&mut self) -> Result<(), ReplayError> {
        let ready = std::mem::take(&mut self.ready);
        for (row, s) in &ready {
            if !self.estimate_one(*row, s)? {
                break;
            }
        }
        self.ready = ready;
        Ok(())
    }

    /// Reports the estimator's new restarts and change alarms the moment they happen, on the
    /// live console and stream (the estimates jump then, not at the end of the record).
    fn report_events(&mut self, row: u64, t_s: f64) {
        use aeroident_estimators::EventKind;
        let Some(r) = self.run.as_ref() else { return };
        let (method, log) = (r.est.method(), r.est.events());
        let (restarts, changes) =
            (log.count(EventKind::Restart), log.count(EventKind::ChangeDetected));
        let mut lines = Vec::new();
        if restarts > self.restarts_seen {
            lines.push(format!(
                "estimator `{method}` restarted from its priors at t = {t_s} s (row {row}); its estimates come from the samples after it only"
            ));
        }
        if changes > self.changes_seen {
            // The event itself when the log still lists it (its subject and statistic).
            let last = log.listed().iter().rev().find(|e| e.kind == EventKind::ChangeDetected);
            let subject = last.map_or(String::new(), |e| format!(" of `{}`", e.subject));
            let statistic = last
                .and_then(|e| e.statistic)
                .map_or(String::new(), |g| format!(", statistic {g:.1}"));
            lines.push(format!(
                "estimator `{method}` detected a change{subject} at t = {t_s} s (row {row}{statistic}); its memory of it was re-opened (docs/change-detection.md)"
            ));
        }
        (self.restarts_seen, self.changes_seen) = (restarts, changes);
        for line in lines {
            self.observer.warning(&line);
        }
    }

    /// One estimator update; `false` when the estimator diverged (the replay stops). A
    /// numerical failure on valid input is a divergence (the estimator's status says so,
    /// with or without an error); any other error refuses this sample only.
    fn estimate_one(&mut self, row: u64, s: &AirDataSample) -> Result<bool, ReplayError> {
        let Some(r) = self.run.as_mut() else { return Ok(true) };
        let t_in = Instant::now();
        let result =
            r.est.update(s).copied().map_err(|e| explain::estimator_error(&e, self.mapping));
        self.busy += t_in.elapsed();
        if r.est.estimates().status == Status::Diverged {
            let why = result.err().map_or(String::new(), |e| format!(" ({e})"));
            let reason = format!(
                "estimator `{}` diverged at t = {} s{why}; replay stopped",
                r.est.method(),
                s.t_s
            );
            self.rejections.push("estimator diverged", Rejection { row, reason });
            self.diverged = true;
            return Ok(false);
        }
        self.report_events(row, s.t_s);
        let e = match result {
            Ok(e) => e,
            Err(err) => {
                self.samples_rejected += 1;
                let reason = format!("estimator refused sample: {err}");
                self.rejections.push("estimator refused sample", Rejection { row, reason });
                return Ok(true);
            }
        };
        let n = self.history.names.len();
        let values: Vec<Option<f64>> = (0..n).map(|i| e.value(i)).collect();
        let sigmas: Vec<Option<f64>> = (0..n).map(|i| e.sigma(i)).collect();
        self.pace(s.t_s);
        self.observer.sample(s);
        self.observer.estimate(s.t_s, &values, &sigmas)?;
        self.history.push(s.t_s, values, sigmas);
        if !self.opts.estimates_only {
            self.recorder.push(s);
            self.fed.push(*s);
            self.spread.push(s);
            self.kinematics.push(s);
            self.sign_log.push(*s);
        }
        Ok(true)
    }

    /// With [`Pacing::Realtime`], waits until the wall clock reaches sample time `t_s`.
    fn pace(&mut self, t_s: f64) {
        if self.opts.pacing != Pacing::Realtime {
            return;
        }
        let dt = self.run.as_ref().and_then(|r| r.stage.dt_s()).or(self.mapping.nominal_dt_s);
        let (wait, note) = self.pacer.wait(t_s, dt, Instant::now());
        if let Some(n) = note {
            self.observer.warning(&n);
            self.warnings.push(n);
        }
        if !wait.is_zero() {
            std::thread::sleep(wait);
        }
    }

    /// The end of the record: the last samples the differentiator could not centre, the
    /// summary, the validation on the record and the identifiability measures.
    ///
    /// # Errors
    /// No usable sample; a failed write of the observer.
    pub(super) fn finish(mut self) -> Result<ReplayOutcome, ReplayError> {
        self.history.finish();
        // A request that came while the reader waited (a live feed ended by its reader on the
        // request) is an interruption too.
        self.stop_requested();
        self.observer.finish()?;
        if let Some(r) = &mut self.run
            && !self.diverged
        {
            r.stage.flush(&mut self.unused);
            self.reject_uncentred(
                "not estimated: no centred derivative (end of record within the differentiator lag)",
            );
        }
        let no_samples = self.run.is_none() || (self.history.t_s.is_empty() && !self.diverged);
        let Some(r) = self.run.take().filter(|_| !no_samples) else {
            if self.interrupted {
                return Err(ReplayError::Interrupted {
                    file: self.file,
                    samples_read: self.samples_read,
                });
            }
            return Err(FlightDataError::NoSamples {
                file: self.file,
                rejected: self.samples_rejected,
                first: self.rejections.first(3),
            }
            .into());
        };
        let mut summary = self.summary(&r);
        summary.warnings.extend(self.spread.warnings(r.est.structure(), self.mapping));
        summary.warnings.extend(self.kinematics.warnings(self.mapping));
        let (sign_tests, sign_warnings) =
            super::sign_tests::checked_log(&self.sign_log, self.mapping);
        summary.sign_tests = sign_tests;
        summary.warnings.extend(sign_warnings);
        let differentiated = r.stage.supplies().to_vec();
        let n = r.est.structure().n_params();
        let final_covariance: Vec<Option<f64>> =
            (0..n * n).map(|k| r.est.covariance(k / n, k % n)).collect();
        let (validation, identifiability) = if self.diverged || self.opts.estimates_only {
            (None, None)
        } else {
            let values: Vec<Option<f64>> = summary.parameters.iter().map(|p| p.estimate).collect();
            let cov = |i: usize, j: usize| r.est.covariance(i, j);
            let v = validate_coefficients(
                &self.recorder,
                r.est.structure(),
                &values,
                &cov,
                &self.file,
                None,
            );
            let id = diagnostics::identifiability(r.est.structure(), &cov, &self.recorder, &values);
            for c in &id.collinear_regressors {
                summary.warnings.push(super::diagnostics::collinear_warning(c));
            }
            (Some(v), Some(id))
        };
        Ok(ReplayOutcome {
            model: r.spec,
            model_defaulted: r.defaulted,
            differentiated,
            history: self.history,
            summary,
            validation,
            identifiability,
            final_covariance,
            recorder: self.recorder,
            samples: self.fed,
            cross_check: None,
            repeatability: None,
            reader: Vec::new(),
        })
    }

    /// The summary document of the finished replay (warnings: the stage's, the estimator's
    /// sign and consistency checks, its restarts, the rejections not listed).
    fn summary(&mut self, r: &Running) -> ReplaySummary {
        let status = if self.diverged { Status::Diverged } else { r.est.estimates().status };
        let parameters = self.parameter_summaries(&r.spec);
        let (coefficients, correlations) = self.conditioning(r);
        let mut warnings = std::mem::take(&mut self.warnings);
        let status = if self.interrupted && !self.diverged {
            warnings.push(format!(
                "interrupted after {} rows (last estimated sample t = {} s): the estimates are those of the samples read until then; the estimator's own status was `{}`",
                self.samples_read,
                self.history.t_s.last().map_or("-".into(), |t| t.to_string()),
                status.name()
            ));
            super::STATUS_INTERRUPTED.to_string()
        } else if status == Status::Running {
            super::STATUS_COMPLETE.to_string()
        } else {
            status.name().to_string()
        };
        if !self.diverged {
            let values: Vec<Option<f64>> = parameters.iter().map(|p| p.estimate).collect();
            let sigmas: Vec<Option<f64>> = parameters.iter().map(|p| p.std_error).collect();
            warnings.extend(diagnostics::sign_warnings(r.est.structure(), &values, &sigmas));
            if let Some(nis) = r.est.nis() {
                let text = format!(
                    "normalised innovation squared (mean e²/S) = {nis:.2} (1 for a consistent filter; > 2 means its σ are optimistic, < 0.5 pessimistic)"
                );
                warnings.push(Warning::new(WarningKind::Consistency, text));
            }
        }
        // The estimator's events; its restarts were reported as they happened.
        let events = EventsSummary::from_log(r.est.events());
        warnings.extend(events.restart_warnings());
        // Throughput of the estimation stage: the estimator update per sample (CSV parsing,
        // differentiation, pacing and output are excluded).
        let secs = self.busy.as_secs_f64().max(1e-9);
        let (rejections, unlisted) = std::mem::take(&mut self.rejections).finish();
        warnings.extend(unlisted);
        ReplaySummary {
            schema_version: aeroident_io::SCHEMA_VERSION,
            estimator: r.est.method().to_string(),
            model: r.spec.name.clone(),
            alpha_knots_rad: r.spec.structure.knots().as_slice().to_vec(),
            status,
            samples_read: self.samples_read,
            samples_rejected: self.samples_rejected,
            rejections,
            throughput_samples_per_s: self.history.samples as f64 / secs,
            parameters,
            coefficients,
            correlations,
            events,
            warnings,
            sign_tests: Vec::new(),
        }
    }

    /// Each parameter's final estimate, σ (the estimator's covariance), the model file's
    /// reference and settling time (estimate, σ and settling time `null` after a divergence);
    /// the statuses are judged once the run is complete ([`super::verdict`]).
    fn parameter_summaries(&self, spec: &ModelSpec) -> Vec<ParameterSummary> {
        let h = &self.history;
        let last = if self.diverged { None } else { h.values.last() };
        h.names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let (estimate, std_error) = match last {
                    Some(v) => (v[i], h.sigmas.last().and_then(|s| s[i])),
                    None => (None, None),
                };
                let result =
                    ParameterResult::new(*name, estimate, std_error, spec.reference(name), None)
                        .with_source(StdErrorSource::Covariance);
                ParameterSummary {
                    result,
                    settle_time_s: if self.diverged { None } else { settle_time_s(h, i) },
                }
            })
            .collect()
    }

    /// Each coefficient's condition number and the strong correlations (none after a
    /// divergence).
    fn conditioning(&self, r: &Running) -> (Vec<CoefficientSummary>, Vec<Correlation>) {
        if self.diverged {
            let none = r
                .est
                .structure()
                .coefficients()
                .map(|c| CoefficientSummary { name: c.name().into(), condition_number: None })
                .collect();
            return (none, Vec::new());
        }
        (
            diagnostics::coefficient_conditions(r.est.as_ref()),
            diagnostics::strong_correlations(r.est.as_ref()),
        )
    }
}
