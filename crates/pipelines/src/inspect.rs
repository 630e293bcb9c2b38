//! `aeroident inspect`: what a log holds (the catalogue of [`aeroident_io::inspect`]) and its
//! candidate manoeuvres ([`detect`]), as one report the faces render as text, as the
//! `--json` document (docs/inspect.md) and as a plot. With a mapping, the record is also read
//! as air-data samples and its candidates judged in flight terms ([`rank`]): the ground and
//! taxi left out ([`envelope`]), phugoids added ([`phugoid`]), each candidate ranked per axis
//! by the information it holds ([`information`]).

pub mod detect;
pub mod envelope;
pub mod information;
pub mod phugoid;
pub mod rank;

use crate::error::PipelineError;
use crate::window::TimeWindow;
use aeroident_io::inspect::surfaces::Surface;
use aeroident_io::inspect::{INSPECT_SCHEMA, InspectOptions, LogSummary, Signal, inspect_log};
use detect::{ChannelDetection, DetectionRule};
use rank::Ranking;
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
    /// Per surface: quiet level, threshold and manoeuvres (with a mapping whose record has
    /// ground spans, of the flight part: the ground part's are `flight.ground_detections`).
    pub detections: Vec<ChannelDetection>,
    /// With a mapping: the ground spans, phugoids, ranks and window sets ([`rank`]).
    pub flight: Option<Ranking>,
    /// Why there is no `flight` judgement (no mapping, or the record could not be read as
    /// air-data samples through it).
    pub flight_note: Option<String>,
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
/// `rule`; with a mapping, judges them in flight terms with sets of
/// [`rank::DEFAULT_SET_SIZE`] windows per axis ([`inspect_ranked`]).
///
/// # Errors
/// The reader's error ([`inspect_log`]: file, byte or row, field), passed through.
pub fn inspect(
    path: &str,
    options: &InspectOptions,
    rule: &DetectionRule,
) -> Result<InspectOutcome, PipelineError> {
    inspect_ranked(path, options, rule, rank::DEFAULT_SET_SIZE)
}

/// [`inspect`] with window sets of `set_size` windows per axis.
///
/// # Errors
/// As [`inspect`]. A record the mapping cannot read as air-data samples is not an error: the
/// report's `flight_note` says why it is not judged.
pub fn inspect_ranked(
    path: &str,
    options: &InspectOptions,
    rule: &DetectionRule,
    set_size: usize,
) -> Result<InspectOutcome, PipelineError> {
    let ins = inspect_log(path, options).map_err(|e| PipelineError::Source(Box::new(e)))?;
    let samples = read_samples(path, options);
    let envelope = samples
        .as_ref()
        .ok()
        .and_then(|s| envelope::envelope(s, &envelope::EnvelopeRule::default()));
    let ground = envelope.as_ref().map_or(&[][..], |e| e.ground.as_slice());
    let signals = ins.surfaces.iter().filter_map(|s| {
        let sig = ins.signals.iter().find(|g| g.column == s.column)?;
        Some((s.column.as_str(), sig.t_s.as_slice(), sig.values.as_slice()))
    });
    let (detections, ground_detections) = detect_apart(signals, ground, rule);
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
    let (flight, flight_note) = match samples {
        Ok(samples) => {
            let inputs = [&detections, &ground_detections].map(|d| windows_of(d));
            let ranking = rank::rank(&samples, envelope, &inputs, set_size);
            (Some(rank::Ranking { ground_detections, ..ranking }), None)
        }
        Err(why) => (None, Some(why)),
    };
    let report = InspectReport {
        schema: INSPECT_SCHEMA,
        log: ins.summary,
        surfaces: ins.surfaces,
        surface_hint,
        detection_rule: *rule,
        detections,
        flight,
        flight_note,
    };
    Ok(InspectOutcome { report, signals: ins.signals })
}

/// Each surface signal `(channel, t_s, values)`'s manoeuvres, `(flight, ground)`: the flight
/// and the ground spans `ground` are judged apart, each by its own levels, since a taxi's
/// control check would otherwise set the flight's range and threshold.
fn detect_apart<'a>(
    signals: impl Iterator<Item = (&'a str, &'a [f64], &'a [f64])>,
    ground: &[envelope::GroundSpan],
    rule: &DetectionRule,
) -> (Vec<ChannelDetection>, Vec<ChannelDetection>) {
    let on_ground = |t: f64| ground.iter().any(|g| (g.start_s..=g.end_s).contains(&t));
    signals
        .map(|(channel, t_s, values)| {
            let part = |ground: bool| {
                let (t, v): (Vec<f64>, Vec<f64>) =
                    t_s.iter().zip(values).filter(|(t, _)| on_ground(**t) == ground).unzip();
                detect::detect(channel, &t, &v, rule)
            };
            (part(false), part(true))
        })
        .unzip()
}

/// The ranking of a record already read as air-data samples `samples` (time order), its
/// manoeuvres detected on the mapped surfaces `de`, `da`, `dr` by `rule` with sets of
/// `set_size` windows per axis: what [`inspect_ranked`] judges, without the log's own columns
/// (the surfaces in radians, as mapped, rather than in the column's unit: the detector's levels
/// scale with the signal). `None` when no surface is mapped.
pub fn rank_samples(
    samples: &[aeroident_estimators::AirDataSample],
    rule: &DetectionRule,
    set_size: usize,
) -> Option<Ranking> {
    type Surface = fn(&aeroident_estimators::AirDataSample) -> Option<f64>;
    const SURFACES: [(&str, Surface); 3] =
        [("de", |s| s.de_rad), ("da", |s| s.da_rad), ("dr", |s| s.dr_rad)];
    let t: Vec<f64> = samples.iter().map(|s| s.t_s).collect();
    let columns: Vec<(&str, Vec<f64>)> = SURFACES
        .iter()
        .filter(|(_, get)| samples.iter().any(|s| get(s).is_some()))
        .map(|(name, get)| (*name, samples.iter().map(|s| get(s).unwrap_or(f64::NAN)).collect()))
        .collect();
    if columns.is_empty() {
        return None;
    }
    let envelope = envelope::envelope(samples, &envelope::EnvelopeRule::default());
    let ground = envelope.as_ref().map_or(&[][..], |e| e.ground.as_slice());
    let signals = columns.iter().map(|(c, v)| (*c, t.as_slice(), v.as_slice()));
    let (detections, ground_detections) = detect_apart(signals, ground, rule);
    let inputs = [&detections, &ground_detections].map(|d| windows_of(d));
    let ranking = rank::rank(samples, envelope, &inputs, set_size);
    Some(Ranking { ground_detections, ..ranking })
}

/// The suggested windows of `detections`, `(start, end, channel)`.
fn windows_of(detections: &[ChannelDetection]) -> Vec<(f64, f64, String)> {
    detections
        .iter()
        .flat_map(|d| d.manoeuvres.iter().map(|m| (m.start_s, m.end_s, m.channel.clone())))
        .collect()
}

/// The record at `path` as air-data samples through the mapping of `options`, or why not.
fn read_samples(
    path: &str,
    options: &InspectOptions,
) -> Result<Vec<aeroident_estimators::AirDataSample>, String> {
    let mapping = options.mapping.ok_or(
        "no mapping: give `--map MAPPING.toml` to leave out the ground and taxi and to rank the \
         candidates by the information they hold",
    )?;
    let not_read = |e: &dyn std::fmt::Display| {
        format!("the record could not be read as air-data samples through the mapping: {e}")
    };
    let source = aeroident_io::RecordSource::Path(path.to_string());
    let opened = aeroident_io::Record::open(source, options.format, mapping);
    let reader = opened.map_err(|e| not_read(&e))?.reader;
    let record = crate::record::read_manoeuvres(reader, None, &[]).map_err(|e| not_read(&e))?;
    Ok(record.manoeuvres.into_iter().flatten().collect())
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
