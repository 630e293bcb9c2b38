//! The record stage, below every job: a recorded flight from its reader to the samples the
//! estimators, the batch fits, the compatibility check and the structure selection see.
//!
//! `read → map → screen → correct → window → manoeuvres`:
//! - **read, map**: an [`aeroident_io::FlightDataReader`] (any log format, through the
//!   mapping) yields [`RecordEvent`]s: SI samples at the CG, counted rejections and gaps;
//! - **screen**: isolated spikes rejected ([`outliers`]);
//! - **actuate**: a surface mapped as a command passed through its declared actuator
//!   ([`actuated`]);
//! - **correct**: a compatibility check's biases, scale factors and time shifts undone, a
//!   missing sideslip filled ([`corrections`]);
//! - **window**: the time windows of the record, each a manoeuvre ([`crate::window`]);
//! - **manoeuvres**: for the whole-record consumers, the events gathered into manoeuvres split
//!   at the gaps ([`read_records`]).
//!
//! [`duplicates`] refuses a record given twice (same file or same content) unless asked;
//! [`tally`] names a file of several that gives no sample, and warns of one most of whose rows
//! were rejected.
//! [`needs`] says what a model structure needs from a record's samples. Every error of the
//! stage is a [`RecordError`], naming the file, the option as the command line spells it, or
//! the model.

pub mod actuated;
pub mod cache;
pub mod corrections;
pub mod duplicates;
pub mod needs;
pub mod outliers;
pub mod tally;

pub use corrections::{Corrected, Corrections};
pub use needs::unsupported;

use aeroident_estimators::AirDataSample;
use aeroident_io::{FlightDataError, FlightDataReader, RecordEvent, Rejection, RejectionLog};
use std::io::Read;

/// Errors of the record stage and of the whole-record analyses on it (compatibility check,
/// structure selection).
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// Reading the record failed fatally, or it has no usable sample.
    #[error(transparent)]
    Data(#[from] FlightDataError),
    /// An option is invalid; `option` is its name as the command line spells it, without the
    /// leading `--`.
    #[error("option `--{option}`: {reason}")]
    Option {
        /// Option name.
        option: &'static str,
        /// Why.
        reason: String,
    },
    /// The record does not support what is asked of it (a model, a selection, a check).
    #[error("{0}")]
    Model(String),
}

/// The events of a record as the estimators see them: read, screened for isolated spikes when
/// `screen` is given ([`outliers`]), commanded surfaces passed through their actuators
/// ([`actuated`]), corrected by a compatibility check's corrections when
/// given ([`Corrected`], over the whole record: its time shifts reach across
/// window edges), then cut to the time windows ([`crate::window`]).
pub fn record_events<'a, R: Read + 'a>(
    reader: FlightDataReader<R>,
    screen: Option<outliers::SpikeScreen>,
    compat: Option<&Corrections>,
    windows: &[crate::window::TimeWindow],
) -> RecordEvents<'a> {
    let reader_notes = reader.notes();
    let mapping = reader.mapping();
    let screened =
        outliers::Screened::new(reader, screen).named_by(std::sync::Arc::clone(&mapping));
    let screen_notes = screened.notes();
    staged(Box::new(screened), &mapping, [reader_notes, screen_notes], compat, windows)
}

/// The stages after the spike screen (actuators, corrections, windows) over `screened`, the
/// events of a record read through `mapping` and screened, whose reader and screen notes are
/// `notes`: [`record_events`]'s second half, and how a record held in memory
/// ([`cache::ScreenedRecord`]) is read again.
fn staged<'a>(
    screened: Box<dyn Iterator<Item = Result<RecordEvent, FlightDataError>> + 'a>,
    mapping: &aeroident_io::Mapping,
    notes: [outliers::ScreenNotes; 2],
    compat: Option<&Corrections>,
    windows: &[crate::window::TimeWindow],
) -> RecordEvents<'a> {
    let actuators: Vec<_> = mapping.actuators.iter().map(|(c, a)| (*c, *a)).collect();
    let mut actuator_notes: Vec<String> =
        actuators.iter().map(|(c, a)| actuated::note(*c, a)).collect();
    // Thrust from a law is an input every estimator takes as measured: the summary says so.
    actuator_notes.extend(
        mapping.thrust_model.map(|law| {
            format!("{}: every estimator sees this thrust as if measured", law.describe())
        }),
    );
    let mut saturation = None;
    let actuated: Box<dyn Iterator<Item = Result<RecordEvent, FlightDataError>> + 'a> =
        if actuators.is_empty() {
            screened
        } else {
            let a = actuated::Actuated::new(screened, actuators);
            saturation = Some(a.saturation());
            Box::new(a)
        };
    let mut sideslip = None;
    let events: Box<dyn Iterator<Item = Result<RecordEvent, FlightDataError>> + 'a> = match compat {
        Some(c) => {
            let corrected = Corrected::new(actuated, c.clone());
            sideslip = Some((c.clone(), corrected.sideslip_cover()));
            Box::new(corrected)
        }
        None => actuated,
    };
    let events = crate::window::Windowed::new(events, windows.to_vec());
    RecordEvents { events, notes, actuator_notes, saturation, sideslip }
}

/// [`record_events`]: the events, and the notes of the stages they went through.
pub struct RecordEvents<'a> {
    events: crate::window::Windowed<
        Box<dyn Iterator<Item = Result<RecordEvent, FlightDataError>> + 'a>,
    >,
    /// The warnings of the reader ([`FlightDataReader::notes`]) and of the spike screen.
    notes: [outliers::ScreenNotes; 2],
    /// What the actuator stage does, one line per commanded surface, and the thrust law when
    /// the mapping gives one.
    actuator_notes: Vec<String>,
    /// How often each actuator held its surface ([`actuated::Saturation`]), when any is declared.
    saturation: Option<actuated::SaturationCounts>,
    /// The corrections applied and how much of the record their reconstructed sideslip
    /// covered ([`Corrections::cover_warning`]).
    sideslip: Option<(Corrections, corrections::SideslipCover)>,
}

impl RecordEvents<'_> {
    /// The warnings of the stages so far: the reader's (an implausible time unit), what the
    /// time windows did, the runs the spike screen saw but did not reject, and the commanded
    /// surfaces passed through their actuators.
    pub fn notes(&self) -> Vec<String> {
        let [reader, screen] = &self.notes;
        let get = |n: &outliers::ScreenNotes| n.lock().map(|n| n.clone()).unwrap_or_default();
        let actuated = self.actuator_notes.iter().cloned();
        let held: Vec<String> = self.saturation.as_ref().map_or_else(Vec::new, |c| {
            let c = c.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            c.iter().filter_map(|(ch, a, n)| n.warning(*ch, a)).collect()
        });
        let uncovered = self.sideslip.as_ref().and_then(|(c, cover)| {
            c.cover_warning(*cover.lock().unwrap_or_else(std::sync::PoisonError::into_inner))
        });
        get(reader)
            .into_iter()
            .chain(self.events.note())
            .chain(get(screen))
            .chain(actuated)
            .chain(held)
            .chain(uncovered)
            .collect()
    }
}

impl RecordEvents<'_> {
    /// `error` (the end of a replay of `file`), or in place of a "no usable samples" one the
    /// `--window` error saying that the windows missed the record ([`crate::window::Windowed::missed`]).
    /// With windows and every row rejected, the error counts and names the rejections the
    /// windows could not place, as it would without windows (not "0 rows rejected").
    pub fn explain_no_samples(&self, file: &str, error: RecordError) -> RecordError {
        match (&error, self.events.missed(), self.events.unplaced_rejections()) {
            (RecordError::Data(FlightDataError::NoSamples { .. }), Some(why), _) => {
                RecordError::Option { option: "window", reason: format!("{file}: {why}") }
            }
            (
                RecordError::Data(FlightDataError::NoSamples { file, rejected: 0, .. }),
                None,
                Some((n, first)),
            ) => RecordError::Data(FlightDataError::NoSamples {
                file: file.clone(),
                rejected: n,
                first: first.to_vec(),
            }),
            _ => error,
        }
    }

    /// [`crate::window::Windowed::missed`] of these events.
    pub fn windows_missed(&self) -> Option<String> {
        self.events.missed()
    }

    /// [`crate::window::Windowed::unplaced_rejections`] of these events.
    pub fn unplaced_rejections(&self) -> Option<(usize, &[(u64, String)])> {
        self.events.unplaced_rejections()
    }
}

impl Iterator for RecordEvents<'_> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.events.next()
    }
}

/// The median of the positive intervals between consecutive samples of each stretch of
/// `stretches` (manoeuvres, or a record's first samples), s: a gap, a repeated time stamp or
/// a rejected row does not move it. `None` without two samples in one stretch.
pub fn median_interval_s<'a>(
    stretches: impl IntoIterator<Item = &'a [AirDataSample]>,
) -> Option<f64> {
    let mut d: Vec<f64> = stretches
        .into_iter()
        .flat_map(|m| m.windows(2).map(|w| w[1].t_s - w[0].t_s))
        .filter(|v| *v > 0.0)
        .collect();
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    Some(*d.select_nth_unstable_by(mid, f64::total_cmp).1)
}
/// The spike screen's settings must be sane ([`outliers::SpikeScreen::check`]).
pub fn check_spike_screen(screen: Option<&outliers::SpikeScreen>) -> Result<(), RecordError> {
    screen
        .map_or(Ok(()), outliers::SpikeScreen::check)
        .map_err(|reason| RecordError::Option { option: "spike-screen", reason })
}

/// Where a manoeuvre starts: its record file and first row (as the reader counts rows, the
/// header line 1).
pub type Origin = (String, u64);

/// A whole record, split into manoeuvres at its gaps.
#[derive(Debug)]
pub struct Manoeuvres {
    /// The samples of each manoeuvre, in time order; none empty, none of one sample.
    pub manoeuvres: Vec<Vec<AirDataSample>>,
    /// Where each manoeuvre starts.
    pub origins: Vec<Origin>,
    /// The rejected rows, gaps and one-sample manoeuvres (bounded, counted per kind).
    pub rejections: RejectionLog,
    /// Rows read (accepted and rejected).
    pub read: usize,
    /// Rows rejected (gaps count none).
    pub rejected: usize,
    /// What the time windows did and the runs the spike screen saw but did not reject
    /// ([`RecordEvents::notes`]), one warning each.
    pub notes: Vec<String>,
}

/// Reads the whole record, splitting it into manoeuvres at the reader's gap events, with a
/// compatibility check's corrections applied when given.
///
/// # Errors
/// Fatal data errors; no usable sample.
pub fn read_manoeuvres<R: Read>(
    reader: FlightDataReader<R>,
    compat: Option<&Corrections>,
    windows: &[crate::window::TimeWindow],
) -> Result<Manoeuvres, RecordError> {
    read_records(vec![reader], Some(outliers::SpikeScreen::default()), compat, windows)
}

/// [`read_manoeuvres`] over several records of one aircraft (same mapping), each file starting
/// a manoeuvre of its own; with more than one file every rejection names its file.
///
/// # Errors
/// As [`read_manoeuvres`]; no usable sample in any file.
pub fn read_records<R: Read>(
    readers: Vec<FlightDataReader<R>>,
    screen: Option<outliers::SpikeScreen>,
    compat: Option<&Corrections>,
    windows: &[crate::window::TimeWindow],
) -> Result<Manoeuvres, RecordError> {
    crate::window::check_windows(windows)
        .map_err(|reason| RecordError::Option { option: "window", reason })?;
    check_spike_screen(screen.as_ref())?;
    let sources = readers.into_iter().map(|r| {
        let file = r.file().to_string();
        (record_events(r, screen, compat, windows), file)
    });
    read_events(sources.collect())
}

/// [`read_records`] of a record held in memory ([`cache::ScreenedRecord`]): the same
/// manoeuvres, rejections and notes as from its file with its spike screen.
///
/// # Errors
/// As [`read_records`].
pub fn read_cached(
    record: &cache::ScreenedRecord,
    compat: Option<&Corrections>,
    windows: &[crate::window::TimeWindow],
) -> Result<Manoeuvres, RecordError> {
    crate::window::check_windows(windows)
        .map_err(|reason| RecordError::Option { option: "window", reason })?;
    read_events(vec![(record.events(compat, windows), record.file().to_string())])
}

/// [`read_records`] over each file's events (its stages set up), with the file's name.
fn read_events(sources: Vec<(RecordEvents<'_>, String)>) -> Result<Manoeuvres, RecordError> {
    let files: Vec<String> = sources.iter().map(|(_, f)| f.clone()).collect();
    let named = files.len() > 1;
    let mut manoeuvres: Vec<Vec<AirDataSample>> = vec![Vec::new()];
    // Each manoeuvre's first row, file prefix and file, to name a manoeuvre too short.
    let first_file = files.first().cloned().unwrap_or_default();
    let mut starts: Vec<(u64, String, String)> = vec![(0, String::new(), first_file)];
    let mut rejections = RejectionLog::default();
    let (mut read, mut rejected) = (0usize, 0usize);
    let mut notes = Vec::new();
    let mut missed = Vec::new();
    let mut unplaced: Vec<(u64, String)> = Vec::new();
    for ((mut events, _), file) in sources.into_iter().zip(&files) {
        let prefix = if named { format!("{file}: ") } else { String::new() };
        let mut tally = tally::FileTally::default();
        for event in events.by_ref() {
            let event = event?;
            tally.count(&event);
            match event {
                RecordEvent::Sample { row, sample } => {
                    read += 1;
                    if let (Some(m), Some(start)) = (manoeuvres.last_mut(), starts.last_mut()) {
                        if m.is_empty() {
                            *start = (row, prefix.clone(), file.clone());
                        }
                        m.push(sample);
                    }
                }
                RecordEvent::Rejected { row, problem } => {
                    read += 1;
                    rejected += 1;
                    let reason = format!("{prefix}{problem}");
                    rejections.push(problem.kind(), Rejection { row, reason });
                }
                RecordEvent::Gap { row, dt_s, nominal_dt_s } => {
                    rejections.push("gap", Rejection {
                        row,
                        reason: format!(
                            "{prefix}gap: {dt_s} s before this row (nominal {nominal_dt_s} s); a new manoeuvre with its own initial state"
                        ),
                    });
                    manoeuvres.push(Vec::new());
                    starts.push((row, prefix.clone(), file.clone()));
                }
            }
        }
        notes.extend(events.notes().into_iter().map(|n| format!("{prefix}{n}")));
        if named && let Some(why) = tally.empty_reason(file) {
            return Err(RecordError::Option {
                option: "and",
                reason: format!("{why}: fix its mapping or leave it out"),
            });
        }
        notes.extend(tally.warning(file));
        missed.push(events.windows_missed().map(|why| format!("{file}: {why}")));
        if let Some((n, first)) = events.unplaced_rejections() {
            // Every row of this file rejected before a window could place it.
            rejected += n;
            unplaced.extend(first.iter().map(|(row, why)| (*row, format!("{prefix}{why}"))));
        }
        manoeuvres.push(Vec::new());
        starts.push((0, String::new(), String::new()));
    }
    let (lone, origins) = reject_lone_samples(&mut manoeuvres, &starts, &mut rejections);
    rejected += lone.len();
    if manoeuvres.is_empty()
        && let Some(why) = missed.into_iter().collect::<Option<Vec<String>>>()
    {
        // Every file's samples all lie outside the windows: the windows are the cause.
        return Err(RecordError::Option { option: "window", reason: why.join("; ") });
    }
    if manoeuvres.is_empty() {
        // Lone samples first: the gaps before them say nothing of why nothing is left.
        let mut first = lone;
        first.extend(rejections.first(3));
        first.extend(unplaced);
        first.truncate(3);
        return Err(aeroident_io::FlightDataError::NoSamples {
            file: files.join(", "),
            rejected,
            first,
        }
        .into());
    }
    Ok(Manoeuvres { manoeuvres, origins, rejections, read, rejected, notes })
}

/// Removes the empty manoeuvres and rejects each manoeuvre of one sample (a lone sample between
/// two gaps, or alone in a time window): output error simulates every manoeuvre from its first
/// sample, so one sample holds nothing to fit. Each is listed in `rejections` by its row and file
/// prefix (`starts`, parallel to `manoeuvres`). Returns the rejections (row, reason).
fn reject_lone_samples(
    manoeuvres: &mut Vec<Vec<AirDataSample>>,
    starts: &[(u64, String, String)],
    rejections: &mut RejectionLog,
) -> (Vec<(u64, String)>, Vec<Origin>) {
    let mut lone = Vec::new();
    let mut kept = Vec::with_capacity(manoeuvres.len());
    let mut origins = Vec::with_capacity(manoeuvres.len());
    for (m, (row, prefix, file)) in manoeuvres.drain(..).zip(starts) {
        if m.len() == 1 {
            let reason = format!(
                "{prefix}a manoeuvre of one sample (alone between gaps or in its time window): output error simulates each manoeuvre from its first sample and needs at least two"
            );
            rejections
                .push("one-sample manoeuvre", Rejection { row: *row, reason: reason.clone() });
            lone.push((*row, reason));
        } else if !m.is_empty() {
            kept.push(m);
            origins.push((file.clone(), *row));
        }
    }
    *manoeuvres = kept;
    (lone, origins)
}
