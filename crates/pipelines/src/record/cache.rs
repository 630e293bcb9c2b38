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
//! A replay of a CSV file reads it once: on a second thread while its own estimator takes the
//! events, keeping them for the steps after ([`ScreenedRecord::read_while_feeding`]).
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

/// One event of a record as its reader and screen give it.
type Event = Result<RecordEvent, aeroident_io::FlightDataError>;

/// Events sent to the feed at a time by [`ScreenedRecord::read_while_feeding`]'s reader: one
/// message per batch, not per event.
const BATCH: usize = 256;

/// Batches the reader may be ahead of the feed: it waits beyond them (bounded memory).
const BATCHES_AHEAD: usize = 64;

/// The events of `screened`, sent to the feed in batches of [`BATCH`] and kept: all of them
/// when the record ended with no error and within [`MAX_EVENTS`], else `None`. A feed that
/// stops taking them (its time windows ended, it diverged or was stopped) does not stop the
/// reading: the steps after it want the whole record.
fn keep_while_sending(
    screened: impl Iterator<Item = Event>,
    tx: &std::sync::mpsc::SyncSender<Vec<Event>>,
) -> Option<Vec<RecordEvent>> {
    let (mut kept, mut keeping, mut feeding) = (Vec::new(), true, true);
    let mut batch = Vec::with_capacity(BATCH);
    for event in screened {
        match &event {
            Ok(e) if keeping && kept.len() < MAX_EVENTS => kept.push(e.clone()),
            _ => (keeping, kept) = (false, Vec::new()),
        }
        if feeding {
            batch.push(event);
            if batch.len() == BATCH {
                feeding = tx.send(std::mem::replace(&mut batch, Vec::with_capacity(BATCH))).is_ok();
            }
        } else if !keeping {
            return None;
        }
    }
    if feeding && !batch.is_empty() {
        let _ = tx.send(batch);
    }
    keeping.then_some(kept)
}

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

    /// `reader` read through the spike screen `screen` (settings checked by the caller) on a
    /// thread of its own while `feed` takes its events on this one, through the stages after
    /// the screen as [`super::record_events`] sets them up (`compat`, `windows`); the events
    /// are kept as they pass. The reading and screening (about half of a least-squares pass)
    /// then overlap the estimator instead of preceding it, and the record is read once for the
    /// feed and every step after it.
    ///
    /// Returns `feed`'s result and the record held: `None` for a record of more than
    /// [`MAX_EVENTS`] events or one whose reading failed (the feed saw the error).
    pub fn read_while_feeding<R: Read + Send, T>(
        reader: FlightDataReader<R>,
        screen: Option<SpikeScreen>,
        stages: (Option<&Corrections>, &[crate::window::TimeWindow]),
        feed: impl FnOnce(RecordEvents<'_>) -> T,
    ) -> (T, Option<Self>) {
        let file = reader.file().to_string();
        let (reader_notes, mapping) = (reader.notes(), reader.mapping());
        let screened = outliers::Screened::new(reader, screen).named_by(Arc::clone(&mapping));
        let screen_notes = screened.notes();
        let notes = [Arc::clone(&reader_notes), Arc::clone(&screen_notes)];
        let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Event>>(BATCHES_AHEAD);
        let (fed, kept) = std::thread::scope(|scope| {
            let reading = scope.spawn(move || keep_while_sending(screened, &tx));
            let events = rx.into_iter().flatten();
            let fed = feed(super::staged(Box::new(events), &mapping, notes, stages.0, stages.1));
            // The feed has let go of the receiver: a reader not yet at the end goes on
            // reading (and keeping) without sending.
            (fed, reading.join().ok().flatten())
        });
        let snapshot = |n: &ScreenNotes| n.lock().map(|n| n.clone()).unwrap_or_default();
        let notes = [snapshot(&reader_notes), snapshot(&screen_notes)];
        let record =
            kept.map(|events| Self { file, mapping, screen, events: events.into(), notes });
        (fed, record)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn row(e: &RecordEvent) -> u64 {
        match e {
            RecordEvent::Sample { row, .. }
            | RecordEvent::Rejected { row, .. }
            | RecordEvent::Gap { row, .. } => *row,
        }
    }

    fn gaps(n: usize) -> Vec<Event> {
        let gap = |row| RecordEvent::Gap { row, dt_s: 1.0, nominal_dt_s: 0.01 };
        (0..n as u64).map(|row| Ok(gap(row))).collect()
    }

    /// A feed that lets go of the events before the end (a receiver dropped, so the first
    /// batch cannot be sent) leaves the reading going: every event is kept, in order. One it
    /// took to the end gets them all, in batches, and they are kept too.
    #[test]
    fn the_events_are_kept_whole_whether_or_not_the_feed_takes_them_all() {
        let n = 3 * BATCH + 7;
        let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Event>>(0);
        drop(rx);
        let kept = keep_while_sending(gaps(n).into_iter(), &tx).expect("kept");
        let rows: Vec<u64> = kept.iter().map(row).collect();
        assert_eq!(rows, (0..n as u64).collect::<Vec<_>>());
        let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Event>>(2 * n);
        let kept = keep_while_sending(gaps(n).into_iter(), &tx).expect("kept");
        drop(tx);
        let sent: Vec<u64> = rx.into_iter().flatten().map(|e| row(&e.unwrap())).collect();
        assert_eq!(sent, (0..n as u64).collect::<Vec<_>>());
        assert_eq!(kept.len(), n);
    }

    /// A reading error ends the keeping (the record is read again from its file by whoever
    /// needs it), whether the feed took the error or had let go before it.
    #[test]
    fn a_reading_error_keeps_nothing() {
        let error = || {
            let source = std::io::Error::other("disk");
            Err(aeroident_io::FlightDataError::Io { file: "f.csv".into(), source })
        };
        for capacity in [0, 64] {
            let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<Event>>(capacity);
            if capacity == 0 {
                drop(rx);
            }
            let events = gaps(2 * BATCH).into_iter().chain(std::iter::once(error()));
            assert!(keep_while_sending(events, &tx).is_none(), "capacity {capacity}");
        }
    }
}
