//! Identified derivatives as the `<plugin>` element of Gazebo's `AdvancedLiftDrag` system
//! (gz-sim `src/systems/advanced_lift_drag/AdvancedLiftDrag.cc`, gazebosim/gz-sim; the same
//! elements as PX4-SITL_gazebo-classic `src/liftdrag_plugin/advanced_liftdrag_plugin.cpp`,
//! which names the reference point `ref_pt` instead of `cp`). Documented with its formula in
//! `docs/export.md`.
//!
//! The plugin works on the link's frame, forward `1 0 0` and upward `0 0 1` (a FLU link, as
//! PX4's models): body axes x forward, y right, z down; `α = atan2(w, u)`, `β = atan2(v, u)`,
//! and it normalises with the speed in the body x–z plane `V_xz = √(u² + w²)`:
//! `q̄ = ½ρV_xz²`, rate terms `C_p · p b/(2V_xz)` (b = √(area·AR)), `C_q · q mac/(2V_xz)`.
//! Lift along −z and drag along −x of the stability axes, side force along body y, moments
//! about body x, y, z; rates and moments of the link's FLU axes are flipped to FRD by the
//! plugin. With the blend `σ` of `alpha_stall` (sharpness M = 15, not configurable):
//!
//! ```text
//! CL = (1−σ)(CL0 + CLa α) + σ·flat plate + CLb β + Σ CL_ctrl θ°·dir           (+ CLp p̂ + CLq q̂ + CLr r̂)
//! CD = (1−σ)(CD0 + CL²/(π AR eff)) + σ·flat plate + Σ CD_ctrl θ°·dir           (+ CDp p̂ …)
//! CY = CYa α + CYb β + Σ CY_ctrl θ°·dir (+ CYp p̂ …);  Cl, Cn alike (Cella, Cellb …; Cena, Cenb …)
//! Cm = Cemb β + Σ Cem_ctrl θ°·dir (+ Cemp p̂ + Cemq q̂ + Cemr r̂)
//! ```
//!
//! The plugin computes `Cem0 + Cema α` and then overwrites it with `Cemb β` (`Cem = ` where
//! `Cem += ` was meant, in both sources as read), so `Cm_0` and `Cm_alpha` cannot be held by
//! `Cem0`, `Cema`. What the plugin does apply is the force at the centre of pressure `cp`
//! (`torque + cp × force`, the air velocity taken there): with `cp = (x, 0, 0)`,
//! `x = Cm_alpha c̄ / CL_alpha`, the lift's moment about the CG is the static stability
//! (`at_centre_of_pressure`). The control terms take the joint angle θ in degrees times a
//! per-degree derivative and the element's `direction`: with `direction` d and share `k` the
//! export writes `C_ctrl = k · C_δ · π/180`, and aeroident's deflection is `δ = d · θ` (one
//! joint, `k = 1`), or `δa = (d_L θ_L − d_R θ_R)/2` for an aileron pair (`k = ±½`).

use super::uav::{self, Exported, Geometry};
use crate::summary_file::SummaryParameters;
use aeroident_estimators::vocabulary::{Coefficient, Param, Term};
use std::fmt::Write as _;

/// One control surface: the model's joint and how its angle relates to aeroident's
/// deflection.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlJoint {
    /// The surface's term: [`Term::De`], [`Term::Da`] or [`Term::Dr`].
    pub surface: Term,
    /// Joint name in the model (`<name>`).
    pub joint: String,
    /// `<direction>`: +1 when the joint's positive angle is aeroident's positive deflection
    /// (δe trailing edge down, δa right aileron trailing edge down, δr trailing edge left),
    /// −1 when it is the opposite.
    pub direction: f64,
    /// The share of aeroident's derivative this joint carries: 1 for a single surface, ½ and
    /// −½ for the left and right joints of an aileron pair (each rotating the same way for the
    /// same `direction`, as PX4's `advanced_plane` servos).
    pub share: f64,
}

/// What the summary does not give.
#[derive(Debug, Clone, PartialEq)]
pub struct GazeboOptions {
    /// Reference geometry (`area`, `AR = b²/S`, `mac`).
    pub geometry: Geometry,
    /// The control surfaces (only those with a derivative in the summary are written).
    pub joints: Vec<ControlJoint>,
    /// `link_name`: the aircraft body link.
    pub link_name: String,
    /// `air_density`, kg/m³ (the plugin uses this constant, not an atmosphere).
    pub air_density_kgpm3: f64,
    /// `alpha_stall`, rad. The plugin's blend width is fixed (M = 15): at 90° the flat-plate
    /// share is below 1e-8 for |α| < 20°, at 15° it is about 4 % at α = 0.
    pub alpha_stall_rad: f64,
    /// Write terms the plugin cannot represent as its formula allows, with a warning each,
    /// instead of refusing.
    pub drop_unrepresentable: bool,
    /// What the options' files say that the plugin cannot hold (a servo), noted in the file
    /// and printed.
    pub notes: Vec<String>,
}

/// The scalar elements: aeroident's parameter and the plugin's element. `Cem0` and `Cema` are
/// last: the plugin discards them (module doc).
const ELEMENTS: [(Coefficient, Term, &str); 29] = {
    use Coefficient::*;
    use Term::*;
    [
        (CL, Bias, "CL0"),
        (CL, Alpha, "CLa"),
        (CY, Alpha, "CYa"),
        (Cl, Alpha, "Cella"),
        (Cn, Alpha, "Cena"),
        (CL, Beta, "CLb"),
        (CY, Beta, "CYb"),
        (Cl, Beta, "Cellb"),
        (Cm, Beta, "Cemb"),
        (Cn, Beta, "Cenb"),
        (CD, P, "CDp"),
        (CY, P, "CYp"),
        (CL, P, "CLp"),
        (Cl, P, "Cellp"),
        (Cm, P, "Cemp"),
        (Cn, P, "Cenp"),
        (CD, Q, "CDq"),
        (CY, Q, "CYq"),
        (CL, Q, "CLq"),
        (Cl, Q, "Cellq"),
        (Cm, Q, "Cemq"),
        (Cn, Q, "Cenq"),
        (CD, R, "CDr"),
        (CY, R, "CYr"),
        (CL, R, "CLr"),
        (Cl, R, "Cellr"),
        (Cm, R, "Cemr"),
        (Cn, R, "Cenr"),
        (Cm, Bias, "Cem0"),
    ]
};

/// The per-surface derivative elements, in the plugin's order.
const CONTROL_ELEMENTS: [(Coefficient, &str); 6] = [
    (Coefficient::CD, "CD_ctrl"),
    (Coefficient::CY, "CY_ctrl"),
    (Coefficient::CL, "CL_ctrl"),
    (Coefficient::Cl, "Cell_ctrl"),
    (Coefficient::Cm, "Cem_ctrl"),
    (Coefficient::Cn, "Cen_ctrl"),
];

/// Why the plugin cannot represent `p`, `None` if it can.
fn why_not(p: Param) -> Option<String> {
    use Coefficient::*;
    let (c, t) = (p.coefficient, p.term);
    let surface = matches!(t, Term::De | Term::Da | Term::Dr) && c != CX && c != CZ;
    let polar = c == CD && matches!(t, Term::Bias | Term::Alpha | Term::Alpha2);
    let pitch = matches!((c, t), (Cm, Term::Alpha));
    if surface || polar || pitch || ELEMENTS.iter().any(|(ec, et, _)| *ec == c && *et == t) {
        return None;
    }
    Some(match (c, t) {
        (CX | CZ, _) => "the plugin takes lift and drag, not body-axis CX/CZ".into(),
        (CY | Cl | Cn, Term::Bias) => format!("the plugin has no zero-α {} term", c.name()),
        (CD, Term::Beta) => "the plugin's drag has no β term".into(),
        _ => uav::beyond_linear(t)
            .unwrap_or_else(|| format!("the plugin's {} has no `{}` term", c.name(), t.name())),
    })
}

/// The plugin squares its whole static lift in the induced drag: with induced drag, a lift
/// term in β or a surface adds β² or δ² drag the model does not have.
fn squared_lift_problems(s: &uav::Sorted, polar: &uav::Polar) -> Vec<String> {
    if polar.inv_k == 0.0 {
        return Vec::new();
    }
    [Term::Beta, Term::De, Term::Da, Term::Dr]
        .into_iter()
        .filter(|t| s.has(Coefficient::CL, *t))
        .map(|t| {
            format!(
                "CL_{} = {}: with induced drag (CD_alpha2) the plugin's CL²/(π AR eff) squares it into a {}² drag term the model does not have",
                t.name(),
                s.value(Coefficient::CL, t),
                t.name()
            )
        })
        .collect()
}

/// The centre of pressure, m ahead of the CG (negative: aft), at which the lift's moment
/// gives `Cm_alpha`: `x = Cm_alpha c̄ / CL_alpha`; 0 without `Cm_alpha`.
///
/// # Errors
/// `Cm_alpha` without `CL_alpha` (no lift slope to carry it), as a problem line.
fn centre_of_pressure_m(s: &uav::Sorted, g: &Geometry) -> Result<f64, String> {
    let (cm_a, cl_a) =
        (s.value(Coefficient::Cm, Term::Alpha), s.value(Coefficient::CL, Term::Alpha));
    match (cm_a, cl_a) {
        (0.0, _) => Ok(0.0),
        (_, 0.0) => Err(format!(
            "Cm_alpha = {cm_a}: the plugin holds static stability only through the lift at its centre of pressure, and CL_alpha is not identified"
        )),
        _ => Ok(cm_a * g.chord_m / cl_a),
    }
}

/// `value` into `w` as `coefficient_term`, unless it is 0 and absent.
fn set(w: &mut uav::Sorted, coefficient: Coefficient, term: Term, value: f64) {
    let p = Param::new(coefficient, term);
    if value != 0.0 || w.values.contains_key(&p) {
        w.values.insert(p, value);
    }
}

/// The values to write so that the plugin, with its force at `cp = (x, 0, 0)`, gives the
/// model about the CG to first order in the flow angles: the lift's and side force's moments
/// about the CG taken out of `Cm` and `Cn` (`Cm_t − (x/c̄) CL_t`, `Cn_t − (x/b) CY_t`; so
/// `Cm_alpha` becomes 0 and `Cm_0` the residual `Cm_0 − (x/c̄) CL_0`), then the flow angles
/// at the cp (`α − (2x/c̄) q̂`, `β + (2x/b) r̂`) made up in the rate terms. Left out, second
/// order: the lift's `1 − cos α` and the drag's `sin α` in the arm, `V_xz` at the cp.
fn at_centre_of_pressure(s: &uav::Sorted, x_m: f64, g: &Geometry) -> uav::Sorted {
    use Coefficient::*;
    use Term::*;
    let (kc, kb) = (x_m / g.chord_m, x_m / g.span_m);
    let mut w = s.clone();
    for t in [Bias, Alpha, Beta, P, Q, R, De, Da, Dr] {
        set(&mut w, Cm, t, s.value(Cm, t) - kc * s.value(CL, t));
        set(&mut w, Cn, t, s.value(Cn, t) - kb * s.value(CY, t));
    }
    // Exactly: x was chosen for it.
    set(&mut w, Cm, Alpha, 0.0);
    for c in [CL, CY, Cl, Cm, Cn] {
        let (q, r) = (
            w.value(c, Q) + 2.0 * kc * w.value(c, Alpha),
            w.value(c, R) - 2.0 * kb * w.value(c, Beta),
        );
        set(&mut w, c, Q, q);
        set(&mut w, c, R, r);
    }
    w
}

/// What the centre of pressure holds, and the `Cm_0` residual a plugin as read discards (with
/// the trim elevator it shifts), as notes.
fn pitch_notes(s: &uav::Sorted, w: &uav::Sorted, x_m: f64) -> Vec<String> {
    use aeroident_physics::text::Short;
    let mut notes = Vec::new();
    if x_m != 0.0 {
        notes.push(format!(
            "static pitch stability through the centre of pressure: cp = {} m (Cm_alpha c̄ / CL_alpha), Cm and Cn terms corrected for the lift and side force acting there, rate terms for the flow angles there; Cema = 0",
            Short(x_m)
        ));
    }
    let residual = w.value(Coefficient::Cm, Term::Bias);
    if residual != 0.0 {
        let cm_de = s.value(Coefficient::Cm, Term::De);
        let trim = if cm_de != 0.0 {
            format!(
                ": it trims with δe shifted by {} rad (residual / Cm_de)",
                Short(residual / cm_de)
            )
        } else {
            String::new()
        };
        notes.push(format!(
            "Cm_0 − (x/c̄) CL_0 = {} written to Cem0, which a corrected plugin adds but the plugin as read (AdvancedLiftDrag.cc) discards{trim}",
            Short(residual)
        ));
    }
    notes
}

/// Checks the options the plugin divides by.
fn check_options(o: &GazeboOptions) -> crate::error::Result<()> {
    use super::uav::positive_at_most;
    o.geometry.check()?;
    // Sea-level air is 1.225 kg/m³; no flight condition reaches 2.
    positive_at_most("air density", o.air_density_kgpm3, 2.0, "kg/m³")?;
    positive_at_most("alpha_stall", o.alpha_stall_rad, uav::MAX_STALL_DEG.to_radians(), "rad")?;
    for j in &o.joints {
        if j.direction.abs() != 1.0 {
            crate::bail!(
                "joint `{}`: direction must be 1 or -1, got {}",
                j.joint,
                aeroident_physics::text::Short(j.direction)
            );
        }
        if !(j.share.is_finite() && j.share != 0.0 && j.share.abs() <= 1.0) {
            crate::bail!(
                "joint `{}`: share must be in [-1, 1] and not 0, got {}",
                j.joint,
                aeroident_physics::text::Short(j.share)
            );
        }
    }
    Ok(())
}

/// Writes the `AdvancedLiftDrag` `<plugin>` element for the identified parameters; `source`
/// is named in the notes and messages.
///
/// # Errors
/// An option out of range ([`Geometry::check`], density, stall angle, a direction not ±1),
/// nothing identified, a surface derivative without its joint in `o.joints`, or (without
/// `drop_unrepresentable`) any identified term the plugin cannot hold, each named with why.
pub fn gazebo_plugin_sdf(
    summary: &SummaryParameters,
    source: &str,
    o: &GazeboOptions,
) -> crate::error::Result<Exported> {
    check_options(o)?;
    uav::require_identified(summary, source)?;
    let sorted = uav::sort(summary, why_not);
    let (polar, mut problems) = uav::drag_polar(&sorted);
    problems.extend(squared_lift_problems(&sorted, &polar));
    let x_cp = centre_of_pressure_m(&sorted, &o.geometry).unwrap_or_else(|p| {
        problems.push(p);
        0.0
    });
    let joints = used_joints(&sorted, o, source)?;
    let mut warnings = uav::warnings_or_refuse(
        source,
        "Gazebo AdvancedLiftDrag",
        &sorted,
        problems,
        o.drop_unrepresentable,
    )?;
    warnings.push(
        "the plugin normalises with the speed in the body x-z plane, √(u²+w²) = V cos β: at β ≠ 0 its forces and moments differ from the model's by that factor; see docs/export.md".into(),
    );
    let written = at_centre_of_pressure(&sorted, x_cp, &o.geometry);
    warnings.extend(pitch_notes(&sorted, &written, x_cp));
    warnings.extend(o.notes.iter().cloned());
    let header = format!(
        "Generated by `aeroident export gazebo` from {source} (estimator {}, model {}). Derivatives per rad and per normalised rate; control derivatives per degree of joint angle; formula and signs: docs/export.md.",
        summary.estimator, summary.model
    );
    let mut x = String::new();
    x.push_str("<plugin filename=\"gz-sim-advanced-lift-drag-system\" name=\"gz::sim::systems::AdvancedLiftDrag\">\n");
    for note in std::iter::once(&header).chain(&warnings) {
        let _ = writeln!(x, "  <!-- {} -->", comment(note));
    }
    write_scalars(&mut x, &written, &polar, o, x_cp);
    let _ = writeln!(x, "  <num_ctrl_surfaces>{}</num_ctrl_surfaces>", joints.len());
    for j in joints {
        write_surface(&mut x, &written, j);
    }
    x.push_str("</plugin>\n");
    Ok(Exported { text: x, warnings })
}

/// The joints of the surfaces the summary has a derivative of.
///
/// # Errors
/// A surface with a derivative and no joint in the options.
fn used_joints<'a>(
    s: &uav::Sorted,
    o: &'a GazeboOptions,
    source: &str,
) -> crate::error::Result<Vec<&'a ControlJoint>> {
    let mut used = Vec::new();
    for surface in [Term::De, Term::Da, Term::Dr] {
        if !s.values.keys().any(|p| p.term == surface) {
            continue;
        }
        let before = used.len();
        used.extend(o.joints.iter().filter(|j| j.surface == surface));
        if used.len() == before {
            crate::bail!(
                "{source}: the model has `{}` derivatives but no control joint is given for it (--{}-joint)",
                surface.name(),
                surface.name()
            );
        }
    }
    Ok(used)
}

/// The model-wide elements.
fn write_scalars(
    x: &mut String,
    s: &uav::Sorted,
    polar: &uav::Polar,
    o: &GazeboOptions,
    x_cp: f64,
) {
    let g = &o.geometry;
    let mut el = |name: &str, v: String| {
        let _ = writeln!(x, "  <{name}>{v}</{name}>");
    };
    el("link_name", xml_text(&o.link_name));
    el("area", num(g.area_m2));
    el("AR", num(g.aspect_ratio()));
    el("mac", num(g.chord_m));
    el("eff", num(polar.oswald(g.aspect_ratio())));
    el("air_density", num(o.air_density_kgpm3));
    el("forward", "1 0 0".into());
    el("upward", "0 0 1".into());
    el("cp", format!("{} 0 0", num(x_cp)));
    el("alpha_stall", num(o.alpha_stall_rad));
    el("Cema_stall", num(0.0));
    el("CD0", num(polar.parasitic));
    for (c, t, name) in ELEMENTS {
        el(name, num(s.value(c, t)));
    }
    el("Cema", num(s.value(Coefficient::Cm, Term::Alpha)));
}

/// One `<control_surface>`: per-degree derivatives (module doc).
fn write_surface(x: &mut String, s: &uav::Sorted, j: &ControlJoint) {
    let _ = writeln!(x, "  <control_surface>");
    let _ = writeln!(x, "    <name>{}</name>", xml_text(&j.joint));
    let _ = writeln!(x, "    <direction>{}</direction>", num(j.direction));
    for (c, name) in CONTROL_ELEMENTS {
        let per_degree = j.share * s.value(c, j.surface) * std::f64::consts::PI / 180.0;
        let _ = writeln!(x, "    <{name}>{}</{name}>", num(per_degree));
    }
    let _ = writeln!(x, "  </control_surface>");
}

/// `v` as text that reads back to the same f64.
fn num(v: f64) -> String {
    // `+ 0.0` writes −0 (a negated zero derivative) as 0.
    format!("{:?}", v + 0.0)
}

/// `s` as XML text: the markup characters escaped.
fn xml_text(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// `s` as comment content: as [`xml_text`], and `--` (not allowed in a comment) split.
fn comment(s: &str) -> String {
    xml_text(s).replace("--", "- -")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn param(name: &str) -> Param {
        Param::from_name(name).unwrap()
    }

    #[test]
    fn each_term_the_plugin_cannot_hold_says_why() {
        for (name, why) in [
            ("CX_alpha", "body-axis CX/CZ"),
            ("CY_0", "no zero-α CY"),
            ("Cl_0", "no zero-α Cl"),
            ("Cn_0", "no zero-α Cn"),
            ("CD_beta", "drag has no β"),
            ("Cm_alphadot", "no α̇ term"),
        ] {
            let got = why_not(param(name)).unwrap_or_default();
            assert!(got.contains(why), "{name}: {got}");
        }
        for held in ["Cm_alpha", "Cm_0", "CD_alpha2", "Cn_dr", "CL_beta"] {
            assert_eq!(why_not(param(held)), None, "{held}");
        }
    }

    fn options(direction: f64, share: f64) -> GazeboOptions {
        GazeboOptions {
            geometry: Geometry { area_m2: 0.4, span_m: 1.6, chord_m: 0.25 },
            joints: vec![ControlJoint { surface: Term::Da, joint: "a".into(), direction, share }],
            link_name: "base_link".into(),
            air_density_kgpm3: 1.2,
            alpha_stall_rad: 1.0,
            drop_unrepresentable: false,
            notes: vec![],
        }
    }

    #[test]
    fn a_joint_direction_and_share_at_their_bounds() {
        for (d, s) in [(1.0, 1.0), (-1.0, -1.0), (1.0, 0.5), (1.0, -0.5)] {
            assert!(check_options(&options(d, s)).is_ok(), "{d} {s}");
        }
        for (d, s, what) in [
            (0.5, 1.0, "direction"),
            (1.0, 0.0, "share"),
            (1.0, 1.0001, "share"),
            (1.0, -1.0001, "share"),
            (1.0, f64::NAN, "share"),
        ] {
            let e = check_options(&options(d, s)).unwrap_err().to_string();
            assert!(e.contains(what) && e.contains("joint `a`"), "{d} {s}: {e}");
        }
    }

    #[test]
    fn the_centre_of_pressure_needs_a_lift_slope_and_is_zero_without_cm_alpha() {
        let g = Geometry { area_m2: 0.4, span_m: 1.6, chord_m: 0.25 };
        let sorted = |pairs: &[(&str, f64)]| {
            let mut s = uav::Sorted::default();
            for (n, v) in pairs {
                s.values.insert(param(n), *v);
            }
            s
        };
        assert_eq!(centre_of_pressure_m(&sorted(&[("CL_alpha", 5.0)]), &g), Ok(0.0));
        assert_eq!(centre_of_pressure_m(&sorted(&[]), &g), Ok(0.0));
        let x = centre_of_pressure_m(&sorted(&[("CL_alpha", 5.0), ("Cm_alpha", -1.0)]), &g);
        assert_eq!(x, Ok(-0.25 / 5.0));
        let e = centre_of_pressure_m(&sorted(&[("Cm_alpha", -1.0)]), &g).unwrap_err();
        assert!(e.contains("CL_alpha is not identified"), "{e}");
        // A zero value is not written where the term is absent, but kept where present.
        let mut w = sorted(&[("Cn_r", -0.1)]);
        set(&mut w, Coefficient::Cn, Term::P, 0.0);
        set(&mut w, Coefficient::Cn, Term::R, 0.0);
        assert!(!w.values.contains_key(&param("Cn_p")) && w.values[&param("Cn_r")] == 0.0);
    }
}
