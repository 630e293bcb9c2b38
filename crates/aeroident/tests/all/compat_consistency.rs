//! The per-manoeuvre consistency test of the compatibility check: flights of the degraded F-16
//! record (`scenarios/sim/degraded_compat.toml`: 10 Hz, biases, the α vane 0.2 s late, no β)
//! checked jointly. Two flights with the same sensors (another noise seed): no manoeuvre is
//! named. A third flight with its α vane on time: that manoeuvre alone is named, with the α
//! shift (its own ≈ 0 against the others' 0.2 s; the joint fit lies between), and the joint
//! shift fails on the manoeuvres held out in turn, so `replay --compat` refuses it; with the
//! two flights alike, no determined correction fails.

use crate::common;
use aeroident::outdir::OutputDir;
use aeroident::sim::write_outputs;
use aeroident_estimators::compat::CompatConfig;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::compat::{CompatSummary, Corrections, check_records};
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

fn check(files: &[&str], m: &Mapping) -> CompatSummary {
    let readers = files.iter().map(|f| open_log(f, None, m).unwrap()).collect();
    check_records(readers, &[], &CompatConfig::default()).unwrap().0
}

fn findings<'a>(s: &'a CompatSummary, what: &str) -> Vec<&'a String> {
    s.findings.iter().filter(|f| f.contains(what)).collect()
}

const DISAGREES: &str = "disagrees with the other manoeuvres";
const HELD_OUT: &str = "held out in turn";

/// Long by nature (about 80 s in release on 2 cores): three 10-Hz flights are simulated and
/// checked jointly twice, and each joint check refits every correction with each manoeuvre held
/// out in turn; the test needs two flights alike and one that differs, so none can go.
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
    let same = check(&[&late, &late_again], &m);
    assert!(findings(&same, DISAGREES).is_empty(), "{:?}", same.findings);
    assert!(findings(&same, HELD_OUT).is_empty(), "{:?}", same.findings);
    assert!(Corrections::from_summary(&same).unwrap().refused.is_empty());
    let all = check(&[&late, &late_again, &on_time], &m);
    let held = findings(&all, HELD_OUT);
    assert!(held.len() == 1 && held[0].contains("alpha_rad time shift"), "{:?}", all.findings);
    let refused = Corrections::from_summary(&all).unwrap().refused;
    assert!(
        refused.iter().any(|r| r.starts_with("alpha_rad time shift: applied to the manoeuvres")),
        "{refused:?}"
    );
    let changed = findings(&all, DISAGREES);
    assert_eq!(changed.len(), 1, "{changed:?}");
    assert!(
        changed[0].starts_with("manoeuvre 3 disagrees")
            && changed[0].contains("alpha_rad time shift"),
        "{}",
        changed[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
