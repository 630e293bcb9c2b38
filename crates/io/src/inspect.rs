//! What a log holds, before any mapping is written (`aeroident inspect`) — CSV, `.asc`, `.mat`,
//! ULog, DataFlash, and MAVLink telemetry `.tlog` ([`crate::tlog`], by its extension): its
//! topics (or columns) with their fields and units, per topic the sample count, time span, rate and gaps,
//! the parameters of a ULog or DataFlash log, and the values of the few channels asked for
//! (the surfaces the manoeuvre detector reads, the channels a plot draws).
//!
//! # What is held in memory
//!
//! A multi-rate log (ULog, DataFlash) is streamed through its reader with a
//! [`TopicFilter::times_and`]: every topic keeps its timestamps (8 bytes a message — what a
//! rate and a gap need), and only the asked-for fields and the known actuator topics
//! ([`surfaces::KNOWN_SURFACE_TOPICS`]) keep values. A 100 MB log of about two million messages
//! costs some 16 MB of timestamps, not the file again. A CSV or `.asc` file is streamed row by
//! row keeping the time column and the asked-for columns; a `.mat` file is read whole (its
//! reader decodes it whole) and summarised from that one copy.
//!
//! # Rates and gaps
//!
//! Per topic ([`TimeStats`]): the mean rate is (samples − 1) / span; the median interval is the
//! median of the positive intervals; a gap is an interval longer than [`GAP_MULTIPLE`] times
//! the median interval, and the longest interval is reported with the time it starts at.
//! For a table the time column is the mapping's `[time] column` (in its unit), else the first
//! column whose name says time (`time`, `t`, `time_s`, `timestamp`, …, with a `[s]`/`[ms]`/
//! `[us]` unit or a `_ms`/`_us` suffix read as such), else the first column — the summary says
//! which ([`TimeColumn::source`]).

pub mod surfaces;
mod text;

use crate::FlightDataError;
use crate::log::LogFormat;
use crate::log_contents::{LogContents, TopicFilter, base_topic};
use crate::mapping::Mapping;
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// An interval longer than this many median intervals is a gap. Above 2 so that one missed
/// sample (an interval of 2 medians) with a logger's timing jitter is not counted; a stall of
/// two missed samples or more is.
pub const GAP_MULTIPLE: f64 = 2.5;

/// The version of the `--json` document (docs/inspect.md); raised when a key changes meaning
/// or goes away.
pub const INSPECT_SCHEMA: &str = "aeroident-inspect/1";

/// One field of a topic and its unit where the format states one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldInfo {
    /// Field name (without the topic prefix).
    pub name: String,
    /// The unit the log states (a DataFlash `FMTU` label, a CSV header's `name [unit]`), or
    /// `None` where the format states none (ULog).
    pub unit: Option<String>,
}

/// The timing of one topic's samples (module doc).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TimeStats {
    /// Samples with a usable timestamp.
    pub samples: usize,
    /// First and last sample time, s (log time: since boot for ULog/DataFlash).
    pub first_s: Option<f64>,
    /// Last sample time, s.
    pub last_s: Option<f64>,
    /// `last_s − first_s`, s.
    pub span_s: Option<f64>,
    /// Mean rate (samples − 1) / span, Hz; `None` under two samples or a zero span.
    pub rate_hz: Option<f64>,
    /// Median of the positive intervals, s.
    pub median_interval_s: Option<f64>,
    /// Longest interval, s, and the time of the sample it starts at.
    pub longest_gap_s: Option<f64>,
    /// Time the longest interval starts at, s.
    pub longest_gap_at_s: Option<f64>,
    /// Intervals longer than [`GAP_MULTIPLE`] × the median interval.
    pub gaps: usize,
    /// Intervals that are zero or negative (a table's time going back or repeating; a
    /// multi-rate reader has already left those samples out and says so in the notes).
    pub non_increasing: usize,
}

impl TimeStats {
    /// The statistics of the sample times `t_s` (s, in file order).
    pub fn of(t_s: &[f64]) -> Self {
        let n = t_s.len();
        let mut s = TimeStats { samples: n, ..Self::default() };
        let (Some(&first), Some(&last)) = (t_s.first(), t_s.last()) else { return s };
        s.first_s = Some(first);
        s.last_s = Some(last);
        s.span_s = Some(last - first);
        if n >= 2 && last > first {
            s.rate_hz = Some((n - 1) as f64 / (last - first));
        }
        let mut dt: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
        s.non_increasing = dt.iter().filter(|d| **d <= 0.0).count();
        if let Some((k, &d)) = dt
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.partial_cmp(b.1).unwrap_or(std::cmp::Ordering::Equal))
        {
            s.longest_gap_s = Some(d);
            s.longest_gap_at_s = Some(t_s[k]);
        }
        let median = {
            dt.retain(|d| *d > 0.0);
            median(&mut dt)
        };
        if let Some(m) = median {
            s.median_interval_s = Some(m);
            s.gaps = t_s.windows(2).filter(|w| w[1] - w[0] > GAP_MULTIPLE * m).count();
        }
        s
    }
}

/// The median of `v` (reordered), `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let k = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    Some(*m)
}

/// One topic of a log (for a table: the one table, named after the file).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TopicSummary {
    /// Topic name (`vehicle_imu[1]`, `XKF1`, or the table file's stem).
    pub name: String,
    /// Messages (rows) in the file, before the reader's timestamp checks.
    pub messages: usize,
    /// Every numeric field, in the order of the topic's definition.
    pub fields: Vec<FieldInfo>,
    /// Timing of the samples kept.
    #[serde(flatten)]
    pub time: TimeStats,
}

/// Which column of a table is its time, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimeColumn {
    /// Column name.
    pub name: String,
    /// `"mapping"` (`[time] column`), `"name"` (a name that says time) or `"first column"`.
    pub source: String,
    /// Factor from the column's values to seconds.
    pub to_s: f64,
}

/// Everything `inspect` lists of a log (serialised as the `--json` document's log part).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogSummary {
    /// The file as given.
    pub file: String,
    /// Its format ([`LogFormat::name`], or `tlog`).
    pub format: String,
    /// A table's time column; `None` for a multi-rate log (each topic has its timestamps).
    pub time_column: Option<TimeColumn>,
    /// [`GAP_MULTIPLE`], for the reader of the document.
    pub gap_multiple: f64,
    /// Topics (a table: one), in the file's order.
    pub topics: Vec<TopicSummary>,
    /// Parameters by name (ULog `P`, DataFlash `PARM`; the last value of one changed in
    /// flight). Empty for other formats.
    pub parameters: BTreeMap<String, f64>,
    /// What the reader left out or skipped (out-of-order samples, a cut last message, corrupt
    /// bytes), one line each.
    pub notes: Vec<String>,
}

/// The values of one channel: `values[k]` at `t_s[k]` (s), in the log's own unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Signal {
    /// `topic.field` (multi-rate log) or the column name (table).
    pub column: String,
    /// The unit the log states, if any.
    pub unit: Option<String>,
    /// Sample times, s, increasing.
    pub t_s: Vec<f64>,
    /// Values (NaN where a table's field is not a number).
    pub values: Vec<f64>,
}

/// What to read besides the summary.
#[derive(Debug, Clone, Default)]
pub struct InspectOptions<'a> {
    /// The format; `None`: by the extension ([`LogFormat::from_extension`]), else CSV.
    pub format: Option<LogFormat>,
    /// A channel mapping: a table's time column and names (`[columns] names`), and the surface
    /// channels ([`surfaces::choose`]).
    pub mapping: Option<&'a Mapping>,
    /// Channels whose values to return besides the surfaces (`topic.field` or column names).
    pub keep: Vec<String>,
}

/// A log's summary and the values of its surface channels and of the channels asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Inspection {
    /// The catalogue.
    pub summary: LogSummary,
    /// The surfaces found ([`surfaces::choose`]).
    pub surfaces: Vec<surfaces::Surface>,
    /// The values of the surfaces and of [`InspectOptions::keep`], by column.
    pub signals: Vec<Signal>,
}

/// Reads `path` (`-`: stdin, CSV or `.asc` only) as `options` say and summarises it.
///
/// # Errors
/// The reader's errors naming the file and the byte or row: [`FlightDataError::Io`],
/// [`FlightDataError::LogDecode`], [`FlightDataError::Format`] (a binary log from stdin, a
/// `.mat` it cannot read), [`FlightDataError::Csv`] and [`FlightDataError::Row`] (a time value
/// that is not a number, naming the row and column), [`FlightDataError::NoData`] (no header),
/// and [`FlightDataError::Format`] for a channel of [`InspectOptions::keep`] the log lacks
/// (listing what it has).
pub fn inspect_log(path: &str, options: &InspectOptions) -> Result<Inspection, FlightDataError> {
    let format = LogFormat::resolve(options.format, path);
    let inspection = match format {
        LogFormat::Tlog => {
            inspect_multirate(path, format.name(), options, crate::tlog::read_tlog_filtered)?
        }
        LogFormat::Ulog => inspect_multirate(path, format.name(), options, |p, f| {
            crate::ulog::read_ulog_filtered(p, f).map(|c| (c, None))
        })?,
        LogFormat::Dataflash => inspect_multirate(path, format.name(), options, |p, f| {
            crate::dataflash::read_dataflash_filtered(p, f).map(|c| (c, None))
        })?,
        _ => text::inspect_table(path, format, options)?,
    };
    for c in &options.keep {
        if !inspection.signals.iter().any(|s| &s.column == c) {
            return Err(FlightDataError::Format {
                file: path.to_string(),
                message: no_channel(&inspection.summary, c),
            });
        }
    }
    Ok(inspection)
}

/// Why channel `c` is not in the log, listing what it has.
fn no_channel(summary: &LogSummary, c: &str) -> String {
    let topic = summary
        .topics
        .iter()
        .find(|t| c.strip_prefix(t.name.as_str()).is_some_and(|r| r.starts_with('.')));
    match (topic, &summary.time_column) {
        (Some(t), None) => format!(
            "topic `{}` has no field `{}` (it has: {})",
            t.name,
            &c[t.name.len() + 1..],
            t.fields.iter().map(|f| f.name.as_str()).collect::<Vec<_>>().join(", ")
        ),
        (_, Some(_)) => format!(
            "no column `{c}` (columns: {})",
            summary
                .topics
                .iter()
                .flat_map(|t| &t.fields)
                .map(|f| f.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        (None, None) => format!(
            "no topic for `{c}` (give `<topic>.<field>`; topics: {})",
            summary.topics.iter().map(|t| t.name.as_str()).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// A ULog, DataFlash or `.tlog` log (`format` its name), read by `read` streaming, keeping
/// every topic's timestamps and the values of `options.keep`, the mapping's surface columns
/// and the known actuator topics; `read` also returns a note of its own, if any.
fn inspect_multirate(
    path: &str,
    format: &str,
    options: &InspectOptions,
    read: impl FnOnce(&Path, &TopicFilter) -> Result<(LogContents, Option<String>), FlightDataError>,
) -> Result<Inspection, FlightDataError> {
    if path == "-" {
        return Err(FlightDataError::Format {
            file: path.to_string(),
            message: format!("a {format} log is read from a file, not from stdin"),
        });
    }
    let mut keep = options.keep.clone();
    if let Some(m) = options.mapping {
        keep.extend(surfaces::mapping_surfaces(m).into_iter().map(|s| s.column));
    }
    let filter = TopicFilter::times_and(
        keep.iter().map(String::as_str),
        surfaces::KNOWN_SURFACE_TOPICS.iter().copied(),
    );
    let (contents, note) = read(Path::new(path), &filter)?;
    let mut summary = multirate_summary(path, format, &contents);
    summary.notes.extend(note);
    let surfaces = surfaces::choose(&summary, options.mapping);
    keep.extend(surfaces.iter().map(|s| s.column.clone()));
    let signals = multirate_signals(contents, &keep, &summary);
    Ok(Inspection { summary, surfaces, signals })
}

/// The summary of a multi-rate log's contents (every topic's timestamps kept).
fn multirate_summary(path: &str, format: &str, contents: &LogContents) -> LogSummary {
    let by_name: HashMap<&str, usize> =
        contents.topics.iter().enumerate().map(|(i, t)| (t.name.as_str(), i)).collect();
    let topics = contents
        .catalogue
        .iter()
        .map(|info| {
            let units = contents.units.get(base_topic(&info.name));
            let fields = info
                .fields
                .iter()
                .map(|f| FieldInfo { name: f.clone(), unit: units.and_then(|u| u.get(f)).cloned() })
                .collect();
            let time = by_name
                .get(info.name.as_str())
                .map_or_else(TimeStats::default, |&i| TimeStats::of(&contents.topics[i].t_s));
            TopicSummary { name: info.name.clone(), messages: info.messages, fields, time }
        })
        .collect();
    LogSummary {
        file: path.to_string(),
        format: format.to_string(),
        time_column: None,
        gap_multiple: GAP_MULTIPLE,
        topics,
        parameters: contents.parameters.clone(),
        notes: contents.notes(path),
    }
}

/// The values of the `keep` columns (`topic.field`) that the log has, each once.
fn multirate_signals(contents: LogContents, keep: &[String], summary: &LogSummary) -> Vec<Signal> {
    let mut out: Vec<Signal> = Vec::new();
    for c in keep {
        if out.iter().any(|s| &s.column == c) {
            continue;
        }
        let Some((tname, field)) = crate::align::split_column(c) else { continue };
        let Some(topic) = contents.topics.iter().find(|t| t.name == tname) else { continue };
        let Some((_, values)) = topic.fields.iter().find(|(f, _)| f == field) else { continue };
        let unit = summary
            .topics
            .iter()
            .find(|t| t.name == tname)
            .and_then(|t| t.fields.iter().find(|f| f.name == field))
            .and_then(|f| f.unit.clone());
        out.push(Signal {
            column: c.clone(),
            unit,
            t_s: topic.t_s.clone(),
            values: values.clone(),
        });
    }
    out
}
