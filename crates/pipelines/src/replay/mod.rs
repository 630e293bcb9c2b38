//! Replay of a recorded flight through an online estimator, sample by sample, causally.
//!
//! Pipeline per row: [`aeroident_io::FlightDataReader`] (CSV → SI [`AirDataSample`] at the CG,
//! or a counted rejection) → the [conditioning stage](crate::condition) (the `ṗ, q̇, ṙ, α̇` the
//! model needs and the record lacks, from a causal differentiator, every channel delayed by its
//! lag) →
//! `Box<dyn Estimator>` from [`crate::estimators::build`] (measured coefficients are the core's
//! [`AirDataSample::measured_coefficients`]) → one estimates line (to `estimates.csv`, and to
//! stdout in live mode).
//!
//! **Model.** The one given (`--model`), else the richest preset (`six-axis`, `longitudinal`,
//! `lateral`) the first sample supports: every term formed from its channels and constants,
//! and, for estimators on measured coefficients, every modelled coefficient measurable
//! (derivatives the stage will supply count as present). A `V/V0` term without a mapped `v0`
//! uses the first sample's V as V0.
//!
//! **Gaps.** At a [`RecordEvent::Gap`](aeroident_io::RecordEvent::Gap) the differentiator restarts and the estimator is told
//! that a new manoeuvre starts ([`Estimator::new_manoeuvre`]: model states re-initialised,
//! parameters kept); nothing is bridged.
//!
//! Nothing is dropped silently: every rejected row, every gap, every sample the differentiator
//! could not centre (its first and last `(N−1)/2` samples and those around a gap) and every
//! sample an estimator refused is listed in the summary's `rejections` and counted in
//! `samples_rejected` (gap entries are listed but count no sample). The list is bounded
//! ([`RejectionLog`](aeroident_io::RejectionLog)): the first 1,000 entries and always the last; the others are counted per
//! kind in a warning (`N further rejections not listed: …`). A diverged estimator stops
//! the replay (its row is listed) and the summary's `status` is `diverged`, with every estimate
//! `null`.
//!
//! **settle_time_s** (summary): the first sample time after which the estimate stays, to the
//! end of the record, within `max(5 % of |final|, 2 σ_final)` of its final value (σ_final = 0
//! where the method gives none); `null` if the final estimate is not identified.
//!
//! **Validation and identifiability** (summary keys `validation`, `validation_on`,
//! `identifiability`; [`ReplayOutcome::document`]): after the replay, every modelled measured
//! coefficient is predicted from its regressors with the final estimates and compared with
//! the measured one ([`prediction::validate_coefficients`], metrics in [`crate::validation`]);
//! [`validate_on`] does the same on a second record not used for the fit. The record's
//! identifiability measures are [`diagnostics::identifiability`].

pub mod arrays;
pub mod batch;
pub mod constant;
pub mod cross_check;
pub mod diagnostics;
pub mod explain;
pub mod fed;
pub mod fit;
pub mod frequency;
mod online;
pub use aeroident_registry::precision;
pub mod prediction;
pub mod repeatability;
pub mod sample_timing;
pub mod sign_tests;
pub use aeroident_registry::unmodelled;
pub mod verdict;

use crate::condition::Derivative;
use crate::estimators::{BuildError, EstimatorKind, EstimatorOptions, build};
use crate::record::{RecordError, check_spike_screen, outliers, record_events, unsupported};
use aeroident_estimators::{AirDataSample, Coefficient, Estimator, ModelStructure, Status, Term};
use aeroident_io::mapping::{Channel, Mapping};
use aeroident_io::replay_output::ReplaySummary;
use aeroident_io::{FlightDataError, FlightDataReader, ModelSpec, ReaderReport};
use prediction::{Frozen, Recorder, ValidationReport, validate_coefficients};
use std::io::{Read, Write};
use std::time::{Duration, Instant};

/// Where the derivatives `ṗ, q̇, ṙ, α̇` come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DerivativeSource {
    /// The record's channel where mapped, else the causal differentiator.
    Auto,
    /// Always the causal differentiator (ignores recorded derivatives).
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
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Estimator.
    pub estimator: EstimatorKind,
    /// Model structure and priors; `None`: the richest preset the first sample supports.
    pub model: Option<ModelSpec>,
    /// The estimator's own options, as the registry parsed them from the face's key/value
    /// pairs ([`crate::estimators::parse_options`]); an `instrument_delay` of `None` is the
    /// differentiator window's ([`crate::estimators::instrument_delay`]).
    pub estimator_options: EstimatorOptions,
    /// Source of the derivatives.
    pub derivatives: DerivativeSource,
    /// Differentiator window, samples (odd, ≥ 3).
    pub diff_window: usize,
    /// Pacing.
    pub pacing: Pacing,
    /// A compatibility check's corrections, applied to every sample before the conditioning
    /// stage ([`crate::compat::Corrected`]); the summary's warnings list them.
    pub compat: Option<crate::record::Corrections>,
    /// The time windows of the record used, each its own manoeuvre ([`crate::window`]); empty:
    /// the whole record.
    pub windows: Vec<crate::window::TimeWindow>,
    /// The spike screen before every estimator ([`outliers`]); `None`: off. Default on.
    pub spike_screen: Option<outliers::SpikeScreen>,
    /// Only the estimates and their σ (a refit that reads nothing else: the panel, the
    /// regressor-noise and timing tests): no residual validation, identifiability or sign
    /// tests, and none of the samples they need kept. Default off.
    pub estimates_only: bool,
}

/// What a face sees of a replay while it runs: the model once chosen, each identified sample's
/// estimates, warnings as they arise. Every method defaults to doing nothing, so `()` observes
/// nothing; [`EstimateRows`] writes the estimates as CSV lines.
pub trait ReplayObserver {
    /// Once, when the first sample has chosen the model: a line naming it.
    fn model(&mut self, _line: &str) {}

    /// Once, with the parameter names, before the first [`estimate`](Self::estimate).
    ///
    /// # Errors
    /// A failed write.
    fn start(&mut self, _names: &[&str]) -> std::io::Result<()> {
        Ok(())
    }

    /// One accepted sample's estimates and σ (`None`: not identified / no σ), in the order of
    /// the names given to [`start`](Self::start); `t_s` is the sample's time, s.
    ///
    /// # Errors
    /// A failed write.
    fn estimate(
        &mut self,
        _t_s: f64,
        _values: &[Option<f64>],
        _sigmas: &[Option<f64>],
    ) -> std::io::Result<()> {
        Ok(())
    }

    /// A warning, the moment it arises (those about the data are also kept in the summary).
    fn warning(&mut self, _text: &str) {}

    /// Each record event as it is read (a sample, a rejected row, a gap), before the replay
    /// acts on it: what a live view counts of the feed.
    fn record_event(&mut self, _event: &aeroident_io::RecordEvent) {}

    /// The conditioned sample fed to the estimator, just before the
    /// [`estimate`](Self::estimate) it gives (a sample the estimator refuses gives none): its
    /// inputs are what a live view draws beside the estimates.
    fn sample(&mut self, _sample: &AirDataSample) {}

    /// Once at the end of the record.
    ///
    /// # Errors
    /// A failed write.
    fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }

    /// Whether the face asks the replay to stop (a signal, Ctrl-C): asked after each record
    /// event, so the current sample is finished first; the replay then ends as at the end of
    /// the record, with the summary's status [`STATUS_INTERRUPTED`].
    fn stop_requested(&mut self) -> bool {
        false
    }
}

/// `summary.status` of a replay stopped on request ([`ReplayObserver::stop_requested`]) before
/// the end of its record: its estimates are those of the samples read until then.
pub const STATUS_INTERRUPTED: &str = "interrupted";

/// `summary.status` of a replay whose estimator ran to the end of its record, every
/// parameter identified at least once: the run is over (a recursive estimator's own status
/// would still say `running`); whether each estimate can be trusted is its own `status`.
pub const STATUS_COMPLETE: &str = "complete";

impl ReplayObserver for () {}

/// Two observers, each told everything in turn (the first, then the second).
impl<A: ReplayObserver, B: ReplayObserver> ReplayObserver for (A, B) {
    fn model(&mut self, line: &str) {
        self.0.model(line);
        self.1.model(line);
    }

    fn start(&mut self, names: &[&str]) -> std::io::Result<()> {
        self.0.start(names)?;
        self.1.start(names)
    }

    fn estimate(
        &mut self,
        t_s: f64,
        values: &[Option<f64>],
        sigmas: &[Option<f64>],
    ) -> std::io::Result<()> {
        self.0.estimate(t_s, values, sigmas)?;
        self.1.estimate(t_s, values, sigmas)
    }

    fn warning(&mut self, text: &str) {
        self.0.warning(text);
        self.1.warning(text);
    }

    fn record_event(&mut self, event: &aeroident_io::RecordEvent) {
        self.0.record_event(event);
        self.1.record_event(event);
    }

    fn sample(&mut self, sample: &AirDataSample) {
        self.0.sample(sample);
        self.1.sample(sample);
    }

    fn finish(&mut self) -> std::io::Result<()> {
        self.0.finish()?;
        self.1.finish()
    }

    fn stop_requested(&mut self) -> bool {
        self.0.stop_requested() || self.1.stop_requested()
    }
}

/// An observer borrowed (`&mut dyn ReplayObserver` too): a face that may or may not add an
/// observer of its own pairs it with the others without owning it.
impl<T: ReplayObserver + ?Sized> ReplayObserver for &mut T {
    fn model(&mut self, line: &str) {
        (**self).model(line);
    }

    fn start(&mut self, names: &[&str]) -> std::io::Result<()> {
        (**self).start(names)
    }

    fn estimate(
        &mut self,
        t_s: f64,
        values: &[Option<f64>],
        sigmas: &[Option<f64>],
    ) -> std::io::Result<()> {
        (**self).estimate(t_s, values, sigmas)
    }

    fn warning(&mut self, text: &str) {
        (**self).warning(text);
    }

    fn record_event(&mut self, event: &aeroident_io::RecordEvent) {
        (**self).record_event(event);
    }

    fn sample(&mut self, sample: &AirDataSample) {
        (**self).sample(sample);
    }

    fn finish(&mut self) -> std::io::Result<()> {
        (**self).finish()
    }

    fn stop_requested(&mut self) -> bool {
        (**self).stop_requested()
    }
}

/// Writes the estimates to each sink as CSV: a header line, then one line per sample,
/// `t_s, <names>, sigma_<names>` with empty fields where not identified or no σ
/// ([`aeroident_io::replay_output::write_estimates_row`]). With `flush_each` (a paced, live
/// feed) each line goes out at its time; otherwise the sinks stay buffered until the end.
pub struct EstimateRows<'a> {
    /// Where the lines go (an `estimates.csv` file, stdout in live mode).
    pub sinks: Vec<&'a mut dyn Write>,
    /// Flush after every line.
    pub flush_each: bool,
    /// Which rows are written ([`RowRate::every_s`]); default every one.
    pub rate: RowRate,
}

/// The faces' default [`RowRate`] for a record file, s: ten rows a second. An online
/// estimate moves on the time scale of the estimator's memory (λ = 0.995 at 100 Hz: 2 s), so
/// ten rows a second draw every figure and convergence plot as every row would, and a record
/// at 10 Hz or slower keeps every row. A 1-hour six-axis record at 100 Hz writes 48 MB
/// (measured) instead of about ten times that.
pub const DEFAULT_ESTIMATES_EVERY_S: f64 = 0.1;

/// The share of [`RowRate`]'s interval by which a row may come early and still be written: a
/// logger's sample times jitter (the HFB-320 record's 0.1-s intervals run 0.09999 to 0.10001
/// s), and a record sampled at the rate asked for keeps every row.
pub const ROW_RATE_JITTER: f64 = 0.05;

/// How often [`EstimateRows`] writes a row: every estimate (default), or at most one per
/// `every_s` seconds of record time (less [`ROW_RATE_JITTER`]), the first and the last always
/// written (so the last row is the final estimate a summary reports). A long record's `estimates.csv` then holds what
/// its figures and a reader need, not every sample.
#[derive(Debug, Clone, Default)]
pub struct RowRate {
    every_s: Option<f64>,
    last_written_s: Option<f64>,
    held: Option<HeldRow>,
}

/// The last estimate seen and not yet written: time, values, σ.
type HeldRow = (f64, Vec<Option<f64>>, Vec<Option<f64>>);

impl RowRate {
    /// At most one row per `every_s` seconds (positive and finite; otherwise every row).
    pub fn every_s(every_s: f64) -> Self {
        let every_s = (every_s.is_finite() && every_s > 0.0).then_some(every_s);
        Self { every_s, ..Self::default() }
    }

    /// Whether the estimate at `t_s` is written now; else it is held as the last one seen.
    fn due(&mut self, t_s: f64, values: &[Option<f64>], sigmas: &[Option<f64>]) -> bool {
        let Some(every) = self.every_s else { return true };
        if self.last_written_s.is_none_or(|last| t_s - last >= every * (1.0 - ROW_RATE_JITTER)) {
            self.last_written_s = Some(t_s);
            self.held = None;
            return true;
        }
        let (t, v, s) = self.held.get_or_insert_with(HeldRow::default);
        *t = t_s;
        v.clear();
        v.extend_from_slice(values);
        s.clear();
        s.extend_from_slice(sigmas);
        false
    }
}

impl ReplayObserver for EstimateRows<'_> {
    fn start(&mut self, names: &[&str]) -> std::io::Result<()> {
        for s in self.sinks.iter_mut() {
            aeroident_io::replay_output::write_estimates_header(s, names)?;
        }
        Ok(())
    }

    fn estimate(
        &mut self,
        t_s: f64,
        values: &[Option<f64>],
        sigmas: &[Option<f64>],
    ) -> std::io::Result<()> {
        if self.rate.due(t_s, values, sigmas) {
            self.write(t_s, values, sigmas)?;
        }
        Ok(())
    }

    fn finish(&mut self) -> std::io::Result<()> {
        if let Some((t_s, values, sigmas)) = self.rate.held.take() {
            self.write(t_s, &values, &sigmas)?;
        }
        for s in self.sinks.iter_mut() {
            s.flush()?;
        }
        Ok(())
    }
}

impl EstimateRows<'_> {
    /// One row to every sink.
    fn write(
        &mut self,
        t_s: f64,
        values: &[Option<f64>],
        sigmas: &[Option<f64>],
    ) -> std::io::Result<()> {
        for s in self.sinks.iter_mut() {
            aeroident_io::replay_output::write_estimates_row(s, t_s, values, sigmas)?;
            if self.flush_each {
                s.flush()?;
            }
        }
        Ok(())
    }
}

impl ReplayOptions {
    /// The options the estimator is built with over a record of `mapping`: its own options,
    /// the instrument delay the differentiator window implies when none is given, and the
    /// record's nominal sample interval.
    pub fn built_estimator_options(&self, mapping: &Mapping) -> EstimatorOptions {
        let given = self.estimator_options.instrument_delay;
        EstimatorOptions {
            instrument_delay: Some(crate::estimators::instrument_delay(given, self.diff_window)),
            sample_interval_s: mapping.nominal_dt_s,
            ..self.estimator_options
        }
    }
}

impl Default for ReplayOptions {
    fn default() -> Self {
        Self {
            estimator: EstimatorKind::Rls,
            model: None,
            estimator_options: EstimatorOptions::default(),
            derivatives: DerivativeSource::Auto,
            diff_window: 5,
            pacing: Pacing::Unpaced,
            compat: None,
            windows: Vec::new(),
            spike_screen: Some(outliers::SpikeScreen::default()),
            estimates_only: false,
        }
    }
}

/// Errors of a replay.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// Reading the record failed fatally.
    #[error(transparent)]
    Data(#[from] FlightDataError),
    /// The estimator could not be built.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// The model does not fit the record.
    #[error("{0}")]
    Model(String),
    /// An option is invalid; `option` is its name as the command line spells it, without the
    /// leading `--`.
    #[error("option `--{option}`: {reason}")]
    Option {
        /// Option name.
        option: &'static str,
        /// Why.
        reason: String,
    },
    /// Writing the live output failed.
    #[error("writing estimates: {0}")]
    Output(#[from] std::io::Error),
    /// Options or stages that do not go together (a whole-record step on a live feed, a batch
    /// method in the online replay): the message says what to do instead.
    #[error("{0}")]
    Combination(String),
    /// A face could not run a step (a thread that did not start, or ended without a result).
    #[error("{0}")]
    Step(String),
    /// The replay was stopped on request before any sample was estimated.
    #[error("{file}: interrupted before any sample was estimated ({samples_read} rows read)")]
    Interrupted {
        /// The record.
        file: String,
        /// Rows read until then.
        samples_read: usize,
    },
}

impl From<RecordError> for ReplayError {
    fn from(e: RecordError) -> Self {
        match e {
            RecordError::Data(e) => ReplayError::Data(e),
            RecordError::Option { option, reason } => ReplayError::Option { option, reason },
            RecordError::Model(m) => ReplayError::Model(m),
        }
    }
}

/// Kind of the rejections of samples the differentiator could not centre (warm-up, gaps, end).
const KIND_NOT_CENTRED: &str = "not estimated: no centred derivative";

/// Largest differentiator window, samples (a lag of 500 samples: 5 s at 100 Hz).
pub const MAX_DIFF_WINDOW: usize = 1001;

/// In real-time pacing, a time step longer than this multiple of the interval is a jump that
/// is not slept across (the wall clock restarts at the next sample, and the summary says so).
pub const REALTIME_JUMP_FACTOR: f64 = 10.0;

/// Real-time pacing: the wall clock follows the record's time, except across jumps.
#[derive(Debug, Default)]
struct Pacer {
    /// Wall-clock start and the record time it corresponds to.
    clock: Option<(Instant, f64)>,
    /// Previous sample time, s.
    prev_t_s: Option<f64>,
}

impl Pacer {
    /// How long to wait before emitting the sample at `t_s`, given the interval `dt_s` (`None`:
    /// unknown yet); a jump longer than [`REALTIME_JUMP_FACTOR`] × `dt_s` is not slept across:
    /// the clock restarts and the returned note says so. No single wait exceeds
    /// `REALTIME_JUMP_FACTOR` × `dt_s` (nor 1 s while the interval is unknown).
    fn wait(&mut self, t_s: f64, dt_s: Option<f64>, now: Instant) -> (Duration, Option<String>) {
        let cap_s = dt_s.map_or(1.0, |dt| REALTIME_JUMP_FACTOR * dt);
        let mut note = None;
        if let (Some(prev), Some(_)) = (self.prev_t_s, self.clock)
            && t_s - prev > cap_s
        {
            note = Some(format!(
                "real-time pacing: time jumps {} s (from {prev} s to {t_s} s), more than {REALTIME_JUMP_FACTOR} × the interval; not slept across",
                t_s - prev
            ));
            self.clock = None;
        }
        self.prev_t_s = Some(t_s);
        let (start, t0) = *self.clock.get_or_insert((now, t_s));
        let ahead_s = (t_s - t0).clamp(0.0, f64::MAX);
        let due = start.checked_add(Duration::try_from_secs_f64(ahead_s).unwrap_or(Duration::MAX));
        let wait = due.map_or(Duration::ZERO, |d| d.saturating_duration_since(now));
        (wait.min(Duration::from_secs_f64(cap_s.clamp(0.0, 1e6))), note)
    }
}

/// The history of estimates over the record, bounded: at most [`History::MAX_POINTS`] points
/// (plus the last sample) are kept, so a 24 h live feed holds constant memory. Beyond that the
/// history is decimated: every `stride`-th sample is kept (the stride doubles each time the
/// limit is reached), and [`History::finish`] appends the last sample, so the final estimate and
/// the settling time's reference are exact; the settling time then has the resolution of the
/// stride.
#[derive(Debug, Clone)]
pub struct History {
    /// Parameter names.
    pub names: Vec<&'static str>,
    /// Times, s.
    pub t_s: Vec<f64>,
    /// `values[k][i]`: parameter `i` at time `k` (`None` until identified).
    pub values: Vec<Vec<Option<f64>>>,
    /// `sigmas[k][i]`.
    pub sigmas: Vec<Vec<Option<f64>>>,
    /// Samples per kept point (1: every sample kept).
    pub stride: usize,
    /// Samples pushed.
    pub samples: usize,
    limit: usize,
    last: Option<Point>,
}

/// One sample's time, estimates and σ.
type Point = (f64, Vec<Option<f64>>, Vec<Option<f64>>);

impl Default for History {
    fn default() -> Self {
        Self::with_limit(Self::MAX_POINTS)
    }
}

impl History {
    /// Default bound on the points kept: 4,000, the most a figure draws per series
    /// (`plot.rs`), ≈ 4 MB for 32 parameters with σ. The figure's copies of the history are of
    /// the same size, so the whole live run stays well under 64 MB (measured over 24 h at
    /// 100 Hz: docs/reliability.md); the settling time's resolution is then the stride, e.g.
    /// 2,048 samples (20 s at 100 Hz) after 24 h.
    pub const MAX_POINTS: usize = 4_000;

    /// An empty history keeping at most `limit` (≥ 2) points before decimating.
    pub fn with_limit(limit: usize) -> Self {
        Self {
            names: Vec::new(),
            t_s: Vec::new(),
            values: Vec::new(),
            sigmas: Vec::new(),
            stride: 1,
            samples: 0,
            limit: limit.max(2),
            last: None,
        }
    }

    /// Adds one sample's estimates (decimating as described on the type).
    pub fn push(&mut self, t_s: f64, values: Vec<Option<f64>>, sigmas: Vec<Option<f64>>) {
        if self.samples.is_multiple_of(self.stride) {
            self.t_s.push(t_s);
            self.values.push(values.clone());
            self.sigmas.push(sigmas.clone());
            if self.t_s.len() > self.limit {
                let keep = |k: usize| k.is_multiple_of(2);
                let mut k = 0;
                self.t_s.retain(|_| (keep(k), k += 1).0);
                k = 0;
                self.values.retain(|_| (keep(k), k += 1).0);
                k = 0;
                self.sigmas.retain(|_| (keep(k), k += 1).0);
                self.stride *= 2;
            }
        }
        self.samples += 1;
        self.last = Some((t_s, values, sigmas));
    }

    /// Appends the last sample if decimation skipped it (call once, after the last push).
    pub fn finish(&mut self) {
        if let Some((t, v, s)) = self.last.take()
            && self.t_s.last() != Some(&t)
        {
            self.t_s.push(t);
            self.values.push(v);
            self.sigmas.push(s);
        }
    }
}

/// Result of a replay.
#[derive(Debug, Clone)]
pub struct ReplayOutcome {
    /// The model identified.
    pub model: ModelSpec,
    /// Whether the model was chosen by default (richest supported preset).
    pub model_defaulted: bool,
    /// The derivatives the differentiator supplied.
    pub differentiated: Vec<Derivative>,
    /// Estimates over time.
    pub history: History,
    /// The summary document.
    pub summary: ReplaySummary,
    /// Validation on the replayed record (`None` if the estimator diverged).
    pub validation: Option<ValidationReport>,
    /// Identifiability measures (`None` if the estimator diverged).
    pub identifiability: Option<diagnostics::Identifiability>,
    /// The final parameter covariance, `n × n` row-major (`None` where the estimator gives no
    /// entry), for applying the estimates to another record ([`validate_on`]).
    pub final_covariance: Vec<Option<f64>>,
    /// The samples fed to the estimator, as regressors and measured coefficients.
    pub recorder: Recorder,
    /// The samples fed to the estimator (bounded), for the fit quality and the
    /// model-vs-measured figure.
    pub samples: crate::sample_log::SampleLog<AirDataSample>,
    /// The record's other methods beside this one ([`cross_check`], `--cross-check`), when
    /// asked for.
    pub cross_check: Option<cross_check::CrossCheck>,
    /// Whether the estimates repeat across the record's windows, each replayed alone
    /// ([`repeatability`]; two or more `--window`s, not a live feed); `None` otherwise.
    pub repeatability: Option<repeatability::Repeatability>,
    /// What reading the record left out before its rows (a multi-rate log's dropped
    /// samples, skipped bytes, cut message, alignment drops), as the caller that opened it
    /// reports it ([`aeroident_io::Record::open`]); empty when nothing was or for a
    /// CSV.
    pub reader: Vec<ReaderReport>,
}

/// `summary.json`: the [`ReplaySummary`] keys, then `identifiability`, `validation`,
/// `validation_on` (`null` unless `--validate-on`), `cross_check` (`null` when the panel did
/// not run), `repeatability` (`null` unless two or more windows) and `reader` (what the log
/// reader left out, per file).
#[derive(Debug, Clone, serde::Serialize)]
pub struct SummaryDocument<'a> {
    /// The replay summary (flattened).
    #[serde(flatten)]
    pub summary: &'a ReplaySummary,
    /// [`diagnostics::Identifiability`].
    pub identifiability: Option<&'a diagnostics::Identifiability>,
    /// Validation on the fitted record.
    pub validation: Option<&'a ValidationReport>,
    /// Validation on a second record.
    pub validation_on: Option<&'a ValidationReport>,
    /// The record's other methods beside this one (`--cross-check`), else `null`.
    pub cross_check: Option<&'a cross_check::CrossCheck>,
    /// [`ReplayOutcome::repeatability`].
    pub repeatability: Option<&'a repeatability::Repeatability>,
    /// What the log reader left out, per file read ([`ReplayOutcome::reader`]).
    pub reader: &'a [ReaderReport],
}

impl ReplayOutcome {
    /// The `summary.json` document, with the validation on a second record if given.
    pub fn document<'a>(
        &'a self,
        validation_on: Option<&'a ValidationReport>,
    ) -> SummaryDocument<'a> {
        SummaryDocument {
            summary: &self.summary,
            identifiability: self.identifiability.as_ref(),
            validation: self.validation.as_ref(),
            validation_on,
            cross_check: self.cross_check.as_ref(),
            repeatability: self.repeatability.as_ref(),
            reader: &self.reader,
        }
    }

    /// Whether the estimator diverged.
    pub fn diverged(&self) -> bool {
        self.summary.status == Status::Diverged.name()
    }

    /// Whether the replay was stopped on request before the end of its record
    /// ([`STATUS_INTERRUPTED`]).
    pub fn interrupted(&self) -> bool {
        self.summary.status == STATUS_INTERRUPTED
    }

    /// The failure message of a diverged replay (`None` when it did not diverge), naming the
    /// `estimator` and the row and reason of the last rejection.
    pub fn diverged_error(&self, estimator: &str) -> Option<String> {
        if !self.diverged() {
            return None;
        }
        let at = self
            .summary
            .rejections
            .last()
            .map_or(String::new(), |r| format!(" (row {}: {})", r.row, r.reason));
        Some(format!(
            "estimator `{estimator}` diverged{at}; its estimates are not a result (summary written with status `diverged`)"
        ))
    }
}

impl crate::Named for DerivativeSource {
    const ALL: &'static [Self] = &[DerivativeSource::Auto, DerivativeSource::Differentiate];

    fn name(self) -> &'static str {
        match self {
            DerivativeSource::Auto => "auto",
            DerivativeSource::Differentiate => "differentiate",
        }
    }
}

/// `model` for a record whose first sample has no sideslip: `CY_0` left out when the model
/// integrates β, with the note that says so.
///
/// Without a β measurement the level of β is not determined: a constant sideslip `δ` with
/// `CY_0`, `Cl_0`, `Cn_0` shifted by `−CY_β δ`, `−Cl_β δ`, `−Cn_β δ` gives the same side
/// force, moments, `ay`, `p` and `r` (the model is linear in β up to the small `cos β` factors
/// of the kinematics). The fit then wanders along that valley (ATTAS AilRud1 without its β
/// column: β0 = 27° ± 9°, `CY_0` = 0.55). Zero side force at zero sideslip and zero controls, a
/// symmetric aircraft, fixes the level: β is then the sideslip that balances the measured
/// side force.
pub(crate) fn sideslip_level(
    model: ModelSpec,
    first: &AirDataSample,
) -> (ModelSpec, Option<String>) {
    let cy0 = aeroident_estimators::Param::new(
        aeroident_estimators::Coefficient::CY,
        aeroident_estimators::Term::Bias,
    );
    let integrates_beta = aeroident_estimators::StateSet::of(&model.structure)
        .is_ok_and(|set| set.states().contains(&aeroident_estimators::flight_model::state::BETA));
    if first.beta_rad.is_some() || !integrates_beta || !model.structure.contains(cy0) {
        return (model, None);
    }
    let note = "β is not measured: the model carries it as a state, its initial value estimated; CY_0 is left out (zero side force at zero sideslip), since without β a constant sideslip and CY_0 are the same thing to the record";
    (model.without(cy0), Some(note.into()))
}

/// The derivatives the stage must supply for `structure` with estimator `kind`, given what the
/// mapping records and the source option.
fn derivatives_to_supply(
    structure: &ModelStructure,
    kind: EstimatorKind,
    mapping: &Mapping,
    source: DerivativeSource,
) -> Vec<Derivative> {
    let measured = kind.uses_measured_coefficients();
    let has = |c| structure.has(c);
    let needed = |d: Derivative| match d {
        Derivative::Alphadot => structure.params().any(|p| p.term == Term::Alphadot),
        Derivative::Qdot => measured && has(Coefficient::Cm),
        Derivative::Pdot | Derivative::Rdot => {
            measured && (has(Coefficient::Cl) || has(Coefficient::Cn))
        }
    };
    let recorded = |d: Derivative| {
        mapping.has(match d {
            Derivative::Pdot => Channel::Pdot,
            Derivative::Qdot => Channel::Qdot,
            Derivative::Rdot => Channel::Rdot,
            Derivative::Alphadot => Channel::Alphadot,
        })
    };
    let source_mapped = |d: Derivative| {
        mapping.has(match d {
            Derivative::Pdot => Channel::P,
            Derivative::Qdot => Channel::Q,
            Derivative::Rdot => Channel::R,
            Derivative::Alphadot => Channel::Alpha,
        })
    };
    Derivative::ALL
        .into_iter()
        .filter(|d| {
            needed(*d)
                && source_mapped(*d)
                && (source == DerivativeSource::Differentiate || !recorded(*d))
        })
        .collect()
}

/// Replays a record through the chosen estimator; `observer` sees the model, each sample's
/// estimates and the warnings as they arise ([`EstimateRows`] writes `estimates.csv` or the
/// live feed's lines, `&mut ()` sees nothing).
///
/// # Errors
/// [`ReplayError`] for fatal data errors (missing column, unreadable CSV), invalid options, an
/// estimator that cannot be built, a model the record cannot support, no usable sample, or a
/// failed write.
pub fn replay<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
    observer: &mut dyn ReplayObserver,
) -> Result<ReplayOutcome, ReplayError> {
    let o = opts.built_estimator_options(mapping);
    replay_with(reader, mapping, opts, maker(opts, &o), observer)
}

/// How a replay builds its estimator once the first sample has chosen the model: `opts`'
/// kind with the options `o` built for the mapping.
fn maker<'a>(
    opts: &'a ReplayOptions,
    o: &'a EstimatorOptions,
) -> impl Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError> + 'a {
    move |model: &ModelSpec| {
        build(opts.estimator, model.structure, model.priors, o).map(|e| e as Box<dyn Estimator>)
    }
}

/// [`replay`] with the estimator made by `make` (for tests that need an estimator of their
/// own; the CLI uses [`replay`]).
///
/// # Errors
/// As [`replay`].
pub fn replay_with<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
    make: impl Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError>,
    observer: &mut dyn ReplayObserver,
) -> Result<ReplayOutcome, ReplayError> {
    check_record_options(opts)?;
    check_spike_screen(opts.spike_screen.as_ref())?;
    let file = reader.file().to_string();
    let events = record_events(reader, opts.spike_screen, opts.compat.as_ref(), &opts.windows);
    replay_events(events, file, mapping, opts, make, observer)
}

/// [`replay`] of a record file whose steps after the feed will read it again: the record is
/// read and screened on a second thread as the estimator takes it, and kept in memory for
/// those steps ([`crate::record::cache::ScreenedRecord::read_while_feeding`]); the outcome is
/// [`replay`]'s, bit for bit.
///
/// Returns the replay's result and the record held (`None`: too long to hold, or unreadable).
///
/// # Errors
/// As [`replay`].
pub fn replay_holding<R: Read + Send>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
    observer: &mut dyn ReplayObserver,
) -> (Result<ReplayOutcome, ReplayError>, Option<crate::record::cache::ScreenedRecord>) {
    let checked = check_record_options(opts)
        .and_then(|()| Ok(check_spike_screen(opts.spike_screen.as_ref())?));
    if let Err(e) = checked {
        return (Err(e), None);
    }
    let o = opts.built_estimator_options(mapping);
    let file = reader.file().to_string();
    let stages = (opts.compat.as_ref(), opts.windows.as_slice());
    crate::record::cache::ScreenedRecord::read_while_feeding(
        reader,
        opts.spike_screen,
        stages,
        |events| replay_events(events, file, mapping, opts, maker(opts, &o), observer),
    )
}

/// [`replay`] of a record held in memory ([`crate::record::cache::ScreenedRecord`], read with
/// `opts`' spike screen): the same outcome as from its file, at the cost of the estimator.
///
/// # Errors
/// As [`replay`]; [`ReplayError::Option`] (`spike-screen`) when `record` was screened
/// otherwise than `opts` asks.
pub fn replay_cached(
    record: &crate::record::cache::ScreenedRecord,
    mapping: &Mapping,
    opts: &ReplayOptions,
    observer: &mut dyn ReplayObserver,
) -> Result<ReplayOutcome, ReplayError> {
    let o = opts.built_estimator_options(mapping);
    replay_cached_with(record, mapping, opts, maker(opts, &o), observer)
}

/// [`replay_cached`] with the estimator made by `make` (as [`replay_with`] is to [`replay`]).
///
/// # Errors
/// As [`replay_cached`].
pub fn replay_cached_with(
    record: &crate::record::cache::ScreenedRecord,
    mapping: &Mapping,
    opts: &ReplayOptions,
    make: impl Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError>,
    observer: &mut dyn ReplayObserver,
) -> Result<ReplayOutcome, ReplayError> {
    record.check_screen(opts.spike_screen)?;
    check_record_options(opts)?;
    let events = record.events(opts.compat.as_ref(), &opts.windows);
    replay_events(events, record.file().to_string(), mapping, opts, make, observer)
}

/// The replay of `events` (the record `events_file`, its stages set up), options checked.
fn replay_events(
    mut events: crate::record::RecordEvents<'_>,
    events_file: String,
    mapping: &Mapping,
    opts: &ReplayOptions,
    make: impl Fn(&ModelSpec) -> Result<Box<dyn Estimator>, BuildError>,
    observer: &mut dyn ReplayObserver,
) -> Result<ReplayOutcome, ReplayError> {
    let mut run = online::Replay::new(events_file.clone(), mapping, opts, observer);
    let mut tally = crate::record::tally::FileTally::default();
    for item in events.by_ref() {
        let event = item?;
        tally.count(&event);
        run.event(event, &make)?;
        if run.diverged() || run.stop_requested() {
            break;
        }
    }
    let file = events_file;
    let mut out = run.finish().map_err(|e| match e {
        ReplayError::Data(d) => events.explain_no_samples(&file, RecordError::Data(d)).into(),
        e => e,
    })?;
    if !out.diverged() {
        out.summary
            .warnings
            .extend(precision::warning(out.summary.parameters.iter().map(|p| &p.result)));
    }
    if let Some(c) = &opts.compat {
        out.summary.warnings.extend(c.warnings());
    }
    out.summary.warnings.extend(events.notes());
    out.summary.warnings.extend(tally.warning(&file));
    verdict::judge(&mut out, crate::plausibility::thrust_mapped(mapping));
    Ok(out)
}

/// A second real-time estimator following events another replay has already read: `events`
/// are that replay's [`ReplayObserver::record_event`]s, already screened for spikes,
/// corrected and windowed, so `opts`' spike screen, corrections and windows are not applied
/// again (nor listed in the outcome's warnings). What a live view's cross-check runs beside
/// the feed's own estimator ([`crate::live::panel`]); `file` names the record in errors.
///
/// # Errors
/// As [`replay`].
pub fn follow(
    events: impl IntoIterator<Item = aeroident_io::RecordEvent>,
    file: &str,
    mapping: &Mapping,
    opts: &ReplayOptions,
    observer: &mut dyn ReplayObserver,
) -> Result<ReplayOutcome, ReplayError> {
    check_numeric_options(opts)?;
    let o = opts.built_estimator_options(mapping);
    let make = maker(opts, &o);
    let mut run = online::Replay::new(file.to_string(), mapping, opts, observer);
    for event in events {
        run.event(event, &make)?;
        if run.diverged() || run.stop_requested() {
            break;
        }
    }
    run.finish()
}

/// The options of a replay of a record (file or held in memory), checked before anything is
/// read: the numeric ones ([`check_numeric_options`]) and the time windows.
fn check_record_options(opts: &ReplayOptions) -> Result<(), ReplayError> {
    check_numeric_options(opts)?;
    crate::window::check_windows(&opts.windows)
        .map_err(|reason| ReplayError::Option { option: "window", reason })
}

/// The numeric options of a replay, checked before anything is read or built, each error
/// naming the option as the command line spells it and the value exactly as given: the
/// differentiator window, the forgetting factor (of the estimators that take one) and the
/// instruments' delay.
fn check_numeric_options(opts: &ReplayOptions) -> Result<(), ReplayError> {
    check_diff_window(opts.diff_window)?;
    let forgetting = opts.estimator_options.forgetting;
    if opts.estimator.options().contains(&"forgetting") && !(forgetting > 0.0 && forgetting <= 1.0)
    {
        return Err(ReplayError::Option {
            option: "forgetting",
            reason: format!("must be in (0, 1] (1: no forgetting), got {forgetting}"),
        });
    }
    let max = aeroident_estimators::iv::MAX_INSTRUMENT_DELAY;
    match opts.estimator_options.instrument_delay {
        Some(d) if !(1..=max).contains(&d) => Err(ReplayError::Option {
            option: "instrument-delay",
            reason: format!("must be 1 to {max} samples, got {d}"),
        }),
        _ => Ok(()),
    }
}

/// The differentiator window must be odd, ≥ 3 and ≤ [`MAX_DIFF_WINDOW`].
fn check_diff_window(window: usize) -> Result<(), ReplayError> {
    if window < 3 || window.is_multiple_of(2) {
        return Err(ReplayError::Option {
            option: "diff-window",
            reason: format!("must be odd and ≥ 3 (a whole-sample lag), got {window}"),
        });
    }
    if window > MAX_DIFF_WINDOW {
        return Err(ReplayError::Option {
            option: "diff-window",
            reason: format!(
                "must be ≤ {MAX_DIFF_WINDOW} samples (a lag of {} samples), got {window}",
                MAX_DIFF_WINDOW / 2
            ),
        });
    }
    Ok(())
}

/// Applies the final estimates of `fitted` to a second record (`--validate-on`): the record
/// goes through the same reader, derivative stage and model as the fit, with the parameters
/// frozen at `fitted`'s final values (and its covariance for the prediction intervals); the
/// report has the same metrics as the fit's own `validation`, with `used_for_fit = false`.
///
/// # Errors
/// As [`replay`] (the second record must support the fitted model).
pub fn validate_on<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    opts: &ReplayOptions,
    fitted: &ReplayOutcome,
) -> Result<ValidationReport, ReplayError> {
    let file = reader.file().to_string();
    let values: Vec<Option<f64>> = fitted.summary.parameters.iter().map(|p| p.estimate).collect();
    let opts = ReplayOptions {
        model: Some(fitted.model.clone()),
        pacing: Pacing::Unpaced,
        ..opts.clone()
    };
    let make = |spec: &ModelSpec| -> Result<Box<dyn Estimator>, BuildError> {
        Ok(Box::new(Frozen::new(spec.structure, &values, fitted.final_covariance.clone())))
    };
    let out = replay_with(reader, mapping, &opts, make, &mut ())?;
    let cov = |i: usize, j: usize| {
        let n = fitted.model.structure.n_params();
        fitted.final_covariance.get(i * n + j).copied().flatten()
    };
    Ok(validate_coefficients(
        &out.recorder,
        &fitted.model.structure,
        &values,
        &cov,
        &file,
        fitted.validation.as_ref(),
    ))
}

/// The given model, or the richest preset the first sample supports.
fn choose_model(
    opts: &ReplayOptions,
    mapping: &Mapping,
    first: &AirDataSample,
    uses_measured: bool,
) -> Result<(ModelSpec, bool), ReplayError> {
    if let Some(m) = &opts.model {
        return Ok((m.clone(), false));
    }
    let supports = |spec: &ModelSpec| {
        let supply =
            derivatives_to_supply(&spec.structure, opts.estimator, mapping, opts.derivatives);
        let missing = unsupported(&spec.structure, first, uses_measured, &supply);
        if missing.is_empty() { Ok(()) } else { Err(missing.join("; ")) }
    };
    let spec = crate::record::needs::richest_preset(supports).map_err(|why| {
        ReplayError::Model(format!(
            "no preset model is supported by the channels of {} ({why}); map the missing channels or give --model FILE",
            mapping.file
        ))
    })?;
    Ok((spec, true))
}

fn model_line(spec: &ModelSpec, defaulted: bool, supply: &[Derivative], window: usize) -> String {
    let how = if defaulted { " (default: the richest preset the record supports)" } else { "" };
    let diff = if supply.is_empty() {
        String::new()
    } else {
        let names: Vec<&str> = supply.iter().map(|d| d.name()).collect();
        format!(
            "; differentiated: {} (window {window}, lag {} samples)",
            names.join(", "),
            window / 2
        )
    };
    format!(
        "model: {}{how}: {} parameters ({}){diff}",
        spec.name,
        spec.structure.n_params(),
        spec.structure.names().collect::<Vec<_>>().join(", ")
    )
}

/// Settling time of parameter `i`, s (definition in the module doc).
pub fn settle_time_s(h: &History, i: usize) -> Option<f64> {
    let fin = h.values.last()?[i]?;
    let sigma = h.sigmas.last().and_then(|s| s[i]).unwrap_or(0.0);
    let band = (0.05 * fin.abs()).max(2.0 * sigma);
    let mut first_in = None;
    for (k, v) in h.values.iter().enumerate().rev() {
        match v[i] {
            Some(v) if (v - fin).abs() <= band => first_in = Some(h.t_s[k]),
            _ => break,
        }
    }
    first_in
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::{Estimates, EstimatorError, EventKind, EventLog};
    use std::cell::RefCell;
    use std::rc::Rc;

    /// What a test estimator saw: sample times and `new_manoeuvre` calls, in order.
    #[derive(Debug, Clone, PartialEq)]
    enum Seen {
        Sample(f64),
        NewManoeuvre,
    }

    /// A test double of the estimator interface: records what it is fed; reports
    /// `Diverged` from sample `diverge_at` on.
    struct Probe {
        structure: ModelStructure,
        est: Estimates,
        seen: Rc<RefCell<Vec<Seen>>>,
        diverge_at: usize,
    }

    impl Estimator for Probe {
        fn method(&self) -> &'static str {
            "probe"
        }
        fn structure(&self) -> &ModelStructure {
            &self.structure
        }
        fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
            self.seen.borrow_mut().push(Seen::Sample(s.t_s));
            let n = self.seen.borrow().iter().filter(|x| matches!(x, Seen::Sample(_))).count();
            for i in 0..self.est.n {
                self.est.set(i, s.qdot_rad_s2.unwrap_or(f64::NAN), None, true);
            }
            self.est.status = if n >= self.diverge_at { Status::Diverged } else { Status::Running };
            Ok(&self.est)
        }
        fn estimates(&self) -> &Estimates {
            &self.est
        }
        fn new_manoeuvre(&mut self) {
            self.seen.borrow_mut().push(Seen::NewManoeuvre);
        }
    }

    const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\nthrust = { value = 0.0, unit = \"N\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

    /// q = 2t (so q̇ = 2 exactly), 10 samples, a gap of 1 s after the sixth.
    fn record() -> String {
        let mut csv = String::from("t,V,a,q,ax,az,de\n");
        for k in 0..10 {
            let t = if k < 6 { k as f64 * 0.1 } else { 1.5 + (k - 6) as f64 * 0.1 };
            csv.push_str(&format!("{t:.1},50,0.05,{:.1},0.1,-9.8,0.01\n", 2.0 * t));
        }
        csv
    }

    fn probe_run(diverge_at: usize) -> (Result<ReplayOutcome, ReplayError>, Vec<Seen>) {
        let m = Mapping::from_toml_str(MAP, "probe.toml").unwrap();
        let csv = record();
        let reader = FlightDataReader::new(csv.as_bytes(), "probe.csv", &m).unwrap();
        let seen = Rc::new(RefCell::new(Vec::new()));
        let s2 = seen.clone();
        let make = move |spec: &ModelSpec| -> Result<Box<dyn Estimator>, BuildError> {
            Ok(Box::new(Probe {
                structure: spec.structure,
                est: Estimates::new(spec.structure.n_params()),
                seen: s2.clone(),
                diverge_at,
            }))
        };
        let opts = ReplayOptions { diff_window: 3, ..Default::default() };
        let out = replay_with(reader, &m, &opts, make, &mut ());
        let seen = seen.borrow().clone();
        (out, seen)
    }

    /// What an observer was told.
    #[derive(Default)]
    struct Told {
        model: Vec<String>,
        names: Vec<String>,
        estimates: Vec<(f64, Vec<Option<f64>>)>,
        warnings: Vec<String>,
        finished: bool,
    }

    impl ReplayObserver for Told {
        fn model(&mut self, line: &str) {
            self.model.push(line.into());
        }
        fn start(&mut self, names: &[&str]) -> std::io::Result<()> {
            self.names = names.iter().map(|n| n.to_string()).collect();
            Ok(())
        }
        fn estimate(
            &mut self,
            t_s: f64,
            values: &[Option<f64>],
            _sigmas: &[Option<f64>],
        ) -> std::io::Result<()> {
            self.estimates.push((t_s, values.to_vec()));
            Ok(())
        }
        fn warning(&mut self, text: &str) {
            self.warnings.push(text.into());
        }
        fn finish(&mut self) -> std::io::Result<()> {
            self.finished = true;
            Ok(())
        }
    }

    /// A [`Probe`] that raises one change alarm (`Cm`, statistic 13) at its `alarm_at`-th
    /// sample, as the equation-error change test does (`aeroident_estimators::change`).
    struct AlarmProbe {
        inner: Probe,
        events: EventLog,
        fed: usize,
        alarm_at: usize,
    }

    impl Estimator for AlarmProbe {
        fn method(&self) -> &'static str {
            "alarm-probe"
        }
        fn structure(&self) -> &ModelStructure {
            self.inner.structure()
        }
        fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
            self.fed += 1;
            if self.fed == self.alarm_at {
                self.events.push_with_statistic(s.t_s, EventKind::ChangeDetected, "Cm", 13.0);
            }
            self.inner.update(s)
        }
        fn estimates(&self) -> &Estimates {
            self.inner.estimates()
        }
        fn events(&self) -> &EventLog {
            &self.events
        }
    }

    /// A change alarm reaches the live observer once, the moment it happens, naming the
    /// equation and its statistic; the summary lists it among the events.
    #[test]
    fn change_alarm_is_told_to_the_observer_when_it_happens() {
        let m = Mapping::from_toml_str(MAP, "probe.toml").unwrap();
        let csv = record();
        let reader = FlightDataReader::new(csv.as_bytes(), "probe.csv", &m).unwrap();
        let make = |spec: &ModelSpec| -> Result<Box<dyn Estimator>, BuildError> {
            let inner = Probe {
                structure: spec.structure,
                est: Estimates::new(spec.structure.n_params()),
                seen: Rc::new(RefCell::new(Vec::new())),
                diverge_at: usize::MAX,
            };
            Ok(Box::new(AlarmProbe { inner, events: EventLog::new(), fed: 0, alarm_at: 3 }))
        };
        let opts = ReplayOptions { diff_window: 3, ..Default::default() };
        let mut told = Told::default();
        replay_with(reader, &m, &opts, make, &mut told).unwrap();
        let changes: Vec<&String> =
            told.warnings.iter().filter(|w| w.contains("detected a change")).collect();
        assert_eq!(changes.len(), 1, "{:?}", told.warnings);
        let t3 = told.estimates[2].0;
        assert!(changes[0].contains("of `Cm`"), "{}", changes[0]);
        assert!(changes[0].contains("statistic 13.0"), "{}", changes[0]);
        assert!(changes[0].contains(&format!("t = {t3} s")), "{} (third sample {t3})", changes[0]);
    }

    /// A pair of observers is told everything, each in full: the model once, the names, one
    /// estimate per sample fed (the history's), the end; the CSV side writes a header and
    /// one line per sample with the estimates (q̇ = 2 exactly for the probe).
    #[test]
    fn observer_pair_sees_every_estimate() {
        let m = Mapping::from_toml_str(MAP, "probe.toml").unwrap();
        let csv = record();
        let reader = FlightDataReader::new(csv.as_bytes(), "probe.csv", &m).unwrap();
        let make = |spec: &ModelSpec| -> Result<Box<dyn Estimator>, BuildError> {
            Ok(Box::new(Probe {
                structure: spec.structure,
                est: Estimates::new(spec.structure.n_params()),
                seen: Rc::new(RefCell::new(Vec::new())),
                diverge_at: usize::MAX,
            }))
        };
        let opts = ReplayOptions { diff_window: 3, ..Default::default() };
        let mut lines = Vec::new();
        let mut pair = (
            Told::default(),
            EstimateRows { sinks: vec![&mut lines], flush_each: false, rate: RowRate::default() },
        );
        let o = replay_with(reader, &m, &opts, make, &mut pair).unwrap();
        let told = pair.0;
        assert_eq!(told.model.len(), 1);
        assert!(told.model[0].contains(&o.model.name), "{:?}", told.model);
        assert_eq!(told.names, o.history.names);
        assert_eq!(told.estimates.len(), o.history.samples);
        assert_eq!(told.estimates.iter().map(|e| e.0).collect::<Vec<_>>(), o.history.t_s);
        assert!(told.estimates.iter().all(|(_, v)| v.iter().all(|x| *x == Some(2.0))));
        assert!(told.finished);
        let text = String::from_utf8(lines).unwrap();
        assert_eq!(text.lines().count(), 1 + o.history.samples, "{text}");
        assert!(text.lines().next().unwrap().starts_with("t_s,"), "{text}");
    }

    /// At a gap the estimator is told a new manoeuvre starts — after the last sample before
    /// the gap and before the first after it — and the differentiator restarts: the samples
    /// it cannot centre on either side are listed, and every q̇ fed is the exact one.
    #[test]
    fn gap_starts_a_new_manoeuvre_and_restarts_the_differentiator() {
        let (out, seen) = probe_run(usize::MAX);
        let o = out.unwrap();
        let r = |t: f64| Seen::Sample(t);
        assert_eq!(
            seen,
            vec![r(0.1), r(0.2), r(0.3), r(0.4), Seen::NewManoeuvre, r(1.6), r(1.7)],
            "{seen:?}"
        );
        assert_eq!(o.differentiated, vec![Derivative::Qdot]);
        // Rows (header = 1): 2…7 before the gap, 8…11 after; N = 3 loses one each side.
        let rows: Vec<u64> = o.summary.rejections.iter().map(|r| r.row).collect();
        assert_eq!(rows, vec![2, 8, 7, 8, 11]);
        assert!(o.summary.rejections[1].reason.starts_with("gap: "));
        assert_eq!(o.summary.samples_rejected, 4);
        for p in &o.summary.parameters {
            assert!((p.estimate.unwrap() - 2.0).abs() < 1e-9, "q̇ = 2: {p:?}");
        }
        assert_eq!((o.model.name.as_str(), o.model_defaulted), ("longitudinal", true));
    }

    /// A diverged estimator stops the replay: its row is listed, the status is `diverged` and
    /// no estimate is reported as a result.
    #[test]
    fn diverged_estimator_stops_and_reports_no_result() {
        let (out, seen) = probe_run(3);
        let o = out.unwrap();
        assert!(o.diverged());
        assert_eq!(o.summary.status, "diverged");
        assert_eq!(seen.iter().filter(|s| matches!(s, Seen::Sample(_))).count(), 3);
        let last = o.summary.rejections.last().unwrap();
        assert_eq!(last.row, 5);
        assert!(last.reason.contains("diverged at t = 0.3 s"), "{}", last.reason);
        assert!(o.summary.parameters.iter().all(|p| p.estimate.is_none() && p.std_error.is_none()));
        assert!(o.summary.coefficients.iter().all(|c| c.condition_number.is_none()));
        let e = o.diverged_error("probe").unwrap();
        assert!(e.contains("estimator `probe` diverged (row 5"), "{e}");
    }

    /// The default model is the richest preset the first sample supports, counting the
    /// derivatives the differentiator will supply; a model the record cannot support names
    /// what is missing.
    #[test]
    fn default_model_is_the_richest_supported_preset() {
        let lon = Mapping::from_toml_str(MAP, "lon.toml").unwrap();
        let s = AirDataSample {
            vt_mps: 50.0,
            alpha_rad: 0.05,
            qbar_pa: 1250.0,
            q_rad_s: Some(0.1),
            ax_mps2: Some(0.1),
            az_mps2: Some(-9.8),
            de_rad: Some(0.0),
            constants: aeroident_estimators::AircraftConstants {
                mass_kg: 1000.0,
                S_m2: 10.0,
                cbar_m: Some(1.5),
                Iyy_kgm2: Some(2000.0),
                ..Default::default()
            },
            ..Default::default()
        };
        let opts = ReplayOptions::default();
        let (m, defaulted) = choose_model(&opts, &lon, &s, true).unwrap();
        assert_eq!((m.name.as_str(), defaulted), ("longitudinal", true));
        let lat = ModelStructure::lateral();
        let missing = unsupported(&lat, &s, true, &[Derivative::Pdot, Derivative::Rdot]);
        assert!(missing.iter().any(|m| m == "term `beta` (needs beta)"), "{missing:?}");
        assert!(missing.iter().any(|m| m.starts_with("coefficient `Cl`")), "{missing:?}");
        // Without q̇ recorded or supplied, Cm is not measurable.
        assert!(
            unsupported(&ModelStructure::longitudinal(), &s, true, &[])
                .iter()
                .any(|m| m.starts_with("coefficient `Cm`"))
        );
        // …but an estimator that does not use measured coefficients needs only the terms.
        assert!(unsupported(&ModelStructure::longitudinal(), &s, false, &[]).is_empty());
    }

    /// In real-time pacing a huge time jump (1e308 s, 1e10 s) neither panics nor
    /// sleeps across: the wait is capped at 10 intervals and the jump is reported; ordinary
    /// steps wait their interval.
    #[test]
    fn errors_realtime_time_jump_is_not_slept_across() {
        let now = Instant::now();
        let mut p = Pacer::default();
        assert_eq!(p.wait(0.0, Some(0.1), now), (Duration::ZERO, None));
        let (w, n) = p.wait(0.1, Some(0.1), now);
        assert!((w.as_secs_f64() - 0.1).abs() < 1e-9 && n.is_none(), "{w:?}");
        for jump in [1e10, 1e308] {
            let (w, n) = p.wait(jump, Some(0.1), now);
            assert!(w <= Duration::from_secs(1), "{w:?}");
            assert!(n.as_deref().is_some_and(|n| n.contains("not slept")), "{n:?}");
        }
        // After the jump the clock restarts: the next ordinary step waits one interval.
        let (w, n) = p.wait(1e308 + 1e292, Some(1e292), now);
        assert!(n.is_none() && w <= Duration::from_secs_f64(1e6), "{w:?}");
        let mut p = Pacer::default();
        p.wait(0.0, None, now);
        let (w, _) = p.wait(0.5, None, now);
        assert!((w.as_secs_f64() - 0.5).abs() < 1e-9);
    }

    /// An absurd differentiator window is a clear option error, not an allocation
    /// abort.
    #[test]
    fn errors_diff_window_has_an_upper_bound() {
        let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
        let csv = "t,V,a,q,ax,az,de\n0,50,0.1,0,0,-9.8,0\n";
        for w in [1003, usize::MAX] {
            let r = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
            let opts = ReplayOptions { diff_window: w, ..Default::default() };
            let e = replay(r, &m, &opts, &mut ()).unwrap_err().to_string();
            assert!(e.contains("diff-window") && e.contains("1001"), "{e}");
        }
    }

    /// The history stays bounded (decimated by a doubling stride) and keeps the
    /// first and the last sample exactly.
    #[test]
    fn analytic_history_is_decimated_and_bounded() {
        let mut h = History::with_limit(100);
        let n = 200_000usize;
        for k in 0..n {
            h.push(k as f64, vec![Some(k as f64)], vec![None]);
            assert!(h.t_s.len() <= 100, "{k}: {}", h.t_s.len());
        }
        h.finish();
        assert_eq!(h.samples, n);
        assert!(h.stride >= n / 100 && h.stride <= 2 * n / 100 * 2, "stride {}", h.stride);
        assert_eq!(h.t_s[0], 0.0);
        assert_eq!(*h.t_s.last().unwrap(), (n - 1) as f64);
        assert_eq!(h.values.last().unwrap()[0], Some((n - 1) as f64));
        // Every kept point but the appended last one lies on the stride grid, in order.
        for w in h.t_s[..h.t_s.len() - 1].windows(2) {
            assert_eq!(w[1] - w[0], h.stride as f64);
        }
        assert_eq!(h.t_s.len(), h.values.len());
        assert_eq!(h.t_s.len(), h.sigmas.len());
        // Below the limit nothing is dropped.
        let mut h = History::with_limit(100);
        for k in 0..50 {
            h.push(k as f64, vec![None], vec![None]);
        }
        h.finish();
        assert_eq!(h.t_s, (0..50).map(f64::from).collect::<Vec<_>>());
    }

    /// When every row is rejected, the error gives the first reasons (row and
    /// column), not only a count.
    #[test]
    fn errors_no_usable_samples_names_the_first_reasons() {
        let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
        let csv = record().replace(",0.05,", ",,");
        let r = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
        let e = replay(r, &m, &ReplayOptions::default(), &mut ()).unwrap_err().to_string();
        assert!(e.contains("d.csv") && e.contains("no usable samples"), "{e}");
        assert!(e.contains("row 2: column `a`: blank value"), "{e}");
    }

    /// A forgetting factor so small that nothing is ever identified reports every
    /// estimate as `None` (null), never 0.0, and the status says so.
    #[test]
    fn errors_never_identified_parameters_are_null_not_zero() {
        let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
        // Independent excitation of α, q, δe and the accelerations: identifiable with λ = 1.
        let mut csv = String::from("t,V,a,q,ax,az,de\n");
        for k in 0..200 {
            let t = k as f64 * 0.1;
            let (a, q, de) =
                (0.05 + 0.02 * (1.3 * t).sin(), 0.1 * (0.7 * t).cos(), 0.03 * (2.9 * t).sin());
            let (ax, az) = (0.1 + 0.5 * a + 0.2 * de, -9.8 - 30.0 * a - 4.0 * de + q);
            csv.push_str(&format!("{t:.1},50,{a},{q},{ax},{az},{de}\n"));
        }
        let run = |forgetting: f64| {
            let r = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
            let estimator_options = EstimatorOptions { forgetting, ..Default::default() };
            let opts = ReplayOptions { estimator_options, diff_window: 3, ..Default::default() };
            replay(r, &m, &opts, &mut ()).unwrap()
        };
        let ok = run(1.0);
        assert!(ok.summary.parameters.iter().all(|p| p.estimate.is_some()), "{:?}", ok.summary);
        let out = run(1e-300);
        assert_ne!(out.summary.status, STATUS_COMPLETE);
        assert!(!out.summary.parameters.is_empty());
        for p in &out.summary.parameters {
            assert_eq!(p.estimate, None, "{}", p.name);
            assert_eq!(p.std_error, None, "{}", p.name);
        }
    }

    /// One row per second: a row 0.949 s after the last one written is held, one 0.951 s
    /// after it is written (the 5 % jitter allowance at its edge, on both sides); without an
    /// interval every row is.
    #[test]
    fn the_row_rate_admits_five_per_cent_early_and_no_more() {
        let mut rate = RowRate::every_s(1.0);
        let due = |r: &mut RowRate, t: f64| r.due(t, &[Some(1.0)], &[None]);
        assert!(due(&mut rate, 0.0));
        assert!(!due(&mut rate, 0.949));
        assert!(due(&mut rate, 0.951));
        assert!(!due(&mut rate, 0.951 + 0.949));
        assert!(due(&mut rate, 0.951 + 0.951));
        let mut every = RowRate::every_s(0.0);
        assert!((0..5).all(|i| due(&mut every, f64::from(i) * 1e-3)));
    }
}
