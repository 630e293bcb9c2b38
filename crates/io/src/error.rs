//! Errors of flight-data reading. Every variant names the file, and where it applies the row
//! (line number in the file, header = line 1), the column and the channel. Values are shown
//! exact when short, else in short scientific form ([`crate::message::exact_or_short`]): a
//! corrupt value or an absurd mapping scale (1e300) would otherwise be written out in hundreds
//! of digits.

use crate::message::{exact_or_short, short};

/// A flight-data or mapping error.
#[derive(Debug, thiserror::Error)]
pub enum FlightDataError {
    /// The file could not be opened or read.
    #[error("{file}: {source}")]
    Io {
        /// File path (or `-` for stdin).
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The mapping TOML did not parse (the message carries line and column).
    #[error("{file}: mapping syntax: {message}")]
    MappingSyntax {
        /// Mapping file.
        file: String,
        /// Parser message with the TOML line and column.
        message: String,
    },
    /// A `[channels]` key is not a known channel.
    #[error("{file}: line {line}: unknown channel `{channel}` (valid: {valid})")]
    UnknownChannel {
        /// Mapping file.
        file: String,
        /// Line of the key in the mapping file.
        line: usize,
        /// The key.
        channel: String,
        /// Valid keys.
        valid: String,
    },
    /// A unit string did not parse.
    #[error("{file}: channel `{channel}`: {message}")]
    Unit {
        /// Mapping file.
        file: String,
        /// Channel key.
        channel: String,
        /// What was wrong.
        message: String,
    },
    /// A unit has the wrong dimension for its channel.
    #[error("{file}: channel `{channel}`: unit `{unit}` is not a {expected} unit")]
    WrongDimension {
        /// Mapping file.
        file: String,
        /// Channel key.
        channel: String,
        /// The unit given.
        unit: String,
        /// The dimension expected.
        expected: String,
    },
    /// A channel entry is malformed (no source, two sources, non-finite value…).
    #[error("{file}: channel `{channel}`: {reason}")]
    BadSpec {
        /// Mapping file.
        file: String,
        /// Channel key.
        channel: String,
        /// What was wrong.
        reason: String,
    },
    /// A required channel is not mapped.
    #[error("{file}: required channel `{channel}` is not mapped")]
    MissingChannel {
        /// Mapping file.
        file: String,
        /// Channel key.
        channel: String,
    },
    /// A mapped column is not in the data file's header. `hint` is empty or a sentence that
    /// starts with "; " (e.g. the header looks delimited by `;` or a tab, not a comma).
    #[error("{file}: row 1 (header): column `{column}` for channel `{channel}` is missing{hint}")]
    MissingColumn {
        /// Data file.
        file: String,
        /// Channel key.
        channel: String,
        /// Column name.
        column: String,
        /// Extra hint (empty, or starting with "; ").
        hint: String,
    },
    /// Two header fields have the same name: which one a mapping means is ambiguous.
    #[error(
        "{file}: row 1 (header): column `{column}` appears twice (fields {first} and {second})"
    )]
    DuplicateColumn {
        /// Data file.
        file: String,
        /// Column name.
        column: String,
        /// First field, 1-based.
        first: usize,
        /// Second field, 1-based.
        second: usize,
    },
    /// A mapped column is not among the columns of a file without a CSV header (an `.asc`
    /// file, a `.mat` record or an aligned log), whose names come from the file or from the
    /// mapping's `[columns] names`.
    #[error("{file}: column `{column}` for channel `{channel}` is not in the record ({available})")]
    NoSuchColumn {
        /// Data file.
        file: String,
        /// Channel key.
        channel: String,
        /// Column name.
        column: String,
        /// The columns the record has (a short list or a count, and where names come from).
        available: String,
    },
    /// A log file that is not of its format, or a format that cannot be read (yet).
    #[error("{file}: {message}")]
    Format {
        /// Data file.
        file: String,
        /// What is wrong, naming the format (and the line or variable where it applies).
        message: String,
    },
    /// The CSV itself could not be read (header or framing).
    #[error("{file}: row {row}: {message}")]
    Csv {
        /// Data file.
        file: String,
        /// Line number.
        row: u64,
        /// Parser message.
        message: String,
    },
    /// A data row was rejected (strict mode turns rejections into errors).
    #[error("{file}: row {row}: {problem}")]
    Row {
        /// Data file.
        file: String,
        /// Line number.
        row: u64,
        /// What was wrong, naming the column.
        problem: RowProblem,
    },
    /// The file holds no data at all: no bytes, or a header row and no data row. Said apart
    /// from [`FlightDataError::NoSamples`] (rows that were all rejected), whose count would be a
    /// misleading "0 rows rejected" here.
    #[error("{file}: the file has no data ({what})")]
    NoData {
        /// Data file.
        file: String,
        /// What it holds instead, e.g. "a header row and no data rows".
        what: String,
    },
    /// The record has no usable samples.
    #[error("{file}: no usable samples ({rejected} rows rejected{})", first_reasons(.first))]
    NoSamples {
        /// Data file.
        file: String,
        /// Rows rejected.
        rejected: usize,
        /// The first rejections (row and reason), so the cause is visible.
        first: Vec<(u64, String)>,
    },
    /// A binary log (PX4 ULog, ArduPilot DataFlash) could not be decoded at this byte offset.
    #[error("{file}: byte {offset}: {message}")]
    LogDecode {
        /// Log file.
        file: String,
        /// Byte offset in the file where the problem was found (for a streaming decoder: at or
        /// before this offset).
        offset: u64,
        /// What was wrong, naming the message and field where known.
        message: String,
    },
    /// A live MAVLink feed could not be opened or read ([`crate::mavlink`]).
    #[error(transparent)]
    Mavlink(#[from] crate::mavlink::MavlinkError),
    /// A topic, message or field a mapping or alignment needs is not in the log.
    #[error("{file}: `{column}` for {needed_by}: {reason}")]
    MissingTopic {
        /// Log file.
        file: String,
        /// The `<topic>.<field>` column asked for.
        column: String,
        /// What needs it (a channel, the clock, …).
        needed_by: String,
        /// Why it is missing (no such topic / no such field / no samples), listing what exists.
        reason: String,
    },
    /// Multi-rate alignment could not produce a table (bad rate, no overlap, every row dropped).
    #[error("{file}: alignment: {reason}")]
    Align {
        /// Log file.
        file: String,
        /// What was wrong.
        reason: String,
    },
}

fn first_reasons(first: &[(u64, String)]) -> String {
    if first.is_empty() {
        return String::new();
    }
    let list: Vec<String> = first.iter().map(|(row, r)| format!("row {row}: {r}")).collect();
    format!("; first: {}", list.join("; "))
}

/// Why a data row was rejected. Each names the column.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RowProblem {
    /// An empty field.
    #[error("column `{column}`: blank value")]
    Blank {
        /// Column name.
        column: String,
    },
    /// A field that is not a number.
    #[error("column `{column}`: `{text}` is not a number")]
    NotANumber {
        /// Column name.
        column: String,
        /// The field text.
        text: String,
    },
    /// A field whose bytes are not UTF-8 text (e.g. a Latin-1 `é`), so no number.
    #[error(
        "field {field} (column `{column}`): invalid UTF-8 byte 0x{byte:02X} at byte {offset} of the field: not a number (is the file in another encoding?)"
    )]
    InvalidUtf8 {
        /// 1-based field position in the row.
        field: usize,
        /// Column name.
        column: String,
        /// The first byte that is not UTF-8.
        byte: u8,
        /// Its 0-based offset in the field.
        offset: usize,
    },
    /// NaN or infinity.
    #[error("column `{column}`: non-finite value `{text}`")]
    NonFinite {
        /// Column name.
        column: String,
        /// The field text.
        text: String,
    },
    /// A finite raw value that is not finite after the unit conversion (overflow).
    #[error("column `{column}`: `{text}` is not finite in SI (`{channel}` = {})", short(*value))]
    NonFiniteSi {
        /// Column name(s).
        column: String,
        /// Channel key.
        channel: String,
        /// The field text (the first column's).
        text: String,
        /// The converted value.
        value: f64,
    },
    /// Time equal to the previous accepted sample's.
    #[error("column `{column}`: repeated time {} s", exact_or_short(*t_s))]
    RepeatedTime {
        /// Time column name.
        column: String,
        /// The time, s.
        t_s: f64,
    },
    /// Time earlier than the previous accepted sample's.
    #[error(
        "column `{column}`: time {} s goes backwards (previous {} s)",
        exact_or_short(*t_s),
        exact_or_short(*prev_t_s)
    )]
    NonMonotonicTime {
        /// Time column name.
        column: String,
        /// The time, s.
        t_s: f64,
        /// Previous accepted time, s.
        prev_t_s: f64,
    },
    /// A time that jumps implausibly far ahead of the previous accepted sample (more than
    /// [`crate::flight_data::IMPLAUSIBLE_JUMP_FACTOR`] × the nominal interval): the row is
    /// rejected and the previous time kept, so one corrupt time does not reject every later row.
    #[error(
        "column `{column}`: time {} s jumps implausibly far ahead of the previous {} s (more than {factor:e} × the nominal interval {} s)",
        exact_or_short(*t_s),
        exact_or_short(*prev_t_s),
        exact_or_short(*nominal_dt_s)
    )]
    ImplausibleTimeJump {
        /// Time column name.
        column: String,
        /// The time, s.
        t_s: f64,
        /// Previous accepted time, s.
        prev_t_s: f64,
        /// Nominal interval, s.
        nominal_dt_s: f64,
        /// The factor.
        factor: f64,
    },
    /// A time ahead of the record around it: the row is one of a short run (at most
    /// [`crate::flight_data::TIME_RUN_MAX`] rows) after a jump in time, or at the record's
    /// start, and the rows after the run go on from before it (after a gap they would stay
    /// later). A corrupt time stamp, not a gap: the run alone is rejected and the record goes
    /// on from the previous time.
    #[error(
        "column `{column}`: time {} s is ahead of {}: a bad time stamp, not a gap",
        exact_or_short(*t_s),
        outlier_neighbours(*prev_t_s, *next_t_s)
    )]
    TimeOutlier {
        /// Time column name.
        column: String,
        /// The time, s.
        t_s: f64,
        /// Previous accepted time, s (`None`: the row is at the record's start).
        prev_t_s: Option<f64>,
        /// The time of the row going on from before the run, s.
        next_t_s: f64,
    },
    /// The last line of a live feed (`-`) has no terminating newline: it may have been cut off
    /// inside a value, so it is not used.
    #[error(
        "last line has no terminating newline: possibly truncated (a live feed cut inside a value), not used"
    )]
    Truncated,
    /// Wrong number of fields.
    #[error("{found} fields, header has {expected}")]
    FieldCount {
        /// Fields in the header.
        expected: usize,
        /// Fields in this row.
        found: usize,
    },
    /// A finite value outside the plausibility limits every estimator applies
    /// (`aeroident_estimators::sample::PLAUSIBILITY`, e.g. V > 5000 m/s, |α| > 10 rad): a
    /// corrupt record, rejected here so that no sample the reader yields is refused later.
    #[error(
        "{field} = {} is implausible (limit {}; SI, after the mapping's conversion)",
        exact_or_short(*value),
        exact_or_short(*limit)
    )]
    Implausible {
        /// The channel as the mapping names it, and its source
        /// ([`crate::Mapping::field_label`], e.g. ``channel `vt` (column `V`)``).
        field: String,
        /// The SI value.
        value: f64,
        /// The limit it exceeds, SI.
        limit: f64,
    },
    /// A spike in a measured channel, found by a screening stage after the reader (the
    /// pipelines' spike screen): an isolated sample (`samples` = 1), or one of a short run of
    /// `samples` consecutive gross outliers with the channel back at its level on both sides.
    /// The row is not used.
    #[error(
        "{field} = {} is {}",
        exact_or_short(*value),
        spike_detail(*samples, *median, *threshold)
    )]
    Spike {
        /// The channel as the mapping names it, and its source
        /// ([`crate::Mapping::field_label`], e.g. ``channel `thrust` (column `thrust_N`)``).
        field: String,
        /// The SI value.
        value: f64,
        /// The median of the window around it (of the samples around the run), SI.
        median: f64,
        /// The departure from the median beyond which a sample is a spike, SI.
        threshold: f64,
        /// Samples in the run (1: an isolated spike).
        samples: usize,
    },
    /// A value outside the physical domain (e.g. V ≤ 0, mass ≤ 0).
    #[error("column `{column}`: {reason}")]
    Domain {
        /// Column name.
        column: String,
        /// What is wrong.
        reason: String,
    },
}

/// What a [`RowProblem::Spike`] is, for its message.
fn spike_detail(samples: usize, median: f64, threshold: f64) -> String {
    let (median, threshold) = (exact_or_short(median), exact_or_short(threshold));
    match samples {
        1 => format!(
            "an isolated spike (median of its neighbours {median}, more than {threshold} away)"
        ),
        n => format!(
            "one of a run of {n} spikes (median of the samples around the run {median}, more than {threshold} away from it and from the samples on both sides)"
        ),
    }
}

/// The rows a [`RowProblem::TimeOutlier`] is ahead of, for its message.
fn outlier_neighbours(prev_t_s: Option<f64>, next_t_s: f64) -> String {
    let next = exact_or_short(next_t_s);
    match prev_t_s {
        Some(p) => {
            format!("both the previous row ({} s) and the next ({next} s)", exact_or_short(p))
        }
        None => format!("the rows after it (next {next} s) at the record's start"),
    }
}

impl RowProblem {
    /// A short fixed label of the problem's kind, without the column or value (e.g.
    /// `blank value`, `time goes backwards`): what [`crate::rejection_log::RejectionLog`] counts
    /// rejections by once it stops listing them.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Blank { .. } => "blank value",
            Self::NotANumber { .. } => "not a number",
            Self::InvalidUtf8 { .. } => "invalid UTF-8",
            Self::NonFinite { .. } => "non-finite value",
            Self::NonFiniteSi { .. } => "not finite in SI",
            Self::RepeatedTime { .. } => "repeated time",
            Self::NonMonotonicTime { .. } => "time goes backwards",
            Self::ImplausibleTimeJump { .. } => "implausible time jump",
            Self::TimeOutlier { .. } => "time outlier",
            Self::Truncated => "truncated last line",
            Self::FieldCount { .. } => "wrong field count",
            Self::Implausible { .. } => "implausible value",
            Self::Spike { samples: 1, .. } => "isolated spike",
            Self::Spike { .. } => "spike run",
            Self::Domain { .. } => "value outside its domain",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row problem holding a value: with values no record holds (1e300, 1e-300, which
    /// Rust writes out in over 300 characters) its message stays a line and gives them in
    /// short scientific form; ordinary values stay exact.
    #[test]
    fn row_problems_show_huge_and_tiny_values_short() {
        let column = || "t".to_string();
        let field = || "channel `q` (column `Q`)".to_string();
        let (big, tiny) = (1e300, -1e-300);
        let problems = [
            RowProblem::NonFiniteSi {
                column: column(),
                channel: "q".into(),
                text: "1e300".into(),
                value: f64::INFINITY,
            },
            RowProblem::RepeatedTime { column: column(), t_s: big },
            RowProblem::NonMonotonicTime { column: column(), t_s: tiny, prev_t_s: big },
            RowProblem::ImplausibleTimeJump {
                column: column(),
                t_s: big,
                prev_t_s: tiny,
                nominal_dt_s: tiny,
                factor: 1e6,
            },
            RowProblem::TimeOutlier {
                column: column(),
                t_s: big,
                prev_t_s: Some(tiny),
                next_t_s: big,
            },
            RowProblem::TimeOutlier { column: column(), t_s: big, prev_t_s: None, next_t_s: tiny },
            RowProblem::Implausible { field: field(), value: big, limit: tiny },
            RowProblem::Spike {
                field: field(),
                value: big,
                median: tiny,
                threshold: big,
                samples: 1,
            },
            RowProblem::Spike {
                field: field(),
                value: tiny,
                median: big,
                threshold: big,
                samples: 3,
            },
        ];
        for p in &problems {
            let m = p.to_string();
            assert!(m.len() < 300, "{} bytes: {m}", m.len());
            assert!(m.contains("1.000e300") || m.contains("inf"), "{m}");
        }
        // A value just past its limit (π/2, written out as Rust writes it) stays told apart.
        let limit = std::f64::consts::FRAC_PI_2;
        let m = RowProblem::Implausible { field: field(), value: 1.57081, limit }.to_string();
        assert!(m.contains("= 1.57081 is implausible (limit 1.5707963267948966;"), "{m}");
    }
}
