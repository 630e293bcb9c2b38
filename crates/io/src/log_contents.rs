//! What the multi-rate log readers ([`crate::ulog`], [`crate::dataflash`]) return, the filter
//! that tells them which topics and fields to keep, and the per-topic sample collector they
//! share.
//!
//! # Kept and left out
//!
//! A read keeps only what its [`TopicFilter`] names (a mapping's columns and clock topic,
//! [`TopicFilter::for_mapping`]); every other topic is still decoded far enough to be checked
//! and counted, and is listed with its fields in [`LogContents::catalogue`] so that an error
//! for a column the log lacks can name what it has. Memory is then the kept samples, not the
//! file.
//!
//! # Timestamps that do not increase
//!
//! A topic's samples are kept in the order of the file; samples whose timestamps break the
//! increasing order are left out as the fewest that must go: the kept samples are a longest
//! strictly increasing subsequence of the timestamps (patience sorting, O(n log n); among
//! equal timestamps the first is kept). One absurd timestamp (a glitch to `u64::MAX`) thus
//! costs that sample, not every later one. Each topic's left-out count, first left-out sample
//! and the byte offset of the first message whose timestamp did not increase over the one
//! before are in [`LogContents::dropped`] and [`LogContents::dropped_at`].
//! The last few samples of a topic after a jump forward longer than the topic's whole span
//! before it (a corrupt timestamp, nothing after it) are left out as time outliers
//! ([`LogContents::time_outliers`]); so are, mirrored, the first few samples of a topic before
//! a jump longer than its whole span after them (e.g. stamped a day early,
//! [`LogContents::early_time_outliers`]). Either end is judged without the few samples the
//! other end could lose, so a topic with both ends corrupt loses both.

use crate::flight_data::TIME_RUN_MAX;
use crate::mapping::{Clock, Mapping};
use crate::table::Topic;
use std::collections::{BTreeMap, BTreeSet};

/// Most skipped stretches listed one by one in [`LogContents::skipped`]; further ones are only
/// counted in [`LogContents::skipped_total`] (a file of garbage must not cost more memory to
/// describe than to read).
pub const MAX_SKIPPED_LISTED: usize = 100;

/// Which topics and which of their fields a log read keeps.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TopicFilter {
    /// `None`: every topic and field. Otherwise topic name → fields kept (an empty set keeps
    /// the timestamps only, for an `[align] clock` topic).
    only: Option<BTreeMap<String, BTreeSet<String>>>,
    /// Topics (by base name: without `[instance]` and `#layout`) kept with every field, on
    /// top of `only`.
    whole: BTreeSet<String>,
    /// Keep the timestamps of every topic `only` and `whole` do not name (for a catalogue
    /// with rates and gaps, [`TopicFilter::times_and`]).
    every_topic_times: bool,
}

/// The field set of a topic kept for its timestamps only.
static NO_FIELDS: BTreeSet<String> = BTreeSet::new();

impl TopicFilter {
    /// Keeps every topic and field.
    pub fn all() -> Self {
        Self::default()
    }

    /// Keeps the `<topic>.<field>` columns named (as a mapping writes them: `vehicle_imu.x`,
    /// `actuator_outputs[1].output[2]`, `ATT.Roll`) and the timestamps of `clock_topics`.
    /// A name that is not `<topic>.<field>` keeps nothing (the mapping check reports it).
    pub fn columns<'a>(
        columns: impl IntoIterator<Item = &'a str>,
        clock_topics: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        let mut only: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for c in columns {
            if let Some((topic, field)) = crate::align::split_column(c) {
                only.entry(topic).or_default().insert(field.to_string());
            }
        }
        for t in clock_topics {
            only.entry(t.strip_suffix("[0]").unwrap_or(t).to_string()).or_default();
        }
        Self { only: Some(only), ..Self::default() }
    }

    /// Keeps the timestamps of every topic (8 bytes a message: what rates and gaps need), the
    /// `<topic>.<field>` `columns` named, and every field of the topics in `whole` (base names,
    /// `actuator_outputs` keeps `actuator_outputs[1]` too). For `aeroident inspect`: the
    /// values of a log are not held, only those of the channels asked for.
    pub fn times_and<'a>(
        columns: impl IntoIterator<Item = &'a str>,
        whole: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        Self {
            whole: whole.into_iter().map(str::to_string).collect(),
            every_topic_times: true,
            ..Self::columns(columns, [])
        }
    }

    /// The columns `mapping` reads from a log ([`crate::multirate::needed_columns`]: channels,
    /// `[attitude]`, `[air_data]`) and its `[align] clock` topic.
    pub fn for_mapping(mapping: &Mapping) -> Self {
        let needed = crate::multirate::needed_columns(mapping);
        let clock = match mapping.align.as_ref().map(|a| &a.clock) {
            Some(Clock::Topic(t)) => Some(t.as_str()),
            _ => None,
        };
        Self::columns(needed.iter().map(|(c, _)| c.as_str()), clock)
    }

    /// Is topic `name` kept, and which fields: `None` not kept, `Some(None)` every field,
    /// `Some(Some(set))` the fields in `set`.
    pub(crate) fn topic(&self, name: &str) -> Option<Option<&BTreeSet<String>>> {
        if self.whole.contains(base_topic(name)) {
            return Some(None);
        }
        match &self.only {
            None => Some(None),
            Some(m) => match m.get(name) {
                Some(set) => Some(Some(set)),
                None if self.every_topic_times => Some(Some(&NO_FIELDS)),
                None => None,
            },
        }
    }
}

/// A topic's name without its `[instance]` and `#layout` suffixes (`XKF1[1]#2` → `XKF1`): the
/// message type it was defined as.
pub fn base_topic(name: &str) -> &str {
    let end = name.find(['[', '#']).unwrap_or(name.len());
    &name[..end]
}

/// One topic of a log as read: its name, every field it has and how many messages it had,
/// kept or not.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicInfo {
    /// Topic name as in [`Topic::name`].
    pub name: String,
    /// Every numeric field, in the order of the topic's definition.
    pub fields: Vec<String>,
    /// Messages of the topic in the file (before timestamp checks).
    pub messages: usize,
}

/// Everything a multi-rate log reader returns besides the topics.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogContents {
    /// The kept topics that have samples, in order of subscription (definition), with only
    /// the kept fields.
    pub topics: Vec<Topic>,
    /// Every topic with at least one message, kept or not, in the same order.
    pub catalogue: Vec<TopicInfo>,
    /// Parameters by name, as logged (the last value of a parameter changed in flight).
    pub parameters: BTreeMap<String, f64>,
    /// Units of fields as the log states them (DataFlash `FMTU` with `UNIT` and `MULT`): message
    /// type name (no instance suffix) → field → unit label. Empty for a format that states
    /// none (ULog).
    pub units: BTreeMap<String, BTreeMap<String, String>>,
    /// Samples left out because their timestamp broke the topic's increasing order (module
    /// doc): topic name → count. Kept topics only.
    pub dropped: BTreeMap<String, usize>,
    /// For each topic in [`LogContents::dropped`]: the index (0-based, in file order) of its
    /// first left-out sample and the byte offset of its first message whose timestamp did not
    /// increase over the one before.
    pub dropped_at: BTreeMap<String, (usize, u64)>,
    /// Samples left out as time outliers: the last few samples of a topic after a jump
    /// forward longer than the topic's whole span before it (a corrupt timestamp, e.g. one
    /// day late; kept, it would stretch the aligned time base over the day). Topic name →
    /// (count, index of the first, 0-based in the kept order, its time in s). Kept topics only.
    pub time_outliers: BTreeMap<String, (usize, usize, f64)>,
    /// Samples left out as time outliers at a topic's start: the first few samples before a
    /// jump forward longer than the topic's whole span after it, all earlier than every
    /// topic's other samples (a corrupt timestamp, e.g. one day early; kept, it would stretch
    /// the aligned time base over the day). Topic name → (count, time of the first in s);
    /// they are the topic's first samples in kept order (from sample 0). Kept topics only.
    pub early_time_outliers: BTreeMap<String, (usize, f64)>,
    /// Byte offset of a message the file ends inside (that partial message is not used).
    pub truncated_at: Option<u64>,
    /// Corrupt stretches skipped to find the next message: `(byte offset, length)`, the first
    /// [`MAX_SKIPPED_LISTED`] (DataFlash resynchronises on the message header as pymavlink
    /// does; ULog never skips).
    pub skipped: Vec<(u64, u64)>,
    /// All skipped stretches: `(count, total bytes)`, listed or not.
    pub skipped_total: (u64, u64),
    /// A `.tlog`'s frames skipped whole because the dialect does not know their message id:
    /// id → count (empty for the other formats).
    pub unknown_messages: BTreeMap<u32, usize>,
}

impl LogContents {
    /// One line per thing left out of the topics (non-increasing samples, a truncated last
    /// message, skipped bytes), for the caller to print; empty when nothing was.
    pub fn notes(&self, file: &str) -> Vec<String> {
        let mut v: Vec<String> = self
            .dropped
            .iter()
            .map(|(t, n)| {
                let at = match self.dropped_at.get(t) {
                    Some((k, byte)) => format!(
                        " (the first at sample {k}; the first timestamp that did not increase at byte {byte})"
                    ),
                    None => String::new(),
                };
                format!(
                    "{file}: topic `{t}`: {n} samples left out (timestamp out of increasing order){at}"
                )
            })
            .collect();
        for (t, (n, t_s)) in &self.early_time_outliers {
            v.push(format!("{file}: topic `{t}`: {}", early_head_note(*n, *t_s)));
        }
        for (t, (n, k, t_s)) in &self.time_outliers {
            v.push(format!("{file}: topic `{t}`: {}", late_tail_note(*n, *k, *t_s)));
        }
        if let Some(at) = self.truncated_at {
            v.push(format!("{file}: byte {at}: the file ends inside this message (not used)"));
        }
        for (at, len) in &self.skipped {
            v.push(format!("{file}: byte {at}: {len} corrupt bytes skipped"));
        }
        let (n, bytes) = self.skipped_total;
        if n as usize > self.skipped.len() {
            v.push(format!(
                "{file}: {n} corrupt stretches skipped in all ({bytes} bytes; the first {} listed)",
                self.skipped.len()
            ));
        }
        v
    }

    /// Records a corrupt stretch skipped at `offset`.
    pub(crate) fn skip(&mut self, offset: u64, len: u64) {
        if self.skipped.len() < MAX_SKIPPED_LISTED {
            self.skipped.push((offset, len));
        }
        self.skipped_total.0 += 1;
        self.skipped_total.1 += len;
    }

    /// Ends a read: each builder's samples out of increasing order go to
    /// [`LogContents::dropped`], and each kept builder that has a sample becomes a topic, in
    /// the builders' order; every builder with a message enters the catalogue.
    pub(crate) fn add_topics(&mut self, mut builders: Vec<TopicBuilder>) {
        for b in builders.iter_mut().filter(|b| b.kept) {
            b.dropped_by_order = b.keep_increasing();
        }
        self.drop_early_heads(&mut builders);
        self.drop_late_tails(&mut builders);
        for mut b in builders {
            if b.messages > 0 {
                self.catalogue.push(TopicInfo {
                    name: b.name.clone(),
                    fields: std::mem::take(&mut b.all_fields),
                    messages: b.messages,
                });
            }
            if !b.kept {
                continue;
            }
            let (dropped, first) = b.dropped_by_order;
            if dropped > 0 {
                self.dropped.insert(b.name.clone(), dropped);
                self.dropped_at.insert(b.name.clone(), (first, b.first_descent.unwrap_or(0)));
            }
            if !b.t_us.is_empty() {
                self.topics.push(b.finish());
            }
        }
    }
}

impl LogContents {
    /// Leaves out the late tails of the kept topics ([`LogContents::time_outliers`]): a tail
    /// ([`TopicBuilder::late_tail_start`]) that starts after the end of every topic's samples
    /// before its own tail. A late sample of an event topic (a parameter changed in flight)
    /// lies within the other topics' time and is kept.
    fn drop_late_tails(&mut self, builders: &mut [TopicBuilder]) {
        let starts: Vec<Option<usize>> =
            builders.iter().filter(|b| b.kept).map(TopicBuilder::late_tail_start).collect();
        let body_end = |b: &TopicBuilder, k: Option<usize>| b.t_us[k.unwrap_or(b.t_us.len()) - 1];
        let ends: Vec<u64> = builders
            .iter()
            .filter(|b| b.kept)
            .zip(&starts)
            .filter(|(b, _)| !b.t_us.is_empty())
            .map(|(b, &k)| body_end(b, k))
            .collect();
        let Some(&log_end) = ends.iter().max() else { return };
        let mut starts = starts.into_iter();
        for b in builders.iter_mut().filter(|b| b.kept) {
            let Some(Some(k)) = starts.next() else { continue };
            if b.t_us[k] > log_end {
                let late = (b.t_us.len() - k, k, seconds(b.t_us[k]));
                b.truncate(k);
                self.time_outliers.insert(b.name.clone(), late);
            }
        }
    }
}

impl LogContents {
    /// Leaves out the early heads of the kept topics ([`LogContents::early_time_outliers`]),
    /// the mirror of [`LogContents::drop_late_tails`]: a head
    /// ([`TopicBuilder::early_head_end`]) that ends before the start of every topic's samples
    /// after its own head. An event topic's early sample (a parameter logged at boot) that
    /// lies within the other topics' time is kept.
    fn drop_early_heads(&mut self, builders: &mut [TopicBuilder]) {
        let ends: Vec<Option<usize>> =
            builders.iter().filter(|b| b.kept).map(TopicBuilder::early_head_end).collect();
        let starts: Vec<u64> = builders
            .iter()
            .filter(|b| b.kept)
            .zip(&ends)
            .filter(|(b, _)| !b.t_us.is_empty())
            .map(|(b, &k)| b.t_us[k.unwrap_or(0)])
            .collect();
        let Some(&log_start) = starts.iter().min() else { return };
        let mut ends = ends.into_iter();
        for b in builders.iter_mut().filter(|b| b.kept) {
            let Some(Some(k)) = ends.next() else { continue };
            if b.t_us[k - 1] < log_start {
                self.early_time_outliers.insert(b.name.clone(), (k, seconds(b.t_us[0])));
                b.drain_head(k);
            }
        }
    }
}

/// One topic being collected: timestamps in µs and the kept fields, in file order.
pub(crate) struct TopicBuilder {
    pub(crate) name: String,
    /// Every field of the topic (for the catalogue).
    pub(crate) all_fields: Vec<String>,
    /// Is the topic kept (else only its messages are counted)?
    pub(crate) kept: bool,
    pub(crate) t_us: Vec<u64>,
    /// Kept fields' names and values.
    pub(crate) names: Vec<String>,
    pub(crate) values: Vec<Vec<f64>>,
    /// Messages seen, kept or not.
    pub(crate) messages: usize,
    /// Byte offset of the first message whose timestamp did not increase over the previous.
    pub(crate) first_descent: Option<u64>,
    /// What [`TopicBuilder::keep_increasing`] left out: (count, index of the first).
    dropped_by_order: (usize, usize),
}

impl TopicBuilder {
    /// A topic with fields `all_fields`, of which `kept` (names) are collected if `kept_topic`.
    pub(crate) fn new(name: String, all_fields: Vec<String>, kept: Option<Vec<String>>) -> Self {
        let kept_topic = kept.is_some();
        let names = kept.unwrap_or_default();
        let n = names.len();
        Self {
            name,
            all_fields,
            kept: kept_topic,
            t_us: Vec::new(),
            names,
            values: vec![Vec::new(); n],
            messages: 0,
            first_descent: None,
            dropped_by_order: (0, 0),
        }
    }

    /// Appends one sample (message at byte `offset`); `row` has one value per kept field.
    pub(crate) fn push(&mut self, t_us: u64, row: &[f64], offset: u64) {
        self.messages += 1;
        if !self.kept {
            return;
        }
        // Compared as the seconds they become: two stamps past 2⁵³ µs can differ as integers
        // and be equal as `f64`.
        if self.first_descent.is_none()
            && self.t_us.last().is_some_and(|&last| seconds(t_us) <= seconds(last))
        {
            self.first_descent = Some(offset);
        }
        self.t_us.push(t_us);
        for (col, v) in self.values.iter_mut().zip(row) {
            col.push(*v);
        }
    }

    /// Leaves out the fewest samples so the rest have strictly increasing times (module doc);
    /// returns how many were left out and the index of the first.
    fn keep_increasing(&mut self) -> (usize, usize) {
        if self.first_descent.is_none() {
            return (0, 0);
        }
        // Non-negative finite `f64`s order as their bits.
        let keys: Vec<u64> = self.t_us.iter().map(|&t| seconds(t).to_bits()).collect();
        let keep = longest_increasing(&keys);
        drop(keys);
        let n = self.t_us.len();
        let first = keep.iter().position(|k| !k).unwrap_or(n);
        let dropped = keep.iter().filter(|k| !**k).count();
        let mut it = keep.iter();
        self.t_us.retain(|_| *it.next().unwrap_or(&false));
        for col in &mut self.values {
            let mut it = keep.iter();
            col.retain(|_| *it.next().unwrap_or(&false));
        }
        (dropped, first)
    }

    /// Where a late tail starts: at most [`TIME_RUN_MAX`] last samples after a jump longer
    /// than the topic's span before it, with at least [`LATE_TAIL_MIN_BEFORE`] samples before.
    fn late_tail_start(&self) -> Option<usize> {
        let n = self.t_us.len();
        let t = |i: usize| seconds(self.t_us[i]);
        let first = n.saturating_sub(TIME_RUN_MAX).max(LATE_TAIL_MIN_BEFORE);
        (first..n).find(|&k| t(k) - t(k - 1) > t(k - 1) - t(0))
    }

    /// Where an early head ends (the mirror of [`TopicBuilder::late_tail_start`]): the count
    /// `k` of at most [`TIME_RUN_MAX`] first samples before a jump longer than the topic's span
    /// after it, with at least [`LATE_TAIL_MIN_BEFORE`] samples after. The span after is
    /// measured without the last [`TIME_RUN_MAX`] samples, which may be a late tail of their
    /// own (judged after the head is gone).
    fn early_head_end(&self) -> Option<usize> {
        let n = self.t_us.len();
        let t = |i: usize| seconds(self.t_us[i]);
        let last = TIME_RUN_MAX.min(n.saturating_sub(LATE_TAIL_MIN_BEFORE + TIME_RUN_MAX));
        let body_end = n.saturating_sub(1 + TIME_RUN_MAX);
        (1..=last).rev().find(|&k| t(k) - t(k - 1) > t(body_end) - t(k))
    }

    /// Leaves out the first `k` samples.
    fn drain_head(&mut self, k: usize) {
        self.t_us.drain(..k);
        for col in &mut self.values {
            col.drain(..k);
        }
    }

    /// Keeps the first `k` samples.
    fn truncate(&mut self, k: usize) {
        self.t_us.truncate(k);
        for col in &mut self.values {
            col.truncate(k);
        }
    }

    pub(crate) fn finish(self) -> Topic {
        // In place (same size and alignment): no second copy of the time column.
        let t_s: Vec<f64> = self.t_us.into_iter().map(seconds).collect();
        let mut fields: Vec<(String, Vec<f64>)> = self.names.into_iter().zip(self.values).collect();
        for (_, v) in &mut fields {
            v.shrink_to_fit();
        }
        Topic { name: self.name, t_s, fields }
    }
}

/// Fewest samples a topic must have before a jump for the samples after it to be judged a
/// late tail (`TopicBuilder::late_tail_start`): a topic of a few samples has no span to judge by.
pub const LATE_TAIL_MIN_BEFORE: usize = 8;

/// What a late tail of `n` samples from sample `k` at `t_s` s is, for a note.
pub(crate) fn late_tail_note(n: usize, k: usize, t_s: f64) -> String {
    format!(
        "{n} last samples left out as time outliers (from sample {k}, at {t_s} s, the topic jumps further ahead than its whole span before)"
    )
}

/// What an early head of `n` samples whose first is at `t_s` s is, for a note.
pub(crate) fn early_head_note(n: usize, t_s: f64) -> String {
    format!(
        "{n} first samples left out as time outliers (from sample 0, at {t_s} s, before a jump further ahead than the topic's whole span after it)"
    )
}

/// A timestamp in µs as seconds.
fn seconds(t_us: u64) -> f64 {
    t_us as f64 * 1e-6
}

/// Which elements of `t` form a longest strictly increasing subsequence. Among the longest,
/// the one taken keeps the earlier samples (it is built from the end, each run starting at
/// the largest value, the earliest of equal ones): a repeated timestamp keeps its first sample
/// and a sample that goes back in time is the one left out, as a reader that only compared
/// each sample with the previous would do when one sample is enough.
pub(crate) fn longest_increasing(t: &[u64]) -> Vec<bool> {
    // heads[k]: start of the run of length k + 1 (so far, from the end) with the largest
    // first value; their values decrease with k.
    let mut heads: Vec<u32> = Vec::new();
    let mut next: Vec<u32> = vec![u32::MAX; t.len()];
    for i in (0..t.len()).rev() {
        let x = t[i];
        let pos = heads.partition_point(|&j| t[j as usize] > x);
        if pos > 0 {
            next[i] = heads[pos - 1];
        }
        if pos == heads.len() {
            heads.push(i as u32);
        } else {
            heads[pos] = i as u32;
        }
    }
    let mut keep = vec![false; t.len()];
    let mut k = heads.last().copied().unwrap_or(u32::MAX);
    while k != u32::MAX {
        keep[k as usize] = true;
        k = next[k as usize];
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A topic at 100 Hz over 10 s whose last message is stamped one day late: that sample is
    /// a time outlier, counted, and the topic ends at 9.99 s; a gap followed by more samples
    /// than a run, or a jump shorter than the span before it, is the topic's own time.
    #[test]
    fn errors_late_last_timestamp_is_a_time_outlier() {
        let topic = |name: &str, n: u64, tail: &[u64]| {
            let mut b = TopicBuilder::new(name.into(), vec!["x".into()], Some(vec!["x".into()]));
            for i in 0..n {
                b.push(i * 10_000, &[i as f64], i);
            }
            for &t in tail {
                b.push(t, &[0.0], 0);
            }
            b
        };
        let day_late = |t: u64| 86_400_000_000 + 10_000_000 + t;
        let built = |tail: &[u64]| {
            let mut c = LogContents::default();
            c.add_topics(vec![topic("imu", 1000, tail), topic("gps", 900, &[day_late(0)])]);
            c
        };
        let day = day_late(0);
        let c = built(&[day]);
        assert_eq!(c.time_outliers["imu"], (1, 1000, 86_410.0));
        assert_eq!(c.time_outliers["gps"], (1, 900, 86_410.0));
        assert_eq!(c.topics[0].t_s.len(), 1000);
        assert_eq!(*c.topics[0].t_s.last().unwrap(), 9.99);
        let note = c.notes("x.ulg").join("\n");
        assert!(note.contains("x.ulg: topic `imu`: 1 last samples left out as time outliers (from sample 1000, at 86410 s"), "{note}");
        let report = crate::reader_report::ReaderReport::from_contents("x.ulg", "ulog", &c);
        assert_eq!(report.totals().0, 2);
        let c = built(&[day, day + 10_000, day + 20_000, day + 30_000, day + 40_000]);
        assert!(c.time_outliers.is_empty() && c.topics[0].t_s.len() == 1005);
        let c = built(&[19_000_000]);
        assert_eq!(c.topics[0].t_s.len(), 1001);
        assert_eq!(c.time_outliers.keys().collect::<Vec<_>>(), ["gps"]);
        // A late sample within the other topics' time (a parameter changed in flight) is kept.
        let mut c = LogContents::default();
        c.add_topics(vec![topic("parm", 10, &[300_000_000]), topic("imu", 60_000, &[])]);
        assert!(c.time_outliers.is_empty() && c.topics[0].t_s.len() == 11);
    }

    /// The mirror: every topic's first sample stamped one day before the rest is a time
    /// outlier, counted, and each topic starts with its own samples; a topic whose first and
    /// last samples are both a day off loses both; an early sample within the other topics'
    /// time (a parameter logged at boot) and a head before a jump shorter than the span after
    /// it are kept.
    #[test]
    fn errors_early_first_timestamp_is_a_time_outlier() {
        let day = 86_400_000_000u64;
        let topic_from = |name: &str, head: &[u64], start: u64, n: u64, dt: u64, tail: &[u64]| {
            let mut b = TopicBuilder::new(name.into(), vec!["x".into()], Some(vec!["x".into()]));
            for &t in head {
                b.push(t, &[-1.0], 0);
            }
            for i in 0..n {
                b.push(start + i * dt, &[i as f64], i);
            }
            for &t in tail {
                b.push(t, &[-2.0], 0);
            }
            b
        };
        let topic = |name: &str, head: &[u64], n: u64, dt: u64, tail: &[u64]| {
            topic_from(name, head, day + 1_000_000, n, dt, tail)
        };
        let mut c = LogContents::default();
        c.add_topics(vec![
            topic("imu", &[1_000_000], 1000, 10_000, &[]),
            topic("gps", &[2_000_000], 50, 200_000, &[]),
        ]);
        assert_eq!(c.early_time_outliers["imu"], (1, 1.0));
        assert_eq!(c.early_time_outliers["gps"], (1, 2.0));
        assert!(c.time_outliers.is_empty() && c.dropped.is_empty());
        assert_eq!(c.topics[0].t_s.len(), 1000);
        assert_eq!(c.topics[0].t_s[0], 86_401.0);
        assert_eq!(c.topics[0].fields[0].1[0], 0.0);
        assert_eq!(c.topics[1].t_s.len(), 50);
        let note = c.notes("x.ulg").join("\n");
        assert!(note.contains("x.ulg: topic `imu`: 1 first samples left out as time outliers (from sample 0, at 1 s"), "{note}");
        let report = crate::reader_report::ReaderReport::from_contents("x.ulg", "ulog", &c);
        assert_eq!(report.totals().0, 2);
        assert!(
            report.dropped.iter().all(|d| d.kind == crate::reader_report::DropKind::TimeOutlier
                && d.first_sample == Some(0))
        );
        assert!(report.notes()[0].contains("first samples left out"), "{:?}", report.notes());
        // Two early samples, and a day-late last one on the same topic: all three go.
        let late = 2 * day;
        let mut c = LogContents::default();
        c.add_topics(vec![topic("imu", &[0, 10_000], 1000, 10_000, &[late])]);
        assert_eq!(c.early_time_outliers["imu"], (2, 0.0));
        assert_eq!(c.time_outliers["imu"], (1, 1000, 172_800.0));
        assert_eq!(c.topics[0].t_s.len(), 1000);
        // A parameter logged early but within the imu's time, its later values much later,
        // is kept; so is a head before a jump shorter than the span after it.
        let mut c = LogContents::default();
        c.add_topics(vec![
            topic_from("parm", &[day + 2_000_000], day + 400_000_000, 20, 10_000, &[]),
            topic("imu", &[], 60_000, 10_000, &[]),
        ]);
        assert!(c.early_time_outliers.is_empty() && c.topics[0].t_s.len() == 21);
        let mut c = LogContents::default();
        c.add_topics(vec![topic("imu", &[day - 5_000_000], 1000, 10_000, &[])]);
        assert!(c.early_time_outliers.is_empty() && c.topics[0].t_s.len() == 1001);
    }

    #[test]
    fn analytic_builder_drops_out_of_order_times_and_converts_us_to_s() {
        let mut b = TopicBuilder::new("t".into(), vec!["x".into()], Some(vec!["x".into()]));
        b.push(1_000_000, &[1.0], 10);
        b.push(1_000_000, &[2.0], 20);
        b.push(500_000, &[3.0], 30);
        b.push(1_500_000, &[4.0], 40);
        assert_eq!(b.keep_increasing(), (2, 1));
        // Two samples must go either way: the later ones that go back in time do.
        assert_eq!(b.first_descent, Some(20));
        let t = b.finish();
        assert_eq!(t.t_s, vec![1.0, 1.5]);
        assert_eq!(t.fields, vec![("x".to_string(), vec![1.0, 4.0])]);
    }

    #[test]
    fn analytic_one_absurd_timestamp_costs_one_sample() {
        let mut t: Vec<u64> = (0..2001).map(|i| 1_000 * i).collect();
        t[600] = u64::MAX;
        let keep = longest_increasing(&t);
        assert_eq!(keep.iter().filter(|k| !**k).count(), 1);
        assert!(!keep[600]);
        // A clock that restarts keeps the longer run; a value at the start that is too
        // large costs only itself.
        let keep = longest_increasing(&[5, 6, 7, 1, 2, 3, 4]);
        assert_eq!(keep, [false, false, false, true, true, true, true]);
        let keep = longest_increasing(&[u64::MAX, 1, 2, 3]);
        assert_eq!(keep, [false, true, true, true]);
        assert!(longest_increasing(&[]).is_empty());
    }

    #[test]
    fn analytic_stamps_equal_as_seconds_count_as_repeated() {
        // u64::MAX − 1 and u64::MAX are the same f64: the second is a repeat.
        let mut b = TopicBuilder::new("t".into(), vec![], Some(vec![]));
        for (k, t) in [1, u64::MAX - 1, u64::MAX].into_iter().enumerate() {
            b.push(t, &[], k as u64);
        }
        assert_eq!(b.keep_increasing(), (1, 2));
        let t = b.finish();
        assert!(t.t_s.windows(2).all(|w| w[1] > w[0]), "{:?}", t.t_s);
    }
}
