//! Physical plausibility of an identified parameter: whether a conventional aircraft (or the
//! aircraft the model file describes, `[plausible.X]`) can have the value, and what most
//! likely made it otherwise. A record nobody prepared carries unit slips, reversed signs,
//! absurd constants and missing thrust that no fit statistic reveals: a lift slope of 0.7, a
//! negative drag, an elevator power 57 times too small are each a good fit of bad data.
//!
//! Two verdicts, both in the parameter's `flags` ([`aeroident_io::ParameterResult`]):
//! - a value outside [`ModelSpec::plausible_range`] by more than 2σ (any amount without a σ):
//!   flagged, with the likely cause of its kind of term ([`implausible`]);
//! - a σ so large that ±2σ spans more than the whole plausible range: flagged, the record
//!   does not determine the value whatever it is ([`undetermined`]). This catches what the
//!   relative-σ precision check cannot see: a constant term (`CL_0`), exempt from it because
//!   its value may be near 0, with σ 22 on a lift coefficient;
//! - drag and axial-force terms (`CD_*`, `CX_*`) of a record without thrust: withdrawn
//!   (`null`, not identified), since they are then drag minus thrust ([`without_thrust`]);
//! - pitching-moment terms (`Cm_*`) of a record without thrust whose speed or throttle
//!   varied: flagged, since they may carry the engine's moment ([`unmapped_thrust_moment`]).

use aeroident_estimators::{Coefficient, Param, Term};
use aeroident_io::{Channel, Mapping, ModelSpec, ParameterResult};

/// The flag of parameter `p` = `estimate` ± `std_error` when it lies outside the aircraft's
/// plausible range by more than 2σ (module doc), naming the range and the likely cause; else
/// `None`. A wrong sign may also carry the sign check's warning: the two say different things
/// (which convention, which range).
pub fn implausible(
    model: &ModelSpec,
    p: Param,
    estimate: f64,
    std_error: Option<f64>,
) -> Option<String> {
    let (lo, hi) = model.plausible_range(p)?;
    let outside = if estimate < lo { lo - estimate } else { estimate - hi };
    // A σ that is not a number (a parameter held at its prior) gives no margin, not a NaN
    // one that every comparison fails.
    let margin = 2.0 * std_error.filter(|s| s.is_finite()).unwrap_or(0.0);
    if outside <= margin || !estimate.is_finite() {
        return None;
    }
    let whose = if model.plausible.iter().any(|r| r.param == p) {
        "this aircraft's range (the model file's)"
    } else {
        "the range of a conventional aircraft"
    };
    Some(format!(
        "{} = {estimate:+.4} lies outside {whose} [{lo}, {hi}]: likely {}; a model file's [plausible.{}] sets an unconventional aircraft's range",
        p.name(),
        likely_cause(p),
        p.name()
    ))
}

/// The flag of parameter `p` whose ±2σ interval (width `4 std_error`) is wider than its whole
/// plausible range (module doc): no value in or out of the range is supported; else `None`.
pub fn undetermined(model: &ModelSpec, p: Param, std_error: Option<f64>) -> Option<String> {
    let (lo, hi) = model.plausible_range(p)?;
    let s = std_error.filter(|s| s.is_finite())?;
    (4.0 * s > hi - lo).then(|| {
        format!(
            "{}: σ {} makes ±2σ wider than the whole plausible range [{lo}, {hi}]: the record does not determine it",
            p.name(),
            aeroident_io::message::short(s)
        )
    })
}

/// What most often puts a term of `p`'s kind out of range.
fn likely_cause(p: Param) -> &'static str {
    match (p.coefficient, p.term) {
        (Coefficient::CY | Coefficient::Cn, Term::Da) | (Coefficient::Cl, Term::Dr) => {
            "a surface that barely moved, or moved with the other one, so that this cross-control term takes what neither can determine (excite the surfaces apart, or leave the term out), or a surface in degrees mapped as radians (÷57.3)"
        }
        (_, Term::De | Term::Da | Term::Dr) => {
            "a surface in degrees mapped as radians (÷57.3), a reversed surface, or a surface that barely moved"
        }
        (Coefficient::Cm, Term::Q | Term::Q0)
        | (Coefficient::Cl, Term::P)
        | (Coefficient::Cn, Term::R) => {
            "a time skew or lag between the rate and the other channels (run compat), or too little excitation"
        }
        (Coefficient::CD | Coefficient::CX, _) => {
            "the thrust model, or an axial accelerometer mapped with gravity removed or the wrong sign"
        }
        _ => {
            "an angle in the wrong unit or with an offset, the mass, inertia or reference geometry constants, or a correlated pair (see the correlations)"
        }
    }
}

/// Whether the record's mapping gives thrust (a `thrust` channel or a `[thrust_model]` law):
/// without it the measured drag and axial force are drag minus thrust.
pub fn thrust_mapped(mapping: &Mapping) -> bool {
    mapping.channels.contains_key(&Channel::Thrust) || mapping.thrust_model.is_some()
}

/// The change of airspeed (peak to peak over its mid value) or of throttle (of its 0–1
/// travel) over the estimated samples beyond which an unmapped engine's moment can move the
/// `Cm` terms by the accuracy a derivative is wanted to
/// ([`crate::precision::RELATIVE_SIGMA_LIMIT`], 10 %): a propeller's thrust at a held
/// throttle goes about as 1/V (constant power), so a 10 % change of speed moves it, and any
/// moment it has about the CG, by about 10 %.
pub const THRUST_VARIATION_LIMIT: f64 = 0.10;

/// `(hi − lo)` over the mean of `lo` and `hi`: how much a speed varied, as a share of itself.
pub fn relative_variation(lo: f64, hi: f64) -> f64 {
    (hi - lo) / (0.5 * (hi + lo))
}

/// A warning about every `Cm` parameter of `structure` when `mapping` gives neither thrust
/// ([`thrust_mapped`]) nor its pitching moment (`thrust_moment`) and the record shows the
/// thrust can have changed within a manoeuvre: `airspeed_mps` or `throttle`, each the
/// `(smallest, largest)` value of the estimated samples of the manoeuvre where it varied most,
/// varied beyond [`THRUST_VARIATION_LIMIT`] (across manoeuvres flown apart, each manoeuvre's
/// own `Cm_0` would take a constant engine moment, but the fit has one `Cm_0`: that is the
/// repeatability test's to see, per parameter). The engine's
/// moment about the CG (a thrust line off the CG, the propeller's normal force) is then part
/// of the measured pitching moment and follows the flight condition, and every method fits
/// it into the airframe's terms alike, so no cross-check can see it (a JSBSim Cessna 172
/// whose speed varied 27 %: Cm_q 13 % off in oe and 12 % in the EKF, Cm_α 14 % in least squares). `None`
/// otherwise: with the speed held, the engine's moment is about constant and `Cm_0` takes it.
pub fn unmapped_thrust_moment(
    structure: &aeroident_estimators::ModelStructure,
    mapping: &Mapping,
    airspeed_mps: Option<(f64, f64)>,
    throttle: Option<(f64, f64)>,
) -> Option<aeroident_io::warning::Warning> {
    let moment_given =
        thrust_mapped(mapping) || mapping.channels.contains_key(&Channel::ThrustMoment);
    let has_cm = structure.params().any(|p| p.coefficient == Coefficient::Cm);
    if moment_given || !has_cm {
        return None;
    }
    let speed = airspeed_mps
        .map(|(lo, hi)| relative_variation(lo, hi))
        .filter(|v| *v > THRUST_VARIATION_LIMIT)
        .map(|v| format!("the airspeed varied {:.0} % within a manoeuvre", 100.0 * v));
    let lever = throttle
        .map(|(lo, hi)| hi - lo)
        .filter(|v| *v > THRUST_VARIATION_LIMIT)
        .map(|v| format!("the throttle moved {:.0} % of its travel within a manoeuvre", 100.0 * v));
    let why = [speed, lever].into_iter().flatten().collect::<Vec<_>>().join(" and ");
    (!why.is_empty()).then(|| {
        let text = format!(
            "thrust is not mapped and {why}: the pitching moment then includes the engine's (a thrust line off the CG, the propeller's normal force), which every method fits into the Cm terms alike (map `thrust` and `thrust_moment`, or `[thrust_model]`: docs/mapping.md)"
        );
        aeroident_io::warning::Warning::new(
            aeroident_io::warning::WarningKind::UnmodelledForce,
            text,
        )
        .about("Cm")
    })
}

/// Withdraws `r` (a drag or axial-force term, `CD_*` or `CX_*`) when the record has no thrust
/// (module doc); other parameters are left as they are. Returns whether it withdrew it.
pub fn without_thrust(r: &mut ParameterResult, thrust_mapped: bool) -> bool {
    let drag = Param::from_name(&r.name)
        .is_some_and(|p| matches!(p.coefficient, Coefficient::CD | Coefficient::CX));
    if thrust_mapped || !drag {
        return false;
    }
    r.withdraw(
        "thrust is not mapped: the record's drag is drag minus thrust, so a drag term is not identified (map `thrust`, or give `[thrust_model]` a law of the throttle or the propeller speed: docs/mapping.md)",
    );
    true
}

/// Flags every parameter of `results` the plausibility check refuses ([`implausible`],
/// [`undetermined`]) and
/// withdraws the drag terms of a record without thrust ([`without_thrust`]); the caller judges
/// the status afterwards.
pub fn check<'a>(
    model: &ModelSpec,
    thrust_mapped: bool,
    results: impl IntoIterator<Item = &'a mut ParameterResult>,
) {
    for r in results {
        if without_thrust(r, thrust_mapped) {
            continue;
        }
        let (Some(p), Some(e)) = (Param::from_name(&r.name), r.estimate) else { continue };
        if let Some(flag) = implausible(model, p, e, r.std_error) {
            r.flag(flag);
        }
        if let Some(flag) = undetermined(model, p, r.std_error) {
            r.flag(flag);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> ModelSpec {
        ModelSpec::preset("six-axis").unwrap()
    }

    /// The 2σ margin: CD_0 = −0.068 ± 0.015 is 4.5σ below 0 (flagged); −0.02 ± 0.015 is within
    /// 2σ of the range (not flagged); a surface in degrees mapped as radians (Cm_de −1.53/57.3
    /// with a small σ) is flagged with the unit named as the likely cause.
    #[test]
    fn outside_by_more_than_two_sigma_is_flagged_with_its_cause() {
        let m = ModelSpec::preset("longitudinal").unwrap();
        let cd0 = Param::from_name("CD_0").unwrap();
        let f = implausible(&m, cd0, -0.068, Some(0.015)).unwrap();
        assert!(f.contains("likely the thrust model"), "{f}");
        assert!(implausible(&m, cd0, -0.02, Some(0.015)).is_none());
        let cm_q = Param::from_name("Cm_q").unwrap();
        let f = implausible(&m, cm_q, 5.0, Some(0.1)).unwrap();
        assert!(f.contains("likely a time skew or lag between the rate"), "{f}");
        let cl_alpha = Param::from_name("CL_alpha").unwrap();
        let f = implausible(&m, cl_alpha, 0.5, Some(0.01)).unwrap();
        assert!(f.contains("likely an angle in the wrong unit"), "{f}");
        let de = Param::from_name("Cm_de").unwrap();
        let f = implausible(&m, de, -1.53 / 57.3, Some(0.001)).unwrap();
        assert!(f.contains("degrees mapped as radians") && f.contains("[-5, -0.1]"), "{f}");
        assert!(implausible(&m, de, -1.53, Some(0.1)).is_none());
        // An override replaces the conventional range.
        let mut m = m;
        m.plausible.push(aeroident_io::PlausibleRange { param: de, min: 0.2, max: 2.0 });
        assert!(implausible(&m, de, -1.53, Some(0.1)).unwrap().contains("this aircraft's"));
        assert!(implausible(&m, de, 1.0, None).is_none());
        // A parameter held at its prior has a NaN σ: inside the range it is not flagged,
        // outside it is (no margin).
        let cy_beta = Param::from_name("CY_beta").unwrap();
        let six = model();
        assert!(implausible(&six, cy_beta, -0.5, Some(f64::NAN)).is_none());
        assert!(implausible(&six, cy_beta, 0.5, Some(f64::NAN)).is_some());
    }

    /// The PX4 template log's output-error CL_0 = −6.46 ± 22: ±2σ spans 88, the range of a
    /// conventional aircraft's CL_0 is 2 wide: flagged though its relative σ is exempt (a
    /// constant term) and the 2σ margin swallows the range check. CL_0 = 0.3 ± 0.4 (±2σ = 1.6
    /// wide) is not; nor is a term without a range.
    #[test]
    fn a_sigma_wider_than_the_plausible_range_is_flagged() {
        let m = ModelSpec::preset("longitudinal").unwrap();
        let cl0 = Param::from_name("CL_0").unwrap();
        assert!(implausible(&m, cl0, -6.457, Some(22.0)).is_none(), "the 2σ margin covers it");
        let f = undetermined(&m, cl0, Some(22.0)).unwrap();
        assert!(f.contains("[-0.5, 1.5]") && f.contains("does not determine"), "{f}");
        let mut r = ParameterResult::new("CL_0", Some(-6.457), Some(22.0), None, None);
        check(&m, true, std::iter::once(&mut r));
        assert_eq!(r.flags.len(), 1, "{:?}", r.flags);
        assert!(undetermined(&m, cl0, Some(0.4)).is_none());
        // At the edge: ±2σ exactly as wide as the range [-0.5, 1.5] is not wider.
        assert!(undetermined(&m, cl0, Some(0.5)).is_none());
        assert!(undetermined(&m, cl0, Some(0.500_001)).is_some());
        assert!(undetermined(&m, Param::from_name("CL_q").unwrap(), Some(1e3)).is_none());
    }

    /// Without thrust the drag terms are withdrawn with the reason, the others untouched.
    #[test]
    fn drag_terms_without_thrust_are_not_identified() {
        let mut rs = [
            ParameterResult::new("CD_0", Some(-0.07), Some(0.01), None, None),
            ParameterResult::new("Cl_p", Some(-0.4), Some(0.01), None, None),
        ];
        check(&model(), false, rs.iter_mut());
        assert_eq!((rs[0].estimate, rs[0].status.as_str()), (None, "not identified"));
        assert!(rs[0].flags[0].starts_with("thrust is not mapped"));
        assert_eq!((rs[1].estimate, rs[1].flags.len()), (Some(-0.4), 0));
        let mut cd = ParameterResult::new("CD_0", Some(0.03), Some(0.01), None, None);
        check(&model(), true, std::iter::once(&mut cd));
        assert_eq!((cd.estimate, cd.flags.len()), (Some(0.03), 0));
    }

    /// Without thrust, a 26 % speed change (about the JSBSim Cessna 172 multisine record's 27 %) or a
    /// throttle moved 15 % of its travel flags every `Cm` term, through a warning about the
    /// coefficient; 4 % (its 3-2-1-1 record) does not, nor any change with `thrust` or
    /// `thrust_moment` mapped, nor a structure without `Cm`.
    #[test]
    fn cm_terms_without_thrust_are_flagged_when_the_speed_or_throttle_varied() {
        use aeroident_estimators::ModelStructure;
        let base = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n";
        let no_thrust = Mapping::from_toml_str(base, "m.toml").unwrap();
        let lon = ModelStructure::preset("longitudinal").unwrap();
        let w = unmapped_thrust_moment(&lon, &no_thrust, Some((48.7, 63.3)), None).unwrap();
        assert!(w.text.contains("airspeed varied 26 %") && w.text.contains("`thrust_moment`"));
        let mut ws = aeroident_io::warning::Warnings::new();
        ws.push(w);
        assert_eq!(
            (ws.about("Cm_q").len(), ws.about("Cm_0").len(), ws.about("CL_alpha").len()),
            (1, 1, 0)
        );
        assert!(unmapped_thrust_moment(&lon, &no_thrust, Some((57.9, 60.3)), None).is_none());
        let w = unmapped_thrust_moment(&lon, &no_thrust, Some((57.9, 60.3)), Some((0.5, 0.65)));
        assert!(w.unwrap().text.contains("throttle moved 15 %"));
        // At the 10 % limit (exactly, in floating point) it is not exceeded; just past it is.
        let at = |speed, throttle| unmapped_thrust_moment(&lon, &no_thrust, speed, throttle);
        assert!(at(Some((95.0, 105.0)), None).is_none());
        assert!(at(Some((94.999, 105.0)), None).is_some());
        assert!(at(None, Some((0.0, 0.1))).is_none());
        assert!(at(None, Some((0.0, 0.100_001))).is_some());
        for channel in [
            "thrust = { column = \"T\", unit = \"N\" }",
            "thrust_moment = { column = \"M\", unit = \"N*m\" }",
        ] {
            let m = Mapping::from_toml_str(&format!("{base}{channel}\n"), "m.toml").unwrap();
            assert!(
                unmapped_thrust_moment(&lon, &m, Some((48.7, 63.3)), None).is_none(),
                "{channel}"
            );
        }
        let lat = ModelStructure::preset("lateral").unwrap();
        assert!(unmapped_thrust_moment(&lat, &no_thrust, Some((48.7, 63.3)), None).is_none());
    }

    /// Every conventional range at its edges, hand-set (the numbers of
    /// `aeroident_estimators::prior::plausible_range`'s doc and table): a value just inside
    /// either bound is not flagged, just outside is (no σ); and the 2σ margin at its edge: a
    /// value outside by just under 2σ is not flagged, by just over is.
    #[test]
    fn every_range_and_the_margin_at_their_edges() {
        let m = ModelSpec::preset("six-axis").unwrap();
        #[rustfmt::skip]
        let table: [(&str, f64, f64); 19] = [
            ("CL_0", -0.5, 1.5), ("CL_alpha", 1.5, 8.0), ("CZ_alpha", -8.0, -1.5),
            ("CD_0", 0.0, 0.3), ("CD_alpha", -0.2, 3.0), ("Cm_alpha", -5.0, 1.0),
            ("Cm_q", -100.0, 0.0), ("Cm_de", -5.0, -0.1), ("CY_beta", -2.0, 0.0),
            ("Cl_beta", -0.5, 0.05), ("Cl_p", -1.5, 0.0), ("Cl_da", -1.0, -0.02),
            ("Cn_beta", -0.05, 0.5), ("Cn_r", -1.0, 0.0), ("Cn_dr", -0.5, -0.01),
            ("CY_da", -0.5, 0.5), ("CY_dr", -0.2, 1.0), ("Cl_dr", -0.2, 0.2), ("Cn_da", -0.2, 0.2),
        ];
        let e = 1e-9;
        for (name, lo, hi) in table {
            let p = Param::from_name(name).unwrap();
            assert_eq!(m.plausible_range(p), Some((lo, hi)), "{name}");
            for (v, flagged) in [(lo + e, false), (hi - e, false), (lo - e, true), (hi + e, true)] {
                assert_eq!(implausible(&m, p, v, None).is_some(), flagged, "{name} = {v}");
            }
            let s = 0.01;
            assert!(implausible(&m, p, hi + 2.0 * s - e, Some(s)).is_none(), "{name}");
            assert!(implausible(&m, p, hi + 2.0 * s + e, Some(s)).is_some(), "{name}");
            assert!(implausible(&m, p, lo - 2.0 * s + e, Some(s)).is_none(), "{name}");
            assert!(implausible(&m, p, lo - 2.0 * s - e, Some(s)).is_some(), "{name}");
        }
        // The undetermined rule: ±2σ (4σ wide) just inside and just past the range's width.
        let cl_alpha = Param::from_name("CL_alpha").unwrap();
        assert!(undetermined(&m, cl_alpha, Some(6.5 / 4.0 - e)).is_none());
        assert!(undetermined(&m, cl_alpha, Some(6.5 / 4.0 + e)).is_some());
    }
}
