//! The batch-fit job: whole records fitted by output error, the filter-error method or
//! frequency-domain output error (`aeroident replay --estimator oe|fem|fdoe`, Python
//! `aeroident.fit`), with every stage a user can ask for ([module doc](super)).
//!
//! The face opens the records (stdin through its own reader) and may run the fit where it can
//! stop it; the job sequences `compat → model → fit → validate on a second record` and forms
//! `summary.json` ([`FitJobOutcome::document`]).

use super::{CompatSource, Guard, JobLog, ModelChoice, Ran, Records, Step, prepare_stages};
use crate::replay::batch::{BatchOutcome, FitOptions};
use crate::replay::{ReplayError, STATUS_INTERRUPTED};
use crate::structure::AutoSelection;
use aeroident_io::{FlightDataReader, ModelSpec, ReaderReport};
use std::io::Read;

/// Everything a batch-fit job does, as one value.
#[derive(Debug, Clone)]
pub struct FitJob {
    /// The records, each a manoeuvre of its own (or several, at gaps and windows).
    pub records: Records,
    /// How the model is chosen.
    pub model: ModelChoice,
    /// The compatibility corrections to apply, if any (checked on the main record with `auto`,
    /// applied to all).
    pub compat: Option<CompatSource>,
    /// The fit's options; the job sets their `compat` from its own stage.
    pub options: FitOptions,
    /// The record's other methods run beside the fit ([`super::cross_check::Panel`]).
    pub cross_check: super::cross_check::Panel,
    /// A second record (same mapping) to validate the fitted model on.
    pub validate_on: Option<super::ValidateOn>,
}

/// The stages before the fit, done: the model (`None`: the fit's default) and the options
/// (corrections set).
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The model given or selected.
    pub model: Option<ModelSpec>,
    /// The options of the fit.
    pub options: FitOptions,
    /// The structure selection of `--model auto`.
    pub selection: Option<AutoSelection>,
}

/// A batch-fit job's outcome: the fit (with its validation on the second record in
/// `summary.validation_on`) and the structure selection.
#[derive(Debug, Clone)]
pub struct FitJobOutcome {
    /// The fit.
    pub outcome: BatchOutcome,
    /// The structure selection of `--model auto`.
    pub selection: Option<AutoSelection>,
}

impl FitJobOutcome {
    /// `summary.json`: the fit's summary with the structure selection.
    ///
    /// # Errors
    /// A summary that does not serialise (a bug).
    pub fn document(&self) -> Result<serde_json::Value, serde_json::Error> {
        super::document(&self.outcome.summary, self.selection.as_ref())
    }
}

impl FitJob {
    /// The stages before the fit: the records checked to be distinct, the compatibility
    /// corrections, then the model.
    ///
    /// # Errors
    /// A record given twice ([`Records::check_distinct`]); as [`super::corrections`] and
    /// [`super::choose_model`].
    pub fn prepare(
        &self,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
    ) -> Result<Ran<Prepared>, ReplayError> {
        // Before any step reads a record: one given twice would be fitted as new data.
        self.records.check_distinct()?;
        let (records, windows) = (&self.records, &self.options.windows);
        let compat_source = self.compat.as_ref();
        let (compat, (model, selection)) =
            match prepare_stages(records, &self.model, compat_source, windows, guard, log)? {
                Ran::Done(done) => done,
                Ran::Stopped(step) => return Ok(Ran::Stopped(step)),
            };
        let options = FitOptions { compat, ..self.options.clone() };
        Ok(Ran::Done(Prepared { model, options, selection }))
    }

    /// The fit of `readers` (the job's records, opened by the face) with the prepared model and
    /// options; `reports` (what each reader left out) go into the summary.
    ///
    /// # Errors
    /// As [`crate::replay::fit::fit_records`].
    pub fn fit<R: Read>(
        &self,
        prepared: Prepared,
        readers: Vec<FlightDataReader<R>>,
        reports: Vec<ReaderReport>,
    ) -> Result<(BatchOutcome, Option<AutoSelection>), ReplayError> {
        let mapping = &self.records.mapping;
        let mut outcome =
            crate::replay::fit::fit_records(readers, mapping, prepared.model, prepared.options)?;
        outcome.summary.reader = reports;
        Ok((outcome, prepared.selection))
    }

    /// The stages after the fit: the cross-check, then the validation on the second record,
    /// unless the fit was interrupted (then a warning says they were not done). A validation a
    /// stop abandoned leaves the run `interrupted`, with `stopped_why` as its warning and
    /// reason.
    ///
    /// # Errors
    /// The second record cannot be opened or read.
    pub fn finish(
        &self,
        mut outcome: BatchOutcome,
        selection: Option<AutoSelection>,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
        stopped_why: impl FnOnce() -> String,
    ) -> Result<FitJobOutcome, ReplayError> {
        let interrupted = outcome.summary.status == STATUS_INTERRUPTED;
        // The timing refits and the panel read the record again: held in memory, each costs
        // its estimator.
        let records = &if interrupted {
            self.records.clone()
        } else {
            self.records.held(outcome.options.spike_screen)
        };
        if !interrupted {
            self.timing_refit(records, &mut outcome, guard, log)?;
        }
        if self.cross_check.runs() && interrupted {
            let w = "the run was interrupted: the cross-check not done".to_string();
            outcome.summary.warnings.push(w);
        } else if self.cross_check.runs() && self.records.live {
            let w = super::cross_check::not_run_warning(super::cross_check::LIVE_FEED);
            log.warning(&w);
            outcome.summary.warnings.push(w);
        } else if self.cross_check.runs() {
            self.cross_check(records, &mut outcome, guard, log)?;
        } else {
            let w = super::cross_check::not_run_warning(super::cross_check::TURNED_OFF);
            log.warning(&w);
            outcome.summary.warnings.push(w);
        }
        match &self.validate_on {
            Some(_) if interrupted => {
                let w = "the run was interrupted: --validate-on not done".to_string();
                outcome.summary.warnings.push(w);
            }
            Some(v) => self.validate(v, &mut outcome, guard, log, stopped_why)?,
            None => {}
        }
        Ok(FitJobOutcome { outcome, selection })
    }

    /// The cross-check: the panel's methods run with the fitted model
    /// ([`super::cross_check::run_panel`]) and the fit judged beside them
    /// ([`crate::replay::cross_check`]), its verdicts judged again with the panel's flags.
    fn cross_check(
        &self,
        records: &Records,
        outcome: &mut BatchOutcome,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
    ) -> Result<(), ReplayError> {
        let (kind, own) = own(outcome);
        let base = crate::replay::ReplayOptions {
            estimator: kind,
            model: Some(outcome.model.clone()),
            compat: outcome.options.compat.clone(),
            windows: outcome.options.windows.clone(),
            spike_screen: outcome.options.spike_screen,
            ..Default::default()
        };
        let warnings = &mut outcome.summary.warnings;
        let panel = self.cross_check;
        let Some(check) =
            super::cross_check::check(records, &own, base, panel, guard, log, warnings)?
        else {
            return Ok(());
        };
        outcome.summary.cross_check = Some(check);
        let thrust = crate::plausibility::thrust_mapped(&self.records.mapping);
        outcome.summary.judge(&outcome.model, thrust);
        Ok(())
    }

    /// The timing refit ([`super::timing::refit_step`]) and the sample-timing test
    /// ([`super::timing::skew_step`]): the records fitted again by the same method, model and
    /// options (no bootstrap) with a warned surface lead undone, and with the gyros skewed by
    /// half a sample (its σ added to every estimate's); then the unmodelled σ added
    /// ([`crate::replay::unmodelled`]) and the verdicts judged again.
    fn timing_refit(
        &self,
        rec: &Records,
        outcome: &mut BatchOutcome,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
    ) -> Result<(), ReplayError> {
        let (kind, own) = own(outcome);
        let (records, model) = (rec.clone(), Some(outcome.model.clone()));
        let mut options = outcome.options.clone();
        options.bootstrap_refits = None;
        let fit = move |compat: crate::record::Corrections| {
            let options = FitOptions { compat: Some(compat), ..options.clone() };
            super::cross_check::batch_estimates(&records, kind, model.clone(), options)
        };
        let s = &mut outcome.summary;
        let compat = outcome.options.compat.as_ref();
        let (tests, w) = (&s.sign_tests, &mut s.warnings);
        super::timing::refit_step(rec, &own, tests, compat, fit.clone(), guard, log, w)?;
        let spreads = super::timing::skew_step(rec, &own, compat, fit, guard, log, w)?;
        let results = outcome.summary.parameters.iter_mut().map(|p| &mut p.result);
        super::timing::widen_sigma(results, &spreads);
        let thrust = crate::plausibility::thrust_mapped(&self.records.mapping);
        outcome.summary.judge(&outcome.model, thrust);
        Ok(())
    }

    /// `--validate-on`: the fitted model simulated on the record `v` names, within its windows
    /// ([`crate::replay::batch::validate_on`]), into `summary.validation_on`; a warning when
    /// those are data the fit used.
    fn validate(
        &self,
        v: &super::ValidateOn,
        outcome: &mut BatchOutcome,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
        stopped_why: impl FnOnce() -> String,
    ) -> Result<(), ReplayError> {
        let overlap = v.overlap_warning(&self.records.data, &self.options.windows);
        outcome.summary.warnings.extend(overlap);
        let (v, mapping, fitted) = (v.clone(), self.records.mapping.clone(), outcome.clone());
        let step = move || -> Result<_, ReplayError> {
            let (reader, notes) = v.open(&mapping)?;
            Ok((crate::replay::batch::validate_on(reader, &fitted, &v.windows)?, notes))
        };
        match guard.run(Step::ValidateOn, step)? {
            Some(done) => {
                let (report, notes) = done?;
                notes.iter().for_each(|n| log.reader_note(n));
                outcome.summary.validation_on = Some(report);
            }
            None => {
                let why = stopped_why();
                let s = &mut outcome.summary;
                s.warnings.push(why.clone());
                s.status = STATUS_INTERRUPTED.to_string();
                s.status_reason = Some(why);
            }
        }
        Ok(())
    }
}

/// The fit's method and its estimates as the panel reads them.
fn own(
    outcome: &BatchOutcome,
) -> (crate::estimators::EstimatorKind, crate::replay::cross_check::MethodEstimates) {
    let s = &outcome.summary;
    let kind = <crate::estimators::EstimatorKind as crate::Named>::from_name(&s.estimator)
        .unwrap_or(crate::estimators::EstimatorKind::Oe);
    let rows = s.parameters.iter().map(|p| &p.result);
    (kind, super::cross_check::own_estimates(kind, &s.status, rows))
}
