//! Sign tests of surfaces and accelerometers on real and simulated records
//! (../shared/flightdata; skipped with a message when absent, a failure under CI). The
//! reference is physics and the record's documentation, not the code: the ATTAS lateral flight
//! (Jategaonkar 2015 test case) is mapped with aeroident's conventions and the book's output
//! error gives it L_δa, N_δr < 0 there; a channel mapped with the opposite sign must then read
//! reversed, named on that channel, whatever the estimator.

use crate::common;
use common::{shared, workspace};
use std::path::Path;
use std::process::Command;

/// `replay DATA --map MAP ARGS --out DIR` through the binary: asserts success, returns the
/// parsed `summary.json`, stderr and `report.html`.
fn replay(
    data: &Path,
    map: &Path,
    args: &[&str],
    name: &str,
) -> (serde_json::Value, String, String) {
    let out = std::env::temp_dir().join(format!("aeroident-sign-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("replay")
        .arg(data)
        .arg("--map")
        .arg(map)
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{name}: {err}");
    let v = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap());
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    (v.unwrap(), err, html)
}

/// The F-16's six-axis excitation flown by `f16 sim` into its own directory (under `tag`):
/// its `timeseries.csv`.
fn six_axis_sim(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("aeroident-sign-{}-{tag}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["f16", "sim"])
        .arg(workspace().join("scenarios/sim/six_axis_excitation.toml"))
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dir.join("timeseries.csv")
}

/// The simulation's mapping with the three surfaces read from their commands (no actuator).
fn commanded_mapping(tag: &str) -> std::path::PathBuf {
    edited_mapping(
        "aeroident-sim.toml",
        &[
            ("de = ", "de = { column = \"elevator_cmd_rad\", unit = \"rad\" }"),
            ("da = ", "da = { column = \"aileron_cmd_rad\", unit = \"rad\" }"),
            ("dr = ", "dr = { column = \"rudder_cmd_rad\", unit = \"rad\" }"),
        ],
        tag,
    )
}

/// The verdict of `channel` in a summary's `sign_tests`.
fn verdict<'a>(v: &'a serde_json::Value, channel: &str) -> &'a serde_json::Value {
    v["sign_tests"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["channel"] == channel)
        .unwrap_or_else(|| panic!("{channel} not tested: {}", v["sign_tests"]))
}

/// `mappings/NAME` with each `(line start, replacement line)` swapped in, written to a
/// scratch file.
fn edited_mapping(name: &str, edits: &[(&str, &str)], tag: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(workspace().join("mappings").join(name)).unwrap();
    let lines: Vec<String> = text
        .lines()
        .map(|l| match edits.iter().find(|(start, _)| l.starts_with(start)) {
            Some((_, new)) => new.to_string(),
            None => l.to_string(),
        })
        .collect();
    let path =
        std::env::temp_dir().join(format!("aeroident-sign-{}-{tag}.toml", std::process::id()));
    std::fs::write(&path, lines.join("\n")).unwrap();
    path
}

/// As mapped, every surface and accelerometer of the ATTAS aileron–rudder flight is
/// consistent (online RLS: the test reads the replay's fed samples). With the rudder and the
/// lateral accelerometer mapped reversed, an output-error fit names both reversed, flags
/// Cn_dr with the test's evidence, prints the verdicts and puts them in the report; the
/// aileron stays consistent.
#[test]
fn val_attas_reversed_rudder_and_lateral_accelerometer_are_named() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv") else { return };
    let map = workspace().join("mappings/attas_lateral.toml");
    let (v, _, _) = replay(&data, &map, &["--estimator", "rls"], "attas-rls");
    for ch in ["da", "dr", "ay", "az"] {
        assert_eq!(verdict(&v, ch)["verdict"], "consistent", "{ch}: {}", v["sign_tests"]);
    }
    let flipped = edited_mapping(
        "attas_lateral.toml",
        &[
            ("dr = ", "dr = { column = \"rudder_deg\", unit = \"deg\", scale = -1.0 }"),
            ("ay = ", "ay = { column = \"ay_cg_mps2\", unit = \"m/s2\", scale = -1.0 }"),
        ],
        "attas-flipped",
    );
    let (v, err, html) = replay(&data, &flipped, &["--estimator", "oe"], "attas-oe-flipped");
    assert_eq!(verdict(&v, "dr")["verdict"], "reversed", "{}", v["sign_tests"]);
    assert_eq!(verdict(&v, "ay")["verdict"], "reversed", "{}", v["sign_tests"]);
    assert_eq!(verdict(&v, "da")["verdict"], "consistent", "{}", v["sign_tests"]);
    let g = verdict(&v, "dr")["gain"].as_f64().unwrap();
    assert!(g > 4.0 * verdict(&v, "dr")["sigma"].as_f64().unwrap(), "N_δr {g}");
    let cn_dr = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == "Cn_dr").unwrap();
    let flags = cn_dr["flags"].to_string();
    assert!(cn_dr["status"] == "flagged" && flags.contains("sign test: channel `dr`"), "{cn_dr}");
    assert!(err.contains("dr REVERSED") && err.contains("ay REVERSED"), "{err}");
    assert!(html.contains("sign tests") && html.contains("REVERSED"));
    let _ = std::fs::remove_file(flipped);
}

/// A JSBSim F-16 lateral record without its β channel: the lateral accelerometer cannot be
/// decided and says it needs β; the surfaces are still judged (β's place taken by a_y), and
/// the elevator, which does not move, cannot be decided.
#[test]
fn val_without_beta_the_lateral_accelerometer_cannot_be_decided() {
    let Some(data) = shared("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv") else { return };
    let map = edited_mapping("jsbsim.toml", &[("beta = ", "")], "jsbsim-no-beta");
    let (v, err, _) = replay(&data, &map, &["--estimator", "rls"], "f16-no-beta");
    let ay = verdict(&v, "ay");
    assert_eq!(ay["verdict"], "undecided");
    assert!(
        ay["gain"].is_null() && ay["evidence"].as_str().unwrap().contains("`beta` is not mapped")
    );
    assert_eq!(verdict(&v, "da")["verdict"], "consistent", "{}", v["sign_tests"]);
    assert_eq!(verdict(&v, "dr")["verdict"], "consistent", "{}", v["sign_tests"]);
    assert_eq!(verdict(&v, "de")["verdict"], "undecided", "{}", v["sign_tests"]);
    assert!(err.contains("ay cannot be decided from this record"), "{err}");
    let _ = std::fs::remove_file(map);
}

/// The F-16 simulation (Stevens & Lewis airframe with its NASA TP-1538 actuators: first-order
/// lags of 0.0495 s with rate and position limits) writes both the surfaces and the commands.
/// Mapped to the surfaces, no surface leads its response (within 0.005 s) and no timing warning
/// is given; mapped to the commands, each surface leads by the actuator's lag within 0.01 s, a
/// warning names it as commanded on its control derivative, and where the refit with the lead
/// undone moves that derivative beyond ±2σ (at least one of the three), its flag has both
/// values, the refitted one nearer the fit on the true surfaces.
#[test]
fn commanded_surfaces_lead_by_the_actuator_lag() {
    let data = six_axis_sim("sim");
    let map = workspace().join("mappings/aeroident-sim.toml");
    let (truth, err, _) = replay(&data, &map, &["--estimator", "oe"], "sim-surfaces");
    for ch in ["de", "da", "dr"] {
        let lead = verdict(&truth, ch)["lead_s"].as_f64().unwrap();
        assert!(lead.abs() < 0.005, "{ch}: {lead}");
    }
    assert!(!err.contains("input timing"), "{err}");
    let estimate = |v: &serde_json::Value, name: &str| {
        let p = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name);
        p.unwrap()["estimate"].as_f64().unwrap()
    };
    let commanded = commanded_mapping("sim-commanded");
    let (v, err, _) = replay(&data, &commanded, &["--estimator", "oe"], "sim-commands");
    let mut refitted = 0;
    for (ch, derivative) in [("de", "Cm_de"), ("da", "Cl_da"), ("dr", "Cn_dr")] {
        let lead = verdict(&v, ch)["lead_s"].as_f64().unwrap();
        assert!((lead - 0.0495).abs() < 0.01, "{ch}: {lead}");
        let p = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == derivative);
        let flags = p.unwrap()["flags"].to_string();
        assert!(
            flags.contains(&format!("channel `{ch}`")) && flags.contains("commanded"),
            "{flags}"
        );
        // Where the refit moved it beyond ±2σ, towards the fit on the true surfaces.
        if let Some((from, to)) = refit_values(&flags, derivative) {
            assert!(flags.contains(&format!("`{ch}` +0.0")), "{flags}");
            let want = estimate(&truth, derivative);
            assert!((to - want).abs() < (from - want).abs(), "{derivative}: {from} → {to}, {want}");
            refitted += 1;
        }
    }
    assert!(refitted >= 1, "the refit moved no control derivative: {}", v["warnings"]);
    assert!(err.contains("warning: input timing") && err.contains("commanded"), "{err}");
    // The commands through the F-16's actuators declared in the mapping (values of
    // `SurfaceActuators::f16`: τ = 1/20.2 s, 60/80/120 °/s, ±25/21.5/30°): no lead is left, no
    // timing warning, the summary says what was done, and output error's control and damping
    // derivatives equal the fit on the true surfaces within 0.5 %.
    let actuator = |rate_deg_s: f64, limit_deg: f64| {
        format!(
            "actuator = {{ tau_s = {}, rate_limit_rad_s = {}, position_limits_rad = [{}, {}] }}",
            1.0 / 20.2,
            rate_deg_s.to_radians(),
            -limit_deg.to_radians(),
            limit_deg.to_radians()
        )
    };
    let lines = [
        format!(
            "de = {{ column = \"elevator_cmd_rad\", unit = \"rad\", {} }}",
            actuator(60.0, 25.0)
        ),
        format!(
            "da = {{ column = \"aileron_cmd_rad\", unit = \"rad\", {} }}",
            actuator(80.0, 21.5)
        ),
        format!(
            "dr = {{ column = \"rudder_cmd_rad\", unit = \"rad\", {} }}",
            actuator(120.0, 30.0)
        ),
    ];
    let declared = edited_mapping(
        "aeroident-sim.toml",
        &[("de = ", &lines[0]), ("da = ", &lines[1]), ("dr = ", &lines[2])],
        "sim-actuated",
    );
    let (v, err, _) = replay(&data, &declared, &["--estimator", "oe"], "sim-actuated");
    for ch in ["de", "da", "dr"] {
        let lead = verdict(&v, ch)["lead_s"].as_f64().unwrap();
        assert!(lead.abs() < 0.005, "{ch}: {lead}");
        assert!(err.contains(&format!("`{ch}` is mapped as a command")), "{err}");
    }
    assert!(!err.contains("input timing"), "{err}");
    for name in ["Cm_de", "Cm_q", "Cl_da", "Cl_p", "Cn_dr", "Cn_r"] {
        let (want, got) = (estimate(&truth, name), estimate(&v, name));
        assert!(((got - want) / want).abs() < 0.005, "{name}: {got} vs {want}");
    }
    let _ = std::fs::remove_dir_all(data.parent().unwrap());
    let _ = std::fs::remove_file(commanded);
    let _ = std::fs::remove_file(declared);
}

/// The two values of the timing refit's flag on `name` in `flags` (`… {name} moves from A to
/// B (…`), if it has one.
fn refit_values(flags: &str, name: &str) -> Option<(f64, f64)> {
    let key = format!("{name} moves from ");
    let rest = &flags[flags.find(&key)? + key.len()..];
    let mut words = rest.split_whitespace();
    let from = words.next()?.parse().ok()?;
    assert_eq!(words.next(), Some("to"), "{rest}");
    Some((from, words.next()?.parse().ok()?))
}

/// `--compat auto` on the F-16 simulation mapped to its surface commands (no actuator
/// declared): the check measures each surface's lead on the record as logged and delays the
/// surface by it, says so, and leaves a lead under 0.02 s for the fit's own sign tests; output
/// error's control derivatives move towards the fit on the true surfaces.
#[test]
fn compat_auto_delays_a_commanded_surface_by_its_measured_lead() {
    let data = six_axis_sim("auto");
    let truth_map = workspace().join("mappings/aeroident-sim.toml");
    let (truth, _, _) = replay(&data, &truth_map, &["--estimator", "oe"], "auto-surfaces");
    let commanded = commanded_mapping("auto-commanded");
    let (plain, _, _) = replay(&data, &commanded, &["--estimator", "oe"], "auto-plain");
    let args = ["--estimator", "oe", "--compat", "auto"];
    let (auto, err, _) = replay(&data, &commanded, &args, "auto-compat");
    let estimate = |v: &serde_json::Value, name: &str| {
        let p = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name);
        p.unwrap()["estimate"].as_f64().unwrap()
    };
    for (ch, derivative) in [("de", "Cm_de"), ("da", "Cl_da"), ("dr", "Cn_dr")] {
        assert!(
            err.contains(&format!("`{ch}` leads its response by +0.0"))
                && err.contains("delayed by it (--compat)"),
            "{ch}: {err}"
        );
        let lead = verdict(&auto, ch)["lead_s"].as_f64().unwrap();
        assert!(lead.abs() < 0.02, "{ch}: {lead}");
        let want = estimate(&truth, derivative);
        let (from, to) = (estimate(&plain, derivative), estimate(&auto, derivative));
        assert!((to - want).abs() < (from - want).abs(), "{derivative}: {from} → {to}, {want}");
    }
    // The same leads from the check's compat.json: the same estimates.
    let checked = data.parent().unwrap().join("compat");
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("compat")
        .arg(&data)
        .arg("--map")
        .arg(&commanded)
        .arg("--out")
        .arg(&checked)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = checked.join("compat.json").display().to_string();
    let args = ["--estimator", "oe", "--compat", file.as_str()];
    let (from_file, err, _) = replay(&data, &commanded, &args, "auto-file");
    assert!(err.contains("delayed by it (--compat)"), "{err}");
    for derivative in ["Cm_de", "Cl_da", "Cn_dr", "Cm_q", "Cl_p", "Cn_r"] {
        assert_eq!(estimate(&from_file, derivative), estimate(&auto, derivative), "{derivative}");
    }
    let _ = std::fs::remove_dir_all(data.parent().unwrap());
    let _ = std::fs::remove_file(commanded);
}
