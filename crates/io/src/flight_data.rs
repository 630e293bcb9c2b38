//! Streaming reader of recorded flight data: a CSV with one header row, mapped to the channels
//! of an [`AirDataSample`] by a [`Mapping`], converted to SI, one row at a time (works on stdin;
//! the whole file is never loaded).
//!
//! Every row yields exactly one [`RecordEvent`]: a sample, or a rejection naming the row (line
//! number in the file, header = line 1), the column and the reason. Rows are rejected for a
//! blank, non-numeric or non-finite value in a mapped column, a value that is not finite after
//! the unit conversion, a wrong field count, a repeated or backward time, a time implausibly far
//! ahead ([`IMPLAUSIBLE_JUMP_FACTOR`] × the nominal interval; the last good time is kept), a
//! short run of bad time stamps (below), a non-positive airspeed, mass, area, chord, span,
//! moment of inertia, density or dynamic pressure, and a mass, area, chord, span or inertia
//! outside its physical range ([`crate::mapping::CONSTANT_RANGES`]). A gap — an interval longer than [`ONE_SAMPLE_HOLE_MAX`] × the nominal interval — is
//! reported as a [`RecordEvent::Gap`] *before* the sample that follows it; it is never bridged
//! silently. Nothing is dropped without an event.
//!
//! # A hole of one sample is no gap
//!
//! An interval of about two nominal intervals (over [`GAP_FACTOR`], up to
//! [`ONE_SAMPLE_HOLE_MAX`] × nominal) is one sample missing from the grid — a row this reader
//! rejected (a bad time stamp, a blank value), or a sample the recorder lost — and the record
//! goes on on the same grid: it is no [`RecordEvent::Gap`], so the row costs itself only. Every
//! stage after the reader takes sample times from the samples (output error integrates over the
//! interval as it is), and the pipelines' differentiating stage puts a stand-in, interpolated
//! between the two neighbours, in the missing sample's place, so no restart costs the `N − 1`
//! samples around it. A longer hole is a gap.
//!
//! # Bad time stamps cost their own rows
//!
//! A time further ahead of the previous sample than a gap (over the rows between: rows
//! rejected between two samples explain a longer interval) is either the sample after a gap or
//! a corrupt time stamp (a 10000 in a record at 2 s): accepting the latter would reject every
//! later row as going backwards. Such a sample (and the second sample of a record whose mapping
//! gives no `nominal_dt_s`, which would fix the nominal interval) therefore starts a *run* that
//! is held until later rows settle it:
//!
//! - a good sample later than the previous time but earlier than the run goes on from before
//!   the jump: every row of the run is rejected ([`RowProblem::TimeOutlier`], each with its
//!   row), and the record goes on from the previous time;
//! - more than [`TIME_RUN_MAX`] samples in the run (each later than the one before it) make it
//!   the record's own time: a gap, every row kept, as is a run still held at the record's end.
//!
//! A jump within a run starts a run of its own, judged the same way (a bad time stamp a few
//! rows after a genuine gap costs its own row). A rejected row proves nothing (it may be the
//! bad one) and waits in its place, up to [`HELD_ROWS_MAX`] rows held; a row rejected as
//! repeated or backward against a run that is then rejected is a time outlier too.
//!
//! The record's *first* rows have no previous time to judge them by, so they are held too: the
//! first sample starts the record when more than [`TIME_RUN_MAX`] later samples are after it,
//! and is a time outlier when more than that many are before it (at the record's end, or with
//! [`HELD_ROWS_MAX`] rows held, the majority decides; a tie keeps it); then the next sample is
//! judged the same way. A 10000 in the first row of a record at 0.1 s thus costs that row, not
//! the 600 after it.
//!
//! The cost on a live feed is latency: [`TIME_RUN_MAX`] + 1 samples at the start and after a
//! gap. The price of telling a short run from a gap is that a run of at most [`TIME_RUN_MAX`]
//! genuine samples after a gap, followed by a bad time stamp between the two, is rejected in
//! its place (a gap that short, then a bad stamp, is the rarer record).
//!
//! A file without data rows (empty, or a header alone) is an error of its own
//! ([`FlightDataError::NoData`]), not a record whose rows were all rejected.
//!
//! # What a sample holds
//!
//! Channels and units as in [`crate::mapping`] (full reference: `docs/mapping.md`). A channel
//! the mapping does not map is `None` in the sample, never 0. Derived here:
//!
//! - `q̄ = ½ ρ V²` when only `rho` is mapped, `ρ = 2 q̄ / V²` when only `qbar` is (both are
//!   then present in every sample);
//! - the flow angles at the CG from those at the vanes. A vane at body position
//!   `r_v = (x, y, z)` from the CG moves with `v_v = v_cg + ω × r_v` (rigid-body velocity
//!   transport, `ω = (p, q, r)`), i.e. `u_v = u + q z − r y`,
//!   `v_v = v + r x − p z`, `w_v = w + p y − q x` — the transport Jategaonkar 2015 applies to
//!   the ATTAS noseboom (book code `chapter04/umr_reg_attas.m`; Klein & Morelli 2006 ch. 10,
//!   instrument position corrections). With `α ≈ w/u`, `β ≈ v/V` and `u ≈ V`, to first order
//!   in the rates and with `y = 0`:
//!
//!   ```text
//!   α_cg = α_vane + x_α q / V                    (vane x_α ahead of the CG)
//!   β_cg = β_vane − x_β r / V + z_β p / V        (vane x_β ahead of, z_β below the CG)
//!   ```
//!
//!   (a yaw rate to the right moves a nose vane to the right, so it sees more sideslip than
//!   the CG). The neglected terms are products of two small quantities (e.g. `α · z q / V`):
//!   ≈ 10⁻⁵ rad for the ATTAS noseboom. The airspeed is not corrected (its change is second
//!   order).
//!
//! Finiteness is checked on the raw text and again after the unit conversion (a finite raw
//! value can overflow), and the finished sample is checked field by field.

use crate::error::{FlightDataError, RowProblem};
use crate::line_ends::BareCrAsLf;
use crate::mapping::{Channel, ChannelMap, Mapping, Source};
use aeroident_estimators::{AirDataSample, AircraftConstants};
use std::collections::{BTreeMap, VecDeque};
use std::io::Read;

mod held;

/// Longest regular interval, in nominal intervals: beyond it a sample is missing (one, up to
/// [`ONE_SAMPLE_HOLE_MAX`]) or there is a gap.
pub const GAP_FACTOR: f64 = 1.5;

/// Longest interval, in nominal intervals, that is one sample missing from the grid (module
/// doc, "A hole of one sample is no gap"): an interval over [`GAP_FACTOR`] and up to this is
/// no gap. Two intervals, with the jitter [`GAP_FACTOR`] allows a single one.
pub const ONE_SAMPLE_HOLE_MAX: f64 = 2.5;

/// A time more than this multiple of the nominal interval ahead of the previous accepted
/// sample is implausible (a corrupt value such as 1e308): the row is rejected and the previous
/// time kept. Smaller jumps are gaps ([`GAP_FACTOR`]).
pub const IMPLAUSIBLE_JUMP_FACTOR: f64 = 1e6;

/// The sample rates of flight data, Hz (lowest, highest): a record whose median interval over
/// its first [`RATE_CHECK_INTERVALS`] is outside them after the time unit's conversion is
/// warned of ([`FlightDataReader::notes`]), naming the unit that would give a plausible rate.
/// Wide: a 0.2 Hz record (5 s between samples) resolves no short period, and nothing logs a
/// whole record for identification at 5 kHz; a time column in ms declared `s` (or the
/// reverse) is off by 1000 and lands outside for any rate from 5 Hz to 200 Hz.
pub const PLAUSIBLE_RATE_HZ: (f64, f64) = (0.2, 5000.0);

/// Accepted intervals whose median is checked against [`PLAUSIBLE_RATE_HZ`] (all of them in a
/// shorter record, if it has two).
pub const RATE_CHECK_INTERVALS: usize = 20;

/// Warnings of a reader, shared with whoever reports them after the events are consumed.
pub type ReaderNotes = std::sync::Arc<std::sync::Mutex<Vec<String>>>;

/// Most rows held while time stamps are judged (module doc): past it the rows held are taken as
/// they are (a rejection waits behind a held sample, to keep the events in row order).
pub const HELD_ROWS_MAX: usize = 64;

/// Most rows after a jump in time (or at the record's start) that can be rejected together as
/// bad time stamps when the record goes on from before them (module doc); a run of more
/// samples is the record's own time. Also the rows of latency after a gap on a live feed.
pub const TIME_RUN_MAX: usize = 4;

/// A rejected row: its line number and the reason (naming the column).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Rejection {
    /// Line number in the file (header = 1).
    pub row: u64,
    /// Why, e.g. "column `alpha_rad`: blank value".
    pub reason: String,
}

/// What one data row produced.
// The sample variant is large; events are consumed one at a time, so it is not boxed (no
// allocation per row for it).
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum RecordEvent {
    /// A good sample.
    Sample {
        /// Line number.
        row: u64,
        /// The sample, SI, at the CG.
        sample: AirDataSample,
    },
    /// The row was rejected.
    Rejected {
        /// Line number.
        row: u64,
        /// Why.
        problem: RowProblem,
    },
    /// A time gap precedes the sample on `row` (which follows as a `Sample` event).
    Gap {
        /// Line number of the sample after the gap.
        row: u64,
        /// Interval found, s.
        dt_s: f64,
        /// Nominal interval, s.
        nominal_dt_s: f64,
    },
}

#[derive(Debug, Clone)]
struct Resolved {
    columns: Vec<usize>,
    names: Vec<String>,
    weights: Vec<f64>,
    map: ChannelMap,
}

/// The source under the CSV parser, remembering whether it reached its end and its last byte
/// (to tell a last line cut off without its newline).
struct Tail<R> {
    inner: R,
    eof: bool,
    last_byte: Option<u8>,
}

impl<R: Read> Read for Tail<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n == 0 && !buf.is_empty() {
            self.eof = true;
        } else if n > 0 {
            self.last_byte = Some(buf[n - 1]);
        }
        Ok(n)
    }
}

/// The streaming reader. Iterate it for [`RecordEvent`]s; fatal problems are `Err` items (an
/// error of the source itself is [`FlightDataError::Io`]; a source that ends without a data row
/// ends with [`FlightDataError::NoData`]).
///
/// Two framing problems are caught: a quote that is never closed (the CSV parser would take
/// the rest of the file as one field) is a fatal error naming the row, the column and the lines
/// it spans; and in a live feed (file name `-`) a last line without a terminating newline is
/// rejected as possibly truncated ([`RowProblem::Truncated`]). Files keep their last line.
/// A bare `\r` (old Mac line ends) ends a line as `\n` does. Rows are read as bytes: a mapped
/// field that is not UTF-8 rejects its row ([`RowProblem::InvalidUtf8`]), not the file.
pub struct FlightDataReader<R: Read> {
    file: String,
    csv: csv::Reader<Tail<BareCrAsLf<R>>>,
    csv_headers: Vec<String>,
    header_len: usize,
    time: Resolved,
    channels: BTreeMap<Channel, Resolved>,
    constants: BTreeMap<Channel, f64>,
    record: csv::ByteRecord,
    last_t: Option<f64>,
    /// Row of the last accepted sample.
    last_row: u64,
    nominal_dt: Option<f64>,
    inertia_reference_mass_kg: Option<f64>,
    /// Events read but not yet returned.
    pending: VecDeque<Result<RecordEvent, FlightDataError>>,
    /// Rows held while the time stamps after a jump (or at the record's start) are judged, in
    /// row order ([`held`]).
    held: Vec<held::Entry>,
    /// Whether the record's start is still being judged ([`held`]).
    opening: bool,
    /// Data records read (to tell a file without data from one whose rows were all rejected).
    rows_seen: u64,
    done: bool,
    /// Lines of the CSV text that are not lines of the file the user gave (a header
    /// [`crate::log`] writes for a file without one): subtracted from every row number.
    synthetic_lines: u64,
    /// The mapping file (named in the reader's warnings).
    mapping_file: String,
    /// The mapping, to name a sample field in a row's message as the user wrote it.
    mapping: std::sync::Arc<Mapping>,
    /// The first accepted intervals, s, until the rate is checked ([`PLAUSIBLE_RATE_HZ`]).
    intervals: Vec<f64>,
    rate_checked: bool,
    notes: ReaderNotes,
}

impl<R: Read> FlightDataReader<R> {
    /// Opens a reader on `source` (named `file` in messages) and checks the header against the
    /// mapping.
    ///
    /// # Errors
    /// [`FlightDataError::Csv`] if the header cannot be read, [`FlightDataError::NoData`] for an
    /// empty source, [`FlightDataError::MissingColumn`] for a mapped column not in the header.
    pub fn new(source: R, file: &str, mapping: &Mapping) -> Result<Self, FlightDataError> {
        let mut csv = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(true)
            .trim(csv::Trim::All)
            // Lines end at `\n` only: with the default (`\r` also ends a record) the parser
            // reports every row of a CRLF file one line early; the `\r` before the `\n` is
            // trimmed as whitespace.
            .terminator(csv::Terminator::Any(b'\n'))
            .from_reader(Tail { inner: BareCrAsLf::new(source), eof: false, last_byte: None });
        // A name that is not UTF-8 (a Latin-1 `é` of an unmapped column) is read with U+FFFD in
        // place of its bad bytes: the file is not lost for a column the mapping never reads.
        let headers = csv
            .byte_headers()
            .map_err(|e| FlightDataError::Csv {
                file: file.to_string(),
                row: 1,
                message: e.to_string(),
            })
            .map(|h| csv::StringRecord::from_byte_record_lossy(h.clone()))?;
        if headers.is_empty() {
            return Err(FlightDataError::NoData {
                file: file.to_string(),
                what: "it is empty: no header row and no data rows".into(),
            });
        }
        let header_len = headers.len();
        let positions = column_positions(&headers, file)?;
        let hint = match headers.iter().collect::<Vec<_>>().as_slice() {
            [one] if one.contains(';') => {
                "; the header is one field containing `;`: the file looks semicolon-delimited, \
                 but only comma-separated files are read"
                    .to_string()
            }
            [one] if one.contains('\t') => {
                "; the header is one field containing a tab: the file looks tab-delimited, \
                 but only comma-separated files are read"
                    .to_string()
            }
            _ => String::new(),
        };
        let resolve = |key: &str, m: &ChannelMap| -> Result<Option<Resolved>, FlightDataError> {
            let Source::Columns(cols) = &m.source else { return Ok(None) };
            let names: Vec<String> = cols.iter().map(|(n, _)| n.clone()).collect();
            let weights: Vec<f64> = cols.iter().map(|(_, w)| *w).collect();
            let mut columns = Vec::with_capacity(names.len());
            for n in &names {
                let idx = positions.get(n.as_str()).copied().ok_or_else(|| {
                    FlightDataError::MissingColumn {
                        file: file.to_string(),
                        channel: key.to_string(),
                        column: n.clone(),
                        hint: hint.clone(),
                    }
                })?;
                columns.push(idx);
            }
            Ok(Some(Resolved { columns, names, weights, map: m.clone() }))
        };
        let time = resolve("time", &mapping.time)?.ok_or_else(|| FlightDataError::BadSpec {
            file: mapping.file.clone(),
            channel: "time".into(),
            reason: "time must come from a column".into(),
        })?;
        let mut channels = BTreeMap::new();
        let mut constants = BTreeMap::new();
        for (ch, m) in &mapping.channels {
            match (&m.source, resolve(ch.key(), m)?) {
                (Source::Constant(v), _) => {
                    constants.insert(*ch, *v);
                }
                (_, Some(r)) => {
                    channels.insert(*ch, r);
                }
                (_, None) => {}
            }
        }
        Ok(Self {
            file: file.to_string(),
            csv,
            csv_headers: headers.iter().map(str::to_string).collect(),
            header_len,
            time,
            channels,
            constants,
            record: csv::ByteRecord::new(),
            last_t: None,
            last_row: 0,
            nominal_dt: mapping.nominal_dt_s,
            inertia_reference_mass_kg: mapping.inertia_reference_mass_kg,
            pending: VecDeque::new(),
            held: Vec::new(),
            opening: true,
            rows_seen: 0,
            done: false,
            synthetic_lines: 0,
            mapping_file: mapping.file.clone(),
            mapping: std::sync::Arc::new(mapping.clone()),
            intervals: Vec::new(),
            rate_checked: false,
            notes: ReaderNotes::default(),
        })
    }

    /// Row numbers of the events count `n` fewer lines: for CSV text rendered from another
    /// format with a header line of its own ([`crate::log`]), so that rows name the line of an
    /// `.asc` file or the row of a table (1-based), not the line of the rendering.
    pub(crate) fn with_synthetic_lines(mut self, n: u64) -> Self {
        self.synthetic_lines = n;
        self
    }

    /// The reader's warnings, filled as the record is read (shared: the reader is usually
    /// consumed by the stages after it): a time unit that makes the record's rate implausible
    /// ([`PLAUSIBLE_RATE_HZ`]).
    pub fn notes(&self) -> ReaderNotes {
        std::sync::Arc::clone(&self.notes)
    }

    /// The mapping the record is read with (the stages after the reader name its channels).
    pub fn mapping(&self) -> std::sync::Arc<Mapping> {
        std::sync::Arc::clone(&self.mapping)
    }

    /// The data file's name as used in messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The text of field `idx` (0-based) of the current row, column `name`: read as bytes, so
    /// that a byte that is not UTF-8 costs its row (a bad field), not the file.
    fn text(&self, idx: usize, name: &str) -> Result<&str, RowProblem> {
        let bytes = self.record.get(idx).unwrap_or(b"");
        std::str::from_utf8(bytes).map_err(|e| RowProblem::InvalidUtf8 {
            field: idx + 1,
            column: name.to_string(),
            byte: bytes[e.valid_up_to()],
            offset: e.valid_up_to(),
        })
    }

    fn field(&self, ch: &str, r: &Resolved) -> Result<f64, RowProblem> {
        let mut sum = 0.0;
        let mut values = Vec::new();
        for ((idx, name), w) in r.columns.iter().zip(r.names.iter()).zip(r.weights.iter()) {
            let text = self.text(*idx, name)?;
            if text.is_empty() {
                return Err(RowProblem::Blank { column: name.clone() });
            }
            let v: f64 = text.parse().map_err(|_| RowProblem::NotANumber {
                column: name.clone(),
                text: text.to_string(),
            })?;
            if !v.is_finite() {
                return Err(RowProblem::NonFinite { column: name.clone(), text: text.to_string() });
            }
            sum += w * v;
            if r.map.expression.is_some() {
                values.push(v);
            }
        }
        if let Some(e) = &r.map.expression {
            sum = e.eval(&values);
        }
        let si = r.map.to_si(sum);
        if !si.is_finite() {
            return Err(RowProblem::NonFiniteSi {
                column: match &r.map.expression {
                    Some(e) => format!("expr `{}` over {}", e.text(), r.names.join(", ")),
                    None => r.names.join("+"),
                },
                channel: ch.to_string(),
                text: String::from_utf8_lossy(self.record.get(r.columns[0]).unwrap_or(b""))
                    .into_owned(),
                value: si,
            });
        }
        Ok(si)
    }

    /// The SI value of `ch` in the current row (`None` when not mapped); mapped channels of
    /// [`Channel::POSITIVE`] must be > 0.
    fn get(&self, ch: Channel) -> Result<Option<f64>, RowProblem> {
        let v = if let Some(v) = self.constants.get(&ch) {
            *v
        } else {
            match self.channels.get(&ch) {
                Some(r) => self.field(ch.key(), r)?,
                None => return Ok(None),
            }
        };
        if Channel::POSITIVE.contains(&ch) && (v.is_nan() || v <= 0.0) {
            let column = match self.channels.get(&ch) {
                Some(r) => r.names.join("+"),
                None => format!("{} (constant)", ch.key()),
            };
            return Err(RowProblem::Domain {
                column,
                reason: format!("{} must be > 0, got {v}", ch.key()),
            });
        }
        // Constants were checked with the mapping; a column's value is checked here.
        if let Some(r) = self.channels.get(&ch)
            && let Err(reason) = crate::mapping::check_constant_range(ch, v)
        {
            return Err(RowProblem::Domain {
                column: r.names.join("+"),
                reason: format!("{}: {reason}", ch.key()),
            });
        }
        Ok(Some(v))
    }

    /// A channel the mapping guarantees ([`Channel::REQUIRED`]).
    fn required(&self, ch: Channel) -> Result<f64, RowProblem> {
        self.get(ch)?.ok_or_else(|| RowProblem::Domain {
            column: ch.key().to_string(),
            reason: "required channel not mapped".into(),
        })
    }

    /// The current row's time, s, after the field count is checked (the time is needed before
    /// the rest of the row to judge a time stamp held back as a possible outlier).
    fn row_time(&self) -> Result<f64, RowProblem> {
        if self.record.len() != self.header_len {
            return Err(RowProblem::FieldCount {
                expected: self.header_len,
                found: self.record.len(),
            });
        }
        self.field("time", &self.time)
    }

    /// `t_s` against the time of the sample before it (`prev`, `None` at the record's start):
    /// not repeated, not backwards, not implausibly far ahead.
    fn check_time(&self, prev: Option<f64>, t_s: f64) -> Result<(), RowProblem> {
        let Some(prev) = prev else { return Ok(()) };
        let column = self.time.names[0].clone();
        if t_s == prev {
            return Err(RowProblem::RepeatedTime { column, t_s });
        }
        if t_s < prev {
            return Err(RowProblem::NonMonotonicTime { column, t_s, prev_t_s: prev });
        }
        if let Some(nom) = self.nominal_dt
            && t_s - prev > IMPLAUSIBLE_JUMP_FACTOR * nom
        {
            return Err(RowProblem::ImplausibleTimeJump {
                column,
                t_s,
                prev_t_s: prev,
                nominal_dt_s: nom,
                factor: IMPLAUSIBLE_JUMP_FACTOR,
            });
        }
        Ok(())
    }

    /// The row's thrust, N: the `thrust` channel, or the mapping's `[thrust_model]` law at
    /// density `rho_kgpm3` and airspeed `vt_mps` (`None` when neither is mapped).
    fn thrust(&self, rho_kgpm3: f64, vt_mps: f64) -> Result<Option<f64>, RowProblem> {
        let Some(law) = &self.mapping.thrust_model else { return self.get(Channel::Thrust) };
        // The mapping refuses a law without its input channel (Mapping::from_toml_str).
        let input = self.required(crate::mapping::law_input(law))?;
        Ok(Some(law.thrust_n(rho_kgpm3, vt_mps, input)))
    }

    /// The sample of the current row at time `t_s` (already read and checked).
    fn parse_row(&self, t_s: f64) -> Result<AirDataSample, RowProblem> {
        let g = |ch: Channel| self.get(ch);
        let vt_mps = self.required(Channel::Vt)?;
        let alpha_vane = self.required(Channel::Alpha)?;
        let (p, q, r) = (g(Channel::P)?, g(Channel::Q)?, g(Channel::R)?);
        let beta_vane = g(Channel::Beta)?;
        // Vane → CG (module doc). Mapping validation guarantees the rates a correction needs.
        let alpha_rad = match (g(Channel::AlphaVaneX)?, q) {
            (Some(x), Some(q)) => alpha_vane + x * q / vt_mps,
            _ => alpha_vane,
        };
        let (bx, bz) = (g(Channel::BetaVaneX)?, g(Channel::BetaVaneZ)?);
        let beta_rad = beta_vane.map(|b| {
            let dx = match (bx, r) {
                (Some(x), Some(r)) => -x * r / vt_mps,
                _ => 0.0,
            };
            let dz = match (bz, p) {
                (Some(z), Some(p)) => z * p / vt_mps,
                _ => 0.0,
            };
            b + dx + dz
        });
        let (qbar, rho) = (g(Channel::Qbar)?, g(Channel::Rho)?);
        let v2 = vt_mps * vt_mps;
        let qbar_pa = match (qbar, rho) {
            (Some(q), _) => q,
            (None, Some(rho)) => 0.5 * rho * v2,
            (None, None) => {
                return Err(RowProblem::Domain {
                    column: "qbar/rho".into(),
                    reason: "neither dynamic pressure nor density mapped".into(),
                });
            }
        };
        let mass_kg = self.required(Channel::Mass)?;
        let k = self.inertia_reference_mass_kg.map_or(1.0, |m0| mass_kg / m0);
        let inertia = |ch: Channel| g(ch).map(|v| v.map(|v| v * k));
        let constants = AircraftConstants {
            mass_kg,
            S_m2: self.required(Channel::S)?,
            cbar_m: g(Channel::Cbar)?,
            b_m: g(Channel::B)?,
            Ixx_kgm2: inertia(Channel::Ixx)?,
            Iyy_kgm2: inertia(Channel::Iyy)?,
            Izz_kgm2: inertia(Channel::Izz)?,
            Ixz_kgm2: inertia(Channel::Ixz)?,
            thrust_arm_m: g(Channel::ThrustArm)?.unwrap_or(0.0),
            thrust_incidence_rad: g(Channel::ThrustIncidence)?.unwrap_or(0.0),
            v0_mps: g(Channel::V0)?,
        };
        let s = AirDataSample {
            t_s,
            vt_mps,
            alpha_rad,
            qbar_pa,
            beta_rad,
            p_rad_s: p,
            q_rad_s: q,
            r_rad_s: r,
            pdot_rad_s2: g(Channel::Pdot)?,
            qdot_rad_s2: g(Channel::Qdot)?,
            rdot_rad_s2: g(Channel::Rdot)?,
            alphadot_rad_s: g(Channel::Alphadot)?,
            phi_rad: g(Channel::Phi)?,
            theta_rad: g(Channel::Theta)?,
            psi_rad: g(Channel::Psi)?,
            ax_mps2: g(Channel::Ax)?,
            ay_mps2: g(Channel::Ay)?,
            az_mps2: g(Channel::Az)?,
            de_rad: g(Channel::De)?,
            da_rad: g(Channel::Da)?,
            dr_rad: g(Channel::Dr)?,
            thrust_n: self.thrust(rho.unwrap_or(2.0 * qbar_pa / v2), vt_mps)?,
            throttle: g(Channel::Throttle)?,
            thrust_moment_nm: g(Channel::ThrustMoment)?,
            rho_kgpm3: Some(rho.unwrap_or(2.0 * qbar_pa / v2)),
            constants,
        };
        // Derived values (vane corrections, q̄ from ρ) can still overflow.
        if let Some((field, value)) = s.first_non_finite() {
            return Err(RowProblem::Domain {
                column: field.to_string(),
                reason: format!("derived value {value} is not finite"),
            });
        }
        if let Some((field, value, limit)) = s.first_implausible() {
            let field = self.mapping.field_label(field);
            return Err(RowProblem::Implausible { field, value, limit });
        }
        Ok(s)
    }
}

impl<R: Read> Iterator for FlightDataReader<R> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(ev) = self.pending.pop_front() {
                return Some(ev);
            }
            if self.done {
                return None;
            }
            self.read_record();
        }
    }
}

impl<R: Read> FlightDataReader<R> {
    fn header_name(&self, i: usize) -> String {
        self.csv_headers.get(i).cloned().unwrap_or_else(|| format!("#{}", i + 1))
    }

    /// Reads one CSV record and queues what it produced (none, one or several events: a held
    /// time stamp is settled by the row after it).
    fn read_record(&mut self) {
        let mut record = std::mem::take(&mut self.record);
        let more = self.csv.read_byte_record(&mut record);
        let shift = self.synthetic_lines;
        let row = record.position().map(|p| p.line()).unwrap_or(0).saturating_sub(shift);
        self.record = record;
        match more {
            Err(e) => {
                let row = e.position().map(|p| p.line().saturating_sub(shift)).unwrap_or(row);
                let message = e.to_string();
                let error = match e.into_kind() {
                    // The source's own error (e.g. a live feed that ended without data) says
                    // what went wrong; it is no CSV row's.
                    csv::ErrorKind::Io(source) => {
                        FlightDataError::Io { file: self.file.clone(), source }
                    }
                    _ => FlightDataError::Csv { file: self.file.clone(), row, message },
                };
                self.end(Some(error));
            }
            Ok(false) => {
                let error = (self.rows_seen == 0).then(|| FlightDataError::NoData {
                    file: self.file.clone(),
                    what: if self.synthetic_lines > 0 {
                        "no data rows".into()
                    } else {
                        "a header row and no data rows".into()
                    },
                });
                self.end(error);
            }
            // A blank line (an empty `\r\n`, or `\r\r\n` of a file converted to CRLF twice)
            // is no row, as a blank `\n` line is not.
            Ok(true) if self.record.len() == 1 && matches!(&self.record[0], b"" | b"\r") => {}
            Ok(true) => {
                self.rows_seen += 1;
                if let Some(i) =
                    self.record.iter().position(|f| f.iter().any(|&b| b == b'\n' || b == b'\r'))
                {
                    let column = self.header_name(i);
                    let tail = self.csv.get_ref();
                    // After a final newline the position is on the (empty) next line.
                    let ended_on_newline = tail.eof && tail.last_byte == Some(b'\n');
                    let end = self
                        .csv
                        .position()
                        .line()
                        .saturating_sub(u64::from(ended_on_newline) + shift);
                    let error = FlightDataError::Csv {
                        file: self.file.clone(),
                        row,
                        message: format!(
                            "field {} (column `{column}`) contains a line break: a quote opened here is never closed and runs over lines {row}–{end} (the rest of the file would be read as one field)",
                            i + 1
                        ),
                    };
                    self.end(Some(error));
                    return;
                }
                let tail = self.csv.get_ref();
                // The csv crate numbers a record from where its reading began, so a record
                // after blank lines would be numbered at the first blank line. The line it ends
                // on is exact: the record's line is the one before the position after it (the
                // parser stops right after the newline), or that position itself for a last line
                // without a newline (the source ended while the record was read).
                let unterminated = tail.eof && tail.last_byte != Some(b'\n');
                let row =
                    self.csv.position().line().saturating_sub(u64::from(!unterminated) + shift);
                if self.file == "-" && unterminated {
                    self.end(None);
                    self.pending.push_back(Ok(RecordEvent::Rejected {
                        row,
                        problem: RowProblem::Truncated,
                    }));
                    return;
                }
                self.event(row);
            }
        }
    }

    /// Queues an accepted sample, after a [`RecordEvent::Gap`] if its interval is one (longer
    /// than a hole of one sample, module doc); the first interval fixes the nominal one when
    /// the mapping gives none.
    fn accept(&mut self, row: u64, sample: AirDataSample) {
        if let Some(prev) = self.last_t {
            let dt = sample.t_s - prev;
            match self.nominal_dt {
                None => self.nominal_dt = Some(dt),
                Some(nom) if dt > ONE_SAMPLE_HOLE_MAX * nom => {
                    self.pending.push_back(Ok(RecordEvent::Gap {
                        row,
                        dt_s: dt,
                        nominal_dt_s: nom,
                    }));
                }
                Some(_) => {}
            }
        }
        if let Some(prev) = self.last_t
            && !self.rate_checked
        {
            self.intervals.push(sample.t_s - prev);
            if self.intervals.len() >= RATE_CHECK_INTERVALS {
                self.check_rate();
            }
        }
        self.last_t = Some(sample.t_s);
        self.last_row = row;
        self.pending.push_back(Ok(RecordEvent::Sample { row, sample }));
    }
}

impl<R: Read> FlightDataReader<R> {
    /// Checks the median of the first accepted intervals against [`PLAUSIBLE_RATE_HZ`] (once,
    /// with at least two): outside, a warning naming the time column, its unit and the unit
    /// (s, ms, us) that would give a plausible rate.
    fn check_rate(&mut self) {
        if self.rate_checked || self.intervals.len() < 2 {
            return;
        }
        self.rate_checked = true;
        let mut intervals = std::mem::take(&mut self.intervals);
        intervals.sort_by(f64::total_cmp);
        let dt = intervals[intervals.len() / 2];
        let (lo, hi) = PLAUSIBLE_RATE_HZ;
        let plausible = |dt: f64| dt >= 1.0 / hi && dt <= 1.0 / lo;
        if plausible(dt) {
            return;
        }
        // The interval in each time unit, the raw column and its scale unchanged; the one
        // nearest the middle of the plausible rates (log scale) is named.
        let middle = (lo * hi).sqrt().recip().ln();
        let declared = &self.time.map;
        let other = [("s", 1.0), ("ms", 1e-3), ("us", 1e-6)]
            .into_iter()
            .map(|(unit, to_si)| (unit, dt / declared.to_si * to_si))
            .filter(|&(_, d)| plausible(d))
            .min_by(|a, b| (a.1.ln() - middle).abs().total_cmp(&(b.1.ln() - middle).abs()));
        let hint = match other {
            Some((unit, d)) => format!(
                "with `unit = \"{unit}\"` it would be {} s ({} Hz): check the unit",
                sig(d),
                sig(1.0 / d)
            ),
            None => {
                "no time unit (s, ms, us) gives a plausible rate: check the column and its scale"
                    .into()
            }
        };
        let note = format!(
            "{}: time column `{}` in `{}` ({} [time]): the median interval of the first {} samples is {} s ({} Hz), outside the rates of flight data ({lo} Hz to {hi} Hz); {hint}",
            self.file,
            self.time.names.join("+"),
            declared.unit,
            self.mapping_file,
            intervals.len() + 1,
            sig(dt),
            sig(1.0 / dt),
        );
        if let Ok(mut notes) = self.notes.lock() {
            notes.push(note);
        }
    }
}

/// Each header name's 0-based position (one pass, hashed: a record may have 10⁵ columns);
/// a name given twice is an error naming both positions (1-based). Empty names may repeat.
fn column_positions<'h>(
    headers: &'h csv::StringRecord,
    file: &str,
) -> Result<std::collections::HashMap<&'h str, usize>, FlightDataError> {
    let mut positions = std::collections::HashMap::with_capacity(headers.len());
    for (i, h) in headers.iter().enumerate().filter(|(_, h)| !h.is_empty()) {
        if let Some(&j) = positions.get(h) {
            return Err(FlightDataError::DuplicateColumn {
                file: file.to_string(),
                column: h.to_string(),
                first: j + 1,
                second: i + 1,
            });
        }
        positions.insert(h, i);
    }
    Ok(positions)
}

/// `x` to 4 significant digits, without trailing zeros.
fn sig(x: f64) -> String {
    if !(x.is_finite() && x != 0.0) {
        return format!("{x}");
    }
    let decimals = (3 - x.abs().log10().floor() as i64).clamp(0, 20) as usize;
    let text = format!("{x:.decimals$}");
    match text.contains('.') {
        true => text.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => text,
    }
}
