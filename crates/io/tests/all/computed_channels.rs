//! Channels a raw log does not record directly, computed by the mapping: density from pressure
//! altitude and static temperature, mass from fuel used, inertias scaled with mass, and any
//! expression over columns, each checked against hand arithmetic and the standard atmosphere's
//! published values; a bad expression is an error naming the file and the channel.

use aeroident_io::{FlightDataError, FlightDataReader, Mapping, RecordEvent, RowProblem};

const MAPPING: &str = r#"
inertia_reference_mass_kg = 17631.0
[time]
column = "t"
unit = "s"
[channels]
vt = { column = "V", unit = "m/s" }
alpha = { column = "a", unit = "deg" }
rho = { expr = "isa_pressure(h_ft * 0.3048) / (287.05287 * sat_K)", unit = "kg/m3" }
mass = { expr = "17631 - fuel_used_kg", unit = "kg" }
Ixx = { value = 1.33367e5, unit = "kg*m2" }
de = { expr = "({elev.left} + {elev.right}) / 2", unit = "deg", offset = 1.0 }
S = { value = 64.0, unit = "m2" }
"#;

const CSV: &str = "t,V,a,h_ft,sat_K,fuel_used_kg,elev.left,elev.right\n\
0.0,100.0,2.0,0.0,288.15,0.0,1.0,3.0\n\
0.1,100.0,2.0,16404.2,255.65,1763.1,-2.0,-4.0\n\
0.2,100.0,2.0,70000.0,216.65,0.0,0.0,0.0\n";

fn events(mapping: &str, csv: &str) -> Vec<RecordEvent> {
    let m = Mapping::from_toml_str(mapping, "computed.toml").unwrap();
    FlightDataReader::new(csv.as_bytes(), "computed.csv", &m).unwrap().map(|e| e.unwrap()).collect()
}

fn sample(e: &RecordEvent) -> &aeroident_estimators::AirDataSample {
    match e {
        RecordEvent::Sample { sample, .. } => sample,
        other => panic!("{other:?}"),
    }
}

/// ISA at sea level (1.2250 kg/m³) and at 5 km pressure altitude on a standard day (0.73612
/// kg/m³; 16 404.2 ft, 255.65 K); mass = 17 631 − fuel; Ixx × mass / 17 631; the mean of two
/// elevator columns plus the offset; a pressure altitude above the model is a rejected row
/// naming the expression.
#[test]
fn analytic_density_mass_inertia_and_expression_channels() {
    let ev = events(MAPPING, CSV);
    assert_eq!(ev.len(), 3);
    let (s0, s1) = (sample(&ev[0]), sample(&ev[1]));
    assert!((s0.rho_kgpm3.unwrap() - 1.2250).abs() < 1e-4, "{:?}", s0.rho_kgpm3);
    assert!((s1.rho_kgpm3.unwrap() - 0.736_12).abs() < 2e-4, "{:?}", s1.rho_kgpm3);
    assert!((s0.qbar_pa - 0.5 * 1.2250 * 100.0 * 100.0).abs() < 1.0);
    assert_eq!(s0.constants.mass_kg, 17631.0);
    assert_eq!(s1.constants.mass_kg, 17631.0 - 1763.1);
    assert!((s1.constants.Ixx_kgm2.unwrap() - 1.33367e5 * 0.9).abs() < 1e-6);
    assert_eq!(s0.constants.Ixx_kgm2, Some(1.33367e5));
    assert!((s0.de_rad.unwrap() - 3.0f64.to_radians()).abs() < 1e-15);
    assert!((s1.de_rad.unwrap() - (-2.0f64).to_radians()).abs() < 1e-15);
    let RecordEvent::Rejected { row: 4, problem: RowProblem::NonFiniteSi { column, channel, .. } } =
        &ev[2]
    else {
        panic!("{:?}", ev[2])
    };
    assert_eq!(channel, "rho");
    assert!(column.starts_with("expr `isa_pressure(h_ft"), "{column}");
}

/// A mapped expression's columns must be in the record, an expression must parse and read a
/// column, and `expr` excludes the other sources: each refusal names the file and channel.
#[test]
fn errors_bad_expressions_name_the_file_and_channel() {
    let with = |line: &str| {
        MAPPING.replace("mass = { expr = \"17631 - fuel_used_kg\", unit = \"kg\" }", line)
    };
    for (line, needle) in [
        ("mass = { expr = \"17631 - \", unit = \"kg\" }", "expr `17631 - `"),
        ("mass = { expr = \"17631\", unit = \"kg\" }", "reads no column"),
        ("mass = { expr = \"m\", value = 3.0, unit = \"kg\" }", "exactly one of"),
    ] {
        let e = Mapping::from_toml_str(&with(line), "computed.toml").unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, FlightDataError::BadSpec { .. }), "{text}");
        assert!(
            text.contains("computed.toml") && text.contains("mass") && text.contains(needle),
            "{text}"
        );
    }
    let m = Mapping::from_toml_str(
        &with("mass = { expr = \"m0 - burnt\", unit = \"kg\" }"),
        "computed.toml",
    )
    .unwrap();
    let Err(e) = FlightDataReader::new(CSV.as_bytes(), "computed.csv", &m) else { panic!() };
    assert!(
        matches!(&e, FlightDataError::MissingColumn { column, channel, .. } if column == "burnt" || column == "m0")
            && e.to_string().contains("mass"),
        "{e}"
    );
    let bad =
        MAPPING.replace("inertia_reference_mass_kg = 17631.0", "inertia_reference_mass_kg = 0.0");
    let e = Mapping::from_toml_str(&bad, "computed.toml").unwrap_err().to_string();
    assert!(e.contains("inertia_reference_mass_kg") && e.contains("> 0"), "{e}");
}

/// Expressions that do not parse: the error names the file, the channel and the expression,
/// and says what is wrong in the mapping's terms (the parser's own wording, about its counts of
/// operators and nodes, is not what a user can act on).
#[test]
fn errors_malformed_expressions_say_what_is_wrong_in_plain_words() {
    let with = |expr: &str| {
        MAPPING.replace(
            "de = { expr = \"({elev.left} + {elev.right}) / 2\", unit = \"deg\", offset = 1.0 }",
            &format!("de = {{ expr = \"{expr}\", unit = \"deg\" }}"),
        )
    };
    for (expr, cause) in [
        (
            "2e * elevator_rad",
            "`2e` is not a number: exponent notation needs digits after `e`, as in `2e-3`",
        ),
        (
            "1.5E+ * x",
            "`1.5E+` is not a number: exponent notation needs digits after `E`, as in `2e-3`",
        ),
        ("2x + 1", "`2x` is not a number"),
        ("3. * x", "`3.` is not a number: a decimal point needs digits after it, as in `3.0`"),
        ("x y", "no operator between `x` and `y`"),
        ("2 (x + 1)", "no operator between `2` and `(`"),
        ("(x + 1", "the `(` at character 1 is not closed"),
        ("x + 1)", "the `)` at character 6 closes no `(`"),
        ("x * / y", "`/` at character 5 has no value on its left"),
        ("x *", "the expression ends with `*`: a value is missing after it"),
        ("x $ y", "`$` (character 3) is not part of an expression"),
        ("{x + 1", "the `{` at character 1 has no closing `}`"),
    ] {
        let e = Mapping::from_toml_str(&with(expr), "computed.toml").unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, FlightDataError::BadSpec { .. }), "{expr}: {text}");
        assert!(
            text.starts_with(&format!("computed.toml: channel `de`: expr `{expr}`: ")),
            "{expr}: {text}"
        );
        assert!(text.contains(cause), "{expr}: {text}");
        assert!(!text.contains("node") && !text.contains("wlog"), "{expr}: {text}");
    }
}

/// A mapping whose constants describe no body is refused naming the file and the channel:
/// moments of inertia that break the triangle inequality (each at most the sum of the other
/// two), an `Ixz` with `Ixz² ≥ Ixx·Izz`, and an `inertia_reference_mass_kg` so far from the
/// constant mass that the scaled inertias are a unit error (1 kg beside a 17,631-kg aircraft
/// scaled them ×17,631 and gave Cm_α −17,817 "converged"). The edges pass: a flat plate's
/// `Izz = Ixx + Iyy`, a ratio of exactly 3.
#[test]
fn errors_constants_of_a_body_that_cannot_exist() {
    // The module's mapping without its mass, inertia and reference mass.
    let base: String = MAPPING
        .lines()
        .filter(|l| !l.starts_with("Ixx") && !l.starts_with("inertia_"))
        .map(|l| format!("{l}\n"))
        .collect();
    let with = |extra: &str| Mapping::from_toml_str(&format!("{base}{extra}"), "body.toml");
    let constant_mass = base.replace(
        "mass = { expr = \"17631 - fuel_used_kg\", unit = \"kg\" }",
        "mass = { value = 17631.0, unit = \"kg\" }",
    );
    assert_ne!(constant_mass, base);
    let inertia = |ixx: f64, iyy: f64, izz: f64, ixz: f64| {
        with(&format!(
            "Ixx = {{ value = {ixx}, unit = \"kg*m2\" }}\nIyy = {{ value = {iyy}, unit = \"kg*m2\" }}\nIzz = {{ value = {izz}, unit = \"kg*m2\" }}\nIxz = {{ value = {ixz}, unit = \"kg*m2\" }}\n"
        ))
    };
    inertia(133367.0, 252687.0, 359593.0, 11442.0).unwrap();
    inertia(1.0, 2.0, 3.0, 0.0).unwrap();
    let e = inertia(1.0, 2.0, 3.01, 0.0).unwrap_err().to_string();
    assert!(e.contains("body.toml") && e.contains("Izz = 3.01 kg·m² exceeds Ixx + Iyy = 3"), "{e}");
    let e = inertia(1.0, 5.0, 3.0, 0.0).unwrap_err().to_string();
    assert!(e.contains("Iyy = 5 kg·m² exceeds Ixx + Izz = 4"), "{e}");
    inertia(4.0, 5.0, 9.0, 5.99).unwrap();
    let e = inertia(4.0, 5.0, 9.0, 6.0).unwrap_err().to_string();
    assert!(e.contains("Ixz = 6 kg·m²") && e.contains("below Ixx·Izz"), "{e}");
    let mass = |m0: f64| {
        Mapping::from_toml_str(
            &format!(
                "inertia_reference_mass_kg = {m0}\n{constant_mass}Ixx = {{ value = 1.0, unit = \"kg*m2\" }}\n"
            ),
            "body.toml",
        )
    };
    mass(17631.0 / 3.0).unwrap();
    mass(17631.0 * 3.0).unwrap();
    let e = mass(1.0).unwrap_err().to_string();
    assert!(e.contains("inertia_reference_mass_kg") && e.contains("1 kg beside"), "{e}");
    assert!(e.contains("scale the inertias by 17631:"), "{e}");
    assert!(mass(17631.0 / 3.01).is_err() && mass(17631.0 * 3.01).is_err());
}
