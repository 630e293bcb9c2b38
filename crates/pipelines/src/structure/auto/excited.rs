//! The axes a record excites, judged from the selection itself: plain `--model auto` offers
//! every coefficient the record measures, and keeps an axis only when its moment equations
//! need a surface term.
//!
//! Why the surfaces: identifying an axis means separating its damping and static stability
//! from the inputs that moved it. A manoeuvre on an axis is flown with that axis' surfaces,
//! and when the stepwise regression finds no surface term worth its partial F in the axis'
//! moment equations (`Cm` for δe; `Cl`, `Cn` for δa, δr), the axis moved only by what the
//! record does not measure (gusts, the pilot's or autopilot's small corrections, coupling from
//! the other axis). Its coefficients would then be fitted to that unmeasured motion: a
//! pitch-only record's `Cn_β` or `CY_0` are not a lateral model. SIDPAC and FVSysID analyse
//! each manoeuvre with the model of the axes it excites (Klein & Morelli 2006, ch. 5 and 9;
//! Jategaonkar 2015, ch. 3), which is what this rule chooses without being told.
//!
//! A second reading guards the first: the axis kept must also be the one whose surfaces
//! moved most (the largest standard deviation of a surface over the record, radians). A
//! 3-2-1-1 on the elevator whose `Cm_δe` falls just short of the cut-off on noisy pitch
//! accelerations, beside an autopilot's aileron corrections that pass it, is not a lateral
//! manoeuvre; when the two readings disagree both axes are kept.

use super::Scope;
use crate::structure::CoefficientSelection;
use aeroident_estimators::{AirDataSample, Coefficient, Term, TermInput};

/// The moment coefficients and the surfaces that judge each axis.
const AXES: [(Scope, &[Coefficient], &[TermInput]); 2] = [
    (Scope::Longitudinal, &[Coefficient::Cm], &[TermInput::De]),
    (Scope::Lateral, &[Coefficient::Cl, Coefficient::Cn], &[TermInput::Da, TermInput::Dr]),
];

/// The scope whose axes the selection found excited, and why, when it is narrower than
/// six-axis: `(scope, None)` when both axes are excited or neither is (then nothing tells one
/// from the other, and both are kept as offered).
/// `samples`: the manoeuvres selected on, whose surfaces' spread is the second reading.
pub(super) fn excited_scope(
    selections: &[CoefficientSelection],
    samples: &[&[AirDataSample]],
) -> (Scope, Option<String>) {
    let excited = |(_, moments, surfaces): &(Scope, &[Coefficient], &[TermInput])| {
        selections
            .iter()
            .filter(|s| moments.contains(&s.coefficient))
            .any(|s| s.kept().iter().any(|t| reads_any(*t, surfaces)))
    };
    let [lon, lat] = [excited(&AXES[0]), excited(&AXES[1])];
    let (kept, dropped) = match (lon, lat) {
        (true, false) => (Scope::Longitudinal, &AXES[1]),
        (false, true) => (Scope::Lateral, &AXES[0]),
        _ => return (Scope::SixAxis, None),
    };
    let spread = |(_, _, surfaces): &(Scope, &[Coefficient], &[TermInput])| {
        surfaces.iter().map(|s| surface_sd_rad(samples, *s)).fold(0.0, f64::max)
    };
    let kept_axis = if kept == Scope::Longitudinal { &AXES[0] } else { &AXES[1] };
    if spread(kept_axis) <= spread(dropped) {
        return (Scope::SixAxis, None);
    }
    let (dropped_scope, moments, surfaces) = dropped;
    let evidence: Vec<String> = selections
        .iter()
        .filter(|s| moments.contains(&s.coefficient))
        .map(|s| format!("{}: {}", s.coefficient.name(), surface_f(s, surfaces)))
        .collect();
    let reason = format!(
        "scope {}: the {} moment equations keep no surface term ({}; partial F ≤ the cut-off), so the record does not excite the {} axes and their coefficients would be fitted to motion it does not measure; they are left out (`--model auto:six-axis` keeps them)",
        kept.name(),
        dropped_scope.name(),
        evidence.join("; "),
        dropped_scope.name()
    );
    (kept, Some(reason))
}

/// The standard deviation of surface `s` over the samples that have it, rad (0 without any).
fn surface_sd_rad(samples: &[&[AirDataSample]], s: TermInput) -> f64 {
    let value = |x: &AirDataSample| match s {
        TermInput::De => x.de_rad,
        TermInput::Da => x.da_rad,
        TermInput::Dr => x.dr_rad,
        _ => None,
    };
    let v: Vec<f64> = samples.iter().flat_map(|m| m.iter().filter_map(value)).collect();
    if v.len() < 2 {
        return 0.0;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// Whether `t`'s regressor reads one of `inputs`.
fn reads_any(t: Term, inputs: &[TermInput]) -> bool {
    t.inputs().iter().any(|i| inputs.contains(i))
}

/// Each offered surface term of `s` with its partial F were it added (`—`: collinear with
/// the kept terms, or waiting for a parent).
fn surface_f(s: &CoefficientSelection, surfaces: &[TermInput]) -> String {
    let terms: Vec<String> = s
        .left_out
        .iter()
        .filter(|(t, _, parent)| reads_any(*t, surfaces) && parent.is_none())
        .map(|(t, f, _)| match f {
            Some(f) => format!("{} {f:.1}", t.name()),
            None => format!("{} —", t.name()),
        })
        .collect();
    if terms.is_empty() { "no surface term offered".into() } else { terms.join(", ") }
}
