//! A [`ModelFileAircraft`] from files: the model file's structure, the parameter values of a
//! replay summary (else the model file's `[reference.<param>]` values) and a mapping's
//! constants. Every error names the file and the field.

use super::{Airframe, ModelFileAircraft, Propulsion};
use crate::summary_file::{SummaryParameters, read_summary};
use aeroident_io::mapping::{Channel, Mapping};
use aeroident_io::model_file::ModelSpec;
use aeroident_models::aircraft::{AircraftMass, ReferenceGeometry};
use std::path::Path;

/// The airframe constants of `mapping` (SI): the constants `mass`, `Ixx`, `Iyy`, `Izz`, `S`,
/// `b`, `cbar` (required), `Ixz`, `thrust_arm`, `thrust_incidence` (0 when absent), `v0`; the
/// inertias scaled by `mass / inertia_reference_mass_kg` when that is given (constant radii of
/// gyration, as the records are). Thrust: the `[thrust_model]` law when there is one, else
/// the command is the thrust itself ([`Propulsion`]); the actuators of the commanded surfaces.
///
/// # Errors
/// A required constant that is absent or mapped to columns, naming the file and channel.
pub fn airframe_from_mapping(m: &Mapping) -> crate::error::Result<Airframe> {
    let file = &m.file;
    let constant = |ch: Channel| -> crate::error::Result<Option<f64>> {
        match m.channels.get(&ch) {
            None => Ok(None),
            Some(c) => c.constant().map(Some).ok_or_else(|| {
                crate::err!(
                    "{file}: `{}` is mapped to record columns; flying the aircraft needs a constant",
                    ch.key()
                )
            }),
        }
    };
    let required = |ch: Channel| -> crate::error::Result<f64> {
        constant(ch)?.ok_or_else(|| {
            crate::err!("{file}: no constant `{}`: flying the aircraft needs it", ch.key())
        })
    };
    let mass_kg = required(Channel::Mass)?;
    let scale = m.inertia_reference_mass_kg.map_or(1.0, |r| mass_kg / r);
    let mass = AircraftMass {
        mass_kg,
        jx_kgm2: required(Channel::Ixx)? * scale,
        jy_kgm2: required(Channel::Iyy)? * scale,
        jz_kgm2: required(Channel::Izz)? * scale,
        jxz_kgm2: constant(Channel::Ixz)?.unwrap_or(0.0) * scale,
    };
    let geometry = ReferenceGeometry {
        wing_area_m2: required(Channel::S)?,
        span_m: required(Channel::B)?,
        chord_m: required(Channel::Cbar)?,
    };
    Ok(Airframe {
        mass,
        geometry,
        thrust_arm_m: constant(Channel::ThrustArm)?.unwrap_or(0.0),
        thrust_incidence_rad: constant(Channel::ThrustIncidence)?.unwrap_or(0.0),
        v0_mps: constant(Channel::V0)?,
        propulsion: m.thrust_model.map_or(Propulsion::Commanded, Propulsion::Law),
        actuators: [Channel::De, Channel::Da, Channel::Dr].map(|c| m.actuators.get(&c).copied()),
    })
}

/// The value of every parameter of `spec`'s structure, in structure order, with a note per
/// value not identified: the summary's estimate when a summary is given (`summary_file` names
/// it), else the model file's `[reference.<param>]` value; a parameter `null` in the summary
/// or absent from it (a partial test card: no thrust, so no drag; one axis flown) is flown at
/// the model's stated prior ([`ModelSpec::priors`]: the model file's `[prior.<param>]` or the
/// conventional aircraft's), and the note says so.
///
/// # Errors
/// A parameter without a reference when no summary is given, or a summary parameter the
/// model does not have; each naming the file and parameter.
pub fn parameter_values(
    spec: &ModelSpec,
    model_file: &str,
    summary: Option<(&SummaryParameters, &str)>,
) -> crate::error::Result<(Vec<f64>, Vec<String>)> {
    if let Some((s, file)) = summary
        && let Some(extra) = s.parameters.iter().find(|p| !spec.structure.contains(p.param))
    {
        crate::bail!(
            "{file}: parameter `{}` is not in the model of {model_file}: the summary is of another model",
            extra.param.name()
        );
    }
    let mut notes = Vec::new();
    let mut values = Vec::new();
    for (i, p) in spec.structure.params().enumerate() {
        let v = match summary {
            Some((s, file)) => match s.parameters.iter().find(|q| q.param == p) {
                Some(q) if q.value.is_some() => q.value,
                found => {
                    let prior = spec.priors.prior[i].value;
                    let why = if found.is_some() { "not identified (null)" } else { "absent" };
                    notes.push(format!(
                        "`{}` is {why} in {file}: flown at the model's prior {prior}",
                        p.name()
                    ));
                    Some(prior)
                }
            },
            None => spec.references.iter().find(|r| r.param == p).map(|r| r.value),
        };
        values.push(v.ok_or_else(|| {
            crate::err!(
                "{model_file}: no [reference.{}] value (give a --summary with its estimate)",
                p.name()
            )
        })?);
    }
    Ok((values, notes))
}

/// The aircraft of model file `model` (or a preset's name, [`ModelSpec::preset`]), summary
/// `summary` (optional) and mapping `mapping`
/// (see [`airframe_from_mapping`], [`parameter_values`]), in the standard atmosphere.
///
/// # Errors
/// A file that cannot be read or parsed, or any error of the functions above and of
/// [`ModelFileAircraft::new`], naming the file.
pub fn load(
    model: &Path,
    summary: Option<&Path>,
    mapping: &Path,
) -> crate::error::Result<ModelFileAircraft> {
    let model_file = model.display().to_string();
    // A preset's name (`six-axis`, as `replay --model` takes) where no such file exists: the
    // values then come from the summary.
    let spec = match ModelSpec::preset(&model_file) {
        Some(preset) if !model.exists() => preset,
        _ => ModelSpec::from_path(model).map_err(|e| crate::err!("{e}"))?,
    };
    let summary_read = summary.map(read_summary).transpose()?;
    let summary_file = summary.map(|p| p.display().to_string()).unwrap_or_default();
    let (theta, notes) = parameter_values(
        &spec,
        &model_file,
        summary_read.as_ref().map(|s| (s, summary_file.as_str())),
    )?;
    let map = Mapping::from_path(mapping).map_err(|e| crate::err!("{e}"))?;
    let airframe = airframe_from_mapping(&map)?;
    ModelFileAircraft::new(&spec.name, spec.structure, theta, airframe)
        .map(|a| a.with_notes(notes))
        .map_err(|e| crate::err!("{model_file} with {}: {e}", map.file))
}
