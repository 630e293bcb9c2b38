//! Runs the EKF over one JSBSim logger record and prints truth, estimate ± σ and error for
//! every parameter of a preset (the measurements reported in the EKF's closing note).
//!
//! `cargo run --release -p aeroident-estimators --example ekf_record -- RECORD.csv TRUTH.json
//! longitudinal|lateral|six-axis [--angular-accelerations] [--t0 S] [--t1 S] [--coloured]
//! [--qscale F] [--alphadot]` (`--qscale` multiplies the default state process noise;
//! `--alphadot` adds `CL_alphadot` and `Cm_alphadot` to the preset)
#![allow(missing_docs)]

#[path = "../tests/all/common/records.rs"]
mod records;

use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_estimators::{Ekf, EkfConfig, Estimator, SigmaOption};
use std::path::Path;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: ekf_record RECORD.csv TRUTH.json PRESET [options]".into());
    }
    let mut structure = ModelStructure::preset(&args[2]).ok_or("unknown preset")?;
    let flag = |f: &str| args.iter().any(|a| a == f);
    if flag("--alphadot") {
        use aeroident_estimators::vocabulary::{Coefficient, Term};
        structure = structure
            .with(Coefficient::CL, &[Term::Alphadot])
            .with(Coefficient::Cm, &[Term::Alphadot]);
    }
    let val = |f: &str| {
        args.iter().position(|a| a == f).and_then(|i| args.get(i + 1)).map(|v| v.parse::<f64>())
    };
    let channels = records::JsbsimChannels {
        noisy: true,
        angular_accelerations: flag("--angular-accelerations"),
    };
    let samples = records::jsbsim(Path::new(&args[0]), channels)?.samples;
    let truth = records::read_truth(Path::new(&args[1]))?;
    let t0 = val("--t0").transpose().map_err(|e| e.to_string())?.unwrap_or(f64::NEG_INFINITY);
    let t1 = val("--t1").transpose().map_err(|e| e.to_string())?.unwrap_or(f64::INFINITY);
    let mut cfg = EkfConfig::new(structure);
    if let Some(q) = val("--qscale").transpose().map_err(|e| e.to_string())? {
        for v in cfg.state_process_noise.iter_mut() {
            *v *= q;
        }
    }
    if flag("--coloured") {
        cfg.sigma = SigmaOption::ColouredResiduals;
    }
    let mut ekf = Ekf::new(cfg).map_err(|e| e.to_string())?;
    let start = std::time::Instant::now();
    let mut n = 0;
    for s in samples.iter().filter(|s| s.t_s >= t0 && s.t_s <= t1) {
        ekf.update(s).map_err(|e| format!("t = {}: {e}", s.t_s))?;
        n += 1;
    }
    let el = start.elapsed();
    let rows = records::rows(&structure, ekf.estimates(), &truth);
    println!("{}", records::table(&rows));
    println!(
        "{n} samples in {:.1} ms ({:.0} samples/s); status {}; coloured-residual factor {:.2}",
        el.as_secs_f64() * 1e3,
        n as f64 / el.as_secs_f64(),
        ekf.estimates().status.name(),
        ekf.coloured_residual_factor()
    );
    Ok(())
}
