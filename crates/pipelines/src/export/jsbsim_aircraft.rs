//! A complete JSBSim aircraft (`<fdm_config>`) flying the identified derivatives: the
//! mapping's metrics, mass and inertia, its thrust (commanded, or its `[thrust_model]` law as
//! a JSBSim function) as an external force along the thrust line, its actuators as JSBSim
//! `<actuator>` components, and the [`super::jsbsim::aerodynamics_xml_in`] fragment in
//! JSBSim's stability axes. Written in SI
//! with JSBSim's unit attributes (JSBSim converts them; JSBSim reference manual, "Metrics",
//! "Mass Balance", "External Reactions", "Flight Control"). Documented in `docs/export.md`.
//!
//! The inputs a user (or a script) sets, aeroident's signs (Stevens & Lewis): `fcs/elevator-cmd-rad`
//! (> 0 trailing edge down), `fcs/aileron-cmd-rad` (> 0 a negative rolling moment),
//! `fcs/rudder-cmd-rad` (> 0 trailing edge left), and the engine command: `fcs/thrust-cmd-n`
//! (N), `fcs/throttle-cmd-norm` (0–1, the throttle law) or `fcs/prop-speed-cmd-rad_sec` (the
//! propeller law). The surfaces are `fcs/elevator-pos-rad`, `fcs/rudder-pos-rad` and
//! `fcs/left-aileron-pos-rad` (JSBSim's aileron sign, −δa), through each surface's actuator
//! (`τ δ̇ = u − δ` as JSBSim's `lag` 1/τ, its rate limit and its position limits) or
//! directly when the mapping declares none. The CG is the structural origin; the thrust acts
//! at `z = −arm / cos i` (JSBSim's structural z is up) along `(cos i, 0, −sin i)` in body
//! axes, so its pitching moment is `arm · T`.

use super::jsbsim::{ForceAxes, SurfaceProperties, aerodynamics_xml_in};
use crate::airframe::{Airframe, Propulsion};
use crate::summary_file::SummaryParameters;
use aeroident_io::mapping::{Actuator, Channel};
use aeroident_io::thrust_model::ThrustModel;
use std::collections::BTreeMap;
use std::fmt::Write as _;

use aeroident_physics::units::{KGPM3_PER_SLUGPFT3, M_PER_FT, N_PER_LBF};

/// The surfaces: command property, position property, the mapping channel of its actuator,
/// and the gain from aeroident's deflection to the position property.
const SURFACES: [(&str, &str, Channel, f64); 3] = [
    ("fcs/elevator-cmd-rad", "fcs/elevator-pos-rad", Channel::De, 1.0),
    ("fcs/aileron-cmd-rad", "fcs/left-aileron-pos-rad", Channel::Da, -1.0),
    ("fcs/rudder-cmd-rad", "fcs/rudder-pos-rad", Channel::Dr, 1.0),
];

/// The complete aircraft `name` (module doc) of `summary`'s derivatives on `airframe` with
/// the mapping's `actuators`; `source` is named in the header.
///
/// # Errors
/// As [`aerodynamics_xml_in`] (mixed axis systems, nothing identified), or a name JSBSim cannot
/// load (empty, or not letters, digits, `_`, `-`).
pub fn aircraft_xml(
    summary: &SummaryParameters,
    source: &str,
    name: &str,
    airframe: &Airframe,
    actuators: &BTreeMap<Channel, Actuator>,
) -> crate::error::Result<String> {
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        crate::bail!(
            "aircraft name `{name}`: JSBSim loads it as a file name: use letters, digits, `_`, `-`"
        );
    }
    let surfaces = SurfaceProperties {
        elevator: SURFACES[0].1.into(),
        aileron: SURFACES[1].1.into(),
        rudder: SURFACES[2].1.into(),
    };
    // Stability axes: aeroident's CL, CD, CY exactly (the wind axes' β rotation made a_y 10 %
    // off in a rudder doublet).
    let aero =
        aerodynamics_xml_in(summary, source, &surfaces, airframe.v0_mps, ForceAxes::Stability)?;
    let mut x = String::from("<?xml version=\"1.0\"?>\n");
    let _ = writeln!(
        x,
        "<fdm_config name=\"{name}\" version=\"2.0\" release=\"ALPHA\">\n  <!-- A complete aircraft by `aeroident export jsbsim` with a mapping, from {}: inputs fcs/elevator-cmd-rad, fcs/aileron-cmd-rad, fcs/rudder-cmd-rad (aeroident's signs) and the engine command {}; docs/export.md. -->",
        source.replace("--", "- -"),
        engine_property(airframe.propulsion)
    );
    x.push_str(&metrics_and_mass(airframe));
    x.push_str(&thrust(airframe));
    x.push_str(&flight_control(airframe.propulsion, actuators));
    x.push_str(&aero);
    x.push_str("</fdm_config>\n");
    Ok(x)
}

/// The engine command's property.
fn engine_property(p: Propulsion) -> &'static str {
    match p {
        Propulsion::Commanded => "fcs/thrust-cmd-n",
        Propulsion::Law(ThrustModel::Throttle { .. }) => "fcs/throttle-cmd-norm",
        Propulsion::Law(ThrustModel::Propeller { .. }) => "fcs/prop-speed-cmd-rad_sec",
    }
}

/// `<metrics>` and `<mass_balance>`: SI, the CG at the structural origin, JSBSim's `ixz` the
/// tensor element `−Jxz`.
fn metrics_and_mass(a: &Airframe) -> String {
    let (g, m) = (&a.geometry, &a.mass);
    let origin = |name: &str| {
        format!("    <location name=\"{name}\" unit=\"M\"><x>0</x><y>0</y><z>0</z></location>\n")
    };
    let mut x = String::from("  <metrics>\n");
    let _ = writeln!(x, "    <wingarea unit=\"M2\">{}</wingarea>", g.wing_area_m2);
    let _ = writeln!(x, "    <wingspan unit=\"M\">{}</wingspan>", g.span_m);
    let _ = writeln!(x, "    <chord unit=\"M\">{}</chord>", g.chord_m);
    for n in ["AERORP", "EYEPOINT", "VRP"] {
        x.push_str(&origin(n));
    }
    x.push_str("  </metrics>\n  <mass_balance>\n");
    for (el, v) in
        [("ixx", m.jx_kgm2), ("iyy", m.jy_kgm2), ("izz", m.jz_kgm2), ("ixz", -m.jxz_kgm2)]
    {
        let _ = writeln!(x, "    <{el} unit=\"KG*M2\">{v}</{el}>");
    }
    let _ = writeln!(x, "    <emptywt unit=\"KG\">{}</emptywt>", m.mass_kg);
    x.push_str(&origin("CG"));
    // JSBSim requires the element; the identified aircraft has no gear (it flies in the air).
    x.push_str("  </mass_balance>\n  <ground_reactions/>\n");
    x
}

/// `<external_reactions>`: the thrust along its line (module doc), magnitude in lbf.
fn thrust(a: &Airframe) -> String {
    let (si, ci) = a.thrust_incidence_rad.sin_cos();
    let magnitude = match a.propulsion {
        Propulsion::Commanded => "<property>fcs/thrust-cmd-n</property>".to_string(),
        Propulsion::Law(law) => law_function(law),
    };
    format!(
        "  <external_reactions>\n    <force name=\"thrust\" frame=\"BODY\">\n      <function>\n        <product>\n          <value>{}</value>\n          {magnitude}\n        </product>\n      </function>\n      <location unit=\"M\"><x>0</x><y>0</y><z>{}</z></location>\n      <direction><x>{ci}</x><y>0</y><z>{}</z></direction>\n    </force>\n  </external_reactions>\n",
        1.0 / N_PER_LBF,
        -a.thrust_arm_m / ci + 0.0,
        -si + 0.0
    )
}

/// A thrust law as a JSBSim function of its command, the airspeed and the density, N
/// ([`ThrustModel`]).
fn law_function(law: ThrustModel) -> String {
    let v = format!(
        "<product><property>velocities/vt-fps</property><value>{M_PER_FT}</value></product>"
    );
    match law {
        ThrustModel::Throttle { static_thrust_n, zero_thrust_speed_mps, exponent } => format!(
            "<value>{static_thrust_n}</value><pow><property>fcs/throttle-cmd-norm</property><value>{exponent}</value></pow><difference><value>1</value><quotient>{v}<value>{zero_thrust_speed_mps}</value></quotient></difference>"
        ),
        ThrustModel::Propeller { diameter_m: d, ct0, ct_j } => {
            // T = ρ D⁴ n² ct0 + ρ D³ n V ct_j, n = ω / 2π rev/s.
            let rho = format!(
                "<product><property>atmosphere/rho-slugs_ft3</property><value>{KGPM3_PER_SLUGPFT3}</value></product>"
            );
            let n = format!(
                "<quotient><property>fcs/prop-speed-cmd-rad_sec</property><value>{}</value></quotient>",
                2.0 * std::f64::consts::PI
            );
            format!(
                "{rho}<sum><product><value>{}</value>{n}{n}</product><product><value>{}</value>{n}{v}</product></sum>",
                d.powi(4) * ct0,
                d.powi(3) * ct_j
            )
        }
    }
}

/// `<flight_control>`: the command properties, each surface through its actuator (or
/// directly), the aileron's sign turned to JSBSim's.
fn flight_control(p: Propulsion, actuators: &BTreeMap<Channel, Actuator>) -> String {
    let mut x = String::from("  <flight_control name=\"aeroident\">\n");
    for (cmd, ..) in SURFACES {
        let _ = writeln!(x, "    <property value=\"0\">{cmd}</property>");
    }
    let _ = writeln!(x, "    <property value=\"0\">{}</property>", engine_property(p));
    x.push_str("    <channel name=\"surfaces\">\n");
    for (cmd, pos, ch, gain) in SURFACES {
        let key = ch.key();
        let deflection = format!("fcs/{key}-deflection-rad");
        match actuators.get(&ch) {
            Some(a) => x.push_str(&actuator(key, cmd, &deflection, a)),
            None => {
                let _ = writeln!(
                    x,
                    "      <pure_gain name=\"fcs/{key}-ideal\"><input>{cmd}</input><gain>1</gain><output>{deflection}</output></pure_gain>"
                );
            }
        }
        let _ = writeln!(
            x,
            "      <pure_gain name=\"fcs/{key}-to-jsbsim\"><input>{deflection}</input><gain>{gain}</gain><output>{pos}</output></pure_gain>"
        );
    }
    x.push_str("    </channel>\n  </flight_control>\n");
    x
}

/// One `<actuator>`: JSBSim's lag `1/τ`, rate limit and position limits (each only when
/// finite).
fn actuator(key: &str, cmd: &str, out: &str, a: &Actuator) -> String {
    let mut x = format!(
        "      <actuator name=\"fcs/{key}-actuator\">\n        <input>{cmd}</input>\n        <lag>{}</lag>\n",
        1.0 / a.tau_s
    );
    if a.rate_limit_rad_s.is_finite() {
        let _ = writeln!(x, "        <rate_limit>{}</rate_limit>", a.rate_limit_rad_s);
    }
    let (lo, hi) = a.position_limits_rad;
    if lo.is_finite() && hi.is_finite() {
        let _ = writeln!(x, "        <clipto><min>{lo}</min><max>{hi}</max></clipto>");
    }
    let _ = writeln!(x, "        <output>{out}</output>\n      </actuator>");
    x
}
