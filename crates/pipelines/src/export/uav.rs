//! What the UAV-simulator exports ([`super::ardupilot`], [`super::gazebo`]) share: the
//! reference geometry a summary does not carry, the sorting of a summary's parameters into
//! those a target's formula holds, those not identified and those it cannot represent, and the
//! drag polar both targets build their drag from. Documented in `docs/export.md`.
//!
//! Both targets compute drag as `CD0 + CL_s² / (π e AR)` (a parabolic polar on the static lift
//! `CL_s`, the lift without rate terms), with no term of their own linear in α. aeroident's
//! `CD_0 + CD_alpha α + CD_alpha2 α²` is that polar exactly when
//! `1/(π e AR) = CD_alpha2 / CL_alpha²` and `CD_alpha = 2 CL_0 CD_alpha2 / CL_alpha` (without
//! `CD_alpha2`: no induced drag, `CD_alpha = 0`); the exporters check it.

use crate::summary_file::SummaryParameters;
use aeroident_estimators::vocabulary::{Coefficient, Param, Term};
use std::collections::BTreeMap;

/// Reference geometry of the aircraft, SI (a summary does not carry it: from the mapping's
/// constants or the command line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Wing reference area S, m².
    pub area_m2: f64,
    /// Wing span b, m.
    pub span_m: f64,
    /// Mean aerodynamic chord c̄, m.
    pub chord_m: f64,
}

/// The largest reference area taken, m²: above the largest wings flown (An-225 905 m², the
/// H-4 Hercules 1,061 m²), so a larger number is a typing or unit error.
pub const MAX_AREA_M2: f64 = 2000.0;
/// The largest span or chord taken, m (the Stratolaunch spans 117 m).
pub const MAX_LENGTH_M: f64 = 150.0;
/// The largest surface throw taken, degrees: a control surface travels a fraction of a right
/// angle, so more is a typing or unit error.
pub const MAX_THROW_DEG: f64 = 90.0;
/// The largest stall angle taken, degrees: an angle of attack lies within a half turn (a
/// stall angle past 90° turns a simulator's stall blend off over every α flown).
pub const MAX_STALL_DEG: f64 = 180.0;

impl Geometry {
    /// Checks the area lies in (0, [`MAX_AREA_M2`]] and each length in (0, [`MAX_LENGTH_M`]].
    ///
    /// # Errors
    /// The first that does not, naming it and its value in short form.
    pub fn check(&self) -> crate::error::Result<()> {
        positive_at_most("reference area S", self.area_m2, MAX_AREA_M2, "m²")?;
        positive_at_most("reference span b", self.span_m, MAX_LENGTH_M, "m")?;
        positive_at_most("reference chord c̄", self.chord_m, MAX_LENGTH_M, "m")
    }

    /// Aspect ratio `b² / S`, –.
    pub fn aspect_ratio(&self) -> f64 {
        self.span_m * self.span_m / self.area_m2
    }
}

/// Checks an option lies in `(0, max]` (a physical bound: beyond it the number is a typing or
/// unit error, and would reach the simulator as an aircraft no one flies).
///
/// # Errors
/// Naming `name`, the value in short form ([`aeroident_physics::text::Short`]), the bound and
/// its `unit`.
pub fn positive_at_most(name: &str, v: f64, max: f64, unit: &str) -> crate::error::Result<()> {
    use aeroident_physics::text::Short;
    if !(v.is_finite() && v > 0.0 && v <= max) {
        crate::bail!("{name} must be > 0 and at most {} {unit}, got {}", Short(max), Short(v));
    }
    Ok(())
}

/// The file an export writes and the warnings to print beside it (each also a note in the
/// file).
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The file's text.
    pub text: String,
    /// One line per parameter written as zero (not identified, or not representable and
    /// dropped on request) or approximated.
    pub warnings: Vec<String>,
}

/// A summary's parameters sorted for one target.
#[derive(Debug, Clone, Default)]
pub(crate) struct Sorted {
    /// Identified values of the parameters the target represents; absent = 0.
    pub values: BTreeMap<Param, f64>,
    /// Parameters reported `null`: written as 0.
    pub not_identified: Vec<String>,
    /// Identified parameters the target cannot represent, with why.
    pub unrepresentable: Vec<String>,
}

impl Sorted {
    /// The identified value of `coefficient_term`, 0 when absent or not identified.
    pub fn value(&self, coefficient: Coefficient, term: Term) -> f64 {
        self.values.get(&Param::new(coefficient, term)).copied().unwrap_or(0.0)
    }

    /// Whether `coefficient_term` is identified (and represented) with a non-zero value.
    pub fn has(&self, coefficient: Coefficient, term: Term) -> bool {
        self.value(coefficient, term) != 0.0
    }
}

/// Sorts `summary`'s parameters: `why_not(param)` is `None` when the target represents it,
/// else the reason it cannot (not asked of a value of exactly 0, which needs no term).
pub(crate) fn sort(
    summary: &SummaryParameters,
    why_not: impl Fn(Param) -> Option<String>,
) -> Sorted {
    let mut sorted = Sorted::default();
    for p in &summary.parameters {
        let name = p.param.name();
        match (p.value, why_not(p.param)) {
            (None, _) => sorted.not_identified.push(name.to_string()),
            // A term at exactly 0 adds nothing the target's formula would have to hold.
            (Some(v), Some(why)) => {
                if v != 0.0 {
                    sorted.unrepresentable.push(format!("{name} = {v}: {why}"));
                }
            }
            (Some(v), None) => {
                sorted.values.insert(p.param, v);
            }
        }
    }
    sorted
}

/// The drag polar of the targets (module doc): `inv_k = 1/(π e AR)` and the parasitic drag
/// `CD0 − CL_0² inv_k` that makes `CD(α = 0) = CD_0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Polar {
    /// `1/(π e AR)` = `CD_alpha2 / CL_alpha²`, 0 without `CD_alpha2`.
    pub inv_k: f64,
    /// The target's zero-lift drag, `CD_0 − CL_0² inv_k`.
    pub parasitic: f64,
}

impl Polar {
    /// Oswald factor `e = 1 / (π AR inv_k)`; with no induced drag (`inv_k = 0`)
    /// [`NO_INDUCED_DRAG_OSWALD`], which makes it negligible (an `e` of 0 divides by zero).
    pub fn oswald(&self, aspect_ratio: f64) -> f64 {
        if self.inv_k == 0.0 {
            NO_INDUCED_DRAG_OSWALD
        } else {
            1.0 / (std::f64::consts::PI * aspect_ratio * self.inv_k)
        }
    }
}

/// The Oswald factor written when the model has no induced drag: `CL²/(π e AR)` is then below
/// 1e-28 of any lift coefficient, far under the float resolution of either target.
pub const NO_INDUCED_DRAG_OSWALD: f64 = 1e30;

/// The polar through `CL_0`, `CL_alpha` and `CD_alpha2` of `s`, and why `CD_alpha` (or
/// `CD_alpha2` without a lift slope) does not fit it, if it does not.
pub(crate) fn drag_polar(s: &Sorted) -> (Polar, Vec<String>) {
    use Coefficient::{CD, CL};
    let (c0, ca) = (s.value(CL, Term::Bias), s.value(CL, Term::Alpha));
    let (d1, d2) = (s.value(CD, Term::Alpha), s.value(CD, Term::Alpha2));
    let mut problems = Vec::new();
    let inv_k = if d2 == 0.0 {
        0.0
    } else if ca == 0.0 {
        problems.push(format!(
            "CD_alpha2 = {d2}: the target's α² drag is induced drag CL_alpha² α²/(π e AR), and CL_alpha is 0 or absent"
        ));
        0.0
    } else {
        d2 / (ca * ca)
    };
    let implied = 2.0 * c0 * ca * inv_k;
    if (d1 - implied).abs() > 1e-9 * d1.abs().max(implied.abs()) {
        problems.push(format!(
            "CD_alpha = {d1}: the target's drag is CD0 + (CL_0 + CL_alpha α)²/(π e AR), whose α term is 2 CL_0 CL_alpha/(π e AR) = {implied} for this CL_0, CL_alpha and CD_alpha2"
        ));
    }
    (Polar { inv_k, parasitic: s.value(CD, Term::Bias) - c0 * c0 * inv_k }, problems)
}

/// Refuses the export when `problems` is not empty and dropping was not asked for; else
/// returns the warnings: each problem (written as the target's formula gives it) and each
/// parameter not identified (written as 0).
///
/// # Errors
/// The problems, one a line, with the flag that writes them anyway.
pub(crate) fn warnings_or_refuse(
    source: &str,
    target: &str,
    sorted: &Sorted,
    problems: Vec<String>,
    drop_unrepresentable: bool,
) -> crate::error::Result<Vec<String>> {
    let unrepresentable: Vec<String> =
        sorted.unrepresentable.iter().cloned().chain(problems).collect();
    if !unrepresentable.is_empty() && !drop_unrepresentable {
        crate::bail!(
            "{source}: {target} cannot represent {} identified term(s):\n  {}\n(give --drop-unrepresentable to write them as the {target} formula allows, with a warning each)",
            unrepresentable.len(),
            unrepresentable.join("\n  ")
        );
    }
    let mut warnings: Vec<String> = unrepresentable
        .into_iter()
        .map(|u| format!("not representable, written as {target}'s formula allows: {u}"))
        .collect();
    warnings.extend(
        sorted
            .not_identified
            .iter()
            .map(|n| format!("{n}: not identified (null in the summary), written as 0")),
    );
    Ok(warnings)
}

/// Refuses a summary with nothing identified.
///
/// # Errors
/// Every parameter is `null`.
pub(crate) fn require_identified(
    summary: &SummaryParameters,
    source: &str,
) -> crate::error::Result<()> {
    if summary.parameters.iter().all(|p| p.value.is_none()) {
        crate::bail!("{source}: no parameter is identified (all null); nothing to export");
    }
    Ok(())
}

/// Why `term` cannot be a term of a target whose terms are `1, α, β, p̂, q̂, r̂` and the three
/// surfaces: the higher-order and reference-speed terms of the vocabulary.
pub(crate) fn beyond_linear(term: Term) -> Option<String> {
    match term {
        Term::Bias
        | Term::Alpha
        | Term::Beta
        | Term::P
        | Term::Q
        | Term::R
        | Term::De
        | Term::Da
        | Term::Dr => None,
        t if t.knot().is_some() => Some("an α spline; the target's model is linear in α".into()),
        Term::Alphadot => Some("the target has no α̇ term".into()),
        Term::V | Term::Q0 => Some("the target has no reference speed V0".into()),
        Term::Mach | Term::Mach2 => Some("the target has no Mach dependence".into()),
        t => Some(format!("the product term `{}` is not in the target's formula", t.name())),
    }
}
