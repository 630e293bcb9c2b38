//! PX4 ULog reader: every logged topic as a [`Topic`] with its own timestamps.
//!
//! The format is PX4's "ULog File Format" (docs.px4.io, `dev_log/ulog_file_format`; reference
//! reader: pyulog `core.py`): a 16-byte header (`ULog` magic, version, start time), then
//! messages `u16 size, u8 type, payload`. Read here: `B` flag bits (appended-data offsets,
//! incompatible flags), `F` formats (`name:type field;…`, nested types and fixed arrays), `P`
//! parameters, `A` subscriptions (`multi_id`, `msg_id`, format name) and `D` data; every other
//! type (`I`, `M`, `Q`, `L`, `C`, `S`, `O`, `R`, unknown) is skipped as the format requires.
//!
//! Topics:
//! - One topic per subscription `(message name, multi_id)`. Instance 0 is named by the message
//!   name alone (`actuator_outputs`), instance `k ≥ 1` as `name[k]` (`actuator_outputs[1]`), so
//!   a mapping written for a single-instance log reads a multi-instance one unchanged.
//! - Fields are flattened in declaration order: arrays as `field[i]` (`output[1]`, `q[0]`),
//!   nested types as `field.sub` (`heartbeats[0].type`); booleans are 0/1; `char` fields and
//!   `_padding…` fields are not numeric and are left out. The `timestamp` field is the time base.
//! - Times are the messages' `timestamp` (µs since boot) in seconds, **not** shifted to the
//!   log start: a few PX4 topics carry timestamps before the file header's start time, and an
//!   unsigned subtraction would wrap around (pyulog's `sample_log_small.ulg` has four).
//! - A sample whose timestamp does not increase over its topic's previous one is left out and
//!   counted in [`LogContents::dropped`] (never silently).
//! - Parameters (`PWM_MAIN_REV2`, …) are kept in [`LogContents::parameters`] (last value wins).
//!
//! A file that ends inside a message (a log cut at power-off) keeps every complete message
//! and reports the cut in [`LogContents::truncated_at`]. Any other problem is a
//! [`FlightDataError::LogDecode`] naming the file, the byte offset of the message and what is
//! wrong (message type, topic, field). The whole file is read into memory (logs are MB).
//!
//! Why not a crate: `yule_log` 0.4.0 reads both shipped PX4 logs correctly but decodes a
//! message cut off by the end of the file from a zero-filled buffer (fabricated samples at
//! time 0, found by the truncation proptest in `tests/fuzz_logs.rs`), prints a debug line to
//! stdout for every `*heartbeat*` format, and reports no byte offsets.

use crate::FlightDataError;
use crate::table::Topic;
use std::collections::BTreeMap;
use std::path::Path;

/// Everything a multi-rate log reader returns besides the topics.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogContents {
    /// The topics (message streams) that have samples, in order of subscription.
    pub topics: Vec<Topic>,
    /// Parameters by name, as logged (the last value of a parameter changed in flight).
    pub parameters: BTreeMap<String, f64>,
    /// Samples left out because their timestamp did not increase: topic name → count.
    pub dropped: BTreeMap<String, usize>,
    /// Byte offset of a message the file ends inside (that partial message is not used).
    pub truncated_at: Option<u64>,
    /// Corrupt stretches skipped to find the next message: `(byte offset, length)`
    /// (DataFlash resynchronises on the message header as pymavlink does; ULog never skips).
    pub skipped: Vec<(u64, u64)>,
}

impl LogContents {
    /// One line per thing left out of the topics (non-increasing samples, a truncated last
    /// message, skipped bytes), for the caller to print; empty when nothing was.
    pub fn notes(&self, file: &str) -> Vec<String> {
        let mut v: Vec<String> = self
            .dropped
            .iter()
            .map(|(t, n)| {
                format!("{file}: topic `{t}`: {n} samples left out (timestamp did not increase)")
            })
            .collect();
        if let Some(at) = self.truncated_at {
            v.push(format!("{file}: byte {at}: the file ends inside this message (not used)"));
        }
        for (at, len) in &self.skipped {
            v.push(format!("{file}: byte {at}: {len} corrupt bytes skipped"));
        }
        v
    }

    /// Ends a read: each builder's non-increasing samples go to [`LogContents::dropped`], and
    /// each builder that kept a sample becomes a topic, in the builders' order (the last step
    /// of both binary log readers, ULog and DataFlash).
    pub(crate) fn add_topics(&mut self, builders: Vec<TopicBuilder>) {
        for b in builders {
            if b.dropped > 0 {
                self.dropped.insert(b.name.clone(), b.dropped);
            }
            if !b.t_us.is_empty() {
                self.topics.push(b.finish());
            }
        }
    }
}

/// One topic being collected: timestamps in µs and the flattened fields.
pub(crate) struct TopicBuilder {
    pub(crate) name: String,
    pub(crate) t_us: Vec<u64>,
    pub(crate) names: Vec<String>,
    pub(crate) values: Vec<Vec<f64>>,
    pub(crate) dropped: usize,
}

impl TopicBuilder {
    pub(crate) fn new(name: String, names: Vec<String>) -> Self {
        let n = names.len();
        Self { name, t_us: Vec::new(), names, values: vec![Vec::new(); n], dropped: 0 }
    }

    /// Appends one sample if its time increases; `row` must have one value per field.
    pub(crate) fn push(&mut self, t_us: u64, row: &[f64]) {
        if self.t_us.last().is_some_and(|&last| t_us <= last) {
            self.dropped += 1;
            return;
        }
        self.t_us.push(t_us);
        for (col, v) in self.values.iter_mut().zip(row) {
            col.push(*v);
        }
    }

    pub(crate) fn finish(self) -> Topic {
        Topic {
            name: self.name,
            t_s: self.t_us.iter().map(|&t| t as f64 * 1e-6).collect(),
            fields: self.names.into_iter().zip(self.values).collect(),
        }
    }
}

/// Reads a ULog file's topics (see the module doc for naming and time base).
///
/// # Errors
/// [`FlightDataError::Io`] if the file cannot be opened, [`FlightDataError::LogDecode`] naming
/// the byte offset for a file that is not ULog or is corrupt.
pub fn read_ulog(path: &Path) -> Result<Vec<Topic>, FlightDataError> {
    Ok(read_ulog_contents(path)?.topics)
}

/// Reads a ULog file: topics, parameters and what was left out.
///
/// # Errors
/// As [`read_ulog`].
pub fn read_ulog_contents(path: &Path) -> Result<LogContents, FlightDataError> {
    let file = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|source| FlightDataError::Io { file: file.clone(), source })?;
    parse_ulog(&bytes, &file)
}

/// ULog file magic (first 7 bytes of the header).
const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// Header length: magic, version, start timestamp.
const HEADER_LEN: usize = 16;
/// Deepest nesting of formats followed (a format that contains itself is corrupt).
const MAX_NESTING: usize = 8;

/// Basic ULog field types and their sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Basic {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Char,
}

impl Basic {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "int8_t" => Self::I8,
            "uint8_t" => Self::U8,
            "int16_t" => Self::I16,
            "uint16_t" => Self::U16,
            "int32_t" => Self::I32,
            "uint32_t" => Self::U32,
            "int64_t" => Self::I64,
            "uint64_t" => Self::U64,
            "float" => Self::F32,
            "double" => Self::F64,
            "bool" => Self::Bool,
            "char" => Self::Char,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 | Self::Bool | Self::Char => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// Little-endian value at the start of `b` (`b.len() >= self.size()`).
    fn read(self, b: &[u8]) -> f64 {
        let a = |n: usize| -> [u8; 8] {
            let mut x = [0u8; 8];
            x[..n].copy_from_slice(&b[..n]);
            x
        };
        match self {
            Self::I8 => f64::from(b[0] as i8),
            Self::U8 | Self::Char => f64::from(b[0]),
            Self::Bool => f64::from(u8::from(b[0] != 0)),
            Self::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Self::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Self::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::I64 => i64::from_le_bytes(a(8)) as f64,
            Self::U64 => u64::from_le_bytes(a(8)) as f64,
            Self::F64 => f64::from_le_bytes(a(8)),
        }
    }
}

/// One `type name` entry of a format definition.
#[derive(Debug, Clone)]
struct FieldDef {
    /// Basic type name or a nested format's name.
    type_name: String,
    /// Array length, if an array.
    len: Option<usize>,
    name: String,
}

/// A numeric leaf of a compiled format: flattened name, type, byte offset in the struct.
#[derive(Debug, Clone)]
struct Leaf {
    name: String,
    kind: Basic,
    offset: usize,
}

/// A format compiled for decoding data messages.
#[derive(Debug, Clone)]
struct Compiled {
    /// Numeric leaves except the timestamp.
    leaves: Vec<Leaf>,
    /// Offset of the `uint64_t timestamp` field.
    timestamp: usize,
}

fn parse_format(text: &str) -> Result<(String, Vec<FieldDef>), String> {
    let (name, rest) = text.split_once(':').ok_or_else(|| format!("format `{text}` has no `:`"))?;
    let mut fields = Vec::new();
    for f in rest.split(';').map(str::trim).filter(|f| !f.is_empty()) {
        let (ty, fname) =
            f.split_once(' ').ok_or_else(|| format!("format `{name}`: field `{f}` has no type"))?;
        let (type_name, len) = match ty.split_once('[') {
            Some((t, n)) => {
                let n = n
                    .strip_suffix(']')
                    .and_then(|n| n.parse::<usize>().ok())
                    .filter(|n| *n <= 65_535)
                    .ok_or_else(|| format!("format `{name}`: bad array type `{ty}`"))?;
                (t.to_string(), Some(n))
            }
            None => (ty.to_string(), None),
        };
        fields.push(FieldDef { type_name, len, name: fname.trim().to_string() });
    }
    Ok((name.to_string(), fields))
}

/// Size of format `name` in bytes and its numeric leaves (prefixed with `prefix`), at `base`.
fn compile(
    formats: &BTreeMap<String, Vec<FieldDef>>,
    name: &str,
    prefix: &str,
    base: usize,
    depth: usize,
    leaves: &mut Vec<Leaf>,
) -> Result<usize, String> {
    if depth > MAX_NESTING {
        return Err(format!("format `{name}` nests deeper than {MAX_NESTING} levels"));
    }
    let fields = formats.get(name).ok_or_else(|| format!("no format definition for `{name}`"))?;
    let mut at = base;
    for f in fields {
        let count = f.len.unwrap_or(1);
        let padding = f.name.starts_with("_padding");
        if let Some(kind) = Basic::parse(&f.type_name) {
            if !padding && kind != Basic::Char {
                for i in 0..count {
                    let n = match f.len {
                        Some(_) => format!("{prefix}{}[{i}]", f.name),
                        None => format!("{prefix}{}", f.name),
                    };
                    leaves.push(Leaf { name: n, kind, offset: at + i * kind.size() });
                }
            }
            at += count * kind.size();
        } else {
            for i in 0..count {
                let p = match f.len {
                    Some(_) => format!("{prefix}{}[{i}].", f.name),
                    None => format!("{prefix}{}.", f.name),
                };
                let mut sub = Vec::new();
                at = compile(formats, &f.type_name, &p, at, depth + 1, &mut sub)?;
                if !padding {
                    leaves.extend(sub);
                }
            }
        }
    }
    Ok(at)
}

fn compile_topic(
    formats: &BTreeMap<String, Vec<FieldDef>>,
    name: &str,
) -> Result<Compiled, String> {
    let mut leaves = Vec::new();
    compile(formats, name, "", 0, 0, &mut leaves)?;
    let ts = leaves
        .iter()
        .position(|l| l.name == "timestamp" && l.kind == Basic::U64)
        .ok_or_else(|| format!("format `{name}` has no `uint64_t timestamp` field"))?;
    let timestamp = leaves.remove(ts).offset;
    Ok(Compiled { leaves, timestamp })
}

struct Subscription {
    topic: usize,
    compiled: Compiled,
}

/// Decodes ULog bytes; `file` names them in errors.
///
/// # Errors
/// [`FlightDataError::LogDecode`] naming `file`, the byte offset of the offending message and
/// what is wrong: not a ULog file, unknown incompatible flags, a malformed format definition,
/// subscription or parameter, a data message for an unknown subscription or shorter than its
/// format.
pub fn parse_ulog(bytes: &[u8], file: &str) -> Result<LogContents, FlightDataError> {
    let err = |offset: usize, message: String| FlightDataError::LogDecode {
        file: file.to_string(),
        offset: offset as u64,
        message,
    };
    if bytes.len() < HEADER_LEN || bytes[..7] != MAGIC {
        return Err(err(0, "not a ULog file (no `ULog` header magic)".into()));
    }
    let mut out = LogContents::default();
    let mut formats: BTreeMap<String, Vec<FieldDef>> = BTreeMap::new();
    let mut subs: BTreeMap<u16, Subscription> = BTreeMap::new();
    let mut builders: Vec<TopicBuilder> = Vec::new();
    let mut by_key: BTreeMap<(String, u8), usize> = BTreeMap::new();
    let mut appended: Vec<usize> = Vec::new();
    let mut row: Vec<f64> = Vec::new();
    let mut at = HEADER_LEN;
    while at < bytes.len() {
        // A main section that ends inside a message before appended data: continue there.
        if let Some(&next) = appended.first()
            && at + 3 > next
        {
            at = next;
            appended.remove(0);
            continue;
        }
        let Some(head) = bytes.get(at..at + 3) else {
            out.truncated_at = Some(at as u64);
            break;
        };
        let size = usize::from(u16::from_le_bytes([head[0], head[1]]));
        let kind = head[2];
        let Some(payload) = bytes.get(at + 3..at + 3 + size) else {
            if appended.first().is_some_and(|&next| next > at) {
                at = appended.remove(0);
                continue;
            }
            out.truncated_at = Some(at as u64);
            break;
        };
        let text = |b: &[u8], what: &str| {
            std::str::from_utf8(b)
                .map(str::to_string)
                .map_err(|_| err(at, format!("`{}` message: {what} is not UTF-8", kind as char)))
        };
        match kind {
            b'B' => {
                if payload.len() < 40 {
                    return Err(err(at, format!("flag bits message of {size} bytes (< 40)")));
                }
                let incompat = &payload[8..16];
                if incompat[0] & !1 != 0 || incompat[1..].iter().any(|b| *b != 0) {
                    return Err(err(
                        at,
                        format!(
                            "unknown incompatible flags {incompat:?}: this ULog version is not supported"
                        ),
                    ));
                }
                if incompat[0] & 1 == 1 {
                    for k in 0..3 {
                        let o = u64::from_le_bytes(
                            payload[16 + 8 * k..24 + 8 * k].try_into().unwrap_or([0; 8]),
                        );
                        if o > 0 && (o as usize) > at && (o as usize) <= bytes.len() {
                            appended.push(o as usize);
                        }
                    }
                    appended.sort_unstable();
                }
            }
            b'F' => {
                let t = text(payload, "the format")?;
                let (name, fields) = parse_format(&t).map_err(|m| err(at, m))?;
                formats.insert(name, fields);
            }
            b'P' => {
                let Some((&klen, rest)) = payload.split_first() else {
                    return Err(err(at, "empty parameter message".into()));
                };
                let klen = usize::from(klen);
                let (Some(key), Some(value)) = (rest.get(..klen), rest.get(klen..)) else {
                    return Err(err(at, "parameter key runs past the message".into()));
                };
                let key = text(key, "the parameter key")?;
                let (ty, name) = key
                    .split_once(' ')
                    .ok_or_else(|| err(at, format!("parameter key `{key}` has no type")))?;
                let v = match (ty, value) {
                    ("int32_t", [a, b, c, d, ..]) => {
                        f64::from(i32::from_le_bytes([*a, *b, *c, *d]))
                    }
                    ("float", [a, b, c, d, ..]) => f64::from(f32::from_le_bytes([*a, *b, *c, *d])),
                    _ => {
                        return Err(err(
                            at,
                            format!(
                                "parameter `{name}`: type `{ty}` with {} value bytes",
                                value.len()
                            ),
                        ));
                    }
                };
                out.parameters.insert(name.to_string(), v);
            }
            b'A' => {
                if payload.len() < 3 {
                    return Err(err(at, format!("subscription message of {size} bytes (< 3)")));
                }
                let multi = payload[0];
                let id = u16::from_le_bytes([payload[1], payload[2]]);
                let name = text(&payload[3..], "the subscription's format name")?;
                let compiled = compile_topic(&formats, &name)
                    .map_err(|m| err(at, format!("subscription {id} (`{name}`): {m}")))?;
                let key = (name.clone(), multi);
                let topic = match by_key.get(&key) {
                    Some(&i) => i,
                    None => {
                        let tname = if multi == 0 { name } else { format!("{name}[{multi}]") };
                        let names = compiled.leaves.iter().map(|l| l.name.clone()).collect();
                        builders.push(TopicBuilder::new(tname, names));
                        by_key.insert(key, builders.len() - 1);
                        builders.len() - 1
                    }
                };
                subs.insert(id, Subscription { topic, compiled });
            }
            b'D' => {
                if payload.len() < 2 {
                    return Err(err(at, format!("data message of {size} bytes (< 2)")));
                }
                let id = u16::from_le_bytes([payload[0], payload[1]]);
                let data = &payload[2..];
                let sub = subs.get(&id).ok_or_else(|| {
                    err(at, format!("data message for unknown subscription {id}"))
                })?;
                let b = &mut builders[sub.topic];
                let field = |l: &Leaf| data.get(l.offset..l.offset + l.kind.size());
                let Some(ts) = data.get(sub.compiled.timestamp..sub.compiled.timestamp + 8) else {
                    return Err(err(
                        at,
                        format!("topic `{}`: data message too short for `timestamp`", b.name),
                    ));
                };
                let t_us = u64::from_le_bytes(ts.try_into().unwrap_or([0; 8]));
                row.clear();
                for l in &sub.compiled.leaves {
                    let Some(v) = field(l) else {
                        return Err(err(
                            at,
                            format!(
                                "topic `{}`: data message of {} bytes too short for field `{}` (byte {} of the struct)",
                                b.name,
                                data.len(),
                                l.name,
                                l.offset
                            ),
                        ));
                    };
                    row.push(l.kind.read(v));
                }
                b.push(t_us, &row);
            }
            _ => {}
        }
        at += 3 + size;
    }
    out.add_topics(builders);
    Ok(out)
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_not_ulog_names_file_and_offset() {
        let e = parse_ulog(b"this is not a ulog file at all", "x.ulg").unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("x.ulg: byte "), "{s}");
        assert!(matches!(e, FlightDataError::LogDecode { .. }), "{s}");
    }

    #[test]
    fn analytic_builder_drops_non_increasing_times_and_converts_us_to_s() {
        let mut b = TopicBuilder::new("t".into(), vec!["x".into()]);
        b.push(1_000_000, &[1.0]);
        b.push(1_000_000, &[2.0]);
        b.push(500_000, &[3.0]);
        b.push(1_500_000, &[4.0]);
        assert_eq!(b.dropped, 2);
        let t = b.finish();
        assert_eq!(t.t_s, vec![1.0, 1.5]);
        assert_eq!(t.fields, vec![("x".to_string(), vec![1.0, 4.0])]);
    }
}
