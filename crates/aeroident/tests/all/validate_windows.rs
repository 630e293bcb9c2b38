//! `--validate-window`: a fit validated on held-out windows of its own record (or of the
//! `--validate-on` record). Independent check: the number of samples validated is the count of
//! the simulation's rows inside the window (100 Hz, both ends included), and a window that
//! overlaps the fitted one is validated with a warning, for a batch and a real-time estimator.

use crate::common;
use common::workspace;
use std::process::Command;

fn aeroident() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

#[test]
fn held_out_windows_of_the_fitted_record_are_validated() {
    let dir = std::env::temp_dir().join(format!("aeroident-valwin-{}", std::process::id()));
    let o = aeroident()
        .args(["f16", "sim"])
        .arg(workspace().join("scenarios/sim/six_axis_excitation.toml"))
        .arg("--out")
        .arg(dir.join("sim"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let data = dir.join("sim/timeseries.csv");
    for estimator in ["oe", "rls"] {
        for (window, overlaps) in [("12:16", false), ("11:16", true)] {
            let out = dir.join(format!("{estimator}-{window}").replace(':', "_"));
            let o = aeroident()
                .arg("replay")
                .arg(&data)
                .arg("--map")
                .arg(workspace().join("mappings/aeroident-sim.toml"))
                .args(["--estimator", estimator, "--window", "0:12", "--validate-window", window])
                .arg("--out")
                .arg(&out)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{err}");
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                    .unwrap();
            let (a, b): (f64, f64) = {
                let (a, b) = window.split_once(':').unwrap();
                (a.parse().unwrap(), b.parse().unwrap())
            };
            let rows = ((b - a) / 0.01).round() as u64 + 1;
            let on = &v["validation_on"];
            assert_eq!(on["used_for_fit"], false, "{estimator} {window}");
            assert_eq!(on["samples"], rows, "{estimator} {window}: {on}");
            let warned = v["warnings"].to_string().contains("overlap the fitted data");
            assert_eq!(warned, overlaps, "{estimator} {window}: {}", v["warnings"]);
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}
