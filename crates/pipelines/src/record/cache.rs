//! A record read and screened once and held in memory, for the steps that read the same
//! record again and again after a job's own estimator: the cross-check panel's methods, the
//! regressor-noise test and the timing refits.
//!
//! Reading a text log and screening it for spikes is about half of a least-squares pass over
//! it (a six-axis replay of a 600-s, 100 Hz record: the reader 20 % of the wall, the screen
//! 20 %, the estimator 34 %; `perf`, docs/six-axis.md), and a replay's checks read the record
//! four to eight times. Held in memory, each later pass costs what its estimator costs: the
//! events come out exactly as the reader and the screen gave them (the screen is a function of
//! the record alone, the actuators, corrections and windows after it are applied again per
//! pass), so every estimate is bit-identical to a pass that reads the file
//! (`a_record_held_in_memory_replays_and_fits_bit_identically`).
//!
//! A record of more than [`MAX_EVENTS`] events is not held (a pass then reads the file, as
//! before); nor is one whose reading fails (the pass that reads it again reports the error).

use super::outliers::{self, ScreenNotes, SpikeScreen};
use super::{Corrections, RecordEvents};
use aeroident_io::{FlightDataReader, Mapping, RecordEvent};
use std::io::Read;
use std::sync::{Arc, Mutex};

/// Most events a record held in memory may have: 2.8 hours at 100 Hz, about 0.5 GB.
pub const MAX_EVENTS: usize = 1_000_000;

/// A record's events after its reader and spike screen, in memory, with the notes the two
/// wrote (module doc).
#[derive(Debug)]
pub struct ScreenedRecord {
    file: String,
    mapping: Arc<Mapping>,
    screen: Option<SpikeScreen>,
    events: Arc<[RecordEvent]>,
    /// The reader's notes and the screen's, as they stood at the end of the record.
    notes: [Vec<String>; 2],
}

impl ScreenedRecord {
    /// `reader` read to its end through the spike screen `screen` (settings checked by the
    /// caller, [`super::check_spike_screen`]). `None` for a record of more than
    /// [`MAX_EVENTS`] events or one whose reading fails: it is left to be read from its file.
    pub fn read<R: Read>(reader: FlightDataReader<R>, screen: Option<SpikeScreen>) -> Option<Self> {
        let file = reader.file().to_string();
        let (reader_notes, mapping) = (reader.notes(), reader.mapping());
        let screened = outliers::Screened::new(reader, screen).named_by(Arc::clone(&mapping));
        let screen_notes = screened.notes();
        let mut events = Vec::new();
        for event in screened {
            events.push(event.ok()?);
            if events.len() > MAX_EVENTS {
                return None;
            }
        }
        let snapshot = |n: &ScreenNotes| n.lock().map(|n| n.clone()).unwrap_or_default();
        let notes = [snapshot(&reader_notes), snapshot(&screen_notes)];
        Some(Self { file, mapping, screen, events: events.into(), notes })
    }

    /// The data file's name as used in messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The spike screen the record was read through.
    pub fn screen(&self) -> Option<SpikeScreen> {
        self.screen
    }

    /// Whether a pass asking for the spike screen `screen` may read this record.
    ///
    /// # Errors
    /// [`super::RecordError::Option`] (`spike-screen`) when the record was screened otherwise.
    pub fn check_screen(&self, screen: Option<SpikeScreen>) -> Result<(), super::RecordError> {
        if self.screen == screen {
            return Ok(());
        }
        let reason = "the record held in memory was screened with other settings".to_string();
        Err(super::RecordError::Option { option: "spike-screen", reason })
    }

    /// The record's events through the stages after the screen, as
    /// [`super::record_events`] gives them from the file: commanded surfaces through their
    /// actuators, `compat`'s corrections, the time `windows`.
    pub fn events(
        &self,
        compat: Option<&Corrections>,
        windows: &[crate::window::TimeWindow],
    ) -> RecordEvents<'static> {
        let events = Arc::clone(&self.events);
        let iter = (0..events.len()).map(move |i| Ok(events[i].clone()));
        let note = |n: &Vec<String>| -> ScreenNotes { Arc::new(Mutex::new(n.clone())) };
        let notes = [note(&self.notes[0]), note(&self.notes[1])];
        super::staged(Box::new(iter), &self.mapping, notes, compat, windows)
    }
}
