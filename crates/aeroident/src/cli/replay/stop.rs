//! How `aeroident replay` answers signals (crate::interrupt): the steps over a whole record on
//! a thread a signal abandons ([`Watched`], the jobs' [`Guard`]), the summary of a run stopped
//! before it had estimates, and the writing phase in which further signals are ignored.

use super::ReplayArgs;
use aeroident_pipelines::job::{Guard, JobLog, Step};
use aeroident_pipelines::replay::ReplayError;

/// The jobs' [`Guard`] of the command line: each step over a whole record on a thread of its
/// own, abandoned on a signal ([`stage_watched`]).
pub(super) struct Watched<'a>(pub(super) &'a crate::interrupt::Interrupt);

impl Guard for Watched<'_> {
    fn run<T: Send + 'static>(
        &mut self,
        _step: Step,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Result<Option<T>, ReplayError> {
        stage_watched(self.0, f).map_err(|e| ReplayError::Step(format!("{e:#}")))
    }
}

/// The jobs' [`JobLog`] of the command line: every line on stderr.
pub(super) struct Stderr;

impl JobLog for Stderr {
    fn note(&mut self, line: &str) {
        aeroident_report::note!("{line}");
    }
}

/// Ends a run that a signal stopped during `step` (an option's step over the whole record),
/// before any estimator ran: `summary.json` with status `interrupted` and why; the error to
/// return (exit 128 + signal), or an output I/O error.
pub(super) fn stopped_before_fit(
    args: &ReplayArgs,
    interrupt: &crate::interrupt::Interrupt,
    out: Option<&mut crate::outdir::OutputDir>,
    step: Step,
) -> anyhow::Error {
    interrupt.begin_writing();
    let why = format!(
        "interrupted by {} during {}, before any estimate",
        interrupt.signal_name().unwrap_or_default(),
        step.describe()
    );
    match write_stopped_summary(args, out, None, &why) {
        Ok(()) => stopped(interrupt, "no estimates; summary.json says why"),
        Err(e) => e,
    }
}

/// Runs `stage`, a step over a whole record that no estimator watches (`--compat auto`,
/// `--model auto`, `--validate-on`), abandoned at once on a signal
/// ([`crate::interrupt::Interrupt::watched`]): such a step has no safe point to stop at and
/// nothing of it is worth keeping half done.
///
/// # Errors
/// The thread could not start or ended without a result (a panic).
pub(super) fn stage_watched<T: Send + 'static>(
    interrupt: &crate::interrupt::Interrupt,
    stage: impl FnOnce() -> T + Send + 'static,
) -> anyhow::Result<Option<T>> {
    interrupt.watched(stage)
}

/// The warning of a run that a signal stopped during `--validate-on`.
pub(super) fn validation_stopped(interrupt: &crate::interrupt::Interrupt) -> String {
    format!(
        "interrupted by {} during --validate-on: the fit's results are written, the validation on the second record is not done",
        interrupt.signal_name().unwrap_or_default()
    )
}

/// Enters the writing phase of `interrupt` (crate::interrupt: further signals are ignored from
/// here). Returns whether a second signal came first, in which case only the summary is to be
/// written and `warnings` says so; otherwise an `interrupted` run says on stderr what it writes.
pub(super) fn begin_writing(
    interrupt: Option<&crate::interrupt::Interrupt>,
    interrupted: bool,
    samples_read: usize,
    warnings: &mut aeroident_io::warning::Warnings,
) -> bool {
    let summary_only = interrupt.is_some_and(crate::interrupt::Interrupt::begin_writing);
    if summary_only {
        warnings.push(SUMMARY_ONLY.to_string());
    } else if interrupted {
        aeroident_report::note!(
            "interrupted: writing the results of the {samples_read} samples read; a further signal is ignored until they are written"
        );
    }
    summary_only
}

/// The warning (and error) of a run that a second signal stopped before its results were
/// written (crate::interrupt): `summary.json` was written, nothing else.
pub(super) const SUMMARY_ONLY: &str = "a second signal came before the results were written: only summary.json (and the real-time estimators' estimates.csv) was written, not report.html or the figures";

/// The error ending a run stopped by a signal, `what` saying what was written.
pub(super) fn stopped(interrupt: &crate::interrupt::Interrupt, what: &str) -> anyhow::Error {
    interrupt
        .error(what)
        .map_or_else(|| anyhow::anyhow!("internal: stopped without a signal"), Into::into)
}

/// Writes the `summary.json` of a run a signal stopped before it had estimates: status
/// `interrupted`, `status_reason` why, the estimates `null`; into `out` (then marked
/// complete), or on stderr without `--out`.
///
/// # Errors
/// Output I/O errors.
pub(super) fn write_stopped_summary(
    args: &ReplayArgs,
    out: Option<&mut crate::outdir::OutputDir>,
    samples_read: Option<usize>,
    why: &str,
) -> anyhow::Result<()> {
    let summary = serde_json::json!({
        "estimator": args.estimator.name(),
        "model": args.model,
        "status": aeroident_pipelines::replay::STATUS_INTERRUPTED,
        "status_reason": why,
        "samples_read": samples_read,
        "parameters": null,
        "warnings": [why],
    });
    let text = serde_json::to_string_pretty(&summary)?;
    match out {
        Some(o) => {
            let path = o.write_bytes("summary.json", text.as_bytes())?;
            o.finish();
            aeroident_report::note!("{why}; wrote {}", path.display());
        }
        None => aeroident_report::note!("{text}"),
    }
    Ok(())
}
