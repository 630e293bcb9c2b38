//! `aeroident export`: results for other tools (docs/export.md).
//!
//! ```text
//! aeroident export jsbsim --summary DIR/summary.json [--out FILE] [--v0-mps V0]
//!                  [--elevator-property P] [--aileron-property P] [--rudder-property P]
//!                  [--mapping M [--name NAME]]
//! aeroident export ardupilot --summary S (--mapping M | --area-m2 A --span-m B --chord-m C
//!                  --mass-kg M --ixx-kgm2 JX …) [--out FILE] [--aileron-throw-deg D …]
//!                  [--sitl-mass-kg 2] [--alpha-stall-deg 27] [--mcoeff 50] [--drop-unrepresentable]
//! aeroident export gazebo --summary S (--mapping M | …) [--out FILE] [--de-joint J …]
//!                  [--da-joint LEFT,RIGHT] [--de-direction ±1 …] [--link-name base_link]
//!                  [--air-density RHO] [--drop-unrepresentable]
//! ```
//! Writes the identified derivatives of a `replay` summary as a JSBSim `<aerodynamics>`
//! fragment, an ArduPilot SITL plane coefficient JSON or a Gazebo `AdvancedLiftDrag`
//! `<plugin>` element to FILE (atomically: a temporary file beside it, renamed) or to stdout;
//! the conversions are in `aeroident_pipelines::export`.

use aeroident_estimators::vocabulary::Term;
use aeroident_io::{Channel, Mapping};
use aeroident_models::aircraft::AircraftMass;
use aeroident_pipelines::export::ardupilot::{
    ArdupilotOptions, Throws, ardupilot_json, mapped_throw,
};
use aeroident_pipelines::export::gazebo::{ControlJoint, GazeboOptions, gazebo_plugin_sdf};
use aeroident_pipelines::export::jsbsim::{SurfaceProperties, aerodynamics_xml};
use aeroident_pipelines::export::uav::{Exported, Geometry, MAX_STALL_DEG, MAX_THROW_DEG};
use aeroident_pipelines::summary_file::{SummaryParameters, read_summary};
use aeroident_report::outfile;
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// What to export.
    #[command(subcommand)]
    pub what: ExportWhat,
}

/// The export formats.
#[derive(Debug, clap::Subcommand)]
pub enum ExportWhat {
    /// Identified derivatives as a JSBSim `<aerodynamics>` fragment.
    Jsbsim(JsbsimArgs),
    /// Identified derivatives as ArduPilot SITL's plane coefficient JSON (`--model plane:FILE`).
    Ardupilot(ArdupilotArgs),
    /// Identified derivatives as a Gazebo `AdvancedLiftDrag` `<plugin>` element (PX4 SITL).
    Gazebo(GazeboArgs),
}

/// Where the reference geometry comes from: the mapping's constants, or the options (which
/// take precedence).
#[derive(Debug, clap::Args)]
pub struct GeometryArgs {
    /// Mapping whose constants `S`, `b`, `cbar` give the reference geometry.
    #[arg(long)]
    pub mapping: Option<PathBuf>,
    /// Wing reference area S, m² (overrides the mapping's).
    #[arg(long)]
    pub area_m2: Option<f64>,
    /// Wing span b, m (overrides the mapping's).
    #[arg(long)]
    pub span_m: Option<f64>,
    /// Mean aerodynamic chord c̄, m (overrides the mapping's).
    #[arg(long)]
    pub chord_m: Option<f64>,
    /// Write the terms the target cannot represent as its formula allows (warning for each)
    /// instead of refusing the export.
    #[arg(long)]
    pub drop_unrepresentable: bool,
}

/// Arguments of `aeroident export ardupilot`.
#[derive(Debug, clap::Args)]
pub struct ArdupilotArgs {
    /// The `summary.json` of a replay (online estimator or `--estimator oe`).
    #[arg(long)]
    pub summary: PathBuf,
    /// Output file (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Reference geometry and unrepresentable terms.
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Aileron deflection at full servo command, degrees (`deltaa_max`; default: the
    /// mapping's `da` actuator limits or calibration range, else SITL's 20°).
    #[arg(long)]
    pub aileron_throw_deg: Option<f64>,
    /// Elevator deflection at full servo command, degrees (`deltae_max`; default as the
    /// aileron's, from `de`).
    #[arg(long)]
    pub elevator_throw_deg: Option<f64>,
    /// Rudder deflection at full servo command, degrees (`deltar_max`; default as the
    /// aileron's, from `dr`).
    #[arg(long)]
    pub rudder_throw_deg: Option<f64>,
    /// The aircraft's mass and inertia (default: the mapping's constants).
    #[command(flatten)]
    pub mass: MassArgs,
    /// The mass SITL's plane divides its forces by, kg: 2 for the default frame, 8 for
    /// `-heavy`, 22 for `-jet`.
    #[arg(long, default_value_t = aeroident_pipelines::export::ardupilot::SITL_MASS_KG)]
    pub sitl_mass_kg: f64,
    /// Stall angle of SITL's lift blend, degrees (`alpha_stall`).
    #[arg(long, default_value_t = 27.0)]
    pub alpha_stall_deg: f64,
    /// Sharpness of SITL's lift blend, 1/rad (`mcoeff`).
    #[arg(long, default_value_t = 50.0)]
    pub mcoeff: f64,
}

/// The aircraft's mass and inertia: each option, else the mapping's constant (inertias
/// scaled by the mapping's `inertia_reference_mass_kg` when it has one).
#[derive(Debug, clap::Args)]
pub struct MassArgs {
    /// Aircraft mass, kg (overrides the mapping's `mass`).
    #[arg(long)]
    pub mass_kg: Option<f64>,
    /// Roll inertia Jx, kg·m² (overrides the mapping's `Ixx`).
    #[arg(long)]
    pub ixx_kgm2: Option<f64>,
    /// Pitch inertia Jy, kg·m² (overrides the mapping's `Iyy`).
    #[arg(long)]
    pub iyy_kgm2: Option<f64>,
    /// Yaw inertia Jz, kg·m² (overrides the mapping's `Izz`).
    #[arg(long)]
    pub izz_kgm2: Option<f64>,
    /// Product of inertia Jxz, kg·m², Stevens & Lewis sign (overrides the mapping's `Ixz`;
    /// default 0).
    #[arg(long, allow_negative_numbers = true)]
    pub ixz_kgm2: Option<f64>,
}

/// Arguments of `aeroident export gazebo`.
#[derive(Debug, clap::Args)]
pub struct GazeboArgs {
    /// The `summary.json` of a replay (online estimator or `--estimator oe`).
    #[arg(long)]
    pub summary: PathBuf,
    /// Output file (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Reference geometry and unrepresentable terms.
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Elevator joint of the model (PX4's `advanced_plane`: `servo_2`).
    #[arg(long, default_value = "servo_2")]
    pub de_joint: String,
    /// Aileron joint, or the left and right joints of an aileron pair as `LEFT,RIGHT` (PX4's
    /// `advanced_plane`: `servo_0,servo_1`; each then carries half the derivative, the right
    /// one mirrored).
    #[arg(long, default_value = "servo_0,servo_1")]
    pub da_joint: String,
    /// Rudder joint of the model (PX4's `advanced_plane`: `servo_3`).
    #[arg(long, default_value = "servo_3")]
    pub dr_joint: String,
    /// +1 if the elevator joint's positive angle is trailing edge down, −1 if up (PX4's
    /// `servo_2`, axis `0 1 0` of a FLU model: −1).
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub de_direction: f64,
    /// A single aileron joint: +1 if its positive angle rolls left (right aileron trailing
    /// edge down), −1 if right. A pair: +1 if the left joint's positive angle is its trailing
    /// edge up (PX4's `servo_0`/`servo_1`, axis `0 1 0`), −1 if down.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub da_direction: f64,
    /// +1 if the rudder joint's positive angle is trailing edge left, −1 if right (PX4's
    /// `servo_3`, axis `0 0 1` of a FLU model: −1).
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub dr_direction: f64,
    /// The aircraft body link.
    #[arg(long, default_value = "base_link")]
    pub link_name: String,
    /// Air density the plugin uses, kg/m³ (a constant in the plugin; default: the mapping's
    /// constant `rho`, else the plugin's 1.2041).
    #[arg(long)]
    pub air_density: Option<f64>,
    /// Stall angle of the plugin's lift blend, degrees (its blend width is fixed: a lower
    /// angle blends flat-plate lift in at small α).
    #[arg(long, default_value_t = 90.0)]
    pub alpha_stall_deg: f64,
}

/// Arguments of `aeroident export jsbsim`.
#[derive(Debug, clap::Args)]
pub struct JsbsimArgs {
    /// The `summary.json` of a replay (online estimator or `--estimator oe`).
    #[arg(long)]
    pub summary: PathBuf,
    /// Output file (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Reference speed V0, m/s, for the `V` (V/V0) and `q0` (q c̄/2V0) terms; without it they
    /// are omitted with a comment.
    #[arg(long)]
    pub v0_mps: Option<f64>,
    /// JSBSim property of the elevator deflection, rad, > 0 trailing edge down.
    #[arg(long, default_value = "fcs/elevator-pos-rad")]
    pub elevator_property: String,
    /// JSBSim property of the aileron deflection, rad, > 0 rolls right wing down (the
    /// fragment multiplies it by −1: aeroident's δa > 0 rolls left).
    #[arg(long, default_value = "fcs/left-aileron-pos-rad")]
    pub aileron_property: String,
    /// JSBSim property of the rudder deflection, rad, > 0 trailing edge left.
    #[arg(long, default_value = "fcs/rudder-pos-rad")]
    pub rudder_property: String,
    /// A mapping whose constants (mass, inertia, S, b, c̄, thrust line, v0), thrust law and
    /// actuators complete the aircraft: writes a whole JSBSim `<fdm_config>` instead of the
    /// `<aerodynamics>` fragment (its surfaces are then the file's own properties).
    #[arg(long)]
    pub mapping: Option<PathBuf>,
    /// With `--mapping`: the aircraft's name (JSBSim loads `aircraft/NAME/NAME.xml`; default:
    /// the `--out` file's stem, else `identified`).
    #[arg(long)]
    pub name: Option<String>,
}

/// Runs `aeroident export`.
///
/// # Errors
/// An unreadable or malformed summary (naming the file and parameter), nothing identified,
/// mixed axis systems, a non-positive V0, or an output I/O error naming the file.
pub fn execute(args: ExportArgs) -> anyhow::Result<()> {
    match args.what {
        ExportWhat::Jsbsim(a) => jsbsim(a),
        ExportWhat::Ardupilot(a) => ardupilot(a),
        ExportWhat::Gazebo(a) => gazebo(a),
    }
}

/// The reference geometry: each option, else the mapping's constant.
fn geometry(g: &GeometryArgs) -> anyhow::Result<Geometry> {
    let mapping = g.mapping.as_deref().map(Mapping::from_path).transpose()?;
    let pick = |given: Option<f64>, ch: Channel, flag: &str| -> anyhow::Result<f64> {
        let mapped = || mapping.as_ref()?.channels.get(&ch)?.constant();
        given.or_else(mapped).with_context(|| {
            format!("no {flag}: give it, or a --mapping with a constant `{}`", ch.key())
        })
    };
    Ok(Geometry {
        area_m2: pick(g.area_m2, Channel::S, "--area-m2")?,
        span_m: pick(g.span_m, Channel::B, "--span-m")?,
        chord_m: pick(g.chord_m, Channel::Cbar, "--chord-m")?,
    })
}

/// The aircraft's mass and inertia: each option, else the mapping's constant.
fn mass(g: &GeometryArgs, a: &MassArgs) -> anyhow::Result<AircraftMass> {
    let mapping = g.mapping.as_deref().map(Mapping::from_path).transpose()?;
    let mapped = |ch: Channel| mapping.as_ref()?.channels.get(&ch)?.constant();
    let need = |given: Option<f64>, ch: Channel, flag: &str| -> anyhow::Result<f64> {
        given.or_else(|| mapped(ch)).with_context(|| {
            format!(
                "no {flag}: SITL applies its own mass and unit inertia, so the export needs the aircraft's; give it, or a --mapping with a constant `{}`",
                ch.key()
            )
        })
    };
    let mass_kg = need(a.mass_kg, Channel::Mass, "--mass-kg")?;
    // The mapping's inertias hold at its reference mass (constant radii of gyration).
    let reference = mapping.as_ref().and_then(|m| m.inertia_reference_mass_kg);
    let inertia = |given: Option<f64>, ch, flag| -> anyhow::Result<f64> {
        match given {
            Some(v) => Ok(v),
            None => Ok(need(None, ch, flag)? * reference.map_or(1.0, |r| mass_kg / r)),
        }
    };
    Ok(AircraftMass {
        mass_kg,
        jx_kgm2: inertia(a.ixx_kgm2, Channel::Ixx, "--ixx-kgm2")?,
        jy_kgm2: inertia(a.iyy_kgm2, Channel::Iyy, "--iyy-kgm2")?,
        jz_kgm2: inertia(a.izz_kgm2, Channel::Izz, "--izz-kgm2")?,
        jxz_kgm2: match a.ixz_kgm2.or_else(|| mapped(Channel::Ixz)) {
            Some(_) => inertia(a.ixz_kgm2, Channel::Ixz, "--ixz-kgm2")?,
            None => 0.0,
        },
    })
}

/// Each surface's throw: the option, else the mapping's ([`mapped_throw`]), else SITL's
/// default; the notes say where each came from when not given.
fn throws(a: &ArdupilotArgs) -> anyhow::Result<(Throws, Vec<String>)> {
    let mapping = a.geometry.mapping.as_deref().map(Mapping::from_path).transpose()?;
    let default = Throws::default();
    let mut notes = Vec::new();
    let mut pick = |given: Option<f64>, ch: Channel, flag: &str, sitl: f64| {
        if let Some(deg) = given {
            positive_at_most_deg(flag, deg, MAX_THROW_DEG)?;
            return anyhow::Ok(deg.to_radians());
        }
        let (rad, note) = match mapping.as_ref().and_then(|m| mapped_throw(m, ch)) {
            Some(t) => (t.rad, t.note),
            None => (
                sitl,
                format!(
                    "no {flag} and no throw of `{}` in a mapping: SITL's {}° written",
                    ch.key(),
                    sitl.to_degrees().round()
                ),
            ),
        };
        notes.push(note);
        Ok(rad)
    };
    let throws = Throws {
        aileron_rad: pick(
            a.aileron_throw_deg,
            Channel::Da,
            "--aileron-throw-deg",
            default.aileron_rad,
        )?,
        elevator_rad: pick(
            a.elevator_throw_deg,
            Channel::De,
            "--elevator-throw-deg",
            default.elevator_rad,
        )?,
        rudder_rad: pick(
            a.rudder_throw_deg,
            Channel::Dr,
            "--rudder-throw-deg",
            default.rudder_rad,
        )?,
    };
    Ok((throws, notes))
}

fn ardupilot(a: ArdupilotArgs) -> anyhow::Result<()> {
    check_out(a.out.as_deref(), &a.summary, a.geometry.mapping.as_deref())?;
    let (throws, mut notes) = throws(&a)?;
    notes.extend(servo_notes(
        a.geometry.mapping.as_deref(),
        "SITL's servo model is its own (SIM_SERVO_SPEED, the time for 60° of servo travel; 0 = none), not this lag",
    )?);
    positive_at_most_deg("--alpha-stall-deg", a.alpha_stall_deg, MAX_STALL_DEG)?;
    let summary = read_summary(&a.summary)?;
    note_unfinished(&a.summary, &summary);
    let options = ArdupilotOptions {
        geometry: geometry(&a.geometry)?,
        throws,
        alpha_stall_rad: a.alpha_stall_deg.to_radians(),
        mcoeff: a.mcoeff,
        drop_unrepresentable: a.geometry.drop_unrepresentable,
        mass: mass(&a.geometry, &a.mass)?,
        sitl_mass_kg: a.sitl_mass_kg,
        notes,
    };
    let out = ardupilot_json(&summary, &a.summary.display().to_string(), &options)?;
    write_exported(&a.summary, a.out.as_deref(), &out)
}

fn gazebo(a: GazeboArgs) -> anyhow::Result<()> {
    check_out(a.out.as_deref(), &a.summary, a.geometry.mapping.as_deref())?;
    positive_at_most_deg("--alpha-stall-deg", a.alpha_stall_deg, MAX_STALL_DEG)?;
    let summary = read_summary(&a.summary)?;
    note_unfinished(&a.summary, &summary);
    let mut joints = Vec::new();
    for (surface, names, direction, flag) in [
        (Term::De, &a.de_joint, a.de_direction, "--de-joint"),
        (Term::Da, &a.da_joint, a.da_direction, "--da-joint"),
        (Term::Dr, &a.dr_joint, a.dr_direction, "--dr-joint"),
    ] {
        joints.extend(control_joints(surface, names, direction, flag)?);
    }
    let options = GazeboOptions {
        geometry: geometry(&a.geometry)?,
        joints,
        air_density_kgpm3: air_density(&a)?,
        link_name: a.link_name,
        alpha_stall_rad: a.alpha_stall_deg.to_radians(),
        drop_unrepresentable: a.geometry.drop_unrepresentable,
        notes: servo_notes(
            a.geometry.mapping.as_deref(),
            "Gazebo's joints follow their JointPositionController (its p_gain), not this servo",
        )?,
    };
    let out = gazebo_plugin_sdf(&summary, &a.summary.display().to_string(), &options)?;
    write_exported(&a.summary, a.out.as_deref(), &out)
}

/// The joints of one surface from `names`: one joint (share 1), or an aileron pair
/// `LEFT,RIGHT` (shares ½ and −½: the right joint mirrored).
///
/// # Errors
/// An empty name, more than two, or a pair on the elevator or rudder, naming `flag`.
fn control_joints(
    surface: Term,
    names: &str,
    direction: f64,
    flag: &str,
) -> anyhow::Result<Vec<ControlJoint>> {
    let parts: Vec<&str> = names.split(',').map(str::trim).collect();
    if parts.iter().any(|p| p.is_empty()) || parts.len() > 2 {
        anyhow::bail!("{flag} `{names}`: give one joint name, or LEFT,RIGHT for an aileron pair");
    }
    if parts.len() == 2 && surface != Term::Da {
        anyhow::bail!("{flag} `{names}`: only the aileron takes a LEFT,RIGHT pair");
    }
    let shares: &[f64] = if parts.len() == 2 { &[0.5, -0.5] } else { &[1.0] };
    Ok(parts
        .iter()
        .zip(shares)
        .map(|(joint, &share)| ControlJoint { surface, joint: joint.to_string(), direction, share })
        .collect())
}

/// A note per actuator the mapping declares (the surface the derivatives were fitted
/// through), with what the target does instead (`instead`): the target's file cannot hold it.
fn servo_notes(mapping: Option<&Path>, instead: &str) -> anyhow::Result<Vec<String>> {
    let Some(path) = mapping else { return Ok(Vec::new()) };
    let m = Mapping::from_path(path)?;
    Ok(m.actuators
        .iter()
        .map(|(ch, a)| {
            format!(
                "the mapping's `{}` actuator (τ {} s, rate limit {} rad/s) is not in the file: {instead}; `export jsbsim --mapping` carries it",
                ch.key(),
                aeroident_io::message::short(a.tau_s),
                aeroident_io::message::short(a.rate_limit_rad_s)
            )
        })
        .collect())
}

/// The plugin's air density: the option, else the mapping's constant `rho`, else the
/// plugin's default 1.2041 kg/m³ (with a note).
fn air_density(a: &GazeboArgs) -> anyhow::Result<f64> {
    if let Some(rho) = a.air_density {
        return Ok(rho);
    }
    let mapping = a.geometry.mapping.as_deref().map(Mapping::from_path).transpose()?;
    match mapping.as_ref().and_then(|m| m.channels.get(&Channel::Rho)?.constant()) {
        Some(rho) => Ok(rho),
        None => {
            aeroident_report::note!(
                "{}: no --air-density and no constant `rho` in a mapping: the plugin's 1.2041 kg/m³ written",
                a.summary.display()
            );
            Ok(1.2041)
        }
    }
}

/// Prints each warning, then writes the file to `out` or stdout.
fn write_exported(summary: &Path, out: Option<&Path>, e: &Exported) -> anyhow::Result<()> {
    for w in &e.warnings {
        aeroident_report::note!("warning: {}: {w}", summary.display());
    }
    match out {
        Some(path) => {
            outfile::write_file("--out", path, e.text.as_bytes())?;
            aeroident_report::note!("{}: wrote {}", summary.display(), path.display());
        }
        None => {
            let mut stdout = std::io::stdout().lock();
            stdout.write_all(e.text.as_bytes())?;
            stdout.flush()?;
        }
    }
    Ok(())
}

fn jsbsim(a: JsbsimArgs) -> anyhow::Result<()> {
    if let Some(v) = a.v0_mps
        && !(v.is_finite() && v > 0.0 && v <= MAX_V0_MPS)
    {
        anyhow::bail!(
            "--v0-mps must be a speed > 0 and at most {MAX_V0_MPS} m/s, got {}",
            aeroident_io::message::short(v)
        );
    }
    check_out(a.out.as_deref(), &a.summary, a.mapping.as_deref())?;
    let summary = read_summary(&a.summary)?;
    note_unfinished(&a.summary, &summary);
    if let Some(mapping) = &a.mapping {
        return jsbsim_aircraft(&a, mapping, &summary);
    }
    let surfaces = SurfaceProperties {
        elevator: a.elevator_property,
        aileron: a.aileron_property,
        rudder: a.rudder_property,
    };
    let xml = aerodynamics_xml(&summary, &a.summary.display().to_string(), &surfaces, a.v0_mps)?;
    let exported = xml.matches("<function ").count();
    let omitted = xml.matches("omitted").count();
    match &a.out {
        Some(path) => {
            outfile::write_file("--out", path, xml.as_bytes())?;
            aeroident_report::note!(
                "{}: {exported} derivatives exported, {omitted} omitted (see the comments); wrote {}",
                a.summary.display(),
                path.display()
            );
        }
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(xml.as_bytes())?;
            out.flush()?;
        }
    }
    Ok(())
}

/// `export jsbsim --mapping`: the complete aircraft of `summary` with the mapping's airframe
/// and actuators ([`aeroident_pipelines::export::jsbsim_aircraft`]).
fn jsbsim_aircraft(
    a: &JsbsimArgs,
    mapping: &Path,
    summary: &SummaryParameters,
) -> anyhow::Result<()> {
    if a.v0_mps.is_some() {
        anyhow::bail!("--v0-mps: with --mapping the reference speed is the mapping's `v0`");
    }
    let m = Mapping::from_path(mapping)?;
    let airframe = aeroident_pipelines::airframe::airframe_from_mapping(&m)?;
    let stem = a.out.as_deref().and_then(|p| p.file_stem()).and_then(|s| s.to_str());
    let name = a.name.as_deref().or(stem).unwrap_or("identified");
    let source = a.summary.display().to_string();
    let xml = aeroident_pipelines::export::jsbsim_aircraft::aircraft_xml(
        summary,
        &source,
        name,
        &airframe,
        &m.actuators,
    )?;
    let e = Exported { text: xml, warnings: Vec::new() };
    write_exported(&a.summary, a.out.as_deref(), &e)
}

/// The largest `--v0-mps` taken: Mach 3 at altitude, beyond any aircraft a fit describes.
const MAX_V0_MPS: f64 = 1000.0;

/// Checks an angle option in degrees lies in (0, `max`]: a throw beyond a right angle, or a
/// stall angle beyond a half turn, is a typing or unit error.
fn positive_at_most_deg(flag: &str, deg: f64, max: f64) -> anyhow::Result<()> {
    if !(deg.is_finite() && deg > 0.0 && deg <= max) {
        anyhow::bail!(
            "{flag} must be > 0 and at most {max}°, got {}",
            aeroident_io::message::short(deg)
        );
    }
    Ok(())
}

/// Warns when the summary is of a run that did not finish (an interrupted replay, a fit that
/// did not converge): what is exported is where it stopped.
fn note_unfinished(path: &Path, summary: &SummaryParameters) {
    if let Some(note) = summary.unfinished() {
        aeroident_report::note!("warning: {}: {note}", path.display());
    }
}

/// Refuses, before the export reads anything, an `--out` that is not a regular file or that
/// names one of its inputs (`--summary`, `--mapping`): the write would replace it.
fn check_out(out: Option<&Path>, summary: &Path, mapping: Option<&Path>) -> anyhow::Result<()> {
    let Some(out) = out else { return Ok(()) };
    let mut inputs = vec![("--summary", summary)];
    inputs.extend(mapping.map(|m| ("--mapping", m)));
    Ok(outfile::check_outputs(&[("--out", out)], &inputs)?)
}
