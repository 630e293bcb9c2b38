//! The shipped `mappings/uav_oat.toml` on the UAV-OAT ArduPlane records
//! (../shared/flightdata/uav_oat; skipped with a message when absent, a failure under CI), and
//! batch fits of a record where a surface never moves.
//!
//! The records carry no reference values, so the checks are physics a conventional stable
//! aircraft obeys (Cm_α, Cm_q, Cm_δe, Cl_p, Cl_δa < 0; CL_α, Cn_β > 0 in Stevens & Lewis'
//! signs, docs/mapping.md), the lift-curve slope bounded by a finite wing's, and the drag terms
//! withheld because the record has no thrust.

use crate::common;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_pipelines::replay::batch::{BatchMethod, BatchSummary, FitOptions};
use aeroident_pipelines::replay::fit::fit_record;
use common::{shared, workspace};
use std::path::Path;

fn mapping() -> Mapping {
    let path = workspace().join("mappings/uav_oat.toml");
    Mapping::from_toml_str(&std::fs::read_to_string(&path).unwrap(), "uav_oat.toml").unwrap()
}

fn fit(data: &Path, model: ModelSpec, method: BatchMethod) -> BatchSummary {
    let m = mapping();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let options = FitOptions { method, ..FitOptions::default() };
    fit_record(reader, &m, Some(model), options).unwrap_or_else(|e| panic!("{e}")).summary
}

fn estimate(s: &BatchSummary, name: &str) -> Option<f64> {
    s.parameters.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no {name}")).estimate
}

/// The manoeuvre files of the set whose name holds `kind` (`_el_`, `_ail_`).
fn records(kind: &str) -> Option<Vec<std::path::PathBuf>> {
    let dir = shared("uav_oat/csv")?;
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().contains(kind))
        .collect();
    files.sort();
    Some(files)
}

/// Output error, longitudinal model, on every elevator multistep but the one the team logged
/// as poorly flown (2022-05-07 `el_4`: airspeed down to 3 m/s, α 21°; README): the pitch
/// derivatives have a stable aircraft's signs; CL_α is positive and below the 2π·A/(A + 2)
/// of a finite wing (A = b²/S = 6.7: 4.7 /rad) by less than a factor 4 (the α is computed from
/// the EKF wind, not a vane); every drag term is `null` with the no-thrust reason, none `ok`.
#[test]
fn val_uav_oat_elevator_multisteps_give_a_stable_aircrafts_pitch_derivatives() {
    let Some(files) = records("_el_") else { return };
    assert_eq!(files.len(), 6, "{files:?}");
    let wing = 2.0 * std::f64::consts::PI * 6.67 / 8.67;
    for data in files.iter().filter(|f| !f.ends_with("uavoat_2022_05_07_11_13_57_el_4.csv")) {
        let s = fit(data, ModelSpec::preset("longitudinal").unwrap(), BatchMethod::Oe);
        let name = data.file_name().unwrap().to_string_lossy();
        for p in ["Cm_alpha", "Cm_q", "Cm_de"] {
            let e = estimate(&s, p).unwrap();
            assert!(e < 0.0, "{name}: {p} = {e}");
        }
        let cla = estimate(&s, "CL_alpha").unwrap();
        assert!(cla > 0.0 && cla < 4.0 * wing, "{name}: CL_alpha = {cla}");
        for p in s.parameters.iter().filter(|p| p.name.starts_with("CD_")) {
            assert!(p.estimate.is_none() && p.status == "not identified", "{name}: {p:?}");
            assert!(p.flags.iter().any(|f| f.contains("thrust is not mapped")), "{p:?}");
        }
    }
}

/// Output error, lateral model, on every aileron multistep: roll damping and the aileron's
/// rolling moment negative (δa > 0 right trailing edge down), weathercock stability positive.
#[test]
fn val_uav_oat_aileron_multisteps_give_a_stable_aircrafts_roll_derivatives() {
    let Some(files) = records("_ail_") else { return };
    assert_eq!(files.len(), 7, "{files:?}");
    for data in &files {
        let s = fit(data, ModelSpec::preset("lateral").unwrap(), BatchMethod::Oe);
        let name = data.file_name().unwrap().to_string_lossy();
        let [clp, clda, cnb] = ["Cl_p", "Cl_da", "Cn_beta"].map(|p| estimate(&s, p).unwrap());
        assert!(clp < 0.0 && clda < 0.0 && cnb > 0.0, "{name}: {clp} {clda} {cnb}");
    }
}

/// The 2023 aileron record never moves the rudder (all 350 samples 0). Output error, the
/// filter-error method and frequency-domain output error no longer stop at the rudder terms:
/// each fits the rest, reports `CY_dr`, `Cl_dr`, `Cn_dr` `null` with the channel named, and
/// its other estimates equal those of the same method on a model written without the rudder
/// terms (an independent path: no term held out).
#[test]
fn val_a_surface_that_never_moves_leaves_its_terms_null_and_the_rest_fitted() {
    let Some(data) = shared("uav_oat/csv/uavoat_2023_02_01_14_21_28_ail_1.csv") else { return };
    let full = ModelSpec::preset("lateral").unwrap();
    let mut without = ModelSpec::preset("lateral").unwrap();
    let rudder: Vec<_> = full.structure.params().filter(|p| p.name().ends_with("_dr")).collect();
    assert_eq!(rudder.len(), 3);
    rudder.iter().for_each(|p| without.structure.remove(*p));
    let fdoe = BatchMethod::Fdoe { band_hz: (0.1, 2.0) };
    for method in [BatchMethod::Oe, BatchMethod::Fem, fdoe] {
        let held = fit(&data, full.clone(), method);
        let reference = fit(&data, without.clone(), method);
        assert_eq!(held.parameters.len(), 18, "{method:?}");
        for p in &held.parameters {
            if p.name.ends_with("_dr") {
                assert!(p.estimate.is_none() && p.status == "not identified", "{p:?}");
                assert!(p.flags.iter().any(|f| f.contains("channel `dr`")), "{p:?}");
                continue;
            }
            let r = reference.parameters.iter().find(|q| q.name == p.name).unwrap();
            assert_eq!(p.estimate, r.estimate, "{method:?} {}", p.name);
            assert_eq!(p.std_error, r.std_error, "{method:?} {}", p.name);
        }
    }
}

/// The compatibility check on the UAV-OAT records, which have a sideslip channel (ArduPilot's,
/// from the EKF wind): on the 2023-02-01 `el_1` multistep the check determines a β bias of
/// −0.235 ± 0.031 rad (13.5°) and a heading lag of 1.0 ± 0.2 s, on the 2022-05-07 `ail_1` one
/// a heading lead of 0.027 ± 0.013 s. Each is named as implausible for its channel (bounds
/// ±0.175 rad, ±0.5 s, no AHRS lead beyond 0.02 s), and `replay --compat` applies none of them
/// and says why; a record with its own sideslip gets no reconstructed one.
#[test]
fn val_uav_oat_compat_refuses_the_implausible_corrections_with_their_reason() {
    use aeroident_estimators::compat::CompatConfig;
    use aeroident_pipelines::compat::{Corrections, check_record};
    let Some(dir) = shared("uav_oat/csv") else { return };
    let cases = [
        ("uavoat_2023_02_01_14_21_28_el_1.csv", &["beta_rad bias", "psi_rad time shift"][..]),
        ("uavoat_2022_05_07_11_13_57_ail_1.csv", &["psi_rad time shift"][..]),
    ];
    for (name, implausible) in cases {
        let m = mapping();
        let reader = open_log(&dir.join(name).display().to_string(), None, &m).unwrap();
        let s = check_record(reader, &CompatConfig::default()).unwrap().0;
        let named: Vec<&String> = s.findings.iter().filter(|f| f.contains("implausible")).collect();
        assert_eq!(named.len(), 1, "{name}: {:?}", s.findings);
        let c = Corrections::from_summary(&s).unwrap();
        for what in implausible {
            assert!(named[0].contains(what), "{name}, {what}: {}", named[0]);
            let channel = what.split(' ').next().unwrap();
            assert!(!c.applied.iter().any(|a| a.starts_with(channel)), "{name}: {:?}", c.applied);
            assert!(c.refused.iter().any(|r| r.starts_with(channel)), "{name}: {:?}", c.refused);
        }
        assert!(!c.applied.iter().any(|a| a.contains("reconstructed")), "{:?}", c.applied);
    }
}
