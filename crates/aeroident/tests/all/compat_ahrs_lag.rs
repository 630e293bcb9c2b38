//! The check's AHRS lag (`CompatConfig::ahrs_lag`, `aeroident compat --ahrs-lag`) on an `f16
//! sim` record whose AHRS passes its rates and attitudes through one first-order filter
//! (`scenarios/sim/ahrs_lag_degraded.toml`: τ = 0.15 s, the α vane 0.2 s late, biases and
//! 2–5 % scale factors, no β vane, light turbulence, linear aerodynamics about the trim), kept
//! at 10 Hz: the time constant, and the derivatives output error and the filter-error method
//! estimate on the record corrected (`replay --compat`) with the lag model, the gyros' time
//! shifts, the default check (`--compat auto`) and none, against the simulator's truth.

use crate::common;
use aeroident_estimators::compat::CompatConfig;
use aeroident_estimators::vocabulary::Param;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_models::f16::{AeroIncrements, F16};
use aeroident_pipelines::aircraft::truth::local_derivatives;
use aeroident_pipelines::compat::{CompatSummary, Corrections, check_record};
use aeroident_pipelines::replay::batch::{BatchMethod, BatchSummary, FitOptions};
use aeroident_pipelines::replay::fit::fit_record;
use aeroident_pipelines::sim::{load_scenario, run};
use aeroident_signals::sensors::SensorConfig;
use common::workspace;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

/// The simulator's sensed channels.
const SENSED: [&str; 14] = [
    "vt_air_fps",
    "alpha_air_rad",
    "ax_fps2",
    "ay_fps2",
    "az_fps2",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "elevator_rad",
    "aileron_rad",
    "rudder_rad",
];

/// The flown record kept at every `stride`th 0.01-s step, its measured mapping, and the
/// truth (the trim's derivatives: the aerodynamics are linear about it).
struct Record {
    dir: PathBuf,
    csv: String,
    map: PathBuf,
    mapping: Mapping,
    truth: aeroident_pipelines::aircraft::truth::LocalDerivatives,
}

impl Record {
    fn fly(stride: usize) -> Self {
        Self::fly_with(stride, false)
    }

    /// The record, with a β vane (the α vane's noise, not late) when `vane`.
    fn fly_with(stride: usize, vane: bool) -> Self {
        let path = workspace().join("scenarios/sim/ahrs_lag_degraded.toml");
        let mut sc = load_scenario(&path).unwrap();
        if vane {
            let alpha = sc.sensor.iter().find(|s| s.channel == "alpha_air_rad").unwrap();
            let beta =
                SensorConfig { channel: "beta_air_rad".into(), delay_s: None, ..alpha.clone() };
            sc.sensor.push(beta);
        }
        let sim = run(&sc, path.parent().unwrap()).unwrap();
        // One directory per record: the tests run in parallel in one process, and each
        // record's directory goes when it is dropped.
        static FLOWN: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let k = FLOWN.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir()
            .join(format!("aeroident-compat-ahrs-lag-{stride}-{}-{k}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut csv = sim.table.columns.join(",") + "\n";
        for k in (0..sim.table.data[0].len()).step_by(stride) {
            let row: Vec<String> =
                sim.table.data.iter().map(|c| format!("{:.10e}", c[k])).collect();
            let _ = writeln!(csv, "{}", row.join(","));
        }
        let csv_path = dir.join("timeseries.csv");
        std::fs::write(&csv_path, csv).unwrap();
        // The shipped mapping pointed at what the sensors measured, without the β vane and the
        // model's own state derivatives (a logger has neither).
        let shipped = std::fs::read_to_string(workspace().join("mappings/aeroident-sim.toml"));
        let skip = ["beta =", "pdot =", "qdot =", "rdot =", "alphadot ="];
        let skip = if vane { &skip[1..] } else { &skip[..] };
        let mut text: String = shipped
            .unwrap()
            .lines()
            .filter(|l| !skip.iter().any(|s| l.starts_with(s)))
            .collect::<Vec<_>>()
            .join("\n");
        for c in SENSED.iter().chain(vane.then_some(&"beta_air_rad")) {
            text = text.replace(&format!("column = \"{c}\""), &format!("column = \"meas_{c}\""));
        }
        let map = dir.join("measured.toml");
        std::fs::write(&map, text).unwrap();
        let f16 = F16::new(sc.aircraft.as_ref().unwrap().xcg).unwrap();
        let truth =
            local_derivatives(&f16, &sim.trim.state, &sim.trim.controls, &AeroIncrements::zero())
                .unwrap();
        let mapping = Mapping::from_path(&map).unwrap();
        Self { dir, csv: csv_path.display().to_string(), map, mapping, truth }
    }

    fn check(&self, config: CompatConfig) -> CompatSummary {
        let reader = open_log(&self.csv, None, &self.mapping).unwrap();
        let (s, _) = check_record(reader, &config).unwrap();
        eprintln!(
            "check {config:?}\n  {} after {}; lag {:?} ± {:?}",
            s.status, s.iterations, s.ahrs_lag_tau_s, s.ahrs_lag_tau_sigma_s
        );
        for c in &s.channels {
            eprintln!(
                "  {:<10} bias {:?} scale {:?} shift {:?} ± {:?}",
                c.name, c.bias, c.scale, c.time_shift_s, c.time_shift_sigma_s
            );
        }
        eprintln!("  findings {:?}\n  warnings {:?}", s.findings, s.warnings);
        s
    }

    fn fit(&self, method: BatchMethod, compat: Option<Corrections>) -> BatchSummary {
        let reader = open_log(&self.csv, None, &self.mapping).unwrap();
        let model = Some(ModelSpec::from_arg("six-axis").unwrap());
        let options =
            FitOptions { method, compat, max_iterations: Some(100), ..FitOptions::default() };
        fit_record(reader, &self.mapping, model, options).unwrap().summary
    }

    /// Per primary derivative the fit has, `(name, relative error)`.
    fn errors(&self, s: &BatchSummary) -> Vec<(String, f64)> {
        let primary = aeroident_pipelines::aircraft::summary::PRIMARY_DERIVATIVES;
        s.parameters
            .iter()
            .filter(|p| primary.contains(&p.name.as_str()))
            .filter_map(|p| {
                let t = self.truth.derivative(Param::from_name(&p.name)?)?;
                Some((p.name.clone(), (p.estimate? - t) / t.abs()))
            })
            .collect()
    }
}

impl Drop for Record {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

/// The longitudinal primary derivatives and the lateral ones that do not act through β.
const JUDGED: [&str; 8] =
    ["CL_alpha", "Cm_alpha", "Cm_q", "Cm_de", "Cl_p", "Cl_da", "Cn_beta", "Cn_dr"];

/// At 10 and 20 Hz the check with the AHRS lag (and the inertial scale factors) finds τ within
/// 0.02 s and 2σ of the filter's low-frequency delay, 0.155 s (τ plus the 100-Hz
/// discretisation's half step; measured 0.168 ± 0.017 s at 10 Hz; the gyros' time shifts read
/// 0.15–0.20 s there, the α vane 0.28 s for 0.2). `replay --compat` then passes every other channel through the filter and
/// says so; with it, output error and the filter-error method get each longitudinal primary
/// derivative and the lateral ones that do not act through β closer to the truth than without
/// the corrections, and within 10 % of it but for the filter-error method's Cl_δa (measured,
/// oe: CL_α +4.0 %, Cm_α −4.1, Cm_q −8.6, Cm_δe −6.4, Cl_p −0.2, Cl_δa −1.9, Cn_β −3.8, Cn_δr
/// +0.1; uncorrected +11.7, +5.3, +35.3, +18.9, +34.6, +34.2, −5.0, +30.8; fem: +5.4, −6.6,
/// −1.1, −4.8, −7.2, −15.4, −4.8, −0.6; uncorrected −15.1, +21.5, +21.5, +21.7, +54.4, +49.5,
/// −14.6, +41.7). CY_β, Cl_β and Cn_r, which the reconstructed sideslip carries without a vane,
/// are printed, not judged (oe +24, +12, −19 %; uncorrected −4.3, +4.8, +19.5).
#[test]
fn val_the_ahrs_lag_is_measured_and_its_filter_shared_by_every_channel() {
    let rec = Record::fly(10);
    let lag = rec.check(CompatConfig {
        ahrs_lag: true,
        inertial_scale_factors: true,
        ..CompatConfig::default()
    });
    assert!(lag.status.starts_with("converged"), "{} {:?}", lag.status, lag.status_reason);
    let (tau, sigma) = (lag.ahrs_lag_tau_s.unwrap(), lag.ahrs_lag_tau_sigma_s.unwrap());
    let delay = 0.01 / -(-0.01f64 / 0.15).exp_m1();
    assert!((tau - delay).abs() < 0.02 && (tau - delay).abs() < 2.0 * sigma, "τ {tau} ± {sigma}");
    for method in [BatchMethod::Oe, BatchMethod::Fem] {
        let raw = rec.errors(&rec.fit(method, None));
        let fit = rec.fit(method, Some(Corrections::from_summary(&lag).unwrap()));
        let said = "compat applied: every channel not from the AHRS";
        assert!(fit.warnings.iter().any(|w| w.starts_with(said)), "{:?}", fit.warnings);
        for (name, e) in rec.errors(&fit) {
            let before = raw.iter().find(|r| r.0 == name).map_or(f64::NAN, |r| r.1);
            eprintln!(
                "{method:?} {name}: {:+.1} % corrected, {:+.1} % raw",
                100.0 * e,
                100.0 * before
            );
            if JUDGED.contains(&name.as_str()) {
                assert!(e.abs() <= before.abs(), "{method:?} {name}: {e} vs raw {before}");
                let fem_cl_da = method == BatchMethod::Fem && name == "Cl_da";
                assert!(e.abs() < 0.1 || fem_cl_da, "{method:?} {name}: {e}");
            }
        }
    }
    cli(&rec, tau);
    // At 20 Hz (measured 0.163 ± 0.016 s).
    let fine = Record::fly(5).check(CompatConfig {
        ahrs_lag: true,
        inertial_scale_factors: true,
        ..CompatConfig::default()
    });
    let (tau, sigma) = (fine.ahrs_lag_tau_s.unwrap(), fine.ahrs_lag_tau_sigma_s.unwrap());
    assert!(
        (tau - delay).abs() < 0.02 && (tau - delay).abs() < 2.0 * sigma,
        "20 Hz: τ {tau} ± {sigma}"
    );
}

/// The same through the binary: `compat --ahrs-lag --inertial-scale-factors --out` writes the
/// lag the library found to `compat.json` and prints it, and `replay --compat compat.json
/// --estimator oe` says in its summary that it filtered the other channels with it.
fn cli(rec: &Record, tau: f64) {
    let bin = || Command::new(env!("CARGO_BIN_EXE_aeroident"));
    let out = rec.dir.join("compat");
    let o = bin()
        .args(["compat", &rec.csv, "--ahrs-lag", "--inertial-scale-factors", "--map"])
        .arg(&rec.map)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(
        printed.contains(&format!("AHRS lag (first-order time constant): {tau:.3}")),
        "{printed}"
    );
    let json = out.join("compat.json");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(file["ahrs_lag_tau_s"].as_f64(), Some(tau));
    let fit = rec.dir.join("fit");
    let o = bin()
        .args(["replay", &rec.csv, "--model", "six-axis", "--estimator", "oe", "--map"])
        .arg(&rec.map)
        .arg("--compat")
        .arg(&json)
        .arg("--out")
        .arg(&fit)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = std::fs::read_to_string(fit.join("summary.json")).unwrap();
    assert!(
        summary.contains(&format!("compat applied: every channel not from the AHRS (accelerometers, air data, surfaces, thrust) passed through the AHRS's first-order filter, τ = {tau:.3} s")),
        "{summary}"
    );
}

/// `--compat auto`'s check (biases, no lag model) on the 10-Hz record names the lag it does
/// not model (τ within 0.02 s of the filter's 0.155-s delay) and the command that does; its
/// corrections are right, and output error's six-axis fit of the corrected record without a β vane, which
/// from the equation-error start crept for the whole iteration budget into a valley with
/// Cn_β at a seventh of its value, is started again from the generic priors and keeps every
/// lateral derivative within 5 points of the uncorrected fit's error (the AHRS lag, which this
/// check does not model, leaves Cl_p ≈ 35 % off in both; the corrected fit had CY_β +111 %,
/// Cn_β −86 % and Cn_r −160 % before the second start).
#[test]
fn val_compat_auto_without_a_vane_keeps_the_lateral_axis() {
    let rec = Record::fly(10);
    let check = rec.check(CompatConfig::default());
    // The lag it does not model is named, with τ as the lag check finds it, and not applied.
    let delay = 0.01 / -(-0.01f64 / 0.15).exp_m1();
    let named = check.findings.iter().find(|f| f.contains("look lagged")).expect("a lag finding");
    let tau: f64 = named.split("τ = ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((tau - delay).abs() < 0.02 && named.contains("--ahrs-lag"), "{named}");
    assert_eq!(check.ahrs_lag_tau_s, None);
    let corrections = Corrections::from_summary(&check).unwrap();
    let raw = rec.errors(&rec.fit(BatchMethod::Oe, None));
    let fit = rec.fit(BatchMethod::Oe, Some(corrections));
    assert!(fit.status.starts_with("converged"), "{} {:?}", fit.status, fit.status_reason);
    let lateral = ["CY_beta", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr"];
    for (name, e) in rec.errors(&fit).into_iter().filter(|(n, _)| lateral.contains(&n.as_str())) {
        let before = raw.iter().find(|r| r.0 == name).map_or(f64::NAN, |r| r.1);
        eprintln!("auto {name}: {:+.1} % corrected, {:+.1} % raw", 100.0 * e, 100.0 * before);
        assert!(e.abs() <= before.abs() + 0.05, "{name}: {e} against raw {before}");
    }
}

/// The evidence for leaving the lag out of `--compat auto`, with and without a β vane (the
/// same flight with a β vane of white σ 0.0005 rad added): per primary derivative, % error of
/// output error and the filter-error method uncorrected, with `--compat auto`'s corrections,
/// and with the lag's (`--ahrs-lag --inertial-scale-factors`). A documented campaign (about
/// 2 min): `cargo test --release -p aeroident --test all
/// compat_ahrs_lag::the_lag_against_auto -- --ignored --nocapture`. Measured with the vane,
/// oe: every primary derivative within 13 % with the lag (Cl_p −0.1, Cm_q −7.2, CY_β +11.3,
/// Cn_δr +12.9 %), 35 % off uncorrected and with auto, but CY_β −4.6 % uncorrected; fem does
/// not converge in any of the three (docs/real-data.md).
#[test]
#[ignore = "a documented campaign of about 2 min (docs/real-data.md); run with --ignored"]
fn the_lag_against_auto_with_and_without_a_vane() {
    for vane in [false, true] {
        let rec = Record::fly_with(10, vane);
        let auto = Corrections::from_summary(&rec.check(CompatConfig::default())).unwrap();
        let lagged = rec.check(CompatConfig {
            ahrs_lag: true,
            inertial_scale_factors: true,
            ..CompatConfig::default()
        });
        let lag = Corrections::from_summary(&lagged).unwrap();
        for method in [BatchMethod::Oe, BatchMethod::Fem] {
            let fits = [None, Some(auto.clone()), Some(lag.clone())].map(|c| rec.fit(method, c));
            let status: Vec<&str> = fits.iter().map(|f| f.status.as_str()).collect();
            eprintln!("vane {vane}, {method:?} (none, auto, lag): {status:?}");
            let errors: Vec<Vec<(String, f64)>> = fits.iter().map(|f| rec.errors(f)).collect();
            for (name, _) in &errors[0] {
                let e: Vec<f64> = errors
                    .iter()
                    .map(|x| x.iter().find(|y| &y.0 == name).map_or(f64::NAN, |y| 100.0 * y.1))
                    .collect();
                eprintln!("  {name:<9} {:+7.1} {:+7.1} {:+7.1}", e[0], e[1], e[2]);
                if vane && method == BatchMethod::Oe {
                    assert!(e[2].abs() < 13.0, "{name}: {e:?}");
                }
            }
        }
    }
}
