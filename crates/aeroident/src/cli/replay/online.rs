//! The real-time estimators' face of `aeroident replay`: the record opened as the console
//! needs it (a live MAVLink feed, stdin a signal can end, a CSV file through the progress bar),
//! each sample's estimates to `estimates.csv` and the live stream, the job's remaining stages,
//! then the results written and printed.

use super::stop::{
    SUMMARY_ONLY, Stderr, Watched, begin_writing, stopped, validation_stopped,
    write_stopped_summary,
};
use super::{Console, ReplayArgs, validation_block};
use aeroident_io::{FlightDataReader, LogFormat, open_log_with_report};
use aeroident_pipelines::job::replay::{Prepared, ReplayJob, ReplayJobOutcome};
use aeroident_pipelines::live::{LiveObserver, SharedLive};
use aeroident_pipelines::record::cache::ScreenedRecord;
use aeroident_pipelines::replay::{
    EstimateRows, ReplayError, ReplayObserver, ReplayOptions, ReplayOutcome, RowRate, replay,
    replay_cached, replay_holding,
};
use anyhow::Context;
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
    if crate::live::is_mavlink(&args.data) {
        Box::new(std::io::LineWriter::new(std::io::stdout().lock()))
    } else {
        Box::new(std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock()))
    }
}

/// The feed's outcome and, when the feed held the record in memory (read beside it or
/// before it), the record held ([`Prepared::held`]).
type Fed = (ReplayOutcome, Option<Arc<ScreenedRecord>>);

/// Opens the record as the console reads it and replays it with `opts`: the outer error is
/// one of opening (returned as it is), the inner one the replay's (a live feed a signal ended
/// before any estimate is then a stopped run, not a failure).
fn replay_record(
    args: &ReplayArgs,
    job: &ReplayJob,
    opts: &ReplayOptions,
    (interrupt, view): (&crate::interrupt::Interrupt, Option<&SharedLive>),
    bar: &indicatif::ProgressBar,
    console: &mut dyn ReplayObserver,
) -> anyhow::Result<Result<Fed, ReplayError>> {
    let mapping = &job.records.mapping;
    let format = args
        .format
        .or_else(|| LogFormat::from_extension(Path::new(&args.data)))
        .unwrap_or(LogFormat::Csv);
    if crate::live::is_mavlink(&args.data) {
        let (reader, stats) = crate::live::open_mavlink(&args.data, mapping)?;
        if let Some(v) = view {
            v.lock().unwrap_or_else(std::sync::PoisonError::into_inner).watch_link(stats.clone());
        }
        return Ok(replay(reader, mapping, opts, console)
            .map(|mut outcome| {
                crate::live::finish(&mut outcome.summary, &stats);
                (outcome, None)
            })
            .inspect_err(|_| crate::live::report_failure(&stats)));
    }
    if job.records.live && matches!(format, LogFormat::Csv | LogFormat::Asc) {
        // stdin through a reader that ends the record on a signal even while no line arrives.
        let stdin = crate::interrupt::InterruptibleStdin::new(interrupt.flag());
        let reader = if format == LogFormat::Asc {
            aeroident_io::log::asc_reader(std::io::BufReader::new(stdin), "-", mapping)
        } else {
            FlightDataReader::new(Box::new(stdin) as Box<dyn std::io::Read>, "-", mapping)
        };
        // A header cut short by a signal is an interruption too, not a plain error.
        return Ok(reader
            .map_err(ReplayError::from)
            .and_then(|reader| replay(reader, mapping, opts, console).map(|o| (o, None))));
    }
    feed_file(args, job, opts, format, bar, console)
}

/// [`replay_record`] of a file (or stdin read whole). When the steps after the feed will read
/// it again ([`aeroident_pipelines::job::Records::holds`]) it is read once and held in memory:
/// a CSV file on a second thread as the estimator takes it
/// ([`aeroident_pipelines::replay::replay_holding`]), another format before the feed (its
/// reader has parsed the file already).
fn feed_file(
    args: &ReplayArgs,
    job: &ReplayJob,
    opts: &ReplayOptions,
    format: LogFormat,
    bar: &indicatif::ProgressBar,
    console: &mut dyn ReplayObserver,
) -> anyhow::Result<Result<Fed, ReplayError>> {
    let mapping = &job.records.mapping;
    let holds = job.records.holds(opts.spike_screen);
    if !job.records.live && format == LogFormat::Csv {
        let (reader, report) = open_csv(args, format, mapping, bar)?;
        let fed = |o: ReplayOutcome, held| (with_report(o, report), held);
        if holds {
            let (outcome, held) = replay_holding(reader, mapping, opts, console);
            return Ok(outcome.map(|o| fed(o, held.map(Arc::new))));
        }
        return Ok(replay(reader, mapping, opts, console).map(|o| fed(o, None)));
    }
    let open = || open_log_with_report(&args.data, Some(format), mapping);
    let (reader, report) = open()?;
    report.notes().iter().for_each(|n| aeroident_report::note!("note: {n}"));
    if !holds {
        return Ok(replay(reader, mapping, opts, console).map(|o| (with_report(o, report), None)));
    }
    if let Some(held) = ScreenedRecord::read(reader, opts.spike_screen).map(Arc::new) {
        let outcome = replay_cached(&held, mapping, opts, console);
        return Ok(outcome.map(|o| (with_report(o, report), Some(held))));
    }
    // Too long to hold, or unreadable (the feed then says why): from the file.
    let (reader, report) = open()?;
    Ok(replay(reader, mapping, opts, console).map(|o| (with_report(o, report), None)))
}

/// `outcome` with the record's reader report listed.
fn with_report(mut outcome: ReplayOutcome, report: aeroident_io::ReaderReport) -> ReplayOutcome {
    outcome.reader.push(report);
    outcome
}

/// The CSV file read through the progress bar (what `open_log` opens for CSV), listed like
/// every file read (a CSV reader leaves nothing out before the rows).
fn open_csv(
    args: &ReplayArgs,
    format: LogFormat,
    mapping: &aeroident_io::Mapping,
    bar: &indicatif::ProgressBar,
) -> anyhow::Result<(FlightDataReader<Box<dyn std::io::Read + Send>>, aeroident_io::ReaderReport)> {
    let file = std::fs::File::open(&args.data).with_context(|| format!("opening {}", args.data))?;
    let read: Box<dyn std::io::Read + Send> =
        Box::new(std::io::BufReader::new(bar.wrap_read(file)));
    let report = aeroident_io::ReaderReport {
        file: args.data.clone(),
        format: format.name().to_string(),
        dropped: Vec::new(),
    };
    Ok((FlightDataReader::new(read, &args.data, mapping)?, report))
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
    if crate::live::is_mavlink(&args.data) || args.data == "-" {
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
