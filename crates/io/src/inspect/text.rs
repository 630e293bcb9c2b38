//! Tables: CSV and `.asc` streamed row by row, `.mat` read whole (module doc of
//! [`crate::inspect`]).

use super::{
    FieldInfo, GAP_MULTIPLE, InspectOptions, Inspection, LogSummary, Signal, TimeColumn, TimeStats,
    TopicSummary, surfaces,
};
use crate::FlightDataError;
use crate::log::LogFormat;
use crate::mapping::{Mapping, Source};
use crate::table::Table;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Most rows without a usable time listed one by one in the notes.
const BAD_TIME_LISTED: usize = 5;

/// What a table read keeps: the time column and the kept columns' values.
struct Collector {
    file: String,
    names: Vec<String>,
    time: TimeColumn,
    time_idx: usize,
    keep: Vec<usize>,
    t_s: Vec<f64>,
    values: Vec<Vec<f64>>,
    rows: usize,
    bad_time: Vec<String>,
    bad_time_count: usize,
}

impl Collector {
    /// A collector over columns `names` keeping `options.keep`, the surfaces and the time.
    fn new(file: &str, names: Vec<String>, options: &InspectOptions) -> Self {
        let (time_idx, time) = time_column(&names, options.mapping);
        let mut wanted: Vec<String> = options.keep.clone();
        match options.mapping {
            Some(m) => wanted.extend(surfaces::mapping_surfaces(m).into_iter().map(|s| s.column)),
            None => wanted.extend(surfaces::name_surfaces(&names).into_iter().map(|s| s.column)),
        }
        let mut keep: Vec<usize> = Vec::new();
        for w in &wanted {
            if let Some(i) = names.iter().position(|n| n == w)
                && !keep.contains(&i)
            {
                keep.push(i);
            }
        }
        let values = vec![Vec::new(); keep.len()];
        Self {
            file: file.to_string(),
            names,
            time,
            time_idx,
            keep,
            t_s: Vec::new(),
            values,
            rows: 0,
            bad_time: Vec::new(),
            bad_time_count: 0,
        }
    }

    /// One row (`line` in the file); `field(i)` is its `i`-th field. A row whose time is not
    /// a finite number is left out and noted.
    fn row<'r>(&mut self, line: u64, field: impl Fn(usize) -> Option<&'r str>) {
        self.rows += 1;
        let text = field(self.time_idx).unwrap_or("").trim();
        let t = text.parse::<f64>().ok().map(|t| t * self.time.to_s).filter(|t| t.is_finite());
        let Some(t) = t else {
            self.bad_time_count += 1;
            if self.bad_time.len() < BAD_TIME_LISTED {
                self.bad_time.push(format!(
                    "{}: row {line}: column `{}`: `{text}` is not a finite time: row left out",
                    self.file, self.time.name
                ));
            }
            return;
        };
        self.t_s.push(t);
        for (k, &i) in self.keep.iter().enumerate() {
            let v = field(i).and_then(|s| s.trim().parse::<f64>().ok()).unwrap_or(f64::NAN);
            self.values[k].push(v);
        }
    }

    /// The inspection of the rows collected; `format` names the file's format.
    fn finish(self, format: LogFormat, mapping: Option<&Mapping>) -> Inspection {
        let mut notes = self.bad_time;
        if self.bad_time_count > notes.len() {
            notes.push(format!(
                "{}: {} rows without a finite time in all (the first {} listed)",
                self.file,
                self.bad_time_count,
                notes.len()
            ));
        }
        let stem = Path::new(&self.file)
            .file_stem()
            .map_or_else(|| self.file.clone(), |s| s.to_string_lossy().into_owned());
        let fields: Vec<FieldInfo> = self
            .names
            .iter()
            .map(|n| FieldInfo { name: n.clone(), unit: header_unit(n) })
            .collect();
        let signals = self
            .keep
            .iter()
            .zip(self.values)
            .map(|(&i, values)| Signal {
                column: self.names[i].clone(),
                unit: fields[i].unit.clone(),
                t_s: self.t_s.clone(),
                values,
            })
            .collect();
        let topic = TopicSummary {
            name: stem,
            messages: self.rows,
            fields,
            time: TimeStats::of(&self.t_s),
        };
        let summary = LogSummary {
            file: self.file,
            format: format.name().to_string(),
            time_column: Some(self.time),
            gap_multiple: GAP_MULTIPLE,
            topics: vec![topic],
            parameters: BTreeMap::new(),
            notes,
        };
        let surfaces = surfaces::choose(&summary, mapping);
        Inspection { summary, surfaces, signals }
    }
}

/// The unit of a header `name [unit]` or `name (unit)`, if it has one.
fn header_unit(name: &str) -> Option<String> {
    let n = name.trim_end();
    let (open, close) = match n.chars().last()? {
        ']' => ('[', ']'),
        ')' => ('(', ')'),
        _ => return None,
    };
    let start = n.rfind(open)?;
    let unit = n[start + 1..n.len() - close.len_utf8()].trim();
    (!unit.is_empty() && start > 0).then(|| unit.to_string())
}

/// The time column among `names` and its factor to seconds (module doc of
/// [`crate::inspect`]).
fn time_column(names: &[String], mapping: Option<&Mapping>) -> (usize, TimeColumn) {
    if let Some(m) = mapping
        && let Source::Columns(cols) = &m.time.source
        && let Some((c, _)) = cols.first()
        && let Some(i) = names.iter().position(|n| n == c)
    {
        let to_s = m.time.to_si * m.time.scale;
        return (i, TimeColumn { name: c.clone(), source: "mapping".into(), to_s });
    }
    let said = names.iter().position(|n| time_factor(n).is_some());
    let (i, source) = match said {
        Some(i) => (i, "name"),
        None => (0, "first column"),
    };
    let name = names.get(i).cloned().unwrap_or_default();
    let to_s = time_factor(&name).unwrap_or(1.0);
    (i, TimeColumn { name, source: source.into(), to_s })
}

/// The factor to seconds of a column whose name says time (`time`, `t`, `time_s`, `timestamp`,
/// `time_us`, `TimeMS`, `time [ms]`, …), `None` for any other name.
fn time_factor(name: &str) -> Option<f64> {
    let unit = header_unit(name).map(|u| u.to_ascii_lowercase());
    let base = name.split(['[', '(']).next().unwrap_or(name).trim().to_ascii_lowercase();
    let (stem, suffix) = match base.rsplit_once('_') {
        Some((s, u)) if ["s", "ms", "us", "sec"].contains(&u) => {
            (s.to_string(), Some(u.to_string()))
        }
        _ => match base.strip_suffix("ms").or_else(|| base.strip_suffix("us")) {
            Some(s) if s == "time" => (s.to_string(), Some(base[s.len()..].to_string())),
            _ => (base.clone(), None),
        },
    };
    if !["time", "t", "timestamp", "sec", "seconds"].contains(&stem.as_str()) {
        return None;
    }
    match unit.as_deref().or(suffix.as_deref()) {
        Some("ms") => Some(1e-3),
        Some("us" | "µs") => Some(1e-6),
        _ => Some(1.0),
    }
}

/// A CSV, `.asc` or `.mat` table (module doc of [`crate::inspect`]).
///
/// # Errors
/// As [`super::inspect_log`].
pub(super) fn inspect_table(
    path: &str,
    format: LogFormat,
    options: &InspectOptions,
) -> Result<Inspection, FlightDataError> {
    let io = |source| FlightDataError::Io { file: path.to_string(), source };
    let source: Box<dyn BufRead> = if path == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        Box::new(BufReader::new(std::fs::File::open(path).map_err(io)?))
    };
    if format == LogFormat::Mat {
        // Binary: read as it is (a CR byte inside the compressed data is no line end).
        let names = options.mapping.and_then(|m| m.column_names.as_deref());
        let table = crate::log::read_mat(source, path, names)?;
        return Ok(inspect_mat(table, options));
    }
    let source = BufReader::new(crate::line_ends::BareCrAsLf::new(source));
    match format {
        LogFormat::Asc => inspect_asc(source, path, options),
        _ => inspect_csv(source, path, options),
    }
}

/// A CSV file with one header row, streamed.
fn inspect_csv<R: Read>(
    source: R,
    file: &str,
    options: &InspectOptions,
) -> Result<Inspection, FlightDataError> {
    let mut csv = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_reader(source);
    let csv_err = |row: u64, e: csv::Error| FlightDataError::Csv {
        file: file.to_string(),
        row,
        message: e.to_string(),
    };
    let headers = csv.byte_headers().map_err(|e| csv_err(1, e))?.clone();
    let names: Vec<String> =
        headers.iter().map(|h| String::from_utf8_lossy(h).trim().to_string()).collect();
    if names.iter().all(String::is_empty) {
        return Err(FlightDataError::NoData {
            file: file.to_string(),
            what: "it is empty: no header row and no data rows".into(),
        });
    }
    let mut c = Collector::new(file, names, options);
    let mut record = csv::ByteRecord::new();
    loop {
        let line = csv.position().line();
        match csv.read_byte_record(&mut record) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => return Err(csv_err(e.position().map_or(line, |p| p.line()), e)),
        }
        let line = record.position().map_or(line, |p| p.line());
        c.row(line, |i| record.get(i).and_then(|b| std::str::from_utf8(b).ok()));
    }
    Ok(c.finish(LogFormat::Csv, options.mapping))
}

/// Whitespace-separated numbers without a header, streamed; columns named by the mapping's
/// `[columns] names`, else `1`, `2`, … by position on the first data line.
fn inspect_asc<R: BufRead>(
    mut source: R,
    file: &str,
    options: &InspectOptions,
) -> Result<Inspection, FlightDataError> {
    let io = |source| FlightDataError::Io { file: file.to_string(), source };
    let mut c: Option<Collector> = None;
    let (mut raw, mut line) = (Vec::new(), 0u64);
    loop {
        raw.clear();
        if source.read_until(b'\n', &mut raw).map_err(io)? == 0 {
            break;
        }
        line += 1;
        let text = String::from_utf8_lossy(&raw);
        let fields: Vec<&str> = text.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        let c = c.get_or_insert_with(|| {
            let names = match options.mapping.and_then(|m| m.column_names.clone()) {
                Some(n) => n,
                None => (1..=fields.len()).map(|i| i.to_string()).collect(),
            };
            Collector::new(file, names, options)
        });
        c.row(line, |i| fields.get(i).copied());
    }
    let c = c.ok_or_else(|| FlightDataError::Format {
        file: file.to_string(),
        message: "no data line (whitespace-separated numbers) in the file".into(),
    })?;
    Ok(c.finish(LogFormat::Asc, options.mapping))
}

/// A `.mat` table already in memory: its columns are moved into the collector, not copied
/// beyond the kept ones.
fn inspect_mat(table: Table, options: &InspectOptions) -> Inspection {
    let Table { file, names, columns } = table;
    let mut c = Collector::new(&file, names, options);
    let rows = columns.first().map_or(0, Vec::len);
    let mut texts: Vec<String> = vec![String::new(); columns.len()];
    for r in 0..rows {
        // The collector parses text (one path for every table); a number's shortest
        // round-trip text parses back to the same f64.
        for (k, col) in columns.iter().enumerate() {
            if k == c.time_idx || c.keep.contains(&k) {
                texts[k] = col[r].to_string();
            }
        }
        c.row(r as u64 + 1, |i| texts.get(i).map(String::as_str));
    }
    c.finish(LogFormat::Mat, options.mapping)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_time_names_and_units() {
        assert_eq!(time_factor("time [s]"), Some(1.0));
        assert_eq!(time_factor("time_s"), Some(1.0));
        assert_eq!(time_factor("TimeMS"), Some(1e-3));
        assert_eq!(time_factor("time_us"), Some(1e-6));
        assert_eq!(time_factor("t (ms)"), Some(1e-3));
        assert_eq!(time_factor("t"), Some(1.0));
        assert_eq!(time_factor("theta_deg"), None);
        assert_eq!(time_factor("throttle"), None);
        assert_eq!(header_unit("q [rad/s]").as_deref(), Some("rad/s"));
        assert_eq!(header_unit("[x]"), None);
        assert_eq!(header_unit("q"), None);
    }
}
