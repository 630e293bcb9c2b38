//! What a model structure needs from a record: the channels and constants each term and each
//! measured coefficient is formed from, said in the mapping's names.

use crate::condition::Derivative;
use aeroident_estimators::{AirDataSample, Coefficient, ModelStructure, Term};

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

fn term_needs(t: Term) -> &'static str {
    match t {
        Term::Beta | Term::AlphaBeta => "needs beta",
        Term::P | Term::AlphaP => "needs p and the span b",
        Term::Q | Term::AlphaQ => "needs q and cbar",
        Term::Q0 => "needs q, cbar and v0",
        Term::R | Term::AlphaR => "needs r and the span b",
        Term::Alphadot => "needs alphadot or alpha to differentiate, and cbar",
        Term::De | Term::AlphaDe => "needs de",
        Term::Da | Term::AlphaDa => "needs da",
        Term::Dr | Term::AlphaDr => "needs dr",
        Term::V => "needs v0",
        Term::Mach | Term::Mach2 => "needs a density within the standard atmosphere (-1 to 20 km)",
        Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => {
            "needs its alpha knot in the model"
        }
        Term::Bias | Term::Alpha | Term::Alpha2 => "always available",
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
