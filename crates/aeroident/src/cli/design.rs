//! `aeroident design`: an orthogonal multisine (or one chirp per surface in turn) for chosen
//! surfaces and its predicted Cramér–Rao σ at an F-16 flight condition (docs/export.md).
//!
//! ```text
//! aeroident design --surfaces de,da,dr --amplitude-deg 2 --duration-s 10 --rate-hz 50
//!                  [--band-hz 0.1,1.5] [--alt-ft 20000 --vt-fps 675 --xcg 0.35]
//!                  [--turbulence light|moderate|severe]
//!                  [--signal multisine|chirp [--sweep logarithmic|linear] [--fade-s 1]] --out DIR
//!                  [--throw-deg de=25,da=20,dr=25 [--arm-rc 7]]
//! ```
//! Writes `DIR/input.csv` (t_s, per surface rad and deg), `DIR/injection.csv` (the autopilot
//! table: t_ms and per surface the offset from trim in centidegrees) and `DIR/design.json`
//! (harmonics, condition, predicted σ), and prints σ, σ/|θ| and the response excursions. With
//! `--throw-deg`, also the autopilot forms of the table: `DIR/ardupilot_sysid.lua` (an
//! ArduPlane script) and `DIR/px4_torque.csv` (normalised torque offsets for a PX4 offboard
//! node), both made and checked against the throws by
//! `aeroident_pipelines::export::autopilot`.

use crate::outdir::OutputDir;
use aeroident_pipelines::export::autopilot::{
    AutopilotOptions, Start, ardupilot_lua, px4_torque_table,
};
use aeroident_pipelines::export::design::{
    Design, DesignSpec, Surface, Waveform, actuator_limit_flags, csv_table, design,
    injection_table, large_excursions,
};
use aeroident_signals::inputs::SweepLaw;
use aeroident_signals::turbulence::TurbulenceSeverity;
use std::path::PathBuf;

/// Arguments of `aeroident design`.
#[derive(Debug, clap::Args)]
pub struct DesignArgs {
    /// Surfaces to excite, each with one member of the orthogonal set.
    #[arg(long, value_parser = super::named::<Surface>(), value_delimiter = ',', default_value = "de,da,dr")]
    pub surfaces: Vec<Surface>,
    /// Peak amplitude of each surface's perturbation about trim, degrees.
    #[arg(long, default_value_t = 2.0)]
    pub amplitude_deg: f64,
    /// Record length (the multisine's base period), s.
    #[arg(long, default_value_t = 10.0)]
    pub duration_s: f64,
    /// Sample rate of the tables, Hz.
    #[arg(long, default_value_t = 50.0)]
    pub rate_hz: f64,
    /// Frequency band of the harmonics, Hz: two values, `lo,hi` or `lo hi` (below Nyquist).
    #[arg(long, value_delimiter = ',', num_args = 1..=2, default_values_t = [0.1, 1.5])]
    pub band_hz: Vec<f64>,
    /// Flight condition: trim altitude, ft (F-16, wings level).
    #[arg(long, default_value_t = 20000.0)]
    pub alt_ft: f64,
    /// Flight condition: trim true airspeed, ft/s.
    #[arg(long, default_value_t = 675.0)]
    pub vt_fps: f64,
    /// Centre of gravity, fraction of the mean chord.
    #[arg(long, default_value_t = 0.3)]
    pub xcg: f64,
    /// Fly the record in Dryden turbulence of this MIL-F-8785C severity at the trim altitude:
    /// the bound counts the gusts as process noise (docs/uncertainty.md, "Cramér–Rao bound
    /// with turbulence"); default calm air, white sensor noise only.
    #[arg(long, value_enum)]
    pub turbulence: Option<Turbulence>,
    /// The waveform: orthogonal multisines on every surface at once, or a constant-amplitude
    /// sweep across the band on each surface in turn (`--duration-s` per sweep).
    #[arg(long, value_enum, default_value_t = Signal::Multisine)]
    pub signal: Signal,
    /// The chirp's frequency law: logarithmic (equal time per octave, more time at the low
    /// frequencies of the rigid-body modes) or linear.
    #[arg(long, value_enum, default_value_t = SweepKind::Logarithmic)]
    pub sweep: SweepKind,
    /// The chirp's raised-cosine fade-in and fade-out, s (at most half a sweep).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub fade_s: f64,
    /// Output directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The aircraft: `f16` (the Stevens & Lewis F-16 at `--alt-ft`, `--vt-fps`, `--xcg`), or a
    /// model file (`models/*.toml`) whose derivatives a model-file aircraft flies, with
    /// `--summary`, `--map`, `--vt-mps`, `--alt-m` (docs/aircraft.md).
    #[arg(long, default_value = "f16")]
    pub aircraft: String,
    /// Model-file aircraft: a replay's `summary.json` whose estimates are the values (default:
    /// the model file's `[reference.<param>]` values).
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// Model-file aircraft: the mapping whose constants give mass, inertia, geometry, thrust.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Model-file aircraft: trim true airspeed, m/s.
    #[arg(long)]
    pub vt_mps: Option<f64>,
    /// Model-file aircraft: trim altitude, m.
    #[arg(long, allow_negative_numbers = true)]
    pub alt_m: Option<f64>,
    /// Full throw of each designed surface, degrees (the deflection at a full servo command):
    /// `de=25,da=20,dr=25`. With it, also writes the autopilot forms (`ardupilot_sysid.lua`,
    /// `px4_torque.csv`), refusing a design that moves a surface beyond its throw.
    #[arg(long, value_delimiter = ',', value_parser = parse_throw, allow_negative_numbers = true)]
    pub throw_deg: Vec<(Surface, f64)>,
    /// RC input channel (1–16) whose switch starts (high) and stops (low) the ArduPlane
    /// script; default: the parameter `SCR_USER1` (1 starts, 0 stops).
    #[arg(long)]
    pub arm_rc: Option<u8>,
}

/// One `--throw-deg` entry, `<surface>=<degrees>`.
fn parse_throw(text: &str) -> Result<(Surface, f64), String> {
    use aeroident_pipelines::Named as _;
    let (name, deg) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: give <surface>=<degrees>, e.g. de=25"))?;
    let s = Surface::from_name(name.trim())
        .ok_or_else(|| format!("`{name}`: not a surface (de, da, dr)"))?;
    let deg = deg.trim().parse::<f64>().map_err(|e| format!("`{deg}`: {e}"))?;
    // Radians typed as degrees would lie below the bound: that slip is not caught here.
    use aeroident_pipelines::export::uav::MAX_THROW_DEG;
    if !(deg > 0.0 && deg <= MAX_THROW_DEG) {
        return Err(format!("`{text}`: a throw is > 0 and at most {MAX_THROW_DEG}°"));
    }
    Ok((s, deg))
}

/// `--signal` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Signal {
    /// Orthogonal phase-optimised multisines.
    Multisine,
    /// One frequency sweep per surface, in turn.
    Chirp,
}

/// `--sweep` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepKind {
    /// Equal time per octave.
    Logarithmic,
    /// Frequency linear in time.
    Linear,
}

impl DesignArgs {
    fn waveform(&self) -> Waveform {
        match self.signal {
            Signal::Multisine => Waveform::Multisine,
            Signal::Chirp => Waveform::Chirp {
                law: match self.sweep {
                    SweepKind::Logarithmic => SweepLaw::Logarithmic,
                    SweepKind::Linear => SweepLaw::Linear,
                },
                fade_s: self.fade_s,
            },
        }
    }

    fn signal_name(&self) -> &'static str {
        match (self.signal, self.sweep) {
            (Signal::Multisine, _) => "multisine",
            (Signal::Chirp, SweepKind::Logarithmic) => "chirp (logarithmic)",
            (Signal::Chirp, SweepKind::Linear) => "chirp (linear)",
        }
    }
}

/// `--turbulence` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Turbulence {
    /// Probability of exceedance 10⁻².
    Light,
    /// 10⁻³.
    Moderate,
    /// 10⁻⁵.
    Severe,
}

impl Turbulence {
    fn severity(self) -> TurbulenceSeverity {
        match self {
            Turbulence::Light => TurbulenceSeverity::Light,
            Turbulence::Moderate => TurbulenceSeverity::Moderate,
            Turbulence::Severe => TurbulenceSeverity::Severe,
        }
    }
}

/// Runs `aeroident design`.
///
/// # Errors
/// Invalid options (naming the option), a trim that does not converge, a prediction that fails
/// (e.g. the response leaves the model's domain), or an output error naming the file.
pub fn execute(a: DesignArgs) -> anyhow::Result<()> {
    // `lo,hi` arrives as one argument split in two, `lo hi` as two.
    if a.band_hz.len() != 2 {
        anyhow::bail!("--band-hz: give two frequencies, low and high, Hz (`0.1,1.5` or `0.1 1.5`)");
    }
    check_aircraft_options(&a)?;
    let spec = DesignSpec {
        surfaces: a.surfaces.clone(),
        amplitude_rad: a.amplitude_deg.to_radians(),
        duration_s: a.duration_s,
        rate_hz: a.rate_hz,
        band_hz: (a.band_hz[0], a.band_hz[1]),
        alt_ft: a.alt_ft,
        vt_fps: a.vt_fps,
        xcg: a.xcg,
        turbulence: a.turbulence.map(Turbulence::severity),
        signal: a.waveform(),
    };
    let mut out = a.out.as_deref().map(|d| OutputDir::open(d, "design", &[])).transpose()?;
    let d = match a.aircraft.as_str() {
        "f16" => design(&spec)?,
        model => model_file_design(&a, &spec, model)?,
    };
    crate::cli::print_stdout(&report(&a, &d))?;
    let large = large_excursions(&d);
    if !large.is_empty() {
        aeroident_report::note!(
            "warning: the open-loop response is not a small perturbation ({}): the bound assumes the derivatives hold over it; reduce --amplitude-deg or --duration-s, or fly it with the stability augmentation on",
            large.join(", ")
        );
    }
    for f in actuator_limit_flags(&d) {
        aeroident_report::note!("warning: {f}");
    }
    let forms = autopilot_forms(&a, &d)?;
    if let Some(o) = out.as_mut() {
        o.write_bytes("input.csv", csv_table(&d).as_bytes())?;
        o.write_bytes("injection.csv", injection_table(&d).as_bytes())?;
        o.write_bytes("design.json", serde_json::to_string_pretty(&json(&a, &d))?.as_bytes())?;
        let mut names = vec!["input.csv", "injection.csv", "design.json"];
        for (name, text) in &forms {
            o.write_bytes(name, text.as_bytes())?;
            names.push(name);
        }
        o.finish();
        aeroident_report::note!("wrote {} to {}", names.join(", "), o.path().display());
    }
    Ok(())
}

/// The autopilot forms (file name, text) when `--throw-deg` is given, made and checked by the
/// library; none without it.
fn autopilot_forms(a: &DesignArgs, d: &Design) -> anyhow::Result<Vec<(&'static str, String)>> {
    if a.throw_deg.is_empty() {
        if a.arm_rc.is_some() {
            anyhow::bail!("--arm-rc: give --throw-deg too (the script needs the surfaces' throws)");
        }
        return Ok(Vec::new());
    }
    let o = AutopilotOptions {
        throws: a.throw_deg.iter().map(|(s, deg)| (*s, deg.to_radians())).collect(),
        start: a.arm_rc.map_or(Start::ScrUser1, Start::RcChannel),
    };
    Ok(vec![
        ("ardupilot_sysid.lua", ardupilot_lua(d, &o)?),
        ("px4_torque.csv", px4_torque_table(d, &o)?),
    ])
}

/// Refuses, before any work, what would be silently resolved: a surface given twice in
/// `--throw-deg`, and a model-file aircraft's options (`--summary`, `--map`, `--vt-mps`,
/// `--alt-m`) beside the F-16, which would be designed at its own condition instead.
fn check_aircraft_options(a: &DesignArgs) -> anyhow::Result<()> {
    for (k, (surface, deg)) in a.throw_deg.iter().enumerate() {
        if let Some((_, first)) = a.throw_deg[..k].iter().find(|(s, _)| s == surface) {
            anyhow::bail!(
                "--throw-deg gives {} twice ({first}° and {deg}°): give each surface once",
                surface.name()
            );
        }
    }
    if a.aircraft == "f16" {
        let given: Vec<&str> = [
            ("--summary", a.summary.is_some()),
            ("--map", a.map.is_some()),
            ("--vt-mps", a.vt_mps.is_some()),
            ("--alt-m", a.alt_m.is_some()),
        ]
        .into_iter()
        .filter_map(|(o, g)| g.then_some(o))
        .collect();
        if !given.is_empty() {
            anyhow::bail!(
                "{} describe a model-file aircraft (--aircraft MODEL.toml); the F-16 (the default --aircraft) is set by --alt-ft, --vt-fps and --xcg",
                given.join(", ")
            );
        }
    }
    Ok(())
}

/// The design for a model-file aircraft (`--aircraft MODEL.toml`): its options checked, the
/// aircraft loaded, the library's design run.
fn model_file_design(a: &DesignArgs, spec: &DesignSpec, model: &str) -> anyhow::Result<Design> {
    let (Some(map), Some(vt), Some(alt)) = (&a.map, a.vt_mps, a.alt_m) else {
        anyhow::bail!(
            "--aircraft {model}: give --map (the constants), --vt-mps and --alt-m (the trim)"
        );
    };
    let aircraft = aeroident_pipelines::airframe::load(model.as_ref(), a.summary.as_deref(), map)?;
    super::aircraft_args::note_held_surfaces(&aircraft);
    super::aircraft_args::warn_unfinished(a.summary.as_deref())?;
    Ok(aeroident_pipelines::export::design::design_for_aircraft(spec, &aircraft, vt, alt)?)
}

/// The flight condition in words.
fn condition_text(a: &DesignArgs) -> String {
    match (a.aircraft.as_str(), a.vt_mps, a.alt_m) {
        ("f16", ..) => {
            format!("F-16 trimmed wings level at {} ft, {} ft/s, xcg {}", a.alt_ft, a.vt_fps, a.xcg)
        }
        (m, Some(v), Some(h)) => format!("{m} trimmed wings level at {h} m, {v} m/s"),
        (m, ..) => m.to_string(),
    }
}

fn report(a: &DesignArgs, d: &Design) -> String {
    let r = &d.crb;
    let waveform = match a.signal {
        Signal::Multisine => format!(
            "harmonics (k/{} Hz): {}",
            a.duration_s,
            d.inputs
                .iter()
                .zip(&d.harmonics)
                .map(|((s, _), h)| format!("{} {:?}", s.name(), h))
                .collect::<Vec<_>>()
                .join("; ")
        ),
        Signal::Chirp => {
            format!("{}–{} Hz per surface in turn, fade {} s", a.band_hz[0], a.band_hz[1], a.fade_s)
        }
    };
    let mut s = format!(
        "{}: {} at ±{}°, {} s, {} Hz; {waveform}\n\
         condition: {}; model {}\n\
         predicted Cramér–Rao σ (white sensor noise at the simulator's levels{}, one record):\n",
        a.signal_name(),
        a.surfaces.iter().map(|s| s.name()).collect::<Vec<_>>().join(","),
        a.amplitude_deg,
        a.duration_s,
        a.rate_hz,
        condition_text(a),
        model_name(d),
        a.turbulence.map_or(String::new(), |t| format!(
            " and {} Dryden turbulence as process noise",
            turbulence_name(t)
        )),
    );
    s.push_str(&format!(
        "  {:<12} {:>12} {:>12} {:>9}\n",
        "parameter", "assumed θ", "σ_CRB", "σ/|θ| %"
    ));
    for i in 0..r.n_params {
        let sigma = r.sigma[i].map_or("not identifiable".to_string(), |x| format!("{x:.4e}"));
        // σ/|θ| only where θ is not ~0 (a trimmed bias of a symmetric aircraft is 1e-26).
        let rel = r.relative_sigma[i]
            .filter(|_| r.values[i].abs() > 1e-9)
            .map_or("—".to_string(), |x| format!("{:.2}", 100.0 * x));
        s.push_str(&format!(
            "  {:<12} {:>12.4e} {:>12} {:>9}\n",
            r.names[i], r.values[i], sigma, rel
        ));
    }
    s.push_str(&actuation_text(d));
    s.push_str(&format!("condition number {:.3e}", r.condition_number));
    for (o, e) in r.outputs.iter().zip(&r.output_excursion) {
        s.push_str(&format!("; peak |Δ{o:?}| {e:.3e}"));
    }
    s
}

/// The lines saying the prediction is through the mapping's actuators (the table is the
/// servo command) with each τ and limit, and the flags of the limits the design reaches
/// ([`actuator_limit_flags`]); empty without actuators.
fn actuation_text(d: &Design) -> String {
    if d.actuation.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "prediction through the mapping's actuators (the table is the servo command; the σ are of the deflection the surface makes of it):\n",
    );
    for a in &d.actuation {
        s.push_str(&format!(
            "  {} tau {} s, rate limit {}, command slope up to {:.3} rad/s (amplitude × 2π f_max {:.3}), rate-limited {:.1} % of the samples\n",
            a.surface.name(),
            a.actuator.tau_s,
            finite_or_none(a.actuator.rate_limit_rad_s).map_or("none".into(), |v| format!("{v} rad/s")),
            a.peak_command_rate_rad_s,
            a.nominal_rate_rad_s,
            100.0 * a.rate_limited_fraction
        ));
    }
    for f in actuator_limit_flags(d) {
        s.push_str(&format!("flag: {f}\n"));
    }
    s
}

/// `v` when finite (JSON has no infinity: an unlimited actuator's limit is `null`).
fn finite_or_none(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The `actuators` entry of `design.json`: per actuated surface its τ, limits, command
/// rates and the fractions of the samples limited, and the flags (written only for a design
/// with actuators, so one without reads as before).
fn actuation_json(d: &Design) -> serde_json::Value {
    let surfaces = d.actuation.iter().map(|a| {
        let (lo, hi) = a.actuator.position_limits_rad;
        serde_json::json!({
            "surface": a.surface.name(),
            "tau_s": a.actuator.tau_s,
            "rate_limit_rad_s": finite_or_none(a.actuator.rate_limit_rad_s),
            "position_limits_rad": [finite_or_none(lo), finite_or_none(hi)],
            "nominal_rate_rad_s": a.nominal_rate_rad_s,
            "peak_command_rate_rad_s": a.peak_command_rate_rad_s,
            "rate_limited_fraction": a.rate_limited_fraction,
            "position_limited_fraction": a.position_limited_fraction,
        })
    });
    serde_json::json!({
        "prediction": "through the actuators: the table is the servo command, the prediction uses the deflection",
        "surfaces": surfaces.collect::<Vec<_>>(),
        "flags": actuator_limit_flags(d),
    })
}

fn turbulence_name(t: Turbulence) -> &'static str {
    match t {
        Turbulence::Light => "light",
        Turbulence::Moderate => "moderate",
        Turbulence::Severe => "severe",
    }
}

/// The axes the design's model holds: a model-file aircraft's own terms restricted to the
/// excited axes are no preset, so the name is read from its coefficients.
fn model_name(d: &Design) -> &'static str {
    use aeroident_estimators::vocabulary::Coefficient as C;
    let has = |cs: &[C]| d.structure.params().any(|p| cs.contains(&p.coefficient));
    match (has(&[C::CL, C::CD, C::CX, C::CZ, C::Cm]), has(&[C::CY, C::Cl, C::Cn])) {
        (true, true) => "six-axis",
        (false, true) => "lateral",
        _ => "longitudinal",
    }
}

fn json(a: &DesignArgs, d: &Design) -> serde_json::Value {
    let r = &d.crb;
    let mut v = serde_json::json!({
        "signal": a.signal_name(),
        "fade_s": (a.signal == Signal::Chirp).then_some(a.fade_s),
        "surfaces": a.surfaces.iter().map(|s| s.name()).collect::<Vec<_>>(),
        "amplitude_deg": a.amplitude_deg,
        "duration_s": a.duration_s,
        "rate_hz": a.rate_hz,
        "band_hz": a.band_hz,
        "harmonics": d.harmonics,
        "condition": if a.aircraft == "f16" {
            serde_json::json!({"aircraft": "F-16 (Stevens & Lewis)", "alt_ft": a.alt_ft, "vt_fps": a.vt_fps, "xcg": a.xcg})
        } else {
            serde_json::json!({"aircraft": a.aircraft, "summary": a.summary, "map": a.map, "alt_m": a.alt_m, "vt_mps": a.vt_mps})
        },
        "model": model_name(d),
        "turbulence": a.turbulence.map(turbulence_name),
        "condition_number": if r.condition_number.is_finite() { Some(r.condition_number) } else { None },
        "parameters": (0..r.n_params).map(|i| serde_json::json!({
            "name": r.names[i],
            "assumed": r.values[i],
            "crb_sigma": r.sigma[i],
            "relative_crb_sigma": r.relative_sigma[i],
        })).collect::<Vec<_>>(),
    });
    if !d.actuation.is_empty() {
        v["actuators"] = actuation_json(d);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model-file aircraft without its mapping or trim is refused naming the options, before
    /// any file is read.
    #[test]
    fn errors_a_model_file_aircraft_needs_its_mapping_and_trim() {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Wrap {
            #[command(flatten)]
            args: DesignArgs,
        }
        let a = Wrap::try_parse_from(["design", "--aircraft", "models/x.toml", "--vt-mps", "16"]);
        let a = a.unwrap().args;
        let spec = DesignSpec {
            surfaces: vec![Surface::De],
            amplitude_rad: 0.01,
            duration_s: 10.0,
            rate_hz: 50.0,
            band_hz: (0.1, 1.5),
            alt_ft: 0.0,
            vt_fps: 0.0,
            xcg: 0.3,
            turbulence: None,
            signal: Waveform::Multisine,
        };
        let e = model_file_design(&a, &spec, "models/x.toml").unwrap_err().to_string();
        assert!(e.contains("--map") && e.contains("--alt-m"), "{e}");
    }

    #[test]
    fn writes_the_tables_and_the_prediction() {
        let dir = std::env::temp_dir().join(format!("aeroident-design-cli-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let args = DesignArgs {
            surfaces: vec![Surface::De, Surface::Da],
            amplitude_deg: 1.0,
            duration_s: 8.0,
            rate_hz: 25.0,
            band_hz: vec![0.1, 1.5],
            alt_ft: 20000.0,
            vt_fps: 675.0,
            xcg: 0.3,
            turbulence: None,
            signal: Signal::Multisine,
            sweep: SweepKind::Logarithmic,
            fade_s: 1.0,
            out: Some(dir.clone()),
            aircraft: "f16".into(),
            summary: None,
            map: None,
            vt_mps: None,
            alt_m: None,
            throw_deg: Vec::new(),
            arm_rc: None,
        };
        execute(args).unwrap();
        let input = std::fs::read_to_string(dir.join("input.csv")).unwrap();
        let inj = std::fs::read_to_string(dir.join("injection.csv")).unwrap();
        let lines: Vec<&str> = input.lines().collect();
        assert_eq!(lines[0], "t_s,de_rad,de_deg,da_rad,da_deg");
        assert_eq!(lines.len(), 1 + 201);
        let inj_lines: Vec<&str> = inj.lines().collect();
        assert_eq!(inj_lines[0], "t_ms,de_cdeg,da_cdeg");
        // The injection table is the input table in ms and rounded centidegrees.
        for (a, b) in lines.iter().zip(&inj_lines).skip(1) {
            let x: Vec<f64> = a.split(',').map(|v| v.parse().unwrap()).collect();
            let y: Vec<i64> = b.split(',').map(|v| v.parse().unwrap()).collect();
            assert_eq!(y[0], (x[0] * 1000.0).round() as i64);
            assert_eq!(y[1], (x[2] * 100.0).round() as i64);
            assert_eq!(y[2], (x[4] * 100.0).round() as i64);
            assert!((x[2] - x[1].to_degrees()).abs() < 1e-12);
        }
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("design.json")).unwrap()).unwrap();
        assert_eq!(json["model"], "six-axis");
        let params = json["parameters"].as_array().unwrap();
        let six = aeroident_estimators::vocabulary::ModelStructure::six_axis().n_params();
        assert_eq!(params.len(), six);
        let cm_q = params.iter().find(|p| p["name"] == "Cm_q").unwrap();
        assert!(cm_q["crb_sigma"].as_f64().unwrap() > 0.0);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// With `--throw-deg`, the autopilot forms are written beside the tables: the script holds
    /// the injection table's centidegrees per surface, the PX4 table one row per sample.
    #[test]
    fn writes_the_autopilot_forms_with_throws() {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Wrap {
            #[command(flatten)]
            args: DesignArgs,
        }
        let dir = std::env::temp_dir().join(format!("aeroident-design-ap-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let argv = ["design", "--surfaces", "de", "--duration-s", "4", "--rate-hz", "20"];
        let mut args = Wrap::try_parse_from(argv.iter().copied().chain([
            "--throw-deg",
            "de=20,dr=30",
            "--arm-rc",
            "8",
        ]))
        .unwrap()
        .args;
        args.out = Some(dir.clone());
        execute(args).unwrap();
        let inj = std::fs::read_to_string(dir.join("injection.csv")).unwrap();
        let column: Vec<&str> = inj.lines().skip(1).map(|l| l.split(',').nth(1).unwrap()).collect();
        let lua = std::fs::read_to_string(dir.join("ardupilot_sysid.lua")).unwrap();
        let table = lua.split("offsets_cdeg = {").nth(1).unwrap().split('}').next().unwrap();
        let embedded: Vec<&str> = table.split(',').map(str::trim).collect();
        assert_eq!(embedded, column);
        assert!(lua.contains("local ARM_RC = 8"));
        let px4 = std::fs::read_to_string(dir.join("px4_torque.csv")).unwrap();
        assert_eq!(px4.lines().count(), 1 + column.len());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
