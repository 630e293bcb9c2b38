//! The jobs a face runs, each built from one options value and run by the library: the
//! [replay job](replay::ReplayJob) (a record through an online estimator) and the
//! [batch-fit job](fit::FitJob) (output error, filter error, frequency-domain output error).
//!
//! A job runs every stage a user can ask for, in this order:
//! 1. **compat**: a compatibility check's corrections, from a `compat.json` or checked on the
//!    record itself (`auto`) ([`corrections`]);
//! 2. **model**: a preset, a model file, or the structure selected on the record (`auto`)
//!    ([`choose_model`]);
//! 3. **estimate**: the online replay, or the batch fit, over the record stage
//!    ([`crate::record`]);
//! 4. **check**: the cross-check, the record's other methods beside the estimate
//!    ([`cross_check`], judged by [`crate::replay::cross_check`]), or least squares'
//!    regressor-noise test; the timing refit where a surface leads its response, and the
//!    sample-timing test, the record fitted with the gyros skewed by half a sample ([`timing`]);
//! 5. **validate**: the estimates applied to a second record (`validate_on`).
//!
//! The faces keep what is theirs: opening a live feed or stdin, showing progress, answering
//! signals, writing files. Two hooks carry that: a [`Guard`] runs each step over a whole record
//! (the CLI on a thread it can abandon on a signal; Python and tests in place, [`InPlace`]),
//! and a [`JobLog`] receives the lines a user reads while the job runs (the CLI's stderr).

pub mod cross_check;
pub mod fit;
pub mod repeat;
pub mod replay;
pub mod timing;

use crate::record::Corrections;
use crate::replay::ReplayError;
use crate::structure::AutoSelection;
use crate::window::TimeWindow;
use aeroident_io::{FlightDataError, LogFormat, LogReader, Mapping, ModelSpec, RecordEvent};
use std::path::PathBuf;

/// How many samples [`Records::sample_interval_s`] reads: enough for a median that a few gaps
/// do not move, few enough that a long record is not read twice for it.
pub const INTERVAL_SAMPLES: usize = 1001;

/// The records of a job, as the faces name them.
#[derive(Debug, Clone)]
pub struct Records {
    /// The main record: a file, or `-` (stdin; a live MAVLink address for the replay job).
    pub data: String,
    /// Further records of the same aircraft fitted with it (the batch fits' `--and`).
    pub and: Vec<String>,
    /// The log format; `None`: by each file's extension, else CSV
    /// ([`aeroident_io::Record::open`]).
    pub format: Option<LogFormat>,
    /// The channel mapping of every record.
    pub mapping: Mapping,
    /// Whether the main record is a live feed (stdin or MAVLink): whole-record steps refuse it.
    pub live: bool,
    /// Whether a record may be given twice (the same file, or the same content) on purpose
    /// (`--allow-duplicate-records`); otherwise it is refused
    /// ([`crate::record::duplicates`]).
    pub allow_duplicates: bool,
    /// The main record read and screened once, held in memory for the steps that read it
    /// again ([`Records::held`]); `None`: each step reads the file.
    pub held: Option<std::sync::Arc<crate::record::cache::ScreenedRecord>>,
}

impl Records {
    /// One record file `data` read through `mapping`, its format by its extension: no further
    /// record, not live.
    pub fn one(data: String, mapping: Mapping) -> Self {
        Self {
            data,
            and: Vec::new(),
            format: None,
            mapping,
            live: false,
            allow_duplicates: false,
            held: None,
        }
    }

    /// These records with the main one read through `screen` and held in memory
    /// ([`crate::record::cache`]), for the steps after a job's own estimator that read it
    /// again: each of them then costs its estimator, not a read and screen of the file. As
    /// they are for a live feed, several records (only the main one would be held), a record
    /// that cannot be read or is too long to hold, or a screen whose settings are refused.
    pub fn held(&self, screen: Option<crate::record::outliers::SpikeScreen>) -> Records {
        if self.held.is_some() || !self.holds(screen) {
            return self.clone();
        }
        let held = self.open(&self.data).ok().and_then(|r| {
            crate::record::cache::ScreenedRecord::read(r, screen).map(std::sync::Arc::new)
        });
        Records { held, ..self.clone() }
    }

    /// Whether the main record may be held in memory read through `screen`
    /// ([`Records::held`]): a file (not a live feed), the only record, a screen whose settings
    /// are accepted ([`crate::record::check_spike_screen`]).
    pub fn holds(&self, screen: Option<crate::record::outliers::SpikeScreen>) -> bool {
        !self.live
            && self.and.is_empty()
            && crate::record::check_spike_screen(screen.as_ref()).is_ok()
    }

    /// The main record held in memory, when it was read with `screen`.
    pub fn held_with(
        &self,
        screen: Option<crate::record::outliers::SpikeScreen>,
    ) -> Option<&crate::record::cache::ScreenedRecord> {
        self.held.as_deref().filter(|h| h.screen() == screen)
    }

    /// Every file, the main record first.
    pub fn files(&self) -> impl Iterator<Item = &String> {
        std::iter::once(&self.data).chain(&self.and)
    }

    /// Refuses a record given twice, unless [`Records::allow_duplicates`]: the same file or
    /// bytes ([`crate::record::duplicates::check_distinct`]), or the same samples in other
    /// bytes ([`crate::record::duplicates::check_distinct_samples`]).
    ///
    /// # Errors
    /// [`RecordError`](crate::record::RecordError) naming both files.
    pub fn check_distinct(&self) -> Result<(), crate::record::RecordError> {
        crate::record::duplicates::check_distinct(
            self.files().map(String::as_str),
            self.allow_duplicates,
        )?;
        if self.allow_duplicates || self.live || self.and.is_empty() {
            return Ok(());
        }
        let opened: Vec<(&str, LogReader)> =
            self.files().filter_map(|f| Some((f.as_str(), self.open(f).ok()?))).collect();
        crate::record::duplicates::check_distinct_samples(opened)
    }

    /// Opens every record anew for a step over the whole of them (what the reader left out is
    /// the estimating step's to report, not this one's).
    ///
    /// # Errors
    /// The first record that cannot be opened.
    pub fn open_all(&self) -> Result<Vec<LogReader>, FlightDataError> {
        self.files().map(|f| self.open(f)).collect()
    }

    /// Opens the record `file` with the job's format and mapping.
    ///
    /// # Errors
    /// As [`aeroident_io::Record::open`].
    pub fn open(&self, file: &str) -> Result<LogReader, FlightDataError> {
        let source = aeroident_io::RecordSource::Path(file.to_string());
        aeroident_io::Record::open(source, self.format, &self.mapping).map(|r| r.reader)
    }

    /// The main record's sample interval, s: the median of the positive intervals between its
    /// first [`INTERVAL_SAMPLES`] good samples (a gap or a rejected row does not move a
    /// median). `None` for a live feed, a record that cannot be read again, or fewer than two
    /// samples.
    pub fn sample_interval_s(&self) -> Option<f64> {
        if self.live {
            return None;
        }
        let samples: Vec<_> = (self.open(&self.data).ok()?)
            .filter_map(|e| match e {
                Ok(RecordEvent::Sample { sample, .. }) => Some(sample),
                _ => None,
            })
            .take(INTERVAL_SAMPLES)
            .collect();
        crate::record::median_interval_s([samples.as_slice()])
    }
}

/// How the model is chosen (`--model`, `--select`, `--candidates`, `--knots-deg`).
#[derive(Debug, Clone)]
pub struct ModelChoice {
    /// A preset name, a model file, or `auto[:scope]`; `None`: the richest preset the record
    /// supports, chosen by the estimating step.
    pub model: Option<String>,
    /// `--model auto`'s method: `swr` (stepwise regression) or `mof` (orthogonal functions).
    pub select: String,
    /// `--model auto`'s candidate terms (vocabulary names); empty: the defaults.
    pub candidates: Vec<String>,
    /// `--model auto`'s α knots of the spline candidates, degrees, ascending.
    pub knots_deg: Vec<f64>,
    /// The differentiator window the selection differentiates with, samples (odd ≥ 3).
    pub diff_window: usize,
}

impl Default for ModelChoice {
    fn default() -> Self {
        Self {
            model: None,
            select: "swr".into(),
            candidates: Vec::new(),
            knots_deg: Vec::new(),
            diff_window: crate::structure::DIFF_WINDOW,
        }
    }
}

impl ModelChoice {
    /// Whether the model is selected on the record (`auto…`).
    pub fn is_auto(&self) -> bool {
        self.model.as_deref().is_some_and(|m| m.starts_with("auto"))
    }
}

/// The record a fit is validated on (`--validate-on FILE`, `--validate-window START:END …`):
/// a second record, or held-out windows of the same one.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidateOn {
    /// The record (the fitted one for held-out windows of it).
    pub path: String,
    /// Its windows, each a manoeuvre; empty: the whole record.
    pub windows: Vec<TimeWindow>,
}

impl ValidateOn {
    /// Opens the second record through `mapping` ([`aeroident_io::Record::open`], its format by
    /// its extension): the reader and what its reading left out, one line each.
    ///
    /// # Errors
    /// As [`aeroident_io::Record::open`].
    pub fn open(&self, mapping: &Mapping) -> Result<(LogReader, Vec<String>), FlightDataError> {
        let source = aeroident_io::RecordSource::Path(self.path.clone());
        let record = aeroident_io::Record::open(source, None, mapping)?;
        let notes = record.notes();
        Ok((record.reader, notes))
    }

    /// A second record `path` (if given) and validation windows (`windows`, of `path` or, without
    /// it, of the fitted record `data`); `None` when neither is given.
    pub fn from_args(path: Option<String>, windows: Vec<TimeWindow>, data: &str) -> Option<Self> {
        let path = path.or_else(|| (!windows.is_empty()).then(|| data.to_string()))?;
        Some(Self { path, windows })
    }

    /// The warning when this validation reuses data the fit used: the fitted record `data`
    /// with fit windows `fitted` (empty: the whole record) overlapping the validation's.
    pub fn overlap_warning(&self, data: &str, fitted: &[TimeWindow]) -> Option<String> {
        if self.path != data {
            return None;
        }
        let whole = TimeWindow { start_s: f64::NEG_INFINITY, end_s: f64::INFINITY };
        let fit: &[TimeWindow] =
            if fitted.is_empty() { std::slice::from_ref(&whole) } else { fitted };
        let mine: &[TimeWindow] =
            if self.windows.is_empty() { std::slice::from_ref(&whole) } else { &self.windows };
        let overlap =
            mine.iter().any(|v| fit.iter().any(|f| v.start_s < f.end_s && f.start_s < v.end_s));
        overlap.then(|| {
            "--validate-on: the validation data overlap the fitted data (the same record, overlapping windows or the whole record): `validation_on` is then no independent check; validate on held-out windows (`--validate-window`) or another record".to_string()
        })
    }
}

/// Where a job's compatibility corrections come from (`--compat FILE|auto`).
#[derive(Debug, Clone)]
pub enum CompatSource {
    /// Corrections already read (Python reads its `compat.json` itself); boxed, as the
    /// other sources are small.
    Given(Box<Corrections>),
    /// A `compat.json` written by `aeroident compat`.
    File(PathBuf),
    /// Checked on the main record before estimating.
    Auto,
}

impl CompatSource {
    /// `--compat`'s argument: `auto`, else a `compat.json` path.
    pub fn from_arg(arg: &str) -> Self {
        if arg == "auto" { CompatSource::Auto } else { CompatSource::File(arg.into()) }
    }
}

/// A step of a job over a whole record, which a face may run where it can abandon it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// The compatibility stage (a `compat.json` read, or the check on the record).
    Compat,
    /// The model stage (a preset or file read, or the structure selection on the record).
    Model,
    /// The validation on a second record.
    ValidateOn,
    /// The cross-check: the record's other methods.
    CrossCheck,
    /// Least squares' regressor-noise test: the record replayed by instrumental variables.
    RegressorNoise,
    /// The timing refit: the record fitted again with a surface's measured lead undone.
    TimingRefit,
    /// The sample-timing test: the record fitted again with the gyros half a sample late, and
    /// half a sample early.
    SampleTiming,
    /// The repeatability test of an online replay: each window replayed alone.
    Repeatability,
}

impl Step {
    /// The step as a user asked for it, for messages ("interrupted during …").
    pub fn describe(self) -> &'static str {
        match self {
            Step::Compat => "--compat auto (the data compatibility check)",
            Step::Model => "--model auto (the structure selection)",
            Step::ValidateOn => "--validate-on",
            Step::CrossCheck => "--cross-check (the record's other methods)",
            Step::RegressorNoise => {
                "the regressor-noise test (the record replayed by instrumental variables)"
            }
            Step::TimingRefit => {
                "the timing refit (the record fitted with the measured lead undone)"
            }
            Step::SampleTiming => {
                "the sample-timing test (the record fitted with the gyros skewed by half a sample)"
            }
            Step::Repeatability => "the repeatability test (each window replayed alone)",
        }
    }
}

/// Runs a job's steps over a whole record. The CLI runs each on a thread of its own and
/// abandons it on a signal (nothing of such a step is worth keeping half done); [`InPlace`]
/// runs it where it is called.
pub trait Guard {
    /// Runs `f`, the step `step`; `None` when the face abandoned it (a stop was requested).
    ///
    /// # Errors
    /// The face could not run it (a thread that did not start, or ended without a result).
    fn run<T: Send + 'static>(
        &mut self,
        step: Step,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Result<Option<T>, ReplayError>;
}

/// A [`Guard`] that runs every step in place and never abandons one.
#[derive(Debug, Default, Clone, Copy)]
pub struct InPlace;

impl Guard for InPlace {
    fn run<T: Send + 'static>(
        &mut self,
        _step: Step,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Result<Option<T>, ReplayError> {
        Ok(Some(f()))
    }
}

/// The lines a user reads while a job runs (what it starts, what a step found); `()` drops
/// them.
pub trait JobLog {
    /// One line.
    fn note(&mut self, _line: &str) {}

    /// A warning (also kept in the summary): by default the line `warning: {text}`.
    fn warning(&mut self, text: &str) {
        self.note(&format!("warning: {text}"));
    }

    /// What a log reader said of a record it opened (a step's second record): by default the
    /// line `note: {text}`.
    fn reader_note(&mut self, text: &str) {
        self.note(&format!("note: {text}"));
    }
}

impl JobLog for () {}

/// A job's outcome, or the step a stop abandoned before it had one.
#[derive(Debug)]
pub enum Ran<T> {
    /// The job ran to its end (its outcome may still say `interrupted`).
    Done(T),
    /// A stop abandoned this step before any estimate.
    Stopped(Step),
}

/// The compatibility stage: the corrections `source` names with the surfaces' time shifts the
/// mapping declares ([`Corrections::with_mapping`]); the shifts alone without a source, `None`
/// with neither. Every later step (the fit, the model selection, the refits, the cross-check,
/// the validation) takes these corrections, so all see the same surfaces; the check itself
/// runs on the record as logged (it judges the sensors, not the surfaces). Each shift is noted.
///
/// # Errors
/// `auto` on a live feed; an unreadable `compat.json`; the check's errors; a mapped shift the
/// corrections cannot take.
pub fn corrections(
    records: &Records,
    source: Option<&CompatSource>,
    windows: &[TimeWindow],
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
) -> Result<Ran<Option<Corrections>>, ReplayError> {
    let Some(source) = source else {
        return with_mapped_shifts(&records.mapping, None, log).map(Ran::Done);
    };
    let auto = matches!(source, CompatSource::Auto);
    if auto && records.live {
        return Err(ReplayError::Combination(
            "--compat auto needs the whole record; for a live feed give a compat.json".into(),
        ));
    }
    if auto {
        log.note("compat: checking the record's data compatibility (--compat auto)");
    }
    let mapping = records.mapping.clone();
    let (records, source, windows) = (records.clone(), source.clone(), windows.to_vec());
    let step = move || -> Result<(Option<Corrections>, Vec<String>), ReplayError> {
        match source {
            CompatSource::Given(c) => Ok((Some(*c), Vec::new())),
            CompatSource::File(path) => {
                let files = if records.live || records.data == "-" {
                    Vec::new()
                } else {
                    std::iter::once(records.data.clone()).chain(records.and.clone()).collect()
                };
                Ok((Some(Corrections::from_json_for(&path, &files)?), Vec::new()))
            }
            CompatSource::Auto => {
                let config = aeroident_estimators::compat::CompatConfig::default();
                let readers = records.open_all()?;
                let (summary, _) = crate::compat::check_records(readers, &windows, &config)?;
                Ok((Some(Corrections::from_summary(&summary)?), summary.findings))
            }
        }
    };
    let Some(done) = guard.run(Step::Compat, step)? else { return Ok(Ran::Stopped(Step::Compat)) };
    let (corrections, mut findings) = done?;
    let corrections = corrections.map(|c| {
        let (c, notes) = with_leads_undone(c, &mapping);
        findings.extend(notes);
        c
    });
    findings.iter().for_each(|f| log.note(&format!("compat: {f}")));
    with_mapped_shifts(&mapping, corrections, log).map(Ran::Done)
}

/// `c` with each surface of its `leads` delayed by its measured lead (a commanded surface acts
/// about its actuator's lag after its record), and a note per lead: applied, or left to the
/// `shift_s` the mapping declares for that surface, or beyond what a shift may undo.
fn with_leads_undone(mut c: Corrections, mapping: &Mapping) -> (Corrections, Vec<String>) {
    let declared = mapping.input_shifts();
    let mut notes = Vec::new();
    for l in std::mem::take(&mut c.leads) {
        let what = format!(
            "`{}` leads its response by {:+.3} ± {:.3} s",
            l.channel, l.lead_s, l.lead_sigma_s
        );
        if declared.iter().any(|(ch, _)| ch.key() == l.channel) {
            notes.push(format!("{what}: not applied, the mapping declares its `shift_s`"));
            continue;
        }
        // The stage reads a surface τ later at t + τ: a lead is undone at τ = −lead.
        match c.clone().with_input_shift(&l.channel, -l.lead_s) {
            Ok(shifted) => {
                c = shifted;
                notes.push(format!(
                    "{what}: delayed by it (--compat), as `shift_s = {:+.3}` in the mapping would",
                    l.lead_s
                ));
            }
            Err(why) => notes.push(format!("{what}: not applied ({why})")),
        }
    }
    (c, notes)
}

/// `corrections` (none: none) with the surfaces' time shifts `mapping` declares, each noted;
/// as given when it declares none.
///
/// # Errors
/// [`ReplayError::Combination`]: a shift the corrections cannot take, naming the mapping.
fn with_mapped_shifts(
    mapping: &Mapping,
    corrections: Option<Corrections>,
    log: &mut dyn JobLog,
) -> Result<Option<Corrections>, ReplayError> {
    if mapping.input_shifts().is_empty() {
        return Ok(corrections);
    }
    let c =
        corrections.unwrap_or_default().with_mapping(mapping).map_err(ReplayError::Combination)?;
    c.mapped.iter().for_each(|m| log.note(&format!("mapping: {m}")));
    Ok(Some(c))
}

/// The model stage's outcome: the model (`None`: the estimating step's default) and the
/// structure selection of `--model auto`.
pub type ChosenModel = (Option<ModelSpec>, Option<AutoSelection>);

/// The model stage: the preset or model file `choice` names, or the structure selected on the
/// records (`auto…`, its selection path noted line by line); `(None, None)` without one.
///
/// # Errors
/// `auto` on a live feed; a bad model argument or file; the selection's errors.
pub fn choose_model(
    records: &Records,
    choice: &ModelChoice,
    compat: Option<&Corrections>,
    windows: &[TimeWindow],
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
) -> Result<Ran<ChosenModel>, ReplayError> {
    if choice.is_auto() && records.live {
        return Err(ReplayError::Combination(
            "--model auto selects the terms on the whole record: give a file, not a live feed"
                .into(),
        ));
    }
    if choice.is_auto() {
        log.note("structure: selecting the terms on the whole record (--model auto)");
    }
    let (records, choice) = (records.clone(), choice.clone());
    let (compat, windows) = (compat.cloned(), windows.to_vec());
    let step = move || {
        crate::structure::model_from_args(
            choice.model.as_deref(),
            &choice.select,
            &choice.candidates,
            &choice.knots_deg,
            || records.open_all(),
            &records.mapping,
            compat.as_ref(),
            &windows,
            choice.diff_window,
        )
    };
    let Some(done) = guard.run(Step::Model, step)? else { return Ok(Ran::Stopped(Step::Model)) };
    let (model, selection) = done?;
    for line in selection.iter().flat_map(AutoSelection::path_lines) {
        log.note(&line);
    }
    Ok(Ran::Done((model, selection)))
}

/// The stages before the estimator, shared by both jobs: the corrections `compat` names, then
/// the model `choice` names (selected on the records with the corrections applied, over
/// `windows`).
///
/// # Errors
/// As [`corrections`] and [`choose_model`].
pub fn prepare_stages(
    records: &Records,
    choice: &ModelChoice,
    compat: Option<&CompatSource>,
    windows: &[TimeWindow],
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
) -> Result<Ran<(Option<Corrections>, ChosenModel)>, ReplayError> {
    let compat = match corrections(records, compat, windows, guard, log)? {
        Ran::Done(c) => c,
        Ran::Stopped(step) => return Ok(Ran::Stopped(step)),
    };
    match choose_model(records, choice, compat.as_ref(), windows, guard, log)? {
        Ran::Done(chosen) => Ok(Ran::Done((compat, chosen))),
        Ran::Stopped(step) => Ok(Ran::Stopped(step)),
    }
}

/// `summary.json`'s document: `summary` serialised, with `--model auto`'s structure selection
/// under `structure_selection`.
///
/// # Errors
/// A summary that does not serialise (a bug: every summary type is plain data).
pub fn document(
    summary: &impl serde::Serialize,
    selection: Option<&AutoSelection>,
) -> Result<serde_json::Value, serde_json::Error> {
    let mut doc = serde_json::to_value(summary)?;
    if let (Some(s), Some(map)) = (selection, doc.as_object_mut()) {
        map.insert("structure_selection".into(), serde_json::to_value(s.report())?);
    }
    Ok(doc)
}
