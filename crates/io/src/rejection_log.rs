//! A bounded list of rejections for a replay summary.
//!
//! A replay lists every rejected row and gap in its summary (`rejections`), about 100 bytes
//! each; over a 24 h live feed with a bad channel that list would grow without bound.
//! [`RejectionLog`] keeps the first [`RejectionLog::DEFAULT_LIMIT`] entries verbatim, always the
//! last one (a divergence is reported from the last entry), and for the entries in between only
//! a count per kind ([`RowProblem::kind`], or the replay's own kinds such as `gap`). The counts
//! become one warning in the summary ([`RejectionLog::finish`]). Memory is bounded by the limit
//! and the number of kinds, whatever the record's length.

use crate::error::RowProblem;
use crate::flight_data::Rejection;
use std::collections::BTreeMap;

/// The first `limit` rejections, the last one, and a count per kind of the rest.
#[derive(Debug, Clone)]
pub struct RejectionLog {
    listed: Vec<Rejection>,
    limit: usize,
    /// The latest entry beyond the limit, with its kind (listed by [`RejectionLog::finish`]).
    last: Option<(&'static str, Rejection)>,
    /// Kind → entries beyond the limit that are not listed.
    unlisted: BTreeMap<&'static str, usize>,
}

impl Default for RejectionLog {
    fn default() -> Self {
        Self::with_limit(Self::DEFAULT_LIMIT)
    }
}

impl RejectionLog {
    /// Entries listed verbatim by default: 1,000 (≈ 100 kB of summary), enough to see every
    /// distinct problem of a real record; the count per kind covers the rest.
    pub const DEFAULT_LIMIT: usize = 1_000;

    /// A log listing the first `limit` entries (and always the last).
    pub fn with_limit(limit: usize) -> Self {
        Self { listed: Vec::new(), limit, last: None, unlisted: BTreeMap::new() }
    }

    /// Adds a row the reader rejected (its kind is [`RowProblem::kind`]).
    pub fn push_row(&mut self, row: u64, problem: &RowProblem) {
        self.push(problem.kind(), Rejection { row, reason: problem.to_string() });
    }

    /// Adds an entry of kind `kind` (a short fixed label such as `"gap"`, used in the warning).
    pub fn push(&mut self, kind: &'static str, rejection: Rejection) {
        if self.listed.len() < self.limit && self.last.is_none() {
            self.listed.push(rejection);
        } else if let Some((k, _)) = self.last.replace((kind, rejection)) {
            *self.unlisted.entry(k).or_insert(0) += 1;
        }
    }

    /// Entries added so far (listed or not).
    pub fn len(&self) -> usize {
        self.listed.len() + usize::from(self.last.is_some()) + self.unlisted.values().sum::<usize>()
    }

    /// Whether nothing was added.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The first `n` entries as `(row, reason)` (for [`crate::FlightDataError::NoSamples`]).
    pub fn first(&self, n: usize) -> Vec<(u64, String)> {
        let tail = self.last.as_ref().map(|(_, r)| r);
        self.listed.iter().chain(tail).take(n).map(|r| (r.row, r.reason.clone())).collect()
    }

    /// The latest entry.
    pub fn last(&self) -> Option<&Rejection> {
        self.last.as_ref().map(|(_, r)| r).or(self.listed.last())
    }

    /// The listed entries (the first `limit`, then the last) and, if some were not listed, the
    /// warning `N further rejections not listed (the first L and the last are): n × kind, …`.
    pub fn finish(self) -> (Vec<Rejection>, Option<String>) {
        let mut list = self.listed;
        list.extend(self.last.map(|(_, r)| r));
        let total: usize = self.unlisted.values().sum();
        let warning = (total > 0).then(|| {
            let kinds: Vec<String> =
                self.unlisted.iter().map(|(k, n)| format!("{n} × {k}")).collect();
            format!(
                "{total} further rejections not listed (the first {} and the last are): {}",
                self.limit,
                kinds.join(", ")
            )
        });
        (list, warning)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blank(column: &str) -> RowProblem {
        RowProblem::Blank { column: column.into() }
    }

    /// 10,000 entries through a log of 100: 100 listed, then the last; the other 9,899 are
    /// counted per kind and named in the warning.
    #[test]
    fn long_run_keeps_the_first_the_last_and_a_count_per_kind() {
        let mut log = RejectionLog::with_limit(100);
        for row in 2..10_002u64 {
            if row % 10 == 0 {
                log.push("gap", Rejection { row, reason: "gap: …".into() });
            } else {
                log.push_row(row, &blank("alpha"));
            }
        }
        assert_eq!(log.len(), 10_000);
        assert_eq!(log.last().unwrap().row, 10_001);
        let (list, warning) = log.finish();
        assert_eq!(list.len(), 101);
        let rows: Vec<u64> = list.iter().map(|r| r.row).collect();
        assert_eq!(&rows[..100], &(2..102).collect::<Vec<_>>()[..]);
        assert_eq!(rows[100], 10_001);
        // Beyond the first 100 (rows 2…101) and the last (10,001): rows 102…10,000, of which
        // the multiples of 10 (110…10,000: 990) are gaps.
        let w = warning.unwrap();
        assert!(w.starts_with("9899 further rejections not listed (the first 100"), "{w}");
        assert!(w.contains("990 × gap"), "{w}");
        assert!(w.contains(&format!("{} × blank value", 9899 - 990)), "{w}");
    }

    /// Within the limit nothing is dropped and there is no warning.
    #[test]
    fn within_the_limit_everything_is_listed_without_warning() {
        let mut log = RejectionLog::with_limit(3);
        for row in 2..5 {
            log.push_row(row, &blank("q"));
        }
        assert_eq!(log.first(2), vec![(2, blank("q").to_string()), (3, blank("q").to_string())]);
        let (list, warning) = log.finish();
        assert_eq!(list.iter().map(|r| r.row).collect::<Vec<_>>(), vec![2, 3, 4]);
        assert_eq!(warning, None);
        // One more than the limit: listed too (the last is always listed), still no warning.
        let mut log = RejectionLog::with_limit(3);
        for row in 2..6 {
            log.push_row(row, &blank("q"));
        }
        let (list, warning) = log.finish();
        assert_eq!(list.len(), 4);
        assert_eq!(warning, None);
    }
}
