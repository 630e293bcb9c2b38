//! Judging time stamps by the rows after them (the parent module's doc, "Bad time stamps"):
//! the rows after a jump in time, and the record's first rows, are held until the rows that
//! follow say whether they are the record's own time or a short run of bad time stamps.

use super::{FlightDataReader, GAP_FACTOR, HELD_ROWS_MAX, RecordEvent, TIME_RUN_MAX};
use crate::error::{FlightDataError, RowProblem};
use aeroident_estimators::AirDataSample;
use std::io::Read;

/// A row held while time stamps are judged.
// Few are held (at most HELD_ROWS_MAX), for a few rows: not boxed, as RecordEvent is not.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub(super) enum Entry {
    /// A good sample; `jump`: its time is further ahead of the sample before it than a gap
    /// (it starts a run that rows going on from before it would reject).
    Sample { row: u64, sample: AirDataSample, jump: bool },
    /// A rejected row, with its time when it could be read.
    Rejected { row: u64, problem: RowProblem, t_s: Option<f64> },
}

impl Entry {
    fn sample_time(&self) -> Option<f64> {
        self.timed_row().map(|(t, _)| t)
    }

    /// A sample's time and row.
    fn timed_row(&self) -> Option<(f64, u64)> {
        match self {
            Self::Sample { sample, row, .. } => Some((sample.t_s, *row)),
            Self::Rejected { .. } => None,
        }
    }
}

impl<R: Read> FlightDataReader<R> {
    /// The events of data row `row`: its sample is judged by its time against the samples
    /// before it ([`Self::take_sample`]); a row that cannot be used is rejected, naming a bad
    /// time first (a time is checked before the values, as it is judged first).
    pub(super) fn event(&mut self, row: u64) {
        let t_s = match self.row_time() {
            Ok(t) => t,
            Err(problem) => return self.push_rejected(row, problem, None),
        };
        match self.parse_row(t_s) {
            Ok(sample) => self.take_sample(row, sample),
            Err(problem) => {
                let problem = match self.opening {
                    true => problem,
                    false => self.time_problem(t_s).err().unwrap_or(problem),
                };
                self.push_rejected(row, problem, Some(t_s));
            }
        }
    }

    /// The end of the record: the record's start, if still open, is settled by the rows it
    /// has; rows still held are taken as they are (no row after them can judge them); then
    /// `error`, if any, ends the events.
    pub(super) fn end(&mut self, error: Option<FlightDataError>) {
        self.done = true;
        if self.opening {
            self.settle_opening(true);
        }
        self.release_all();
        self.check_rate();
        self.pending.extend(error.map(Err));
    }

    /// The sample before time `t_s` among the accepted and the held ones, and the held run it
    /// would reject: `(prev, cut)`, `cut` the index in `held` of the first run start later than
    /// `t_s` (a sample going on from before that run), `prev` the time and row of the sample
    /// before it (or of the last held or accepted sample when there is no such run).
    fn reference(&self, t_s: f64) -> (Option<(f64, u64)>, Option<usize>) {
        let cut = self.held.iter().position(
            |e| matches!(e, Entry::Sample { sample, jump: true, .. } if sample.t_s > t_s),
        );
        let before = &self.held[..cut.unwrap_or(self.held.len())];
        let last = self.last_t.map(|t| (t, self.last_row));
        (before.iter().rev().find_map(Entry::timed_row).or(last), cut)
    }

    /// What is wrong with time `t_s` against the sample it follows.
    fn time_problem(&self, t_s: f64) -> Result<(), RowProblem> {
        self.check_time(self.reference(t_s).0.map(|p| p.0), t_s)
    }

    /// The nominal interval, or while the mapping gives none and the first interval has not
    /// fixed it, the first interval between the held samples (if two are held).
    fn nominal(&self) -> Option<f64> {
        self.nominal_dt.or_else(|| {
            let mut times = self.held.iter().filter_map(Entry::sample_time);
            let first = times.next()?;
            Some(times.next()? - first)
        })
    }

    /// Whether a sample at `t_s` on `row` after one at `prev` (time, row) starts a run to hold:
    /// an interval longer than a gap over the rows between (the rows rejected between two
    /// samples explain a longer interval: their times are the record's), or, without a nominal
    /// interval, the interval that would fix it.
    fn is_jump(&self, prev: Option<(f64, u64)>, t_s: f64, row: u64) -> bool {
        match (prev, self.nominal()) {
            (None, _) => false,
            (Some((p, prev_row)), Some(nom)) => {
                t_s - p > GAP_FACTOR * nom * row.saturating_sub(prev_row).max(1) as f64
            }
            (Some(_), None) => !self.held.iter().any(|e| e.sample_time().is_some()),
        }
    }

    /// A good sample: at the record's start it joins the opening rows; otherwise its time is
    /// checked against the sample it follows (a held run later than it, which it goes on from
    /// before, is rejected first), and it is accepted, or held when it starts or extends a
    /// run. A run holding more than [`TIME_RUN_MAX`] samples since its last jump is the
    /// record's own time: every held row is then released.
    fn take_sample(&mut self, row: u64, sample: AirDataSample) {
        if self.opening {
            self.held.push(Entry::Sample { row, sample, jump: false });
            return self.settle_opening(false);
        }
        let t_s = sample.t_s;
        let (prev, cut) = self.reference(t_s);
        if let Err(problem) = self.check_time(prev.map(|p| p.0), t_s) {
            return self.push_rejected(row, problem, Some(t_s));
        }
        if let Some(i) = cut {
            self.reject_run(i, prev.map(|p| p.0), t_s);
        }
        let jump = self.is_jump(prev, t_s, row);
        if self.held.is_empty() && !jump {
            return self.accept(row, sample);
        }
        self.held.push(Entry::Sample { row, sample, jump });
        let run_start =
            self.held.iter().rposition(|e| matches!(e, Entry::Sample { jump: true, .. }));
        let run_len = self.held[run_start.unwrap_or(0)..]
            .iter()
            .filter(|e| e.sample_time().is_some())
            .count();
        if run_len > TIME_RUN_MAX || self.held.len() > HELD_ROWS_MAX {
            self.release_all();
        }
    }

    /// Queues the rejection of `row` (`t_s` its time, if read), behind the held rows if there
    /// are any (events stay in row order); past [`HELD_ROWS_MAX`] held rows they are settled
    /// as they are.
    fn push_rejected(&mut self, row: u64, problem: RowProblem, t_s: Option<f64>) {
        if self.held.is_empty() {
            self.pending.push_back(Ok(RecordEvent::Rejected { row, problem }));
            return;
        }
        self.held.push(Entry::Rejected { row, problem, t_s });
        if self.held.len() > HELD_ROWS_MAX {
            match self.opening {
                true => self.settle_opening(true),
                false => self.release_all(),
            }
        }
    }

    /// Rejects the held run from index `i` on ([`RowProblem::TimeOutlier`]: `prev` the time
    /// before it, `next_t_s` the sample going on from before it): its samples, and the rows
    /// rejected for a repeated or backward time against it (their times are within it). The
    /// rejections keep their places; those ahead of every held sample are queued.
    fn reject_run(&mut self, i: usize, prev: Option<f64>, next_t_s: f64) {
        let column = self.time.names[0].clone();
        let start = self.held[i].sample_time().unwrap_or(f64::INFINITY);
        let outlier = |t_s: f64| RowProblem::TimeOutlier {
            column: column.clone(),
            t_s,
            prev_t_s: prev,
            next_t_s,
        };
        for e in &mut self.held[i..] {
            match e {
                Entry::Sample { row, sample, .. } => {
                    let t_s = sample.t_s;
                    *e = Entry::Rejected { row: *row, problem: outlier(t_s), t_s: Some(t_s) };
                }
                Entry::Rejected { problem, t_s: Some(t), .. }
                    if *t >= start
                        && matches!(
                            problem,
                            RowProblem::RepeatedTime { .. } | RowProblem::NonMonotonicTime { .. }
                        ) =>
                {
                    *problem = outlier(*t);
                }
                Entry::Rejected { .. } => {}
            }
        }
        self.flush_front();
    }

    /// Queues the held rejections ahead of every held sample.
    fn flush_front(&mut self) {
        let n = self.held.iter().position(|e| e.sample_time().is_some()).unwrap_or(self.held.len());
        for e in self.held.drain(..n) {
            if let Entry::Rejected { row, problem, .. } = e {
                self.pending.push_back(Ok(RecordEvent::Rejected { row, problem }));
            }
        }
    }

    /// Takes every held row as it is: samples accepted (a gap before one is reported),
    /// rejections queued, in row order.
    fn release_all(&mut self) {
        for e in std::mem::take(&mut self.held) {
            match e {
                Entry::Sample { row, sample, .. } => self.accept(row, sample),
                Entry::Rejected { row, problem, .. } => {
                    self.pending.push_back(Ok(RecordEvent::Rejected { row, problem }));
                }
            }
        }
    }

    /// Settles the record's start: the first held sample is the start when more than
    /// [`TIME_RUN_MAX`] later samples are after it, and a bad time stamp
    /// ([`RowProblem::TimeOutlier`], no previous time) when more than that many are before it;
    /// with `force` (the end of the record, or too many rows held) the majority of the samples
    /// held decides (a tie keeps it). Once the start is found the held rows are judged again in
    /// order as rows after a start.
    fn settle_opening(&mut self, force: bool) {
        let mut first = 0;
        loop {
            let times: Vec<(usize, f64)> = self.held[first..]
                .iter()
                .enumerate()
                .filter_map(|(k, e)| Some((first + k, e.sample_time()?)))
                .collect();
            let Some(&(k0, t0)) = times.first() else {
                if force {
                    self.opening = false;
                    self.release_all();
                }
                return;
            };
            let after = times.iter().filter(|(_, t)| *t > t0).count();
            let before: Vec<f64> = times.iter().map(|(_, t)| *t).filter(|t| *t < t0).collect();
            let bad = before.len() > TIME_RUN_MAX || (force && before.len() > after);
            if bad {
                let Entry::Sample { row, .. } = self.held[k0] else { unreachable!() };
                let problem = RowProblem::TimeOutlier {
                    column: self.time.names[0].clone(),
                    t_s: t0,
                    prev_t_s: None,
                    next_t_s: before[0],
                };
                self.held[k0] = Entry::Rejected { row, problem, t_s: Some(t0) };
                first = k0 + 1;
                continue;
            }
            if after > TIME_RUN_MAX || force {
                return self.start_at_opening();
            }
            return;
        }
    }

    /// The record's start is settled: the held rows are judged again in order, as rows after
    /// it (a row rejected for its values names a bad time first, as [`Self::event`] does).
    fn start_at_opening(&mut self) {
        self.opening = false;
        for e in std::mem::take(&mut self.held) {
            match e {
                Entry::Sample { row, sample, .. } => self.take_sample(row, sample),
                Entry::Rejected { row, problem, t_s } => {
                    let problem = match (t_s, &problem) {
                        (_, RowProblem::TimeOutlier { .. }) | (None, _) => problem,
                        (Some(t), _) => self.time_problem(t).err().unwrap_or(problem),
                    };
                    self.push_rejected(row, problem, t_s);
                }
            }
        }
    }
}
