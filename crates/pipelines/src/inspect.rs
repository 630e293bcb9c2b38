//! `aeroident inspect`: what a log holds (the catalogue of [`aeroident_io::inspect`]) and its
//! candidate manoeuvres ([`detect`]), as one report the faces render as text, as the
//! `--json` document (docs/inspect.md) and as a plot.

pub mod detect;

use crate::error::PipelineError;
use crate::window::TimeWindow;
use aeroident_io::inspect::surfaces::Surface;
use aeroident_io::inspect::{INSPECT_SCHEMA, InspectOptions, LogSummary, Signal, inspect_log};
use detect::{ChannelDetection, DetectionRule};
use serde::Serialize;

/// The report of one log (the `--json` document).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InspectReport {
    /// [`INSPECT_SCHEMA`].
    pub schema: &'static str,
    /// The catalogue: file, format, topics, parameters, notes.
    #[serde(flatten)]
    pub log: LogSummary,
    /// The surface channels read by the detector.
    pub surfaces: Vec<Surface>,
    /// When no surface is known: how to name one; when some surfaces (a mapping's) are not
    /// in the log: which.
    pub surface_hint: Option<String>,
    /// The thresholds the detector used.
    pub detection_rule: DetectionRule,
    /// Per surface: quiet level, threshold and manoeuvres.
    pub detections: Vec<ChannelDetection>,
}

/// The report and the values of the channels read (surfaces and `--plot` channels).
#[derive(Debug, Clone, PartialEq)]
pub struct InspectOutcome {
    /// The report.
    pub report: InspectReport,
    /// The values, by column.
    pub signals: Vec<Signal>,
}

/// Reads `path` as `options` say, lists it and detects the manoeuvres of its surfaces by
/// `rule`.
///
/// # Errors
/// The reader's error ([`inspect_log`]: file, byte or row, field), passed through.
pub fn inspect(
    path: &str,
    options: &InspectOptions,
    rule: &DetectionRule,
) -> Result<InspectOutcome, PipelineError> {
    let ins = inspect_log(path, options).map_err(|e| PipelineError::Source(Box::new(e)))?;
    let detections = ins
        .surfaces
        .iter()
        .filter_map(|s| {
            let sig = ins.signals.iter().find(|g| g.column == s.column)?;
            Some(detect::detect(&s.column, &sig.t_s, &sig.values, rule))
        })
        .collect();
    let missing: Vec<String> = ins
        .surfaces
        .iter()
        .filter(|s| !ins.signals.iter().any(|g| g.column == s.column))
        .map(|s| format!("`{}` ({})", s.column, s.role))
        .collect();
    let surface_hint = match (ins.surfaces.is_empty(), missing.is_empty()) {
        (true, _) => Some(no_surface_hint(&ins.summary)),
        (false, false) => {
            Some(format!("surface column(s) not in the log, not judged: {}", missing.join(", ")))
        }
        (false, true) => None,
    };
    let report = InspectReport {
        schema: INSPECT_SCHEMA,
        log: ins.summary,
        surfaces: ins.surfaces,
        surface_hint,
        detection_rule: *rule,
        detections,
    };
    Ok(InspectOutcome { report, signals: ins.signals })
}

/// How to name a surface when none is known.
fn no_surface_hint(log: &LogSummary) -> String {
    let why = if log.time_column.is_some() {
        "no column name says control surface (de, da, dr, delta_e, …elevator…, …aileron…, …rudder…)"
            .to_string()
    } else {
        format!(
            "none of the known actuator topics ({}) is in the log with its surface fields",
            aeroident_io::inspect::surfaces::KNOWN_SURFACE_TOPICS.join(", ")
        )
    };
    format!(
        "no surface channel is known: {why}; give a mapping with `--map MAPPING.toml` whose \
         `de`, `da` or `dr` channel names the surface column (docs/mapping.md)"
    )
}

/// The windows of every manoeuvre found, across channels, in time order; windows that overlap
/// (the same manoeuvre seen on two surfaces, or a coupled input) are joined into one.
pub fn manoeuvre_windows(report: &InspectReport) -> Vec<TimeWindow> {
    let mut w: Vec<(f64, f64)> = report
        .detections
        .iter()
        .flat_map(|d| d.manoeuvres.iter().map(|m| (m.start_s, m.end_s)))
        .collect();
    w.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<TimeWindow> = Vec::new();
    for (a, b) in w {
        match out.last_mut() {
            Some(last) if a <= last.end_s => last.end_s = last.end_s.max(b),
            _ => out.push(TimeWindow { start_s: a, end_s: b }),
        }
    }
    out
}
