//! Streaming reader of recorded flight data: a CSV with one header row, mapped to standard
//! channels by a [`Mapping`], converted to SI, one row at a time (works on stdin; the whole file
//! is never loaded).
//!
//! Every row yields exactly one [`RecordEvent`]: a sample, or a rejection naming the row (line
//! number in the file, header = line 1), the column and the reason. Rows are rejected for a
//! blank, non-numeric or non-finite value in a mapped column, a wrong field count, a repeated
//! or backward time, and a non-positive airspeed, mass, inertia, area or chord (or density /
//! dynamic pressure). A gap — an interval longer than 1.5 × the nominal interval — is reported
//! as a [`RecordEvent::Gap`] *before* the sample that follows it; it is never bridged silently.
//! Nothing is dropped without an event.

use crate::error::{FlightDataError, RowProblem};
use crate::mapping::{Channel, ChannelMap, Mapping, Source};
use std::collections::BTreeMap;
use std::io::Read;

/// Gap threshold: an interval longer than this multiple of the nominal interval is a gap.
pub const GAP_FACTOR: f64 = 1.5;

/// One sample in SI units. Optional channels are `None` when not mapped.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FlightSample {
    /// Time, s.
    pub t_s: f64,
    /// True airspeed, m/s.
    pub vt_mps: f64,
    /// Angle of attack as measured (vane), rad.
    pub alpha_rad: f64,
    /// Pitch attitude, rad.
    pub theta_rad: Option<f64>,
    /// Pitch rate, rad/s.
    pub q_rad_s: f64,
    /// Pitch acceleration, rad/s².
    pub qdot_rad_s2: Option<f64>,
    /// Body x specific force at the CG, m/s².
    pub ax_mps2: f64,
    /// Body z specific force at the CG, m/s² (≈ −g level).
    pub az_mps2: f64,
    /// Elevator, rad.
    pub de_rad: f64,
    /// Total thrust, N (0 when not mapped).
    pub thrust_n: f64,
    /// Thrust pitching moment, N·m, when mapped.
    pub thrust_moment_nm: Option<f64>,
    /// Dynamic pressure, Pa, when mapped.
    pub qbar_pa: Option<f64>,
    /// Air density, kg/m³, when mapped.
    pub rho_kgpm3: Option<f64>,
    /// Roll rate, rad/s (0 when not mapped).
    pub p_rad_s: f64,
    /// Yaw rate, rad/s (0 when not mapped).
    pub r_rad_s: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Roll inertia, kg·m² (0 when not mapped).
    pub Ixx_kgm2: f64,
    /// Pitch inertia, kg·m².
    pub Iyy_kgm2: f64,
    /// Yaw inertia, kg·m² (0 when not mapped).
    pub Izz_kgm2: f64,
    /// Product of inertia, kg·m² (0 when not mapped).
    pub Ixz_kgm2: f64,
    /// Reference area, m².
    pub S_m2: f64,
    /// Mean aerodynamic chord, m.
    pub cbar_m: f64,
    /// Thrust moment arm, m (0 when not mapped).
    pub thrust_arm_m: f64,
    /// Thrust inclination, rad (0 when not mapped).
    pub thrust_incidence_rad: f64,
    /// Reference speed, m/s, when mapped.
    pub v0_mps: Option<f64>,
    /// α-vane distance ahead of the CG, m (0 when not mapped).
    pub alpha_vane_x_m: f64,
}

/// A rejected row: its line number and the reason (naming the column).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Rejection {
    /// Line number in the file (header = 1).
    pub row: u64,
    /// Why, e.g. "column `alpha_rad`: blank value".
    pub reason: String,
}

/// What one data row produced.
#[derive(Debug, Clone, PartialEq)]
pub enum RecordEvent {
    /// A good sample.
    Sample {
        /// Line number.
        row: u64,
        /// The sample, SI.
        sample: FlightSample,
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
    map: ChannelMap,
}

/// The streaming reader. Iterate it for [`RecordEvent`]s; fatal problems are `Err` items.
pub struct FlightDataReader<R: Read> {
    file: String,
    csv: csv::Reader<R>,
    header_len: usize,
    time: Resolved,
    channels: BTreeMap<Channel, Resolved>,
    constants: BTreeMap<Channel, f64>,
    record: csv::StringRecord,
    last_t: Option<f64>,
    nominal_dt: Option<f64>,
    pending: Option<RecordEvent>,
    done: bool,
}

impl<R: Read> FlightDataReader<R> {
    /// Opens a reader on `source` (named `file` in messages) and checks the header against the
    /// mapping.
    ///
    /// # Errors
    /// [`FlightDataError::Csv`] if the header cannot be read, [`FlightDataError::MissingColumn`]
    /// for a mapped column not in the header.
    pub fn new(source: R, file: &str, mapping: &Mapping) -> Result<Self, FlightDataError> {
        let mut csv = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(source);
        let headers = csv
            .headers()
            .map_err(|e| FlightDataError::Csv {
                file: file.to_string(),
                row: 1,
                message: e.to_string(),
            })?
            .clone();
        let header_len = headers.len();
        let resolve = |key: &str, m: &ChannelMap| -> Result<Option<Resolved>, FlightDataError> {
            let Source::Columns(names) = &m.source else { return Ok(None) };
            let mut columns = Vec::with_capacity(names.len());
            for n in names {
                let idx = headers.iter().position(|h| h == n).ok_or_else(|| {
                    FlightDataError::MissingColumn {
                        file: file.to_string(),
                        channel: key.to_string(),
                        column: n.clone(),
                    }
                })?;
                columns.push(idx);
            }
            Ok(Some(Resolved { columns, names: names.clone(), map: m.clone() }))
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
            header_len,
            time,
            channels,
            constants,
            record: csv::StringRecord::new(),
            last_t: None,
            nominal_dt: mapping.nominal_dt_s,
            pending: None,
            done: false,
        })
    }

    /// The data file's name as used in messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    fn field(&self, r: &Resolved) -> Result<f64, RowProblem> {
        let mut sum = 0.0;
        for (idx, name) in r.columns.iter().zip(r.names.iter()) {
            let text = self.record.get(*idx).unwrap_or("");
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
            sum += v;
        }
        Ok(r.map.to_si(sum))
    }

    fn get(&self, ch: Channel) -> Result<Option<f64>, RowProblem> {
        if let Some(v) = self.constants.get(&ch) {
            return Ok(Some(*v));
        }
        match self.channels.get(&ch) {
            Some(r) => self.field(r).map(Some),
            None => Ok(None),
        }
    }

    fn positive(&self, ch: Channel, v: f64) -> Result<f64, RowProblem> {
        if v > 0.0 {
            Ok(v)
        } else {
            let column = match self.channels.get(&ch) {
                Some(r) => r.names.join("+"),
                None => format!("{} (constant)", ch.key()),
            };
            Err(RowProblem::Domain { column, reason: format!("{} must be > 0, got {v}", ch.key()) })
        }
    }

    fn parse_row(&self) -> Result<FlightSample, RowProblem> {
        if self.record.len() != self.header_len {
            return Err(RowProblem::FieldCount {
                expected: self.header_len,
                found: self.record.len(),
            });
        }
        let t_s = self.field(&self.time)?;
        if let Some(prev) = self.last_t {
            let column = self.time.names[0].clone();
            if t_s == prev {
                return Err(RowProblem::RepeatedTime { column, t_s });
            }
            if t_s < prev {
                return Err(RowProblem::NonMonotonicTime { column, t_s, prev_t_s: prev });
            }
        }
        // Required channels are guaranteed mapped by `Mapping` validation.
        let req = |ch: Channel| -> Result<f64, RowProblem> { Ok(self.get(ch)?.unwrap_or(0.0)) };
        let mut s = FlightSample {
            t_s,
            vt_mps: req(Channel::Vt)?,
            alpha_rad: req(Channel::Alpha)?,
            theta_rad: self.get(Channel::Theta)?,
            q_rad_s: req(Channel::Q)?,
            qdot_rad_s2: self.get(Channel::Qdot)?,
            ax_mps2: req(Channel::Ax)?,
            az_mps2: req(Channel::Az)?,
            de_rad: req(Channel::De)?,
            thrust_n: req(Channel::Thrust)?,
            thrust_moment_nm: self.get(Channel::ThrustMoment)?,
            qbar_pa: self.get(Channel::Qbar)?,
            rho_kgpm3: self.get(Channel::Rho)?,
            p_rad_s: req(Channel::P)?,
            r_rad_s: req(Channel::R)?,
            mass_kg: req(Channel::Mass)?,
            Ixx_kgm2: req(Channel::Ixx)?,
            Iyy_kgm2: req(Channel::Iyy)?,
            Izz_kgm2: req(Channel::Izz)?,
            Ixz_kgm2: req(Channel::Ixz)?,
            S_m2: req(Channel::S)?,
            cbar_m: req(Channel::Cbar)?,
            thrust_arm_m: req(Channel::ThrustArm)?,
            thrust_incidence_rad: req(Channel::ThrustIncidence)?,
            v0_mps: self.get(Channel::V0)?,
            alpha_vane_x_m: req(Channel::AlphaVaneX)?,
        };
        s.vt_mps = self.positive(Channel::Vt, s.vt_mps)?;
        s.mass_kg = self.positive(Channel::Mass, s.mass_kg)?;
        s.Iyy_kgm2 = self.positive(Channel::Iyy, s.Iyy_kgm2)?;
        s.S_m2 = self.positive(Channel::S, s.S_m2)?;
        s.cbar_m = self.positive(Channel::Cbar, s.cbar_m)?;
        if let Some(v) = s.qbar_pa {
            self.positive(Channel::Qbar, v)?;
        }
        if let Some(v) = s.rho_kgpm3 {
            self.positive(Channel::Rho, v)?;
        }
        Ok(s)
    }
}

impl<R: Read> Iterator for FlightDataReader<R> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(ev) = self.pending.take() {
            return Some(Ok(ev));
        }
        if self.done {
            return None;
        }
        let mut record = std::mem::take(&mut self.record);
        let more = self.csv.read_record(&mut record);
        let row = record.position().map(|p| p.line()).unwrap_or(0);
        self.record = record;
        match more {
            Err(e) => {
                self.done = true;
                let row = e.position().map(|p| p.line()).unwrap_or(row);
                Some(Err(FlightDataError::Csv {
                    file: self.file.clone(),
                    row,
                    message: e.to_string(),
                }))
            }
            Ok(false) => {
                self.done = true;
                None
            }
            Ok(true) => match self.parse_row() {
                Err(problem) => Some(Ok(RecordEvent::Rejected { row, problem })),
                Ok(sample) => {
                    let ev = RecordEvent::Sample { row, sample };
                    let mut out = ev.clone();
                    if let Some(prev) = self.last_t {
                        let dt = sample.t_s - prev;
                        match self.nominal_dt {
                            None => self.nominal_dt = Some(dt),
                            Some(nom) if dt > GAP_FACTOR * nom => {
                                self.pending = Some(ev);
                                out = RecordEvent::Gap { row, dt_s: dt, nominal_dt_s: nom };
                            }
                            Some(_) => {}
                        }
                    }
                    self.last_t = Some(sample.t_s);
                    Some(Ok(out))
                }
            },
        }
    }
}
