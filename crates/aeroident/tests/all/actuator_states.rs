//! The mapping's servo travels with the model: `linearize` of a model-file aircraft whose
//! mapping gives the elevator and aileron actuators has one state per actuator (named as
//! `sim` records the surface) with the pole −1/τ, the surfaces' inputs are their commands, and
//! the text says rate limits are not in a linear model; `design` predicts through the
//! actuator, says so with τ, and flags a rate limit the table reaches. Without actuators
//! the output has none of it.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// An elevator-and-aileron UAV card (no rudder derivative: the rudder is held) with a
/// conventional roll damping, as `cli_linearize` writes it.
const MODEL: &str = "description = \"uav\"\n[coefficients]\nCL = [\"0\", \"alpha\", \"de\"]\nCD = [\"0\"]\nCY = [\"beta\"]\nCl = [\"beta\", \"p\", \"da\"]\nCm = [\"0\", \"alpha\", \"q\", \"de\"]\nCn = [\"beta\", \"r\"]\n";

const VALUES: [(&str, f64); 14] = [
    ("CL_0", 0.3),
    ("CL_alpha", 4.8),
    ("CL_de", 0.3),
    ("CD_0", 0.03),
    ("CY_beta", -0.3),
    ("Cl_beta", -0.08),
    ("Cl_p", -0.45),
    ("Cl_da", -0.25),
    ("Cm_0", 0.02),
    ("Cm_alpha", -0.6),
    ("Cm_q", -9.0),
    ("Cm_de", -1.0),
    ("Cn_beta", 0.06),
    ("Cn_r", -0.08),
];

const CONSTANTS: &str = "mass = { value = 3.3, unit = \"kg\" }\nIxx = { value = 0.17, unit = \"kg*m2\" }\nIyy = { value = 0.289, unit = \"kg*m2\" }\nIzz = { value = 0.443, unit = \"kg*m2\" }\nS = { value = 0.384, unit = \"m2\" }\nb = { value = 1.6, unit = \"m\" }\ncbar = { value = 0.24, unit = \"m\" }\n";

/// A scratch directory with the model and two mappings: `bare.toml` (no actuator) and
/// `servo.toml` (elevator τ `tau_de`, rate limit `rate_de` rad/s, ±0.4 rad; aileron τ 0.1 s).
fn files(tag: &str, tau_de: f64, rate_de: f64) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroident-actuator-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let mut model = String::from(MODEL);
    for (n, v) in VALUES {
        model.push_str(&format!("[reference.{n}]\nvalue = {v}\nsource = \"t\"\n"));
    }
    std::fs::write(d.join("uav.toml"), model).unwrap();
    let head = "description = \"c\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nqbar = { column = \"q\", unit = \"Pa\" }\n";
    std::fs::write(d.join("bare.toml"), format!("{head}{CONSTANTS}")).unwrap();
    let servo = format!(
        "{head}{CONSTANTS}de = {{ column = \"de_cmd\", unit = \"rad\", actuator = {{ tau_s = {tau_de}, rate_limit_rad_s = {rate_de}, position_limits_rad = [-0.4, 0.4] }} }}\nda = {{ column = \"da_cmd\", unit = \"rad\", actuator = {{ tau_s = 0.1 }} }}\n"
    );
    std::fs::write(d.join("servo.toml"), servo).unwrap();
    d
}

fn run(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident")).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    out
}

fn linearize(d: &Path, map: &str, json: bool) -> Output {
    let (m, c) = (d.join("uav.toml"), d.join(map));
    let mut args =
        vec!["linearize", "--aircraft", m.to_str().unwrap(), "--map", c.to_str().unwrap()];
    args.extend(["--vt-mps", "18", "--alt-m", "0"]);
    if json {
        args.push("--json");
    }
    run(&args)
}

#[test]
fn linearize_carries_the_actuators_as_states_with_their_poles() {
    let d = files("lin", 0.05, 2.0);
    let bare: Value = serde_json::from_slice(&linearize(&d, "bare.toml", true).stdout).unwrap();
    let servo: Value = serde_json::from_slice(&linearize(&d, "servo.toml", true).stdout).unwrap();
    assert_eq!(bare["states"].as_array().unwrap().len(), 12);
    assert!(bare.get("actuators").is_none() && bare.get("notes").is_none());
    let states: Vec<&str> =
        servo["states"].as_array().unwrap().iter().map(|s| s.as_str().unwrap()).collect();
    assert_eq!(&states[12..], ["elevator_rad", "aileron_rad"]);
    let inputs: Vec<&str> =
        servo["inputs"].as_array().unwrap().iter().map(|s| s.as_str().unwrap()).collect();
    assert_eq!(&inputs[1..], ["elevator_cmd_rad", "aileron_cmd_rad", "rudder_rad"]);
    let a = servo["a"].as_array().unwrap();
    assert_eq!((a.len(), a[12].as_array().unwrap().len()), (14, 14));
    assert_eq!(servo["b"][12][1].as_f64().unwrap(), 20.0);
    assert_eq!(servo["d"].as_array().unwrap().len(), 14);
    for tau in [0.05, 0.1] {
        let found = servo["eigenvalues"].as_array().unwrap().iter().any(|e| {
            (e[0].as_f64().unwrap() + 1.0 / tau).abs() < 1e-9 && e[1].as_f64().unwrap() == 0.0
        });
        assert!(found, "no eigenvalue at -1/{tau}");
    }
    assert_eq!(servo["modes"], bare["modes"], "the rigid-body modes are the aircraft's");
    assert_eq!(servo["actuators"][0]["pole"][0].as_f64().unwrap(), -20.0);
    assert!(servo["actuators"][1]["rate_limit_rad_s"].is_null());
    let text = String::from_utf8(linearize(&d, "servo.toml", false).stdout).unwrap();
    assert!(text.contains("eigenvalues (14-state A)"), "{text}");
    assert!(text.contains("actuator de") && text.contains("actuator da"), "{text}");
    assert!(text.contains("note:") && text.contains("rate limits"), "{text}");
    let plain = String::from_utf8(linearize(&d, "bare.toml", false).stdout).unwrap();
    assert!(plain.contains("eigenvalues (12-state A)") && !plain.contains("actuator de"));
    assert!(!plain.contains("note:"), "{plain}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `design --aircraft` through an elevator actuator: the text and `design.json` say so with
/// τ; a 4° elevator multisine up to 1.5 Hz (slope ≈ 0.66 rad/s) against a 0.2 rad/s limit is
/// flagged, naming `de`; against 2 rad/s it is not.
#[test]
fn design_predicts_through_the_actuator_and_flags_its_rate_limit() {
    for (rate, flagged) in [(0.2, true), (2.0, false)] {
        let d = files(if flagged { "slow" } else { "fast" }, 0.05, rate);
        let (m, c, out) = (d.join("uav.toml"), d.join("servo.toml"), d.join("des"));
        let args = ["design", "--aircraft", m.to_str().unwrap(), "--map", c.to_str().unwrap()];
        let more = ["--vt-mps", "18", "--alt-m", "0", "--surfaces", "de", "--amplitude-deg", "4"];
        let o = run(&[&args[..], &more[..], &["--out", out.to_str().unwrap()]].concat());
        let text = String::from_utf8(o.stdout).unwrap();
        assert!(text.contains("prediction through the mapping's actuators"), "{text}");
        assert!(text.contains("de tau 0.05 s"), "{text}");
        assert_eq!(text.contains("flag: de: the actuator's rate limit"), flagged, "{text}");
        let j: Value =
            serde_json::from_slice(&std::fs::read(out.join("design.json")).unwrap()).unwrap();
        let s = &j["actuators"]["surfaces"][0];
        assert_eq!((s["surface"].as_str(), s["tau_s"].as_f64()), (Some("de"), Some(0.05)));
        let fraction = s["rate_limited_fraction"].as_f64().unwrap();
        assert_eq!(fraction > 0.0, flagged, "{fraction}");
        assert_eq!(j["actuators"]["flags"].as_array().unwrap().len(), usize::from(flagged));
        let _ = std::fs::remove_dir_all(&d);
    }
}
