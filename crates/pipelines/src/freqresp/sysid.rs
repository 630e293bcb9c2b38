//! The excitation a log records of itself as the frequency response's windows and input:
//! ArduPilot SYSID sweeps ([`aeroident_io::excitation`]).
//!
//! Each chosen sweep's span becomes a time window. The input defaults to the surface the swept
//! axis moves (`FW_MIX_PITCH`: `de`, `FW_MIX_ROLL`: `da`) when the mapping maps it, else to the
//! injected waveform itself, the channel [`INJECTED`] (`SIDD.Targ` in SI: rad for attitude
//! axes, rad/s for rate axes, mixer units for mixer axes).

use crate::record::RecordError;
use crate::window::TimeWindow;
use aeroident_io::excitation::{Axis, Excitation, Sweep};
use aeroident_io::{Channel, Mapping};
use serde::Serialize;

/// The channel name of the injected waveform (`SIDD.Targ`, in SI).
pub const INJECTED: &str = "sysid";

/// One sweep used, as `freqresp.json` lists it under `sweeps`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepSummary {
    /// `SID_AXIS` value.
    pub axis: u8,
    /// ArduPilot's name of the axis, e.g. `FW_MIX_PITCH`.
    pub axis_name: &'static str,
    /// The unit `SIDD.Targ` and `magnitude` are logged in.
    pub injected_unit: &'static str,
    /// `SIDS.Mag`.
    pub magnitude: f64,
    /// Start and stop frequency, Hz.
    pub band_hz: (f64, f64),
    /// The span used as a window, log time, s.
    pub span_s: (f64, f64),
    /// `SIDS.TR`, the waveform's whole length, s.
    pub record_s: f64,
    /// `SIDD` samples in the span.
    pub sidd_samples: usize,
}

impl From<&Sweep> for SweepSummary {
    fn from(s: &Sweep) -> Self {
        Self {
            axis: s.axis.number,
            axis_name: s.axis.name,
            injected_unit: s.axis.unit,
            magnitude: s.magnitude,
            band_hz: s.band_hz,
            span_s: s.span_s,
            record_s: s.record_s,
            sidd_samples: s.sidd_samples,
        }
    }
}

/// The sweeps of `excitation` on `axis` (every sweep with `None`), and their spans as windows.
///
/// # Errors
/// [`RecordError::Option`] `window` when the log has no sweep, or none on `axis` (listing the
/// axes it has).
pub fn choose_sweeps(
    excitation: &Excitation,
    axis: Option<&Axis>,
    file: &str,
) -> Result<(Vec<Sweep>, Vec<TimeWindow>), RecordError> {
    let bad = |reason: String| RecordError::Option { option: "window", reason };
    if excitation.sweeps.is_empty() {
        return Err(bad(format!(
            "`sysid`: {file} has no SIDS message (no ArduPilot SYSID sweep); give the windows as START:END"
        )));
    }
    let chosen: Vec<Sweep> = excitation
        .sweeps
        .iter()
        .filter(|s| axis.is_none_or(|a| a.number == s.axis.number))
        .cloned()
        .collect();
    if chosen.is_empty() {
        return Err(bad(format!(
            "`sysid:{}`: {file} has no sweep on that axis (it has: {})",
            axis.map_or("", |a| a.name),
            axes_of(&excitation.sweeps)
        )));
    }
    let windows =
        chosen.iter().map(|s| TimeWindow { start_s: s.span_s.0, end_s: s.span_s.1 }).collect();
    Ok((chosen, windows))
}

/// The input of a response to `sweeps` when none is given (module doc).
///
/// # Errors
/// [`RecordError::Option`] `input` for sweeps on more than one axis.
pub fn default_input(sweeps: &[Sweep], mapping: &Mapping) -> Result<String, RecordError> {
    let first = sweeps.first().map(|s| s.axis);
    if let Some(a) = first
        && sweeps.iter().all(|s| s.axis.number == a.number)
    {
        let mapped =
            a.surface.filter(|key| Channel::ALL.iter().any(|c| c.key() == *key && mapping.has(*c)));
        return Ok(mapped.unwrap_or(INJECTED).to_string());
    }
    Err(RecordError::Option {
        option: "input",
        reason: format!(
            "the sweeps excite several axes ({}): choose one with --window sysid:AXIS, or name the input",
            axes_of(sweeps)
        ),
    })
}

/// The distinct axes of `sweeps`, `NAME (n)` in order of first appearance.
fn axes_of(sweeps: &[Sweep]) -> String {
    let mut seen: Vec<&Axis> = Vec::new();
    for s in sweeps {
        if !seen.iter().any(|a| a.number == s.axis.number) {
            seen.push(&s.axis);
        }
    }
    seen.iter().map(|a| format!("{} ({})", a.name, a.number)).collect::<Vec<_>>().join(", ")
}
