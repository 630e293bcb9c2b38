//! The sample-timing test end to end, on the JSBSim F-16 aileron and rudder doublets
//! (../shared/flightdata/jsbsim_samples, 60 Hz; skipped with a message when absent, a failure
//! under CI).
//!
//! The reference is an independent path to the same refits: the record replayed twice more
//! through a hand-written `compat.json` that reads the three gyros half a sample late, then
//! early (the compatibility stage a user drives, not the test's own shift). Half the difference
//! of those two runs' estimates is what the skew moves each one; the summary's
//! `timing_std_error` must be that move over √3 (a uniform error over ± the move), and a
//! parameter must carry the "sample timing" flag exactly when the move exceeds 10 % of a
//! significant estimate. On this record least squares' roll damping `Cl_p` is one such. The
//! reported σ is the method's own (output error's coloured-residual σ, as its summary keeps
//! it) with the timing σ and the unmodelled σ, 5.5 % of |estimate|, in quadrature.

use crate::common;
use common::{shared, workspace};
use serde_json::{Value, json};
use std::path::Path;
use std::process::Command;

/// `replay DATA --map jsbsim.toml --model lateral --estimator E ARGS`: the parsed summary.
fn replay(data: &Path, estimator: &str, args: &[&str], name: &str) -> Value {
    let out = std::env::temp_dir().join(format!("aeroident-skew-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("replay")
        .arg(data)
        .arg("--map")
        .arg(workspace().join("mappings/jsbsim.toml"))
        .args(["--model", "lateral", "--estimator", estimator])
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    serde_json::from_str(&text).unwrap()
}

/// The record's sample interval, s: the median interval of its `time` column.
fn interval_s(data: &Path) -> f64 {
    let text = std::fs::read_to_string(data).unwrap();
    let mut rows = text.lines().filter(|l| !l.starts_with('#'));
    let col = rows.next().unwrap().split(',').position(|c| c == "time").unwrap();
    let t: Vec<f64> = rows.map(|l| l.split(',').nth(col).unwrap().parse().unwrap()).collect();
    let mut dt: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    dt.sort_by(f64::total_cmp);
    dt[dt.len() / 2]
}

/// A `compat.json` for `data` reading p, q and r `shift_s` later.
fn gyros_shifted(data: &Path, shift_s: f64, tag: &str) -> std::path::PathBuf {
    let rows: Vec<Value> = ["p_rad_s", "q_rad_s", "r_rad_s"]
        .iter()
        .map(|n| {
            json!({"name": n, "unit": "rad/s", "bias": null, "bias_sigma": null,
            "scale": null, "scale_sigma": null, "time_shift_s": shift_s,
            "time_shift_sigma_s": 1e-9})
        })
        .collect();
    let file = data.file_name().unwrap().to_str().unwrap();
    let path =
        std::env::temp_dir().join(format!("aeroident-skew-{}-{tag}.json", std::process::id()));
    std::fs::write(&path, json!({"file": file, "channels": rows}).to_string()).unwrap();
    path
}

/// Each parameter's estimate, by name.
fn estimates(v: &Value) -> Vec<(String, Option<f64>)> {
    let ps = v["parameters"].as_array().unwrap();
    ps.iter().map(|p| (p["name"].as_str().unwrap().to_string(), p["estimate"].as_f64())).collect()
}

/// The unmodelled σ of a parameter of estimate `value`: 5.5 % of |value| but for a constant
/// term, which has none (docs/output-schema.md).
fn unmodelled_share(p: &Value, value: f64) -> f64 {
    let share = p["unmodelled_std_error"].as_f64();
    if p["name"].as_str().unwrap().ends_with("_0") {
        assert_eq!(share, None, "{p}");
        return 0.0;
    }
    let want = 0.055 * value.abs();
    let share = share.unwrap_or_else(|| panic!("no unmodelled σ: {p}"));
    assert!((share - want).abs() <= 1e-12 * want, "{p}: {share} against {want}");
    share
}

/// A batch fit's noise σ from the key its source names (`coloured_std_error`,
/// `crb_std_error`); `None` for a recursive estimator's covariance, kept nowhere else.
fn noise_of_source(p: &Value) -> Option<f64> {
    match p["std_error_source"].as_str()? {
        "coloured" => p["coloured_std_error"].as_f64(),
        "cramer_rao" => p["crb_std_error"].as_f64(),
        _ => None,
    }
}

/// The run of `estimator` against its refits through `compat.json`: returns the parameters
/// flagged for sample timing.
fn check(data: &Path, estimator: &str) -> Vec<String> {
    let skew = 0.5 * interval_s(data);
    let own = replay(data, estimator, &[], estimator);
    let late_json = gyros_shifted(data, skew, &format!("{estimator}-late"));
    let early_json = gyros_shifted(data, -skew, &format!("{estimator}-early"));
    let late = estimates(&replay(data, estimator, &["--compat", late_json.to_str().unwrap()], "l"));
    let early =
        estimates(&replay(data, estimator, &["--compat", early_json.to_str().unwrap()], "e"));
    let mut flagged = Vec::new();
    for (p, (l, e)) in own["parameters"].as_array().unwrap().iter().zip(late.iter().zip(&early)) {
        let name = p["name"].as_str().unwrap();
        let (Some(value), Some(l), Some(e)) = (p["estimate"].as_f64(), l.1, e.1) else { continue };
        let half = 0.5 * (l - e);
        let timing = p["timing_std_error"].as_f64().unwrap_or_else(|| panic!("{name}: {p}"));
        let want = half.abs() / 3f64.sqrt();
        assert!((timing - want).abs() <= 1e-6 * want + 1e-12, "{name}: {timing} against {want}");
        let sigma = p["std_error"].as_f64().unwrap();
        let unmodelled = unmodelled_share(p, value);
        let noise = (sigma * sigma - timing * timing - unmodelled * unmodelled).max(0.0).sqrt();
        if let Some(own) = noise_of_source(p) {
            let want = own.hypot(timing).hypot(unmodelled);
            assert!((sigma - want).abs() <= 1e-12 * want, "{estimator} {name}: σ {sigma} {want}");
        }
        let texts: Vec<&str> =
            p["flags"].as_array().unwrap().iter().filter_map(Value::as_str).collect();
        let flag = texts.iter().find(|f| f.starts_with("sample timing:"));
        let beyond = half.abs() > 0.1 * value.abs() && value.abs() > 2.0 * noise;
        assert_eq!(
            flag.is_some(),
            beyond,
            "{estimator} {name}: move {half} of {value} ± {noise}: {texts:?}"
        );
        if let Some(f) = flag {
            assert!(f.contains("±8.3 ms (half a sample)"), "{f}");
            flagged.push(name.to_string());
        }
    }
    flagged
}

/// Least squares (online) and output error (batch): every σ and flag as the independent refits
/// say; least squares' roll damping moves by more than 10 % under the skew.
#[test]
fn the_skew_refits_match_refits_through_compat_json() {
    let Some(data) = shared("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv") else { return };
    let rls = check(&data, "rls");
    assert!(rls.contains(&"Cl_p".to_string()), "rls flags {rls:?}");
    check(&data, "oe");
}
