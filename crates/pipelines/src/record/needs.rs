//! What a model structure needs from a record: the channels and constants each term and each
//! measured coefficient is formed from, said in the mapping's names.

use crate::condition::Derivative;
use aeroident_estimators::{AirDataSample, Coefficient, ModelStructure, Term};
use aeroident_io::ModelSpec;

/// What the model needs that sample `s` lacks, as readable items (empty: supported). Terms
/// are checked for every estimator, measured coefficients for those that use them.
/// Derivatives in `supplied` count as present. The estimators that do not use measured
/// coefficients integrate the model's states themselves (EKF, output error, filter error), so
/// for them a state the record does not measure (β without a sideslip vane) is not missing:
/// they carry it as a state.
pub fn unsupported(
    structure: &ModelStructure,
    s: &AirDataSample,
    uses_measured: bool,
    supplied: &[Derivative],
) -> Vec<String> {
    let mut probe = *s;
    for d in supplied {
        if d.source(&probe).is_some() {
            d.set(&mut probe, Some(0.0));
        }
    }
    if !uses_measured && let Ok(set) = aeroident_estimators::StateSet::of(structure) {
        for &i in set.states() {
            let o = aeroident_estimators::Output::ALL[i];
            if o.measured(&probe).is_none() {
                o.set_measured(&mut probe, 0.0);
            }
        }
    }
    let mut out = Vec::new();
    for t in Term::ALL {
        if structure.params().any(|p| p.term == t) && structure.value(t, &probe).is_none() {
            out.push(format!("term `{}` ({})", t.name(), term_needs(t)));
        }
    }
    if uses_measured {
        let m = probe.measured_coefficients();
        for c in structure.coefficients() {
            if m[c.index()].is_none() {
                out.push(format!("coefficient `{}` ({})", c.name(), coefficient_needs(c)));
            }
        }
    }
    out
}

/// What term `t` needs that a record may lack, in the mapping's words ([`Term::inputs`]
/// without the channels every sample has): `needs p and the span b`, or `always available`.
fn term_needs(t: Term) -> String {
    let words: Vec<&str> =
        t.inputs().iter().filter(|i| !i.always_present()).map(|i| i.needs()).collect();
    match words.as_slice() {
        [] => "always available".into(),
        [one] => format!("needs {one}"),
        [init @ .., last] => format!("needs {} and {last}", init.join(", ")),
    }
}

/// What the record must map for coefficient `c` to be measured from its accelerations (in
/// the mapping's channel and constant names).
pub(crate) fn coefficient_needs(c: Coefficient) -> &'static str {
    match c {
        Coefficient::CX | Coefficient::CZ | Coefficient::CL | Coefficient::CD => "needs ax and az",
        Coefficient::CY => "needs ay",
        Coefficient::Cm => "needs q (or qdot), Iyy and cbar",
        Coefficient::Cl | Coefficient::Cn => {
            "needs p, q, r (or their derivatives), Ixx, Iyy, Izz, Ixz and the span b"
        }
    }
}

/// The default model, chosen in one place for every job: the richest preset
/// ([`ModelStructure::PRESETS`]'s order: six-axis, longitudinal, lateral) that `supports`
/// accepts. Each estimator family says what supporting means (the online estimators: every
/// term and measured coefficient formed, [`unsupported`]; the batch fits: a flight model the
/// first sample can drive).
///
/// # Errors
/// Why none is supported: `` `name`: reason `` per preset, joined by ` | `.
pub fn richest_preset(
    supports: impl Fn(&ModelSpec) -> Result<(), String>,
) -> Result<ModelSpec, String> {
    let mut why = Vec::new();
    for name in ModelStructure::PRESETS {
        let Some(spec) = ModelSpec::preset(name) else { continue };
        match supports(&spec) {
            Ok(()) => return Ok(spec),
            Err(reason) => why.push(format!("`{name}`: {reason}")),
        }
    }
    Err(why.join(" | "))
}
