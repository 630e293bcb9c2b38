//! The real-time estimators' face of `aeroident replay`: the record opened as the console
//! needs it (a live MAVLink feed, stdin a signal can end, a CSV file through the progress bar),
//! each sample's estimates to `estimates.csv` and the live stream, the job's remaining stages,
//! then the results written and printed.

use super::stop::{
    SUMMARY_ONLY, Stderr, Watched, begin_writing, stopped, validation_stopped,
    write_stopped_summary,
};
use super::{Console, ReplayArgs, validation_block};
use aeroident_io::record::{Record, RecordSource, is_mavlink};
use aeroident_pipelines::job::replay::{Prepared, ReplayJob, ReplayJobOutcome};
use aeroident_pipelines::live::{LiveObserver, SharedLive};
use aeroident_pipelines::record::cache::ScreenedRecord;
use aeroident_pipelines::replay::{
    EstimateRows, ReplayError, ReplayObserver, ReplayOptions, ReplayOutcome, RowRate, replay,
    replay_holding,
};
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

/// `estimates.csv`'s rate: `--estimates-every`, else every row of a live feed and
/// [`aeroident_pipelines::replay::DEFAULT_ESTIMATES_EVERY_S`] of a file.
fn row_rate(every_s: Option<f64>, live: bool) -> RowRate {
    let default = if live { 0.0 } else { aeroident_pipelines::replay::DEFAULT_ESTIMATES_EVERY_S };
    RowRate::every_s(every_s.unwrap_or(default))
}

/// The real-time estimators' replay (`execute` past the checks and the stages before the
/// estimator): estimates per sample, the stages after it, then the results, into `out_dir`
/// (opened) when `--out` is given.
pub(super) fn execute(
    args: &ReplayArgs,
    job: &ReplayJob,
    prepared: Prepared,
    (interrupt, view): (&crate::interrupt::Interrupt, Option<&mut LiveObserver>),
    mut out_dir: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    let live = job.records.live;
    let mut view = view;
    if let Some(v) = view.as_mut() {
        v.begin(&args.data, &job.records.mapping, &prepared.options);
    }
    let shared = view.as_ref().map(|v| v.shared());
    let mut csv_file = out_dir.as_mut().map(|o| o.create("estimates.csv")).transpose()?;
    let bar = progress_bar(args, live);
    let outcome = {
        let mut stdout = stdout_sink(args);
        let mut status = crate::progress::StatusSink::new(bar.clone());
        let mut sinks: Vec<&mut dyn Write> = Vec::new();
        if let Some(f) = csv_file.as_mut() {
            sinks.push(f);
        }
        if live {
            sinks.push(&mut *stdout);
        }
        if crate::progress::enabled() {
            sinks.push(&mut status);
        }
        let mut none = ();
        let view: &mut dyn ReplayObserver = match view {
            Some(v) => v,
            None => &mut none,
        };
        let rate = row_rate(args.estimates_every_s, live);
        let rows = EstimateRows { sinks, flush_each: args.realtime, rate };
        let mut console = ((Console { interrupt }, rows), view);
        let opened = (interrupt, shared.as_ref());
        replay_record(args, job, &prepared.options, opened, &bar, &mut console)?
    };
    bar.finish_and_clear();
    let (outcome, held) = match outcome {
        Ok(fed) => fed,
        // A live feed stopped before any sample was estimated (even before its header): no
        // results, but still a summary saying so.
        Err(e) if live && interrupt.requested() => {
            drop(csv_file);
            return Err(stopped_live(args, interrupt, out_dir.as_mut(), &e));
        }
        Err(e) => return Err(e.into()),
    };
    let (prepared, stopped_why) = (Prepared { held, ..prepared }, || validation_stopped(interrupt));
    let done = job.finish(prepared, outcome, &mut Watched(interrupt), &mut Stderr, stopped_why)?;
    if let Some(v) = &shared {
        v.lock().unwrap_or_else(std::sync::PoisonError::into_inner).conclude(&done.outcome.summary);
    }
    if let Some(f) = csv_file {
        f.commit()?;
    }
    write(args, done, interrupt, out_dir)
}

/// The progress on stderr when it is a terminal: bytes of the file, or a spinner for a live
/// feed (with the status line of samples, record time and first estimates).
fn progress_bar(args: &ReplayArgs, live: bool) -> indicatif::ProgressBar {
    match std::fs::metadata(&args.data) {
        Ok(m) if !live => crate::progress::bytes_bar(
            m.len(),
            &Path::new(&args.data)
                .file_name()
                .map_or(args.data.clone(), |n| n.to_string_lossy().into()),
        ),
        _ => crate::progress::spinner("replay (live)"),
    }
}

/// Standard output for the live stream of estimates: a MAVLink feed's lines go out as its
/// messages arrive; otherwise buffered, one write per 64 KiB, not per sample (the replay
/// flushes per line only when paced in real time).
fn stdout_sink(args: &ReplayArgs) -> Box<dyn Write> {
    if is_mavlink(&args.data) {
        Box::new(std::io::LineWriter::new(std::io::stdout().lock()))
    } else {
        Box::new(std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock()))
    }
}

/// The feed's outcome and, when the feed held the record in memory (read beside it), the
/// record held ([`Prepared::held`]).
type Fed = (ReplayOutcome, Option<Arc<ScreenedRecord>>);

/// Opens the record ([`Record::open`]) and replays it with `opts`: the outer error is one of
/// opening a file or a feed (returned as it is), the inner one the replay's (a live feed a
/// signal ended before any estimate, even inside its header, is then a stopped run, not a
/// failure). When the steps after the feed will read the record again
/// ([`aeroident_pipelines::job::Records::holds`]) it is held in memory as the estimator takes
/// it ([`aeroident_pipelines::replay::replay_holding`]).
fn replay_record(
    args: &ReplayArgs,
    job: &ReplayJob,
    opts: &ReplayOptions,
    (interrupt, view): (&crate::interrupt::Interrupt, Option<&SharedLive>),
    bar: &indicatif::ProgressBar,
    console: &mut dyn ReplayObserver,
) -> anyhow::Result<Result<Fed, ReplayError>> {
    let (mapping, live) = (&job.records.mapping, job.records.live);
    let source = record_source(args, live, interrupt, bar);
    let Record { reader, report, link } = match Record::open(source, args.format, mapping) {
        Ok(record) => record,
        Err(e) if live && !is_mavlink(&args.data) => return Ok(Err(e.into())),
        Err(e) => return Err(e.into()),
    };
    report.notes().iter().for_each(|n| aeroident_report::note!("note: {n}"));
    if let Some(link) = link {
        aeroident_report::note!("{}", link.listening);
        if let Some(v) = view {
            let mut v = v.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            v.watch_link(link.stats.clone());
        }
        return Ok(replay(reader, mapping, opts, console)
            .map(|mut outcome| {
                crate::live::finish(&mut outcome.summary, &link.stats);
                (outcome, None)
            })
            .inspect_err(|_| crate::live::report_failure(&link.stats)));
    }
    // A file is listed like every file read; stdin read live is not a file.
    let listed = move |mut o: ReplayOutcome| {
        if !live {
            o.reader.push(report);
        }
        o
    };
    if !live && job.records.holds(opts.spike_screen) {
        let (outcome, held) = replay_holding(reader, mapping, opts, console);
        return Ok(outcome.map(|o| (listed(o), held.map(Arc::new))));
    }
    Ok(replay(reader, mapping, opts, console).map(|o| (listed(o), None)))
}

/// Where the console reads the record: a MAVLink feed (its problems printed as they arise),
/// stdin through a reader that ends the record on a signal even while no line arrives, or the
/// file through the progress bar.
fn record_source(
    args: &ReplayArgs,
    live: bool,
    interrupt: &crate::interrupt::Interrupt,
    bar: &indicatif::ProgressBar,
) -> RecordSource {
    if is_mavlink(&args.data) {
        return RecordSource::Mavlink {
            url: args.data.clone(),
            on_problem: Some(crate::live::problem),
        };
    }
    if live {
        let stdin = crate::interrupt::InterruptibleStdin::new(interrupt.flag());
        return RecordSource::Bytes { name: "-".into(), read: Box::new(stdin) };
    }
    let bar = bar.clone();
    RecordSource::Watched {
        path: args.data.clone(),
        watch: Box::new(move |file| Box::new(bar.wrap_read(file))),
    }
}

/// Ends a live feed a signal stopped before any sample was estimated: a summary saying so
/// (with the rows read, when known); the error to return, or an output I/O error.
fn stopped_live(
    args: &ReplayArgs,
    interrupt: &crate::interrupt::Interrupt,
    out: Option<&mut crate::outdir::OutputDir>,
    e: &ReplayError,
) -> anyhow::Error {
    let read = match e {
        ReplayError::Interrupted { samples_read, .. } => Some(*samples_read),
        _ => None,
    };
    let why = format!(
        "interrupted by {} before any sample was estimated: {e}",
        interrupt.signal_name().unwrap_or_default()
    );
    match write_stopped_summary(args, out, read, &why) {
        Ok(()) => stopped(interrupt, "no sample was estimated"),
        Err(e) => e,
    }
}

/// Writes and prints the results of a finished replay job, then ends as the run did (an
/// error for a divergence or an interruption).
fn write(
    args: &ReplayArgs,
    mut done: ReplayJobOutcome,
    interrupt: &crate::interrupt::Interrupt,
    mut out_dir: Option<crate::outdir::OutputDir>,
) -> anyhow::Result<()> {
    let interrupted = done.outcome.interrupted();
    // From here further signals are ignored until the results are written (crate::interrupt);
    // a second one before this point leaves the report and figures out.
    let s = &mut done.outcome.summary;
    let summary_only = begin_writing(Some(interrupt), interrupted, s.samples_read, &mut s.warnings);
    let summary_text = serde_json::to_string_pretty(&done.document()?)?;
    if let (Some(s), Some(o)) = (&done.selection, out_dir.as_mut()) {
        o.write_bytes("model.toml", s.model.to_toml().as_bytes())?;
    }
    match (&args.out, out_dir.as_mut()) {
        (Some(dir), Some(o)) if summary_only => {
            o.write_bytes("summary.json", summary_text.as_bytes())?;
            o.finish();
            let (csv, json) = (dir.join("estimates.csv"), dir.join("summary.json"));
            aeroident_report::note!("wrote {} and {}", csv.display(), json.display());
        }
        (Some(dir), Some(o)) => write_results(args, &done, &summary_text, dir, o)?,
        (Some(_), None) => anyhow::bail!("internal: output directory not open"),
        (None, _) => aeroident_report::note!("{summary_text}"),
    }
    print_diagnostics(&done);
    end(args, &done.outcome, interrupt, interrupted, summary_only)
}

/// `summary.json`, the report, figures and results table of a replay into `o` (marked
/// complete), the table on stdout (beside the log for a live feed, whose stdout carries the
/// estimates), and the run's line on stderr.
fn write_results(
    args: &ReplayArgs,
    done: &ReplayJobOutcome,
    summary_text: &str,
    dir: &Path,
    o: &mut crate::outdir::OutputDir,
) -> anyhow::Result<()> {
    o.write_bytes("summary.json", summary_text.as_bytes())?;
    let outcome = &done.outcome;
    let name = Path::new(&args.data)
        .file_name()
        .map_or(args.data.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("{name} — {} — {}", args.estimator.name(), outcome.model.name);
    let source = crate::report::Source { data: &args.data, mapping: &args.map };
    let references = crate::report::replay::model_references(outcome);
    let results =
        crate::report::replay::write(&source, &done.options, outcome, &title, &references, o)?;
    // Complete: a divergence or an interruption reported below keeps these files.
    o.finish();
    if is_mavlink(&args.data) || args.data == "-" {
        eprint!("{}", crate::table::render(&results));
    } else {
        crate::cli::print_stdout(&crate::table::render(&results))?;
    }
    let s = &outcome.summary;
    aeroident_report::note!(
        "{}: {} samples read, {} rejected, {:.0} samples/s, status {}; wrote {}",
        args.data,
        s.samples_read,
        s.samples_rejected,
        s.throughput_samples_per_s,
        s.status,
        dir.display()
    );
    Ok(())
}

/// The end-of-run lines on stderr: strongly correlated pairs, the validation blocks, and the
/// diagnostic warnings (sign, consistency, collinearity, constant channels, units; the record's
/// warnings were printed as they arose).
fn print_diagnostics(done: &ReplayJobOutcome) {
    let s = &done.outcome.summary;
    if !s.correlations.is_empty() {
        let pairs: Vec<String> =
            s.correlations.iter().map(|c| format!("{}/{} ({:+.3})", c.a, c.b, c.rho)).collect();
        aeroident_report::note!(
            "warning: strongly correlated estimates (|ρ| > 0.9; the data do not separate them): {}",
            pairs.join(", ")
        );
    }
    for v in done.outcome.validation.iter().chain(done.validation_on.iter()) {
        eprint!("{}", validation_block(v));
    }
    if let Some(line) = aeroident_io::replay_output::sign_tests_line(&s.sign_tests) {
        aeroident_report::note!("{line}");
    }
    for w in s.warnings.iter().filter(|w| w.kind.is_diagnostic()) {
        aeroident_report::note!("warning: {w}");
    }
}

/// How the run ends: an error for a divergence, a second signal (summary only) or an
/// interruption (exit 128 + signal); otherwise a warning when not every parameter was
/// identified.
fn end(
    args: &ReplayArgs,
    outcome: &ReplayOutcome,
    interrupt: &crate::interrupt::Interrupt,
    interrupted: bool,
    summary_only: bool,
) -> anyhow::Result<()> {
    if let Some(e) = outcome.diverged_error(args.estimator.name()) {
        anyhow::bail!(e);
    }
    if summary_only {
        return Err(stopped(interrupt, SUMMARY_ONLY));
    }
    if interrupted {
        let what =
            "the results of the samples read until then were written, with status `interrupted`";
        if let Some(e) = interrupt.error(what) {
            return Err(e.into());
        }
    } else if outcome.summary.status != aeroident_pipelines::replay::STATUS_COMPLETE {
        aeroident_report::note!(
            "warning: estimator status `{}`: not every parameter was identified (null in the summary)",
            outcome.summary.status
        );
    }
    Ok(())
}
