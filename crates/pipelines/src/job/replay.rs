//! The replay job: a record through an online estimator (`aeroident replay`, Python
//! `aeroident.replay`), with every stage a user can ask for ([module doc](super)).
//!
//! The face opens the record (a file, stdin, a live feed) and drives the estimating step with
//! its own observer ([`crate::replay::ReplayObserver`]); the job sequences the rest:
//! `compat → model → estimate → cross-check → validate on a second record`, and forms
//! `summary.json` ([`ReplayJobOutcome::document`]).

use super::{CompatSource, Guard, JobLog, ModelChoice, Ran, Records, Step, prepare_stages};
use crate::replay::prediction::ValidationReport;
use crate::replay::{ReplayError, ReplayOptions, ReplayOutcome, STATUS_INTERRUPTED};
use crate::structure::AutoSelection;

/// Everything a replay job does, as one value.
#[derive(Debug, Clone)]
pub struct ReplayJob {
    /// The record (its `and` list must be empty: an online replay reads one record).
    pub records: Records,
    /// How the model is chosen.
    pub model: ModelChoice,
    /// The compatibility corrections to apply, if any.
    pub compat: Option<CompatSource>,
    /// The replay's options; the job sets their `model` and `compat` from its own stages.
    pub options: ReplayOptions,
    /// The record's other methods set beside the replay after the feed
    /// ([`super::cross_check::Panel`]; not run on a live feed, which cannot be read twice).
    pub cross_check: super::cross_check::Panel,
    /// A second record (same mapping) to validate the final estimates on.
    pub validate_on: Option<super::ValidateOn>,
}

/// The stages before the estimator, done: the options it runs with (model and corrections
/// set) and the structure selection of `--model auto`.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The options of the estimating step.
    pub options: ReplayOptions,
    /// The selection, with `--model auto`.
    pub selection: Option<AutoSelection>,
    /// The main record read and screened into memory by the face, beside the feed
    /// ([`crate::replay::replay_holding`]) or before it ([`crate::replay::replay_cached`]),
    /// which the steps after the feed then read instead of the file; `None` (as
    /// [`ReplayJob::prepare`] leaves it): they hold it themselves when [`Records::holds`]
    /// allows.
    pub held: Option<std::sync::Arc<crate::record::cache::ScreenedRecord>>,
}

/// A replay job's outcome.
#[derive(Debug, Clone)]
pub struct ReplayJobOutcome {
    /// The replay's outcome (with the cross-check when asked for).
    pub outcome: ReplayOutcome,
    /// The validation on the second record, when asked for and done.
    pub validation_on: Option<ValidationReport>,
    /// The structure selection of `--model auto`.
    pub selection: Option<AutoSelection>,
    /// The options the estimator ran with (model and corrections set).
    pub options: ReplayOptions,
}

impl ReplayJobOutcome {
    /// `summary.json`: the replay's document ([`ReplayOutcome::document`]) with the structure
    /// selection.
    ///
    /// # Errors
    /// A summary that does not serialise (a bug).
    pub fn document(&self) -> Result<serde_json::Value, serde_json::Error> {
        super::document(
            &self.outcome.document(self.validation_on.as_ref()),
            self.selection.as_ref(),
        )
    }
}

impl ReplayJob {
    /// Refuses what does not go together before anything is read: a batch estimator (the
    /// batch-fit job's), more than one record, a cross-check of a live feed.
    ///
    /// # Errors
    /// [`ReplayError::Combination`] saying what to do instead.
    pub fn check(&self) -> Result<(), ReplayError> {
        let kind = self.options.estimator;
        if kind.is_batch() {
            return Err(ReplayError::Combination(format!(
                "estimator `{}` is a batch method with no per-sample estimates: run the batch-fit job",
                kind.name()
            )));
        }
        if self.cross_check == super::cross_check::Panel::Full && self.records.live {
            return Err(ReplayError::Combination(
                "--cross-check sets a real-time estimator beside the batch fit of a whole record: not for a live feed or a batch estimator".into(),
            ));
        }
        if !self.records.and.is_empty() {
            return Err(ReplayError::Combination(format!(
                "--and fits several records together: it is for the batch fits (--estimator oe | fem); replay each record on its own with --estimator {}",
                kind.name()
            )));
        }
        Ok(())
    }

    /// The stages before the estimator: the compatibility corrections, then the model.
    ///
    /// # Errors
    /// As [`super::corrections`] and [`super::choose_model`].
    pub fn prepare(
        &self,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
    ) -> Result<Ran<Prepared>, ReplayError> {
        let (records, windows) = (&self.records, &self.options.windows);
        let compat_source = self.compat.as_ref();
        let (compat, (model, selection)) =
            match prepare_stages(records, &self.model, compat_source, windows, guard, log)? {
                Ran::Done(done) => done,
                Ran::Stopped(step) => return Ok(Ran::Stopped(step)),
            };
        let options = ReplayOptions { model, compat, ..self.options.clone() };
        Ok(Ran::Done(Prepared { options, selection, held: None }))
    }

    /// The stages after the estimator, on `outcome`: the cross-check (unless the replay was
    /// interrupted), then the validation on the second record (unless it diverged or was
    /// interrupted). A run interrupted before them says which it left out; a validation a
    /// stop abandoned leaves the run `interrupted`, with `stopped_why` as its warning.
    ///
    /// # Errors
    /// The second record cannot be opened or does not support the fitted model.
    pub fn finish(
        &self,
        prepared: Prepared,
        mut outcome: ReplayOutcome,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
        stopped_why: impl FnOnce() -> String,
    ) -> Result<ReplayJobOutcome, ReplayError> {
        let interrupted = outcome.interrupted();
        if interrupted && (self.validate_on.is_some() || self.cross_check.runs()) {
            let w = "the run was interrupted: --validate-on / the cross-check panel not done"
                .to_string();
            log.warning(&w);
            outcome.summary.warnings.push(w);
        }
        if !interrupted
            && (self.cross_check == super::cross_check::Panel::Full || !outcome.diverged())
        {
            let held = prepared.held.clone();
            self.check_after_feed(&prepared.options, held, &mut outcome, guard, log)?;
        }
        let validation_on = match &self.validate_on {
            Some(v) if !outcome.diverged() && !interrupted => {
                self.validate(v, &prepared.options, &mut outcome, guard, log, stopped_why)?
            }
            _ => None,
        };
        let (selection, options) = (prepared.selection, prepared.options);
        Ok(ReplayJobOutcome { outcome, validation_on, selection, options })
    }

    /// The check after the feed, the verdicts judged again with its doubts: unless the panel
    /// is off or the feed live, the record's other methods run with the same model
    /// ([`super::cross_check::run_panel`]) and the online estimates judged beside them
    /// ([`crate::replay::cross_check`]); without it, least squares' regressor-noise test
    /// ([`super::cross_check::regressor_noise_test`]) and a warning that the panel was not
    /// run; then the repeatability test of two or more windows ([`super::repeat`]), the
    /// timing refit
    /// ([`super::timing::refit_step`]) and the sample-timing test
    /// ([`super::timing::skew_step`]), and the unmodelled σ added
    /// ([`crate::replay::unmodelled`]). A stop abandons each with a warning (the online result
    /// stands on its own).
    fn check_after_feed(
        &self,
        options: &ReplayOptions,
        held: Option<std::sync::Arc<crate::record::cache::ScreenedRecord>>,
        outcome: &mut ReplayOutcome,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
    ) -> Result<(), ReplayError> {
        let own = super::cross_check::own_estimates(
            options.estimator,
            &outcome.summary.status,
            outcome.summary.parameters.iter().map(|p| &p.result),
        );
        let base = ReplayOptions { model: Some(outcome.model.clone()), ..options.clone() };
        // Every step below reads the record again: held in memory, each costs its estimator.
        let held = match held.filter(|h| h.screen() == options.spike_screen) {
            Some(h) => Records { held: Some(h), ..self.records.clone() },
            None => self.records.held(options.spike_screen),
        };
        let (records, warnings) = (&held, &mut outcome.summary.warnings);
        if self.cross_check.runs() && !records.live {
            let (b, panel) = (base.clone(), self.cross_check);
            let check = super::cross_check::check(records, &own, b, panel, guard, log, warnings)?;
            outcome.cross_check = check;
        } else {
            let test = base.clone();
            super::cross_check::regressor_noise_test(records, &own, test, guard, log, warnings)?;
            let why = if records.live {
                super::cross_check::LIVE_FEED
            } else {
                super::cross_check::TURNED_OFF
            };
            let w = super::cross_check::not_run_warning(why);
            log.warning(&w);
            warnings.push(w);
        }
        super::repeat::repeat_step(records, &base, outcome, guard, log)?;
        let again = records.clone();
        let fit = move |compat| {
            let opts = ReplayOptions { compat: Some(compat), ..base.clone() };
            super::cross_check::online_estimates(&again, &opts)
        };
        let s = &mut outcome.summary;
        let (tests, compat, w) = (&s.sign_tests, options.compat.as_ref(), &mut s.warnings);
        super::timing::refit_step(records, &own, tests, compat, fit.clone(), guard, log, w)?;
        let spreads = super::timing::skew_step(records, &own, compat, fit, guard, log, w)?;
        let results = outcome.summary.parameters.iter_mut().map(|p| &mut p.result);
        super::timing::widen_sigma(results, &spreads);
        let thrust = crate::plausibility::thrust_mapped(&records.mapping);
        crate::replay::verdict::judge(outcome, thrust);
        Ok(())
    }

    /// `--validate-on`: the final estimates applied to the record `v` names, within its windows
    /// (not the fit's); `None` when a stop abandoned it (the run is then `interrupted`,
    /// `stopped_why()` its warning). A warning when those are data the fit used.
    fn validate(
        &self,
        v: &super::ValidateOn,
        options: &ReplayOptions,
        outcome: &mut ReplayOutcome,
        guard: &mut impl Guard,
        log: &mut dyn JobLog,
        stopped_why: impl FnOnce() -> String,
    ) -> Result<Option<ValidationReport>, ReplayError> {
        let overlap = v.overlap_warning(&self.records.data, &options.windows);
        if let Some(w) = overlap {
            log.warning(&w);
            outcome.summary.warnings.push(w);
        }
        let (v, mapping) = (v.clone(), self.records.mapping.clone());
        let options = ReplayOptions { windows: v.windows.clone(), ..options.clone() };
        let fitted = outcome.clone();
        let step = move || -> Result<_, ReplayError> {
            let (reader, notes) = v.open(&mapping)?;
            let report = crate::replay::validate_on(reader, &mapping, &options, &fitted)?;
            Ok((report, notes))
        };
        match guard.run(Step::ValidateOn, step)? {
            Some(done) => {
                let (report, notes) = done?;
                notes.iter().for_each(|n| log.reader_note(n));
                Ok(Some(report))
            }
            None => {
                outcome.summary.status = STATUS_INTERRUPTED.to_string();
                outcome.summary.warnings.push(stopped_why());
                Ok(None)
            }
        }
    }
}
