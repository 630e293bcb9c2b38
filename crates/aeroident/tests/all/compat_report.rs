//! `aeroident compat --out DIR` on the HFB-320 record (../shared/flightdata; skipped with a
//! message when absent, a failure under CI): the report's traces are the check's own residuals
//! (their RMS is `compat.json`'s `residual_rms`, formed independently from the variances), and
//! `report.html` carries the figure of every fitted channel and the α-lag finding.

use crate::common;
use aeroident_estimators::compat::CompatConfig;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::compat::{check_record, traces};
use common::{shared, workspace};
use std::process::Command;

#[test]
fn val_compat_report_traces_are_the_residuals_of_the_check() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let map = workspace().join("mappings/hfb320.toml");
    let m = Mapping::from_path(&map).unwrap();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let (summary, result) = check_record(reader, &CompatConfig::default()).unwrap();
    let tr = traces(&result);
    assert_eq!(tr.len(), summary.residual_rms.len());
    for t in &tr {
        let (name, rms) = (t.name.as_str(), summary.residual_rms[t.name.as_str()]);
        assert_eq!((t.stride, t.t_s.len()), (1, 601), "{name}");
        let e: Vec<f64> = t.measured.iter().zip(&t.simulated).map(|(z, y)| z - y).collect();
        let got = (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
        assert!((got / rms - 1.0).abs() < 1e-9, "{name}: {got} vs {rms}");
    }
    let out = std::env::temp_dir().join(format!("aeroident-compat-report-{}", std::process::id()));
    let st = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["compat", &data.display().to_string(), "--map", &map.display().to_string()])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    for name in summary.residual_rms.keys() {
        assert!(
            html.contains(&format!("{name}: measured vs the reconstructed flight path")),
            "{name}"
        );
    }
    assert!(html.contains("alpha_rad lags the kinematics by 0.2"));
    assert!(out.join("compat.json").exists() && out.join("compat.png").exists());
    std::fs::remove_dir_all(&out).ok();
}
