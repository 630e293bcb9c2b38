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

/// White noise on every output, SI (a small air-data system and an AHRS).
const SENSORS: [(&str, f64); 11] = [
    ("vt_mps", 0.3),
    ("alpha_rad", 0.0017),
    ("beta_rad", 0.0017),
    ("p_rad_s", 0.0025),
    ("q_rad_s", 0.0025),
    ("r_rad_s", 0.0025),
    ("phi_rad", 0.005),
    ("theta_rad", 0.005),
    ("ax_mps2", 0.1),
    ("ay_mps2", 0.1),
    ("az_mps2", 0.1),
];

/// [`write_inputs`] with the scenario's outputs sensed ([`SENSORS`]).
fn write_sensed_inputs(dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let (model, constants, scenario) = write_inputs(dir);
    let mut text = std::fs::read_to_string(&scenario).unwrap();
    for (ch, sigma) in SENSORS {
        text.push_str(&format!(
            "[[sensor]]\nchannel = \"{ch}\"\nwhite_sigma = {sigma}\nsample_rate_hz = 50.0\n"
        ));
    }
    std::fs::write(&scenario, text).unwrap();
    (model, constants, scenario)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// `run --aircraft MODEL.toml`: one noisy flight of the light single, `rls` and `oe` on its
/// record. Every reference is the value flown, and every output-error estimate lies within
/// 4σ of it (white noise: a fit whose σ or truth were wrong would not).
#[test]
fn a_model_file_aircraft_runs_its_estimation_experiment_against_the_values_flown() {
    let dir = std::env::temp_dir().join(format!("aeroident-cli-run-mf-{}", std::process::id()));
    let (model, constants, scenario) = write_sensed_inputs(&dir);
    let out = dir.join("run");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let said = run(&[
        "run",
        &s(&scenario),
        "--aircraft",
        &s(&model),
        "--map",
        &s(&constants),
        "--estimator",
        "rls,oe",
        "--out",
        &s(&out),
    ]);
    assert!(said.contains("rls") && said.contains("oe") && said.contains("flown"), "{said}");
    for f in ["timeseries.csv", "mapping.toml", "report.html", "summary.json"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let summary = json(&out.join("summary.json"));
    let estimators = summary["estimators"].as_array().unwrap();
    assert_eq!(estimators.len(), 2);
    let oe = estimators.iter().find(|e| e["name"] == "oe").unwrap();
    for (name, flown) in VALUES {
        let p = oe["params"].as_array().unwrap().iter().find(|p| p["name"] == name).unwrap();
        assert_eq!(p["reference"].as_f64(), Some(flown), "{name}");
        let (e, sigma) = (p["estimate"].as_f64().unwrap(), p["std_error"].as_f64().unwrap());
        assert!((e - flown).abs() <= 4.0 * sigma, "{name}: {e} ± {sigma} against {flown}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `montecarlo --aircraft MODEL.toml`: eight noisy flights; output error's scatter of each
/// primary derivative lies within [0.4, 2.0] × the Cramér–Rao σ of the flight (eight draws:
/// the sample σ has a relative standard error of 27 %), and the campaign is complete.
#[test]
fn a_model_file_aircraft_s_monte_carlo_scatters_as_its_bound() {
    let dir = std::env::temp_dir().join(format!("aeroident-cli-mc-mf-{}", std::process::id()));
    let (model, constants, scenario) = write_sensed_inputs(&dir);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let said = run(&[
        "montecarlo",
        &s(&scenario),
        "--aircraft",
        &s(&model),
        "--map",
        &s(&constants),
        "--estimator",
        "oe",
        "--runs",
        "8",
        "--json",
    ]);
    let c: serde_json::Value = serde_json::from_str(&said).unwrap();
    assert_eq!(c["status"], "complete", "{c}");
    let oe = &c["estimators"][0];
    assert_eq!(oe["name"], "oe");
    let mut checked = 0;
    for p in oe["parameters"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        let flown = VALUES.iter().find(|(n, _)| *n == name).unwrap().1;
        assert_eq!(p["reference"].as_f64(), Some(flown), "{name}");
        let ratio = p["scatter"].as_f64().unwrap() / p["crb_std_error"].as_f64().unwrap();
        assert!((0.4..=2.0).contains(&ratio), "{name}: scatter / σ_CRB {ratio}");
        checked += 1;
    }
    assert_eq!(checked, VALUES.len());
    let _ = std::fs::remove_dir_all(&dir);
}

/// What cannot make a model-file experiment is refused by name, before any flight.
#[test]
fn model_file_experiment_options_are_checked_by_name() {
    let dir = std::env::temp_dir().join(format!("aeroident-cli-mf-bad-{}", std::process::id()));
    let (model, constants, scenario) = write_inputs(&dir);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let fails = |args: &[&str], needle: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_aeroident")).args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(needle), "{args:?}: {err}");
    };
    let (m, c, sc) = (s(&model), s(&constants), s(&scenario));
    let aircraft = ["--aircraft", m.as_str(), "--map", c.as_str()];
    for (cmd, extra, needle) in [
        ("run", ["--estimator", "nope"], "known: rls"),
        ("run", ["--estimator", "oe,oe"], "named twice"),
        ("montecarlo", ["--runs", "2"], "no [[sensor]] with white noise"),
    ] {
        let mut args = vec![cmd, sc.as_str()];
        args.extend(aircraft);
        args.extend(extra);
        fails(&args, needle);
    }
    fails(&["montecarlo", "--estimator", "rls", "--runs", "2"], "--estimator is for a model-file");
    fails(&["run", "--aircraft", &m, "--map", &c], "give its file");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scenario shorter than a few steps (`dt_s` above `duration_s`) is refused by `sim` and by
/// `run --aircraft` naming both numbers: `sim` wrote a one-row record and `run` a flight on
/// which every estimator failed, both with exit 0.
#[test]
fn a_run_of_fewer_than_ten_steps_is_refused() {
    let dir = std::env::temp_dir().join(format!("aeroident-cli-sim-short-{}", std::process::id()));
    let (model, constants, scenario) = write_inputs(&dir);
    let text = std::fs::read_to_string(&scenario).unwrap();
    std::fs::write(&scenario, text.replacen("duration_s = 16.0", "duration_s = 0.01", 1)).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    for cmd in ["sim", "run"] {
        let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .args([cmd, &s(&scenario), "--aircraft", &s(&model), "--map", &s(&constants)])
            .arg("--out")
            .arg(dir.join(cmd))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{cmd}: {err}");
        assert!(err.contains("duration_s / dt_s = 0.01 / 0.02 gives 1 step(s)"), "{cmd}: {err}");
        assert!(!dir.join(cmd).join("timeseries.csv").exists(), "{cmd}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
