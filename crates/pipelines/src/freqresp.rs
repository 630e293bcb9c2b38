//! Frequency responses of a record (`aeroident freqresp`): read through the mapping → the time
//! windows → contiguous, uniformly sampled stretches → the composite-window spectral estimate
//! of [`aeroident_signals::spectral`] for every (output, input) pair → optional low-order
//! transfer-function fits ([`aeroident_signals::tf_fit`]).
//!
//! **Channels** are named by their mapping keys and read in SI from the reader's samples
//! ([`AirDataSample::field`]): any channel that fills a measured field, e.g. `de, da, dr`
//! (rad), `p, q, r` (rad/s), `alpha, beta, phi, theta, psi` (rad), `ax, ay, az` (m/s²), `vt`
//! (m/s), `qbar` (Pa), `throttle` (–), `thrust` (N), `pdot` (rad/s²). A response's magnitude is in
//! dB of the output's SI unit per the input's (rad/s per rad for `q/de`). On a log with
//! ArduPilot SYSID sweeps, the channel [`sysid::INJECTED`] (`sysid`) is the injected waveform
//! ([`FreqRespOptions::excitation`], [`sysid`]), linear between its samples; a sample it does
//! not cover (outside the sweeps, across a gap in `SIDD`) ends the stretch.
//!
//! **Stretches.** Spectral windows need every sample at the same interval: the record is split
//! at its gaps (the reader's gap events, the time windows) and wherever an interval differs
//! from the record's median by more than 1 % (a rejected row leaves a hole); each stretch is
//! windowed on its own. No spike screen: a spike is data the coherence judges.
//!
//! `freqresp.json` keys: `file, samples, stretches, dt_s, window_lengths_s, overlap,
//! sweeps[…] (see [`sysid::SweepSummary`]; empty without `excitation`), pairs[{input, output, frequency_hz[], magnitude_db[], phase_deg[], coherence[],
//! multiple_coherence[], random_error[], magnitude_error_db[], phase_error_deg[]}],
//! fits[…] (see [`FitSummary`]), warnings[]`; a value not identified is `null`.

use crate::record::RecordError;
use crate::record::read_records;
use crate::window::TimeWindow;
use aeroident_estimators::AirDataSample;
use aeroident_estimators::sample::MEASURED_FIELDS;
use aeroident_io::excitation::{Excitation, injected_at};
use aeroident_io::{Channel, FlightDataReader};
use aeroident_signals::spectral::{PairResponse, SpectralOptions, Stretch, frequency_responses};
use aeroident_signals::tf_fit::{FitOptions, TfFit, TfSpec, fit_transfer_function};
use serde::Serialize;
use std::io::Read;
use sysid::{INJECTED, SweepSummary};

pub mod sysid;

/// Options of one frequency-response run.
#[derive(Debug, Clone, Default)]
pub struct FreqRespOptions {
    /// Input channels (mapping keys), at least one.
    pub inputs: Vec<String>,
    /// Output channels (mapping keys), at least one.
    pub outputs: Vec<String>,
    /// Time windows of the record used; empty: all of it.
    pub windows: Vec<TimeWindow>,
    /// Spectral options.
    pub spectral: SpectralOptions,
    /// Transfer-function fits to make on the responses.
    pub fits: Vec<TfSpec>,
    /// Options of the fits.
    pub fit: FitOptions,
    /// The log's SYSID sweeps used (their spans are normally the `windows`) and the injected
    /// waveform, the channel [`sysid::INJECTED`]; `None`: no such channel.
    pub excitation: Option<Excitation>,
}

/// One transfer-function fit in `freqresp.json` (the fitted model and how well it matches).
#[derive(Debug, Clone, Serialize)]
pub struct FitSummary {
    /// The spec as given, e.g. `q/de:1/2+delay`.
    pub spec: String,
    /// The fit ([`TfFit`] documents its keys).
    #[serde(flatten)]
    pub fit: TfFit,
}

/// `freqresp.json` (module doc).
#[derive(Debug, Clone, Serialize)]
pub struct FreqRespOutcome {
    /// The record.
    pub file: String,
    /// Samples used.
    pub samples: usize,
    /// Contiguous stretches the samples form.
    pub stretches: usize,
    /// Sample interval, s.
    pub dt_s: f64,
    /// Window lengths, s.
    pub window_lengths_s: Vec<f64>,
    /// Window overlap, fraction.
    pub overlap: f64,
    /// The SYSID sweeps used (empty without [`FreqRespOptions::excitation`]).
    pub sweeps: Vec<SweepSummary>,
    /// Every (output, input) pair, outputs outer.
    pub pairs: Vec<PairResponse>,
    /// Transfer-function fits.
    pub fits: Vec<FitSummary>,
    /// What the reader and the stage noticed (rejected rows, stretches dropped).
    pub warnings: Vec<String>,
}

/// The sample field (SI name, [`MEASURED_FIELDS`]) that the mapping's channel `key` fills;
/// `None` for a key that fills none (a constant, or no channel).
fn sample_field(key: &str) -> Option<&'static str> {
    MEASURED_FIELDS
        .iter()
        .copied()
        .find(|f| Channel::of_sample_field(f).is_some_and(|c| c.key() == key))
}

/// The mapping keys a response can be taken of: every channel that fills a measured field of
/// the sample.
pub fn channels() -> Vec<&'static str> {
    MEASURED_FIELDS.iter().filter_map(|f| Channel::of_sample_field(f)).map(Channel::key).collect()
}

/// Frequency responses (and fits) of the record `reader` reads (module doc).
///
/// # Errors
/// [`RecordError::Option`] naming `input`/`output` for a channel that is not known or not in
/// the record, `window` for bad time windows, and the spectral stage's errors (window too long,
/// an input not excited, frequency range) naming their option or channel; fatal data errors.
pub fn freqresp<R: Read>(
    reader: FlightDataReader<R>,
    opts: &FreqRespOptions,
) -> Result<FreqRespOutcome, RecordError> {
    check(opts)?;
    let file = reader.file().to_string();
    let rec = read_records(vec![reader], None, None, &opts.windows)?;
    let mut warnings = rec.notes.clone();
    let (rejections, unlisted) = rec.rejections.finish();
    warnings.extend(rejections.iter().take(20).map(|r| format!("row {}: {}", r.row, r.reason)));
    warnings.extend(unlisted);
    let names: Vec<String> = opts.inputs.iter().chain(&opts.outputs).cloned().collect();
    let sources = Sources {
        names: &names,
        n_inputs: opts.inputs.len(),
        excitation: opts.excitation.as_ref(),
    };
    let (stretches, dt_s, dropped) = stretches(&rec.manoeuvres, &sources)?;
    if dropped.short > 0 {
        warnings.push(format!(
            "{} samples in stretches of fewer than 4 samples between holes were not used",
            dropped.short
        ));
    }
    if dropped.uncovered > 0 {
        warnings.push(format!(
            "{} samples outside the injected waveform's samples (SIDD) were not used",
            dropped.uncovered
        ));
    }
    if stretches.is_empty() {
        return Err(RecordError::Option {
            option: "window",
            reason: format!(
                "no uniformly sampled stretch of 4 or more samples in the record{} ({} samples in shorter ones): nothing to transform",
                if opts.windows.is_empty() { "" } else { "'s windows" },
                dropped.short
            ),
        });
    }
    let samples = stretches.iter().map(|s| s[0].len()).sum();
    let r = frequency_responses(&stretches, &opts.inputs, &opts.outputs, dt_s, &opts.spectral)
        .map_err(spectral_error)?;
    let fits = opts
        .fits
        .iter()
        .map(|spec| fit_one(spec, &r.pairs, &opts.fit))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(FreqRespOutcome {
        file,
        samples,
        stretches: stretches.len(),
        dt_s,
        window_lengths_s: r.window_lengths_s,
        overlap: r.overlap,
        sweeps: opts
            .excitation
            .iter()
            .flat_map(|e| e.sweeps.iter().map(SweepSummary::from))
            .collect(),
        pairs: r.pairs,
        fits,
        warnings,
    })
}

/// Checks what the options alone decide ([`freqresp`] does it first): the channels known and
/// distinct, the spectral options and the coherence in range. A face calls it before it
/// touches its output, so that a bad option leaves the previous results in place.
///
/// # Errors
/// [`RecordError::Option`] naming the option as the command line spells it.
pub fn check(opts: &FreqRespOptions) -> Result<(), RecordError> {
    check_channels(opts)?;
    check_options(opts)
}

fn check_channels(opts: &FreqRespOptions) -> Result<(), RecordError> {
    for (option, list) in [("input", &opts.inputs), ("output", &opts.outputs)] {
        if list.is_empty() {
            return Err(RecordError::Option { option, reason: "give at least one channel".into() });
        }
        if list.iter().any(|k| k == INJECTED)
            && opts.excitation.as_ref().is_none_or(|e| e.t_s.is_empty())
        {
            return Err(RecordError::Option {
                option,
                reason: format!(
                    "`{INJECTED}` is the injected waveform of an ArduPilot SYSID log: give --window sysid on a log with SIDS and SIDD messages"
                ),
            });
        }
        if let Some(bad) = list.iter().find(|k| *k != INJECTED && sample_field(k).is_none()) {
            return Err(RecordError::Option {
                option,
                reason: format!("`{bad}` is not a channel; one of {}", channels().join(", ")),
            });
        }
    }
    let lists = [
        ("input", &opts.inputs, "an input conditioned on itself leaves nothing to excite it"),
        (
            "output",
            &opts.outputs,
            "each output's responses are computed once; the second would repeat them",
        ),
    ];
    for (option, list, why) in lists {
        if let Some((_, dup)) = list.iter().enumerate().find(|(k, c)| list[..*k].contains(c)) {
            return Err(RecordError::Option {
                option,
                reason: format!("`{dup}` is given twice ({why})"),
            });
        }
    }
    if let Some(dup) = opts.inputs.iter().find(|k| opts.outputs.contains(k)) {
        return Err(RecordError::Option {
            option: "output",
            reason: format!("`{dup}` is also an input"),
        });
    }
    Ok(())
}

/// Checks what the options alone decide before the record is read, so that a value out of
/// range (a points-per-decade that would size a grid of terabytes, a NaN coherence that no
/// frequency passes) is named at once rather than after the read or not at all.
fn check_options(opts: &FreqRespOptions) -> Result<(), RecordError> {
    opts.spectral.check().map_err(spectral_error)?;
    let c = opts.fit.min_coherence;
    if !(0.0..=1.0).contains(&c) {
        return Err(RecordError::Option {
            option: "min-coherence",
            reason: format!("{c} is not a coherence in [0, 1]"),
        });
    }
    Ok(())
}

/// The command-line spelling of a [`SpectralOptions`] field, as [`RecordError::Option`] names
/// options (the Python keywords are the same words with underscores).
fn spectral_flag(field: &'static str) -> &'static str {
    match field {
        "window_lengths_s" => "windows-s",
        "f_min_hz" => "f-min-hz",
        "f_max_hz" => "f-max-hz",
        "points_per_decade" => "points-per-decade",
        other => other,
    }
}

fn spectral_error(e: aeroident_signals::spectral::SpectralError) -> RecordError {
    use aeroident_signals::spectral::SpectralError as E;
    match e {
        E::Option { option, reason } => {
            RecordError::Option { option: spectral_flag(option), reason }
        }
        E::NotExcited { .. } => RecordError::Option { option: "input", reason: e.to_string() },
        E::Data(m) => RecordError::Model(m),
    }
}

/// Where the channels of a response come from: the sample's fields, or the injected waveform.
struct Sources<'a> {
    /// Inputs then outputs (mapping keys or [`INJECTED`]).
    names: &'a [String],
    n_inputs: usize,
    excitation: Option<&'a Excitation>,
}

/// Samples left out of the stretches.
#[derive(Default)]
struct Dropped {
    /// In stretches too short to use.
    short: usize,
    /// Where the injected waveform has no value.
    uncovered: usize,
}

/// Splits the manoeuvres into uniformly sampled stretches of the channels `src.names` (module
/// doc). Returns them, the interval and the samples left out.
fn stretches(
    manoeuvres: &[Vec<AirDataSample>],
    src: &Sources,
) -> Result<(Vec<Stretch>, f64, Dropped), RecordError> {
    let dt = crate::record::median_interval_s(manoeuvres.iter().map(Vec::as_slice))
        .ok_or_else(|| RecordError::Model("fewer than two samples: no sample interval".into()))?;
    // Resolved once: the keys were checked by `check_channels`.
    let fields: Vec<&str> = src.names.iter().map(|k| sample_field(k).unwrap_or("")).collect();
    let hold = src.excitation.map_or(0.0, |e| aeroident_io::align::hold_interval_s(&e.t_s));
    let mut out: Vec<Stretch> = Vec::new();
    let mut dropped = Dropped::default();
    for m in manoeuvres {
        let mut current: Stretch = vec![Vec::new(); src.names.len()];
        let mut last_t: Option<f64> = None;
        for s in m {
            if let Some(t0) = last_t
                && ((s.t_s - t0) - dt).abs() > 0.01 * dt
            {
                dropped.short += close(&mut current, &mut out);
            }
            last_t = Some(s.t_s);
            let Some(row) = row_of(s, src, &fields, hold)? else {
                dropped.uncovered += 1;
                dropped.short += close(&mut current, &mut out);
                continue;
            };
            for (c, v) in row.into_iter().enumerate() {
                current[c].push(v);
            }
        }
        dropped.short += close(&mut current, &mut out);
    }
    Ok((out, dt, dropped))
}

/// The channels' values in sample `s`; `None` where the injected waveform has none.
///
/// # Errors
/// A mapped channel the sample lacks, naming it.
fn row_of(
    s: &AirDataSample,
    src: &Sources,
    fields: &[&str],
    hold: f64,
) -> Result<Option<Vec<f64>>, RecordError> {
    let mut row = Vec::with_capacity(fields.len());
    for (c, (key, field)) in src.names.iter().zip(fields).enumerate() {
        if key == INJECTED {
            match src.excitation.and_then(|e| injected_at(e, s.t_s, hold)) {
                Some(v) => row.push(v),
                None => return Ok(None),
            }
            continue;
        }
        let v = s.field(field).ok_or_else(|| RecordError::Option {
            option: if c < src.n_inputs { "input" } else { "output" },
            reason: format!(
                "channel `{key}` is not in the record at t = {} s (map it in the mapping's [channels])",
                s.t_s
            ),
        })?;
        row.push(v);
    }
    Ok(Some(row))
}

/// Moves `current` to `out` when it holds at least 4 samples; returns the samples dropped.
fn close(current: &mut Stretch, out: &mut Vec<Stretch>) -> usize {
    let n = current[0].len();
    let taken = std::mem::replace(current, vec![Vec::new(); current.len()]);
    if n >= 4 {
        out.push(taken);
        0
    } else {
        n
    }
}

/// Fits `spec` to its pair's response.
fn fit_one(
    spec: &TfSpec,
    pairs: &[PairResponse],
    opts: &FitOptions,
) -> Result<FitSummary, RecordError> {
    let p = pairs.iter().find(|p| p.input == spec.input && p.output == spec.output).ok_or_else(
        || RecordError::Option {
            option: "fit",
            reason: format!(
                "`{}`: no response of `{}` to `{}` (give them as --output and --input)",
                spec.text, spec.output, spec.input
            ),
        },
    )?;
    let fit = fit_transfer_function(p, spec, opts).map_err(|e| RecordError::Option {
        option: "fit",
        reason: format!("`{}`: {e}", spec.text),
    })?;
    Ok(FitSummary { spec: spec.text.clone(), fit })
}

/// The coherence from which `aeroident freqresp`'s summary counts a frequency as identified
/// (its `coherence ≥ 0.8` band, [`coherent_band`]).
pub const GOOD_COHERENCE: f64 = 0.8;

/// Where a pair's response is coherent: the first and last grid frequency with the coherence
/// at or above a threshold, and how many grid points are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoherentBand {
    /// The lowest such frequency, rad/s.
    pub lo_rad_s: f64,
    /// The highest such frequency, rad/s.
    pub hi_rad_s: f64,
    /// Grid points with the coherence at or above the threshold (not necessarily contiguous).
    pub points: usize,
    /// Grid points of the pair.
    pub of: usize,
}

/// The band of `p`'s frequency grid (ascending, Hz) whose coherence is at least
/// `min_coherence` (–), in rad/s; `None` when no frequency is.
pub fn coherent_band(p: &PairResponse, min_coherence: f64) -> Option<CoherentBand> {
    let good: Vec<f64> = p
        .frequency_hz
        .iter()
        .zip(&p.coherence)
        .filter(|(_, g)| **g >= min_coherence)
        .map(|(f, _)| 2.0 * std::f64::consts::PI * f)
        .collect();
    Some(CoherentBand {
        lo_rad_s: *good.first()?,
        hi_rad_s: *good.last()?,
        points: good.len(),
        of: p.frequency_hz.len(),
    })
}

#[cfg(test)]
mod tests;
