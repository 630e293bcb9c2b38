//! The data compatibility check measures the time shift of the gyros against the
//! accelerometers (`CompatConfig::gyro_time_shifts`, `aeroident compat --gyro-time-shifts`) on
//! F-16 records whose AHRS the simulator delays or lags (`aeroident_signals::SensorModel`,
//! independent of the check's kinematics): every channel sampled at 10 Hz and the record kept
//! at those samples (`scenarios/sim/ahrs_delay_compat.toml`, `ahrs_lag_compat.toml`).

use crate::common;
use aeroident_estimators::compat::CompatConfig;
use aeroident_io::{Mapping, RecordEvent, open_log};
use aeroident_pipelines::compat::{CompatSummary, Corrected, Corrections, check_record};
use aeroident_pipelines::sim::{load_scenario, run};
use common::workspace;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

/// The channels every scenario senses, as the simulator names them.
const SENSED: [&str; 12] = [
    "vt_air_fps",
    "alpha_air_rad",
    "beta_air_rad",
    "ax_fps2",
    "ay_fps2",
    "az_fps2",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "phi_rad",
    "theta_rad",
    "psi_rad",
];

/// The sensors' sample interval, s.
const T_S: f64 = 0.1;

/// A flown scenario at the sensors' samples: `timeseries.csv` and the mapping of its measured
/// channels in `dir`, and the true pitch rate at each row.
struct Record {
    dir: PathBuf,
    csv: String,
    map: PathBuf,
    q_true: Vec<f64>,
}

impl Record {
    /// Flies `scenario` (a file of `scenarios/sim`) and keeps every 10th step (the sensors' 10 Hz
    /// samples).
    fn fly(scenario: &str) -> Self {
        Self::fly_every(scenario, 10, true)
    }

    /// Flies `scenario` and keeps every `stride`th step of the simulator's 0.01 s; without
    /// `beta_vane` the mapping leaves `beta` out.
    fn fly_every(scenario: &str, stride: usize, beta_vane: bool) -> Self {
        let path = workspace().join("scenarios/sim").join(scenario);
        let sc = load_scenario(&path).unwrap();
        let sim = run(&sc, path.parent().unwrap()).unwrap();
        let dir = std::env::temp_dir()
            .join(format!("aeroident-compat-gyro-{scenario}-{stride}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rows: Vec<usize> = (0..sim.table.data[0].len()).step_by(stride).collect();
        let mut csv = sim.table.columns.join(",") + "\n";
        for &k in &rows {
            let row: Vec<String> =
                sim.table.data.iter().map(|c| format!("{:.10e}", c[k])).collect();
            let _ = writeln!(csv, "{}", row.join(","));
        }
        let csv_path = dir.join("timeseries.csv");
        std::fs::write(&csv_path, csv).unwrap();
        let shipped = workspace().join("mappings/aeroident-sim.toml");
        let mut text = std::fs::read_to_string(shipped).unwrap();
        if !beta_vane {
            text = text.lines().filter(|l| !l.starts_with("beta =")).collect::<Vec<_>>().join("\n");
        }
        for c in SENSED {
            text = text.replace(&format!("column = \"{c}\""), &format!("column = \"meas_{c}\""));
        }
        let map = dir.join("measured.toml");
        std::fs::write(&map, text).unwrap();
        let q = sim.table.columns.iter().position(|c| c == "q_rad_s").unwrap();
        let q_true = rows.iter().map(|&k| sim.table.data[q][k]).collect();
        Self { dir, csv: csv_path.display().to_string(), map, q_true }
    }

    /// The check of the record with the gyros' time shifts.
    fn check(&self) -> CompatSummary {
        self.check_with(CompatConfig { gyro_time_shifts: true, ..CompatConfig::default() })
    }

    /// The check of the record with `config`.
    fn check_with(&self, config: CompatConfig) -> CompatSummary {
        let mapping = Mapping::from_path(&self.map).unwrap();
        let reader = open_log(&self.csv, None, &mapping).unwrap();
        let (s, _) = check_record(reader, &config).unwrap();
        for c in &s.channels {
            eprintln!(
                "{:<10} bias {:?} ± {:?}  shift {:?} ± {:?}",
                c.name, c.bias, c.bias_sigma, c.time_shift_s, c.time_shift_sigma_s
            );
        }
        eprintln!("{} after {}: {:?} {:?}", s.status, s.iterations, s.findings, s.warnings);
        s
    }

    /// The RMS error of the measured pitch rate against the true one, as recorded and with
    /// `corr` applied (`replay --compat`), over the rows a shift of up to 0.5 s does not hold.
    fn q_errors(&self, corr: Corrections) -> (f64, f64) {
        let mapping = Mapping::from_path(&self.map).unwrap();
        let q = |events: &mut dyn Iterator<Item = _>| -> Vec<f64> {
            events
                .filter_map(|e| match e {
                    Ok(RecordEvent::Sample { sample, .. }) => sample.q_rad_s,
                    _ => None,
                })
                .collect()
        };
        let raw = q(&mut open_log(&self.csv, None, &mapping).unwrap());
        let reader = open_log(&self.csv, None, &mapping).unwrap();
        let corrected = q(&mut Corrected::new(reader, corr));
        assert_eq!((raw.len(), corrected.len()), (self.q_true.len(), self.q_true.len()));
        let rms = |z: &[f64]| {
            let n = z.len() - 5;
            let ss: f64 = z[..n].iter().zip(&self.q_true).map(|(a, b)| (a - b).powi(2)).sum();
            (ss / n as f64).sqrt()
        };
        (rms(&raw), rms(&corrected))
    }
}

impl Drop for Record {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

/// `(time shift, σ)` of channel `name`.
fn shift(s: &CompatSummary, name: &str) -> (f64, f64) {
    let c = s.channels.iter().find(|c| c.name == name).unwrap();
    (c.time_shift_s.unwrap(), c.time_shift_sigma_s.unwrap())
}

/// Pure delays of 0.1 s on the gyros and the attitudes and 0.2 s on the α vane, none on the β
/// vane: every shift within 0.03 s and 2σ of its delay (measured within 0.014 s), the gyros'
/// named in the findings; undoing the corrections (`replay --compat`) brings the pitch rate to
/// the true one within the gyro's noise; the CLI writes the gyros' shifts to `compat.json` and
/// `report.html`.
#[test]
fn val_compat_recovers_pure_delays_of_the_gyros_attitudes_and_alpha_vane() {
    let rec = Record::fly("ahrs_delay_compat.toml");
    let s = rec.check();
    assert!(s.status.starts_with("converged"), "{} {:?}", s.status, s.status_reason);
    let want = [
        ("p_rad_s", 0.1),
        ("q_rad_s", 0.1),
        ("r_rad_s", 0.1),
        ("phi_rad", 0.1),
        ("theta_rad", 0.1),
        ("psi_rad", 0.1),
        ("alpha_rad", 0.2),
        ("beta_rad", 0.0),
    ];
    for (name, delay) in want {
        let (t, sigma) = shift(&s, name);
        assert!((t - delay).abs() < 0.03, "{name}: {t} ± {sigma} vs {delay}");
        assert!((t - delay).abs() < 2.0 * sigma, "{name}: {t} ± {sigma} vs {delay}");
    }
    for g in ["p_rad_s", "q_rad_s", "r_rad_s"] {
        let f = format!("{g} lags the kinematics by 0.1");
        assert!(s.findings.iter().any(|x| x.starts_with(&f)), "{f}: {:?}", s.findings);
    }

    let corr = Corrections::from_summary(&s).unwrap();
    assert!(corr.applied.iter().any(|a| a.starts_with("q_rad_s: read +0.1")), "{:?}", corr.applied);
    let (raw, corrected) = rec.q_errors(corr);
    eprintln!("q error RMS: raw {raw:.2e}, corrected {corrected:.2e} rad/s");
    // The delay leaves 7.9e-3 rad/s; undone, the gyro's white noise is left (σ 5e-4 rad/s;
    // measured 5.04e-4).
    assert!(
        corrected < 1.5 * 5e-4 && raw > 10.0 * corrected,
        "q RMS: raw {raw}, corrected {corrected}"
    );

    let out = rec.dir.join("out");
    let st = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["compat", &rec.csv, "--gyro-time-shifts", "--map"])
        .arg(&rec.map)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compat.json")).unwrap()).unwrap();
    let rows = json["channels"].as_array().unwrap();
    let q = rows.iter().find(|r| r["name"] == "q_rad_s").unwrap();
    assert_eq!(q["time_shift_s"].as_f64(), Some(shift(&s, "q_rad_s").0));
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("q_rad_s time shift (s)") && html.contains("q_rad_s lags the kinematics")
    );
}

/// The low-frequency delay, s, of the simulator's lag of time constant `tau_s`: it filters the
/// held samples and reads before each step (`SensorModel`), `y_k = a·y_{k−1} + (1 − a)·u_{k−1}`,
/// `a = e^{−T/τ}`, whose group delay at zero frequency is `T / (1 − a)` (≈ τ + T/2 + T²/12τ).
fn lag_delay_s(tau_s: f64) -> f64 {
    T_S / -(-T_S / tau_s).exp_m1()
}

/// First-order lags, τ = 0.1 s on the gyros and 0.15 s on the attitudes (the α vane 0.2 s late,
/// the β vane not): against the β vane, each shift within 0.03 s of the lag's low-frequency
/// delay, 0.158 s and 0.206 s (measured 0.141–0.155 s and 0.186–0.196 s; α 0.191 s for 0.2).
/// Against the accelerometers every channel, the vanes too, reads 0.06 s later still (β 0.059
/// s): a delay fits a lag only in part, and the record ties the whole set to the
/// accelerometers through the airspeed and the vanes alone, so the misfit moves it as a whole.
#[test]
fn val_compat_measures_first_order_lags_of_an_ahrs() {
    let s = Record::fly("ahrs_lag_compat.toml").check();
    assert!(s.status.starts_with("converged"), "{} {:?}", s.status, s.status_reason);
    let (beta, _) = shift(&s, "beta_rad");
    assert!(beta.abs() < 0.1, "β vane {beta}");
    let want = [
        ("p_rad_s", lag_delay_s(0.1)),
        ("q_rad_s", lag_delay_s(0.1)),
        ("r_rad_s", lag_delay_s(0.1)),
        ("phi_rad", lag_delay_s(0.15)),
        ("theta_rad", lag_delay_s(0.15)),
        ("psi_rad", lag_delay_s(0.15)),
        ("alpha_rad", 0.2),
    ];
    for (name, delay) in want {
        let (t, sigma) = shift(&s, name);
        eprintln!("{name}: {t:.3} ± {sigma:.3} s, {:.3} s after β; delay {delay:.3} s", t - beta);
        assert!((t - beta - delay).abs() < 0.03, "{name}: {t} − β {beta} vs {delay}");
    }
}

/// Without a β vane the gyros and attitudes are tied to the accelerometers through the α vane
/// alone, whose own shift and scale factor are free (`compat` module doc, "What decides the
/// common AHRS shift"). Every rate, attitude and the α vane 0.2 s late, biases and 2–5 % scale
/// factors, still air (`scenarios/sim/ahrs_delay_nobeta.toml`): at 100 Hz every shift within
/// 0.03 s and 2σ of 0.2 s (measured 0.206–0.214 ± 0.007–0.010 s) and no caveat. Kept at 10 Hz
/// q, θ and α come out 0.215 s but p, r, φ and ψ 0.250–0.255 ± 0.015 s, with σ that do not
/// show it, so at a coarse rate the check says to check them before applying them.
#[test]
fn val_without_a_beta_vane_the_ahrs_shift_is_measured_at_100_hz_and_flagged_at_10_hz() {
    let config = CompatConfig {
        gyro_time_shifts: true,
        inertial_scale_factors: true,
        ..CompatConfig::default()
    };
    // Every scale factor the check reports is within 2 % of the scenario's (σ-pruned ones are
    // left out, not guessed): a 10 Hz record that determined them no better once got the
    // accelerometers' at 0.74.
    let scales_right = |s: &CompatSummary| {
        let truth = [
            ("ax_mps2", 1.03),
            ("ay_mps2", 0.98),
            ("az_mps2", 1.02),
            ("p_rad_s", 1.04),
            ("q_rad_s", 0.97),
            ("r_rad_s", 1.05),
            ("alpha_rad", 1.0),
        ];
        for c in &s.channels {
            if let Some(k) = c.scale {
                let (_, want) = truth.iter().find(|(n, _)| *n == c.name).unwrap();
                assert!((k - want).abs() < 0.02, "{}: scale {k} vs {want}", c.name);
            }
        }
    };
    let untrusted = |s: &CompatSummary| {
        s.warnings
            .iter()
            .chain(&s.findings)
            .any(|w| w.contains("check them against a record with a sideslip vane"))
    };
    let fine = Record::fly_every("ahrs_delay_nobeta.toml", 1, false).check_with(config);
    assert!(fine.status.starts_with("converged"), "{} {:?}", fine.status, fine.status_reason);
    for name in ["p_rad_s", "q_rad_s", "r_rad_s", "phi_rad", "theta_rad", "psi_rad", "alpha_rad"] {
        let (t, sigma) = shift(&fine, name);
        assert!((t - 0.2).abs() < 0.03 && (t - 0.2).abs() < 2.0 * sigma, "{name}: {t} ± {sigma}");
    }
    assert!(!untrusted(&fine), "{:?} {:?}", fine.warnings, fine.findings);
    scales_right(&fine);

    let coarse = Record::fly_every("ahrs_delay_nobeta.toml", 10, false).check_with(config);
    assert!(coarse.status.starts_with("converged"), "{} {:?}", coarse.status, coarse.status_reason);
    for name in ["p_rad_s", "q_rad_s", "r_rad_s", "alpha_rad"] {
        let (t, sigma) = shift(&coarse, name);
        eprintln!("10 Hz without a β vane: {name} shift {t:.3} ± {sigma:.3} s for 0.2 s");
    }
    assert!(untrusted(&coarse), "{:?} {:?}", coarse.warnings, coarse.findings);
    scales_right(&coarse);
}
