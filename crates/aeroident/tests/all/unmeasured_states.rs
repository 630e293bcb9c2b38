//! A real lateral record without its sideslip channel (ATTAS AilRud1 with the `beta` line of the
//! shipped mapping removed, ../shared/flightdata; skipped with a message when absent, a failure
//! under CI): output error and the EKF carry β as a state instead of refusing the record, and
//! output error agrees with the fit of the same record with β measured.

use crate::common;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::estimators::EstimatorKind;
use aeroident_pipelines::replay::batch::{BatchSummary, FitOptions};
use aeroident_pipelines::replay::fit::fit_record;
use aeroident_pipelines::replay::{ReplayOptions, replay};
use common::{shared, workspace};
use std::path::Path;

const RECORD: &str = "jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv";

/// The shipped ATTAS lateral mapping, without its sideslip channel when `with_beta` is false.
fn mapping(with_beta: bool) -> Mapping {
    let path = workspace().join("mappings/attas_lateral.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text: String = text
        .lines()
        .filter(|l| with_beta || !l.starts_with("beta"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(text.contains("\nbeta ="), with_beta);
    Mapping::from_toml_str(&text, "attas_lateral.toml").unwrap()
}

fn oe(data: &Path, m: &Mapping) -> BatchSummary {
    let reader = open_log(&data.display().to_string(), None, m).unwrap();
    fit_record(reader, m, None, FitOptions::default()).unwrap().summary
}

fn estimate(s: &BatchSummary, name: &str) -> (f64, f64) {
    let p = s.parameters.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("no {name}"));
    (p.estimate.unwrap(), p.std_error.unwrap())
}

/// Output error without β: converged, β's initial value estimated per manoeuvre and said so,
/// `CY_0` left out, and the primary roll and yaw derivatives within 2 combined σ of the
/// β-measured fit of the same record (the target: Cl_p, Cl_da, Cn_β, Cn_r, Cn_dr).
#[test]
fn val_attas_lateral_output_error_without_beta_agrees_with_the_beta_measured_fit() {
    let Some(data) = shared(RECORD) else { return };
    let with = oe(&data, &mapping(true));
    let without = oe(&data, &mapping(false));
    assert_eq!(without.status, "converged", "{:?}", without.status_reason);
    assert_eq!(without.model, "lateral without CY_0");
    assert!(without.warnings.iter().any(|w| w.starts_with("β is not measured")));
    let x0: Vec<&str> = without.estimated_initial_states.iter().map(|(n, ..)| n.as_str()).collect();
    assert_eq!(x0, ["x0_m1_beta_rad", "x0_m2_beta_rad"]);
    assert!(!without.residual_rms.iter().any(|(o, _)| o == "beta_rad"));
    for name in ["Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr"] {
        let (a, sa) = estimate(&with, name);
        let (b, sb) = estimate(&without, name);
        let z = (a - b).abs() / sa.hypot(sb);
        assert!(z < 2.0, "{name}: {b} ± {sb} without β vs {a} ± {sa} with ({z:.2} combined σ)");
    }
}

/// The EKF on the same record without β runs (no "needs beta" refusal), starts β at 0 and
/// ends with the roll damping and weathercock stability of the β-measured EKF within 3 combined σ.
#[test]
fn val_attas_lateral_ekf_without_beta_runs_and_agrees() {
    let Some(data) = shared(RECORD) else { return };
    let opts = ReplayOptions { estimator: EstimatorKind::Ekf, ..Default::default() };
    let run = |m: &Mapping| {
        replay(open_log(&data.display().to_string(), None, m).unwrap(), m, &opts, &mut ()).unwrap()
    };
    let (with, without) = (run(&mapping(true)), run(&mapping(false)));
    assert_eq!(without.summary.status, "complete");
    assert_eq!(without.model.name, "lateral without CY_0");
    for name in ["Cl_p", "Cn_beta"] {
        let get = |o: &aeroident_pipelines::replay::ReplayOutcome| {
            let p = o.summary.parameters.iter().find(|p| p.name == name).unwrap();
            (p.estimate.unwrap(), p.std_error.unwrap())
        };
        let ((a, sa), (b, sb)) = (get(&with), get(&without));
        let z = (a - b).abs() / sa.hypot(sb);
        assert!(z < 3.0, "{name}: {b} ± {sb} without β vs {a} ± {sa} with ({z:.2} combined σ)");
    }
}
