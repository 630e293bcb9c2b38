//! What each file of a record gave: rows read, samples kept, rows rejected and why. A file of
//! several that gives nothing, or most of whose rows are rejected, is said so by name: its loss
//! is otherwise a count inside the whole record's rejections (a surface in degrees mapped as
//! radians rejected 88 % of a record's rows as implausible and the fit ran on the rest, unsaid).

use aeroident_io::RowProblem;
use std::collections::BTreeMap;

/// Share of a file's rows (inside the time windows) rejected above which the record stage warns:
/// beyond half, what is fitted is no longer the record the user gave.
pub const MOST_REJECTED: f64 = 0.5;

/// One file's counts.
#[derive(Debug, Default)]
pub struct FileTally {
    /// Rows read inside the windows (kept and rejected).
    pub read: usize,
    /// Samples kept.
    pub samples: usize,
    /// Rejected rows per cause (the problem's kind and, for an implausible value, its channel),
    /// with the first such row's reason.
    causes: BTreeMap<String, (usize, String)>,
}

impl FileTally {
    /// Counts a kept sample.
    pub fn sample(&mut self) {
        self.read += 1;
        self.samples += 1;
    }

    /// Counts a rejected row `row` for `problem`.
    pub fn rejected(&mut self, row: u64, problem: &RowProblem) {
        self.read += 1;
        let cause = match problem {
            RowProblem::Implausible { field, .. } => format!("implausible {field}"),
            p => p.kind().to_string(),
        };
        self.causes.entry(cause).or_insert_with(|| (0, format!("row {row}: {problem}"))).0 += 1;
    }

    /// Counts one record event: a sample, a rejected row, or nothing for a gap.
    pub fn count(&mut self, event: &aeroident_io::RecordEvent) {
        match event {
            aeroident_io::RecordEvent::Sample { .. } => self.sample(),
            aeroident_io::RecordEvent::Rejected { row, problem } => self.rejected(*row, problem),
            aeroident_io::RecordEvent::Gap { .. } => {}
        }
    }

    /// Rows rejected.
    pub fn rejected_rows(&self) -> usize {
        self.causes.values().map(|(n, _)| n).sum()
    }

    /// The most frequent cause: its name, count and first row's reason.
    fn main_cause(&self) -> Option<(&str, usize, &str)> {
        self.causes
            .iter()
            .max_by_key(|(_, (n, _))| *n)
            .map(|(c, (n, first))| (c.as_str(), *n, first.as_str()))
    }

    /// A warning for `file` when more than [`MOST_REJECTED`] of its rows were rejected.
    pub fn warning(&self, file: &str) -> Option<String> {
        let rejected = self.rejected_rows();
        if self.read == 0 || (rejected as f64) <= MOST_REJECTED * self.read as f64 {
            return None;
        }
        let (cause, n, first) = self.main_cause()?;
        Some(format!(
            "{file}: {rejected} of {} rows ({:.0} %) were rejected, {n} of them as {cause} (first, {first}); the fit uses the other {}: check the mapping's units, scales and columns, or leave a taxi or ground segment out with --window",
            self.read,
            100.0 * rejected as f64 / self.read as f64,
            self.samples
        ))
    }

    /// Why `file` gave no sample, when it gave none but had rows: its main cause.
    pub fn empty_reason(&self, file: &str) -> Option<String> {
        if self.samples > 0 || self.read == 0 {
            return None;
        }
        let (cause, n, first) = self.main_cause()?;
        Some(format!(
            "{file}: none of its {} rows is usable, {n} rejected as {cause} (first, {first})",
            self.read
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn implausible(field: &str) -> RowProblem {
        RowProblem::Implausible { field: field.into(), value: 50.0, limit: 1.0 }
    }

    /// 3 of 5 rows rejected, two for one channel: the warning names the share, the channel
    /// and the kept count; at exactly half (2 of 4) there is none.
    #[test]
    fn warns_beyond_half_naming_the_main_cause() {
        let mut t = FileTally::default();
        t.sample();
        t.sample();
        t.rejected(2, &implausible("channel `de`"));
        t.rejected(3, &implausible("channel `de`"));
        assert!(t.warning("a.csv").is_none() && t.empty_reason("a.csv").is_none());
        t.rejected(4, &RowProblem::Blank { column: "q".into() });
        let w = t.warning("a.csv").unwrap();
        assert!(w.starts_with("a.csv: 3 of 5 rows (60 %) were rejected, 2 of them as implausible channel `de` (first, row 2: "), "{w}");
        assert!(w.contains("the fit uses the other 2"), "{w}");
    }

    #[test]
    fn a_file_of_rejected_rows_only_is_named_with_its_cause() {
        let mut t = FileTally::default();
        for row in 1..=5 {
            t.rejected(row, &RowProblem::Blank { column: "q".into() });
        }
        let e = t.empty_reason("b.csv").unwrap();
        assert!(
            e.starts_with(
                "b.csv: none of its 5 rows is usable, 5 rejected as blank value (first, row 1: "
            ),
            "{e}"
        );
        assert!(FileTally::default().empty_reason("c.csv").is_none());
    }
}
