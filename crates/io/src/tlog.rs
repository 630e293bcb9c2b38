//! MAVLink telemetry logs (`.tlog`, as Mission Planner, MAVProxy and QGroundControl write
//! them), for `aeroident inspect` and, aligned by the mapping's `[align]` as a ULog or
//! DataFlash log is, for `replay` ([`crate::log::open_log`]; a live feed: docs/mavlink.md).
//!
//! The file is a sequence of records: a big-endian `u64` timestamp (µs since the Unix epoch,
//! when the ground station received the message) and one MAVLink frame, v1 (`0xFE`, 6-byte
//! header) or v2 (`0xFD`, 10-byte header, 13 more bytes when signed), each ending in its
//! CRC-16/MCRF4XX over the frame after the magic byte and the message's `CRC_EXTRA`
//! (mavlink.io, "Packet Serialization"). Frames are decoded with the `mavlink` crate's
//! `ardupilotmega` dialect (which includes `common`).
//!
//! Topics: one per message name, times the records' timestamps in seconds (Unix time); a
//! message that carries a `name` (`NAMED_VALUE_FLOAT`, `NAMED_VALUE_INT`, `DEBUG_FLOAT_ARRAY`)
//! is one topic per name, `NAMED_VALUE_FLOAT[de]`, as a live feed names it (docs/mavlink.md),
//! so one mapping reads the recorded and the live traffic alike. (One topic for every name
//! kept only the last name's value at each time.)
//! Fields: the message's numeric fields as the crate names them, in alphabetical order, arrays
//! as `field[i]`; enum, flag and text fields are not numeric and are left out; a float sent
//! as NaN is NaN. `PARAM_VALUE` messages fill [`LogContents::parameters`].
//!
//! A record whose frame does not start with a magic byte, runs past the end of the file or
//! fails its CRC is corrupt: one byte is skipped and the next record looked for (listed in
//! [`LogContents::skipped`]); a frame whose message id the dialect does not know cannot be
//! checked and is skipped whole, counted in a note. The file is streamed; only what a
//! [`TopicFilter`] names is kept.

use crate::FlightDataError;
use crate::byte_window::ByteWindow;
use crate::log_contents::{LogContents, TopicBuilder, TopicFilter};
use mavlink::Message;
use mavlink::dialects::ardupilotmega::MavMessage;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::Path;

/// One record's frame: its length in bytes, the message id and where its payload lies.
struct Frame {
    len: usize,
    id: u32,
    payload: std::ops::Range<usize>,
    version: mavlink::MavlinkVersion,
}

/// The frame at the start of `b` (magic byte first) if its header is complete: `None` for no
/// magic byte. The length may exceed `b` (the caller reads more).
fn frame_header(b: &[u8]) -> Option<Frame> {
    match *b.first()? {
        0xFE if b.len() >= 6 => {
            let n = usize::from(b[1]);
            Some(Frame {
                len: 8 + n,
                id: u32::from(b[5]),
                payload: 6..6 + n,
                version: mavlink::MavlinkVersion::V1,
            })
        }
        0xFD if b.len() >= 10 => {
            let n = usize::from(b[1]);
            let signed = if b[2] & 1 == 1 { 13 } else { 0 };
            let id = u32::from_le_bytes([b[7], b[8], b[9], 0]);
            Some(Frame {
                len: 12 + n + signed,
                id,
                payload: 10..10 + n,
                version: mavlink::MavlinkVersion::V2,
            })
        }
        _ => None,
    }
}

/// Reads a `.tlog` keeping what `filter` names (module doc), with a note of the frames of
/// message ids the dialect does not know, if any.
///
/// # Errors
/// [`FlightDataError::Io`] naming the file; [`FlightDataError::LogDecode`] at byte 0 for a
/// file with no valid MAVLink record.
pub fn read_tlog_filtered(
    path: &Path,
    filter: &TopicFilter,
) -> Result<(LogContents, Option<String>), FlightDataError> {
    let file = path.display().to_string();
    let f = std::fs::File::open(path)
        .map_err(|source| FlightDataError::Io { file: file.clone(), source })?;
    decode_tlog(f, &file, filter)
}

/// The decoder's state between records.
struct Decoder<'a> {
    filter: &'a TopicFilter,
    out: LogContents,
    builders: Vec<TopicBuilder>,
    by_name: HashMap<String, usize>,
    unknown_ids: BTreeMap<u32, usize>,
}

/// Decodes a `.tlog` stream keeping what `filter` names; `file` names it in errors.
///
/// # Errors
/// As [`read_tlog_filtered`].
pub fn decode_tlog<R: Read>(
    source: R,
    file: &str,
    filter: &TopicFilter,
) -> Result<(LogContents, Option<String>), FlightDataError> {
    let io = |source| FlightDataError::Io { file: file.to_string(), source };
    let mut w = ByteWindow::new(source);
    let mut d = Decoder {
        filter,
        out: LogContents::default(),
        builders: Vec::new(),
        by_name: HashMap::new(),
        unknown_ids: BTreeMap::new(),
    };
    let (mut skip_start, mut messages): (Option<u64>, usize) = (None, 0);
    loop {
        let at = w.offset();
        let Some(b) = w.peek(9).map_err(io)? else {
            if !w.at_end().map_err(io)? {
                d.out.truncated_at = Some(at);
            }
            break;
        };
        let header = match b[8] {
            0xFE => 6,
            0xFD => 10,
            _ => 0,
        };
        let frame = match w.peek(8 + header.max(1)).map_err(io)? {
            Some(h) if header > 0 => frame_header(&h[8..]),
            Some(_) => None,
            None => {
                d.out.truncated_at = Some(at);
                break;
            }
        };
        let Some(frame) = frame else {
            skip_start.get_or_insert(at);
            w.consume(1).map_err(io)?;
            continue;
        };
        let Some(rec) = w.peek(8 + frame.len).map_err(io)?.map(<[u8]>::to_vec) else {
            d.out.truncated_at = Some(at);
            break;
        };
        if d.record(&rec, &frame, at).is_some() {
            if let Some(s) = skip_start.take() {
                d.out.skip(s, at - s);
            }
            messages += 1;
            w.consume((8 + frame.len) as u64).map_err(io)?;
        } else {
            skip_start.get_or_insert(at);
            w.consume(1).map_err(io)?;
        }
    }
    if let Some(s) = skip_start {
        let end = w.offset();
        d.out.skip(s, end - s);
    }
    if messages == 0 {
        return Err(FlightDataError::LogDecode { file: file.to_string(), offset: 0, message: "no MAVLink telemetry record found (a big-endian µs timestamp, then a frame starting 0xFE or 0xFD with a valid CRC)".into() });
    }
    Ok(d.finish(file))
}

impl Decoder<'_> {
    /// One record `rec` (timestamp and frame) at byte `at`: `None` when the frame is corrupt.
    fn record(&mut self, rec: &[u8], frame: &Frame, at: u64) -> Option<()> {
        let t_us = u64::from_be_bytes(rec[..8].try_into().ok()?);
        let b = &rec[8..];
        if MavMessage::default_message_from_id(frame.id).is_none() {
            *self.unknown_ids.entry(frame.id).or_default() += 1;
            return Some(());
        }
        let crc_end = frame.payload.end;
        let crc = mavlink::calculate_crc(&b[1..crc_end], MavMessage::extra_crc(frame.id));
        if crc.to_le_bytes() != b[crc_end..crc_end + 2] {
            return None;
        }
        let msg = MavMessage::parse(frame.version, frame.id, &b[frame.payload.clone()]).ok()?;
        self.message(&msg, t_us, at);
        Some(())
    }

    /// A decoded message received at `t_us`.
    fn message(&mut self, msg: &MavMessage, t_us: u64, at: u64) {
        let Ok(Value::Object(obj)) = serde_json::to_value(msg) else { return };
        if let MavMessage::PARAM_VALUE(p) = msg
            && let Some(name) = obj.get("param_id").and_then(Value::as_str)
        {
            let name = name.trim_end_matches('\0').to_string();
            self.out.parameters.insert(name, f64::from(p.param_value));
        }
        let name = topic_name(msg.message_name(), &obj);
        let b = match self.by_name.get(&name) {
            Some(&b) => b,
            None => {
                let all = numeric_fields(&obj).into_iter().map(|(f, _)| f).collect::<Vec<_>>();
                let kept = self.filter.topic(&name).map(|only| {
                    all.iter().filter(|f| only.is_none_or(|s| s.contains(*f))).cloned().collect()
                });
                self.builders.push(TopicBuilder::new(name.clone(), all, kept));
                self.by_name.insert(name, self.builders.len() - 1);
                self.builders.len() - 1
            }
        };
        let builder = &mut self.builders[b];
        let values: HashMap<String, f64> = numeric_fields(&obj).into_iter().collect();
        let row: Vec<f64> =
            builder.names.iter().map(|n| values.get(n).copied().unwrap_or(f64::NAN)).collect();
        builder.push(t_us, &row, at);
    }

    /// The contents read, and a note of the frames of unknown message ids (if any).
    fn finish(self, file: &str) -> (LogContents, Option<String>) {
        let Decoder { mut out, builders, unknown_ids, .. } = self;
        out.add_topics(builders);
        out.unknown_messages = unknown_ids.clone();
        let note = (!unknown_ids.is_empty()).then(|| {
            let ids: Vec<String> =
                unknown_ids.iter().map(|(id, n)| format!("{id} ({n}×)")).collect();
            format!(
                "{file}: frames of message ids the ardupilotmega dialect does not know were skipped: {}",
                ids.join(", ")
            )
        });
        (out, note)
    }
}

/// The topic of a message `message` serialised as `obj`: `MESSAGE[name]` when it carries a
/// text `name` (trailing NULs dropped), else the message name (module doc).
fn topic_name(message: &str, obj: &serde_json::Map<String, Value>) -> String {
    match obj.get("name") {
        Some(Value::String(n)) => format!("{message}[{}]", n.trim_end_matches('\0')),
        _ => message.to_string(),
    }
}

/// The numeric fields of a serialised message (module doc), `(name, value)`.
fn numeric_fields(obj: &serde_json::Map<String, Value>) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for (k, v) in obj.iter().filter(|(k, _)| *k != "type") {
        match v {
            Value::Number(n) => out.push((k.clone(), n.as_f64().unwrap_or(f64::NAN))),
            Value::Null => out.push((k.clone(), f64::NAN)),
            Value::Array(a) if a.iter().all(|x| x.is_number() || x.is_null()) => {
                for (i, x) in a.iter().enumerate() {
                    out.push((format!("{k}[{i}]"), x.as_f64().unwrap_or(f64::NAN)));
                }
            }
            _ => {}
        }
    }
    out
}
