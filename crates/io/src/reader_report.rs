//! What reading a multi-rate log (ULog, DataFlash, MAVLink `.tlog`) left out before the first row reached the
//! estimators, as data: counted per kind and per topic with where it began, for `summary.json`
//! (`reader`) and the report, as well as the `note:` lines a command prints.
//!
//! Kinds ([`DropKind`]): samples whose timestamp broke their topic's increasing order, the
//! message a cut file ends inside, corrupt bytes skipped to resynchronise, and aligned rows
//! dropped because a topic had no value there ([`crate::align`]), and the far-early first or
//! far-late last samples of a topic left out as time outliers, and a `.tlog`'s frames of
//! message ids its dialect does not know.

use crate::log_contents::LogContents;
use serde::Serialize;

/// What was left out, of which kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DropKind {
    /// Samples of a topic whose timestamp broke its increasing order (unit: samples).
    TimestampOrder,
    /// The message a cut file ends inside (unit: messages; always 1).
    Truncated,
    /// Corrupt bytes skipped to find the next message (unit: bytes).
    SkippedBytes,
    /// Aligned rows dropped because a topic had no value there (unit: rows).
    Alignment,
    /// The last samples of a topic after a jump forward longer than its span before
    /// ([`LogContents::time_outliers`]), or its first samples before a jump longer than its
    /// span after ([`LogContents::early_time_outliers`]; `first_sample` 0); unit: samples.
    TimeOutlier,
    /// A `.tlog`'s frames of one message id the MAVLink dialect does not know, so that neither
    /// their CRC nor their fields can be read ([`LogContents::unknown_messages`]; topic
    /// `message id N`; unit: messages).
    UnknownMessage,
}

/// One kind of loss, for one topic where it has one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Dropped {
    /// What was left out.
    pub kind: DropKind,
    /// The topic (message type) concerned, if the loss is one topic's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub topic: Option<String>,
    /// How many, in `unit`.
    pub count: u64,
    /// `samples`, `messages`, `bytes` or `rows`.
    pub unit: &'static str,
    /// Out of how many (alignment: the rows considered), where known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub of: Option<u64>,
    /// Byte offset in the file where it began: the first message whose timestamp did not
    /// increase, the cut message, the first skipped stretch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_byte: Option<u64>,
    /// Index (0-based, in file order) of the first left-out sample of the topic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_sample: Option<u64>,
    /// Time stamp, s, of the first left-out sample, where it says why (a time outlier).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_time_s: Option<f64>,
}

/// Everything a log read left out; empty `dropped` when nothing was.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ReaderReport {
    /// The file read.
    pub file: String,
    /// Its format (`ulog`, `dataflash`; others leave nothing out here).
    pub format: String,
    /// One entry per kind and topic.
    pub dropped: Vec<Dropped>,
}

impl ReaderReport {
    /// The report of `file` read in the format named `format` (`LogFormat::name`) by a reader
    /// that leaves nothing out before the rows (CSV, `.asc`, `.mat`, arrays, a live feed).
    pub fn empty(file: &str, format: &str) -> Self {
        Self { file: file.to_string(), format: format.to_string(), dropped: Vec::new() }
    }

    /// The losses a multi-rate reader recorded in `contents`.
    pub fn from_contents(file: &str, format: &str, contents: &LogContents) -> Self {
        let mut dropped: Vec<Dropped> = contents
            .dropped
            .iter()
            .map(|(topic, &n)| {
                let at = contents.dropped_at.get(topic);
                Dropped {
                    kind: DropKind::TimestampOrder,
                    topic: Some(topic.clone()),
                    count: n as u64,
                    unit: "samples",
                    of: contents
                        .catalogue
                        .iter()
                        .find(|t| &t.name == topic)
                        .map(|t| t.messages as u64),
                    first_byte: at.map(|a| a.1),
                    first_sample: at.map(|a| a.0 as u64),
                    first_time_s: None,
                }
            })
            .collect();
        let early = contents.early_time_outliers.iter().map(|(t, &(n, t_s))| (t, (n, 0, t_s)));
        let late = contents.time_outliers.iter().map(|(t, &v)| (t, v));
        for (topic, (n, k, t_s)) in early.chain(late) {
            dropped.push(Dropped {
                kind: DropKind::TimeOutlier,
                topic: Some(topic.clone()),
                count: n as u64,
                unit: "samples",
                of: contents.catalogue.iter().find(|t| &t.name == topic).map(|t| t.messages as u64),
                first_byte: None,
                first_sample: Some(k as u64),
                first_time_s: Some(t_s),
            });
        }
        if let Some(at) = contents.truncated_at {
            dropped.push(Dropped {
                kind: DropKind::Truncated,
                topic: None,
                count: 1,
                unit: "messages",
                of: None,
                first_byte: Some(at),
                first_sample: None,
                first_time_s: None,
            });
        }
        let (stretches, bytes) = contents.skipped_total;
        if stretches > 0 {
            dropped.push(Dropped {
                kind: DropKind::SkippedBytes,
                topic: None,
                count: bytes,
                unit: "bytes",
                of: None,
                first_byte: contents.skipped.first().map(|s| s.0),
                first_sample: None,
                first_time_s: None,
            });
        }
        for (id, &n) in &contents.unknown_messages {
            dropped.push(Dropped {
                kind: DropKind::UnknownMessage,
                topic: Some(format!("message id {id}")),
                count: n as u64,
                unit: "messages",
                of: None,
                first_byte: None,
                first_sample: None,
                first_time_s: None,
            });
        }
        Self { file: file.to_string(), format: format.to_string(), dropped }
    }

    /// Adds the rows alignment dropped: topic → count, out of `considered` rows.
    pub fn add_alignment<'a>(
        &mut self,
        by_topic: impl IntoIterator<Item = (&'a String, &'a usize)>,
        considered: usize,
    ) {
        for (topic, &n) in by_topic {
            self.dropped.push(Dropped {
                kind: DropKind::Alignment,
                topic: Some(topic.clone()),
                count: n as u64,
                unit: "rows",
                of: Some(considered as u64),
                first_byte: None,
                first_sample: None,
                first_time_s: None,
            });
        }
    }

    /// Total of each unit left out: `(samples, messages, bytes, rows)`.
    pub fn totals(&self) -> (u64, u64, u64, u64) {
        let sum = |u: &str| self.dropped.iter().filter(|d| d.unit == u).map(|d| d.count).sum();
        (sum("samples"), sum("messages"), sum("bytes"), sum("rows"))
    }

    /// One line per entry, naming the file (what the CLI prints as `note:`).
    pub fn notes(&self) -> Vec<String> {
        let f = &self.file;
        self.dropped
            .iter()
            .map(|d| {
                let topic = d.topic.as_deref().unwrap_or("");
                match d.kind {
                    DropKind::TimestampOrder => format!(
                        "{f}: topic `{topic}`: {} of {} samples left out (timestamp out of increasing order; the first is sample {}, the first timestamp that did not increase is at byte {})",
                        d.count,
                        d.of.unwrap_or(0),
                        d.first_sample.unwrap_or(0),
                        d.first_byte.unwrap_or(0)
                    ),
                    DropKind::Truncated => format!(
                        "{f}: byte {}: the file ends inside this message (not used)",
                        d.first_byte.unwrap_or(0)
                    ),
                    DropKind::SkippedBytes => format!(
                        "{f}: {} corrupt bytes skipped (the first stretch at byte {})",
                        d.count,
                        d.first_byte.unwrap_or(0)
                    ),
                    // A late tail has samples before it; only an early head starts at sample 0.
                    DropKind::TimeOutlier if d.first_sample == Some(0) => format!(
                        "{f}: topic `{topic}`: {}",
                        crate::log_contents::early_head_note(
                            d.count as usize,
                            d.first_time_s.unwrap_or(f64::NAN)
                        )
                    ),
                    DropKind::TimeOutlier => format!(
                        "{f}: topic `{topic}`: {}",
                        crate::log_contents::late_tail_note(
                            d.count as usize,
                            d.first_sample.unwrap_or(0) as usize,
                            d.first_time_s.unwrap_or(f64::NAN)
                        )
                    ),
                    DropKind::UnknownMessage => format!(
                        "{f}: {} frames of {topic} skipped: the ardupilotmega dialect does not know it",
                        d.count
                    ),
                    DropKind::Alignment => format!(
                        "{f}: {} of {} aligned rows dropped: topic `{topic}` had no value there (before its first sample or past its hold interval)",
                        d.count,
                        d.of.unwrap_or(0)
                    ),
                }
            })
            .collect()
    }
}
