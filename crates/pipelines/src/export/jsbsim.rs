//! Identified derivatives as a JSBSim `<aerodynamics>` fragment.
//!
//! Each identified parameter `<coef>_<term>` becomes one function
//! `aero/coefficient/<coef>_<term>` in the axis of its coefficient, the product of the
//! dimensional scaling, the derivative and the term's regressor as JSBSim properties
//! (JSBSim reference manual, "Aerodynamics"; the regressors of
//! [`aeroident_estimators::vocabulary::Term::value`]):
//!
//! | coefficient | axis | scaling |
//! |---|---|---|
//! | CL, CD, CY | LIFT, DRAG, SIDE (wind axes) | `aero/qbar-area` |
//! | CX, CY, CZ | X, Y, Z (body axes) | `aero/qbar-area` |
//! | Cl, Cn | ROLL, YAW | `aero/qbar-area` · `metrics/bw-ft` |
//! | Cm | PITCH | `aero/qbar-area` · `metrics/cbarw-ft` |
//!
//! | term | regressor |
//! |---|---|
//! | bias | 1 |
//! | alpha, alpha2, beta, alpha_beta | `aero/alpha-rad`, its square, `aero/beta-rad`, α·β |
//! | p, r | `velocities/p-aero-rad_sec`, `velocities/r-aero-rad_sec` · `aero/bi2vel` (b/2V) |
//! | q, alphadot | `velocities/q-aero-rad_sec`, `aero/alphadot-rad_sec` · `aero/ci2vel` (c̄/2V) |
//! | de, da, dr, alpha_de | the surface properties ([`SurfaceProperties`]), α·δe |
//! | V (V/V0), q0 (q c̄/2V0) | `velocities/vt-fps` / V0, `velocities/q-aero-rad_sec` · `metrics/cbarw-ft` / (2 V0): need V0 |
//! | alpha_k1 … alpha_k4 | `max(aero/alpha-rad − k, 0)`, a `<max>` of a `<difference>`: needs the knot (`alpha_knots_rad` of the summary) |
//! | mach, mach2 | `velocities/mach`, its square (JSBSim's Mach, from its own atmosphere) |
//!
//! Signs are aeroident's (Stevens & Lewis 3rd ed. §2.3): JSBSim's LIFT is up, DRAG aft, SIDE
//! and Y right, X forward, Z down, ROLL/PITCH/YAW right wing down / nose up / nose right, the
//! same as CL, CD, CY, CX, CZ, Cl, Cm, Cn; δe > 0 trailing edge down and δr > 0 trailing edge
//! left as JSBSim's `fcs/elevator-pos-rad` and `fcs/rudder-pos-rad`. The aileron is the
//! exception: aeroident's δa > 0 gives a negative rolling moment (Stevens & Lewis,
//! Jategaonkar), JSBSim's aileron property is > 0 rolling the right wing down, so the fragment
//! multiplies the property by −1 (check the aircraft's aileron property). aeroident's CL and CD are stability-axis
//! coefficients (rotated by α); JSBSim's LIFT and DRAG are wind axes (also rotated by β): the
//! difference is of order β·CD. Lift and drag on one side and body X/Z on the other cannot be
//! mixed in one fragment (JSBSim refuses mixed axis systems). A parameter that is not
//! identified (`null`) is omitted with a comment, never written as 0.

use crate::summary_file::{Identified, SummaryParameters};
use aeroident_estimators::vocabulary::{Coefficient, Term};
use aeroident_physics::units::FT_PER_M;
use std::fmt::Write as _;
/// The JSBSim properties of the control-surface deflections, rad.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceProperties {
    /// Elevator, > 0 trailing edge down.
    pub elevator: String,
    /// Aileron, > 0 rolls right wing down (JSBSim's convention; the fragment uses −1 × it as
    /// aeroident's δa).
    pub aileron: String,
    /// Rudder, > 0 trailing edge left.
    pub rudder: String,
}

impl SurfaceProperties {
    /// Checks each property is a name JSBSim's property tree accepts (so the fragment is
    /// well-formed XML and JSBSim finds the property): `/`-separated components of ASCII
    /// letters, digits, `_`, `-` and `.`, each starting with a letter or `_` and optionally
    /// indexed `[n]`.
    ///
    /// # Errors
    /// The first property that is not such a name, naming the surface, the property and the
    /// offending character.
    pub fn check(&self) -> crate::error::Result<()> {
        for (surface, name) in
            [("elevator", &self.elevator), ("aileron", &self.aileron), ("rudder", &self.rudder)]
        {
            if let Err(why) = check_property_name(name) {
                crate::bail!(
                    "{surface} property `{name}` is not a JSBSim property name: {why} (a property is `/`-separated names of letters, digits, `_`, `-`, `.`, each starting with a letter or `_`, optionally indexed `[n]`, e.g. `fcs/elevator-pos-rad`)"
                );
            }
        }
        Ok(())
    }
}

/// Why `name` is not a JSBSim property path (see [`SurfaceProperties::check`]).
fn check_property_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("it is empty".into());
    }
    for part in name.split('/') {
        let (base, index) = match part.split_once('[') {
            Some((b, rest)) => (b, Some(rest)),
            None => (part, None),
        };
        let mut chars = base.chars();
        match chars.next() {
            None => return Err(format!("an empty component in `{name}`")),
            Some(c) if !(c.is_ascii_alphabetic() || c == '_') => {
                return Err(format!("component `{part}` starts with `{c}`"));
            }
            Some(_) => {}
        }
        if let Some(c) = chars.find(|c| !(c.is_ascii_alphanumeric() || "_-.".contains(*c))) {
            return Err(format!("character `{c}` in component `{part}`"));
        }
        if let Some(rest) = index {
            let digits = rest.strip_suffix(']').unwrap_or("x");
            if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) {
                return Err(format!("component `{part}` has a malformed index"));
            }
        }
    }
    Ok(())
}

impl Default for SurfaceProperties {
    fn default() -> Self {
        Self {
            elevator: "fcs/elevator-pos-rad".into(),
            aileron: "fcs/left-aileron-pos-rad".into(),
            rudder: "fcs/rudder-pos-rad".into(),
        }
    }
}

/// The regressor of `term` as JSBSim function elements (properties, or for a spline its
/// `<max>` element) and a constant factor, or why it cannot be expressed. `knots_rad` are the
/// model's α knots.
fn regressor(
    term: Term,
    s: &SurfaceProperties,
    v0_mps: Option<f64>,
    knots_rad: &[f64],
) -> Result<(Vec<String>, f64), String> {
    let elements = |names: Vec<String>| {
        names.iter().map(|n| format!("<property>{}</property>", xml_text(n))).collect()
    };
    if let Some(i) = term.knot() {
        let k = knots_rad.get(i).ok_or_else(|| {
            format!(
                "term `{}` needs its α knot; the summary gives {}",
                term.name(),
                knots_rad.len()
            )
        })?;
        let spline = format!(
            "<max><difference><property>aero/alpha-rad</property><value>{k:?}</value></difference><value>0</value></max>"
        );
        return Ok((vec![spline], 1.0));
    }
    let (names, factor) = regressor_properties(term, s, v0_mps)?;
    Ok((elements(names), factor))
}

/// The regressor of a term that is a product of JSBSim properties (every term but the
/// splines), with its constant factor.
fn regressor_properties(
    term: Term,
    s: &SurfaceProperties,
    v0_mps: Option<f64>,
) -> Result<(Vec<String>, f64), String> {
    let p = |names: &[&str]| names.iter().map(|n| (*n).to_string()).collect::<Vec<_>>();
    let v0_fps = || {
        v0_mps.map(|v| v * FT_PER_M).ok_or_else(|| {
            format!("term `{}` needs the reference speed V0: give --v0-mps", term.name())
        })
    };
    Ok(match term {
        Term::Bias => (Vec::new(), 1.0),
        Term::Alpha => (p(&["aero/alpha-rad"]), 1.0),
        Term::Alpha2 => (p(&["aero/alpha-rad", "aero/alpha-rad"]), 1.0),
        Term::Beta => (p(&["aero/beta-rad"]), 1.0),
        Term::AlphaBeta => (p(&["aero/alpha-rad", "aero/beta-rad"]), 1.0),
        Term::P => (p(&["velocities/p-aero-rad_sec", "aero/bi2vel"]), 1.0),
        Term::Q => (p(&["velocities/q-aero-rad_sec", "aero/ci2vel"]), 1.0),
        Term::R => (p(&["velocities/r-aero-rad_sec", "aero/bi2vel"]), 1.0),
        Term::Alphadot => (p(&["aero/alphadot-rad_sec", "aero/ci2vel"]), 1.0),
        Term::De => (vec![s.elevator.clone()], 1.0),
        // JSBSim's aileron rolls right wing down when > 0, aeroident's δa rolls left.
        Term::Da => (vec![s.aileron.clone()], -1.0),
        Term::Dr => (vec![s.rudder.clone()], 1.0),
        Term::AlphaDe => (vec!["aero/alpha-rad".into(), s.elevator.clone()], 1.0),
        Term::AlphaP => (p(&["aero/alpha-rad", "velocities/p-aero-rad_sec", "aero/bi2vel"]), 1.0),
        Term::AlphaQ => (p(&["aero/alpha-rad", "velocities/q-aero-rad_sec", "aero/ci2vel"]), 1.0),
        Term::AlphaR => (p(&["aero/alpha-rad", "velocities/r-aero-rad_sec", "aero/bi2vel"]), 1.0),
        Term::AlphaDa => (vec!["aero/alpha-rad".into(), s.aileron.clone()], -1.0),
        Term::AlphaDr => (vec!["aero/alpha-rad".into(), s.rudder.clone()], 1.0),
        Term::V => (p(&["velocities/vt-fps"]), 1.0 / v0_fps()?),
        Term::Q0 => {
            (p(&["velocities/q-aero-rad_sec", "metrics/cbarw-ft"]), 1.0 / (2.0 * v0_fps()?))
        }
        Term::Mach => (p(&["velocities/mach"]), 1.0),
        Term::Mach2 => (p(&["velocities/mach", "velocities/mach"]), 1.0),
        Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => {
            return Err(format!("term `{}` is a spline, not a product", term.name()));
        }
    })
}

/// The axis of a coefficient and its scaling properties.
fn axis(c: Coefficient) -> (&'static str, &'static [&'static str]) {
    const F: &[&str] = &["aero/qbar-area"];
    match c {
        Coefficient::CL => ("LIFT", F),
        Coefficient::CD => ("DRAG", F),
        Coefficient::CX => ("X", F),
        Coefficient::CZ => ("Z", F),
        Coefficient::CY => ("SIDE", F),
        Coefficient::Cl => ("ROLL", &["aero/qbar-area", "metrics/bw-ft"]),
        Coefficient::Cm => ("PITCH", &["aero/qbar-area", "metrics/cbarw-ft"]),
        Coefficient::Cn => ("YAW", &["aero/qbar-area", "metrics/bw-ft"]),
    }
}

/// The axes JSBSim takes lift, drag and side force in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceAxes {
    /// `LIFT`, `DRAG`, `SIDE`: JSBSim's wind axes, rotated by α and β (aeroident's CL, CD
    /// are rotated by α only: they differ at order β·CD). What an existing aircraft's
    /// `<aerodynamics>` usually holds.
    Wind,
    /// `X`, `Y`, `Z` with `frame="STABILITY"`: drag, side force and lift positive aft, right
    /// and up (`FGAerodynamics::Run`, atStability), rotated by α only: aeroident's CL, CD,
    /// CY exactly.
    Stability,
}

/// The opening `<axis>` element of coefficient `c` (`body`: the model is in body X/Z).
fn axis_open(c: Coefficient, body: bool, axes: ForceAxes) -> String {
    let (name, _) = axis(c);
    let name = if c == Coefficient::CY && body { "Y" } else { name };
    let stability = match (axes, body, name) {
        (ForceAxes::Stability, false, "DRAG") => Some("X"),
        (ForceAxes::Stability, false, "SIDE") => Some("Y"),
        (ForceAxes::Stability, false, "LIFT") => Some("Z"),
        _ => None,
    };
    match stability {
        Some(s) => format!("  <axis name=\"{s}\" frame=\"STABILITY\">"),
        None => format!("  <axis name=\"{name}\">"),
    }
}

/// Writes the `<aerodynamics>` fragment of the identified parameters, forces in JSBSim's
/// wind axes ([`aerodynamics_xml_in`]).
///
/// # Errors
/// As [`aerodynamics_xml_in`].
pub fn aerodynamics_xml(
    summary: &SummaryParameters,
    source: &str,
    surfaces: &SurfaceProperties,
    v0_mps: Option<f64>,
) -> crate::error::Result<String> {
    aerodynamics_xml_in(summary, source, surfaces, v0_mps, ForceAxes::Wind)
}

/// Writes the `<aerodynamics>` fragment of the identified parameters, lift, drag and side
/// force in `axes`. `source` is named in the header comment.
///
/// # Errors
/// A surface property JSBSim would not accept ([`SurfaceProperties::check`]), lift/drag
/// mixed with body X/Z coefficients, or no identified parameter at all.
pub fn aerodynamics_xml_in(
    summary: &SummaryParameters,
    source: &str,
    surfaces: &SurfaceProperties,
    v0_mps: Option<f64>,
    axes: ForceAxes,
) -> crate::error::Result<String> {
    surfaces.check()?;
    let coefs: Vec<Coefficient> = summary.parameters.iter().map(|p| p.param.coefficient).collect();
    let wind = coefs.iter().any(|c| matches!(c, Coefficient::CL | Coefficient::CD));
    let body = coefs.iter().any(|c| matches!(c, Coefficient::CX | Coefficient::CZ));
    if wind && body {
        crate::bail!(
            "{source}: the model mixes lift/drag (CL, CD) with body-axis CX/CZ; JSBSim takes one axis system per aircraft"
        );
    }
    if summary.parameters.iter().all(|p| p.value.is_none()) {
        crate::bail!("{source}: no parameter is identified (all null); nothing to export");
    }
    let mut x = String::new();
    let _ = writeln!(
        x,
        "<!-- Generated by `aeroident export jsbsim` from {} (estimator {}, model {}).\n     \
         Dimensionless derivatives per rad and per unit normalised rate (q c/2V, p b/2V, r b/2V);\n     \
         signs as in docs/export.md. Replace an aircraft's <aerodynamics> with this element. -->",
        xml_escape(source),
        xml_escape(&summary.estimator),
        xml_escape(&summary.model)
    );
    x.push_str("<aerodynamics>\n");
    for c in Coefficient::ALL {
        let of_c: Vec<&Identified> =
            summary.parameters.iter().filter(|p| p.param.coefficient == c).collect();
        if of_c.is_empty() {
            continue;
        }
        let (_, scale) = axis(c);
        let _ = writeln!(x, "{}", axis_open(c, body, axes));
        for p in of_c {
            let pname = p.param.name();
            let Some(v) = p.value else {
                let _ = writeln!(
                    x,
                    "    <!-- {pname}: not identified (null in the summary); omitted -->"
                );
                continue;
            };
            let knots = &summary.alpha_knots_rad;
            let (factors, factor) = match regressor(p.param.term, surfaces, v0_mps, knots) {
                Ok(r) => r,
                Err(why) => {
                    let _ =
                        writeln!(x, "    <!-- {pname} = {v}: omitted, {} -->", xml_escape(&why));
                    continue;
                }
            };
            let sigma = p.sigma.map_or(String::new(), |s| format!(" ± {s} (1σ)"));
            let pname = xml_text(pname);
            let _ = writeln!(x, "    <function name=\"aero/coefficient/{pname}\">");
            let _ = writeln!(x, "      <description>{pname} = {v}{sigma}</description>");
            x.push_str("      <product>\n");
            for s in scale {
                let _ = writeln!(x, "        <property>{}</property>", xml_text(s));
            }
            for f in factors {
                let _ = writeln!(x, "        {f}");
            }
            let _ = writeln!(x, "        <value>{}</value>", v * factor);
            x.push_str("      </product>\n    </function>\n");
        }
        x.push_str("  </axis>\n");
    }
    x.push_str("</aerodynamics>\n");
    Ok(x)
}

/// `s` as XML text or attribute value (either quote): the markup characters escaped.
fn xml_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// `s` as comment content: as [`xml_text`], and `--` (not allowed in a comment) split.
fn xml_escape(s: &str) -> String {
    xml_text(s).replace("--", "- -")
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::vocabulary::Param;

    fn id(name: &str, value: Option<f64>) -> Identified {
        Identified { param: Param::from_name(name).unwrap(), value, sigma: Some(0.5) }
    }

    fn summary(ps: Vec<Identified>) -> SummaryParameters {
        SummaryParameters {
            estimator: "rls".into(),
            model: "m".into(),
            parameters: ps,
            alpha_knots_rad: Vec::new(),
            status: "complete".into(),
        }
    }

    #[test]
    fn functions_are_scaling_times_value_times_regressor() {
        let s = summary(vec![
            id("Cm_q", Some(-12.5)),
            id("Cm_alphadot", None),
            id("CL_alpha", Some(4.25)),
            id("Cm_V", Some(0.1)),
        ]);
        let x = aerodynamics_xml(&s, "s.json", &SurfaceProperties::default(), Some(100.0)).unwrap();
        let cmq = "<function name=\"aero/coefficient/Cm_q\">\n      <description>Cm_q = -12.5 ± 0.5 (1σ)</description>\n      <product>\n        <property>aero/qbar-area</property>\n        <property>metrics/cbarw-ft</property>\n        <property>velocities/q-aero-rad_sec</property>\n        <property>aero/ci2vel</property>\n        <value>-12.5</value>";
        assert!(x.contains(cmq), "{x}");
        assert!(x.contains("<!-- Cm_alphadot: not identified (null in the summary); omitted -->"));
        assert!(x.contains("<axis name=\"LIFT\">"));
        // V/V0: 0.1 / (100 m/s in ft/s).
        let v = format!("<value>{}</value>", 0.1 / (100.0 / 0.3048));
        assert!(x.contains(&v), "{x}");
        // Without V0 the V term is omitted, with the reason.
        let x = aerodynamics_xml(&s, "s.json", &SurfaceProperties::default(), None).unwrap();
        assert!(x.contains("Cm_V = 0.1: omitted, term `V` needs the reference speed V0"));
    }

    #[test]
    fn body_axes_use_x_y_z_and_mixing_is_refused() {
        let s = summary(vec![id("CX_alpha", Some(0.1)), id("CY_beta", Some(-0.5))]);
        let x = aerodynamics_xml(&s, "s", &SurfaceProperties::default(), None).unwrap();
        assert!(x.contains("<axis name=\"X\">") && x.contains("<axis name=\"Y\">"), "{x}");
        let s = summary(vec![id("CX_alpha", Some(0.1)), id("CL_alpha", Some(4.0))]);
        let e = aerodynamics_xml(&s, "s", &SurfaceProperties::default(), None).unwrap_err();
        assert!(e.to_string().contains("mixes lift/drag"), "{e}");
        let s = summary(vec![id("CL_alpha", None)]);
        assert!(aerodynamics_xml(&s, "s", &SurfaceProperties::default(), None).is_err());
    }

    /// Every element's text, in document order, after a strict parse (malformed XML fails).
    fn parsed_texts(x: &str) -> Vec<String> {
        let mut r = quick_xml::Reader::from_str(x);
        r.config_mut().check_comments = true;
        r.config_mut().check_end_names = true;
        let (mut texts, mut depth) = (Vec::new(), 0_i32);
        loop {
            match r.read_event().unwrap_or_else(|e| panic!("malformed XML: {e}\n{x}")) {
                quick_xml::events::Event::Start(_) => depth += 1,
                quick_xml::events::Event::End(_) => depth -= 1,
                quick_xml::events::Event::Text(t) => {
                    let raw = std::str::from_utf8(&t).unwrap().to_string();
                    let text = quick_xml::escape::unescape(&raw).unwrap().trim().to_string();
                    if !text.is_empty() {
                        texts.push(text);
                    }
                }
                quick_xml::events::Event::Eof => break,
                _ => {}
            }
        }
        assert_eq!(depth, 0, "unbalanced elements:\n{x}");
        texts
    }

    #[test]
    fn property_names_jsbsim_would_not_accept_are_refused() {
        let s = summary(vec![id("Cm_de", Some(-1.2))]);
        for bad in ["fcs/a&b<c", "fcs/a\"b", "", "fcs//x", "fcs/1x", "fcs/x y", "fcs/x[1", "-fcs/x"]
        {
            let p = SurfaceProperties { elevator: bad.into(), ..SurfaceProperties::default() };
            let e = aerodynamics_xml(&s, "s", &p, None).unwrap_err().to_string();
            assert!(e.contains("elevator property") && e.contains(bad), "{bad:?}: {e}");
        }
        // Indexed and dotted names are JSBSim's own: accepted, and the text parses back to them.
        let p = SurfaceProperties {
            elevator: "fcs/elevator-pos-rad[1]".into(),
            rudder: "fcs/rudder.pos_rad".into(),
            ..SurfaceProperties::default()
        };
        let s = summary(vec![id("Cm_de", Some(-1.2)), id("Cn_dr", Some(-0.1))]);
        let x = aerodynamics_xml(&s, "a&b <c> --d.json", &p, None).unwrap();
        let texts = parsed_texts(&x);
        assert!(texts.iter().any(|t| t == "fcs/elevator-pos-rad[1]"), "{texts:?}");
        assert!(texts.iter().any(|t| t == "fcs/rudder.pos_rad"), "{texts:?}");
    }

    #[test]
    fn each_product_term_is_its_properties_and_constant_factor() {
        let s = SurfaceProperties::default();
        let of = |term: &str| regressor_properties(Term::from_name(term).unwrap(), &s, Some(100.0));
        let props = |names: &[&str]| names.iter().map(|n| n.to_string()).collect::<Vec<_>>();
        let cases: [(&str, &[&str], f64); 8] = [
            ("alpha2", &["aero/alpha-rad", "aero/alpha-rad"], 1.0),
            ("alpha_beta", &["aero/alpha-rad", "aero/beta-rad"], 1.0),
            ("da", &["fcs/left-aileron-pos-rad"], -1.0),
            ("alpha_da", &["aero/alpha-rad", "fcs/left-aileron-pos-rad"], -1.0),
            ("alpha_dr", &["aero/alpha-rad", "fcs/rudder-pos-rad"], 1.0),
            ("alpha_p", &["aero/alpha-rad", "velocities/p-aero-rad_sec", "aero/bi2vel"], 1.0),
            ("mach2", &["velocities/mach", "velocities/mach"], 1.0),
            ("0", &[], 1.0),
        ];
        for (term, names, factor) in cases {
            assert_eq!(of(term), Ok((props(names), factor)), "{term}");
        }
        let (names, factor) = of("V").unwrap();
        assert_eq!(names, ["velocities/vt-fps"]);
        assert!((factor - 0.3048 / 100.0).abs() < 1e-15, "{factor}");
        let (names, factor) = of("q0").unwrap();
        assert_eq!(names, ["velocities/q-aero-rad_sec", "metrics/cbarw-ft"]);
        assert!((factor - 0.3048 / 200.0).abs() < 1e-15, "{factor}");
        let e = regressor_properties(Term::V, &s, None).unwrap_err();
        assert_eq!(e, "term `V` needs the reference speed V0: give --v0-mps");
        assert!(of("alpha_k1").unwrap_err().contains("is a spline"));
    }

    #[test]
    fn a_spline_term_is_the_excess_over_its_knot_and_needs_the_knot() {
        let s = SurfaceProperties::default();
        let k2 = Term::from_name("alpha_k2").unwrap();
        let spline = "<max><difference><property>aero/alpha-rad</property><value>0.2</value></difference><value>0</value></max>";
        assert_eq!(regressor(k2, &s, None, &[0.1, 0.2]), Ok((vec![spline.to_string()], 1.0)));
        let e = regressor(k2, &s, None, &[0.1]).unwrap_err();
        assert_eq!(e, "term `alpha_k2` needs its α knot; the summary gives 1");
        let q = regressor(Term::Q, &s, None, &[]).unwrap();
        let q_props =
            ["<property>velocities/q-aero-rad_sec</property>", "<property>aero/ci2vel</property>"];
        assert_eq!(q, (q_props.map(String::from).to_vec(), 1.0));
    }

    #[test]
    fn each_coefficient_has_its_axis_and_scaling() {
        let (f, b, c) = ("aero/qbar-area", "metrics/bw-ft", "metrics/cbarw-ft");
        let cases: [(Coefficient, &str, &[&str]); 8] = [
            (Coefficient::CL, "LIFT", &[f]),
            (Coefficient::CD, "DRAG", &[f]),
            (Coefficient::CX, "X", &[f]),
            (Coefficient::CY, "SIDE", &[f]),
            (Coefficient::CZ, "Z", &[f]),
            (Coefficient::Cl, "ROLL", &[f, b]),
            (Coefficient::Cm, "PITCH", &[f, c]),
            (Coefficient::Cn, "YAW", &[f, b]),
        ];
        for (coefficient, name, scaling) in cases {
            assert_eq!(axis(coefficient), (name, scaling), "{coefficient:?}");
        }
        let s = summary(vec![id("CL_alpha", Some(4.0)), id("CY_beta", Some(-0.5))]);
        let x = aerodynamics_xml(&s, "s", &SurfaceProperties::default(), None).unwrap();
        assert!(x.contains("<axis name=\"SIDE\">") && !x.contains("<axis name=\"Y\">"), "{x}");
        let s = summary(vec![id("CD_alpha", Some(0.1)), id("CZ_alpha", Some(-4.0))]);
        assert!(aerodynamics_xml(&s, "s", &SurfaceProperties::default(), None).is_err());
    }

    #[test]
    fn comment_and_text_escapes_cover_every_markup_character() {
        assert_eq!(xml_text(r#"a&b<c>"d'"#), "a&amp;b&lt;c&gt;&quot;d&apos;");
        assert_eq!(xml_escape("x--y<"), "x- -y&lt;");
        let mut s = summary(vec![id("Cm_q", Some(-12.5))]);
        s.status = "?".into();
        assert_eq!(s.unfinished(), None);
        s.status = "diverged".into();
        assert!(s.unfinished().unwrap().starts_with("the summary's status is `diverged`"));
    }
}
