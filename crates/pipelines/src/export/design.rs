//! Input design before flight: an orthogonal phase-optimised multisine on chosen surfaces
//! (Morelli, "Multiple input design for real-time parameter estimation in the frequency
//! domain", IFAC SYSID 2003; [`aeroident_signals::orthogonal`]), its injection tables, and the
//! predicted Cramér–Rao σ of every derivative for it at a flight condition of the F-16
//! ([`aeroident_estimators::output_error::design::predict_crb`]; Klein & Morelli 2006 ch. 6, 9).
//!
//! The harmonics are those of the record length `T` (the base period, so every member is
//! periodic over the record and the members are orthogonal over it) in a band (default
//! 0.1–1.5 Hz, the rigid-body modes of a fighter-sized aircraft): `k / T` Hz for
//! `k = ⌈f_lo T⌉ … ⌊f_hi T⌋`, dealt to the surfaces in turn (every `n`-th harmonic to surface
//! `i`). Each surface's signal has the given peak amplitude and starts and ends at 0.
//!
//! The flight condition is the Stevens & Lewis F-16 trimmed wings-level at the given altitude
//! and airspeed; the assumed derivatives are its true local derivatives there
//! ([`crate::aircraft::truth::local_derivatives`]), biases re-trimmed for the estimators' flight
//! model ([`trim_biases`]); sensors are the simulator's raw noise levels
//! ([`crate::montecarlo::crb_sensors`]).

use crate::aircraft::air_data::f16_constants;
use crate::airframe::FlyableAircraft;
use aeroident_estimators::flight_model::{N_STATES, Output};
use aeroident_estimators::output_error::InitialStates;
use aeroident_estimators::output_error::design::{
    DesignPlan, DesignResult, FlightCondition, PlannedInputs, predict_crb, predict_crb_turbulent,
    trim_biases,
};
use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_models::f16::{self, AeroIncrements, F16};
use aeroident_models::trim::{TrimCondition, TrimManeuver, trim};
use aeroident_physics::units::{M_PER_FT, N_PER_LBF, PA_PER_PSF};
use aeroident_signals::InputSignal;
use aeroident_signals::inputs::{Sweep, SweepLaw};
use aeroident_signals::orthogonal::orthogonal_multisine;
use aeroident_signals::turbulence::{DrydenParameters, TurbulenceSeverity};

/// A control surface of a design.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// Elevator, > 0 trailing edge down.
    De,
    /// Aileron, > 0 a negative rolling moment (right aileron trailing edge down).
    Da,
    /// Rudder, > 0 trailing edge left.
    Dr,
}

impl crate::Named for Surface {
    const ALL: &'static [Self] = &[Surface::De, Surface::Da, Surface::Dr];

    fn name(self) -> &'static str {
        Surface::name(self)
    }
}

impl Surface {
    /// `de`, `da`, `dr`.
    pub fn name(self) -> &'static str {
        match self {
            Surface::De => "de",
            Surface::Da => "da",
            Surface::Dr => "dr",
        }
    }
}

/// What to design.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSpec {
    /// Surfaces, each excited by one member of the orthogonal set.
    pub surfaces: Vec<Surface>,
    /// Peak amplitude of every surface's perturbation, rad.
    pub amplitude_rad: f64,
    /// Record length = base period, s.
    pub duration_s: f64,
    /// Sample rate of the tables, Hz.
    pub rate_hz: f64,
    /// Frequency band of the harmonics, Hz.
    pub band_hz: (f64, f64),
    /// Trim altitude, ft.
    pub alt_ft: f64,
    /// Trim true airspeed, ft/s.
    pub vt_fps: f64,
    /// Centre of gravity, fraction of c̄.
    pub xcg: f64,
    /// Dryden turbulence (MIL-F-8785C severity at `alt_ft`, frozen at `vt_fps`) to fly the
    /// record in: the bound then counts it as process noise
    /// ([`aeroident_estimators::output_error::design::predict_crb_turbulent`]); `None`: calm
    /// air, white sensor noise only.
    pub turbulence: Option<TurbulenceSeverity>,
    /// The waveform: an orthogonal multisine (all surfaces at once) or chirps.
    pub signal: Waveform,
}

/// The waveform of a design.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Waveform {
    /// Orthogonal phase-optimised multisines, every surface excited over the whole record
    /// (module doc).
    Multisine,
    /// A constant-amplitude frequency sweep per surface, one surface after another (the
    /// single-axis sweeps of frequency-response testing, Tischler & Remple 2012 ch. 5, and of
    /// ArduPilot's SYSID mode): each sweeps the band from its low to its high edge over
    /// `duration_s`, with `law` and a raised-cosine fade of `fade_s` at both ends
    /// ([`aeroident_signals::inputs::Sweep`]); the record is `n × duration_s` long.
    Chirp {
        /// Linear or logarithmic (equal time per octave) frequency law.
        law: SweepLaw,
        /// Fade-in and fade-out time, s (≤ half the sweep).
        fade_s: f64,
    },
}

/// Peak excursions beyond which the response is no longer a small perturbation (the bound
/// assumes the model's derivatives hold over it): α, β 5°, φ 30°, θ 20°, V 10 %.
pub fn large_excursions(d: &Design) -> Vec<String> {
    let r = &d.crb;
    let vt = d.plan.condition.vt_mps;
    r.outputs
        .iter()
        .zip(&r.output_excursion)
        .filter_map(|(o, e)| {
            let (limit, unit, scale) = match o {
                Output::Alpha | Output::Beta => (5f64.to_radians(), "deg", 1f64.to_degrees()),
                Output::Phi => (30f64.to_radians(), "deg", 1f64.to_degrees()),
                Output::Theta => (20f64.to_radians(), "deg", 1f64.to_degrees()),
                Output::Vt => (0.1 * vt, "m/s", 1.0),
                _ => return None,
            };
            (*e > limit).then(|| {
                format!("{} {:.1} {unit} (limit {:.1})", o.name(), e * scale, limit * scale)
            })
        })
        .collect()
}

/// A designed input and its predicted Cramér–Rao σ.
#[derive(Debug, Clone)]
pub struct Design {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Perturbation per surface (order of the spec), rad.
    pub inputs: Vec<(Surface, Vec<f64>)>,
    /// Harmonic numbers per surface (frequency = k / duration).
    pub harmonics: Vec<Vec<u32>>,
    /// The prediction.
    pub crb: DesignResult,
    /// The model structure predicted for.
    pub structure: ModelStructure,
    /// The plan the prediction is of (for a Monte Carlo check with
    /// [`aeroident_estimators::output_error::design::simulate_plan`]); a surface with an
    /// actuator enters it as the deflection its actuator makes of the command
    /// ([`Self::actuation`]).
    pub plan: DesignPlan,
    /// The designed surfaces that reach the aircraft through an actuator of the mapping (a
    /// model-file aircraft's, [`design_for_aircraft`]), in the order of [`Self::inputs`];
    /// empty when every surface is its command (the F-16's design, a mapping without
    /// actuators). `inputs` is then the servo command.
    pub actuation: Vec<Actuation>,
}

/// A designed surface flown through its actuator: the command table passed through the
/// mapping's first-order lag with its rate and position limits, the discrete model `sim`
/// flies ([`aeroident_io::mapping::Actuator::step`]: the command held over each sample
/// interval, the surface starting at its trim), and how often the limits acted.
#[derive(Debug, Clone, PartialEq)]
pub struct Actuation {
    /// The surface.
    pub surface: Surface,
    /// The mapping's actuator (τ s, rate limit rad/s, position limits rad).
    pub actuator: aeroident_io::mapping::Actuator,
    /// The deflection's perturbation from trim at every sample, rad: what the prediction uses.
    pub surface_rad: Vec<f64>,
    /// The nominal peak command rate, amplitude × 2π f_max (f_max the surface's highest
    /// harmonic, or the chirp's upper band edge), rad/s.
    pub nominal_rate_rad_s: f64,
    /// The command table's steepest slope, `max |Δu| / dt`, rad/s.
    pub peak_command_rate_rad_s: f64,
    /// Fraction of the sample intervals over which the rate limit cut the surface's move
    /// short, 0–1.
    pub rate_limited_fraction: f64,
    /// Fraction of the samples at which the surface sits on a position limit, 0–1.
    pub position_limited_fraction: f64,
}

/// A surface's response to a command table through an actuator ([`through_actuator`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ActuatorResponse {
    /// The deflection's perturbation from trim at every sample, rad.
    pub surface_rad: Vec<f64>,
    /// Sample intervals over which the rate limit acted.
    pub rate_limited_steps: usize,
    /// Samples at which the deflection sits on a position limit.
    pub position_limited_samples: usize,
}

/// The deflection `actuator` makes of `command_rad` (perturbations from the trim deflection
/// `trim_rad`, rad, one per sample `dt_s` apart) as `sim` flies it
/// ([`crate::sim::aircraft`]): the surface starts at trim, and each sample's command is
/// held over the interval after it ([`aeroident_io::mapping::Actuator::step_limited`]), so
/// even a vanishing τ puts the surface one sample behind the table. Limits act on the
/// absolute deflection `trim + δ`.
pub fn through_actuator(
    actuator: &aeroident_io::mapping::Actuator,
    trim_rad: f64,
    command_rad: &[f64],
    dt_s: f64,
) -> ActuatorResponse {
    let (lo, hi) = actuator.position_limits_rad;
    // As `sim` starts it: at the trim deflection, the limits acting from the first step.
    let mut surface = trim_rad;
    let mut out = ActuatorResponse {
        surface_rad: Vec::with_capacity(command_rad.len()),
        rate_limited_steps: 0,
        position_limited_samples: 0,
    };
    let mut held: Option<f64> = None;
    for &u in command_rad {
        if let Some(previous) = held {
            let (next, limited) = actuator.step_limited(surface, trim_rad + previous, dt_s);
            surface = next;
            // A step that ends on a position limit was decided by that limit, not the rate's.
            out.rate_limited_steps += usize::from(limited && next > lo && next < hi);
        }
        held = Some(u);
        out.position_limited_samples += usize::from(surface <= lo || surface >= hi);
        out.surface_rad.push(surface - trim_rad);
    }
    out
}

/// One flag per actuated surface of `d` whose rate limit the design reaches ([`Actuation`]:
/// any sample interval rate-limited), naming the surface, the fraction of the samples
/// limited, the command's slope and the limit; one per surface held on a position limit.
/// Empty when no limit acts (always for a design without actuators).
pub fn actuator_limit_flags(d: &Design) -> Vec<String> {
    let mut flags = Vec::new();
    for a in &d.actuation {
        if a.rate_limited_fraction > 0.0 {
            flags.push(format!(
                "{}: the actuator's rate limit {:.3} rad/s is reached on {:.1} % of the samples (command slope up to {:.3} rad/s, amplitude × 2π f_max {:.3} rad/s): the surface lags the table beyond its τ; lower --amplitude-deg or the band's upper edge",
                a.surface.name(),
                a.actuator.rate_limit_rad_s,
                100.0 * a.rate_limited_fraction,
                a.peak_command_rate_rad_s,
                a.nominal_rate_rad_s
            ));
        }
        if a.position_limited_fraction > 0.0 {
            let (lo, hi) = a.actuator.position_limits_rad;
            flags.push(format!(
                "{}: the surface sits on its position limits [{lo}, {hi}] rad on {:.1} % of the samples: lower --amplitude-deg",
                a.surface.name(),
                100.0 * a.position_limited_fraction
            ));
        }
    }
    flags
}

/// Most samples of a design's tables: checked before any is allocated (a sample count far
/// beyond flight-test practice, ~17 min at 100 Hz, would exhaust memory in the prediction's
/// sensitivities rather than tell anything).
pub const MAX_DESIGN_SAMPLES: f64 = 100_000.0;

/// Most harmonics in the band (each is evaluated at every sample; a designed manoeuvre uses
/// tens of them).
pub const MAX_DESIGN_HARMONICS: f64 = 2_000.0;

/// The altitudes of the flight condition, ft: the span of the F-16 engine's thrust tables
/// (Stevens & Lewis, 0–50 000 ft); beyond it the trim would rest on extrapolated thrust.
pub const DESIGN_ALT_RANGE_FT: (f64, f64) = (0.0, 50_000.0);

/// Checks the band against the sample rate (Nyquist limit).
fn check_band(spec: &DesignSpec) -> crate::error::Result<()> {
    let (lo, hi) = spec.band_hz;
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
        crate::bail!("--band-hz {lo} {hi}: give two finite frequencies, 0 ≤ low < high, Hz");
    }
    let nyquist = spec.rate_hz / 2.0;
    if hi >= nyquist {
        crate::bail!(
            "--band-hz {lo} {hi}: the upper edge is not below the Nyquist frequency {nyquist} Hz of --rate-hz {}: its harmonics cannot be sampled; lower the band or raise the rate",
            spec.rate_hz
        );
    }
    Ok(())
}

/// The harmonics `k` of base period `t` in the band.
fn pool(duration_s: f64, band_hz: (f64, f64)) -> Vec<u32> {
    let lo = (band_hz.0 * duration_s).ceil().max(1.0) as u32;
    let hi = (band_hz.1 * duration_s).floor().max(0.0) as u32;
    (lo..=hi).collect()
}

/// Sampled members of an orthogonal multisine set.
#[derive(Debug, Clone, PartialEq)]
pub struct Multisines {
    /// Sample times, s (0 … duration, both ends).
    pub t_s: Vec<f64>,
    /// One perturbation per surface, rad.
    pub inputs: Vec<Vec<f64>>,
    /// Harmonic numbers per surface.
    pub harmonics: Vec<Vec<u32>>,
}

/// The checks every waveform shares: positive amplitude, duration and rate, the sample
/// count, the band, and the surfaces.
fn check_common(spec: &DesignSpec) -> crate::error::Result<()> {
    for (what, v) in [
        ("--amplitude-deg", spec.amplitude_rad),
        ("--duration-s", spec.duration_s),
        ("--rate-hz", spec.rate_hz),
    ] {
        if !(v.is_finite() && v > 0.0) {
            crate::bail!("{what} must be a positive number, got {v}");
        }
    }
    let samples = spec.duration_s * spec.rate_hz + 1.0;
    if samples > MAX_DESIGN_SAMPLES {
        crate::bail!(
            "--duration-s {} at --rate-hz {} is {samples:.3e} samples, more than {MAX_DESIGN_SAMPLES}: shorten the record or lower the rate",
            spec.duration_s,
            spec.rate_hz
        );
    }
    check_band(spec)?;
    if spec.surfaces.is_empty() {
        crate::bail!("--surfaces: give at least one of de, da, dr");
    }
    for (i, s) in spec.surfaces.iter().enumerate() {
        if spec.surfaces[..i].contains(s) {
            crate::bail!("--surfaces: `{}` given twice", s.name());
        }
    }
    Ok(())
}

/// The orthogonal multisine samples: times and one perturbation per surface (rad).
///
/// # Errors
/// Non-positive or non-finite amplitude, duration or rate; no surface or a repeated one; a band
/// with fewer harmonics than surfaces.
pub fn multisine(spec: &DesignSpec) -> crate::error::Result<Multisines> {
    check_common(spec)?;
    let (lo, hi) = spec.band_hz;
    let harmonics = (hi - lo) * spec.duration_s;
    if harmonics > MAX_DESIGN_HARMONICS {
        crate::bail!(
            "--band-hz {lo} {hi} over --duration-s {} holds about {harmonics:.0} harmonics, more than {MAX_DESIGN_HARMONICS}: narrow the band or shorten the record",
            spec.duration_s
        );
    }
    let pool = pool(spec.duration_s, spec.band_hz);
    let n = spec.surfaces.len();
    if pool.len() < n {
        crate::bail!(
            "--band-hz {}–{} Hz holds {} harmonics of the {} s record, fewer than the {n} surfaces: lengthen the record or widen the band",
            spec.band_hz.0,
            spec.band_hz.1,
            pool.len(),
            spec.duration_s
        );
    }
    let dt = 1.0 / spec.rate_hz;
    let samples = (spec.duration_s * spec.rate_hz).round() as usize + 1;
    let t_s: Vec<f64> = (0..samples).map(|k| k as f64 * dt).collect();
    let mut inputs = Vec::with_capacity(n);
    let mut harmonics = Vec::with_capacity(n);
    for i in 0..n {
        let m = orthogonal_multisine(spec.amplitude_rad, spec.duration_s, &pool, n, i, 0.0, None)?;
        inputs.push(t_s.iter().map(|&t| m.value(t)).collect());
        harmonics.push(aeroident_signals::orthogonal::orthogonal_harmonics(&pool, n, i)?);
    }
    Ok(Multisines { t_s, inputs, harmonics })
}

/// The samples of the spec's waveform ([`multisine`] or [`chirps`]).
///
/// # Errors
/// As [`multisine`] or [`chirps`].
pub fn excitation(spec: &DesignSpec) -> crate::error::Result<Multisines> {
    match spec.signal {
        Waveform::Multisine => multisine(spec),
        Waveform::Chirp { law, fade_s } => chirps(spec, law, fade_s),
    }
}

/// One sweep per surface in turn (the surface order of the spec), each over `duration_s` from
/// the band's low to its high edge (`Waveform::Chirp`); `harmonics` are empty (a sweep has
/// none). Times run 0 … `n × duration_s`, both ends.
///
/// # Errors
/// As [`multisine`] for the amplitude, duration, rate, surfaces and band (below Nyquist,
/// sample count over the whole record); a logarithmic sweep from 0 Hz; a fade longer than half
/// the sweep, naming `--fade-s`.
pub fn chirps(spec: &DesignSpec, law: SweepLaw, fade_s: f64) -> crate::error::Result<Multisines> {
    let n = spec.surfaces.len();
    // The checks of the multisine on the whole record (every surface's sweep in turn).
    let whole = DesignSpec {
        duration_s: spec.duration_s * n.max(1) as f64,
        signal: Waveform::Multisine,
        ..spec.clone()
    };
    check_common(&whole)?;
    let (lo, hi) = spec.band_hz;
    if law == SweepLaw::Logarithmic && lo <= 0.0 {
        crate::bail!("--band-hz {lo} {hi}: a logarithmic sweep needs a low edge above 0 Hz");
    }
    if !(fade_s.is_finite() && fade_s >= 0.0 && fade_s <= 0.5 * spec.duration_s) {
        crate::bail!(
            "--fade-s {fade_s}: give 0 to half the sweep's --duration-s {} s",
            spec.duration_s
        );
    }
    let tau = std::f64::consts::TAU;
    let dt = 1.0 / spec.rate_hz;
    let samples = (whole.duration_s * spec.rate_hz).round() as usize + 1;
    let t_s: Vec<f64> = (0..samples).map(|k| k as f64 * dt).collect();
    let mut inputs = Vec::with_capacity(n);
    for i in 0..n {
        let start = i as f64 * spec.duration_s;
        let sweep =
            Sweep::new(spec.amplitude_rad, tau * lo, tau * hi, start, spec.duration_s, law, fade_s)
                .map_err(|e| crate::err!("chirp: {e}"))?;
        inputs.push(t_s.iter().map(|&t| sweep.value(t)).collect());
    }
    Ok(Multisines { t_s, inputs, harmonics: vec![Vec::new(); n] })
}

/// The structure predicted for: longitudinal for the elevator alone, lateral without it,
/// six-axis for both.
pub fn structure_for(surfaces: &[Surface]) -> ModelStructure {
    let lon = surfaces.contains(&Surface::De);
    let lat = surfaces.iter().any(|s| *s != Surface::De);
    match (lon, lat) {
        (true, false) => ModelStructure::longitudinal(),
        (false, _) => ModelStructure::lateral(),
        (true, true) => ModelStructure::six_axis(),
    }
}

/// Designs the input and predicts its Cramér–Rao σ at the F-16 trim condition.
///
/// # Errors
/// As [`multisine`]; a trim that does not converge; a prediction error (e.g. the response
/// leaves the model's domain: the amplitude is too large).
pub fn design(spec: &DesignSpec) -> crate::error::Result<Design> {
    check_condition(spec)?;
    let Multisines { t_s, inputs, harmonics } = excitation(spec)?;
    let f16m = F16::new(spec.xcg)?;
    let cond = TrimCondition {
        alt_ft: spec.alt_ft,
        vt_fps: spec.vt_fps,
        gamma_rad: 0.0,
        maneuver: TrimManeuver::WingsLevel,
    };
    let tr = trim(&f16m, &cond)?;
    let (x0, u0) = (tr.state, tr.controls);
    let (_, outs) = f16m.evaluate(&x0, &u0, &AeroIncrements::zero())?;
    let vt = x0[f16::VT] * M_PER_FT;
    let condition = FlightCondition {
        vt_mps: vt,
        alpha_rad: x0[f16::ALPHA],
        theta_rad: x0[f16::THETA],
        rho_kgpm3: 2.0 * outs.qbar_psf * PA_PER_PSF / (vt * vt),
        thrust_n: outs.thrust_lbf * N_PER_LBF,
        de_rad: u0.elevator_rad,
        da_rad: u0.aileron_rad,
        dr_rad: u0.rudder_rad,
    };
    let structure = structure_for(&spec.surfaces);
    let local =
        crate::aircraft::truth::local_derivatives(&f16m, &x0, &u0, &AeroIncrements::zero())?;
    let theta: Vec<f64> = structure
        .params()
        .map(|p| {
            local
                .truth(&structure, p)
                .ok_or_else(|| crate::err!("the F-16 gives no single true value of {}", p.name()))
        })
        .collect::<crate::error::Result<_>>()?;
    let constants = f16_constants(&f16m, vt);
    let theta = trim_biases(&structure, &theta, &constants, &condition)?;
    let plan = plan_of(spec, &inputs, structure, theta, constants, condition);
    let crb = match spec.turbulence {
        None => predict_crb(&plan)?,
        Some(sev) => {
            let p = DrydenParameters::mil_f_8785c(spec.alt_ft, sev)?;
            predict_crb_turbulent(&plan, &crate::montecarlo::dryden_gust_model(&p, spec.vt_fps))?
        }
    };
    let inputs = spec.surfaces.iter().copied().zip(inputs).collect();
    Ok(Design { t_s, inputs, harmonics, crb, structure, plan, actuation: Vec::new() })
}

/// Designs `spec`'s input (its surfaces, amplitude, duration, rate, band and waveform; its
/// F-16 condition and turbulence are not used) for `aircraft`, a model-file aircraft, trimmed
/// wings-level at `vt_mps` (m/s) and `alt_m` (m), and predicts its Cramér–Rao σ as
/// [`design`] does, with the aircraft's own structure and values restricted to the excited
/// axes (longitudinal coefficients for the elevator, lateral for aileron and rudder) and the
/// simulator's sensor noise levels ([`crate::montecarlo::crb_sensors_for`]; the σ scale with
/// the noise, so they compare designs).
///
/// # Errors
/// As [`multisine`]; turbulence asked for (not modelled for a model-file aircraft); no trim
/// at the condition; a prediction error.
pub fn design_for_aircraft<const N: usize>(
    spec: &DesignSpec,
    aircraft: &impl FlyableAircraft<N>,
    vt_mps: f64,
    alt_m: f64,
) -> crate::error::Result<Design> {
    if spec.turbulence.is_some() {
        crate::bail!(
            "--turbulence: the Dryden model is flown for the F-16 only; design in calm air"
        );
    }
    let held = aircraft.held_surfaces();
    if let Some(s) = spec.surfaces.iter().find(|s| held.contains(&crate::Named::name(**s))) {
        crate::bail!(
            "--surfaces {}: the model has no `{}` derivative, so an input on it carries no information (leave it out, or fit a model with it)",
            crate::Named::name(*s),
            crate::Named::name(*s)
        );
    }
    let Multisines { t_s, inputs, harmonics } = excitation(spec)?;
    let tr = resolvable_trim(aircraft, (vt_mps, alt_m), spec.rate_hz)?;
    let condition = aircraft.flight_condition(&tr.state, &tr.controls)?;
    let (structure, theta) = excited_part(aircraft, &tr, &spec.surfaces)?;
    let actuation = actuation_of(spec, aircraft, &tr.controls, &inputs, &harmonics);
    let mut seen = inputs.clone();
    for a in &actuation {
        let i = spec.surfaces.iter().position(|s| *s == a.surface).unwrap_or_default();
        seen[i].clone_from(&a.surface_rad);
    }
    let plan = plan_of(spec, &seen, structure, theta, aircraft.constants(), condition);
    let crb = predict_crb(&plan)?;
    let inputs = spec.surfaces.iter().copied().zip(inputs).collect();
    Ok(Design { t_s, inputs, harmonics, crb, structure, plan, actuation })
}

/// Each designed surface of `spec` with an actuator in `aircraft`'s mapping: its command in
/// `inputs` (spec order) through the actuator about the trim `controls` ([`Actuation`]).
fn actuation_of<const N: usize>(
    spec: &DesignSpec,
    aircraft: &impl FlyableAircraft<N>,
    controls: &aeroident_models::aircraft::ControlVector,
    inputs: &[Vec<f64>],
    harmonics: &[Vec<u32>],
) -> Vec<Actuation> {
    let dt = 1.0 / spec.rate_hz;
    let mut out = Vec::new();
    for (i, &surface) in spec.surfaces.iter().enumerate() {
        let k = match surface {
            Surface::De => 0,
            Surface::Da => 1,
            Surface::Dr => 2,
        };
        let Some(actuator) = aircraft.actuators()[k] else { continue };
        let command = &inputs[i];
        let r = through_actuator(&actuator, controls[1 + k], command, dt);
        let f_max = harmonics
            .get(i)
            .and_then(|h| h.last())
            .map_or(spec.band_hz.1, |&h| f64::from(h) / spec.duration_s);
        let slope = command.windows(2).fold(0f64, |m, w| m.max((w[1] - w[0]).abs() / dt));
        let (samples, steps) = (command.len().max(1) as f64, command.len().max(2) as f64 - 1.0);
        out.push(Actuation {
            surface,
            actuator,
            surface_rad: r.surface_rad,
            nominal_rate_rad_s: spec.amplitude_rad * std::f64::consts::TAU * f_max,
            peak_command_rate_rad_s: slope,
            rate_limited_fraction: r.rate_limited_steps as f64 / steps,
            position_limited_fraction: r.position_limited_samples as f64 / samples,
        });
    }
    out
}

/// RK4's stability bound on the negative real axis is |λ| dt ≈ 2.785; a margin below it.
const RK4_STABLE_LAMBDA_DT: f64 = 2.5;

/// Refuses a rate the aircraft's fastest mode outruns: the design simulates the flight at
/// the input rate (as output error fits the record), and RK4 diverges once |λ| dt passes its
/// bound. Names the mode, the least rate that resolves it, and the mode flags
/// ([`crate::airframe::modes`]) that usually explain a mode that fast.
///
/// Returns the trim the linearization was taken about (the design's flight condition).
///
/// # Errors
/// The trim or linearization's, or a mode with |λ| / rate above [`RK4_STABLE_LAMBDA_DT`].
fn resolvable_trim<const N: usize>(
    aircraft: &impl FlyableAircraft<N>,
    (vt_mps, alt_m): (f64, f64),
    rate_hz: f64,
) -> crate::error::Result<aeroident_models::aircraft::AircraftTrim<N>> {
    let l = aeroident_models::aircraft::linearize_level(aircraft, vt_mps, alt_m)?;
    let fastest = l.modes.iter().max_by(|a, b| a.wn_rad_s.total_cmp(&b.wn_rad_s));
    let Some(fastest) = fastest.filter(|m| m.wn_rad_s / rate_hz > RK4_STABLE_LAMBDA_DT) else {
        return Ok(l.trim);
    };
    let flags = crate::airframe::modes::mode_flags(aircraft, &l.trim, &l.modes);
    crate::bail!(
        "--rate-hz {rate_hz}: the {} mode (|λ| {:.1} 1/s) is faster than a simulation at that rate resolves (|λ| dt {:.1} > {RK4_STABLE_LAMBDA_DT}); design at {:.0} Hz or more{}",
        fastest.name.as_str(),
        fastest.wn_rad_s,
        fastest.wn_rad_s / rate_hz,
        (fastest.wn_rad_s / RK4_STABLE_LAMBDA_DT).ceil(),
        if flags.is_empty() {
            String::new()
        } else {
            format!(", or check the model: {}", flags.join("; "))
        }
    )
}

/// The plan of `spec`'s `inputs` (one per surface of `spec`, rad) for `structure` with values
/// `theta` on `constants` at `condition`: the simulator's sensors, initial states estimated
/// with the parameters as a fit of the record would.
fn plan_of(
    spec: &DesignSpec,
    inputs: &[Vec<f64>],
    structure: ModelStructure,
    theta: Vec<f64>,
    constants: aeroident_estimators::AircraftConstants,
    condition: FlightCondition,
) -> DesignPlan {
    let column = |s: Surface| {
        spec.surfaces.iter().position(|x| *x == s).map_or_else(Vec::new, |i| inputs[i].clone())
    };
    let planned = PlannedInputs {
        dt_s: 1.0 / spec.rate_hz,
        de_rad: column(Surface::De),
        da_rad: column(Surface::Da),
        dr_rad: column(Surface::Dr),
    };
    let sensors = crate::montecarlo::crb_sensors_for(&structure, 1.0);
    let mut plan = DesignPlan::new(structure, theta, constants, condition, vec![planned], sensors);
    plan.initial_states = InitialStates::Estimate([true; N_STATES]);
    plan
}

/// The aircraft's structure and values restricted to the axes `surfaces` excite
/// ([`structure_for`]'s choice of axes).
fn excited_part<const N: usize>(
    aircraft: &impl FlyableAircraft<N>,
    trim: &aeroident_models::aircraft::AircraftTrim<N>,
    surfaces: &[Surface],
) -> crate::error::Result<(ModelStructure, Vec<f64>)> {
    use aeroident_estimators::vocabulary::Coefficient as C;
    let lon = surfaces.contains(&Surface::De);
    let lat = surfaces.iter().any(|s| *s != Surface::De);
    let keep = |c: C| match c {
        C::CY | C::Cl | C::Cn => lat,
        _ => lon,
    };
    let (full, values) = (aircraft.flown_structure(), aircraft.flown_values(trim)?);
    let mut structure = full;
    let mut theta = Vec::new();
    for (p, v) in full.params().zip(&values) {
        if keep(p.coefficient) {
            theta.push(*v);
        } else {
            structure.remove(p);
        }
    }
    Ok((structure, theta))
}

/// The fastest `--vt-fps` designed for, ft/s.
const DESIGN_MAX_VT_FPS: f64 = 2600.0;

/// Checks the flight condition is within the F-16 model's range before trimming (a trim
/// outside it fails without saying why).
fn check_condition(spec: &DesignSpec) -> crate::error::Result<()> {
    let (lo, hi) = DESIGN_ALT_RANGE_FT;
    let short = aeroident_io::message::exact_or_short;
    if !(spec.alt_ft.is_finite() && (lo..=hi).contains(&spec.alt_ft)) {
        crate::bail!(
            "--alt-ft {}: the F-16 model's altitudes are {lo}–{hi} ft (its engine's thrust tables)",
            short(spec.alt_ft)
        );
    }
    if !(spec.vt_fps.is_finite() && spec.vt_fps > 0.0 && spec.vt_fps <= DESIGN_MAX_VT_FPS) {
        crate::bail!(
            "--vt-fps {}: give a true airspeed above 0 and at most {DESIGN_MAX_VT_FPS} ft/s (Mach 2.7 in the stratosphere, beyond the F-16 model's low-speed tables)",
            short(spec.vt_fps)
        );
    }
    Ok(())
}

/// The CSV table: `t_s`, then per surface `<s>_rad` and `<s>_deg`.
pub fn csv_table(d: &Design) -> String {
    let mut out = String::from("t_s");
    for (s, _) in &d.inputs {
        out.push_str(&format!(",{0}_rad,{0}_deg", s.name()));
    }
    out.push('\n');
    for (k, t) in d.t_s.iter().enumerate() {
        out.push_str(&format!("{t}"));
        for (_, v) in &d.inputs {
            out.push_str(&format!(",{},{}", v[k], v[k].to_degrees()));
        }
        out.push('\n');
    }
    out
}

/// A deflection in integer centidegrees (rounded): the unit of the injection table.
pub fn centidegrees(rad: f64) -> i64 {
    (rad.to_degrees() * 100.0).round() as i64
}

/// The autopilot injection table: `t_ms` (integer ms from the start of the manoeuvre) and, per
/// surface, `<s>_cdeg`: the offset from the trim deflection in integer centidegrees
/// ([`centidegrees`]), in aeroident's sign convention ([`Surface`]).
pub fn injection_table(d: &Design) -> String {
    let mut out = String::from("t_ms");
    for (s, _) in &d.inputs {
        out.push_str(&format!(",{}_cdeg", s.name()));
    }
    out.push('\n');
    for (k, t) in d.t_s.iter().enumerate() {
        out.push_str(&format!("{}", (t * 1000.0).round() as i64));
        for (_, v) in &d.inputs {
            out.push_str(&format!(",{}", centidegrees(v[k])));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::output_error::design::simulate_plan;
    use aeroident_estimators::output_error::{OeConfig, Start, fit};
    use rand::{Rng, SeedableRng};

    fn spec(surfaces: Vec<Surface>) -> DesignSpec {
        DesignSpec {
            surfaces,
            amplitude_rad: 1f64.to_radians(),
            duration_s: 10.0,
            rate_hz: 50.0,
            band_hz: (0.1, 1.5),
            alt_ft: 20000.0,
            vt_fps: 675.0,
            xcg: 0.3,
            turbulence: None,
            signal: Waveform::Multisine,
        }
    }

    /// [`through_actuator`] of a 0.105 rad step command with a vanishing τ (1e-9 s): the
    /// surface starts at trim, reaches each command one sample later, and a 1 rad/s limit at
    /// 100 Hz lets it move 0.01 rad a sample, so it ramps 0.01 … 0.10 over 10 limited intervals
    /// and then takes the last 0.005; with a position limit at 0.075 it stops there from
    /// sample 8 (0-based) on: the 7 intervals before are rate-limited, the rest held by the
    /// position limit, not the rate's.
    #[test]
    fn analytic_a_step_through_a_rate_limited_actuator_ramps_at_the_limit() {
        let act = aeroident_io::mapping::Actuator {
            tau_s: 1e-9,
            rate_limit_rad_s: 1.0,
            position_limits_rad: (-1.0, 1.0),
        };
        let step = vec![0.105; 15];
        let r = through_actuator(&act, 0.0, &step, 0.01);
        for (k, v) in r.surface_rad.iter().enumerate() {
            let expected = (0.01 * k as f64).min(0.105);
            assert!((v - expected).abs() < 1e-12, "sample {k}: {v} against {expected}");
        }
        assert_eq!((r.rate_limited_steps, r.position_limited_samples), (10, 0));
        let pinned = aeroident_io::mapping::Actuator { position_limits_rad: (-1.0, 0.075), ..act };
        let r = through_actuator(&pinned, 0.0, &step, 0.01);
        assert_eq!((r.rate_limited_steps, r.position_limited_samples), (7, 7));
        assert_eq!(r.surface_rad[14], 0.075);
    }

    /// `--turbulence`: the record flown in moderate Dryden turbulence has a different bound
    /// (the gusts are noise and excitation), finite for every parameter the calm plan
    /// identifies.
    #[test]
    fn turbulence_changes_the_bound() {
        let calm = design(&spec(vec![Surface::De, Surface::Da, Surface::Dr])).unwrap();
        let turb = design(&DesignSpec {
            turbulence: Some(TurbulenceSeverity::Moderate),
            ..spec(vec![Surface::De, Surface::Da, Surface::Dr])
        })
        .unwrap();
        let (a, b) = (&calm.crb, &turb.crb);
        assert_eq!(a.names, b.names);
        let mut changed = 0;
        for i in 0..a.n_params {
            if let Some(sa) = a.sigma[i] {
                let sb = b.sigma[i].expect("identifiable in turbulence too");
                assert!(sb.is_finite() && sb > 0.0);
                changed += usize::from((sb / sa - 1.0).abs() > 0.05);
            }
        }
        assert!(changed * 2 > a.n_params, "{changed} of {} changed", a.n_params);
    }

    /// Bands reaching the Nyquist frequency, sample counts that would exhaust memory and flight
    /// conditions outside the model are refused before anything is allocated or trimmed, each
    /// naming its option.
    #[test]
    fn out_of_range_designs_are_refused_naming_the_option() {
        let all = || spec(vec![Surface::De, Surface::Da, Surface::Dr]);
        let cases: Vec<(DesignSpec, &[&str])> = vec![
            (DesignSpec { band_hz: (0.1, 100.0), ..all() }, &["--band-hz", "Nyquist", "25 Hz"]),
            (DesignSpec { band_hz: (0.1, 25.0), ..all() }, &["--band-hz", "Nyquist"]),
            (DesignSpec { band_hz: (-1.0, 5.0), ..all() }, &["--band-hz", "0 ≤ low < high"]),
            (DesignSpec { band_hz: (2.0, 1.0), ..all() }, &["--band-hz"]),
            (DesignSpec { rate_hz: 1e9, ..all() }, &["--rate-hz", "samples", "100000"]),
            (DesignSpec { duration_s: 1e9, ..all() }, &["--duration-s", "samples"]),
            (
                DesignSpec { duration_s: 1000.0, band_hz: (0.1, 24.0), ..all() },
                &["--band-hz", "harmonics"],
            ),
            (DesignSpec { alt_ft: 1e6, ..all() }, &["--alt-ft", "50000"]),
            (DesignSpec { alt_ft: -100.0, ..all() }, &["--alt-ft"]),
            (DesignSpec { alt_ft: f64::NAN, ..all() }, &["--alt-ft"]),
            (DesignSpec { vt_fps: 0.0, ..all() }, &["--vt-fps"]),
        ];
        for (s, needles) in cases {
            let e = design(&s).unwrap_err().to_string();
            for n in needles {
                assert!(e.contains(n), "{n:?} not in: {e}");
            }
        }
        // Just below the Nyquist frequency is a valid design: harmonics k = 1 … 24 of 1 Hz.
        let m = multisine(&DesignSpec { duration_s: 1.0, band_hz: (0.1, 24.9), ..all() }).unwrap();
        assert_eq!(m.harmonics.iter().map(Vec::len).sum::<usize>(), 24, "k = 1 … 24");
    }

    #[test]
    fn members_are_orthogonal_over_the_record_and_peak_at_the_amplitude() {
        let Multisines { t_s: t, inputs: u, harmonics: h } =
            multisine(&spec(vec![Surface::De, Surface::Da, Surface::Dr])).unwrap();
        assert_eq!(t.len(), 501);
        assert_eq!(h, vec![vec![1, 4, 7, 10, 13], vec![2, 5, 8, 11, 14], vec![3, 6, 9, 12, 15]]);
        let n = t.len() - 1; // one period: the last sample repeats the first
        for i in 0..3 {
            let peak = u[i].iter().fold(0f64, |a, v| a.max(v.abs()));
            assert!((peak - 1f64.to_radians()).abs() < 0.02 * 1f64.to_radians(), "peak {peak}");
            assert!(u[i][0].abs() < 1e-12 && u[i][n].abs() < 1e-9, "starts and ends at 0");
            for j in 0..i {
                let dot: f64 = (0..n).map(|k| u[i][k] * u[j][k]).sum();
                let norm: f64 = (0..n).map(|k| u[i][k] * u[i][k]).sum();
                assert!(dot.abs() < 1e-9 * norm, "members {i}, {j}: {dot} vs {norm}");
            }
        }
        let e = multisine(&DesignSpec { duration_s: 1.0, ..spec(vec![Surface::De, Surface::Da]) })
            .unwrap_err();
        assert!(e.to_string().contains("fewer than the 2 surfaces"), "{e}");
    }

    /// The predicted σ against the scatter of output-error fits to 40 noisy simulations of the
    /// planned record (the model's own response, white noise of the planned σ). With 40 draws the
    /// sample σ has a relative standard error of ≈ 11 %: the ratio must lie in 0.6–1.5.
    #[test]
    fn predicted_crb_matches_the_monte_carlo_scatter() {
        let d = design(&spec(vec![Surface::De])).unwrap();
        let plan = &d.plan;
        let np = plan.structure.n_params();
        let sigmas: Vec<f64> = plan.sensors.iter().map(|s| s.sigma).collect();
        let mut config = OeConfig::new(plan.structure);
        config.outputs = Some(plan.sensors.iter().map(|s| s.output).collect());
        config.initial_states = plan.initial_states;
        config.start = Start::Given(plan.theta.clone());
        let seeds = 40;
        let mut est: Vec<Vec<f64>> = Vec::new();
        for seed in 0..seeds {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(7000 + seed);
            // Box–Muller standard normal draws.
            let mut noise = |j: usize| {
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                sigmas[j] * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            };
            let data = simulate_plan(plan, &mut noise).unwrap();
            let res = fit(&[&data[0]], &config).unwrap();
            est.push(res.values[..np].to_vec());
        }
        let k = seeds as f64;
        let mut ratios = Vec::new();
        for (i, name) in plan.structure.names().enumerate() {
            let mean = est.iter().map(|e| e[i]).sum::<f64>() / k;
            let scatter =
                (est.iter().map(|e| (e[i] - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
            let crb = d.crb.sigma[i].unwrap();
            let ratio = scatter / crb;
            println!(
                "{name:>9} θ {:10.4} σ_CRB {crb:.3e} scatter {scatter:.3e} ratio {ratio:.3}",
                plan.theta[i]
            );
            ratios.push((name, ratio));
        }
        for (name, ratio) in ratios {
            assert!((0.6..=1.5).contains(&ratio), "{name}: scatter / σ_CRB = {ratio}");
        }
    }

    /// Chirps: each surface sweeps in turn; its samples are `A w(τ) sin θ(τ)` with the phase
    /// written here from its definition (`θ = 2π(f₀τ + (f₁ − f₀)τ²/(2T))` linear,
    /// `2π f₀ T (r^{τ/T} − 1)/ln r`, `r = f₁/f₀`, logarithmic) and the raised-cosine fade; the
    /// other surfaces are 0 meanwhile. Bands above Nyquist and fades over half the sweep are
    /// refused by name.
    #[test]
    fn analytic_chirps_follow_the_sweep_law_one_surface_after_another() {
        let (f0, f1, t, a, fade) = (0.2, 3.0, 20.0, 2f64.to_radians(), 2.0);
        for law in [SweepLaw::Linear, SweepLaw::Logarithmic] {
            let sp = DesignSpec {
                band_hz: (f0, f1),
                duration_s: t,
                amplitude_rad: a,
                signal: Waveform::Chirp { law, fade_s: fade },
                ..spec(vec![Surface::De, Surface::Dr])
            };
            let m = excitation(&sp).unwrap();
            assert_eq!(m.t_s.len(), (2.0 * t * 50.0) as usize + 1);
            assert!((m.t_s.last().unwrap() - 2.0 * t).abs() < 1e-9);
            for (k, &time) in m.t_s.iter().enumerate() {
                let (active, idle) = if time < t { (0, 1) } else { (1, 0) };
                let tau = if time < t { time } else { time - t };
                let theta = match law {
                    SweepLaw::Linear => {
                        std::f64::consts::TAU * (f0 * tau + (f1 - f0) * tau * tau / (2.0 * t))
                    }
                    SweepLaw::Logarithmic => {
                        let r: f64 = f1 / f0;
                        std::f64::consts::TAU * f0 * t * (r.powf(tau / t) - 1.0) / r.ln()
                    }
                };
                let edge = tau.min(t - tau);
                let w = if edge < fade {
                    0.5 * (1.0 - (std::f64::consts::PI * edge / fade).cos())
                } else {
                    1.0
                };
                let expected = if time >= 2.0 * t { 0.0 } else { a * w * theta.sin() };
                assert!((m.inputs[active][k] - expected).abs() < 1e-9, "{law:?} t {time}");
                assert_eq!(m.inputs[idle][k], 0.0, "{law:?} t {time}: the other surface rests");
            }
        }
        let chirp = |band_hz, fade_s| DesignSpec {
            band_hz,
            signal: Waveform::Chirp { law: SweepLaw::Logarithmic, fade_s },
            ..spec(vec![Surface::De])
        };
        for (sp, words) in [
            (chirp((0.1, 30.0), 1.0), &["--band-hz", "Nyquist"][..]),
            (chirp((0.0, 3.0), 1.0), &["--band-hz", "logarithmic", "above 0"][..]),
            (chirp((0.1, 3.0), 6.0), &["--fade-s", "half"][..]),
        ] {
            let e = excitation(&sp).unwrap_err().to_string();
            for w in words {
                assert!(e.contains(w), "{e}");
            }
        }
    }
}
