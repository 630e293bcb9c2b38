//! Identified derivatives as ArduPilot SITL's plane coefficient file: the JSON `SIM_Plane`
//! loads with `--model plane:FILE.json` (`Plane::load_coeffs`, keys named as the
//! `coefficient` fields of `libraries/SITL/SIM_Plane.h`, ArduPilot/ardupilot). Documented with
//! its formula in `docs/export.md`.
//!
//! SITL's plane (`Plane::getForce`, `Plane::getTorque`, `libraries/SITL/SIM_Plane.cpp`) works
//! in body axes (x forward, y right, z down) about the CG (`CGOffset` 0), with `α = atan2(w, u)`,
//! `β = atan2(v, u)`, gyro rates normalised `p b/2V`, `q c/2V`, `r b/2V`, and `q̄ = ½ρV²S`:
//!
//! ```text
//! CL = (1−σ)(c_lift_0 + c_lift_a α) + σ·2 sign(α) sin²α cos α  + c_lift_q q̂ + c_lift_deltae u_e
//! CD = c_drag_p + (c_lift_0 + c_lift_a α)²/(π oswald b²/s) + c_drag_q q̂ + c_drag_deltae |u_e|
//! X = q̄(−CD cos α + CL sin α)     Z = q̄(−CD sin α − CL cos α)
//! Y = q̄(c_y_0 + c_y_b β + c_y_p p̂ + c_y_r r̂ + c_y_deltaa u_a + c_y_deltar u_r)
//! L = q̄ b (c_l_0 + c_l_b β + c_l_p p̂ + c_l_r r̂ + c_l_deltaa u_a + c_l_deltar u_r)
//! M = q̄ c (c_m_0 + c_m_a α + c_m_q q̂ + c_m_deltae u_e)
//! N = q̄ b (c_n_0 + c_n_b β + c_n_p p̂ + c_n_r r̂ + c_n_deltaa u_a + c_n_deltar u_r)
//! ```
//!
//! `σ` is the stall blend of `mcoeff` and `alpha_stall`. The surface inputs `u` are the servo
//! commands normalised to ±1 (`(pwm − 1500)/500`), each positive for a positive body moment
//! (aileron: right wing down, elevator: nose up, rudder: nose right), so for aeroident's
//! deflections (δe > 0 trailing edge down, δa > 0 rolling left, δr > 0 nose left) `u = −δ/δmax`
//! with `δmax` the surface's full throw (`deltaa_max` … in the file): every control derivative
//! is written as `−C_δ · δmax`.
//!
//! SITL's equations cannot hold the aircraft's mass and inertia: `calculate_forces` divides
//! the force by the plane's own mass (2 kg; 8 kg with `-heavy`, 22 kg with `-jet`) and
//! `Aircraft::update_dynamics` integrates `ω̇ = (L, M, N)`, unit inertia without the
//! gyroscopic terms (`libraries/SITL/SIM_Aircraft.cpp`). So the coefficients are transformed
//! to give the identified aircraft's accelerations (`sitl_coefficient`): force coefficients
//! times `m_SITL / m`, moment coefficients through the inverse inertia tensor (Stevens &
//! Lewis §2.5: `ṗ = c3 L + c4 N`, `q̇ = c7 M`, `ṙ = c4 L + c9 N` without the rate products).

use super::uav::{self, Exported, Geometry};
use crate::summary_file::SummaryParameters;
use aeroident_estimators::vocabulary::{Coefficient, Param, Term};
use aeroident_io::{Channel, Mapping};
use aeroident_models::aircraft::AircraftMass;
use aeroident_physics::rigid_body::InertiaConstants;
use aeroident_physics::text::Short;
use std::fmt::Write as _;

/// Full throw of each surface, rad: the deflection at a servo command of ±1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Throws {
    /// Aileron, rad (`deltaa_max`).
    pub aileron_rad: f64,
    /// Elevator, rad (`deltae_max`).
    pub elevator_rad: f64,
    /// Rudder, rad (`deltar_max`).
    pub rudder_rad: f64,
}

impl Default for Throws {
    /// SITL's own: 0.3491 rad (20°) each.
    fn default() -> Self {
        Self { aileron_rad: 0.3491, elevator_rad: 0.3491, rudder_rad: 0.3491 }
    }
}

/// What the summary does not give.
#[derive(Debug, Clone, PartialEq)]
pub struct ArdupilotOptions {
    /// Reference geometry (`s`, `b`, `c`).
    pub geometry: Geometry,
    /// Surface throws.
    pub throws: Throws,
    /// Stall angle of the lift blend, rad (`alpha_stall`; SITL's default 0.4712).
    pub alpha_stall_rad: f64,
    /// Sharpness of the lift blend, 1/rad (`mcoeff`; SITL's default 50).
    pub mcoeff: f64,
    /// Write terms SITL cannot represent as its formula allows (0, or the polar's value) with
    /// a warning each, instead of refusing.
    pub drop_unrepresentable: bool,
    /// The identified aircraft's mass and inertia (SI, Stevens & Lewis `Jxz`): the
    /// coefficients are scaled so that SITL's equations give its accelerations (module doc).
    pub mass: AircraftMass,
    /// The mass SITL's plane divides its forces by, kg ([`SITL_MASS_KG`] for the default
    /// frame).
    pub sitl_mass_kg: f64,
    /// What the options' files say that the file cannot (where throws not given came from,
    /// [`mapped_throw`]; a servo SITL models its own way), noted in the file and printed.
    pub notes: Vec<String>,
}

/// A surface's throw read from a mapping, and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedThrow {
    /// The throw, rad: the mean of the two ends' magnitudes (SITL's is symmetric).
    pub rad: f64,
    /// Where it came from, and the two ends when they differ by more than 10 %.
    pub note: String,
}

/// The throw of surface channel `ch` (`de`, `da`, `dr`) in mapping `m`: its actuator's
/// position limits, else the ends of its calibration table; `None` when it has neither or
/// they do not straddle 0.
pub fn mapped_throw(m: &Mapping, ch: Channel) -> Option<MappedThrow> {
    let (lo, hi, from) = match (m.actuators.get(&ch), m.channels.get(&ch)) {
        (Some(a), _) if a.position_limits_rad.0.is_finite() => {
            (a.position_limits_rad.0, a.position_limits_rad.1, "actuator position limits")
        }
        (_, Some(c)) if c.calibration.is_some() => {
            let t = c.calibration.as_ref()?;
            let ends = [t.first()?.0, t.last()?.0].map(|raw| c.to_si(raw));
            (ends[0].min(ends[1]), ends[0].max(ends[1]), "calibration range")
        }
        _ => return None,
    };
    if !(lo < 0.0 && hi > 0.0) {
        return None;
    }
    let rad = 0.5 * (hi - lo);
    let mut note = format!(
        "{} throw {}° from the mapping's {from} ({} to {}°)",
        ch.key(),
        Short(rad.to_degrees()),
        Short(lo.to_degrees()),
        Short(hi.to_degrees())
    );
    if (hi + lo).abs() > 0.1 * rad {
        note.push_str(": the ends differ and SITL's throw is symmetric, so the mean is written");
    }
    Some(MappedThrow { rad, note })
}

/// SITL's plane mass, kg (`Plane::Plane`: 2 kg; the `-heavy` frame 8 kg, `-jet` 22 kg).
pub const SITL_MASS_KG: f64 = 2.0;

/// The largest aircraft mass taken, kg: above the heaviest aircraft flown (An-225, 640 t), so
/// a larger number is a typing or unit error.
pub const MAX_MASS_KG: f64 = 1.0e6;

/// The coefficient keys: aeroident's parameter and SITL's key. The control derivatives are
/// scaled by `−δmax` (module doc); the drag terms come from [`uav::drag_polar`].
const KEYS: [(Coefficient, Term, &str); 27] = {
    use Coefficient::*;
    use Term::*;
    [
        (CL, Bias, "c_lift_0"),
        (CL, De, "c_lift_deltae"),
        (CL, Alpha, "c_lift_a"),
        (CL, Q, "c_lift_q"),
        (CD, Q, "c_drag_q"),
        (CY, Bias, "c_y_0"),
        (CY, Beta, "c_y_b"),
        (CY, P, "c_y_p"),
        (CY, R, "c_y_r"),
        (CY, Da, "c_y_deltaa"),
        (CY, Dr, "c_y_deltar"),
        (Cl, Bias, "c_l_0"),
        (Cl, P, "c_l_p"),
        (Cl, Beta, "c_l_b"),
        (Cl, R, "c_l_r"),
        (Cl, Da, "c_l_deltaa"),
        (Cl, Dr, "c_l_deltar"),
        (Cm, Bias, "c_m_0"),
        (Cm, Alpha, "c_m_a"),
        (Cm, Q, "c_m_q"),
        (Cm, De, "c_m_deltae"),
        (Cn, Bias, "c_n_0"),
        (Cn, Beta, "c_n_b"),
        (Cn, P, "c_n_p"),
        (Cn, R, "c_n_r"),
        (Cn, Da, "c_n_deltaa"),
        (Cn, Dr, "c_n_deltar"),
    ]
};

/// Why SITL's plane cannot represent `p`, `None` if it can.
fn why_not(p: Param) -> Option<String> {
    use Coefficient::*;
    let drag_polar = matches!(p.term, Term::Bias | Term::Alpha | Term::Alpha2);
    if p.coefficient == CD && drag_polar {
        return None;
    }
    if KEYS.iter().any(|(c, t, _)| *c == p.coefficient && *t == p.term) {
        return None;
    }
    Some(match (p.coefficient, p.term) {
        (CX | CZ, _) => "SITL's plane takes lift and drag, not body-axis CX/CZ".into(),
        (CD, Term::De) => {
            "SITL's elevator drag is c_drag_deltae·|δe| (even in δe), not linear".into()
        }
        (_, t) => uav::beyond_linear(t).unwrap_or_else(|| {
            format!("SITL's {} has no `{}` term", p.coefficient.name(), t.name())
        }),
    })
}

/// The surface throw scaling a derivative of `term` to SITL's ±1 command: `−δmax` for the
/// surfaces (module doc), 1 otherwise.
fn command_scale(term: Term, throws: &Throws) -> f64 {
    match term {
        Term::De => -throws.elevator_rad,
        Term::Da => -throws.aileron_rad,
        Term::Dr => -throws.rudder_rad,
        _ => 1.0,
    }
}

/// The value SITL's key for `coefficient_term` gets (module doc): the force coefficients
/// times `m_SITL / m`, the pitching moment's times `c7 = 1/Jy`, the rolling and yawing
/// moments' mixed through `c3, c4, c9` (both are per `q̄ S b`), then the surface scaling
/// ([`command_scale`]).
fn sitl_coefficient(
    sorted: &uav::Sorted,
    (coefficient, term): (Coefficient, Term),
    o: &ArdupilotOptions,
    ic: &InertiaConstants,
) -> f64 {
    use Coefficient::*;
    let v = |c| sorted.value(c, term);
    let scaled = match coefficient {
        Cm => ic.c7 * v(Cm),
        Cl => ic.c3 * v(Cl) + ic.c4 * v(Cn),
        Cn => ic.c4 * v(Cl) + ic.c9 * v(Cn),
        _ => o.sitl_mass_kg / o.mass.mass_kg * v(coefficient),
    };
    scaled * command_scale(term, &o.throws)
}

/// The inertia constants of the aircraft, its mass and SITL's mass checked.
///
/// # Errors
/// A mass outside `(0, MAX_MASS_KG]`, or an inertia that is not a body's
/// ([`InertiaConstants::from_inertia`]), naming it.
fn inertia_constants(o: &ArdupilotOptions) -> crate::error::Result<InertiaConstants> {
    use super::uav::positive_at_most;
    positive_at_most("aircraft mass", o.mass.mass_kg, MAX_MASS_KG, "kg")?;
    positive_at_most("SITL's plane mass", o.sitl_mass_kg, MAX_MASS_KG, "kg")?;
    let m = &o.mass;
    InertiaConstants::from_inertia(m.jx_kgm2, m.jy_kgm2, m.jz_kgm2, m.jxz_kgm2)
        .map_err(|e| crate::err!("aircraft inertia: {e}"))
}

/// What SITL's equations do not hold, noted in the file and printed: the transform and
/// what is left out.
fn transform_notes(o: &ArdupilotOptions) -> Vec<String> {
    let m = &o.mass;
    vec![
        format!(
            "scaled for SITL's equations: force coefficients (lift, drag, side force) × {} ({} kg SITL mass / {} kg aircraft), moment coefficients through the aircraft's inverse inertia (Jx {}, Jy {}, Jz {}, Jxz {} kg·m²; SITL applies the moment as the angular acceleration), so they are per kg·m²; see docs/export.md",
            Short(o.sitl_mass_kg / m.mass_kg),
            Short(o.sitl_mass_kg),
            Short(m.mass_kg),
            Short(m.jx_kgm2),
            Short(m.jy_kgm2),
            Short(m.jz_kgm2),
            Short(m.jxz_kgm2)
        ),
        "not held by SITL's plane: the gyroscopic terms ω × Jω (SITL integrates ω̇ from the moment alone), the identified thrust (SITL's own: throttle × m_SITL·g / 1.2), and the lift beyond alpha_stall (SITL's flat plate, unscaled)".into(),
    ]
}

/// Checks the options SITL divides by or blends with.
fn check_options(o: &ArdupilotOptions) -> crate::error::Result<()> {
    use super::uav::positive_at_most;
    o.geometry.check()?;
    let t = &o.throws;
    let max_throw = uav::MAX_THROW_DEG.to_radians();
    for (name, v) in [
        ("aileron throw", t.aileron_rad),
        ("elevator throw", t.elevator_rad),
        ("rudder throw", t.rudder_rad),
    ] {
        positive_at_most(name, v, max_throw, "rad")?;
    }
    positive_at_most("alpha_stall", o.alpha_stall_rad, uav::MAX_STALL_DEG.to_radians(), "rad")?;
    if !(o.mcoeff.is_finite() && o.mcoeff > 0.0) {
        crate::bail!("mcoeff must be a positive finite number, got {}", Short(o.mcoeff));
    }
    // SITL clamps α to alpha_stall ± 0.8 and evaluates exp(mcoeff (α + alpha_stall)) in
    // double: beyond e^709 it overflows to inf and the lift becomes NaN.
    if o.mcoeff * (2.0 * o.alpha_stall_rad + 0.8) > 700.0 {
        crate::bail!(
            "mcoeff {} with alpha_stall {} rad overflows SITL's stall blend (mcoeff·(2 alpha_stall + 0.8) must stay below 700)",
            Short(o.mcoeff),
            Short(o.alpha_stall_rad)
        );
    }
    Ok(())
}

/// Writes SITL's plane coefficient JSON for the identified parameters; `source` is named in
/// the notes and messages.
///
/// # Errors
/// An option out of range ([`Geometry::check`], a non-positive throw, stall angle or
/// `mcoeff`, a blend that overflows, a mass out of range or an inertia no body has),
/// nothing identified, or (without
/// `drop_unrepresentable`) any identified term SITL's formula cannot hold, each named with why.
pub fn ardupilot_json(
    summary: &SummaryParameters,
    source: &str,
    o: &ArdupilotOptions,
) -> crate::error::Result<Exported> {
    check_options(o)?;
    let ic = inertia_constants(o)?;
    uav::require_identified(summary, source)?;
    let sorted = uav::sort(summary, why_not);
    let (polar, problems) = uav::drag_polar(&sorted);
    let mut warnings = uav::warnings_or_refuse(
        source,
        "ArduPilot SITL",
        &sorted,
        problems,
        o.drop_unrepresentable,
    )?;
    warnings.extend(transform_notes(o));
    warnings.extend(o.notes.iter().cloned());
    let g = &o.geometry;
    let k = o.sitl_mass_kg / o.mass.mass_kg;
    let mut entries: Vec<(String, String)> = vec![
        ("s".into(), num(g.area_m2)),
        ("b".into(), num(g.span_m)),
        ("c".into(), num(g.chord_m)),
        ("mcoeff".into(), num(o.mcoeff)),
        // The induced drag is (k CL)² / (π e' AR) = k CL² / (π e AR) with e' = k e.
        ("oswald".into(), num(k * polar.oswald(g.aspect_ratio()))),
        ("alpha_stall".into(), num(o.alpha_stall_rad)),
        ("c_drag_p".into(), num(k * polar.parasitic)),
        // Only |δe| drag exists in SITL; aeroident's vocabulary has none.
        ("c_drag_deltae".into(), num(0.0)),
    ];
    for (c, t, key) in KEYS {
        entries.push((key.into(), num(sitl_coefficient(&sorted, (c, t), o, &ic))));
    }
    let th = &o.throws;
    for (key, v) in [
        ("deltaa_max", th.aileron_rad),
        ("deltae_max", th.elevator_rad),
        ("deltar_max", th.rudder_rad),
    ] {
        entries.push((key.into(), num(v)));
    }
    entries.push(("CGOffset".into(), "[0.0, 0.0, 0.0]".into()));
    let header = format!(
        "Generated by `aeroident export ardupilot` from {source} (estimator {}, model {}). Derivatives per rad and per normalised rate, scaled to SITL's mass and unit inertia (notes below); control derivatives per unit servo command (±1 = ±delta*_max rad, positive = positive body moment); moments about the CG (CGOffset 0). Formula, scaling and signs: docs/export.md.",
        summary.estimator, summary.model
    );
    Ok(Exported { text: render(&header, &entries, &warnings), warnings })
}

/// `v` as a JSON number that reads back to the same f64.
fn num(v: f64) -> String {
    // `+ 0.0` writes −0 (a negated zero derivative) as 0.
    format!("{:?}", v + 0.0)
}

/// The JSON object: the notes first (a key SITL does not read), then the entries in order.
fn render(header: &str, entries: &[(String, String)], warnings: &[String]) -> String {
    let quoted = |s: &str| serde_json::Value::String(s.to_string()).to_string();
    let mut x = String::from("{\n");
    let notes: Vec<String> =
        std::iter::once(header).chain(warnings.iter().map(String::as_str)).map(quoted).collect();
    let _ =
        writeln!(x, "    \"aeroident_notes\": [\n        {}\n    ],", notes.join(",\n        "));
    let body: Vec<String> =
        entries.iter().map(|(k, v)| format!("    {}: {v}", quoted(k))).collect();
    x.push_str(&body.join(",\n"));
    x.push_str("\n}\n");
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mapping with the surface channel lines `surfaces` (mass 3 kg: the rest does not
    /// matter here).
    fn mapping(surfaces: &str) -> Mapping {
        let text = format!(
            "description = \"t\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = {{ column = \"v\", unit = \"m/s\" }}\nalpha = {{ column = \"a\", unit = \"rad\" }}\nqbar = {{ column = \"q\", unit = \"Pa\" }}\nmass = {{ value = 3.0, unit = \"kg\" }}\nS = {{ value = 0.4, unit = \"m2\" }}\n{surfaces}"
        );
        Mapping::from_toml_str(&text, "t.toml").unwrap()
    }

    #[test]
    fn a_throw_from_the_actuator_limits_the_calibration_or_nothing() {
        let act = |lo: f64, hi: f64| {
            format!(
                "de = {{ column = \"de\", unit = \"rad\", actuator = {{ tau_s = 0.05, position_limits_rad = [{lo}, {hi}] }} }}\n"
            )
        };
        // The mean of the two ends' magnitudes; a note past 10 % of it apart.
        let t = mapped_throw(&mapping(&act(-0.4, 0.3)), Channel::De).unwrap();
        assert!((t.rad - 0.35).abs() < 1e-15 && t.note.contains("differ"), "{t:?}");
        let t = mapped_throw(&mapping(&act(-0.3, 0.3)), Channel::De).unwrap();
        assert!(t.rad == 0.3 && !t.note.contains("differ") && t.note.contains("actuator"), "{t:?}");
        // |hi + lo| against 0.1 · rad on both sides of the edge (rad 0.5).
        assert!(
            !mapped_throw(&mapping(&act(-0.52, 0.48)), Channel::De)
                .unwrap()
                .note
                .contains("differ")
        );
        assert!(
            mapped_throw(&mapping(&act(-0.53, 0.47)), Channel::De).unwrap().note.contains("differ")
        );
        // Limits that do not straddle 0 are no throw; an actuator without limits falls to
        // the calibration.
        assert_eq!(mapped_throw(&mapping(&act(0.1, 0.3)), Channel::De), None);
        assert_eq!(mapped_throw(&mapping(&act(-0.3, -0.1)), Channel::De), None);
        assert_eq!(mapped_throw(&mapping(&act(0.0, 0.3)), Channel::De), None);
        assert_eq!(mapped_throw(&mapping(&act(-0.3, 0.0)), Channel::De), None);
        // Exactly 10 % apart (binary fractions: |hi + lo| 0.125 = 0.1 · 1.25): no note.
        let t = mapped_throw(&mapping(&act(-1.1875, 1.3125)), Channel::De).unwrap();
        assert!(t.rad == 1.25 && !t.note.contains("differ"), "{t:?}");
        let cal = "da = { column = \"da\", unit = \"deg\", calibration = [[-100.0, -20.0], [0.0, 0.0], [100.0, 30.0]], actuator = { tau_s = 0.05 } }\n";
        let t = mapped_throw(&mapping(cal), Channel::Da).unwrap();
        assert!((t.rad - 25f64.to_radians()).abs() < 1e-15 && t.note.contains("calibration"));
        assert_eq!(mapped_throw(&mapping(cal), Channel::De), None);
        let plain = "dr = { column = \"dr\", unit = \"rad\" }\n";
        assert_eq!(mapped_throw(&mapping(plain), Channel::Dr), None);
    }

    fn options() -> ArdupilotOptions {
        ArdupilotOptions {
            geometry: Geometry { area_m2: 0.4, span_m: 1.6, chord_m: 0.25 },
            throws: Throws::default(),
            alpha_stall_rad: 0.4,
            mcoeff: 50.0,
            drop_unrepresentable: false,
            mass: AircraftMass {
                mass_kg: 3.0,
                jx_kgm2: 0.2,
                jy_kgm2: 0.3,
                jz_kgm2: 0.4,
                jxz_kgm2: 0.0,
            },
            sitl_mass_kg: SITL_MASS_KG,
            notes: vec![],
        }
    }

    #[test]
    fn the_stall_blend_at_its_overflow_edge_and_each_bound() {
        assert!(check_options(&options()).is_ok());
        // mcoeff (2 α_s + 0.8) = 700 exactly is taken; above it refused (α_s 0.3: 1.4).
        let at = |mcoeff: f64| ArdupilotOptions { alpha_stall_rad: 0.3, mcoeff, ..options() };
        assert!(check_options(&at(500.0)).is_ok());
        let e = check_options(&at(500.1)).unwrap_err().to_string();
        assert!(e.contains("overflows"), "{e}");
        for bad in [0.0, -1.0, f64::NAN] {
            assert!(check_options(&ArdupilotOptions { mcoeff: bad, ..options() }).is_err());
        }
        let throws = Throws { rudder_rad: 0.0, ..Throws::default() };
        let e = check_options(&ArdupilotOptions { throws, ..options() }).unwrap_err();
        assert!(e.to_string().contains("rudder throw"), "{e}");
        let e = check_options(&ArdupilotOptions { alpha_stall_rad: 0.0, ..options() });
        assert!(e.unwrap_err().to_string().contains("alpha_stall"));
        let heavy = ArdupilotOptions { sitl_mass_kg: 2e6, ..options() };
        assert!(inertia_constants(&heavy).unwrap_err().to_string().contains("SITL's plane mass"));
    }
}
