//! Time windows of a record (`replay --window 3630:3660 --window 3700:3725`): the manoeuvres of
//! a long flight log, each window its own manoeuvre (its own initial state), the rest not used.
//!
//! The stage sits between the reader and the estimators. A sample inside a window passes; the
//! first sample of a window after another is preceded by a [`RecordEvent::Gap`], so every
//! consumer (the batch fit's manoeuvre split, the online estimators' re-initialisation) starts
//! a new manoeuvre there exactly as at a gap in the record. A sample outside every window is
//! not used and counted ([`Windowed::note`] says how many), never silently dropped; a rejected
//! row or a gap is passed only while inside a window (outside, it concerns no used sample).

use aeroident_io::{FlightDataError, RecordEvent};

/// A closed time window `[start_s, end_s]` of record time, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeWindow {
    /// First time, s.
    pub start_s: f64,
    /// Last time, s.
    pub end_s: f64,
}

impl TimeWindow {
    /// Parses `START:END` (record time, s).
    ///
    /// # Errors
    /// A message naming the text when it is not two finite numbers with `START < END`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = || format!("`{text}`: give START:END in record seconds with START < END");
        let (a, b) = text.split_once(':').ok_or_else(bad)?;
        let (start_s, end_s) = (
            a.trim().parse::<f64>().map_err(|_| bad())?,
            b.trim().parse::<f64>().map_err(|_| bad())?,
        );
        if !(start_s.is_finite() && end_s.is_finite() && start_s < end_s) {
            return Err(bad());
        }
        Ok(Self { start_s, end_s })
    }

    fn contains(&self, t_s: f64) -> bool {
        (self.start_s..=self.end_s).contains(&t_s)
    }
}

/// Checks that `windows` are in time order and do not overlap. Touching windows (one's end
/// the next's start, `0:10` then `10:20`) do not overlap: a sample at the instant they share
/// is the first one's, and the next starts a new manoeuvre after it.
///
/// # Errors
/// A message naming the two windows that overlap or are out of order.
pub fn check_windows(windows: &[TimeWindow]) -> Result<(), String> {
    for w in windows.windows(2) {
        if w[1].start_s < w[0].end_s {
            return Err(format!(
                "windows {}:{} and {}:{} overlap or are out of time order",
                w[0].start_s, w[0].end_s, w[1].start_s, w[1].end_s
            ));
        }
    }
    Ok(())
}

/// The window stage over a reader's events (module doc). With no windows it passes everything.
pub struct Windowed<I> {
    inner: I,
    windows: Vec<TimeWindow>,
    /// The window of the last sample, `None` outside all (or before the first sample).
    current: Option<usize>,
    /// Last used sample's time, s (the gap before the next window is measured from it).
    last_used_t_s: Option<f64>,
    /// Time of the first sample read, used or not, s.
    first_seen_t_s: Option<f64>,
    /// Time of the last sample read, used or not, s.
    last_seen_t_s: Option<f64>,
    /// Interval between the last two samples read, s: the nominal interval of the gap event
    /// (of the record, not of the used samples, so a window of one sample has one too).
    last_dt_s: f64,
    /// The sample that follows the gap event just returned.
    pending: Option<RecordEvent>,
    used: usize,
    outside: usize,
    /// Samples used per window.
    per_window: Vec<usize>,
    /// Per window, the last sample's time before its start and the first after its end, s: a
    /// window that used no sample but has both lies in a gap of the record.
    around: Vec<(Option<f64>, Option<f64>)>,
    /// Rejected rows not passed on (outside every window, or before any sample placed the
    /// stage in one): their count and the first few (row, reason), for a record whose every
    /// row was rejected, which otherwise reads "no usable samples (0 rows rejected)".
    unplaced: (usize, Vec<(u64, String)>),
}

/// How many unplaced rejections [`Windowed::unplaced_rejections`] keeps the reasons of.
const UNPLACED_KEPT: usize = 3;

impl<I> Windowed<I> {
    /// The stage over `inner` with `windows` (checked with [`check_windows`] by the caller).
    pub fn new(inner: I, windows: Vec<TimeWindow>) -> Self {
        Self {
            inner,
            current: None,
            last_used_t_s: None,
            first_seen_t_s: None,
            last_seen_t_s: None,
            last_dt_s: f64::NAN,
            pending: None,
            used: 0,
            outside: 0,
            per_window: vec![0; windows.len()],
            around: vec![(None, None); windows.len()],
            windows,
            unplaced: (0, Vec::new()),
        }
    }

    /// The rejected rows this stage did not pass on, when no sample at all was read (every
    /// row rejected): their count and the first few (row, reason). `None` when some sample was
    /// read (the rejections then lay outside the windows, and [`Self::missed`] says why
    /// nothing was used) or none was rejected.
    pub fn unplaced_rejections(&self) -> Option<(usize, &[(u64, String)])> {
        let (n, first) = &self.unplaced;
        (self.first_seen_t_s.is_none() && *n > 0).then_some((*n, first.as_slice()))
    }

    /// Notes `t_s`, a sample's time, as before or after each window.
    fn bracket(&mut self, t_s: f64) {
        for (w, (before, after)) in self.windows.iter().zip(&mut self.around) {
            if t_s < w.start_s {
                *before = Some(t_s);
            } else if t_s > w.end_s && after.is_none() {
                *after = Some(t_s);
            }
        }
    }

    /// The windows that used no sample: those inside the record's time span, each with the
    /// gap of the record it falls in (`"a:b (no sample from x to y s)"`), and those outside
    /// it (`"a:b"`).
    fn empty_windows(&self) -> (Vec<String>, Vec<String>) {
        let (mut in_gap, mut outside) = (Vec::new(), Vec::new());
        for ((w, &n), around) in self.windows.iter().zip(&self.per_window).zip(&self.around) {
            match (n, around) {
                (0, (Some(a), Some(b))) => {
                    in_gap.push(format!("{}:{} (no sample from {a} to {b} s)", w.start_s, w.end_s))
                }
                (0, _) => outside.push(format!("{}:{}", w.start_s, w.end_s)),
                _ => {}
            }
        }
        (in_gap, outside)
    }

    /// What the windows did, for the summary's warnings: `None` without windows.
    pub fn note(&self) -> Option<String> {
        if self.windows.is_empty() {
            return None;
        }
        let list: Vec<String> =
            self.windows.iter().map(|w| format!("{}–{} s", w.start_s, w.end_s)).collect();
        let mut note = format!(
            "time windows {} (each its own manoeuvre): {} samples used, {} outside the windows not used",
            list.join(", "),
            self.used,
            self.outside
        );
        let (in_gap, outside) = self.empty_windows();
        if self.used > 0 && !in_gap.is_empty() {
            let s = if in_gap.len() > 1 { "s" } else { "" };
            note.push_str(&format!(
                "; window{s} {} matched no sample: inside the record's time span, in a gap of the record",
                in_gap.join(", ")
            ));
        }
        if let (Some(first), Some(last)) = (self.first_seen_t_s, self.last_seen_t_s)
            && self.used > 0
            && !outside.is_empty()
        {
            let s = if outside.len() > 1 { "s" } else { "" };
            note.push_str(&format!(
                "; window{s} {} matched no sample: outside the record's time span, {first} to {last} s",
                outside.join(", ")
            ));
        }
        Some(note)
    }
}

impl<I> Windowed<I> {
    /// Why no sample was used, when the record had samples but none in any window: the
    /// windows and the record's time span (the first and last sample read). `None` when a
    /// sample was used, without windows, or when no sample was read at all.
    pub fn missed(&self) -> Option<String> {
        if self.windows.is_empty() || self.used > 0 {
            return None;
        }
        let (first, last) = (self.first_seen_t_s?, self.last_seen_t_s?);
        let (in_gap, outside) = self.empty_windows();
        let mut why = Vec::new();
        if !outside.is_empty() {
            let (s, lie) = if outside.len() > 1 { ("s", "lie") } else { ("", "lies") };
            why.push(format!(
                "the time window{s} {} {lie} outside the record's time span, {first} to {last} s (its first and last sample)",
                outside.join(", ")
            ));
        }
        if !in_gap.is_empty() {
            let (s, lie) = if in_gap.len() > 1 { ("s", "lie") } else { ("", "lies") };
            why.push(format!(
                "the time window{s} {} {lie} inside the record's time span, {first} to {last} s, but in a gap of the record",
                in_gap.join(", ")
            ));
        }
        Some(format!("{}: no sample was used", why.join("; ")))
    }
}

impl<I: Iterator<Item = Result<RecordEvent, FlightDataError>>> Iterator for Windowed<I> {
    type Item = Result<RecordEvent, FlightDataError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.windows.is_empty() {
            return self.inner.next();
        }
        if let Some(e) = self.pending.take() {
            return Some(Ok(e));
        }
        loop {
            let event = match self.inner.next()? {
                Ok(e) => e,
                Err(e) => return Some(Err(e)),
            };
            let RecordEvent::Sample { row, sample } = &event else {
                if self.current.is_some() {
                    return Some(Ok(event));
                }
                if let RecordEvent::Rejected { row, problem } = &event {
                    self.unplaced.0 += 1;
                    if self.unplaced.1.len() < UNPLACED_KEPT {
                        self.unplaced.1.push((*row, problem.to_string()));
                    }
                }
                continue;
            };
            self.first_seen_t_s.get_or_insert(sample.t_s);
            let t_s = sample.t_s;
            self.bracket(t_s);
            if let Some(t0) = self.last_seen_t_s.replace(sample.t_s) {
                self.last_dt_s = sample.t_s - t0;
            }
            let Some(k) = self.windows.iter().position(|w| w.contains(sample.t_s)) else {
                self.current = None;
                self.outside += 1;
                continue;
            };
            let entering = self.current != Some(k);
            self.current = Some(k);
            self.used += 1;
            self.per_window[k] += 1;
            let previous = self.last_used_t_s.replace(sample.t_s);
            let Some(t0) = previous else { return Some(Ok(event)) };
            let dt_s = sample.t_s - t0;
            if !entering {
                return Some(Ok(event));
            }
            // A new window: a manoeuvre boundary, as a gap in the record is.
            let gap = RecordEvent::Gap { row: *row, dt_s, nominal_dt_s: self.last_dt_s };
            self.pending = Some(event);
            return Some(Ok(gap));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::AirDataSample;

    fn sample(row: u64, t_s: f64) -> Result<RecordEvent, FlightDataError> {
        Ok(RecordEvent::Sample { row, sample: AirDataSample { t_s, ..Default::default() } })
    }

    fn times(events: &[RecordEvent]) -> Vec<String> {
        events
            .iter()
            .map(|e| match e {
                RecordEvent::Sample { sample, .. } => format!("{}", sample.t_s),
                RecordEvent::Gap { dt_s, nominal_dt_s, .. } => format!("gap {dt_s} {nominal_dt_s}"),
                RecordEvent::Rejected { row, .. } => format!("rejected {row}"),
            })
            .collect()
    }

    /// Samples 0..10 s at 1 s, windows [2, 4] and [7, 8]: 5 used, 6 outside; a gap of 3 s
    /// (nominal 1 s) before 7 s; the rejected row at 5.5 s (outside) is not passed, the one at
    /// 3.5 s is.
    #[test]
    fn windows_keep_their_samples_and_start_a_manoeuvre_each() {
        let mut input: Vec<_> = (0..=10).map(|k| sample(k + 2, k as f64)).collect();
        let rejected = |row| {
            Ok(RecordEvent::Rejected {
                row,
                problem: aeroident_io::RowProblem::Blank { column: "q".into() },
            })
        };
        input.insert(4, rejected(100));
        input.insert(7, rejected(101));
        let windows = vec![TimeWindow::parse("2:4").unwrap(), TimeWindow::parse(" 7 : 8").unwrap()];
        check_windows(&windows).unwrap();
        let mut w = Windowed::new(input.into_iter(), windows);
        let out: Vec<RecordEvent> = w.by_ref().map(Result::unwrap).collect();
        assert_eq!(times(&out), ["2", "3", "rejected 100", "4", "gap 3 1", "7", "8"]);
        assert!(w.note().unwrap().contains("5 samples used, 6 outside"), "{:?}", w.note());
    }

    #[test]
    fn bad_windows_are_named() {
        assert!(TimeWindow::parse("5:2").unwrap_err().contains("`5:2`"));
        assert!(TimeWindow::parse("5").is_err() && TimeWindow::parse("a:3").is_err());
        let w = [TimeWindow::parse("0:5").unwrap(), TimeWindow::parse("4:9").unwrap()];
        assert!(check_windows(&w).unwrap_err().contains("overlap"));
    }

    /// A window inside the record's time span that falls in a gap of it (samples at 0–3 s
    /// and 7–10 s, window [4, 6]) is said to be so, not "outside the span"; beside a window that
    /// matches samples, the note names the one that matched none and why.
    #[test]
    fn a_window_in_a_gap_is_named_as_such() {
        let times_s = [0.0, 1.0, 2.0, 3.0, 7.0, 8.0, 9.0, 10.0];
        let input = || times_s.iter().enumerate().map(|(k, &t)| sample(k as u64 + 2, t));
        let gap = vec![TimeWindow::parse("4:6").unwrap()];
        let mut w = Windowed::new(input().collect::<Vec<_>>().into_iter(), gap);
        assert_eq!(w.by_ref().count(), 0);
        let missed = w.missed().unwrap();
        assert!(missed.contains("4:6 (no sample from 3 to 7 s) lies inside"), "{missed}");
        assert!(!missed.contains("outside"), "{missed}");
        let two = vec![
            TimeWindow::parse("1:2").unwrap(),
            TimeWindow::parse("4:6").unwrap(),
            TimeWindow::parse("20:30").unwrap(),
        ];
        let mut w = Windowed::new(input().collect::<Vec<_>>().into_iter(), two);
        assert_eq!(w.by_ref().count(), 2);
        assert!(w.missed().is_none());
        let note = w.note().unwrap();
        assert!(
            note.contains("window 4:6 (no sample from 3 to 7 s) matched no sample: inside"),
            "{note}"
        );
        assert!(
            note.contains(
                "window 20:30 matched no sample: outside the record's time span, 0 to 10 s"
            ),
            "{note}"
        );
    }

    /// Touching windows [2, 4] and [4, 6] over samples 0..10 s at 1 s are accepted: the
    /// sample at 4 s is used once (the first window's), the second window starts a manoeuvre
    /// at 5 s; 5 used, 6 outside.
    #[test]
    fn touching_windows_are_accepted() {
        let input: Vec<_> = (0..=10).map(|k| sample(k + 2, k as f64)).collect();
        let windows = vec![TimeWindow::parse("2:4").unwrap(), TimeWindow::parse("4:6").unwrap()];
        check_windows(&windows).unwrap();
        let mut w = Windowed::new(input.into_iter(), windows);
        let out: Vec<RecordEvent> = w.by_ref().map(Result::unwrap).collect();
        assert_eq!(times(&out), ["2", "3", "4", "gap 1 1", "5", "6"]);
        assert!(w.note().unwrap().contains("5 samples used, 6 outside"), "{:?}", w.note());
    }
}
