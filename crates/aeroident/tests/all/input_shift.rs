//! A surface's time shift declared in the mapping (`shift_s`, docs/mapping.md): the record's
//! surfaces are made to lead the response by a known time, and the shift that undoes it must
//! give back the fit of the record as simulated. The truth is the simulator's own record
//! (`aeroident f16 sim`, six-axis excitation, true surfaces, no noise): its surface columns
//! are moved 4 samples (0.04 s at 100 Hz) earlier in the CSV, as a log whose surfaces are
//! stamped late against the response would read.

use crate::common;
use common::workspace;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Samples the surfaces are moved: a lead of 0.04 s at the record's 100 Hz.
const LEAD_SAMPLES: usize = 4;

/// A scratch path unique to this test process.
fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("aeroident-shift-{}-{name}", std::process::id()))
}

/// `aeroident ARGS`: its success, stdout and stderr.
fn run(args: &[&std::ffi::OsStr]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident")).args(args).output().unwrap();
    (o.status.success(), String::from_utf8_lossy(&o.stderr).to_string())
}

/// `replay DATA --map MAP --estimator EST --out DIR`: asserts success, returns the parsed
/// `summary.json` and stderr.
fn replay(data: &Path, map: &Path, estimator: &str, name: &str) -> (serde_json::Value, String) {
    let out = scratch(name);
    let _ = std::fs::remove_dir_all(&out);
    let args = [
        "replay".as_ref(),
        data.as_os_str(),
        "--map".as_ref(),
        map.as_os_str(),
        "--estimator".as_ref(),
        estimator.as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    let (ok, err) = run(&args);
    assert!(ok, "{name}: {err}");
    let v = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap());
    let _ = std::fs::remove_dir_all(&out);
    (v.unwrap(), err)
}

/// The simulator's six-axis record, and a copy whose surface columns lead it by
/// [`LEAD_SAMPLES`] (row i holds the surfaces of row i + k; the last k rows hold the last).
fn records() -> (PathBuf, PathBuf) {
    let dir = scratch("sim");
    let scenario = workspace().join("scenarios/sim/six_axis_excitation.toml");
    let args =
        ["f16".as_ref(), "sim".as_ref(), scenario.as_os_str(), "--out".as_ref(), dir.as_os_str()];
    let (ok, err) = run(&args);
    assert!(ok, "{err}");
    let data = dir.join("timeseries.csv");
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let names: Vec<&str> = header.split(',').collect();
    let surfaces: Vec<usize> = ["elevator_rad", "aileron_rad", "rudder_rad"]
        .iter()
        .map(|c| names.iter().position(|n| n == c).unwrap())
        .collect();
    let mut out = vec![header.to_string()];
    for i in 0..rows.len() {
        let later = &rows[(i + LEAD_SAMPLES).min(rows.len() - 1)];
        let mut row = rows[i].clone();
        surfaces.iter().for_each(|&j| row[j] = later[j]);
        out.push(row.join(","));
    }
    let lead = dir.join("lead.csv");
    std::fs::write(&lead, out.join("\n") + "\n").unwrap();
    (data, lead)
}

/// The shipped simulator mapping with `insert` (`shift_s = …`) put first in the table of each
/// channel whose line starts with one of `keys`, written to a scratch file.
fn mapping_with(keys: &[&str], insert: &str, tag: &str) -> PathBuf {
    let text = std::fs::read_to_string(workspace().join("mappings/aeroident-sim.toml")).unwrap();
    let lines: Vec<String> = text
        .lines()
        .map(|l| match keys.iter().any(|k| l.starts_with(&format!("{k} = {{"))) {
            true => l.replacen("{ ", &format!("{{ {insert}, "), 1),
            false => l.to_string(),
        })
        .collect();
    let path = scratch(&format!("{tag}.toml"));
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    path
}

/// The estimate of `name` in a summary.
fn estimate(v: &serde_json::Value, name: &str) -> f64 {
    let p = v["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name);
    p.unwrap_or_else(|| panic!("{name} not fitted"))["estimate"].as_f64().unwrap()
}

/// The lead of surface `channel` over its response, s, its sign test measured.
fn lead_s(v: &serde_json::Value, channel: &str) -> f64 {
    let tests = v["sign_tests"].as_array().unwrap();
    let t = tests.iter().find(|t| t["channel"] == channel).unwrap();
    t["lead_s"].as_f64().unwrap_or_else(|| panic!("{channel}: no lead in {t}"))
}

/// Output error on the record whose surfaces lead by 0.04 s: without a shift the control and
/// damping derivatives are low (measured: Cm_q −11.9 %, Cl_p −14.1 %, Cl_da −9.4 %, Cm_de
/// −6.9 %) and each surface's sign test finds the 0.04-s lead; with `shift_s = 0.04` on the
/// three surfaces they equal the fit of the record as simulated (measured 0.0 %), no lead is
/// left, and summary.json and the console say what was applied. A shift ignored, or applied
/// with the wrong sign (a 0.08-s lead: −13 % … −25 %), fails the test. The online replay
/// (RLS) applies it too.
#[test]
fn a_declared_shift_undoes_a_known_surface_lead() {
    let (data, lead) = records();
    let plain = workspace().join("mappings/aeroident-sim.toml");
    let (truth, _) = replay(&data, &plain, "oe", "truth");
    let (off, _) = replay(&lead, &plain, "oe", "lead");
    let shift = LEAD_SAMPLES as f64 * 0.01;
    let shifted = mapping_with(&["de", "da", "dr"], &format!("shift_s = {shift}"), "shifted");
    let (fixed, err) = replay(&lead, &shifted, "oe", "fixed");
    for name in ["Cm_de", "Cm_q", "Cl_da", "Cl_p", "Cn_r"] {
        let want = estimate(&truth, name);
        let (bad, good) = (estimate(&off, name), estimate(&fixed, name));
        assert!(((good - want) / want).abs() < 0.01, "{name}: {good} with the shift, {want} true");
        if name != "Cm_de" && name != "Cn_r" {
            assert!(((bad - want) / want).abs() > 0.05, "{name}: {bad} unshifted, {want} true");
        }
    }
    for ch in ["de", "da", "dr"] {
        assert!((lead_s(&off, ch) - shift).abs() < 0.006, "{ch}: {}", lead_s(&off, ch));
        assert!(lead_s(&fixed, ch).abs() < 0.005, "{ch}: {}", lead_s(&fixed, ch));
        let said = format!(
            "mapping applied: {ch}: shift_s = +0.0400 s, the surface delayed by 0.0400 s (the value used at t is the logged one at t − 0.0400 s)"
        );
        let warnings = fixed["warnings"].to_string();
        assert!(warnings.contains(&said), "{warnings}");
        assert!(err.contains(&format!("warning: {said}")), "{err}");
    }
    let (online, _) = replay(&lead, &shifted, "rls", "online");
    assert!(online["warnings"].to_string().contains("mapping applied: de: shift_s = +0.0400 s"));
    assert!(lead_s(&online, "de").abs() < 0.005, "{}", lead_s(&online, "de"));
    let _ = std::fs::remove_dir_all(data.parent().unwrap());
    let _ = std::fs::remove_file(shifted);
}

/// `shift_s` on a channel that is not a surface (`q`), not finite, or beyond ±0.5 s is
/// refused before anything is read, naming the mapping file, the channel and the key.
#[test]
fn errors_a_shift_off_a_surface_or_out_of_range_is_refused() {
    let data = workspace().join("mappings/aeroident-sim.toml"); // never read: the mapping fails first
    for (keys, insert, channel, tag) in [
        (["q"], "shift_s = 0.02", "q", "on-q"),
        (["de"], "shift_s = nan", "de", "nan"),
        (["da"], "shift_s = 0.8", "da", "large"),
    ] {
        let (map, out) = (mapping_with(&keys, insert, tag), scratch(&format!("{tag}-out")));
        let args = [
            "replay".as_ref(),
            data.as_os_str(),
            "--map".as_ref(),
            map.as_os_str(),
            "--estimator".as_ref(),
            "oe".as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ];
        let (ok, err) = run(&args);
        assert!(!ok, "{tag}: accepted");
        let file = map.display().to_string();
        assert!(err.contains(&file), "{tag}: {err}");
        assert!(
            err.contains(&format!("channel `{channel}`")) && err.contains("`shift_s = "),
            "{tag}: {err}"
        );
        let _ = std::fs::remove_file(map);
    }
}
