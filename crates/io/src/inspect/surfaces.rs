//! Which channels of a log are control surfaces (or a system-identification waveform): the
//! channels the manoeuvre detector reads.
//!
//! In order of precedence ([`choose`]):
//! 1. A mapping's `de`, `da`, `dr` channels: each column they read ([`mapping_surfaces`]).
//! 2. A table (CSV, `.asc`, `.mat`): columns whose name says surface ([`name_surfaces`]):
//!    `de`/`da`/`dr`, `delta_e`/`delta_a`/`delta_r`, or a name holding `elevator`, `aileron`,
//!    `rudder`, `elevon` (the unit in `name [unit]` aside). Anything else needs `--map`.
//! 3. A multi-rate log: the known actuator topics ([`KNOWN_SURFACE_TOPICS`],
//!    [`known_surfaces`]): PX4 `actuator_controls_0`/`_1` `control[0..2]` (roll, pitch, yaw
//!    commands, −1…1; `_1` is a VTOL's fixed-wing group) and `actuator_servos.control[i]`
//!    (PX4 ≥ 1.14); ArduPilot `AETR` `Ail`/`Elev`/`Rudd` (normalised outputs, ±4500), its
//!    `SIDD.Targ` (the SYSID mode's waveform), and — when the log has no `AETR` — the `RCOU`
//!    channels whose `SERVOn_FUNCTION` is a surface (4 aileron, 19 elevator, 21 rudder, 24/25
//!    flaperon, 77/78 elevon, 79/80 V-tail); in a MAVLink `.tlog`, the `SERVO_OUTPUT_RAW`
//!    `servoN_raw` by the same parameters.
//!
//! PX4's `actuator_outputs` are not used unmapped: which output drives which surface is in the
//! airframe's mixer, not in the log, and a motor output would read as a manoeuvre.

use super::LogSummary;
use crate::log_contents::base_topic;
use crate::mapping::{Channel, Mapping, Source};
use serde::Serialize;

/// Topics kept whole by `inspect` (small: a few fields at the control rate) because they may
/// hold the surfaces.
pub const KNOWN_SURFACE_TOPICS: [&str; 7] = [
    "actuator_controls_0",
    "actuator_controls_1",
    "actuator_servos",
    "AETR",
    "RCOU",
    "SIDD",
    "SERVO_OUTPUT_RAW",
];

/// ArduPilot `SERVOn_FUNCTION` values of surfaces and what they drive.
const SERVO_FUNCTIONS: [(f64, &str); 9] = [
    (4.0, "aileron"),
    (19.0, "elevator"),
    (21.0, "rudder"),
    (24.0, "flaperon left"),
    (25.0, "flaperon right"),
    (77.0, "elevon left"),
    (78.0, "elevon right"),
    (79.0, "V-tail left"),
    (80.0, "V-tail right"),
];

/// A surface channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Surface {
    /// `topic.field` or a table's column name.
    pub column: String,
    /// What it is (`elevator`, `pitch command`, `SYSID waveform`, …).
    pub role: String,
    /// Why it is taken: `"mapping"`, `"column name"` or `"known actuator topic"`.
    pub source: String,
}

/// The surfaces of the log `summary` describes, by the precedence of the module doc; empty
/// when none is known (the caller says how to give one).
pub fn choose(summary: &LogSummary, mapping: Option<&Mapping>) -> Vec<Surface> {
    if let Some(m) = mapping {
        return mapping_surfaces(m);
    }
    match (&summary.time_column, summary.topics.first()) {
        (Some(_), Some(t)) => {
            let names: Vec<String> = t.fields.iter().map(|f| f.name.clone()).collect();
            name_surfaces(&names)
        }
        _ => known_surfaces(summary),
    }
}

/// Every column the mapping's `de`, `da`, `dr` channels read (a derived column such as
/// `air.alpha` is not a log column and is left out).
pub fn mapping_surfaces(mapping: &Mapping) -> Vec<Surface> {
    let mut out = Vec::new();
    for (ch, role) in [(Channel::De, "elevator"), (Channel::Da, "aileron"), (Channel::Dr, "rudder")]
    {
        let Some(Source::Columns(cols)) = mapping.channels.get(&ch).map(|c| &c.source) else {
            continue;
        };
        for (c, _) in cols.iter().filter(|(c, _)| !crate::multirate::is_derived(c)) {
            out.push(Surface {
                column: c.clone(),
                role: format!("{role} (`{}`)", ch.key()),
                source: "mapping".into(),
            });
        }
    }
    out
}

/// The table columns whose names say surface (module doc).
pub fn name_surfaces(names: &[String]) -> Vec<Surface> {
    names
        .iter()
        .filter_map(|n| {
            let base = n.split(['[', '(']).next().unwrap_or(n).trim().to_ascii_lowercase();
            let role = match base.as_str() {
                "de" | "delta_e" | "elev" => "elevator",
                "da" | "delta_a" | "ail" => "aileron",
                "dr" | "delta_r" | "rud" => "rudder",
                b if b.contains("elevator") => "elevator",
                b if b.contains("aileron") => "aileron",
                b if b.contains("rudder") => "rudder",
                b if b.contains("elevon") => "elevon",
                _ => return None,
            };
            Some(Surface { column: n.clone(), role: role.into(), source: "column name".into() })
        })
        .collect()
}

/// The surfaces among a multi-rate log's known actuator topics (module doc).
pub fn known_surfaces(summary: &LogSummary) -> Vec<Surface> {
    let has_aetr = summary.topics.iter().any(|t| base_topic(&t.name) == "AETR");
    let mut out = Vec::new();
    for t in summary.topics.iter().filter(|t| t.time.samples > 0) {
        let has = |f: &str| t.fields.iter().any(|x| x.name == f);
        let mut add = |field: &str, role: String| {
            if has(field) {
                out.push(Surface {
                    column: format!("{}.{field}", t.name),
                    role,
                    source: "known actuator topic".into(),
                });
            }
        };
        match base_topic(&t.name) {
            "actuator_controls_0" | "actuator_controls_1" => {
                for (i, axis) in ["roll", "pitch", "yaw"].iter().enumerate() {
                    add(&format!("control[{i}]"), format!("{axis} command"));
                }
            }
            "actuator_servos" => {
                for f in t.fields.iter().filter(|f| f.name.starts_with("control[")) {
                    add(&f.name, format!("servo {}", &f.name[7..]));
                }
            }
            "AETR" => {
                for (f, role) in [("Ail", "aileron"), ("Elev", "elevator"), ("Rudd", "rudder")] {
                    add(f, role.to_string());
                }
            }
            "SIDD" => add("Targ", sysid_role(summary)),
            "RCOU" if !has_aetr => {
                for (n, role) in servo_surfaces(summary) {
                    add(&format!("C{n}"), role.to_string());
                }
            }
            "SERVO_OUTPUT_RAW" => {
                for (n, role) in servo_surfaces(summary) {
                    add(&format!("servo{n}_raw"), role.to_string());
                }
            }
            _ => {}
        }
    }
    out
}

/// The SYSID waveform's role, with the axis its `SID_AXIS` parameter names.
fn sysid_role(summary: &LogSummary) -> String {
    match summary.parameters.get("SID_AXIS") {
        Some(a) => format!("SYSID waveform (SID_AXIS {a})"),
        None => "SYSID waveform".into(),
    }
}

/// The servo outputs `n` whose `SERVOn_FUNCTION` is a surface, with what they drive.
fn servo_surfaces(summary: &LogSummary) -> Vec<(usize, &'static str)> {
    (1..=32)
        .filter_map(|n| {
            let f = summary.parameters.get(&format!("SERVO{n}_FUNCTION"))?;
            SERVO_FUNCTIONS.iter().find(|(v, _)| v == f).map(|(_, role)| (n, *role))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_surface_names_with_units_and_without() {
        let names: Vec<String> =
            ["time [s]", "delta_e [AETR_units]", "q [rad/s]", "aileron_left_deg", "de", "dr_x"]
                .iter()
                .map(|s| s.to_string())
                .collect();
        let got: Vec<(String, String)> =
            name_surfaces(&names).into_iter().map(|s| (s.column, s.role)).collect();
        assert_eq!(
            got,
            [
                ("delta_e [AETR_units]".to_string(), "elevator".to_string()),
                ("aileron_left_deg".into(), "aileron".into()),
                ("de".into(), "elevator".into()),
            ]
        );
    }
}
