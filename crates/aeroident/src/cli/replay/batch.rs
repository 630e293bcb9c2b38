//! The batch fits' face of `aeroident replay` (`--estimator oe | fem | fdoe`): the records
//! read (stdin through a reader a signal can end) and fitted on a thread of their own under
//! the signal handlers, the job's validation, then the results written and printed.

use super::stop::{
    SUMMARY_ONLY, Stderr, Watched, begin_writing, stopped, validation_stopped,
    write_stopped_summary,
};
use super::{ReplayArgs, validation_block};
use aeroident_estimators::output_error::StopFlag;
use aeroident_io::{Record, RecordSource};
use aeroident_pipelines::estimators::EstimatorKind;
use aeroident_pipelines::job::fit::{FitJob, FitJobOutcome, Prepared};
use aeroident_pipelines::replay::STATUS_INTERRUPTED;
use aeroident_pipelines::replay::batch::{BatchOutcome, FitOptions, ReplicaCounter};
use aeroident_pipelines::structure::AutoSelection;
use anyhow::Context;
use std::path::Path;

/// `--estimator oe | fem | fdoe`: the batch fit of the whole record(s), into `out` (opened)
/// when `--out` is given.
///
/// The records are read and fitted on a thread of their own under the signal handlers
/// ([`fit_watched`]). A signal while stdin is read ends the read and the fit is of the samples
/// read until then; too few to fit, the summary says so with no estimates. A signal during
/// the fit stops it at its next iteration (a bootstrap before its next replica) and its last
/// iterate is written. Either way `summary.json` has status `interrupted` and the exit code is
/// 128 + signal.
pub(super) fn execute(
    args: &ReplayArgs,
    job: FitJob,
    prepared: Prepared,
    interrupt: &crate::interrupt::Interrupt,
    mut out: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    let (options, stop, bootstrap) = watched_options(prepared.options);
    announce(args.estimator, &options);
    let prepared = Prepared { options, ..prepared };
    let stdin =
        (args.data == "-").then(|| crate::interrupt::InterruptibleStdin::new(interrupt.flag()));
    let progress = stdin.as_ref().map(crate::interrupt::InterruptibleStdin::progress);
    let fit_job = job.clone();
    let fit = move || read_and_fit(&fit_job, prepared, stdin);
    let watched = FitWatched { interrupt, stdin: progress.as_deref(), stop: &stop, bootstrap };
    let Some(fitted) = fit_watched(fit, &watched)? else {
        interrupt.begin_writing();
        let why = format!(
            "a second {} stopped the fit before it ended: no estimates",
            interrupt.signal_name().unwrap_or_default()
        );
        write_stopped_summary(args, out.as_mut(), None, &why)?;
        return Err(stopped(interrupt, "the fit was abandoned; summary.json says so"));
    };
    let cut = progress.as_ref().is_some_and(|p| p.end() == Some(crate::interrupt::StdinEnd::Cut));
    let (mut outcome, selection) = match fitted {
        Ok(f) => f,
        // Nothing to report but why: the summary still says what happened.
        Err(e) if cut || stop.raised() => {
            interrupt.begin_writing();
            let what = match progress.filter(|_| cut) {
                Some(p) => format!(" after {} lines of stdin, too few to fit", p.lines()),
                None => ", with no fit".into(),
            };
            let sig = interrupt.signal_name().unwrap_or_default();
            write_stopped_summary(
                args,
                out.as_mut(),
                None,
                &format!("interrupted by {sig}{what}: {e:#}"),
            )?;
            return Err(stopped(interrupt, "no fit; summary.json says why"));
        }
        Err(e) => return Err(e),
    };
    let signal = interrupt.signal_name().unwrap_or_default();
    if cut {
        mark_interrupted(&mut outcome.summary, &signal);
    } else if stop.raised() {
        mark_stopped(&mut outcome, &signal);
    }
    let stopped_why = || validation_stopped(interrupt);
    let done = job.finish(outcome, selection, &mut Watched(interrupt), &mut Stderr, stopped_why)?;
    write(args, done, interrupt, out)
}

/// `options` with a stop the signals raise and a count of the bootstrap's replicas; the stop,
/// and the count with the replicas asked for (when a bootstrap is).
fn watched_options(options: FitOptions) -> (FitOptions, StopFlag, Option<(usize, ReplicaCounter)>) {
    let (stop, replicas) = (StopFlag::default(), ReplicaCounter::default());
    let options =
        FitOptions { stop: Some(stop.clone()), bootstrap_done: Some(replicas.clone()), ..options };
    let bootstrap = options.bootstrap_refits.map(|n| (n, replicas));
    (options, stop, bootstrap)
}

/// Says on stderr that a batch method reads the whole record first, and what a bootstrap
/// adds.
fn announce(estimator: EstimatorKind, options: &FitOptions) {
    aeroident_report::note!(
        "{} is a batch method: reading the whole record before fitting (not real time)",
        match estimator {
            EstimatorKind::Fem => "the filter-error method",
            EstimatorKind::Fdoe => "frequency-domain output error",
            _ => "output error",
        }
    );
    if let Some(n) = options.bootstrap_refits.filter(|_| estimator == EstimatorKind::Oe) {
        aeroident_report::note!(
            "bootstrap: a filter-error fit for the noise levels, then {n} replicas refitted"
        );
    }
}

/// Opens the job's records ([`Record::open`]; `-` through `stdin` when given), printing what
/// each reader left out, and fits them ([`FitJob::fit`]).
fn read_and_fit(
    job: &FitJob,
    prepared: Prepared,
    mut stdin: Option<crate::interrupt::InterruptibleStdin>,
) -> anyhow::Result<(BatchOutcome, Option<AutoSelection>)> {
    let records = &job.records;
    let (mut readers, mut reports) = (Vec::new(), Vec::new());
    for file in records.files() {
        let source = match stdin.take_if(|_| file == "-") {
            Some(s) => RecordSource::Bytes { name: "-".into(), read: Box::new(s) },
            None => RecordSource::Path(file.clone()),
        };
        let record = Record::open(source, records.format, &records.mapping)?;
        record.notes().iter().for_each(|n| aeroident_report::note!("note: {n}"));
        readers.push(record.reader);
        reports.push(record.report);
    }
    Ok(job.fit(prepared, readers, reports)?)
}

/// Runs `fit` (the batch fit, of a file or of stdin) on a thread of its own while answering the
/// signals (crate::interrupt). Reading stdin (`stdin` tells when and how its read ended), the
/// first signal ends the read and the fit runs on what was read. A first signal once the
/// record is read raises `stop`: the fit ends at its next iteration with its last iterate, the
/// bootstrap before its next replica. A second signal abandons the fit at once: `None`.
///
/// # Errors
/// The fit's thread could not start or ended without a result (a panic).
fn fit_watched<T: Send + 'static>(
    fit: impl FnOnce() -> T + Send + 'static,
    w: &FitWatched<'_>,
) -> anyhow::Result<Option<T>> {
    use std::sync::mpsc::RecvTimeoutError;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("batch-fit".into())
        .stack_size(aeroident_pipelines::WORKER_STACK_BYTES)
        .spawn(move || {
            let _ = tx.send(fit());
        })
        .context("starting the batch fit's thread")?;
    let mut watch = FitWatch::default();
    // A long fit or bootstrap takes tens of seconds: a terminal sees the work is alive.
    let spin = crate::progress::spinner("batch fit (read, fit, σ)");
    let _clear = clear_on_drop(&spin);
    loop {
        match rx.recv_timeout(std::time::Duration::from_millis(50)) {
            Ok(r) => return Ok(Some(r)),
            Err(RecvTimeoutError::Disconnected) => {
                anyhow::bail!("internal: the batch fit's thread ended without a result")
            }
            Err(RecvTimeoutError::Timeout) => {}
        }
        if w.interrupt.stop_now() {
            return Ok(None);
        }
        watch.look(w.interrupt, w.stdin, w.stop);
        if let Some((n, replicas)) = &w.bootstrap {
            crate::progress::count_on(&spin, *n, replicas.done(), "bootstrap replicas");
        }
    }
}

/// What [`fit_watched`] watches while the fit runs: the signals, the read of stdin, the stop it
/// raises, and the bootstrap's replicas (count asked for, count done) when one was asked for.
struct FitWatched<'a> {
    interrupt: &'a crate::interrupt::Interrupt,
    stdin: Option<&'a crate::interrupt::StdinProgress>,
    stop: &'a StopFlag,
    bootstrap: Option<(usize, ReplicaCounter)>,
}

/// Clears `spin` when dropped, whichever way [`fit_watched`] returns.
fn clear_on_drop(spin: &indicatif::ProgressBar) -> impl Drop {
    struct Clear(indicatif::ProgressBar);
    impl Drop for Clear {
        fn drop(&mut self) {
            self.0.finish_and_clear();
        }
    }
    Clear(spin.clone())
}

/// What [`fit_watched`] has seen and said so far.
#[derive(Default)]
struct FitWatch {
    /// The record is read (stdin ended, or a file).
    read: bool,
    /// The first signal has been answered (it cut stdin, or it raised the stop).
    answered: bool,
}

impl FitWatch {
    /// Notes the end of stdin's read, and raises `stop` on a signal that came once the record
    /// was read (one that ended the read is answered by that).
    fn look(
        &mut self,
        interrupt: &crate::interrupt::Interrupt,
        stdin: Option<&crate::interrupt::StdinProgress>,
        stop: &StopFlag,
    ) {
        use crate::interrupt::StdinEnd;
        let sig = || interrupt.signal_name().unwrap_or_default();
        let again = "a second signal stops at once, writing summary.json alone";
        if !self.read {
            let Some(end) = stdin.map_or(Some(StdinEnd::Closed), |p| p.end()) else { return };
            self.read = true;
            let lines = stdin.map_or(0, |p| p.lines());
            match (end, stdin.is_some()) {
                (StdinEnd::Cut, _) => {
                    self.answered = true;
                    aeroident_report::note!(
                        "{}: stdin read ended after {lines} lines; fitting the samples read ({again})",
                        sig()
                    );
                }
                (StdinEnd::Closed, true) => {
                    aeroident_report::note!("stdin closed after {lines} lines: fitting")
                }
                (StdinEnd::Closed, false) => {}
            }
        }
        if !self.answered && interrupt.requested() {
            self.answered = true;
            stop.raise();
            aeroident_report::note!(
                "{}: stopping the fit at its next iteration (a bootstrap before its next replica), its last iterate reported; {again}",
                sig()
            );
        }
    }
}

/// A batch summary of a fit a signal stopped at a safe point: status `interrupted`, and why,
/// with the fit's own status (how many bootstrap replicas were done is in their own warning).
fn mark_stopped(outcome: &mut BatchOutcome, signal: &str) {
    use aeroident_estimators::output_error::{NotConverged, Termination};
    let s = &mut outcome.summary;
    let what = match outcome.result.termination {
        Termination::NotConverged(NotConverged::Stopped)
        | Termination::CostConverged(NotConverged::Stopped) => format!(
            "during the fit: the estimates are its last iterate ({} iterations)",
            s.iterations.len().saturating_sub(1)
        ),
        _ => "after the fit had ended: the estimates are its result, and the warnings say what the stop cut short".to_string(),
    };
    let why = format!(
        "interrupted by {signal} {what}; the fit's own status was `{}`{}",
        s.status,
        s.status_reason.as_deref().map_or(String::new(), |r| format!(" ({r})"))
    );
    s.warnings.push(why.clone());
    s.status = STATUS_INTERRUPTED.to_string();
    s.status_reason = Some(why);
}

/// A batch summary of a record a signal cut short: status `interrupted`, and why, with the
/// fit's own status.
fn mark_interrupted(s: &mut aeroident_pipelines::replay::batch::BatchSummary, signal: &str) {
    let why = format!(
        "interrupted after {} rows by {signal}: the estimates are those of the samples read until then; the fit's own status was `{}`{}",
        s.samples_read,
        s.status,
        s.status_reason.as_deref().map_or(String::new(), |r| format!(" ({r})"))
    );
    s.warnings.push(why.clone());
    s.status = STATUS_INTERRUPTED.to_string();
    s.status_reason = Some(why);
}

/// Prints and writes a batch fit's results into `out` (opened before the fit), else on stdout
/// and stderr. Further signals are ignored while the results are written, and a second signal
/// before then leaves the report out (crate::interrupt); an interrupted run ends with the
/// [`crate::interrupt::Interrupted`] error.
fn write(
    args: &ReplayArgs,
    mut done: FitJobOutcome,
    interrupt: &crate::interrupt::Interrupt,
    out: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    let interrupted = done.outcome.summary.status == STATUS_INTERRUPTED;
    aeroident_report::note!("model: {}", done.outcome.model.name);
    let s = &done.outcome.summary;
    for v in std::iter::once(&s.validation).chain(s.validation_on.iter()) {
        eprint!("{}", validation_block(v));
    }
    if let Some(line) = aeroident_io::replay_output::sign_tests_line(&s.sign_tests) {
        aeroident_report::note!("{line}");
    }
    for w in &s.warnings {
        aeroident_report::note!("warning: {w}");
    }
    let s = &mut done.outcome.summary;
    let summary_only = begin_writing(Some(interrupt), interrupted, s.samples_read, &mut s.warnings);
    let text = serde_json::to_string_pretty(&done.document()?)?;
    match out {
        Some(mut out) => {
            let path = out.write_bytes("summary.json", text.as_bytes())?;
            if let Some(s) = &done.selection {
                out.write_bytes("model.toml", s.model.to_toml().as_bytes())?;
            }
            if summary_only {
                out.finish();
                aeroident_report::note!("wrote {}", path.display());
            } else {
                write_batch_report(args, &done.outcome, &mut out)?;
            }
        }
        None => {
            let table = match &done.outcome.frequency {
                Some(f) => f.to_string(),
                None => done.outcome.result.to_string(),
            };
            crate::cli::print_stdout(&table)?;
            aeroident_report::note!("{text}");
        }
    }
    if summary_only {
        Err(stopped(interrupt, SUMMARY_ONLY))
    } else if interrupted {
        Err(stopped(interrupt, "the results so far were written, with status `interrupted`"))
    } else {
        Ok(())
    }
}

/// The batch fit's report, figures and table (`summary.json` is written), and its line on
/// stderr; marks `out` complete.
fn write_batch_report(
    args: &ReplayArgs,
    outcome: &aeroident_pipelines::replay::batch::BatchOutcome,
    out: &mut crate::outdir::OutputDir,
) -> anyhow::Result<()> {
    let name = Path::new(&args.data)
        .file_name()
        .map_or(args.data.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("{name} — {} — {}", args.estimator.name(), outcome.model.name);
    let source = crate::report::Source { data: &args.data, mapping: &args.map };
    let results = crate::report::batch::write(&source, outcome, &title, out)?;
    out.finish();
    crate::cli::print_stdout(&crate::table::render(&results))?;
    aeroident_report::note!(
        "{}: {} samples in {} manoeuvre(s), {} rejected, {} iterations in {:.3} s; wrote {}",
        args.data,
        outcome.summary.samples_read,
        outcome.summary.manoeuvres,
        outcome.summary.samples_rejected,
        outcome.summary.iterations.len().saturating_sub(1),
        outcome.summary.fit_wall_s,
        out.path().display()
    );
    Ok(())
}
