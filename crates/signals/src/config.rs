//! Serde configuration of inputs and disturbances: the ONE place where scenario-file values
//! (with their declared units) become signals in API units (radians, seconds).
//!
//! Each quantity that can come in two units has two optional keys and exactly one must be given:
//! `amplitude` (the caller's units, e.g. the raw input of a thesis proof-of-concept system, or
//! radians) or `amplitude_deg` (degrees, converted once here with `to_radians`, for aircraft
//! surfaces); `frequency_rad_s` or `frequency_hz`; `phase_rad` or `phase_deg` (optional,
//! default 0). Unknown keys are errors (`deny_unknown_fields`), so a typo such as
//! `amplitud_deg` is reported by the TOML parser with its line.
//!
//! # TOML shapes
//! ```toml
//! [input]                    # any table the scenario schema puts an InputConfig in
//! kind = "doublet"           # step | pulse | doublet | three_two_one_one | sine | sweep |
//!                            # multisine | orthogonal_multisine | recorded |
//!                            # band_limited_white_noise | sum
//! amplitude_deg = -0.05      # or: amplitude = -8.7e-4 (radians / caller's units)
//! start_s = 1.0              # default 0
//! pulse_width_s = 0.5        # width of EACH half
//! ```
//! Every kind, as inline tables (this example is compiled and run as a doctest):
//! ```
//! # use aeroident_signals::{InputConfig, InputSignal};
//! # #[derive(serde::Deserialize)]
//! # struct Examples { input: Vec<InputConfig> }
//! let text = r#"
//! input = [
//!   { kind = "step", amplitude = 3.0, start_s = 0.0 },
//!   { kind = "pulse", amplitude_deg = 1.0, start_s = 1.0, width_s = 0.5 },
//!   { kind = "doublet", amplitude_deg = -0.05, start_s = 1.0, pulse_width_s = 0.5 },
//!   { kind = "three_two_one_one", amplitude_deg = 1.0, start_s = 1.0, dt_s = 0.3 },
//!   { kind = "sine", amplitude_deg = 0.05, frequency_hz = 1.0, phase_deg = 0.0,
//!     start_s = 0.0, duration_s = 20.0 },
//!   { kind = "sweep", amplitude_deg = 0.5, start_frequency_hz = 0.1,
//!     end_frequency_hz = 3.0, duration_s = 30.0, law = "logarithmic", taper_s = 1.0 },
//!   { kind = "multisine", amplitude_deg = 0.2, base_period_s = 10.0,
//!     harmonics = [1, 2, 3, 4, 5, 6, 7] },
//!   { kind = "orthogonal_multisine", amplitude_deg = 1.0, base_period_s = 10.0,
//!     harmonics = [2, 3, 4, 5, 6, 7, 8, 9, 10], inputs = 3, index = 0 },
//!   { kind = "band_limited_white_noise", noise_power = 1e-4, sample_time_s = 0.01, seed = 7 },
//!   { kind = "sum", parts = [ { kind = "step", amplitude = 1.0 },
//!                             { kind = "sine", amplitude = 0.1, frequency_rad_s = 0.7 } ] },
//! ]
//! "#;
//! // (also: { kind = "recorded", path = "stick.csv", time_column = "t_s",
//! //          value_column = "de_deg", unit = "deg" }, resolved by `build_in(dir)`.)
//! let ex: Examples = toml::from_str(text).unwrap();
//! for c in &ex.input {
//!     assert!(c.build().unwrap().value(1.2).is_finite());
//! }
//! ```
//!
//! A scenario schema that adds a channel can flatten this enum:
//! `struct Maneuver { channel: Channel, #[serde(flatten)] input: InputConfig }` — unknown keys are
//! still rejected by the inner enum (tested below).

use serde::Deserialize;

use nalgebra::Vector3;

use crate::WindField;
use crate::error::SignalError;
use crate::gust::{BodyAxis, BodyAxisGust, OneMinusCosineGust};
use crate::turbulence::{DrydenParameters, DrydenTurbulence, TurbulenceSeverity};
use std::path::{Path, PathBuf};

use crate::inputs::{
    Doublet, Input, Multisine, Pulse, Sine, Step, Sum, Sweep, SweepLaw, ThreeTwoOneOne,
};
use crate::noise::BandLimitedWhiteNoise;
use crate::recorded::{RecordedInput, ValueUnit};

/// One input as written in a scenario file; build it with [`InputConfig::build`].
/// See the module docs for the TOML shapes and the unit rules.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum InputConfig {
    /// [`Step`]: `amplitude` | `amplitude_deg`, `start_s` (default 0).
    Step {
        /// Height in the caller's units (radians for surfaces).
        amplitude: Option<f64>,
        /// Height in degrees (converted to radians).
        amplitude_deg: Option<f64>,
        /// Step time (s).
        #[serde(default)]
        start_s: f64,
    },
    /// [`Pulse`]: `amplitude` | `amplitude_deg`, `start_s` (default 0), `width_s`.
    Pulse {
        /// Height in the caller's units.
        amplitude: Option<f64>,
        /// Height in degrees.
        amplitude_deg: Option<f64>,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Width (s), > 0.
        width_s: f64,
    },
    /// [`Doublet`]: `amplitude` | `amplitude_deg`, `start_s` (default 0), `pulse_width_s`
    /// (width of each half).
    Doublet {
        /// Height of the first half in the caller's units (negative flips the doublet).
        amplitude: Option<f64>,
        /// Height of the first half in degrees.
        amplitude_deg: Option<f64>,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Width of each half (s), > 0.
        pulse_width_s: f64,
    },
    /// [`Sine`]: `amplitude` | `amplitude_deg`, `frequency_rad_s` | `frequency_hz`,
    /// optional `phase_rad` | `phase_deg`, `start_s` (default 0), optional `duration_s`.
    Sine {
        /// Amplitude in the caller's units.
        amplitude: Option<f64>,
        /// Amplitude in degrees.
        amplitude_deg: Option<f64>,
        /// Angular frequency (rad/s).
        frequency_rad_s: Option<f64>,
        /// Frequency (Hz), converted to rad/s as 2π·f.
        frequency_hz: Option<f64>,
        /// Phase at `start_s` (rad).
        phase_rad: Option<f64>,
        /// Phase at `start_s` (deg).
        phase_deg: Option<f64>,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Duration (s); absent = until the end of the run.
        duration_s: Option<f64>,
    },
    /// [`ThreeTwoOneOne`]: `amplitude` | `amplitude_deg`, `start_s` (default 0), `dt_s` (the
    /// time unit Δt). TOML kind `three_two_one_one` (alias `3211`).
    #[serde(alias = "3211")]
    ThreeTwoOneOne {
        /// Height of the first (3Δt) pulse in the caller's units.
        amplitude: Option<f64>,
        /// Height of the first pulse in degrees.
        amplitude_deg: Option<f64>,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Time unit Δt (s), > 0.
        dt_s: f64,
    },
    /// [`Sweep`]: `amplitude` | `amplitude_deg`, `start_frequency_hz` | `start_frequency_rad_s`,
    /// `end_frequency_hz` | `end_frequency_rad_s`, `duration_s`, `law` (`linear` |
    /// `logarithmic`), `start_s` (default 0), `taper_s` (default 0 = no taper).
    Sweep {
        /// Amplitude in the caller's units.
        amplitude: Option<f64>,
        /// Amplitude in degrees.
        amplitude_deg: Option<f64>,
        /// Start frequency (rad/s).
        start_frequency_rad_s: Option<f64>,
        /// Start frequency (Hz).
        start_frequency_hz: Option<f64>,
        /// End frequency (rad/s).
        end_frequency_rad_s: Option<f64>,
        /// End frequency (Hz).
        end_frequency_hz: Option<f64>,
        /// Sweep duration (s).
        duration_s: f64,
        /// Frequency law.
        law: SweepLaw,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Raised-cosine fade-in/out length at each end (s).
        #[serde(default)]
        taper_s: f64,
    },
    /// [`Multisine`] with Schroeder phases: `amplitude` | `amplitude_deg` (per component),
    /// `base_period_s`, `harmonics` (e.g. `[1, 2, 3, 4, 5]`), `start_s` (default 0), optional
    /// `duration_s`.
    Multisine {
        /// Amplitude of each component in the caller's units.
        amplitude: Option<f64>,
        /// Amplitude of each component in degrees.
        amplitude_deg: Option<f64>,
        /// Base period T (s); component i has frequency kᵢ·2π/T.
        base_period_s: f64,
        /// Harmonic numbers kᵢ (distinct, ≥ 1).
        harmonics: Vec<u32>,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Duration (s); absent = until the end of the run.
        duration_s: Option<f64>,
    },
    /// One member of an orthogonal phase-optimised multisine set
    /// ([`crate::orthogonal::orthogonal_multisine`], Morelli 2003): `amplitude` |
    /// `amplitude_deg` (the **peak** deflection of this input), `base_period_s`, `harmonics`
    /// (the pool shared by the whole set), `inputs` (members in the set), `index` (this member,
    /// 0-based), `start_s` (default 0), optional `duration_s`. The members of one set must share
    /// `base_period_s`, `harmonics`, `inputs` and `start_s` to stay orthogonal.
    OrthogonalMultisine {
        /// Peak of this member in the caller's units.
        amplitude: Option<f64>,
        /// Peak of this member in degrees.
        amplitude_deg: Option<f64>,
        /// Base period T (s).
        base_period_s: f64,
        /// The harmonic pool of the set (distinct, ≥ 1), dealt out in turn to the members.
        harmonics: Vec<u32>,
        /// Number of members of the set.
        inputs: usize,
        /// This member, 0-based.
        index: usize,
        /// Start (s).
        #[serde(default)]
        start_s: f64,
        /// Duration (s); absent = until the end of the run.
        duration_s: Option<f64>,
    },
    /// [`RecordedInput`] from a CSV file: `path` (relative paths are resolved against the
    /// directory given to [`InputConfig::build_in`], e.g. the scenario file's), optional
    /// `time_column` / `value_column` header names (default: first / second column), `unit`
    /// (`as_is` default | `deg`).
    Recorded {
        /// CSV file.
        path: PathBuf,
        /// Header name of the time column (s).
        time_column: Option<String>,
        /// Header name of the value column.
        value_column: Option<String>,
        /// Unit of the values.
        #[serde(default)]
        unit: ValueUnit,
    },
    /// [`BandLimitedWhiteNoise`]: `noise_power` (units²·s) | `noise_power_deg2_s` (deg²·s,
    /// converted to rad²·s), `sample_time_s`, `seed`.
    BandLimitedWhiteNoise {
        /// Two-sided PSD height in the caller's units² · s.
        noise_power: Option<f64>,
        /// Two-sided PSD height in deg² · s.
        noise_power_deg2_s: Option<f64>,
        /// Hold time of each sample (s), > 0.
        sample_time_s: f64,
        /// Generator seed.
        seed: u64,
    },
    /// [`Sum`] of the `parts` (each itself an `InputConfig`, nested sums allowed).
    Sum {
        /// The superposed inputs.
        parts: Vec<InputConfig>,
    },
}

/// Picks exactly one of two unit alternatives, scaling the second into API units.
fn one_of(
    first: &'static str,
    a: Option<f64>,
    second: &'static str,
    b: Option<f64>,
    scale_b: impl Fn(f64) -> f64,
) -> Result<f64, SignalError> {
    match (a, b) {
        (Some(x), None) => Ok(x),
        (None, Some(y)) => Ok(scale_b(y)),
        (Some(_), Some(_)) => Err(SignalError::UnitChoice { first, second, problem: "both given" }),
        (None, None) => Err(SignalError::UnitChoice { first, second, problem: "neither given" }),
    }
}

/// Like [`one_of`] but with a default when neither is given.
fn one_of_or(
    first: &'static str,
    a: Option<f64>,
    second: &'static str,
    b: Option<f64>,
    scale_b: impl Fn(f64) -> f64,
    default: f64,
) -> Result<f64, SignalError> {
    if a.is_none() && b.is_none() { Ok(default) } else { one_of(first, a, second, b, scale_b) }
}

fn amplitude(a: Option<f64>, a_deg: Option<f64>) -> Result<f64, SignalError> {
    one_of("amplitude", a, "amplitude_deg", a_deg, f64::to_radians)
}

impl InputConfig {
    /// Refuses an input whose highest frequency ([`InputConfig::highest_frequency_hz`]) reaches
    /// the Nyquist frequency of sampling it every `dt_s` (s): sampled, it becomes another, lower
    /// frequency, and the experiment is not the one written. The error says so with both
    /// frequencies.
    ///
    /// # Errors
    /// The reason, for the caller to prefix with the input's name.
    pub fn check_sampled_every(&self, dt_s: f64) -> Result<(), String> {
        let nyquist = 0.5 / dt_s;
        let short = |v: f64| aeroident_physics::text::Short(v).to_string();
        match self.highest_frequency_hz() {
            Some(f) if f >= nyquist => Err(format!(
                "its highest frequency {} Hz is at or above the Nyquist frequency {} Hz of dt_s = {} s: sampled, it becomes a lower frequency; lower it or shorten dt_s",
                short(f),
                short(nyquist),
                short(dt_s)
            )),
            _ => Ok(()),
        }
    }

    /// The highest frequency the input is built of, Hz, where it has one: a sine's, a sweep's
    /// higher end, a multisine's highest harmonic over its base period; `None` for the pulse
    /// inputs (broadband) and recorded ones. A scenario compares it with its sample rate's
    /// Nyquist frequency: a component above it is aliased to a lower one in the sampled run.
    pub fn highest_frequency_hz(&self) -> Option<f64> {
        let hz = |f_hz: Option<f64>, f_rad_s: Option<f64>| {
            f_hz.or(f_rad_s.map(|w| w / (2.0 * core::f64::consts::PI)))
        };
        match self {
            InputConfig::Sine { frequency_hz, frequency_rad_s, .. } => {
                hz(*frequency_hz, *frequency_rad_s)
            }
            InputConfig::Sweep {
                start_frequency_hz,
                start_frequency_rad_s,
                end_frequency_hz,
                end_frequency_rad_s,
                ..
            } => {
                let a = hz(*start_frequency_hz, *start_frequency_rad_s)?;
                let b = hz(*end_frequency_hz, *end_frequency_rad_s)?;
                Some(a.max(b))
            }
            InputConfig::Multisine { base_period_s, harmonics, .. }
            | InputConfig::OrthogonalMultisine { base_period_s, harmonics, .. } => {
                harmonics.iter().max().map(|k| f64::from(*k) / base_period_s)
            }
            _ => None,
        }
    }

    /// Builds the signal, converting every `_deg`/`_hz` value to radians / rad/s exactly once.
    /// Relative recorded-input paths are resolved against the current directory; use
    /// [`InputConfig::build_in`] to resolve them against the scenario file's directory.
    ///
    /// # Errors
    /// [`SignalError::UnitChoice`] when both or neither unit alternative is given, and the
    /// constructor errors of the signal types (naming the field and value).
    pub fn build(&self) -> Result<Input, SignalError> {
        self.build_in(Path::new(""))
    }

    /// As [`InputConfig::build`], resolving a relative recorded-input `path` against `base_dir`.
    ///
    /// # Errors
    /// As [`InputConfig::build`], plus the file errors of [`RecordedInput::from_csv_path`].
    pub fn build_in(&self, base_dir: &Path) -> Result<Input, SignalError> {
        Ok(match *self {
            InputConfig::ThreeTwoOneOne { amplitude: a, amplitude_deg, start_s, dt_s } => {
                ThreeTwoOneOne::new(amplitude(a, amplitude_deg)?, start_s, dt_s)?.into()
            }
            InputConfig::Recorded { ref path, ref time_column, ref value_column, unit } => {
                RecordedInput::from_csv_path(
                    &base_dir.join(path),
                    time_column.as_deref(),
                    value_column.as_deref(),
                    unit,
                )?
                .into()
            }
            InputConfig::Step { amplitude: a, amplitude_deg, start_s } => {
                Step::new(amplitude(a, amplitude_deg)?, start_s)?.into()
            }
            InputConfig::Pulse { amplitude: a, amplitude_deg, start_s, width_s } => {
                Pulse::new(amplitude(a, amplitude_deg)?, start_s, width_s)?.into()
            }
            InputConfig::Doublet { amplitude: a, amplitude_deg, start_s, pulse_width_s } => {
                Doublet::new(amplitude(a, amplitude_deg)?, start_s, pulse_width_s)?.into()
            }
            InputConfig::BandLimitedWhiteNoise {
                noise_power,
                noise_power_deg2_s,
                sample_time_s,
                seed,
            } => BandLimitedWhiteNoise::new(
                one_of(
                    "noise_power",
                    noise_power,
                    "noise_power_deg2_s",
                    noise_power_deg2_s,
                    |p| p * (core::f64::consts::PI / 180.0).powi(2),
                )?,
                sample_time_s,
                seed,
            )?
            .into(),
            InputConfig::Sum { ref parts } => {
                Sum::new(parts.iter().map(InputConfig::build).collect::<Result<Vec<_>, _>>()?)
                    .into()
            }
            InputConfig::Sweep { .. }
            | InputConfig::Multisine { .. }
            | InputConfig::OrthogonalMultisine { .. }
            | InputConfig::Sine { .. } => self.build_harmonic()?,
        })
    }

    /// The harmonic inputs (sweep, Schroeder and orthogonal multisines, sine): the ones with
    /// a frequency or a harmonic set, each frequency given in rad/s or Hz (`ω = 2π f`).
    fn build_harmonic(&self) -> Result<Input, SignalError> {
        let hz = |f: f64| core::f64::consts::TAU * f;
        Ok(match *self {
            InputConfig::Sweep {
                amplitude: a,
                amplitude_deg,
                start_frequency_rad_s,
                start_frequency_hz,
                end_frequency_rad_s,
                end_frequency_hz,
                duration_s,
                law,
                start_s,
                taper_s,
            } => Sweep::new(
                amplitude(a, amplitude_deg)?,
                one_of(
                    "start_frequency_rad_s",
                    start_frequency_rad_s,
                    "start_frequency_hz",
                    start_frequency_hz,
                    hz,
                )?,
                one_of(
                    "end_frequency_rad_s",
                    end_frequency_rad_s,
                    "end_frequency_hz",
                    end_frequency_hz,
                    hz,
                )?,
                start_s,
                duration_s,
                law,
                taper_s,
            )?
            .into(),
            InputConfig::Multisine {
                amplitude: a,
                amplitude_deg,
                base_period_s,
                ref harmonics,
                start_s,
                duration_s,
            } => Multisine::schroeder(
                amplitude(a, amplitude_deg)?,
                base_period_s,
                harmonics,
                start_s,
                duration_s,
            )?
            .into(),
            InputConfig::OrthogonalMultisine {
                amplitude: a,
                amplitude_deg,
                base_period_s,
                ref harmonics,
                inputs,
                index,
                start_s,
                duration_s,
            } => crate::orthogonal::orthogonal_multisine(
                amplitude(a, amplitude_deg)?,
                base_period_s,
                harmonics,
                inputs,
                index,
                start_s,
                duration_s,
            )?
            .into(),
            InputConfig::Sine {
                amplitude: a,
                amplitude_deg,
                frequency_rad_s,
                frequency_hz,
                phase_rad,
                phase_deg,
                start_s,
                duration_s,
            } => Sine::new(
                amplitude(a, amplitude_deg)?,
                one_of("frequency_rad_s", frequency_rad_s, "frequency_hz", frequency_hz, |f| {
                    core::f64::consts::TAU * f
                })?,
                one_of_or("phase_rad", phase_rad, "phase_deg", phase_deg, f64::to_radians, 0.0)?,
                start_s,
                duration_s,
            )?
            .into(),
            _ => unreachable!("build_in passes only the harmonic inputs"),
        })
    }
}

/// Builds the superposition of a list of inputs, e.g. all `[[maneuver]]` entries on one channel.
///
/// # Errors
/// The first error of [`InputConfig::build`] among the entries.
pub fn build_sum(configs: &[InputConfig]) -> Result<Input, SignalError> {
    Ok(Sum::new(configs.iter().map(InputConfig::build).collect::<Result<Vec<_>, _>>()?).into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InputSignal;
    use core::f64::consts::PI;

    fn parse(s: &str) -> Result<InputConfig, toml::de::Error> {
        toml::from_str(s)
    }

    #[test]
    fn analytic_doublet_in_degrees_becomes_radians() {
        let c = parse(
            "kind = \"doublet\"\namplitude_deg = -0.05\nstart_s = 1.0\npulse_width_s = 0.5\n",
        )
        .unwrap();
        let s = c.build().unwrap();
        let a = -0.05 * PI / 180.0;
        assert!((s.value(1.2) - a).abs() < 1e-18);
        assert!((s.value(1.7) + a).abs() < 1e-18);
        assert_eq!(s.value(2.0), 0.0);
    }

    #[test]
    fn analytic_sine_hz_and_phase_deg() {
        let c = parse("kind = \"sine\"\namplitude = 2.0\nfrequency_hz = 1.0\nphase_deg = 90.0\n")
            .unwrap();
        let s = c.build().unwrap();
        // 2 sin(2 pi t + pi/2) = 2 cos(2 pi t)
        assert!((s.value(0.0) - 2.0).abs() < 1e-15);
        assert!((s.value(0.5) + 2.0).abs() < 1e-14);
        assert!((s.value(0.125) - 2.0 * (PI / 4.0).cos()).abs() < 1e-14);
    }

    #[test]
    fn analytic_nested_sum_and_noise() {
        let c = parse(
            r#"
kind = "sum"
parts = [
  { kind = "step", amplitude = 1.0, start_s = 0.5 },
  { kind = "band_limited_white_noise", noise_power = 0.01, sample_time_s = 0.01, seed = 3 },
]
"#,
        )
        .unwrap();
        let s = c.build().unwrap();
        let noise = BandLimitedWhiteNoise::new(0.01, 0.01, 3).unwrap();
        assert_eq!(s.value(0.7), 1.0 + noise.value(0.7));
        assert_eq!(s.value(0.2), noise.value(0.2));
        let deg = parse(
            "kind = \"band_limited_white_noise\"\nnoise_power_deg2_s = 1.0\nsample_time_s = 1.0\nseed = 1\n",
        )
        .unwrap()
        .build()
        .unwrap();
        let Input::Noise(n) = deg else { panic!("not noise") };
        assert!((n.noise_power() - (PI / 180.0).powi(2)).abs() < 1e-18);
    }

    #[test]
    fn errors_name_the_key() {
        // unknown key (typo) is rejected by the parser, naming it
        let e = parse("kind = \"step\"\namplitud_deg = 1.0\n").unwrap_err();
        assert!(e.to_string().contains("amplitud_deg"), "{e}");
        // unknown kind
        let e = parse("kind = \"triangle\"\n").unwrap_err();
        assert!(e.to_string().contains("triangle"), "{e}");
        // both units
        let e = parse("kind = \"step\"\namplitude = 1.0\namplitude_deg = 1.0\n")
            .unwrap()
            .build()
            .unwrap_err();
        assert!(e.to_string().contains("amplitude_deg") && e.to_string().contains("both"));
        // neither
        let e = parse("kind = \"step\"\n").unwrap().build().unwrap_err();
        assert!(e.to_string().contains("neither"), "{e}");
        // bad value
        let e = parse("kind = \"doublet\"\namplitude = 1.0\npulse_width_s = -1.0\n")
            .unwrap()
            .build()
            .unwrap_err();
        assert!(e.to_string().contains("pulse_width_s") && e.to_string().contains("-1"));
    }

    #[test]
    fn flattened_into_a_channel_struct_still_rejects_unknown_keys() {
        #[derive(Deserialize)]
        struct Maneuver {
            #[allow(dead_code)]
            channel: String,
            #[serde(flatten)]
            input: InputConfig,
        }
        let m: Maneuver = toml::from_str(
            "channel = \"elevator\"\nkind = \"step\"\namplitude_deg = 1.0\nstart_s = 2.0\n",
        )
        .unwrap();
        assert!((m.input.build().unwrap().value(3.0) - 1f64.to_radians()).abs() < 1e-18);
        let bad: Result<Maneuver, _> = toml::from_str(
            "channel = \"elevator\"\nkind = \"step\"\namplitude_deg = 1.0\nstrat_s = 2.0\n",
        );
        assert!(bad.is_err());
    }

    #[test]
    fn analytic_step2_kinds_build_from_toml() {
        let m = parse("kind = \"3211\"\namplitude_deg = 1.0\nstart_s = 1.0\ndt_s = 0.5\n")
            .unwrap()
            .build()
            .unwrap();
        let a = 1f64.to_radians();
        assert_eq!(m.value(1.1), a);
        assert_eq!(m.value(2.6), -a);
        assert_eq!(m.value(3.6), a);
        assert_eq!(m.value(4.1), -a);
        let s = parse(
            "kind = \"sweep\"\namplitude = 1.0\nstart_frequency_hz = 1.0\nend_frequency_rad_s = 1.0\nduration_s = 10.0\nlaw = \"linear\"\n",
        )
        .unwrap()
        .build()
        .unwrap();
        let Input::Sweep(sw) = s else { panic!("not a sweep") };
        assert!((sw.instantaneous_frequency_rad_s(0.0) - 2.0 * PI).abs() < 1e-12);
        assert!((sw.instantaneous_frequency_rad_s(10.0) - 1.0).abs() < 1e-12);
        let ms = parse(
            "kind = \"multisine\"\namplitude = 1.0\nbase_period_s = 2.0\nharmonics = [1, 3]\n",
        )
        .unwrap()
        .build()
        .unwrap();
        // phases 0 and -pi*2*1/2 = -pi: cos(pi t) + cos(3 pi t - pi) at t = 0 is 1 - 1 = 0.
        assert!(ms.value(0.0).abs() < 1e-15);
        let e = parse(
            "kind = \"multisine\"\namplitude = 1.0\nbase_period_s = 2.0\nharmonics = [1, 1]\n",
        )
        .unwrap()
        .build()
        .unwrap_err();
        assert!(e.to_string().contains("harmonics"), "{e}");
    }

    #[test]
    fn analytic_recorded_from_toml_resolves_relative_to_base_dir() {
        let dir = std::env::temp_dir().join(format!("aeroident-signals-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("stick.csv"), "t_s,de_deg\n0,0\n2,1\n").unwrap();
        let c = parse("kind = \"recorded\"\npath = \"stick.csv\"\nunit = \"deg\"\n").unwrap();
        let r = c.build_in(&dir).unwrap();
        assert!((r.value(1.0) - 0.5f64.to_radians()).abs() < 1e-15);
        let e = c.build_in(Path::new("/nonexistent")).unwrap_err();
        assert!(e.to_string().contains("stick.csv"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn analytic_build_sum_of_list() {
        let list: Vec<InputConfig> = vec![
            parse("kind = \"step\"\namplitude = 1.0\n").unwrap(),
            parse("kind = \"step\"\namplitude = 2.0\nstart_s = 1.0\n").unwrap(),
        ];
        let s = build_sum(&list).unwrap();
        assert_eq!(s.value(0.5), 1.0);
        assert_eq!(s.value(1.5), 3.0);
    }
}

/// One disturbance as written in a scenario file; build a list with [`build_wind`].
///
/// ```toml
/// [[wind]]                      # thesis eq. 2.32 example: 20 ft/s, 6 s rise, 2 s delay
/// kind = "one_minus_cosine"
/// axis = "x"                    # body axis: x | y | z
/// amplitude_fps = 20.0
/// rise_time_s = 6.0
/// delay_s = 2.0
///
/// [[wind]]                      # MIL-F-8785C presets at the trim altitude and airspeed
/// kind = "dryden"
/// severity = "moderate"         # light | moderate | severe; OR give all six
/// altitude_ft = 20000.0         #   sigma_u_fps, sigma_v_fps, sigma_w_fps, L_u_ft, L_v_ft, L_w_ft
/// vt_fps = 675.0
/// sample_time_s = 0.01
/// duration_s = 60.0             # >= run length (the last sample is held after it)
/// seed = 11
/// ```
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum WindConfig {
    /// [`OneMinusCosineGust`] on one body axis.
    OneMinusCosine {
        /// Body axis.
        axis: BodyAxis,
        /// Final gust magnitude U_wind (ft/s).
        amplitude_fps: f64,
        /// Rise time d (s).
        rise_time_s: f64,
        /// Onset delay T_delay (s).
        #[serde(default)]
        delay_s: f64,
    },
    /// [`DrydenTurbulence`]: either `severity` + `altitude_ft` (MIL-F-8785C presets) or all six
    /// explicit intensities and scale lengths.
    Dryden {
        /// Severity preset (needs `altitude_ft`).
        severity: Option<TurbulenceSeverity>,
        /// Height above ground for the preset (ft).
        altitude_ft: Option<f64>,
        /// Explicit σ_u (ft/s).
        sigma_u_fps: Option<f64>,
        /// Explicit σ_v (ft/s).
        sigma_v_fps: Option<f64>,
        /// Explicit σ_w (ft/s).
        sigma_w_fps: Option<f64>,
        /// Explicit L_u (ft).
        L_u_ft: Option<f64>,
        /// Explicit L_v (ft).
        L_v_ft: Option<f64>,
        /// Explicit L_w (ft).
        L_w_ft: Option<f64>,
        /// Airspeed the turbulence is frozen at (ft/s).
        vt_fps: f64,
        /// Sample time (s).
        sample_time_s: f64,
        /// Generated length (s).
        duration_s: f64,
        /// Generator seed.
        seed: u64,
    },
}

/// A built wind field (static dispatch); sums of several are [`Wind::Sum`].
#[derive(Debug, Clone, PartialEq)]
pub enum Wind {
    /// 1-cos gusts per body axis.
    Gust(BodyAxisGust),
    /// Dryden turbulence.
    Dryden(DrydenTurbulence),
    /// Vector sum of the parts (empty = calm).
    Sum(Vec<Wind>),
}

impl WindField for Wind {
    fn wind_body_fps(&self, t_s: f64) -> Vector3<f64> {
        match self {
            Wind::Gust(g) => g.wind_body_fps(t_s),
            Wind::Dryden(d) => d.wind_body_fps(t_s),
            Wind::Sum(parts) => {
                parts.iter().fold(Vector3::zeros(), |acc, p| acc + p.wind_body_fps(t_s))
            }
        }
    }
}

impl WindConfig {
    /// The Dryden intensities and scale lengths of a `dryden` entry (the preset or the explicit
    /// values; `None` for another kind), frozen at the entry's `vt_fps`.
    ///
    /// # Errors
    /// [`SignalError::InvalidList`] for an entry that mixes or omits the preset and the explicit
    /// parameters; the preset's errors.
    pub fn dryden_parameters(&self) -> Result<Option<DrydenParameters>, SignalError> {
        let WindConfig::Dryden {
            severity,
            altitude_ft,
            sigma_u_fps,
            sigma_v_fps,
            sigma_w_fps,
            L_u_ft,
            L_v_ft,
            L_w_ft,
            ..
        } = *self
        else {
            return Ok(None);
        };
        let explicit = [sigma_u_fps, sigma_v_fps, sigma_w_fps, L_u_ft, L_v_ft, L_w_ft];
        Ok(Some(match (severity, altitude_ft, explicit) {
            (Some(sev), Some(h), [None, None, None, None, None, None]) => {
                DrydenParameters::mil_f_8785c(h, sev)?
            }
            (None, None, [Some(su), Some(sv), Some(sw), Some(lu), Some(lv), Some(lw)]) => {
                DrydenParameters {
                    sigma_u_fps: su,
                    sigma_v_fps: sv,
                    sigma_w_fps: sw,
                    L_u_ft: lu,
                    L_v_ft: lv,
                    L_w_ft: lw,
                }
            }
            _ => {
                return Err(SignalError::InvalidList {
                    field: "dryden",
                    reason: "give either `severity` and `altitude_ft`, or all of \
                             sigma_u_fps, sigma_v_fps, sigma_w_fps, L_u_ft, L_v_ft, L_w_ft"
                        .into(),
                });
            }
        }))
    }

    /// Builds the wind field.
    ///
    /// # Errors
    /// Constructor errors naming the field and value; [`SignalError::InvalidList`] for a Dryden
    /// entry that mixes or omits the preset and the explicit parameters.
    pub fn build(&self) -> Result<Wind, SignalError> {
        Ok(match *self {
            WindConfig::OneMinusCosine { axis, amplitude_fps, rise_time_s, delay_s } => Wind::Gust(
                BodyAxisGust::calm()
                    .with(axis, OneMinusCosineGust::new(amplitude_fps, rise_time_s, delay_s)?),
            ),
            WindConfig::Dryden { vt_fps, sample_time_s, duration_s, seed, .. } => {
                let params = self.dryden_parameters()?.ok_or(SignalError::InvalidList {
                    field: "dryden",
                    reason: "not a Dryden entry".into(),
                })?;
                Wind::Dryden(DrydenTurbulence::generate(
                    &params,
                    vt_fps,
                    sample_time_s,
                    duration_s,
                    seed,
                )?)
            }
        })
    }
}

/// Builds the vector sum of a list of disturbances (an empty list is calm air).
///
/// # Errors
/// The first error of [`WindConfig::build`].
pub fn build_wind(configs: &[WindConfig]) -> Result<Wind, SignalError> {
    Ok(Wind::Sum(configs.iter().map(WindConfig::build).collect::<Result<Vec<_>, _>>()?))
}

#[cfg(test)]
mod wind_tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Scenario {
        wind: Vec<WindConfig>,
    }

    #[test]
    fn analytic_gust_plus_dryden_from_toml() {
        let s: Scenario = toml::from_str(
            r#"
[[wind]]
kind = "one_minus_cosine"
axis = "x"
amplitude_fps = 20.0
rise_time_s = 6.0
delay_s = 2.0

[[wind]]
kind = "dryden"
severity = "moderate"
altitude_ft = 20000.0
vt_fps = 675.0
sample_time_s = 0.01
duration_s = 10.0
seed = 11
"#,
        )
        .unwrap();
        let w = build_wind(&s.wind).unwrap();
        let p = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Moderate).unwrap();
        let d = DrydenTurbulence::generate(&p, 675.0, 0.01, 10.0, 11).unwrap();
        let v = w.wind_body_fps(5.0);
        let expect = d.wind_body_fps(5.0) + Vector3::new(10.0, 0.0, 0.0);
        assert!((v - expect).norm() < 1e-12);
        assert_eq!(build_wind(&[]).unwrap().wind_body_fps(1.0), Vector3::zeros());
    }

    #[test]
    fn errors_for_mixed_dryden_and_bad_axis() {
        let s: Result<Scenario, _> = toml::from_str(
            "[[wind]]\nkind = \"one_minus_cosine\"\naxis = \"q\"\namplitude_fps = 1.0\nrise_time_s = 1.0\n",
        );
        assert!(s.unwrap_err().to_string().contains('q'));
        let s: Scenario = toml::from_str(
            "[[wind]]\nkind = \"dryden\"\nseverity = \"light\"\naltitude_ft = 100.0\nsigma_u_fps = 1.0\nvt_fps = 500.0\nsample_time_s = 0.01\nduration_s = 1.0\nseed = 1\n",
        )
        .unwrap();
        let e = build_wind(&s.wind).unwrap_err();
        assert!(e.to_string().contains("severity"), "{e}");
        let s: Scenario = toml::from_str(
            "[[wind]]\nkind = \"one_minus_cosine\"\naxis = \"z\"\namplitude_fps = 1.0\nrise_time_s = -1.0\n",
        )
        .unwrap();
        let e = build_wind(&s.wind).unwrap_err();
        assert!(e.to_string().contains("rise_time_s"), "{e}");
    }
}
