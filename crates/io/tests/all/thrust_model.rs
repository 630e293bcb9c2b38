//! `[thrust_model]`: thrust from the throttle or the propeller speed, per sample, checked
//! against the law computed by hand from the record's own columns; and the mapping errors that
//! name what is wrong.

use aeroident_io::{FlightDataReader, Mapping, RecordEvent};

const HEAD: &str = r#"
[time]
column = "t"
unit = "s"
[channels]
vt = { column = "V", unit = "m/s" }
alpha = { column = "a", unit = "deg" }
throttle = { column = "thr", unit = "1", scale = 0.01 }
prop_speed = { column = "rpm", unit = "rpm" }
rho = { value = 1.2, unit = "kg/m3" }
mass = { value = 3.3, unit = "kg" }
S = { value = 0.384, unit = "m2" }
"#;

/// Rows: time, airspeed, α, throttle in percent, motor speed in rpm.
const CSV: &str = "t,V,a,thr,rpm\n0.0,15.0,2.0,40,9000\n0.1,18.0,2.5,64,10200\n0.2,5.0,0.0,0,0\n";

fn thrusts(law: &str) -> Vec<Option<f64>> {
    let m = Mapping::from_toml_str(&format!("{HEAD}{law}"), "law.toml").unwrap();
    FlightDataReader::new(CSV.as_bytes(), "law.csv", &m)
        .unwrap()
        .map(|e| match e.unwrap() {
            RecordEvent::Sample { sample, .. } => sample.thrust_n,
            other => panic!("{other:?}"),
        })
        .collect()
}

/// The propeller law by hand from each row: n = rpm/60, J = V/(n D),
/// T = ρ n² D⁴ (ct0 + ct_j J); a propeller at rest gives 0.
#[test]
fn analytic_propeller_law_gives_each_rows_thrust() {
    let t = thrusts(
        "[thrust_model]\nlaw = \"propeller\"\ndiameter_m = 0.28\nct0 = 0.1\nct_j = -0.12\n",
    );
    for (got, (v, rpm)) in t.iter().zip([(15.0, 9000.0), (18.0, 10200.0), (5.0, 0.0)]) {
        let n: f64 = rpm / 60.0;
        let j = if n > 0.0 { v / (n * 0.28) } else { 0.0 };
        let by_hand = 1.2 * n * n * 0.28f64.powi(4) * (0.1 - 0.12 * j);
        assert!(
            (got.unwrap() - by_hand).abs() <= 1e-12 * by_hand.abs().max(1.0),
            "{got:?} {by_hand}"
        );
    }
    assert!((t[0].unwrap() - 9.4833).abs() < 1e-4, "{t:?}");
}

/// The throttle law by hand: 30 N static, zero at 40 m/s, exponent 1:
/// 30·0.40·(1 − 15/40) = 7.5 N, 30·0.64·(1 − 18/40) = 10.56 N, 0 at idle.
#[test]
fn analytic_throttle_law_gives_each_rows_thrust() {
    let t = thrusts(
        "[thrust_model]\nlaw = \"throttle\"\nstatic_thrust_n = 30\nzero_thrust_speed_mps = 40\n",
    );
    for (got, want) in t.iter().zip([7.5, 10.56, 0.0]) {
        assert!((got.unwrap() - want).abs() < 1e-12, "{got:?} against {want}");
    }
}

/// A law beside a thrust channel, a law without its input channel and a bad constant are
/// refused, each naming the table and the key.
#[test]
fn errors_a_thrust_model_names_what_is_wrong() {
    let refuse = |text: &str| Mapping::from_toml_str(text, "bad.toml").unwrap_err().to_string();
    let law =
        "[thrust_model]\nlaw = \"throttle\"\nstatic_thrust_n = 30\nzero_thrust_speed_mps = 40\n";
    let both = HEAD.replace("[channels]\n", "[channels]\nthrust = { value = 5.0, unit = \"N\" }\n");
    let e = refuse(&format!("{both}{law}"));
    assert!(
        e.contains("bad.toml") && e.contains("[thrust_model]") && e.contains("`thrust` channel"),
        "{e}"
    );
    let no_throttle: String =
        HEAD.lines().filter(|l| !l.starts_with("throttle")).map(|l| format!("{l}\n")).collect();
    let e = refuse(&format!("{no_throttle}{law}"));
    assert!(e.contains("reads channel `throttle`, which is not mapped"), "{e}");
    let e =
        refuse(&format!("{HEAD}[thrust_model]\nlaw = \"propeller\"\ndiameter_m = 0\nct0 = 0.1\n"));
    assert!(e.contains("`diameter_m` = 0 must be > 0"), "{e}");
}
