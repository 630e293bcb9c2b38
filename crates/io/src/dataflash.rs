//! ArduPilot DataFlash (`.bin`) reader: every timed message type as a [`Topic`].
//!
//! The format is self-describing (ArduPilot `libraries/AP_Logger/LogStructure.h`; reference
//! reader: pymavlink `DFReader.py`, `DFReader_binary`): every message is `0xA3 0x95`, a type
//! byte and a fixed-length payload. Type 128 (`FMT`, 89 bytes) defines a type: its id, total
//! length, 4-character name, format string (one character per field) and comma-separated
//! column names. `FMTU` messages give each field's unit and multiplier ids; a unit `#` marks
//! the instance field (e.g. `GPS.I`, `XKF1.C`). Field characters, sizes and the scaling
//! applied (pymavlink's `FORMAT_TO_STRUCT`):
//!
//! | char | type | scaling |   | char | type | scaling |
//! |---|---|---|---|---|---|---|
//! | `b` `B` `M` | int8, uint8, uint8 mode | — | | `c` `C` | int16, uint16 | × 0.01 |
//! | `h` `H` | int16, uint16 | — | | `e` `E` | int32, uint32 | × 0.01 |
//! | `i` `I` | int32, uint32 | — | | `L` | int32 lat/lon | × 1e-7 (deg) |
//! | `q` `Q` | int64, uint64 | — | | `g` | IEEE half float | — |
//! | `f` `d` | float, double | — | | `a` | int16\[32\] | — (`field[0..31]`) |
//! | `n` `N` `Z` | char\[4\], \[16\], \[64\] | text, not a field | | | | |
//!
//! The `FMTU`/`MULT` multipliers are **not** applied (pymavlink only uses them to name the
//! unit): a value is in the unit ArduPilot logs it in (`ATT.Roll` in degrees, `IMU.GyrX` in
//! rad/s, `RCOU.C2` in µs PWM); the mapping converts it.
//!
//! Topics: one per message name with a `TimeUS` (µs) or `TimeMS` (ms) field, which becomes the
//! time base in seconds (since boot, not shifted); the time field itself is not repeated as a
//! field. A message type with an instance field is split as ULog topics are: instance 0 keeps
//! the name (`XKF1`), instance `k ≥ 1` is `XKF1[k]`; the instance field stays a field.
//! `PARM` messages also fill [`LogContents::parameters`]. Samples whose time does not increase
//! are left out and counted in [`LogContents::dropped`].
//!
//! Corrupt bytes (no header, or a type with no `FMT`) are skipped byte by byte until the next
//! header, as pymavlink does, and each skipped stretch is listed in [`LogContents::skipped`];
//! a file that ends inside a message reports [`LogContents::truncated_at`]. A malformed `FMT`
//! (length under 3, unknown format character, sizes that do not add up to the length) is a
//! [`FlightDataError::LogDecode`] naming the byte offset and the message name: every later
//! message of that type would be misread.
//!
//! Why not a crate: `ardupilot-binlog` 0.2.0 (its source) computes the payload length as
//! `msg_len as usize - 3`, which underflows for a corrupt `FMT` with a length under 3, stops
//! without a word after 256 consecutive bad headers (the rest of the file is silently lost),
//! and reports no byte offsets.

use crate::FlightDataError;
use crate::byte_window::ByteWindow;
use crate::log_contents::{LogContents, TopicBuilder, TopicFilter};
use crate::table::Topic;
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::Path;

/// Message header bytes.
const HEAD: [u8; 2] = [0xA3, 0x95];
/// Type id of `FMT`.
const FMT_TYPE: u8 = 128;
/// Most fields the topics of one log may have in all (each instance and field layout of a
/// type is a topic: a hostile log could otherwise make millions).
const MAX_FIELDS: usize = 2_000_000;
/// Length of an `FMT` message, header included.
const FMT_LEN: usize = 89;

/// One field's decoding: byte size, kind.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Num { size: usize, scale: f64, signed: bool, float: bool },
    Half,
    Array,
    Text(usize),
}

fn kind(c: u8) -> Option<Kind> {
    let n = |size, signed| Kind::Num { size, scale: 1.0, signed, float: false };
    let s = |size, signed, scale| Kind::Num { size, scale, signed, float: false };
    Some(match c {
        b'b' => n(1, true),
        b'B' | b'M' => n(1, false),
        b'h' => n(2, true),
        b'H' => n(2, false),
        b'i' => n(4, true),
        b'I' => n(4, false),
        b'q' => n(8, true),
        b'Q' => n(8, false),
        b'c' => s(2, true, 0.01),
        b'C' => s(2, false, 0.01),
        b'e' => s(4, true, 0.01),
        b'E' => s(4, false, 0.01),
        b'L' => s(4, true, 1e-7),
        b'f' => Kind::Num { size: 4, scale: 1.0, signed: true, float: true },
        b'd' => Kind::Num { size: 8, scale: 1.0, signed: true, float: true },
        b'g' => Kind::Half,
        b'a' => Kind::Array,
        b'n' => Kind::Text(4),
        b'N' => Kind::Text(16),
        b'Z' => Kind::Text(64),
        _ => return None,
    })
}

fn size(k: Kind) -> usize {
    match k {
        Kind::Num { size, .. } => size,
        Kind::Half => 2,
        Kind::Array => 64,
        Kind::Text(n) => n,
    }
}

/// IEEE 754 binary16 to f64.
fn half(bits: u16) -> f64 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((bits >> 10) & 0x1f);
    let frac = f64::from(bits & 0x3ff);
    match exp {
        0 => sign * frac * 2f64.powi(-24),
        31 if frac == 0.0 => sign * f64::INFINITY,
        31 => f64::NAN,
        e => sign * (1.0 + frac / 1024.0) * 2f64.powi(e - 15),
    }
}

/// Reads field `k` at the start of `b` (`b.len() >= size(k)`), numeric kinds only.
fn read_num(k: Kind, b: &[u8]) -> f64 {
    match k {
        Kind::Num { size, scale, signed, float } => {
            let mut x = [0u8; 8];
            x[..size].copy_from_slice(&b[..size]);
            let raw = match (size, signed, float) {
                (4, _, true) => f64::from(f32::from_le_bytes([x[0], x[1], x[2], x[3]])),
                (8, _, true) => f64::from_le_bytes(x),
                (1, true, _) => f64::from(x[0] as i8),
                (1, false, _) => f64::from(x[0]),
                (2, true, _) => f64::from(i16::from_le_bytes([x[0], x[1]])),
                (2, false, _) => f64::from(u16::from_le_bytes([x[0], x[1]])),
                (4, true, _) => f64::from(i32::from_le_bytes([x[0], x[1], x[2], x[3]])),
                (4, false, _) => f64::from(u32::from_le_bytes([x[0], x[1], x[2], x[3]])),
                (_, true, _) => i64::from_le_bytes(x) as f64,
                (_, false, _) => u64::from_le_bytes(x) as f64,
            };
            // pymavlink divides by 1/scale for accuracy (1e-7 is not exact in binary).
            if scale < 1.0 { raw / (1.0 / scale).round() } else { raw * scale }
        }
        Kind::Half => half(u16::from_le_bytes([b[0], b[1]])),
        Kind::Array | Kind::Text(_) => f64::NAN,
    }
}

/// A message type defined by an `FMT`.
#[derive(Debug, Clone)]
struct Format {
    name: String,
    /// Payload length (message length − 3).
    payload: usize,
    /// (column, kind, payload offset) for every field.
    fields: Vec<(String, Kind, usize)>,
    /// Index into `fields` of the time field and its µs factor.
    time: Option<(usize, u64)>,
    /// Index into `fields` of the instance field (from `FMTU`).
    instance: Option<usize>,
    /// The topic's field names: every numeric field but the time, arrays flattened.
    columns: Vec<String>,
    /// Layout number under this name (1: the name itself, k: `NAME#k`), fixed at the type's
    /// first timed message.
    variant: Option<usize>,
    /// Instance → builder, filled as instances appear (a cache: names are built once per
    /// topic, not per message).
    topics: HashMap<i64, usize>,
}

fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).trim().to_string()
}

/// Parses an `FMT` payload (86 bytes).
fn parse_fmt(p: &[u8]) -> Result<(u8, Format), String> {
    let id = p[0];
    let len = usize::from(p[1]);
    let name = text(&p[2..6]);
    let chars = text(&p[6..22]);
    let cols = text(&p[22..86]);
    if len < 3 {
        return Err(format!("FMT of `{name}` (type {id}): length {len} < 3"));
    }
    let columns: Vec<&str> =
        if cols.is_empty() { Vec::new() } else { cols.split(',').map(str::trim).collect() };
    if columns.len() != chars.len() {
        return Err(format!(
            "FMT of `{name}` (type {id}): {} format characters `{chars}` for {} columns `{cols}`",
            chars.len(),
            columns.len()
        ));
    }
    let mut fields = Vec::with_capacity(chars.len());
    let mut at = 0;
    for (c, col) in chars.bytes().zip(&columns) {
        let k = kind(c).ok_or_else(|| {
            format!(
                "FMT of `{name}` (type {id}): field `{col}`: unknown format character `{}`",
                c as char
            )
        })?;
        fields.push((col.to_string(), k, at));
        at += size(k);
    }
    if at != len - 3 {
        return Err(format!(
            "FMT of `{name}` (type {id}): fields `{chars}` take {at} bytes but the length {len} leaves {}",
            len - 3
        ));
    }
    let time = fields.iter().position(|(c, k, _)| c == "TimeUS" && matches!(k, Kind::Num { .. }));
    let time = time.map(|i| (i, 1)).or_else(|| {
        fields
            .iter()
            .position(|(c, k, _)| c == "TimeMS" && matches!(k, Kind::Num { .. }))
            .map(|i| (i, 1000))
    });
    let columns = time.map_or_else(Vec::new, |(ti, _)| flat_columns(&fields, ti));
    let f = Format {
        name,
        payload: len - 3,
        fields,
        time,
        instance: None,
        columns,
        variant: None,
        topics: HashMap::new(),
    };
    Ok((id, f))
}

/// The numeric fields but the time field `ti`, arrays as `name[0..31]`.
fn flat_columns(fields: &[(String, Kind, usize)], ti: usize) -> Vec<String> {
    let mut names = Vec::new();
    for (i, (c, k, _)) in fields.iter().enumerate() {
        match k {
            _ if i == ti => {}
            Kind::Num { .. } | Kind::Half => names.push(c.clone()),
            Kind::Array => names.extend((0..32).map(|j| format!("{c}[{j}]"))),
            Kind::Text(_) => {}
        }
    }
    names
}

/// Appends the values of `flat_columns(fields, ti)` in payload `p` to `row`.
fn flat_values(fields: &[(String, Kind, usize)], ti: usize, p: &[u8], row: &mut Vec<f64>) {
    for (i, (_, k, o)) in fields.iter().enumerate() {
        match k {
            _ if i == ti => {}
            Kind::Num { .. } | Kind::Half => row.push(read_num(*k, &p[*o..*o + size(*k)])),
            Kind::Array => row.extend((0..32).map(|j| {
                let b = &p[o + 2 * j..o + 2 * j + 2];
                f64::from(i16::from_le_bytes([b[0], b[1]]))
            })),
            Kind::Text(_) => {}
        }
    }
}

/// Reads a DataFlash log's timed message types as topics (see the module doc).
///
/// # Errors
/// [`FlightDataError::Io`] if the file cannot be read, [`FlightDataError::LogDecode`] naming
/// the byte offset for a file with no DataFlash message or a malformed `FMT`.
pub fn read_dataflash(path: &Path) -> Result<Vec<Topic>, FlightDataError> {
    Ok(read_dataflash_contents(path)?.topics)
}

/// Reads a DataFlash log: every topic, parameters and what was left out or skipped.
///
/// # Errors
/// As [`read_dataflash`].
pub fn read_dataflash_contents(path: &Path) -> Result<LogContents, FlightDataError> {
    read_dataflash_filtered(path, &TopicFilter::all())
}

/// Reads a DataFlash log keeping only the topics and fields `filter` names (the others are
/// checked, counted and listed in [`LogContents::catalogue`]); the file is streamed.
///
/// # Errors
/// As [`read_dataflash`].
pub fn read_dataflash_filtered(
    path: &Path,
    filter: &TopicFilter,
) -> Result<LogContents, FlightDataError> {
    let file = path.display().to_string();
    let f = std::fs::File::open(path)
        .map_err(|source| FlightDataError::Io { file: file.clone(), source })?;
    decode_dataflash(f, &file, filter)
}

/// Decodes DataFlash bytes; `file` names them in errors. Every topic and field is kept.
///
/// # Errors
/// [`FlightDataError::LogDecode`] naming `file` and the byte offset: a malformed `FMT`, or no
/// valid message at all (not a DataFlash log).
pub fn parse_dataflash(bytes: &[u8], file: &str) -> Result<LogContents, FlightDataError> {
    decode_dataflash(bytes, file, &TopicFilter::all())
}

/// The reader's state between messages.
struct Decoder<'a> {
    filter: &'a TopicFilter,
    out: LogContents,
    formats: BTreeMap<u8, Format>,
    builders: Vec<TopicBuilder>,
    /// For each builder, the indices of its kept fields among its layout's columns.
    kept: Vec<Vec<usize>>,
    by_name: HashMap<String, usize>,
    /// `(name, columns)` → layout number, and the layouts counted per name: a type
    /// redefined again and again costs one hash lookup per definition, not a search.
    layouts: HashMap<(String, Vec<String>), usize>,
    layout_count: HashMap<String, usize>,
    /// Fields of all topics made so far, against [`MAX_FIELDS`].
    fields_held: usize,
    row: Vec<f64>,
    flat: Vec<f64>,
    /// What the log says of units: `UNIT` id → label, `MULT` id → multiplier, `FMTU` type →
    /// (unit ids, multiplier ids), one id character per field of the type.
    unit_labels: HashMap<u8, String>,
    multipliers: HashMap<u8, f64>,
    unit_ids: HashMap<u8, (Vec<u8>, Vec<u8>)>,
}

/// Decodes a DataFlash stream keeping what `filter` names; `file` names it in errors.
///
/// # Errors
/// As [`parse_dataflash`], and [`FlightDataError::Io`] for a read error.
pub fn decode_dataflash<R: Read>(
    source: R,
    file: &str,
    filter: &TopicFilter,
) -> Result<LogContents, FlightDataError> {
    let io = |source| FlightDataError::Io { file: file.to_string(), source };
    let err = |offset: u64, message: String| FlightDataError::LogDecode {
        file: file.to_string(),
        offset,
        message,
    };
    let mut w = ByteWindow::new(source);
    let mut d = Decoder {
        filter,
        out: LogContents::default(),
        formats: BTreeMap::new(),
        builders: Vec::new(),
        kept: Vec::new(),
        by_name: HashMap::new(),
        layouts: HashMap::new(),
        layout_count: HashMap::new(),
        fields_held: 0,
        row: Vec::new(),
        flat: Vec::new(),
        unit_labels: HashMap::new(),
        multipliers: HashMap::new(),
        unit_ids: HashMap::new(),
    };
    let mut skip_start: Option<u64> = None;
    let mut messages = 0usize;
    loop {
        let at = w.offset();
        let ty = match w.peek(3).map_err(io)? {
            Some([a, b, t])
                if [*a, *b] == HEAD && (*t == FMT_TYPE || d.formats.contains_key(t)) =>
            {
                *t
            }
            Some(_) => {
                skip_start.get_or_insert(at);
                w.consume(1).map_err(io)?;
                continue;
            }
            None => {
                if !w.at_end().map_err(io)? {
                    d.out.truncated_at = Some(at);
                }
                break;
            }
        };
        let len = if ty == FMT_TYPE { FMT_LEN - 3 } else { d.formats[&ty].payload };
        let Some(msg) = w.peek(3 + len).map_err(io)? else {
            d.out.truncated_at = Some(at);
            break;
        };
        if let Some(s) = skip_start.take() {
            d.out.skip(s, at - s);
        }
        messages += 1;
        let p = &msg[3..];
        if ty == FMT_TYPE {
            let (id, f) = parse_fmt(p).map_err(|m| err(at, m))?;
            if id == FMT_TYPE && (f.payload != FMT_LEN - 3 || f.name != "FMT") {
                return Err(err(at, format!("FMT redefines the FMT type as `{}`", f.name)));
            }
            d.formats.insert(id, f);
        } else {
            d.message(ty, p, at).map_err(|m| err(at, m))?;
        }
        w.consume(3 + len as u64).map_err(io)?;
    }
    if let Some(s) = skip_start {
        let end = w.offset();
        d.out.skip(s, end - s);
    }
    if messages == 0 {
        return Err(err(
            0,
            "no DataFlash message found (no `A3 95` header with a known type)".into(),
        ));
    }
    d.out.units = d.units();
    let Decoder { mut out, builders, .. } = d;
    out.add_topics(builders);
    Ok(out)
}

impl Decoder<'_> {
    /// Keeps what a `UNIT` (id, label), `MULT` (id, multiplier) or `FMTU` (type, unit ids,
    /// multiplier ids) message of type `ty` says; a message without those fields says nothing.
    fn unit_message(&mut self, ty: u8, p: &[u8]) {
        let f = &self.formats[&ty];
        let name = f.name.as_str();
        let get = |col: &str| f.fields.iter().find(|(c, _, _)| c == col).map(|&(_, k, o)| (k, o));
        let num = |col: &str| get(col).map(|(k, o)| read_num(k, &p[o..o + size(k)]));
        let txt = |col: &str| get(col).map(|(k, o)| text(&p[o..o + size(k)]));
        match name {
            "UNIT" => {
                if let (Some(id), Some(label)) = (num("Id"), txt("Label")) {
                    self.unit_labels.insert(id as u8, label);
                }
            }
            "MULT" => {
                if let (Some(id), Some(m)) = (num("Id"), num("Mult")) {
                    self.multipliers.insert(id as u8, m);
                }
            }
            _ => {
                if let (Some(t), Some(u), Some(m)) =
                    (num("FmtType"), txt("UnitIds"), txt("MultIds"))
                {
                    self.unit_ids.insert(t as u8, (u.into_bytes(), m.into_bytes()));
                }
            }
        }
    }

    /// The units of every defined type's numeric fields that `FMTU` names with a `UNIT`
    /// label, by type name then field. A multiplier is part of the unit only for a field whose
    /// format character does not scale it already (`c`, `C`, `e`, `E`, `L` are read scaled, the
    /// module doc): `"m ×0.01"` means raw × 0.01 is in metres.
    fn units(&self) -> BTreeMap<String, BTreeMap<String, String>> {
        let mut out: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
        for (ty, (uids, mids)) in &self.unit_ids {
            let Some(f) = self.formats.get(ty) else { continue };
            for (i, (col, k, _)) in f.fields.iter().enumerate() {
                let Some(label) = uids.get(i).and_then(|u| self.unit_labels.get(u)) else {
                    continue;
                };
                let Kind::Num { scale, .. } = k else { continue };
                let mult = mids.get(i).and_then(|m| self.multipliers.get(m)).copied();
                let unit = match mult {
                    // `MULT` values are logged as single floats (1e-3 reads 0.0010000000474…):
                    // shown at single precision.
                    Some(m) if *scale == 1.0 && m != 0.0 && m != 1.0 => {
                        format!("{label} ×{:e}", m as f32)
                    }
                    _ => label.clone(),
                };
                if !unit.is_empty() {
                    out.entry(f.name.clone()).or_default().insert(col.clone(), unit);
                }
            }
        }
        out
    }

    /// A message of defined type `ty` (not `FMT`) at byte `at` with payload `p`.
    fn message(&mut self, ty: u8, p: &[u8], at: u64) -> Result<(), String> {
        if matches!(self.formats[&ty].name.as_str(), "UNIT" | "MULT" | "FMTU") {
            self.unit_message(ty, p);
        }
        let f = &self.formats[&ty];
        let field = |i: usize| {
            let (_, k, o) = f.fields[i];
            read_num(k, &p[o..o + size(k)])
        };
        let col = |name: &str| f.fields.iter().position(|(c, _, _)| c == name);
        let mut instance_of = None;
        match f.name.as_str() {
            "FMTU" => {
                // TimeUS, FmtType, UnitIds, MultIds: the instance field is unit `#`.
                if let (Some(ti), Some(ui)) = (col("FmtType"), col("UnitIds")) {
                    let (_, k, o) = f.fields[ui];
                    instance_of = Some((field(ti) as u8, text(&p[o..o + size(k)]).find('#')));
                }
            }
            "PARM" => {
                if let (Some(ni), Some(vi)) = (col("Name"), col("Value")) {
                    let (_, k, o) = f.fields[ni];
                    self.out.parameters.insert(text(&p[o..o + size(k)]), field(vi));
                }
            }
            _ => {}
        }
        if let Some((ti, us)) = f.time {
            let t_us = (field(ti) as u64).saturating_mul(us);
            let instance = f.instance.map_or(0, |i| field(i) as i64);
            let b = self.topic(ty, instance)?;
            if self.builders[b].kept {
                let f = &self.formats[&ty];
                self.flat.clear();
                flat_values(&f.fields, ti, p, &mut self.flat);
                self.row.clear();
                self.row.extend(self.kept[b].iter().map(|&j| self.flat[j]));
            }
            self.builders[b].push(t_us, &self.row, at);
        }
        if let Some((target, Some(i))) = instance_of
            && let Some(g) = self.formats.get_mut(&target)
            && i < g.fields.len()
            && matches!(g.fields[i].1, Kind::Num { .. })
            && g.instance != Some(i)
        {
            g.instance = Some(i);
            g.topics.clear();
        }
        Ok(())
    }

    /// The builder of type `ty`'s messages of `instance`: `NAME`, `NAME[k]`, and `#n` after
    /// either for the n-th field layout seen under this name (a redefined type).
    ///
    /// # Errors
    /// A new topic that would take the log's topic fields past [`MAX_FIELDS`].
    fn topic(&mut self, ty: u8, instance: i64) -> Result<usize, String> {
        let f = &self.formats[&ty];
        if let Some(&b) = f.topics.get(&instance) {
            return Ok(b);
        }
        let variant = match f.variant {
            Some(v) => v,
            None => {
                let key = (f.name.clone(), f.columns.clone());
                let n = self.layout_count.entry(f.name.clone()).or_default();
                *self.layouts.entry(key).or_insert_with(|| {
                    *n += 1;
                    *n
                })
            }
        };
        let f = self.formats.get_mut(&ty).expect("type checked by the caller");
        f.variant = Some(variant);
        let mut tname =
            if instance == 0 { f.name.clone() } else { format!("{}[{instance}]", f.name) };
        if variant > 1 {
            tname = format!("{tname}#{variant}");
        }
        let b = match self.by_name.get(&tname) {
            Some(&b) => b,
            None => {
                self.fields_held += f.columns.len() + 1;
                if self.fields_held > MAX_FIELDS {
                    return Err(format!(
                        "topic `{tname}`: the log's topics (one per type, instance and field \
                         layout) pass {MAX_FIELDS} fields in all"
                    ));
                }
                let all = f.columns.clone();
                let kept_idx: Option<Vec<usize>> = self.filter.topic(&tname).map(|only| {
                    (0..all.len()).filter(|&j| only.is_none_or(|s| s.contains(&all[j]))).collect()
                });
                let kept = kept_idx.as_ref().map(|ix| ix.iter().map(|&j| all[j].clone()).collect());
                self.builders.push(TopicBuilder::new(tname.clone(), all, kept));
                self.kept.push(kept_idx.unwrap_or_default());
                self.by_name.insert(tname, self.builders.len() - 1);
                self.builders.len() - 1
            }
        };
        f.topics.insert(instance, b);
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_half_floats() {
        assert_eq!(half(0x3c00), 1.0);
        assert_eq!(half(0xc000), -2.0);
        assert_eq!(half(0x3555), 0.333_251_953_125);
        assert_eq!(half(0x0001), 2f64.powi(-24));
        assert!(half(0x7e00).is_nan());
    }

    #[test]
    fn analytic_scaled_types_follow_pymavlink() {
        let c = kind(b'c').unwrap();
        assert_eq!(read_num(c, &(-4500i16).to_le_bytes()), -45.0);
        let l = kind(b'L').unwrap();
        assert_eq!(read_num(l, &(-1_234_567_891i32).to_le_bytes()), -123.4567891);
        let e = kind(b'E').unwrap();
        assert_eq!(read_num(e, &(4_000_000_000u32).to_le_bytes()), 40_000_000.0);
    }

    #[test]
    fn errors_not_dataflash_names_file_and_offset() {
        let e = parse_dataflash(b"plain text, no header", "x.bin").unwrap_err().to_string();
        assert!(e.starts_with("x.bin: byte 0: no DataFlash message"), "{e}");
    }
}
