//! `aeroident linearize --json` is the state-space export: A, B, C, D with the state and input
//! names. For the F-16 it goes through the aircraft interface (SI arguments, the trait's trim)
//! and must give the A and B of `aeroident f16 linearize`, which calls the F-16's own trim and
//! linearization with the textbook's units directly.

use serde_json::Value;
use std::process::Command;

fn json(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident")).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect())
        .collect()
}

/// 20 000 ft = 6096 m, 675 ft/s = 205.74 m/s, xcg 0.35: A and B agree element by element to
/// 1e-6 of each matrix's largest entry; C is the identity over the 13 named states, D is 0.
#[test]
fn analytic_the_state_space_export_equals_the_f16s_own_linearization() {
    let ss = json(&[
        "linearize",
        "--aircraft",
        "f16",
        "--vt-mps",
        "205.74",
        "--alt-m",
        "6096",
        "--json",
    ]);
    let f16 = json(&[
        "f16",
        "linearize",
        "--alt-ft",
        "20000",
        "--vt-fps",
        "675",
        "--xcg",
        "0.35",
        "--json",
    ]);
    for key in ["a", "b"] {
        let (x, y) = (matrix(&ss[key]), matrix(&f16[key]));
        assert_eq!((x.len(), x[0].len()), (y.len(), y[0].len()), "{key}");
        let scale = y.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (rx, ry)) in x.iter().zip(&y).enumerate() {
            for (j, (a, b)) in rx.iter().zip(ry).enumerate() {
                assert!((a - b).abs() <= 1e-6 * scale, "{key}[{i}][{j}]: {a} against {b}");
            }
        }
    }
    let states = ss["states"].as_array().unwrap();
    assert_eq!(states.len(), 13);
    assert_eq!(states[0], "vt_fps");
    assert_eq!(ss["inputs"].as_array().unwrap().len(), 4);
    let (c, d) = (matrix(&ss["c"]), matrix(&ss["d"]));
    for (i, row) in c.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert_eq!(*v, if i == j { 1.0 } else { 0.0 });
        }
    }
    assert!(d.len() == 13 && d.iter().flatten().all(|v| *v == 0.0));
}

/// A partial test card (elevator and aileron, no rudder derivative): `linearize` trims with
/// the rudder held (said on stderr), its JSON carries a zero rudder column and the flag of a
/// roll mode faster than any conventional roll damping gives (Cl_p −3.3 on a 0.17 kg·m² UAV:
/// the bound is q̄ S b² · 1.5 / (2 V Jx) ≈ 47 1/s at 18 m/s); `design` refuses an input on
/// the rudder it does not have.
#[test]
fn a_partial_test_card_linearizes_with_its_rudder_held_and_an_absurd_roll_mode_flagged() {
    let d = std::env::temp_dir().join(format!("aeroident-partial-card-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let mut model = String::from(
        "description = \"uav\"\n[coefficients]\nCL = [\"0\", \"alpha\", \"de\"]\nCD = [\"0\"]\nCY = [\"beta\"]\nCl = [\"beta\", \"p\", \"da\"]\nCm = [\"0\", \"alpha\", \"q\", \"de\"]\nCn = [\"beta\", \"r\"]\n",
    );
    for (n, v) in [
        ("CL_0", 0.3),
        ("CL_alpha", 4.8),
        ("CL_de", 0.3),
        ("CD_0", 0.03),
        ("CY_beta", -0.3),
        ("Cl_beta", -0.08),
        ("Cl_p", -3.3),
        ("Cl_da", -0.25),
        ("Cm_0", 0.02),
        ("Cm_alpha", -0.6),
        ("Cm_q", -9.0),
        ("Cm_de", -1.0),
        ("Cn_beta", 0.06),
        ("Cn_r", -0.08),
    ] {
        model.push_str(&format!("[reference.{n}]\nvalue = {v}\nsource = \"t\"\n"));
    }
    let map = "description = \"c\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nqbar = { column = \"q\", unit = \"Pa\" }\nmass = { value = 3.3, unit = \"kg\" }\nIxx = { value = 0.17, unit = \"kg*m2\" }\nIyy = { value = 0.289, unit = \"kg*m2\" }\nIzz = { value = 0.443, unit = \"kg*m2\" }\nS = { value = 0.384, unit = \"m2\" }\nb = { value = 1.6, unit = \"m\" }\ncbar = { value = 0.24, unit = \"m\" }\n";
    let (m, c) = (d.join("uav.toml"), d.join("c.toml"));
    std::fs::write(&m, model).unwrap();
    std::fs::write(&c, map).unwrap();
    let (m, c) = (m.to_str().unwrap(), c.to_str().unwrap());
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args([
            "linearize",
            "--aircraft",
            m,
            "--map",
            c,
            "--vt-mps",
            "18",
            "--alt-m",
            "0",
            "--json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && err.contains("no `dr` derivative"), "{err}");
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(matrix(&v["b"]).iter().all(|row| row[3] == 0.0), "rudder column not zero");
    let flags = v["mode_flags"].as_array().unwrap();
    assert!(flags.len() == 1 && flags[0].as_str().unwrap().contains("Cl_p = -3.3"), "{flags:?}");
    let design = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["design", "--aircraft", m, "--map", c, "--vt-mps", "18", "--alt-m", "0"])
        .args([
            "--surfaces",
            "de,da,dr",
            "--rate-hz",
            "25",
            "--out",
            d.join("des").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&design.stderr);
    assert!(!design.status.success() && err.contains("--surfaces dr"), "{err}");
    // At 25 Hz the −105 1/s roll mode is beyond what the design's RK4 resolves (|λ| dt 4.2):
    // refused, naming the mode, the least rate and the derivative behind it.
    let design = |rate: &str| {
        Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .args(["design", "--aircraft", m, "--map", c, "--vt-mps", "18", "--alt-m", "0"])
            .args([
                "--surfaces",
                "de,da",
                "--rate-hz",
                rate,
                "--out",
                d.join("des").to_str().unwrap(),
            ])
            .output()
            .unwrap()
    };
    let out = design("25");
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in ["--rate-hz 25", "roll mode", "Hz or more", "Cl_p = -3.3"] {
        assert!(!out.status.success() && err.contains(needle), "{needle}: {err}");
    }
    // With a conventional roll damping the card designs at ArduPilot's Lua rates.
    let text = std::fs::read_to_string(m).unwrap().replace("value = -3.3", "value = -0.45");
    std::fs::write(m, text).unwrap();
    let out = design("20");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // An elevator and an aileron excite both axes: the design's model is named for both.
    let json = std::fs::read_to_string(d.join("des/design.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(json["model"], "six-axis", "{json}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `--aircraft six-axis` (the preset `replay --model six-axis` fits) with a replay's summary:
/// the aircraft flies the summary's values in the preset's structure, no model file needed.
/// Its linear model equals that of the same values in a model file of the same terms
/// (element by element); a partial card's missing values fly at the priors, said by name;
/// a summary of another model is refused by name.
#[test]
fn the_six_axis_preset_flies_a_summary_without_a_model_file() {
    let d = std::env::temp_dir().join(format!("aeroident-six-axis-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let values = [
        ("CY_beta", -0.3),
        ("CY_p", -0.05),
        ("CY_r", 0.2),
        ("CY_dr", 0.15),
        ("CL_0", 0.3),
        ("CL_alpha", 4.8),
        ("CL_q", 6.0),
        ("CL_de", 0.35),
        ("CD_0", 0.03),
        ("CD_alpha", 0.1),
        ("Cl_beta", -0.08),
        ("Cl_p", -0.45),
        ("Cl_r", 0.1),
        ("Cl_da", -0.25),
        ("Cm_0", 0.02),
        ("Cm_alpha", -0.6),
        ("Cm_q", -9.0),
        ("Cm_de", -1.0),
        ("Cn_beta", 0.06),
        ("Cn_p", -0.03),
        ("Cn_r", -0.08),
        ("Cn_dr", -0.05),
    ];
    let preset = aeroident_io::ModelSpec::preset("six-axis").unwrap();
    let names: Vec<&str> = preset.structure.names().collect();
    let value = |n: &str| values.iter().find(|(m, _)| *m == n).map_or(0.0, |(_, v)| *v);
    let params: Vec<_> = names
        .iter()
        .map(|n| serde_json::json!({"name": n, "estimate": value(n), "std_error": 0.01}))
        .collect();
    let summary = serde_json::json!({"estimator": "oe", "model": "six-axis", "status": "converged", "parameters": params});
    std::fs::write(d.join("summary.json"), summary.to_string()).unwrap();
    let mut model = String::from("description = \"same terms\"\n[coefficients]\n");
    for c in ["CL", "CD", "CY", "Cl", "Cm", "Cn"] {
        let terms: Vec<String> = names
            .iter()
            .filter_map(|n| n.strip_prefix(&format!("{c}_")).map(|t| format!("\"{t}\"")))
            .collect();
        model.push_str(&format!("{c} = [{}]\n", terms.join(", ")));
    }
    std::fs::write(d.join("same.toml"), model).unwrap();
    std::fs::write(d.join("c.toml"), "description = \"c\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nqbar = { column = \"q\", unit = \"Pa\" }\nmass = { value = 3.3, unit = \"kg\" }\nIxx = { value = 0.17, unit = \"kg*m2\" }\nIyy = { value = 0.289, unit = \"kg*m2\" }\nIzz = { value = 0.443, unit = \"kg*m2\" }\nS = { value = 0.384, unit = \"m2\" }\nb = { value = 1.6, unit = \"m\" }\ncbar = { value = 0.24, unit = \"m\" }\n").unwrap();
    let s = |p: &str| d.join(p).to_str().unwrap().to_string();
    let lin = |aircraft: &str| {
        json(&[
            "linearize",
            "--aircraft",
            aircraft,
            "--summary",
            &s("summary.json"),
            "--map",
            &s("c.toml"),
            "--vt-mps",
            "18",
            "--alt-m",
            "100",
            "--json",
        ])
    };
    let (preset_a, file_a) = (matrix(&lin("six-axis")["a"]), matrix(&lin(&s("same.toml"))["a"]));
    assert_eq!(preset_a, file_a);
    // A partial card: the drag not identified (no thrust), the roll axis not flown. Those fly
    // at the model's prior, said per parameter, and the aircraft is the one whose summary
    // holds the priors' values.
    let prior = |n: &str| {
        let p = aeroident_estimators::vocabulary::Param::from_name(n).unwrap();
        aeroident_estimators::prior::generic_prior(p).value
    };
    let partial: Vec<_> = names
        .iter()
        .filter(|n| !n.starts_with("Cl_"))
        .map(|n| {
            let v = if n.starts_with("CD_") { None } else { Some(value(n)) };
            serde_json::json!({"name": n, "estimate": v, "std_error": 0.01})
        })
        .collect();
    let filled: Vec<_> = names
        .iter()
        .map(|n| {
            let v = if n.starts_with("CD_") || n.starts_with("Cl_") { prior(n) } else { value(n) };
            serde_json::json!({"name": n, "estimate": v, "std_error": 0.01})
        })
        .collect();
    for (file, params) in [("partial.json", partial), ("filled.json", filled)] {
        let j = serde_json::json!({"estimator": "oe", "model": "six-axis", "parameters": params});
        std::fs::write(d.join(file), j.to_string()).unwrap();
    }
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args([
            "linearize",
            "--aircraft",
            "six-axis",
            "--summary",
            &s("partial.json"),
            "--map",
            &s("c.toml"),
            "--vt-mps",
            "18",
            "--alt-m",
            "100",
            "--json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in ["`CD_0` is not identified (null)", "`Cl_p` is absent", "model's prior"] {
        assert!(out.status.success() && err.contains(needle), "{needle}: {err}");
    }
    let partial_a = matrix(&serde_json::from_slice::<Value>(&out.stdout).unwrap()["a"]);
    let filled_a = matrix(
        &json(&[
            "linearize",
            "--aircraft",
            "six-axis",
            "--summary",
            &s("filled.json"),
            "--map",
            &s("c.toml"),
            "--vt-mps",
            "18",
            "--alt-m",
            "100",
            "--json",
        ])["a"],
    );
    assert_eq!(partial_a, filled_a);
    let other = serde_json::json!({"estimator": "oe", "model": "x", "parameters": [{"name": "Cm_alpha2", "estimate": -1.0, "std_error": 0.1}]});
    std::fs::write(d.join("other.json"), other.to_string()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args([
            "linearize",
            "--aircraft",
            "six-axis",
            "--summary",
            &s("other.json"),
            "--map",
            &s("c.toml"),
            "--vt-mps",
            "18",
            "--alt-m",
            "100",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("Cm_alpha2") && err.contains("six-axis"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
