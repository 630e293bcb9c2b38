//! One entry point for every log format: [`open_log`] picks the reader by the file's extension
//! or an explicit [`LogFormat`] and returns the same streaming [`FlightDataReader`] a CSV gets,
//! so every format passes the same row checks and yields the same [`RecordEvent`]s
//! (`crate::flight_data` documents them).
//!
//! | format | extension | column names | row numbers in events |
//! |---|---|---|---|
//! | CSV ([`LogFormat::Csv`]) | `.csv`, anything else | the header row | line in the file (header = 1) |
//! | whitespace text ([`LogFormat::Asc`]) | `.asc` (other text: `--format asc`) | the mapping's `[columns] names`, else `"1"`, `"2"`, … by position | line in the file |
//! | MATLAB v5 ([`LogFormat::Mat`]) | `.mat` | one matrix: as `.asc`; several variables: each vector is a column named by its variable | row of the record (1-based) |
//! | PX4 ULog ([`LogFormat::Ulog`]) | `.ulg` | `<topic>.<field>` after alignment ([`crate::table`]) | row of the aligned table |
//! | ArduPilot DataFlash ([`LogFormat::Dataflash`]) | `.bin` | `<message>.<field>` after alignment | row of the aligned table |
//! | MAVLink telemetry ([`LogFormat::Tlog`]) | `.tlog` | `<MESSAGE>.<field>` after alignment; times in Unix seconds ([`crate::tlog`]) | row of the aligned table |
//!
//! How the formats meet: a whitespace file is converted line by line to comma-separated text
//! (streaming, so `-` works for a live feed too), and a [`Table`] — what the `.mat` reader and
//! the multi-rate log readers produce — is rendered row by row as CSV text
//! ([`table_reader`]). Both get a header line of column names first; the reader's row numbers
//! discount it. Numbers in a table are written with Rust's shortest round-trip formatting
//! (`{}` for `f64`), which parses back to the identical `f64` (Rust `core::fmt` float
//! formatting: the shortest decimal that round-trips), so a table replays bit for bit as its
//! values: the `.mat` and `.asc` originals of a record give the same estimates as a CSV copy
//! holding the same numbers. Non-finite values are written `NaN`/`inf` and rejected by the row
//! checks like a non-finite CSV field.
//!
//! The multi-rate readers ([`crate::ulog`], [`crate::dataflash`], [`crate::tlog`]) produce topics; they are
//! aligned to one time base by the mapping's `[align]` ([`crate::multirate::log_table`]) into a
//! [`Table`] and handed to [`table_reader`] like a `.mat` record.

use crate::error::FlightDataError;
use crate::flight_data::FlightDataReader;
use crate::log_contents::{LogContents, TopicFilter};
use crate::mapping::{Mapping, Source};
use crate::reader_report::ReaderReport;
use crate::table::Table;
use std::fmt::Write as _;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::str::FromStr;

#[cfg(doc)]
use crate::flight_data::RecordEvent;

/// A log file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    /// Comma-separated values with one header row.
    Csv,
    /// Whitespace-separated numbers without a header row (FVSysID `.asc`, Jategaonkar 2015).
    Asc,
    /// MATLAB `.mat` level 5 (not v7.3/HDF5).
    Mat,
    /// PX4 ULog `.ulg`.
    Ulog,
    /// ArduPilot DataFlash `.bin`.
    Dataflash,
    /// MAVLink telemetry log `.tlog` (Mission Planner, MAVProxy, QGroundControl).
    Tlog,
}

impl LogFormat {
    /// Every format, in the order of the table in the module doc.
    pub const ALL: [LogFormat; 6] = [
        LogFormat::Csv,
        LogFormat::Asc,
        LogFormat::Mat,
        LogFormat::Ulog,
        LogFormat::Dataflash,
        LogFormat::Tlog,
    ];

    /// The name used by `--format`.
    pub fn name(self) -> &'static str {
        match self {
            LogFormat::Csv => "csv",
            LogFormat::Asc => "asc",
            LogFormat::Mat => "mat",
            LogFormat::Ulog => "ulog",
            LogFormat::Dataflash => "dataflash",
            LogFormat::Tlog => "tlog",
        }
    }

    /// The format a record is read in: `given`, else `path`'s extension
    /// ([`LogFormat::from_extension`]), else CSV.
    pub fn resolve(given: Option<LogFormat>, path: &str) -> LogFormat {
        given.or_else(|| LogFormat::from_extension(Path::new(path))).unwrap_or(LogFormat::Csv)
    }

    /// The format a file's extension names (case-insensitive): `.asc` whitespace
    /// text, `.mat`, `.ulg`, `.bin` DataFlash, `.tlog`; `None` for any other (read as CSV by
    /// [`open_log`]).
    pub fn from_extension(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "csv" => Some(LogFormat::Csv),
            "asc" => Some(LogFormat::Asc),
            "mat" => Some(LogFormat::Mat),
            "ulg" | "ulog" => Some(LogFormat::Ulog),
            "bin" => Some(LogFormat::Dataflash),
            "tlog" => Some(LogFormat::Tlog),
            _ => None,
        }
    }
}

impl std::fmt::Display for LogFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of [`LogFormat::from_str`]: the name given and the valid ones.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown log format `{0}` (valid: csv, asc, mat, ulog, dataflash)")]
pub struct UnknownFormat(pub String);

impl FromStr for LogFormat {
    type Err = UnknownFormat;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownFormat(s.to_string()))
    }
}

/// The reader every format gives: the CSV reader over a boxed byte source.
pub type LogReader = FlightDataReader<Box<dyn Read + Send>>;

/// Opens a log for replay through `mapping`: `format`, else the extension of `path`, else CSV.
/// `path` `-` is stdin (CSV or whitespace text; a `.mat` or binary log is read whole, from a
/// file only). What a multi-rate log's reading and alignment left out is discarded here; the
/// CLI uses [`open_log_with_notes`] and prints it.
///
/// # Errors
/// As [`open_log_with_notes`].
pub fn open_log(
    path: &str,
    format: Option<LogFormat>,
    mapping: &Mapping,
) -> Result<LogReader, FlightDataError> {
    open_log_with_notes(path, format, mapping).map(|(reader, _)| reader)
}

/// [`open_log`], and one line per thing the reading or alignment of a multi-rate log (ULog,
/// DataFlash, `.tlog`) left out ([`ReaderReport::notes`]). Empty for CSV, `.asc`, `.mat`.
///
/// # Errors
/// As [`open_log_with_report`].
pub fn open_log_with_notes(
    path: &str,
    format: Option<LogFormat>,
    mapping: &Mapping,
) -> Result<(LogReader, Vec<String>), FlightDataError> {
    open_log_with_report(path, format, mapping).map(|(r, report)| (r, report.notes()))
}

/// [`open_log`], and what the reading or alignment of a multi-rate log (ULog, DataFlash) left
/// out, counted per kind and topic ([`ReaderReport`]): samples whose timestamp broke their
/// topic's order, a truncated last message, skipped corrupt bytes, rows dropped by the
/// alignment. Empty for CSV, `.asc`, `.mat`. A multi-rate log is streamed and only the topics
/// and fields the mapping reads are kept ([`TopicFilter::for_mapping`]).
///
/// # Errors
/// [`FlightDataError::Io`] naming the file; [`FlightDataError::Format`] for a file that is
/// not of its format (or a binary log from stdin); the CSV reader's header errors;
/// [`FlightDataError::NoSuchColumn`] for a mapped column the record lacks; for ULog and
/// DataFlash the decoder's [`FlightDataError::LogDecode`] and the alignment's
/// [`FlightDataError::MissingTopic`] (listing what the log has; led by where a cut file ends
/// and what corrupt bytes were skipped when the topic is absent, else noting them) / [`FlightDataError::BadSpec`] / [`FlightDataError::Align`].
pub fn open_log_with_report(
    path: &str,
    format: Option<LogFormat>,
    mapping: &Mapping,
) -> Result<(LogReader, ReaderReport), FlightDataError> {
    let format = LogFormat::resolve(format, path);
    let io = |source| FlightDataError::Io { file: path.to_string(), source };
    let open = || -> Result<Box<dyn BufRead + Send>, FlightDataError> {
        if path == "-" {
            Ok(Box::new(BufReader::new(std::io::stdin())))
        } else {
            Ok(Box::new(BufReader::new(std::fs::File::open(path).map_err(io)?)))
        }
    };
    let multirate = matches!(format, LogFormat::Ulog | LogFormat::Dataflash | LogFormat::Tlog);
    if !multirate || path == "-" {
        // A binary log from stdin is refused there: it is read from a file.
        let reader = stream_reader(open()?, path, format, mapping)?;
        return Ok((reader, ReaderReport::empty(path, format.name())));
    }
    let filter = TopicFilter::for_mapping(mapping);
    let contents = match format {
        LogFormat::Ulog => crate::ulog::read_ulog_filtered(Path::new(path), &filter)?,
        LogFormat::Tlog => crate::tlog::read_tlog_filtered(Path::new(path), &filter)?.0,
        _ => crate::dataflash::read_dataflash_filtered(Path::new(path), &filter)?,
    };
    let mut report = ReaderReport::from_contents(path, format.name(), &contents);
    let losses = Losses::of(&contents);
    let cut = |e| with_cut_note(e, &losses);
    check_catalogue(&contents, mapping, path)?;
    let aligned = crate::multirate::log_table(&contents.topics, mapping, path).map_err(cut)?;
    drop(contents);
    report.add_alignment(&aligned.dropped_by, aligned.rows_considered);
    Ok((table_reader(aligned.table, mapping)?, report))
}

/// The reader of the text or `.mat` bytes `source` (a file, stdin, a face's wrapper around
/// either), named `file` in messages, in `format`: the one place a byte stream meets its
/// format's reader, for [`open_log_with_report`] and [`crate::Record::open`].
///
/// # Errors
/// The format's reader's errors; [`FlightDataError::Format`] for ULog, DataFlash and `.tlog`,
/// which are read from a file (their readers seek and decode whole files).
pub(crate) fn stream_reader(
    source: Box<dyn BufRead + Send>,
    file: &str,
    format: LogFormat,
    mapping: &Mapping,
) -> Result<LogReader, FlightDataError> {
    match format {
        LogFormat::Csv => {
            FlightDataReader::new(Box::new(source) as Box<dyn Read + Send>, file, mapping)
        }
        LogFormat::Asc => asc_reader(source, file, mapping),
        LogFormat::Mat => {
            table_reader(read_mat(source, file, mapping.column_names.as_deref())?, mapping)
        }
        LogFormat::Ulog | LogFormat::Dataflash | LogFormat::Tlog => Err(FlightDataError::Format {
            file: file.to_string(),
            message: format!(
                "a {} log is read from a file, not from {}",
                format.name(),
                if file == "-" { "stdin" } else { "a stream" }
            ),
        }),
    }
}

/// What a log's decoding could not read: where a cut file ends and the corrupt stretches
/// skipped (`(count, bytes, first offset)`).
#[derive(Debug, Clone, Copy)]
struct Losses {
    truncated_at: Option<u64>,
    skipped: Option<(u64, u64, u64)>,
}

impl Losses {
    fn of(contents: &LogContents) -> Self {
        let (n, bytes) = contents.skipped_total;
        let skipped = contents.skipped.first().filter(|_| n > 0).map(|&(at, _)| (n, bytes, at));
        Self { truncated_at: contents.truncated_at, skipped }
    }

    /// The losses as a clause (`None` for a log read whole).
    fn clause(&self) -> Option<String> {
        let cut =
            self.truncated_at.map(|at| format!("the file ends inside a message at byte {at}"));
        let skipped = self.skipped.map(|(n, bytes, at)| match n {
            1 => format!("a corrupt stretch of {bytes} bytes at byte {at} was skipped"),
            _ => format!(
                "{n} corrupt stretches of {bytes} bytes in all (the first at byte {at}) were \
                 skipped"
            ),
        });
        match (cut, skipped) {
            (None, None) => None,
            (Some(c), None) | (None, Some(c)) => Some(c),
            (Some(c), Some(k)) => Some(format!("{c}, and {k}")),
        }
    }

    /// Where in the file a topic was looked for.
    fn searched(&self) -> String {
        match (self.truncated_at, self.skipped) {
            (Some(at), None) => format!("before byte {at}"),
            (None, Some(_)) => "outside the skipped bytes".into(),
            _ => "in what could be read".into(),
        }
    }
}

/// Why topic `tname` is missing from a log with `have` (its topics): led by what the reading
/// lost, which may be where the topic was.
fn no_topic(tname: &str, have: &[&str], losses: &Losses) -> String {
    let have = if have.is_empty() { "none".to_string() } else { have.join(", ") };
    match losses.clause() {
        None => format!("the log has no topic/message `{tname}` (it has: {have})"),
        Some(lost) => format!(
            "{lost}: no topic/message `{tname}` was found {} (it has: {have})",
            losses.searched()
        ),
    }
}

/// Every `<topic>.<field>` column the mapping reads, and the `[align] clock` topic, must be in
/// the log's catalogue (every topic with a message, kept or not); the error lists what the
/// log has, as [`crate::align::select`] does for the kept topics, led by what a cut or
/// corrupt file lost when the topic is absent.
fn check_catalogue(
    contents: &LogContents,
    mapping: &Mapping,
    file: &str,
) -> Result<(), FlightDataError> {
    let losses = Losses::of(contents);
    let missing = |column: &str, needed_by: &str, reason: String| FlightDataError::MissingTopic {
        file: file.to_string(),
        column: column.to_string(),
        needed_by: needed_by.to_string(),
        reason,
    };
    let mut have: Vec<&str> = contents.catalogue.iter().map(|t| t.name.as_str()).collect();
    have.sort_unstable();
    for (column, needed_by) in crate::multirate::needed_columns(mapping) {
        let Some((tname, field)) = crate::align::split_column(&column) else { continue };
        let Some(topic) = contents.catalogue.iter().find(|t| t.name == tname) else {
            return Err(missing(&column, &needed_by, no_topic(&tname, &have, &losses)));
        };
        if !topic.fields.iter().any(|f| f == field) {
            let reason = format!(
                "topic `{tname}` has no field `{field}` (it has: {})",
                topic.fields.join(", ")
            );
            return Err(with_cut_note(missing(&column, &needed_by, reason), &losses));
        }
    }
    if let Some(crate::mapping::Clock::Topic(name)) = mapping.align.as_ref().map(|a| &a.clock)
        && !contents.catalogue.iter().any(|t| &t.name == name)
    {
        return Err(missing(name, "[align] clock", no_topic(name, &have, &losses)));
    }
    Ok(())
}

/// A missing topic or an alignment failure in a file cut short or with corrupt stretches
/// skipped may only mean the topic was in what was lost: say what was.
fn with_cut_note(e: FlightDataError, losses: &Losses) -> FlightDataError {
    let Some(lost) = losses.clause() else { return e };
    let note = format!("; note: {lost} (what the file holds there is missing)");
    match e {
        FlightDataError::MissingTopic { file, column, needed_by, reason } => {
            FlightDataError::MissingTopic { file, column, needed_by, reason: reason + &note }
        }
        FlightDataError::Align { file, reason } => {
            FlightDataError::Align { file, reason: reason + &note }
        }
        other => other,
    }
}

/// A reader over whitespace-separated text without a header row (FVSysID `.asc`): columns
/// are named by the mapping's `[columns] names`, else `"1"`, `"2"`, … by position (counted
/// on the first non-blank line). Each line is one row; its event carries its line number in
/// the file. Streaming: `source` is read line by line.
///
/// # Errors
/// [`FlightDataError::Io`], [`FlightDataError::Format`] (no data line and no names, or a
/// first data line with a different number of fields than `[columns] names` has), and
/// [`FlightDataError::NoSuchColumn`].
pub fn asc_reader<R: BufRead + Send + 'static>(
    source: R,
    file: &str,
    mapping: &Mapping,
) -> Result<LogReader, FlightDataError> {
    // Bare `\r` line ends (old Mac files) would make the whole file one line.
    let source = BufReader::new(crate::line_ends::BareCrAsLf::new(source));
    let mut text = AscAsCsv { source, lines: Vec::new(), out: Vec::new(), pos: 0, eof: false };
    // Read up to the first data line to count its fields; those lines are replayed after
    // the header, so the line numbering is unchanged.
    let mut first: Option<(usize, usize)> = None; // (line, fields)
    while first.is_none() {
        let mut raw = Vec::new();
        let n = text
            .source
            .read_until(b'\n', &mut raw)
            .map_err(|source| FlightDataError::Io { file: file.to_string(), source })?;
        if n == 0 {
            text.eof = true;
            break;
        }
        let fields = String::from_utf8_lossy(&raw).split_whitespace().count();
        if fields > 0 {
            first = Some((text.lines.len() + 1, fields));
        }
        text.lines.push(raw);
    }
    // A first line that is not numbers is most likely a text header (FVSysID's
    // `*_withHeader.asc`): say so, since every column would be off.
    let text_hint = |line: usize| {
        let raw = String::from_utf8_lossy(&text.lines[line - 1]);
        match raw.split_whitespace().find(|t| t.parse::<f64>().is_err()) {
            Some(t) => format!(
                " (its `{t}` is text: a header line? .asc files are read without one; remove it or replay a CSV copy)"
            ),
            None => String::new(),
        }
    };
    let names = match (&mapping.column_names, first) {
        (Some(names), Some((line, fields))) if fields != names.len() => {
            return Err(FlightDataError::Format {
                file: file.to_string(),
                message: format!(
                    "line {line}: {fields} fields, but the mapping {} names {} columns in `[columns] names`{}",
                    mapping.file,
                    names.len(),
                    text_hint(line)
                ),
            });
        }
        (Some(names), _) => names.clone(),
        (None, Some((_, fields))) => (1..=fields).map(|i| i.to_string()).collect(),
        (None, None) => {
            return Err(FlightDataError::Format {
                file: file.to_string(),
                message: "no data line (whitespace-separated numbers) in the file".into(),
            });
        }
    };
    check_columns(file, &names, mapping)?;
    text.out = csv_line(names.iter().map(String::as_str), true).into_bytes();
    let lines = std::mem::take(&mut text.lines);
    for raw in lines {
        text.out.extend_from_slice(convert_line(&raw).as_bytes());
    }
    Ok(FlightDataReader::new(Box::new(text) as Box<dyn Read + Send>, file, mapping)?
        .with_synthetic_lines(1))
}

/// A reader over a [`Table`] (a `.mat` record, a multi-rate log after alignment): the rows in
/// order, each an event carrying its 1-based row number. The values pass the CSV reader's
/// checks unchanged (bit for bit, module doc).
///
/// # Errors
/// [`FlightDataError::Format`] for a table that breaks its invariant (a name count different
/// from the column count, columns of different lengths, repeated names),
/// [`FlightDataError::NoSuchColumn`] for a mapped column it lacks.
pub fn table_reader(table: Table, mapping: &Mapping) -> Result<LogReader, FlightDataError> {
    let file = table.file.clone();
    let bad = |message: String| FlightDataError::Format { file: file.clone(), message };
    if table.names.len() != table.columns.len() {
        return Err(bad(format!(
            "{} column names for {} columns",
            table.names.len(),
            table.columns.len()
        )));
    }
    let rows = table.columns.first().map_or(0, Vec::len);
    if let Some((name, c)) = table.names.iter().zip(&table.columns).find(|(_, c)| c.len() != rows) {
        return Err(bad(format!("column `{name}` has {} rows, the first has {rows}", c.len())));
    }
    for (i, n) in table.names.iter().enumerate() {
        if let Some(j) = table.names[..i].iter().position(|m| m == n) {
            return Err(bad(format!(
                "column `{n}` appears twice (columns {} and {})",
                j + 1,
                i + 1
            )));
        }
    }
    check_columns(&file, &table.names, mapping)?;
    let header = csv_line(table.names.iter().map(String::as_str), true).into_bytes();
    let source = TableAsCsv { table, row: 0, out: header, pos: 0 };
    Ok(FlightDataReader::new(Box::new(source) as Box<dyn Read + Send>, &file, mapping)?
        .with_synthetic_lines(1))
}

/// Every column the mapping reads must be one of `names` (a file without a CSV header has
/// no header line to name in the error).
fn check_columns(file: &str, names: &[String], mapping: &Mapping) -> Result<(), FlightDataError> {
    let wanted = std::iter::once(("time", &mapping.time))
        .chain(mapping.channels.iter().map(|(c, m)| (c.key(), m)));
    for (channel, m) in wanted {
        let Source::Columns(cols) = &m.source else { continue };
        for (column, _) in cols {
            if !names.contains(column) {
                let shown: Vec<&str> = names.iter().take(12).map(String::as_str).collect();
                let more = if names.len() > 12 { ", …" } else { "" };
                let origin = if mapping.column_names.is_some() {
                    format!("named by `[columns] names` in {}", mapping.file)
                } else {
                    "named by the file, or \"1\", \"2\", … by position when it has no names \
                     (give `[columns] names` in the mapping)"
                        .to_string()
                };
                return Err(FlightDataError::NoSuchColumn {
                    file: file.to_string(),
                    channel: channel.to_string(),
                    column: column.clone(),
                    available: format!(
                        "{} columns: {}{more}; {origin}",
                        names.len(),
                        shown.join(", ")
                    ),
                });
            }
        }
    }
    Ok(())
}

/// One CSV line from fields, quoting a field that holds a comma or a quote.
fn csv_line<'a>(fields: impl Iterator<Item = &'a str>, newline: bool) -> String {
    let mut line = String::new();
    for (i, f) in fields.enumerate() {
        if i > 0 {
            line.push(',');
        }
        if f.contains([',', '"']) {
            line.push('"');
            line.push_str(&f.replace('"', "\"\""));
            line.push('"');
        } else {
            line.push_str(f);
        }
    }
    if newline {
        line.push('\n');
    }
    line
}

/// A whitespace-separated line as a CSV line, keeping whether it ended in a newline (the
/// reader rejects a last line of a live feed that did not).
fn convert_line(raw: &[u8]) -> String {
    let text = String::from_utf8_lossy(raw);
    csv_line(text.split_whitespace(), raw.last() == Some(&b'\n'))
}

/// Whitespace text read as CSV text, one line at a time.
struct AscAsCsv<R> {
    source: R,
    /// Lines read ahead by [`asc_reader`] (only while opening).
    lines: Vec<Vec<u8>>,
    out: Vec<u8>,
    pos: usize,
    eof: bool,
}

impl<R: BufRead> Read for AscAsCsv<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        while self.pos == self.out.len() {
            if self.eof || buf.is_empty() {
                return Ok(0);
            }
            let mut raw = Vec::new();
            if self.source.read_until(b'\n', &mut raw)? == 0 {
                self.eof = true;
                return Ok(0);
            }
            self.out = convert_line(&raw).into_bytes();
            self.pos = 0;
        }
        let n = buf.len().min(self.out.len() - self.pos);
        buf[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// A [`Table`] read as CSV text, one row at a time.
struct TableAsCsv {
    table: Table,
    row: usize,
    out: Vec<u8>,
    pos: usize,
}

impl Read for TableAsCsv {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        while self.pos == self.out.len() {
            let rows = self.table.columns.first().map_or(0, Vec::len);
            if self.row >= rows || buf.is_empty() {
                return Ok(0);
            }
            let mut line = String::new();
            for (i, c) in self.table.columns.iter().enumerate() {
                if i > 0 {
                    line.push(',');
                }
                // Shortest round-trip decimal: parses back to the same f64.
                let _ = write!(line, "{}", c[self.row]);
            }
            line.push('\n');
            self.out = line.into_bytes();
            self.pos = 0;
            self.row += 1;
        }
        let n = buf.len().min(self.out.len() - self.pos);
        buf[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// Reads a MATLAB level-5 `.mat` file (the crate's own level-5 reader, module `mat5`) into a [`Table`].
///
/// - One numeric 2-D variable (the FVSysID layout, e.g. `fAttasElv1`, 626 × 45): its
///   columns are the table's, named by `column_names` (the mapping's `[columns] names`) or
///   `"1"`, `"2"`, … by position.
/// - Several variables: every real vector (n × 1 or 1 × n) of the longest length is a
///   column named by its variable; 1 × 1 scalars are skipped.
///
/// Integer and single-precision data are converted to `f64` exactly.
///
/// # Errors
/// [`FlightDataError::Io`], and [`FlightDataError::Format`] naming the file (and the
/// variable) for a v7.3 (HDF5) or unparsable file, no numeric variable, complex data, a
/// matrix among several variables, vectors of different lengths, or a `column_names` list
/// whose length differs from the matrix's column count.
pub fn read_mat<R: Read>(
    mut source: R,
    file: &str,
    column_names: Option<&[String]>,
) -> Result<Table, FlightDataError> {
    let bad = |message: String| FlightDataError::Format { file: file.to_string(), message };
    let mut bytes = Vec::new();
    source
        .read_to_end(&mut bytes)
        .map_err(|source| FlightDataError::Io { file: file.to_string(), source })?;
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(116)]);
    if head.starts_with("MATLAB 7.3") {
        return Err(bad("a MATLAB v7.3 (HDF5) file: only level-5 .mat files are read \
                        (save it with `save(..., '-v7')`)"
            .into()));
    }
    if !head.starts_with("MATLAB 5.0") {
        return Err(bad("not a MATLAB level-5 .mat file (its header does not start with \
                        `MATLAB 5.0 MAT-file`)"
            .into()));
    }
    check_mat_elements(&bytes).map_err(bad)?;
    let arrays = crate::mat5::read_arrays(&bytes).map_err(bad)?;
    drop(bytes);
    for a in &arrays {
        if a.dims.len() != 2 {
            return Err(bad(format!(
                "variable `{}` has {} dimensions; only 2-D variables are read",
                a.name,
                a.dims.len()
            )));
        }
    }
    let file_s = file.to_string();
    let mut arrays = arrays;
    let n_vars = arrays.len();
    match arrays.as_mut_slice() {
        [] => Err(bad("no numeric variable in the file".into())),
        [a] => {
            let data = &a.values;
            let (rows, cols) = (a.dims[0], a.dims[1]);
            let names: Vec<String> = match column_names {
                Some(n) if n.len() != cols => {
                    return Err(bad(format!(
                        "variable `{}` has {cols} columns, but `[columns] names` names {}",
                        a.name,
                        n.len()
                    )));
                }
                Some(n) => n.to_vec(),
                None => (1..=cols).map(|i| i.to_string()).collect(),
            };
            // Column-major: column k is data[k·rows .. (k+1)·rows].
            let columns = data.chunks(rows.max(1)).map(<[f64]>::to_vec).collect();
            Ok(Table { file: file_s, names, columns })
        }
        many => {
            let len = many
                .iter()
                .filter(|a| a.dims.contains(&1))
                .map(|a| a.values.len())
                .max()
                .unwrap_or(0);
            let mut names = Vec::new();
            let mut columns = Vec::new();
            for a in many.iter_mut() {
                let (s, data) = (&a.dims, &a.values);
                if data.len() == 1 && len > 1 {
                    continue;
                }
                if !s.contains(&1) {
                    return Err(bad(format!(
                        "variable `{}` is a {}×{} matrix among {} variables: save one matrix \
                         (columns = channels) or one vector per channel",
                        a.name, s[0], s[1], n_vars
                    )));
                }
                if data.len() != len {
                    return Err(bad(format!(
                        "variable `{}` has {} values, others have {len}",
                        a.name,
                        data.len()
                    )));
                }
                names.push(a.name.clone());
                columns.push(std::mem::take(&mut a.values));
            }
            Ok(Table { file: file_s, names, columns })
        }
    }
}

/// Walks the top-level data elements of a level-5 file (MathWorks, "MAT-File Format": a
/// 128-byte header whose bytes 126–127 are `IM` little-endian or `MI` big-endian, then
/// elements of an 8-byte tag — type, byte count — and their data, padded to 8 bytes except
/// compressed ones) and checks they end exactly at the end of the file: the parser would
/// otherwise drop a truncated last variable without a word.
fn check_mat_elements(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() < 128 {
        return Err(format!("truncated: {} bytes, shorter than the 128-byte header", bytes.len()));
    }
    let little = match &bytes[126..128] {
        b"IM" => true,
        b"MI" => false,
        other => return Err(format!("bad endian indicator {other:?} at byte 126")),
    };
    let word = |at: usize| {
        let w: [u8; 4] = bytes[at..at + 4].try_into().unwrap_or([0; 4]);
        if little { u32::from_le_bytes(w) } else { u32::from_be_bytes(w) }
    };
    let mut at = 128usize;
    while at < bytes.len() {
        if bytes.len() - at < 8 {
            return Err(format!("truncated: {} stray bytes at byte {at}", bytes.len() - at));
        }
        let (ty, n) = (word(at), word(at + 4) as usize);
        // miCOMPRESSED (15) is not padded; every other element is padded to 8 bytes.
        let len = if ty == 15 { n } else { n.div_ceil(8) * 8 };
        let end = at.saturating_add(8).saturating_add(len);
        if end > bytes.len() {
            return Err(format!(
                "truncated: the variable at byte {at} declares {n} bytes, the file ends {} bytes after its tag",
                bytes.len() - at - 8
            ));
        }
        at = end;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RowProblem;
    use crate::flight_data::RecordEvent;

    const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nmass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\n";

    fn mapping(extra: &str) -> Mapping {
        Mapping::from_toml_str(&format!("{MAP}{extra}"), "m.toml").unwrap()
    }

    fn events(r: LogReader) -> Vec<RecordEvent> {
        r.map(Result::unwrap).collect()
    }

    /// The CSV reader's events on `csv` with every row number moved by `shift` lines.
    fn csv_events(csv: &str, m: &Mapping, shift: i64) -> Vec<RecordEvent> {
        let r = FlightDataReader::new(csv.as_bytes(), "d.csv", m).unwrap();
        r.map(|e| match e.unwrap() {
            RecordEvent::Sample { row, sample } => {
                RecordEvent::Sample { row: (row as i64 + shift) as u64, sample }
            }
            RecordEvent::Rejected { row, problem } => {
                RecordEvent::Rejected { row: (row as i64 + shift) as u64, problem }
            }
            RecordEvent::Gap { row, dt_s, nominal_dt_s } => {
                RecordEvent::Gap { row: (row as i64 + shift) as u64, dt_s, nominal_dt_s }
            }
        })
        .collect()
    }

    /// Deterministic pseudo-random bit patterns (64-bit LCG, Knuth MMIX constants).
    fn lcg_bits(n: usize) -> Vec<u64> {
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        (0..n)
            .map(|_| {
                x = x
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                x
            })
            .collect()
    }

    #[test]
    fn analytic_shortest_float_text_parses_back_to_the_same_bits() {
        let mut values: Vec<f64> = lcg_bits(20_000).into_iter().map(f64::from_bits).collect();
        values.extend([0.0, -0.0, f64::MIN_POSITIVE, 5e-324, f64::MAX, -f64::MAX, 0.1, 1.0 / 3.0]);
        for v in values.into_iter().filter(|v| v.is_finite()) {
            let back: f64 = format!("{v}").parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v}");
        }
    }

    #[test]
    fn val_a_table_gives_the_events_of_the_same_numbers_as_csv() {
        // Rows: good, good, NaN alpha, repeated time, good after a gap, V ≤ 0.
        let t = [0.0, 0.1, 0.2, 0.1, 0.7, 0.8];
        let v = [100.0, 100.5, 101.0, 101.0, 1.0 / 3.0 * 300.0, -1.0];
        let a = [0.05, 0.051_234_567_890_123_4, f64::NAN, 0.05, -0.0, 0.05];
        let table = Table {
            file: "rec.mat".into(),
            names: vec!["t".into(), "V".into(), "a".into()],
            columns: vec![t.to_vec(), v.to_vec(), a.to_vec()],
        };
        let m = mapping("");
        let got = events(table_reader(table, &m).unwrap());
        let mut csv = String::from("t,V,a\n");
        for k in 0..t.len() {
            csv.push_str(&format!("{},{},{}\n", t[k], v[k], a[k]));
        }
        // Table rows are 1-based; the CSV's first data row is line 2.
        assert_eq!(got, csv_events(&csv, &m, -1));
        assert!(
            matches!(&got[2], RecordEvent::Rejected { row: 3, problem: RowProblem::NonFinite { column, .. } } if column == "a")
        );
        assert!(matches!(
            &got[3],
            RecordEvent::Rejected { row: 4, problem: RowProblem::RepeatedTime { .. } }
        ));
        assert!(matches!(got[4], RecordEvent::Gap { row: 5, .. }));
        let RecordEvent::Sample { row: 2, sample } = &got[1] else { panic!("{:?}", got[1]) };
        assert_eq!(sample.alpha_rad.to_bits(), a[1].to_bits());
        let RecordEvent::Sample { row: 5, sample } = &got[5] else { panic!("{:?}", got[5]) };
        // −0 + the mapping's offset 0 = +0, in either path.
        assert_eq!(sample.alpha_rad.to_bits(), 0.0f64.to_bits());
        assert_eq!(sample.vt_mps, 100.0);
        assert!(matches!(
            &got[6],
            RecordEvent::Rejected { row: 6, problem: RowProblem::Domain { .. } }
        ));
        assert_eq!(got.len(), 7);
    }

    #[test]
    fn errors_table_breaking_its_invariant_or_lacking_a_column() {
        let m = mapping("");
        let table = |names: &[&str], cols: Vec<Vec<f64>>| Table {
            file: "x.ulg".into(),
            names: names.iter().map(|s| s.to_string()).collect(),
            columns: cols,
        };
        let e = |t| table_reader(t, &m).err().unwrap().to_string();
        let msg = e(table(&["t", "V", "a"], vec![vec![0.0], vec![1.0, 2.0], vec![0.0]]));
        assert!(msg.starts_with("x.ulg: column `V` has 2 rows, the first has 1"), "{msg}");
        let msg = e(table(&["t", "V", "V"], vec![vec![0.0]; 3]));
        assert!(msg.contains("`V` appears twice (columns 2 and 3)"), "{msg}");
        let msg = e(table(&["t", "V"], vec![vec![0.0]; 3]));
        assert!(msg.contains("2 column names for 3 columns"), "{msg}");
        let msg = e(table(&["t", "V", "alpha"], vec![vec![0.0]; 3]));
        assert!(
            msg.starts_with("x.ulg: column `a` for channel `alpha` is not in the record (3 columns: t, V, alpha;"),
            "{msg}"
        );
    }

    #[test]
    fn val_asc_rows_are_file_lines_with_the_csv_checks() {
        let m = mapping("[columns]\nnames = [\"t\", \"V\", \"a\"]\n");
        // Tabs and runs of spaces, a CRLF line, a non-number, a short line, blank lines.
        let asc =
            "  0.0   100.0  0.05\n0.1\t100.5\t0.051\r\n0.2 101 x1\n0.3 101\n\n \n 0.4 102 0.06";
        let got = events(asc_reader(std::io::Cursor::new(asc), "r.asc", &m).unwrap());
        let csv = asc
            .lines()
            .map(|l| l.split_whitespace().collect::<Vec<_>>().join(","))
            .collect::<Vec<_>>()
            .join("\n");
        assert_eq!(got, csv_events(&format!("t,V,a\n{csv}"), &m, -1));
        assert!(matches!(&got[0], RecordEvent::Sample { row: 1, .. }));
        assert!(
            matches!(&got[2], RecordEvent::Rejected { row: 3, problem: RowProblem::NotANumber { column, text } } if column == "a" && text == "x1")
        );
        assert!(matches!(
            &got[3],
            RecordEvent::Rejected {
                row: 4,
                problem: RowProblem::FieldCount { expected: 3, found: 2 }
            }
        ));
        // After two blank lines, on line 7, without a final newline (kept: a file, not `-`).
        assert!(matches!(got.last(), Some(RecordEvent::Sample { row: 7, .. })), "{got:?}");
    }

    /// Bare `\r` line ends (old Mac files): each `\r` ends a line, as `\n` does.
    #[test]
    fn val_asc_with_bare_cr_line_ends_reads_every_line() {
        let m = mapping("[columns]\nnames = [\"t\", \"V\", \"a\"]\n");
        let asc = "0.0 100.0 0.05\r0.1 100.5 0.051\r\n0.2 101 0.05\r0.3 101 0.06\r";
        let got = events(asc_reader(std::io::Cursor::new(asc), "r.asc", &m).unwrap());
        let rows: Vec<u64> = got
            .iter()
            .map(|e| match e {
                RecordEvent::Sample { row, .. } | RecordEvent::Rejected { row, .. } => *row,
                RecordEvent::Gap { row, .. } => *row,
            })
            .collect();
        assert_eq!(rows, [1, 2, 3, 4], "{got:?}");
        let RecordEvent::Sample { sample, .. } = &got[3] else { panic!("{:?}", got[3]) };
        assert_eq!((sample.t_s, sample.vt_mps, sample.alpha_rad), (0.3, 101.0, 0.06));
    }

    #[test]
    fn val_asc_columns_by_position_without_names() {
        let text =
            MAP.replace("\"t\"", "\"1\"").replace("\"V\"", "\"3\"").replace("\"a\"", "\"2\"");
        let m = Mapping::from_toml_str(&text, "m.toml").unwrap();
        let asc = "0.0 0.05 100.0\n0.1 0.06 101.0\n";
        let got = events(asc_reader(std::io::Cursor::new(asc), "r.asc", &m).unwrap());
        let RecordEvent::Sample { row: 2, sample } = &got[1] else { panic!("{got:?}") };
        assert_eq!((sample.t_s, sample.alpha_rad, sample.vt_mps), (0.1, 0.06, 101.0));
    }

    #[test]
    fn errors_asc_names_count_and_missing_columns() {
        let m = mapping("[columns]\nnames = [\"t\", \"V\", \"a\", \"q\"]\n");
        let e = asc_reader(std::io::Cursor::new("\n0 1 2\n"), "r.asc", &m).err().unwrap();
        assert_eq!(
            e.to_string(),
            "r.asc: line 2: 3 fields, but the mapping m.toml names 4 columns in `[columns] names`"
        );
        let e = asc_reader(std::io::Cursor::new("0 1\n"), "r.asc", &mapping("")).err().unwrap();
        let e = e.to_string();
        assert!(
            e.starts_with(
                "r.asc: column `t` for channel `time` is not in the record (2 columns: 1, 2;"
            ),
            "{e}"
        );
        let e = asc_reader(std::io::Cursor::new("\n \n"), "r.asc", &mapping("")).err().unwrap();
        assert!(e.to_string().contains("no data line"), "{e}");
    }

    #[test]
    fn formats_by_extension_and_name_and_unsupported_ones_say_so() {
        use LogFormat as F;
        for (p, f) in [("a.CSV", Some(F::Csv)), ("b.asc", Some(F::Asc)), ("c.mat", Some(F::Mat))] {
            assert_eq!(F::from_extension(Path::new(p)), f, "{p}");
        }
        assert_eq!(F::from_extension(Path::new("log.ulg")), Some(F::Ulog));
        assert_eq!(F::from_extension(Path::new("00000012.BIN")), Some(F::Dataflash));
        assert_eq!(F::from_extension(Path::new("data")), None);
        // A .txt or .dat may be a CSV: only `--format asc` reads it as whitespace text.
        assert_eq!(F::from_extension(Path::new("x.txt")), None);
        for f in F::ALL {
            assert_eq!(f.name().parse::<F>(), Ok(f));
        }
        assert!("xls".parse::<F>().unwrap_err().to_string().contains("csv, asc, mat"));
        // Binary logs are read by their own decoders: a missing file is named, stdin refused.
        let e = open_log("no-such-flight.ulg", None, &mapping("")).err().unwrap().to_string();
        assert!(e.starts_with("no-such-flight.ulg"), "{e}");
        let e = open_log("-", Some(F::Dataflash), &mapping("")).err().unwrap().to_string();
        assert!(e.contains("a dataflash log is read from a file, not from stdin"), "{e}");
    }

    /// A minimal uncompressed MATLAB level-5 file (MathWorks, "MAT-File Format", ch. 1:
    /// 128-byte header, then one miMATRIX element per variable: array flags, dimensions,
    /// name, real part as miDOUBLE).
    fn mat_v5(vars: &[(&str, usize, usize, &[f64])]) -> Vec<u8> {
        let mut out = format!("{:<116}", "MATLAB 5.0 MAT-file, written by a test").into_bytes();
        out.extend([0u8; 8]);
        out.extend(0x0100u16.to_le_bytes());
        out.extend(*b"IM");
        let tag = |v: &mut Vec<u8>, ty: u32, n: usize| {
            v.extend(ty.to_le_bytes());
            v.extend(u32::try_from(n).unwrap().to_le_bytes());
        };
        let pad = |v: &mut Vec<u8>| v.resize(v.len().div_ceil(8) * 8, 0);
        for (name, rows, cols, data) in vars {
            let mut m = Vec::new();
            tag(&mut m, 6, 8); // miUINT32 array flags: class mxDOUBLE_CLASS = 6
            m.extend(6u32.to_le_bytes());
            m.extend(0u32.to_le_bytes());
            tag(&mut m, 5, 8); // miINT32 dimensions
            m.extend(i32::try_from(*rows).unwrap().to_le_bytes());
            m.extend(i32::try_from(*cols).unwrap().to_le_bytes());
            tag(&mut m, 1, name.len()); // miINT8 name
            m.extend(name.as_bytes());
            pad(&mut m);
            tag(&mut m, 9, 8 * data.len()); // miDOUBLE real part, column-major
            for x in *data {
                m.extend(x.to_le_bytes());
            }
            tag(&mut out, 14, m.len());
            out.extend(m);
        }
        out
    }

    #[test]
    fn val_mat_matrix_columns_by_position_or_names_and_vectors_by_variable() {
        // 3 × 2 matrix [[0, 10], [0.1, 20], [0.2, 30]], column-major.
        let data = [0.0, 0.1, 0.2, 10.0, 20.0, 30.0];
        let bytes = mat_v5(&[("rec", 3, 2, &data)]);
        let t = read_mat(bytes.as_slice(), "r.mat", None).unwrap();
        assert_eq!(t.names, ["1", "2"]);
        assert_eq!(t.columns, vec![vec![0.0, 0.1, 0.2], vec![10.0, 20.0, 30.0]]);
        let names = ["time".to_string(), "V".to_string()];
        let t = read_mat(bytes.as_slice(), "r.mat", Some(&names)).unwrap();
        assert_eq!(t.names, names);
        let e = read_mat(bytes.as_slice(), "r.mat", Some(&names[..1])).unwrap_err().to_string();
        assert!(e.contains("variable `rec` has 2 columns, but `[columns] names` names 1"), "{e}");
        // Several variables: vectors by name (row or column vectors), scalars skipped.
        let bytes = mat_v5(&[
            ("t", 3, 1, &[0.0, 0.1, 0.2]),
            ("dt", 1, 1, &[0.1]),
            ("V", 1, 3, &[100.0, 101.0, 102.0]),
        ]);
        let t = read_mat(bytes.as_slice(), "r.mat", None).unwrap();
        assert_eq!(t.names, ["t", "V"]);
        assert_eq!(t.columns[1], [100.0, 101.0, 102.0]);
        let bytes = mat_v5(&[("t", 3, 1, &[0.0, 0.1, 0.2]), ("V", 2, 1, &[1.0, 2.0])]);
        let e = read_mat(bytes.as_slice(), "r.mat", None).unwrap_err().to_string();
        assert!(e.contains("variable `V` has 2 values, others have 3"), "{e}");
        let bytes = mat_v5(&[("t", 3, 1, &[0.0, 0.1, 0.2]), ("M", 3, 2, &data)]);
        let e = read_mat(bytes.as_slice(), "r.mat", None).unwrap_err().to_string();
        assert!(e.contains("variable `M` is a 3×2 matrix among 2 variables"), "{e}");
    }

    #[test]
    fn errors_mat_not_level_5() {
        let mut v73 = format!("{:<116}", "MATLAB 7.3 MAT-file, Platform: GLNXA64").into_bytes();
        v73.extend([0u8; 12]);
        let e = read_mat(v73.as_slice(), "r.mat", None).unwrap_err().to_string();
        assert!(e.starts_with("r.mat: a MATLAB v7.3 (HDF5) file"), "{e}");
        let e = read_mat(&b"time,V\n0,1\n"[..], "r.mat", None).unwrap_err().to_string();
        assert!(e.contains("not a MATLAB level-5 .mat file"), "{e}");
        let mut cut = mat_v5(&[("rec", 3, 2, &[0.0; 6])]);
        cut.truncate(cut.len() - 5);
        let e = read_mat(cut.as_slice(), "r.mat", None).unwrap_err().to_string();
        assert!(
            e.starts_with("r.mat: truncated: the variable at byte 128 declares 104 bytes"),
            "{e}"
        );
    }
}
