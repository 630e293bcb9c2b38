//! `aeroident export jsbsim` output loaded into JSBSim (the Python wheel) on a copy of its
//! c172x: every exported function evaluates to value × regressor × scaling at a state with
//! non-zero α, β, rates and surfaces, with the regressors computed by the script from JSBSim's
//! state; an unidentified parameter is absent. Skipped without python/jsbsim, failed under
//! `CI=true` (`.ci/run` installs the wheel and sets `AEROIDENT_PYTHON`).

use std::path::PathBuf;
use std::process::Command;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The Python with `jsbsim`: `$AEROIDENT_PYTHON`, else `python3`; `None` (SKIPPED) without it.
fn python_with_jsbsim() -> Option<String> {
    let py = std::env::var("AEROIDENT_PYTHON").unwrap_or_else(|_| "python3".into());
    let ok =
        Command::new(&py).args(["-c", "import jsbsim"]).output().is_ok_and(|o| o.status.success());
    if ok {
        return Some(py);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "`{py}` cannot import jsbsim under CI (.ci/run installs it and sets AEROIDENT_PYTHON)"
    );
    eprintln!(
        "SKIPPED: `{py}` cannot import jsbsim (set AEROIDENT_PYTHON to a Python with the jsbsim wheel)"
    );
    None
}

#[test]
fn exported_fragment_loads_into_jsbsim_and_evaluates_our_derivatives() {
    let Some(py) = python_with_jsbsim() else { return };
    let dir = std::env::temp_dir().join(format!("aeroident-export-jsbsim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A six-axis summary (C172-like magnitudes); Cm_alphadot not identified.
    let params: Vec<(&str, Option<f64>)> = vec![
        ("CL_0", Some(0.31)),
        ("CL_alpha", Some(5.143)),
        ("CL_q", Some(3.9)),
        ("CL_de", Some(0.43)),
        ("CD_0", Some(0.031)),
        ("CD_alpha2", Some(0.8)),
        ("CY_beta", Some(-0.31)),
        ("CY_dr", Some(0.187)),
        ("Cl_beta", Some(-0.089)),
        ("Cl_p", Some(-0.47)),
        ("Cl_r", Some(0.096)),
        ("Cl_da", Some(0.178)),
        ("Cl_dr", Some(0.0147)),
        ("Cm_0", Some(-0.015)),
        ("Cm_alpha", Some(-0.89)),
        ("Cm_q", Some(-12.4)),
        ("Cm_alphadot", None),
        ("Cm_de", Some(-1.28)),
        ("Cn_beta", Some(0.065)),
        ("Cn_p", Some(-0.03)),
        ("Cn_r", Some(-0.099)),
        ("Cn_da", Some(-0.053)),
        ("Cn_dr", Some(-0.0657)),
    ];
    let summary = serde_json::json!({
        "estimator": "rls",
        "model": "test six-axis",
        "parameters": params.iter().map(|(n, v)| serde_json::json!({
            "name": n, "estimate": v, "std_error": v.map(|x: f64| 0.01 * x.abs()),
        })).collect::<Vec<_>>(),
    });
    let summary_path = dir.join("summary.json");
    std::fs::write(&summary_path, serde_json::to_string_pretty(&summary).unwrap()).unwrap();
    let values: serde_json::Map<String, serde_json::Value> =
        params.iter().map(|(n, v)| ((*n).to_string(), serde_json::json!(v))).collect();
    let values_path = dir.join("values.json");
    std::fs::write(&values_path, serde_json::Value::Object(values).to_string()).unwrap();
    let frag = dir.join("aero.xml");
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["export", "jsbsim", "--summary"])
        .arg(&summary_path)
        .arg("--out")
        .arg(&frag)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let xml = std::fs::read_to_string(&frag).unwrap();
    assert!(xml.contains("Cm_alphadot: not identified"), "{xml}");
    let check = Command::new(&py)
        .arg(workspace().join("crates/aeroident/tests/all/jsbsim_load.py"))
        .arg(&frag)
        .arg(&values_path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&check.stdout);
    eprintln!("{stdout}");
    assert!(check.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&check.stderr));
    let report: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    assert_eq!(report["checked"], 22);
    assert!(report["max_rel_error"].as_f64().unwrap() <= 1e-9);
    let _ = std::fs::remove_dir_all(&dir);
}

#[path = "../../../pipelines/tests/all/export_uav/planes.rs"]
mod planes;
use planes::{
    C172X, Plane, UAV, UAV_OAT_RECORDS, completed, mapping_toml, model_toml, scenario_toml,
    uav_oat_dir,
};

/// `values`' model file, `plane`'s mapping (its constants, and an elevator actuator line
/// `de_line`), doublet scenario and a summary of `values`, in `d`.
fn write_plane(d: &std::path::Path, plane: &Plane, values: &[(&str, f64)], de_line: &str) {
    std::fs::create_dir_all(d).unwrap();
    let params: Vec<_> = values
        .iter()
        .map(|(n, v)| serde_json::json!({"name": n, "estimate": v, "std_error": 0.01}))
        .collect();
    let summary = serde_json::json!({"estimator": "oe", "model": "test", "status": "converged", "parameters": params});
    std::fs::write(d.join("model.toml"), model_toml(values)).unwrap();
    std::fs::write(d.join("map.toml"), mapping_toml(plane, de_line)).unwrap();
    std::fs::write(d.join("scenario.toml"), scenario_toml(plane)).unwrap();
    std::fs::write(d.join("summary.json"), summary.to_string()).unwrap();
}

fn cli(d: &std::path::Path, args: &[&str]) -> String {
    let out =
        Command::new(env!("CARGO_BIN_EXE_aeroident")).current_dir(d).args(args).output().unwrap();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A CSV's columns by name.
fn columns(path: &std::path::Path) -> std::collections::BTreeMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let names: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut cols: std::collections::BTreeMap<String, Vec<f64>> =
        names.iter().map(|n| (n.to_string(), Vec::new())).collect();
    for line in lines {
        for (n, v) in names.iter().zip(line.split(',')) {
            cols.get_mut(*n).unwrap().push(v.parse().unwrap());
        }
    }
    cols
}

/// Per channel, JSBSim's largest difference from `sim` relative to `sim`'s largest excursion
/// from its first value.
fn misses(sim: &std::path::Path, jsb: &std::path::Path) -> Vec<(String, f64)> {
    let (s, j) = (columns(sim), columns(jsb));
    let names = ["p_rad_s", "q_rad_s", "r_rad_s", "pdot_rad_s2", "qdot_rad_s2", "rdot_rad_s2"];
    let forces = ["ax_mps2", "ay_mps2", "az_mps2"];
    names
        .iter()
        .chain(&forces)
        .map(|n| {
            let (a, b) = (&s[*n], &j[*n]);
            let excursion = a.iter().map(|x| (x - a[0]).abs()).fold(0.0, f64::max);
            let miss = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            (n.to_string(), miss / excursion)
        })
        .collect()
}

/// `values` on `plane` (with the elevator line `de_line`) flown by `sim` in `d`, exported as
/// the complete aircraft `name` under `d/root`; returns the exported file.
fn sim_and_export(
    d: &std::path::Path,
    (plane, values): (&Plane, &[(&str, f64)]),
    de_line: &str,
    name: &str,
) -> PathBuf {
    write_plane(d, plane, values, de_line);
    let sim = ["sim", "scenario.toml", "--aircraft", "model.toml", "--map", "map.toml"];
    cli(d, &[&sim[..], &["--out", "sim"]].concat());
    std::fs::create_dir_all(d.join(format!("root/aircraft/{name}"))).unwrap();
    let xml = d.join(format!("root/aircraft/{name}/{name}.xml"));
    let export = ["export", "jsbsim", "--summary", "summary.json", "--mapping", "map.toml"];
    cli(d, &[&export[..], &["--out", xml.to_str().unwrap()]].concat());
    xml
}

/// JSBSim (`py`) flying aircraft `name` of `d/root` through `d/sim`'s record: the misses of
/// [`misses`].
fn fly_in_jsbsim(py: &str, d: &std::path::Path, name: &str) -> Vec<(String, f64)> {
    let script = workspace().join("crates/aeroident/tests/all/jsbsim_fly.py");
    let out = Command::new(py)
        .current_dir(d)
        .args([script.to_str().unwrap(), "root", name, "sim/timeseries.csv", "jsbsim.csv"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stdout));
    misses(&d.join("sim/timeseries.csv"), &d.join("jsbsim.csv"))
}

/// `export jsbsim --mapping` writes a complete aircraft (metrics, mass and inertia, thrust,
/// flight control, aerodynamics in JSBSim's stability axes) that the real JSBSim loads and
/// flies through the doublets `sim` flew with the identified UAV: every rate, angular
/// acceleration and specific force within 5 % of its excursion (measured ≤ 0.8 %). The same
/// file with the roll inertia doubled misses p by more; a declared actuator becomes JSBSim's
/// `<actuator>` with lag 1/τ and the rate and position limits.
#[test]
fn a_complete_aircraft_flies_the_identified_doublets_in_jsbsim() {
    let Some(py) = python_with_jsbsim() else { return };
    let d = std::env::temp_dir().join(format!("aeroident-jsbsim-aircraft-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let xml = sim_and_export(&d, (&UAV, UAV.values), "", "uav");
    let fly = |name: &str| fly_in_jsbsim(&py, &d, name);
    let m = fly("uav");
    assert!(m.iter().all(|(_, e)| *e < 0.05), "JSBSim misses {m:?}");
    let text = std::fs::read_to_string(&xml).unwrap();
    std::fs::create_dir_all(d.join("root/aircraft/heavy")).unwrap();
    let heavy = text.replace("<ixx unit=\"KG*M2\">0.17</ixx>", "<ixx unit=\"KG*M2\">0.34</ixx>");
    std::fs::write(
        d.join("root/aircraft/heavy/heavy.xml"),
        heavy.replace("name=\"uav\"", "name=\"heavy\""),
    )
    .unwrap();
    let m = fly("heavy");
    assert!(m[0].1 > 0.05, "a doubled roll inertia went unseen: {m:?}");
    let servo = "de = { column = \"de\", unit = \"rad\", actuator = { tau_s = 0.05, rate_limit_rad_s = 3.5, position_limits_rad = [-0.4, 0.3] } }\n";
    sim_and_export(&d, (&UAV, UAV.values), servo, "uav");
    let text = std::fs::read_to_string(&xml).unwrap();
    for needle in ["<lag>20</lag>", "<rate_limit>3.5</rate_limit>", "<min>-0.4</min><max>0.3</max>"]
    {
        assert!(text.contains(needle), "{needle} not in the actuator: {text}");
    }
    // In JSBSim the surface follows a 0.05-rad step as 0.05 (1 − e^(−t/τ)), τ 0.05 s (the
    // rate limit 3.5 rad/s is not reached), to a 0.2-ms frame.
    let script = workspace().join("crates/aeroident/tests/all/jsbsim_fly.py");
    let out = Command::new(&py)
        .current_dir(&d)
        .args([script.to_str().unwrap(), "--step", "root", "uav"])
        .output()
        .unwrap();
    let got: Vec<f64> =
        String::from_utf8_lossy(&out.stdout).lines().filter_map(|l| l.parse().ok()).collect();
    assert_eq!(got.len(), 3, "{}", String::from_utf8_lossy(&out.stderr));
    for (t, g) in [0.05f64, 0.1, 0.2].iter().zip(&got) {
        let want = 0.05 * (1.0 - (-t / 0.05).exp());
        assert!((g - want).abs() < 0.01 * 0.05, "at {t} s the elevator is {g}, not {want}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The JSBSim c172x's own coefficients, mass and inertia, exported as a complete aircraft and
/// flown in the real JSBSim through `sim`'s doublets at 55 m/s: every channel within 5 % of
/// its excursion.
#[test]
fn a_complete_c172x_flies_the_identified_doublets_in_jsbsim() {
    let Some(py) = python_with_jsbsim() else { return };
    let d = std::env::temp_dir().join(format!("aeroident-jsbsim-c172x-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    sim_and_export(&d, (&C172X, C172X.values), "", "c172");
    let m = fly_in_jsbsim(&py, &d, "c172");
    assert!(m.iter().all(|(_, e)| *e < 0.05), "JSBSim misses {m:?}");
    let _ = std::fs::remove_dir_all(&d);
}

/// uav_oat's identified model, as a user gets it: `replay --estimator oe --model six-axis` of
/// [`UAV_OAT_RECORDS`] through `mappings/uav_oat.toml`, completed for flight ([`completed`]),
/// exported as a complete aircraft and flown in the real JSBSim through `sim`'s doublets:
/// every channel within 5 % of its excursion but a_x, within 10 % (8 % measured: 0.006 m/s²
/// of a 0.07 m/s² excursion). JSBSim flies on a rotating round earth and `sim` on a flat one
/// at rest; started at 0° or 89.9° latitude instead of 45° the same file misses a_x by 13 % and
/// 17 %, so the remainder is the earth model, not the file.
#[test]
fn uav_oats_identified_model_flies_the_same_in_jsbsim() {
    let Some(py) = python_with_jsbsim() else { return };
    let Some(dir) = uav_oat_dir() else { return };
    let d = std::env::temp_dir().join(format!("aeroident-jsbsim-uavoat-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let [el, ail] = UAV_OAT_RECORDS.map(|f| dir.join(f).display().to_string());
    let map = workspace().join("mappings/uav_oat.toml").display().to_string();
    let fit = ["replay", &el, "--and", &ail, "--map", &map, "--model", "six-axis"];
    cli(&d, &[&fit[..], &["--estimator", "oe", "--out", "fit"]].concat());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("fit/summary.json")).unwrap())
            .unwrap();
    let identified: Vec<(String, Option<f64>)> = summary["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["name"].as_str().unwrap().to_string(), p["estimate"].as_f64()))
        .collect();
    let (values, _) = completed(&identified);
    let values: Vec<(&str, f64)> = values.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    sim_and_export(&d, (&UAV, &values), "", "uavoat");
    let m = fly_in_jsbsim(&py, &d, "uavoat");
    eprintln!("uav_oat's identified model in JSBSim, misses / excursion: {m:.4?}");
    let bound = |n: &str| if n == "ax_mps2" { 0.10 } else { 0.05 };
    assert!(m.iter().all(|(n, e)| *e < bound(n)), "JSBSim misses {m:?}");
    let _ = std::fs::remove_dir_all(&d);
}
