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
        .arg(workspace().join("crates/aeroident/tests/jsbsim_load.py"))
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
