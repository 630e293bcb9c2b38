//! `aeroident sim --aircraft MODEL.toml`: a model-file aircraft (a Cessna-172-sized
//! six-axis model with given values and constants) flies doublets on every surface; its record
//! replays through the `mapping.toml` written beside it, and output error with the same model
//! structure gives back the values it flew, each within 0.1 % (noise-free). The replay side (mapping, units, samples, the
//! fit's own integration) shares no code with the simulation's recording, so a wrong column,
//! unit or sign anywhere on the way shows as a wrong derivative.

use std::path::{Path, PathBuf};
use std::process::Command;

fn run(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident")).args(args).output().unwrap();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `(name, value)` of the flown model: magnitudes of a light single-engine aircraft.
const VALUES: [(&str, f64); 24] = [
    ("CL_0", 0.31),
    ("CL_alpha", 5.14),
    ("CL_q", 3.9),
    ("CL_de", 0.43),
    ("CD_0", 0.031),
    ("CD_alpha", 0.13),
    ("CY_beta", -0.31),
    ("CY_dr", 0.187),
    ("Cl_beta", -0.089),
    ("Cl_p", -0.47),
    ("Cl_r", 0.096),
    ("Cl_da", -0.178),
    ("Cl_dr", 0.0147),
    ("Cm_0", 0.04),
    ("Cm_alpha", -0.89),
    ("Cm_q", -12.4),
    ("Cm_de", -1.28),
    ("Cn_beta", 0.065),
    ("Cn_p", -0.03),
    ("Cn_r", -0.099),
    ("Cn_da", -0.0053),
    ("Cn_dr", -0.0657),
    ("CY_p", -0.037),
    ("CY_r", 0.21),
];

fn write_inputs(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    std::fs::create_dir_all(dir).unwrap();
    let mut model = String::from(
        "description = \"light single (test)\"\n[coefficients]\nCL = [\"0\", \"alpha\", \"q\", \"de\"]\nCD = [\"0\", \"alpha\"]\nCY = [\"beta\", \"p\", \"r\", \"dr\"]\nCl = [\"beta\", \"p\", \"r\", \"da\", \"dr\"]\nCm = [\"0\", \"alpha\", \"q\", \"de\"]\nCn = [\"beta\", \"p\", \"r\", \"da\", \"dr\"]\n",
    );
    for (name, v) in VALUES {
        model.push_str(&format!("[reference.{name}]\nvalue = {v}\nsource = \"test\"\n"));
    }
    // A record's mapping: its channels name some record's columns; the aircraft takes the
    // constants.
    let map = "description = \"a record's mapping\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nde = { column = \"de\", unit = \"rad\" }\nqbar = { column = \"qbar\", unit = \"Pa\" }\nmass = { value = 1043.0, unit = \"kg\" }\nIxx = { value = 1285.0, unit = \"kg*m2\" }\nIyy = { value = 1825.0, unit = \"kg*m2\" }\nIzz = { value = 2667.0, unit = \"kg*m2\" }\nS = { value = 16.17, unit = \"m2\" }\nb = { value = 10.91, unit = \"m\" }\ncbar = { value = 1.49, unit = \"m\" }\n";
    let doublet = |ch: &str, deg: f64, t0: f64| {
        format!(
            "[[input]]\nchannel = \"{ch}\"\nkind = \"doublet\"\namplitude_deg = {deg}\nstart_s = {t0}\npulse_width_s = 0.6\n"
        )
    };
    let scenario = format!(
        "kind = \"sim\"\n[trim]\nvt_mps = 55.0\nalt_m = 1200.0\n[run]\nduration_s = 16.0\ndt_s = 0.02\n{}{}{}",
        doublet("elevator", 2.0, 1.0),
        doublet("aileron", 3.0, 5.0),
        doublet("rudder", 3.0, 10.0)
    );
    let paths = (dir.join("model.toml"), dir.join("constants.toml"), dir.join("scenario.toml"));
    std::fs::write(&paths.0, model).unwrap();
    std::fs::write(&paths.1, map).unwrap();
    std::fs::write(&paths.2, scenario).unwrap();
    paths
}

#[test]
fn a_model_file_aircraft_s_record_replays_to_the_values_it_flew() {
    let dir = std::env::temp_dir().join(format!("aeroident-cli-sim-{}", std::process::id()));
    let (model, constants, scenario) = write_inputs(&dir);
    let (sim, fit) = (dir.join("sim"), dir.join("fit"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let said = run(&[
        "sim",
        &s(&scenario),
        "--aircraft",
        &s(&model),
        "--map",
        &s(&constants),
        "--out",
        &s(&sim),
    ]);
    assert!(said.contains("mapping.toml") && said.contains("55.000 m/s"), "{said}");
    for f in ["timeseries.csv", "mapping.toml", "report.html", "states.png", "controls.png"] {
        assert!(sim.join(f).exists(), "{f}");
    }
    run(&[
        "replay",
        &s(&sim.join("timeseries.csv")),
        "--map",
        &s(&sim.join("mapping.toml")),
        "--estimator",
        "oe",
        "--model",
        &s(&model),
        "--out",
        &s(&fit),
    ]);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fit.join("summary.json")).unwrap()).unwrap();
    let estimates = summary["parameters"].as_array().unwrap();
    for (name, truth) in VALUES {
        let p = estimates.iter().find(|p| p["name"] == name).unwrap_or_else(|| panic!("{name}"));
        let e = p["estimate"].as_f64().unwrap_or_else(|| panic!("{name}: {p}"));
        eprintln!("{name}: {e:.5} flown {truth}");
        assert!((e - truth).abs() <= 1e-3 * truth.abs(), "{name}: {e} against {truth}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
