//! The per-manoeuvre consistency test of the compatibility check: flights of the degraded F-16
//! record (`scenarios/sim/degraded_compat.toml`: 10 Hz, biases, the α vane 0.2 s late, no β)
//! checked jointly. Two flights with the same sensors (another noise seed): no manoeuvre is
//! named. A third flight with its α vane on time: that manoeuvre alone is named, with the α
//! shift (its own ≈ 0 against the others' 0.2 s; the joint fit lies between).

mod common;
use aeroident::outdir::OutputDir;
use aeroident::sim::write_outputs;
use aeroident_estimators::compat::CompatConfig;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::compat::check_records;
use aeroident_pipelines::sim::{parse_scenario, run};
use common::workspace;
use std::path::Path;

/// The degraded record flown with `seed` and the α vane `alpha_delay_s` late, written to
/// `dir/name/timeseries.csv`.
fn fly(dir: &Path, name: &str, seed: u64, alpha_delay_s: f64) -> String {
    let path = workspace().join("scenarios/sim/degraded_compat.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace("seed = 3", &format!("seed = {seed}"));
    // The α vane's delay is the first `delay_s` of the file (its sensor comes first).
    let text = text.replacen("delay_s = 0.2", &format!("delay_s = {alpha_delay_s}"), 1);
    let sc = parse_scenario(&text, &path).unwrap();
    let sim = run(&sc, path.parent().unwrap()).unwrap();
    let out = dir.join(name);
    let mut od = OutputDir::open(&out, "f16 sim", &[]).unwrap();
    write_outputs(&sim, &mut od).unwrap();
    od.finish();
    out.join("timeseries.csv").display().to_string()
}

/// The sim's mapping pointed at the sensors' columns, without the sideslip vane.
fn measured_mapping(dir: &Path) -> Mapping {
    let path = dir.join("measured.toml");
    std::fs::write(&path, common::sim_measured_without_beta()).unwrap();
    Mapping::from_path(&path).unwrap()
}

fn disagreements(files: &[&str], m: &Mapping) -> Vec<String> {
    let readers = files.iter().map(|f| open_log(f, None, m).unwrap()).collect();
    let (s, _) = check_records(readers, &[], &CompatConfig::default()).unwrap();
    s.findings.into_iter().filter(|f| f.contains("disagrees with the other manoeuvres")).collect()
}

#[test]
fn a_manoeuvre_whose_sensor_changed_is_named() {
    let dir = std::env::temp_dir().join(format!("aeroident-consistency-{}", std::process::id()));
    let m = measured_mapping(&{
        std::fs::create_dir_all(&dir).unwrap();
        dir.clone()
    });
    let late = fly(&dir, "late", 3, 0.2);
    let late_again = fly(&dir, "late-again", 11, 0.2);
    let on_time = fly(&dir, "on-time", 11, 0.0);
    let same = disagreements(&[&late, &late_again], &m);
    assert!(same.is_empty(), "{same:?}");
    let changed = disagreements(&[&late, &late_again, &on_time], &m);
    assert_eq!(changed.len(), 1, "{changed:?}");
    assert!(
        changed[0].starts_with("manoeuvre 3 disagrees")
            && changed[0].contains("alpha_rad time shift"),
        "{}",
        changed[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
