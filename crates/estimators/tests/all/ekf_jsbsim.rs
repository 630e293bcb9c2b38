//! The EKF on the JSBSim sample records in `shared/flightdata` (third-party simulator data
//! with known true derivatives). Skips, saying so, when the data are absent.
//!
//! Target: within 10 % of the true derivative for every term whose true value is
//! above 5 % of its coefficient's largest term. Measured with the default configuration
//! (generic priors, default noise levels; nothing taken from the truth files), the tests
//! assert the terms that meet it. Known misses, and why (see the EKF closing note):
//! - lateral record: `Cl_p` (−12 %, 6σ): the roll-rate FBW makes δa nearly collinear with p,
//!   so an 8 ms input-timing skew of the logged surfaces (JSBSim logs the state after the
//!   step) biases `Cl_p`; delaying the surfaces by half a log interval gives −2 %. `CY_p`,
//!   `CY_r`, `Cl_r`, `Cn_p`, `Cn_r`: the yaw damper keeps r and β small (β SNR ≈ 4); their σ
//!   is 20–100 % of their value: not determined by this record, and the σ says so.
//! - longitudinal record: `CD_alpha`, `CD_q`, `CD_de`: their effect on ax is ≈ 0.05 m/s²; the
//!   tabulated CD(α, δe) is non-linear across the δe = 0 breakpoint this record crosses.

use crate::common::records;

use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_estimators::{Ekf, EkfConfig, Estimator, Status};
use records::{JsbsimChannels, shared};
use std::path::Path;

fn run(
    csv: &Path,
    truth: &Path,
    structure: ModelStructure,
    adaptive_r: bool,
    within_10pct: &[&str],
) {
    if !records::present(csv) || !records::present(truth) {
        return;
    }
    let channels = JsbsimChannels { noisy: true, angular_accelerations: false };
    let samples = records::jsbsim(csv, channels).unwrap().samples;
    let truth = records::read_truth(truth).unwrap();
    let mut cfg = EkfConfig::new(structure);
    if !adaptive_r {
        cfg.adaptive_r_window = 0;
    }
    let mut ekf = Ekf::new(cfg).unwrap();
    for s in &samples {
        ekf.update(s).unwrap_or_else(|e| panic!("t = {}: {e}", s.t_s));
    }
    assert_eq!(ekf.estimates().status, Status::Running);
    let rows = records::rows(&structure, ekf.estimates(), &truth);
    println!("{}", records::table(&rows));
    for name in within_10pct {
        let r = rows.iter().find(|r| r.name == *name).unwrap();
        let e = r.error_pct().unwrap_or(f64::INFINITY);
        assert!(e.abs() <= 10.0, "{name}: {:?} vs truth {:?} ({e:+.1} %)", r.value, r.truth);
    }
}

#[test]
fn f16_lateral_doublets_sample() {
    let d = shared().join("flightdata/jsbsim_samples");
    run(
        &d.join("f16_ail_rud_doublets_20s_60Hz.csv"),
        &d.join("f16_ail_rud_doublets_truth.json"),
        ModelStructure::lateral(),
        true,
        &["CY_beta", "CY_dr", "Cl_beta", "Cl_da", "Cl_dr", "Cn_beta", "Cn_da", "Cn_dr"],
    );
}

#[test]
fn f16_longitudinal_doublet_sample() {
    let d = shared().join("flightdata/jsbsim_f16_sample");
    run(
        &d.join("f16_doublet_20s_120Hz.csv"),
        &d.join("f16_true_derivatives_trim.json"),
        ModelStructure::longitudinal(),
        false,
        &["CL_alpha", "CL_q", "CL_de", "Cm_q", "Cm_de"],
    );
}

/// The same noise-free record with R estimated from the innovations (the default): there is
/// no sensor noise to estimate, R falls to its floor (σ/10), and the tables' non-linearity
/// is then the dominant error: Cm_q ends +12.8 % (measured), so it is not in the list.
#[test]
fn f16_longitudinal_doublet_sample_adaptive_r() {
    let d = shared().join("flightdata/jsbsim_f16_sample");
    run(
        &d.join("f16_doublet_20s_120Hz.csv"),
        &d.join("f16_true_derivatives_trim.json"),
        ModelStructure::longitudinal(),
        true,
        &["CL_alpha", "CL_q", "CL_de", "Cm_de"],
    );
}
