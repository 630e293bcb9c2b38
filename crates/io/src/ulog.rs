//! PX4 ULog reader: every logged topic as a [`Topic`] with its own timestamps.
//!
//! The format is PX4's "ULog File Format" (docs.px4.io, `dev_log/ulog_file_format`; reference
//! reader: pyulog `core.py`): a 16-byte header (`ULog` magic, version, start time), then
//! messages `u16 size, u8 type, payload`. Read here: `B` flag bits (appended-data offsets,
//! incompatible flags), `F` formats (`name:type field;…`, nested types and fixed arrays), `P`
//! parameters, `A` subscriptions (`multi_id`, `msg_id`, format name), `R` removals of a
//! subscription and `D` data; every other type (`I`, `M`, `Q`, `L`, `C`, `S`, `O`, unknown) is
//! skipped as the format requires.
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
//! - A subscription is decoded by the format definition in force when it was made: a format
//!   redefined under a new `msg_id` with its fields reordered fills the same topic by field
//!   name; one redefined with other fields is a new topic `name#2`, `name#3`, … .
//! - Samples whose timestamps break the increasing order are left out, the fewest that must
//!   go ([`crate::log_contents`]), and counted in [`LogContents::dropped`] (never silently).
//! - Parameters (`PWM_MAIN_REV2`, …) are kept in [`LogContents::parameters`] (last value wins).
//! - A `msg_id` names one subscription until an `R` message removes it. Subscribing it again
//!   to the same format name and instance (a repeated `A`) goes on filling that topic;
//!   subscribing it to another topic or instance while it is still subscribed is an error
//!   naming the byte, the id and both topics: the data after it could be either topic's. After
//!   an `R` the id may be subscribed to anything (the spec asks writers not to re-use an id
//!   even then, but the `R` tells the topics apart), and data for it before that are an error.
//!   An `R` for an id not subscribed removes nothing.
//!
//! Sizes are checked before anything is allocated for them: a format whose struct (arrays of
//! nested formats included) would exceed the 65 533 bytes a data message can carry, nests
//! deeper than 8 levels, or whose flattened field names pass 1 MiB is an error naming the
//! subscription, the format and the field. So is a log whose subscriptions together would
//! build more than 64 MiB of names: each subscription builds its names anew, and a few bytes
//! of subscription message could otherwise cost a megabyte each (the shipped PX4 logs build
//! 14 and 18 kB). `_padding…` fields are skipped by their size, never expanded into names:
//! the work a format costs is bounded by its definition's bytes and these limits.
//!
//! A file that ends inside a message (a log cut at power-off) keeps every complete message
//! and reports the cut in [`LogContents::truncated_at`]. Any other problem is a
//! [`FlightDataError::LogDecode`] naming the file, the byte offset of the message and what is
//! wrong (message type, topic, field). The file is streamed; only the topics and fields a
//! [`TopicFilter`] names are kept ([`read_ulog_filtered`]).
//!
//! Why not a crate: `yule_log` 0.4.0 reads both shipped PX4 logs correctly but decodes a
//! message cut off by the end of the file from a zero-filled buffer (fabricated samples at
//! time 0, found by the truncation proptest in `tests/all/fuzz_logs.rs`), prints a debug line to
//! stdout for every `*heartbeat*` format, and reports no byte offsets.

use crate::FlightDataError;
use crate::byte_window::ByteWindow;
use crate::log_contents::TopicBuilder;
pub use crate::log_contents::{LogContents, TopicFilter, TopicInfo};
use crate::table::Topic;
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::Path;

/// Reads a ULog file's topics (see the module doc for naming and time base).
///
/// # Errors
/// [`FlightDataError::Io`] if the file cannot be opened, [`FlightDataError::LogDecode`] naming
/// the byte offset for a file that is not ULog or is corrupt.
pub fn read_ulog(path: &Path) -> Result<Vec<Topic>, FlightDataError> {
    Ok(read_ulog_contents(path)?.topics)
}

/// Reads a ULog file: every topic, parameters and what was left out.
///
/// # Errors
/// As [`read_ulog`].
pub fn read_ulog_contents(path: &Path) -> Result<LogContents, FlightDataError> {
    read_ulog_filtered(path, &TopicFilter::all())
}

/// Reads a ULog file keeping only the topics and fields `filter` names (the others are
/// checked, counted and listed in [`LogContents::catalogue`]); the file is streamed.
///
/// # Errors
/// As [`read_ulog`].
pub fn read_ulog_filtered(
    path: &Path,
    filter: &TopicFilter,
) -> Result<LogContents, FlightDataError> {
    let file = path.display().to_string();
    let f = std::fs::File::open(path)
        .map_err(|source| FlightDataError::Io { file: file.clone(), source })?;
    decode_ulog(f, &file, filter)
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
    /// Bytes a data message needs to hold every leaf and the timestamp (trailing padding
    /// may be left out of a message).
    min_len: usize,
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

/// Largest struct a data message can carry: its payload size is a `u16`, less the 2-byte
/// `msg_id`.
const MAX_STRUCT: usize = 65_535 - 2;
/// Most fields the subscriptions and topic layouts of one log may define in all (a log can
/// subscribe 65 536 times to a 65 000-field format in a few hundred kB).
const MAX_FIELDS: usize = 2_000_000;
/// Most bytes of flattened field names one topic may have (a nested array repeats its
/// prefix for every element: `a[3].b[7].c`).
const MAX_NAME_BYTES: usize = 1 << 20;

/// The type of field `f` as written in the format (`float[3]`).
fn type_text(f: &FieldDef) -> String {
    match f.len {
        Some(n) => format!("{}[{n}]", f.type_name),
        None => f.type_name.clone(),
    }
}

/// Size in bytes of format `name`, checked against [`MAX_STRUCT`] and [`MAX_NESTING`] before
/// anything is allocated per element (a format nesting arrays of arrays declares sizes far
/// beyond what a message can hold). `memo` holds the sizes of formats already computed;
/// `visited` counts the fields looked at (each format's once).
fn struct_size(
    formats: &BTreeMap<String, Vec<FieldDef>>,
    name: &str,
    depth: usize,
    memo: &mut BTreeMap<String, usize>,
    visited: &mut usize,
) -> Result<usize, String> {
    if let Some(&s) = memo.get(name) {
        return Ok(s);
    }
    if depth > MAX_NESTING {
        return Err(format!("format `{name}` nests deeper than {MAX_NESTING} levels"));
    }
    let fields = formats.get(name).ok_or_else(|| format!("no format definition for `{name}`"))?;
    let mut total: usize = 0;
    *visited += fields.len();
    for f in fields {
        let one = match Basic::parse(&f.type_name) {
            Some(k) => k.size(),
            None => {
                let s = struct_size(formats, &f.type_name, depth + 1, memo, visited)?;
                if s == 0 {
                    return Err(format!(
                        "format `{name}`: field `{} {}`: nested format `{}` has no bytes",
                        type_text(f),
                        f.name,
                        f.type_name
                    ));
                }
                s
            }
        };
        total = f
            .len
            .unwrap_or(1)
            .checked_mul(one)
            .and_then(|b| total.checked_add(b))
            .filter(|t| *t <= MAX_STRUCT)
            .ok_or_else(|| {
                format!(
                    "format `{name}`: field `{} {}` makes the struct larger than {MAX_STRUCT} \
                     bytes, the most a data message holds",
                    type_text(f),
                    f.name
                )
            })?;
    }
    memo.insert(name.to_string(), total);
    Ok(total)
}

/// Most work compiling all of a log's subscriptions may take, counted as [`compile`] counts it
/// (bytes of names built plus one per field visited) and one per field [`struct_size`]
/// visits: every subscription builds its names anew, so a few bytes of `A` message could
/// otherwise make a megabyte of names each, again and again.
const MAX_LOG_NAME_WORK: usize = 64 << 20;

/// Flattens a topic's format into its numeric leaves, counting the work against
/// [`MAX_NAME_BYTES`] for the topic and `log_left` for the log.
struct Flatten<'a> {
    formats: &'a BTreeMap<String, Vec<FieldDef>>,
    /// Sizes of the formats the topic reaches, from [`struct_size`].
    sizes: &'a BTreeMap<String, usize>,
    leaves: Vec<Leaf>,
    /// Bytes of names (leaves and the prefixes of nested elements) built for this topic, plus
    /// one per field visited (a field may have no bytes and no name: `char[0] x`).
    work: usize,
    /// What [`MAX_LOG_NAME_WORK`] still allows.
    log_left: &'a mut usize,
}

impl Flatten<'_> {
    /// Counts `n` units of work done for field `f` of format `name`.
    fn spend(&mut self, n: usize, name: &str, f: &FieldDef) -> Result<(), String> {
        let field = || format!("format `{name}`: field `{} {}`", type_text(f), f.name);
        self.work += n;
        if self.work > MAX_NAME_BYTES {
            return Err(format!(
                "{}: the flattened field names pass {MAX_NAME_BYTES} bytes",
                field()
            ));
        }
        *self.log_left = self.log_left.checked_sub(n).ok_or_else(|| {
            format!(
                "{}: the flattened field names of this log's subscriptions pass \
                 {MAX_LOG_NAME_WORK} bytes in all",
                field()
            )
        })?;
        Ok(())
    }

    /// Appends the numeric leaves of format `name` (prefixed with `prefix`, at byte `base`);
    /// returns the offset after the struct. Call only after [`struct_size`] accepted the
    /// topic: every nested element then has at least one byte, so the elements visited are
    /// at most [`MAX_STRUCT`]. Padding is skipped by its size, never expanded: its elements
    /// have no names to build.
    fn compile(&mut self, name: &str, prefix: &str, base: usize) -> Result<usize, String> {
        let formats = self.formats;
        let fields =
            formats.get(name).ok_or_else(|| format!("no format definition for `{name}`"))?;
        let mut at = base;
        for f in fields {
            self.spend(1, name, f)?;
            let count = f.len.unwrap_or(1);
            let padding = f.name.starts_with("_padding");
            let element = |i: usize, dot: &str| match f.len {
                Some(_) => format!("{prefix}{}[{i}]{dot}", f.name),
                None => format!("{prefix}{}{dot}", f.name),
            };
            let basic = Basic::parse(&f.type_name);
            if padding || basic == Some(Basic::Char) {
                let one = match basic {
                    Some(k) => k.size(),
                    None => self
                        .sizes
                        .get(&f.type_name)
                        .copied()
                        .ok_or_else(|| format!("no format definition for `{}`", f.type_name))?,
                };
                at += count * one;
            } else if let Some(kind) = basic {
                for i in 0..count {
                    let n = element(i, "");
                    self.spend(n.len(), name, f)?;
                    self.leaves.push(Leaf { name: n, kind, offset: at + i * kind.size() });
                }
                at += count * kind.size();
            } else {
                for i in 0..count {
                    let p = element(i, ".");
                    self.spend(p.len(), name, f)?;
                    at = self.compile(&f.type_name, &p, at)?;
                }
            }
        }
        Ok(at)
    }
}

/// Compiles topic format `name`; `budget` is how many more fields the log may hold
/// ([`MAX_FIELDS`]), checked against the struct's size (at least a byte per field) before
/// the fields are built; `log_left` is what [`MAX_LOG_NAME_WORK`] still allows.
fn compile_topic(
    formats: &BTreeMap<String, Vec<FieldDef>>,
    name: &str,
    budget: usize,
    log_left: &mut usize,
) -> Result<Compiled, String> {
    let mut sizes = BTreeMap::new();
    let mut visited = 0;
    let size = struct_size(formats, name, 0, &mut sizes, &mut visited)?;
    *log_left = log_left.checked_sub(visited).ok_or_else(|| {
        format!(
            "format `{name}`: its definitions ({visited} fields): the flattened field names of \
             this log's subscriptions pass {MAX_LOG_NAME_WORK} bytes in all"
        )
    })?;
    if size > budget {
        return Err(format!(
            "format `{name}` ({size} bytes) would take the fields of this log's subscriptions \
             past {MAX_FIELDS} in all"
        ));
    }
    let mut flat = Flatten { formats, sizes: &sizes, leaves: Vec::new(), work: 0, log_left };
    flat.compile(name, "", 0)?;
    let mut leaves = flat.leaves;
    let ts = leaves
        .iter()
        .position(|l| l.name == "timestamp" && l.kind == Basic::U64)
        .ok_or_else(|| format!("format `{name}` has no `uint64_t timestamp` field"))?;
    let timestamp = leaves.remove(ts).offset;
    let min_len = leaves.iter().map(|l| l.offset + l.kind.size()).fold(timestamp + 8, usize::max);
    Ok(Compiled { leaves, timestamp, min_len })
}

/// A subscription (`msg_id`) with the format in force when it was made.
struct Subscription {
    /// Index of its topic's builder.
    topic: usize,
    compiled: Compiled,
    /// For each kept field of the topic, in the topic's order, the leaf that holds it here.
    columns: Vec<usize>,
    /// The format name and instance subscribed, and the byte of the `A` message.
    name: String,
    multi: u8,
    at: u64,
}

/// A subscription an `R` message removed: what it was, and the byte of the `R`.
struct Removed {
    at: u64,
    name: String,
    multi: u8,
}

/// The reader's state between messages.
struct Decoder<'a> {
    filter: &'a TopicFilter,
    out: LogContents,
    formats: BTreeMap<String, Vec<FieldDef>>,
    subs: BTreeMap<u16, Subscription>,
    /// Ids whose subscription an `R` removed and that are not subscribed again (at most one
    /// entry per `u16`).
    removed: BTreeMap<u16, Removed>,
    builders: Vec<TopicBuilder>,
    /// `(message name, multi_id, sorted field names)` → its builder, and the layouts seen
    /// per `(message name, multi_id)` (a format redefined with other fields is a topic
    /// `name#2`, …): one lookup per subscription however often a format is redefined.
    layouts: HashMap<(String, u8, Vec<String>), usize>,
    layout_count: HashMap<(String, u8), usize>,
    /// Fields held by the live subscriptions and the topic layouts, against [`MAX_FIELDS`].
    fields_held: usize,
    /// What [`MAX_LOG_NAME_WORK`] still allows the subscriptions to come.
    name_work_left: usize,
    /// Offsets of appended-data sections still ahead.
    appended: Vec<u64>,
    row: Vec<f64>,
}

/// Decodes ULog bytes; `file` names them in errors. Every topic and field is kept.
///
/// # Errors
/// [`FlightDataError::LogDecode`] naming `file`, the byte offset of the offending message and
/// what is wrong: not a ULog file, unknown incompatible flags, a malformed format definition
/// (or one whose declared size or nesting no data message can hold), subscription, removal or
/// parameter, a `msg_id` subscribed to a second topic without an `R` removing the first, a data
/// message for an unknown or removed subscription or shorter than its format.
pub fn parse_ulog(bytes: &[u8], file: &str) -> Result<LogContents, FlightDataError> {
    decode_ulog(bytes, file, &TopicFilter::all())
}

/// Decodes a ULog stream keeping what `filter` names; `file` names it in errors.
///
/// # Errors
/// As [`parse_ulog`], and [`FlightDataError::Io`] for a read error.
pub fn decode_ulog<R: Read>(
    source: R,
    file: &str,
    filter: &TopicFilter,
) -> Result<LogContents, FlightDataError> {
    let io = |source| FlightDataError::Io { file: file.to_string(), source };
    let mut w = ByteWindow::new(source);
    match w.peek(HEADER_LEN).map_err(io)? {
        Some(h) if h[..7] == MAGIC => {}
        _ => {
            return Err(FlightDataError::LogDecode {
                file: file.to_string(),
                offset: 0,
                message: "not a ULog file (no `ULog` header magic)".into(),
            });
        }
    }
    w.consume(HEADER_LEN as u64).map_err(io)?;
    let mut d = Decoder {
        filter,
        out: LogContents::default(),
        formats: BTreeMap::new(),
        subs: BTreeMap::new(),
        removed: BTreeMap::new(),
        builders: Vec::new(),
        layouts: HashMap::new(),
        layout_count: HashMap::new(),
        fields_held: 0,
        name_work_left: MAX_LOG_NAME_WORK,
        appended: Vec::new(),
        row: Vec::new(),
    };
    loop {
        let at = w.offset();
        if let Some(&next) = d.appended.first()
            && next <= at
        {
            d.appended.remove(0);
            continue;
        }
        let Some(head) = w.peek(3).map_err(io)? else {
            if !w.at_end().map_err(io)? {
                d.out.truncated_at = Some(at);
            }
            break;
        };
        let size = usize::from(u16::from_le_bytes([head[0], head[1]]));
        let end = at + 3 + size as u64;
        // A main section that ends inside a message before appended data: continue there.
        if let Some(&next) = d.appended.first()
            && next < end
        {
            if w.peek((next - at) as usize).map_err(io)?.is_none() {
                d.out.truncated_at = Some(at);
                break;
            }
            w.consume(next - at).map_err(io)?;
            d.appended.remove(0);
            continue;
        }
        let Some(msg) = w.peek(3 + size).map_err(io)? else {
            d.out.truncated_at = Some(at);
            break;
        };
        d.message(msg[2], &msg[3..], at, file)?;
        w.consume(3 + size as u64).map_err(io)?;
    }
    let Decoder { mut out, builders, .. } = d;
    out.add_topics(builders);
    Ok(out)
}

impl Decoder<'_> {
    /// Handles one message of type `kind` at byte `at`.
    fn message(
        &mut self,
        kind: u8,
        payload: &[u8],
        at: u64,
        file: &str,
    ) -> Result<(), FlightDataError> {
        let err = |message: String| FlightDataError::LogDecode {
            file: file.to_string(),
            offset: at,
            message,
        };
        let text = |b: &[u8], what: &str| {
            std::str::from_utf8(b)
                .map(str::to_string)
                .map_err(|_| err(format!("`{}` message: {what} is not UTF-8", kind as char)))
        };
        match kind {
            b'B' => self.flag_bits(payload, at).map_err(err)?,
            b'F' => {
                let t = text(payload, "the format")?;
                let (name, fields) = parse_format(&t).map_err(err)?;
                self.formats.insert(name, fields);
            }
            b'P' => {
                let Some((&klen, rest)) = payload.split_first() else {
                    return Err(err("empty parameter message".into()));
                };
                let klen = usize::from(klen);
                let (Some(key), Some(value)) = (rest.get(..klen), rest.get(klen..)) else {
                    return Err(err("parameter key runs past the message".into()));
                };
                let key = text(key, "the parameter key")?;
                let (ty, name) = key
                    .split_once(' ')
                    .ok_or_else(|| err(format!("parameter key `{key}` has no type")))?;
                let v = match (ty, value) {
                    ("int32_t", [a, b, c, d, ..]) => {
                        f64::from(i32::from_le_bytes([*a, *b, *c, *d]))
                    }
                    ("float", [a, b, c, d, ..]) => f64::from(f32::from_le_bytes([*a, *b, *c, *d])),
                    _ => {
                        return Err(err(format!(
                            "parameter `{name}`: type `{ty}` with {} value bytes",
                            value.len()
                        )));
                    }
                };
                self.out.parameters.insert(name.to_string(), v);
            }
            b'A' => {
                if payload.len() < 3 {
                    return Err(err(format!(
                        "subscription message of {} bytes (< 3)",
                        payload.len()
                    )));
                }
                let name = text(&payload[3..], "the subscription's format name")?;
                self.add_logged(payload[0], u16::from_le_bytes([payload[1], payload[2]]), name, at)
                    .map_err(err)?;
            }
            b'R' => self.remove_logged(payload, at).map_err(err)?,
            b'D' => self.data(payload, at).map_err(err)?,
            _ => {}
        }
        Ok(())
    }

    /// The `B` message: incompatible flags (refused unless only "appended data") and the
    /// appended-data offsets.
    fn flag_bits(&mut self, payload: &[u8], at: u64) -> Result<(), String> {
        if payload.len() < 40 {
            return Err(format!("flag bits message of {} bytes (< 40)", payload.len()));
        }
        let incompat = &payload[8..16];
        if incompat[0] & !1 != 0 || incompat[1..].iter().any(|b| *b != 0) {
            return Err(format!(
                "unknown incompatible flags {incompat:?}: this ULog version is not supported"
            ));
        }
        if incompat[0] & 1 == 1 {
            for k in 0..3 {
                let o = u64::from_le_bytes(
                    payload[16 + 8 * k..24 + 8 * k].try_into().unwrap_or([0; 8]),
                );
                if o > at {
                    self.appended.push(o);
                }
            }
            self.appended.sort_unstable();
        }
        Ok(())
    }

    /// The `A` message at byte `at`: subscription `id` to format `name`, instance `multi`.
    /// `Err` when `id` is still subscribed to another topic or instance (module doc), or the
    /// format does not compile.
    fn add_logged(&mut self, multi: u8, id: u16, name: String, at: u64) -> Result<(), String> {
        if let Some(old) = self.subs.get(&id)
            && (old.name != name || old.multi != multi)
        {
            return Err(format!(
                "the subscription at byte {at} re-uses msg_id {id} of topic `{}` (instance {}, \
                 subscribed at byte {}) for `{name}` (instance {multi}) without removing it \
                 first (an `R` message): the data after it could be either topic's",
                old.name, old.multi, old.at
            ));
        }
        let replaced = self.subs.get(&id).map_or(0, |s| s.compiled.leaves.len());
        let budget = MAX_FIELDS.saturating_sub(self.fields_held - replaced);
        let compiled = compile_topic(&self.formats, &name, budget, &mut self.name_work_left)
            .map_err(|m| format!("subscription {id} (`{name}`): {m}"))?;
        self.removed.remove(&id);
        self.subscribe(id, multi, name, compiled, at);
        Ok(())
    }

    /// The `R` message at byte `at`: subscription `msg_id` ends, its id free for another.
    fn remove_logged(&mut self, payload: &[u8], at: u64) -> Result<(), String> {
        let [lo, hi, ..] = *payload else {
            return Err(format!("remove-subscription message of {} bytes (< 2)", payload.len()));
        };
        let id = u16::from_le_bytes([lo, hi]);
        if let Some(old) = self.subs.remove(&id) {
            self.fields_held -= old.compiled.leaves.len();
            self.removed.insert(id, Removed { at, name: old.name, multi: old.multi });
        }
        Ok(())
    }

    /// Subscription `id` (its `A` message at byte `at`) to format `name`, instance `multi`:
    /// the topic of that field layout (a new one `name#k` for a layout not seen before under
    /// this name), and which leaves fill its kept fields.
    fn subscribe(&mut self, id: u16, multi: u8, name: String, compiled: Compiled, at: u64) {
        let mut sorted: Vec<String> = compiled.leaves.iter().map(|l| l.name.clone()).collect();
        sorted.sort_unstable();
        let key = (name.clone(), multi, sorted);
        let topic = match self.layouts.get(&key) {
            Some(&i) => i,
            None => {
                let count = self.layout_count.entry((key.0.clone(), multi)).or_default();
                *count += 1;
                let base = if multi == 0 { key.0.clone() } else { format!("{}[{multi}]", key.0) };
                let tname = if *count == 1 { base } else { format!("{base}#{count}") };
                let all: Vec<String> = compiled.leaves.iter().map(|l| l.name.clone()).collect();
                let kept = self.filter.topic(&tname).map(|only| match only {
                    None => all.clone(),
                    Some(set) => all.iter().filter(|n| set.contains(*n)).cloned().collect(),
                });
                // The layout's names stay for the catalogue: counted, never given back.
                self.fields_held += all.len() + 1;
                self.builders.push(TopicBuilder::new(tname, all, kept));
                self.layouts.insert(key, self.builders.len() - 1);
                self.builders.len() - 1
            }
        };
        let index: HashMap<&str, usize> =
            compiled.leaves.iter().enumerate().map(|(i, l)| (l.name.as_str(), i)).collect();
        let columns = self.builders[topic]
            .names
            .iter()
            .filter_map(|n| index.get(n.as_str()).copied())
            .collect();
        self.fields_held += compiled.leaves.len();
        let sub = Subscription { topic, compiled, columns, name, multi, at };
        if let Some(old) = self.subs.insert(id, sub) {
            self.fields_held -= old.compiled.leaves.len();
        }
    }

    /// A data message: its subscription's timestamp and kept fields.
    fn data(&mut self, payload: &[u8], at: u64) -> Result<(), String> {
        if payload.len() < 2 {
            return Err(format!("data message of {} bytes (< 2)", payload.len()));
        }
        let id = u16::from_le_bytes([payload[0], payload[1]]);
        let data = &payload[2..];
        let sub = self.subs.get(&id).ok_or_else(|| match self.removed.get(&id) {
            Some(r) => format!(
                "data message for msg_id {id}, whose subscription to `{}` (instance {}) was \
                 removed at byte {}",
                r.name, r.multi, r.at
            ),
            None => format!("data message for unknown subscription {id}"),
        })?;
        let b = &mut self.builders[sub.topic];
        let c = &sub.compiled;
        if data.len() < c.min_len {
            if data.len() < c.timestamp + 8 {
                return Err(format!("topic `{}`: data message too short for `timestamp`", b.name));
            }
            let l = c.leaves.iter().find(|l| l.offset + l.kind.size() > data.len());
            let (field, offset) = l.map_or(("?", 0), |l| (l.name.as_str(), l.offset));
            return Err(format!(
                "topic `{}`: data message of {} bytes too short for field `{field}` (byte {offset} of the struct)",
                b.name,
                data.len(),
            ));
        }
        let t_us =
            u64::from_le_bytes(data[c.timestamp..c.timestamp + 8].try_into().unwrap_or([0; 8]));
        self.row.clear();
        for &li in &sub.columns {
            let l = &c.leaves[li];
            self.row.push(l.kind.read(&data[l.offset..]));
        }
        b.push(t_us, &self.row, at);
        Ok(())
    }
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
}
