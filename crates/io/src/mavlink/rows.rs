//! Zero-order hold of MAVLink message fields into CSV rows, one row per clock message.

use super::MavlinkError;
use crate::mapping::{Mapping, Source};
use mavlink::Message;
use mavlink::dialects::ardupilotmega::MavMessage;
use serde_json::Value;
use std::collections::HashMap;
use std::io::Write;

/// Length of the `name` field of the named messages (`NAMED_VALUE_FLOAT`, `DEBUG_FLOAT_ARRAY` …).
const NAME_LEN: usize = 10;

/// One mapped column: `<MESSAGE>[<instance>].<field>[<index>]`.
#[derive(Debug, Clone)]
struct Column {
    field: String,
    index: Option<usize>,
}

/// Turns received messages into CSV rows over the columns a mapping refers to (module doc of
/// [`crate::mavlink`]).
#[derive(Debug)]
pub struct RowBuilder {
    names: Vec<String>,
    /// The channel (key) that reads each column first (`time` for the clock).
    channels: Vec<String>,
    columns: Vec<Column>,
    /// Latest value per column: `None` until received; NaN = received as unknown.
    values: Vec<Option<f64>>,
    /// Column indices per topic.
    by_topic: HashMap<String, Vec<usize>>,
    clock_topic: String,
    clock_messages: u64,
    clock_without_row: u64,
    rows: u64,
}

/// The parts of a column name `MSG[inst].field[i]`: message, instance, field, index.
type ColumnParts<'a> = (&'a str, Option<&'a str>, &'a str, Option<usize>);

/// Splits `MSG[inst].field[i]` into its parts.
fn split_column(c: &str) -> Result<ColumnParts<'_>, String> {
    let form =
        "expected `<MESSAGE>.<field>`, `<MESSAGE>.<field>[<i>]` or `<MESSAGE>[<name>].<field>`";
    let (message, instance, rest) = match (c.find('['), c.find('.')) {
        (Some(open), Some(dot)) if open < dot => {
            let close = c[open..]
                .find(']')
                .map(|k| open + k)
                .ok_or_else(|| format!("unclosed `[`; {form}"))?;
            let rest = c[close + 1..].strip_prefix('.').ok_or_else(|| form.to_string())?;
            (&c[..open], Some(&c[open + 1..close]), rest)
        }
        (_, Some(dot)) => (&c[..dot], None, &c[dot + 1..]),
        _ => return Err(form.to_string()),
    };
    let (field, index) = match rest.find('[') {
        Some(open) => {
            let idx = rest[open + 1..]
                .strip_suffix(']')
                .and_then(|i| i.parse::<usize>().ok())
                .ok_or_else(|| {
                    format!("array index in `{rest}` is not `[<non-negative integer>]`")
                })?;
            (&rest[..open], Some(idx))
        }
        None => (rest, None),
    };
    if message.is_empty() || field.is_empty() {
        return Err(form.to_string());
    }
    Ok((message, instance, field, index))
}

/// The numeric value of `field[index]` in a serialised message, `Err` describing why not.
fn field_value(
    obj: &serde_json::Map<String, Value>,
    field: &str,
    index: Option<usize>,
) -> Result<f64, String> {
    let v = obj.get(field).ok_or_else(|| {
        let fields: Vec<&str> = obj.keys().map(String::as_str).filter(|k| *k != "type").collect();
        format!("no field `{field}` (fields: {})", fields.join(", "))
    })?;
    let v = match (v, index) {
        (Value::Array(a), Some(i)) => a.get(i).ok_or_else(|| {
            format!("index {i} out of range (`{field}` has {} elements)", a.len())
        })?,
        (Value::Array(a), None) => {
            return Err(format!(
                "`{field}` is an array of {}: give an element, `{field}[<i>]`",
                a.len()
            ));
        }
        (_, Some(_)) => return Err(format!("`{field}` is not an array")),
        (v, None) => v,
    };
    match v {
        Value::Number(n) => {
            n.as_f64().ok_or_else(|| format!("`{field}` is not representable as f64"))
        }
        // serde_json writes a non-finite float as null: MAVLink's "unknown" (NaN).
        Value::Null => Ok(f64::NAN),
        _ => Err(format!("`{field}` is not numeric (an enum, flags or text field)")),
    }
}

impl RowBuilder {
    /// The builder for the columns `mapping` refers to; the clock is the message of its time
    /// column. Every column is checked against the dialect.
    ///
    /// # Errors
    /// [`MavlinkError::Column`] naming the mapping file, channel and column.
    pub fn new(mapping: &Mapping) -> Result<Self, MavlinkError> {
        let mut names: Vec<String> = Vec::new();
        let mut channels: Vec<String> = Vec::new();
        let mut columns = Vec::new();
        let mut by_topic: HashMap<String, Vec<usize>> = HashMap::new();
        let mut clock_topic = String::new();
        let sources = std::iter::once(("time", &mapping.time))
            .chain(mapping.channels.iter().map(|(c, m)| (c.key(), m)));
        for (channel, m) in sources {
            let Source::Columns(cols) = &m.source else { continue };
            for (name, _) in cols {
                let err = |reason: String| MavlinkError::Column {
                    file: mapping.file.clone(),
                    channel: channel.to_string(),
                    column: name.clone(),
                    reason,
                };
                let (message, instance, field, index) = split_column(name).map_err(err)?;
                let id = MavMessage::message_id_from_name(message).ok_or_else(|| {
                    err(format!("`{message}` is not a message of the ardupilotmega/common dialect"))
                })?;
                let default = MavMessage::default_message_from_id(id)
                    .ok_or_else(|| err(format!("no default for message `{message}`")))?;
                let json = serde_json::to_value(&default).map_err(|e| err(e.to_string()))?;
                let obj = json.as_object().ok_or_else(|| err("message is not an object".into()))?;
                let named = matches!(obj.get("name"), Some(Value::String(_)));
                match (named, instance) {
                    (true, None) => {
                        return Err(err(format!(
                            "`{message}` carries a `name`: give it as `{message}[<name>].{field}`"
                        )));
                    }
                    (false, Some(i)) => {
                        return Err(err(format!(
                            "`{message}` has no `name` field, so no `[{i}]` instance"
                        )));
                    }
                    (true, Some(i)) if i.is_empty() || i.len() > NAME_LEN => {
                        return Err(err(format!(
                            "name `{i}` must have 1 to {NAME_LEN} characters (the message's name field)"
                        )));
                    }
                    _ => {}
                }
                field_value(obj, field, index)
                    .map_err(|r| err(format!("message `{message}`: {r}")))?;
                let topic = match instance {
                    Some(i) => format!("{message}[{i}]"),
                    None => message.to_string(),
                };
                if channel == "time" {
                    clock_topic = topic.clone();
                }
                if names.contains(name) {
                    continue;
                }
                by_topic.entry(topic).or_default().push(columns.len());
                names.push(name.clone());
                channels.push(channel.to_string());
                columns.push(Column { field: field.to_string(), index });
            }
        }
        let values = vec![None; columns.len()];
        Ok(Self {
            names,
            channels,
            columns,
            values,
            by_topic,
            clock_topic,
            clock_messages: 0,
            clock_without_row: 0,
            rows: 0,
        })
    }

    /// The CSV header line (with its newline): the mapped columns, time first.
    pub fn header(&self) -> String {
        format!("{}\n", self.names.join(","))
    }

    /// The clock topic (the time column's message).
    pub fn clock_topic(&self) -> &str {
        &self.clock_topic
    }

    /// Clock messages received.
    pub fn clock_messages(&self) -> u64 {
        self.clock_messages
    }

    /// Clock messages that produced no row because a column had not been received yet.
    pub fn clock_without_row(&self) -> u64 {
        self.clock_without_row
    }

    /// Rows written.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Columns not received yet.
    pub fn missing(&self) -> Vec<&str> {
        self.names
            .iter()
            .zip(&self.values)
            .filter(|(_, v)| v.is_none())
            .map(|(n, _)| n.as_str())
            .collect()
    }

    /// The columns not received yet, each with the channel that reads it:
    /// ``AOA_SSA.AOA (channel `alpha`)``.
    pub fn missing_with_channels(&self) -> Vec<String> {
        self.names
            .iter()
            .zip(&self.channels)
            .zip(&self.values)
            .filter(|(_, v)| v.is_none())
            .map(|((n, c), _)| format!("{n} (channel `{c}`)"))
            .collect()
    }

    /// The number of message topics the columns read (the clock's included): a hole of at
    /// least as many messages may have held an update of every column.
    pub fn topics(&self) -> usize {
        self.by_topic.len()
    }

    /// Forgets every held value (after messages were lost in bulk): the next row waits until
    /// every column has been received again.
    pub fn forget(&mut self) {
        self.values.iter_mut().for_each(|v| *v = None);
    }

    /// Takes in one message: updates the held values of its columns and, if it is the clock
    /// message and every column has a value, appends one CSV row to `out`. Returns whether a
    /// row was written. Messages no column refers to are ignored.
    pub fn push(&mut self, msg: &MavMessage, out: &mut Vec<u8>) -> bool {
        let message = msg.message_name();
        if !self.by_topic.keys().any(|t| t.split('[').next() == Some(message)) {
            return false;
        }
        let Ok(Value::Object(obj)) = serde_json::to_value(msg) else { return false };
        let topic = match obj.get("name") {
            Some(Value::String(n)) => format!("{message}[{n}]"),
            _ => message.to_string(),
        };
        let Some(cols) = self.by_topic.get(&topic) else { return false };
        for &k in cols {
            let c = &self.columns[k];
            // Checked against the dialect when built: the field exists and is numeric.
            self.values[k] = field_value(&obj, &c.field, c.index).ok();
        }
        if topic != self.clock_topic {
            return false;
        }
        self.clock_messages += 1;
        if self.values.iter().any(Option::is_none) {
            self.clock_without_row += 1;
            return false;
        }
        for (k, v) in self.values.iter().enumerate() {
            if k > 0 {
                out.push(b',');
            }
            match v {
                Some(x) if x.is_finite() => {
                    // Writing to a Vec cannot fail.
                    let _ = write!(out, "{x}");
                }
                _ => {}
            }
        }
        out.push(b'\n');
        self.rows += 1;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::ardupilotmega::{ATTITUDE_DATA, NAMED_VALUE_FLOAT_DATA};

    const MAP: &str = "[time]\ncolumn = \"ATTITUDE.time_boot_ms\"\nunit = \"ms\"\n[channels]\n\
        vt = { column = \"NAMED_VALUE_FLOAT[vt].value\", unit = \"m/s\" }\n\
        alpha = { column = \"AOA_SSA.AOA\", unit = \"deg\" }\n\
        q = { column = \"ATTITUDE.pitchspeed\", unit = \"rad/s\" }\n\
        mass = { value = 1.0, unit = \"kg\" }\nS = { value = 1.0, unit = \"m2\" }\n\
        rho = { value = 1.0, unit = \"kg/m3\" }\n";

    fn mapping(text: &str) -> Mapping {
        Mapping::from_toml_str(text, "m.toml").unwrap()
    }

    fn nvf(name: &str, value: f32) -> MavMessage {
        MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
            time_boot_ms: 0,
            value,
            name: name.into(),
        })
    }

    fn attitude(t_ms: u32, q: f32) -> MavMessage {
        MavMessage::ATTITUDE(ATTITUDE_DATA {
            time_boot_ms: t_ms,
            pitchspeed: q,
            ..Default::default()
        })
    }

    fn aoa(a: f32) -> MavMessage {
        MavMessage::AOA_SSA(mavlink::dialects::ardupilotmega::AOA_SSA_DATA {
            time_usec: 0,
            AOA: a,
            SSA: 0.0,
        })
    }

    #[test]
    fn header_lists_time_first_then_the_mapped_columns() {
        let b = RowBuilder::new(&mapping(MAP)).unwrap();
        assert_eq!(
            b.header(),
            "ATTITUDE.time_boot_ms,NAMED_VALUE_FLOAT[vt].value,AOA_SSA.AOA,ATTITUDE.pitchspeed\n"
        );
        assert_eq!(b.clock_topic(), "ATTITUDE");
    }

    #[test]
    fn rows_hold_the_latest_values_and_wait_for_every_column() {
        let mut b = RowBuilder::new(&mapping(MAP)).unwrap();
        let mut out = Vec::new();
        assert!(!b.push(&nvf("vt", 100.5), &mut out));
        // Clock before AOA_SSA was seen: no row, counted.
        assert!(!b.push(&attitude(10, 0.25), &mut out));
        assert_eq!(b.clock_without_row(), 1);
        assert_eq!(b.missing(), vec!["AOA_SSA.AOA"]);
        assert_eq!(b.missing_with_channels(), vec!["AOA_SSA.AOA (channel `alpha`)"]);
        b.push(&aoa(2.0), &mut out);
        // Another name of the same message is another topic: ignored here.
        b.push(&nvf("other", 7.0), &mut out);
        assert!(b.push(&attitude(20, 0.1), &mut out));
        // Zero-order hold: vt and AOA from before, q from this clock message (f32 0.1 exactly).
        let q = f64::from(0.1f32);
        assert_eq!(String::from_utf8(out.clone()).unwrap(), format!("20,100.5,2,{q}\n"));
        assert_eq!(format!("{q}").parse::<f64>().unwrap().to_bits(), q.to_bits());
        out.clear();
        b.push(&aoa(f32::NAN), &mut out);
        assert!(b.push(&attitude(30, 0.1), &mut out));
        assert_eq!(String::from_utf8(out).unwrap(), format!("30,100.5,,{q}\n"), "NaN is blank");
        assert_eq!(b.rows(), 2);
        // After `forget` the clock waits for every column again.
        b.forget();
        let mut out = Vec::new();
        assert!(!b.push(&attitude(40, 0.1), &mut out));
        assert_eq!(b.missing(), vec!["NAMED_VALUE_FLOAT[vt].value", "AOA_SSA.AOA"]);
        assert_eq!((b.clock_messages(), b.clock_without_row()), (4, 2));
    }

    #[test]
    fn columns_are_checked_against_the_dialect() {
        for (col, needle) in [
            ("ATTITUDE.pitchsped", "no field `pitchsped` (fields: pitch, pitchspeed, roll"),
            ("ATTITUD.pitchspeed", "`ATTITUD` is not a message"),
            ("NAMED_VALUE_FLOAT.value", "give it as `NAMED_VALUE_FLOAT[<name>].value`"),
            ("ATTITUDE[x].roll", "no `name` field"),
            ("NAMED_VALUE_FLOAT[much_too_long].value", "1 to 10 characters"),
            ("NAMED_VALUE_FLOAT[x].name", "not numeric"),
            ("ACTUATOR_OUTPUT_STATUS.actuator", "give an element"),
            ("ACTUATOR_OUTPUT_STATUS.actuator[32]", "index 32 out of range"),
            ("pitchspeed", "expected `<MESSAGE>.<field>`"),
        ] {
            let text = MAP.replace("ATTITUDE.pitchspeed", col);
            let e = RowBuilder::new(&mapping(&text)).unwrap_err().to_string();
            assert!(
                e.contains(needle) && e.contains("m.toml") && e.contains("channel `q`"),
                "{col}: {e}"
            );
        }
        let ok = MAP.replace("ATTITUDE.pitchspeed", "ACTUATOR_OUTPUT_STATUS.actuator[31]");
        RowBuilder::new(&mapping(&ok)).unwrap();
    }
}
