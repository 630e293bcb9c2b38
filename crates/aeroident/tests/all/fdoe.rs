//! `replay --estimator fdoe` (frequency-domain output error) against the time-domain output
//! error on the same records and models: the target "within 2 combined σ"
//! (`|Δ| ≤ 2 √(σ_fdoe² + σ_oe²)`, each method's reported σ) per shared parameter
//! (docs/fdoe.md has the table). Skip without `../shared`, fail under CI if it is missing.

use crate::common;
use common::workspace;
use std::path::Path;
use std::process::Command;

/// `replay DATA --map MAP --estimator EST ARGS --out DIR` (`MAP` a shipped mapping's name or
/// a path): the parsed `summary.json`.
fn fit(data: &Path, map: &str, estimator: &str, args: &[&str], name: &str) -> serde_json::Value {
    let out = std::env::temp_dir().join(format!("aeroident-fdoe-{}-{name}", std::process::id()));
    // An absolute `map` replaces the directory it is joined to.
    let o = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .arg("replay")
        .arg(data)
        .arg("--map")
        .arg(workspace().join("mappings").join(map))
        .args(["--estimator", estimator])
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let v =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    v
}

/// Per parameter fdoe estimated: `(name, |Δ| / combined σ)` against `oe` (or another fit).
fn combined_sigmas(fd: &serde_json::Value, oe: &serde_json::Value) -> Vec<(String, f64)> {
    let oe_params = oe["parameters"].as_array().unwrap();
    let mut out = Vec::new();
    for p in fd["parameters"].as_array().unwrap() {
        let Some(est) = p["estimate"].as_f64() else {
            assert!(p["std_error"].is_null(), "a null estimate with a σ: {p}");
            continue;
        };
        let o = oe_params.iter().find(|o| o["name"] == p["name"]).unwrap();
        let (s1, s2) = (p["std_error"].as_f64().unwrap(), o["std_error"].as_f64().unwrap());
        let d = (est - o["estimate"].as_f64().unwrap()).abs() / s1.hypot(s2);
        out.push((p["name"].as_str().unwrap().to_string(), d));
    }
    out
}

/// Both fits of one record: fdoe converged, the parameters it cannot see `null`, and the ratios.
fn compare(data: &Path, map: &str, args: &[&str], name: &str) -> Vec<(String, f64)> {
    let oe = fit(data, map, "oe", args, &format!("{name}-oe"));
    let fd = fit(data, map, "fdoe", args, &format!("{name}-fdoe"));
    assert_eq!(oe["status"], "converged", "{name}");
    assert_eq!(fd["status"], "converged", "{name}: {}", fd["status_reason"]);
    assert_eq!(fd["estimator"], "fdoe");
    let f = &fd["frequency_domain"];
    assert_eq!(f["band_hz"], serde_json::json!([0.1, 1.5]));
    let not: Vec<&str> =
        f["not_estimated"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    for n in &not {
        assert!(n.starts_with("CD_") || n.ends_with("_0") || n.ends_with("_V"), "{name}: {n}");
    }
    let ratios = combined_sigmas(&fd, &oe);
    eprintln!("{name}: {ratios:?}");
    ratios
}

/// Twin Otter (SIDPAC 017, 018, 019; the default longitudinal model): every derivative
/// fdoe estimates (`CL_alpha, CL_q, CL_de, Cm_alpha, Cm_q, Cm_de`) within 2 combined σ of
/// output error's. Measured largest ratios 0.63, 0.83, 1.67.
#[test]
fn val_fdoe_agrees_with_output_error_on_the_twin_otter() {
    for rec in ["017", "018", "019"] {
        let Some(data) =
            common::shared(&format!("sidpac_twin_otter/csv/totter_lon_020213f1_{rec}.csv"))
        else {
            return;
        };
        let ratios = compare(&data, "twin_otter.toml", &[], rec);
        assert_eq!(ratios.len(), 6, "{rec}: {ratios:?}");
        for (n, r) in ratios {
            assert!(r <= 2.0, "{rec} {n}: {r:.2} combined σ");
        }
    }
}

/// HFB-320 (the book's model, `models/hfb320_book_q0.toml`): the pitching-moment derivatives
/// agree with output error's within 2 combined σ (measured 0.03, 0.55, 0.45 for Cm_alpha,
/// Cm_de, Cm_q0). CL_alpha is a documented known gap (fdoe 4.28 ± 0.16, oe 3.21 ± 0.19; 4.4
/// combined σ) with a stated cause, and the test checks the cause, not the gap: the
/// time-domain fit weights az by its whole-record residual, which the slow airspeed/attitude
/// model error makes large, so its α channel sets CL_alpha, where the band excludes that slow
/// error and az asks for about 4.3 (docs/fdoe.md). Hence (1) the filter-error method, which
/// models that slow error as process noise, agrees with fdoe within 2 combined σ (measured
/// fem 4.39 ± 0.10, 0.61), and (2) fdoe fitted without az (α, q, q̇ alone) agrees with output
/// error within 2 combined σ (measured 3.48 ± 0.29, 0.78). Either fails if fdoe's CL_alpha
/// moves away from what the physics of the record says, in either direction.
#[test]
fn val_fdoe_on_the_hfb320_agrees_where_the_slow_model_error_is_out_of_the_fit() {
    let Some(data) = common::shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else {
        return;
    };
    let model = workspace().join("models/hfb320_book_q0.toml");
    let args = ["--model", model.to_str().unwrap()];
    let ratios = compare(&data, "hfb320.toml", &args, "hfb320");
    assert_eq!(ratios.len(), 4, "{ratios:?}");
    for (n, r) in ratios.iter().filter(|(n, _)| n != "CL_alpha") {
        assert!(*r <= 2.0, "{n}: {r:.2} combined σ from oe");
    }
    let fd = fit(&data, "hfb320.toml", "fdoe", &args, "hfb320-fdoe-again");
    let fem = fit(&data, "hfb320.toml", "fem", &args, "hfb320-fem");
    assert_eq!(fem["status"], "converged", "{}", fem["status_reason"]);
    let lift = |r: Vec<(String, f64)>| r.into_iter().find(|(n, _)| n == "CL_alpha").unwrap().1;
    let r = lift(combined_sigmas(&fd, &fem));
    assert!(r <= 2.0, "fdoe CL_alpha {r:.2} combined σ from fem's");
    // The same mapping without its az channel: fdoe's outputs are then α, q and q̇ only.
    let text = std::fs::read_to_string(workspace().join("mappings/hfb320.toml")).unwrap();
    let no_az: String =
        text.lines().filter(|l| !l.starts_with("az =")).map(|l| l.to_owned() + "\n").collect();
    let map =
        std::env::temp_dir().join(format!("aeroident-fdoe-{}-no-az.toml", std::process::id()));
    std::fs::write(&map, no_az).unwrap();
    let fd = fit(&data, map.to_str().unwrap(), "fdoe", &args, "hfb320-fdoe-no-az");
    let oe = fit(&data, "hfb320.toml", "oe", &args, "hfb320-oe-again");
    std::fs::remove_file(&map).ok();
    let outputs = &fd["frequency_domain"]["outputs"];
    assert_eq!(outputs, &serde_json::json!(["alpha_rad", "q_rad_s", "qdot_rad_s2"]));
    let r = lift(combined_sigmas(&fd, &oe));
    assert!(r <= 2.0, "fdoe on α, q, q̇: CL_alpha {r:.2} combined σ from oe's");
}

/// A band without frequencies of the record is refused naming it, and `--band-hz` is only for
/// fdoe.
#[test]
fn errors_fdoe_band() {
    let Some(data) = common::shared("sidpac_twin_otter/csv/totter_lon_020213f1_018.csv") else {
        return;
    };
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .arg("replay")
            .arg(&data)
            .arg("--map")
            .arg(workspace().join("mappings/twin_otter.toml"))
            .args(args)
            .output()
            .unwrap()
    };
    let o = run(&["--estimator", "fdoe", "--band-hz", "0.01:0.05"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("no frequency in the band 0.01–0.05 Hz"), "{err}");
    let o = run(&["--estimator", "oe", "--band-hz", "0.1:2"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--band-hz"), "{err}");
    let o = run(&["--estimator", "fdoe", "--band-hz", "2:1"]);
    assert!(!o.status.success());
}

/// A band reaching above the record's Nyquist frequency (25 Hz at 50 Hz) is fitted up to the
/// highest transform frequency below it, and summary.json says so: `band_fitted_hz` holds what
/// was fitted, a warning names the clip. Within the Nyquist frequency the fitted band lies
/// inside the band asked and nothing is warned.
#[test]
fn fdoe_band_above_nyquist_is_recorded_and_warned() {
    let Some(data) = common::shared("sidpac_twin_otter/csv/totter_lon_020213f1_018.csv") else {
        return;
    };
    let rows = std::fs::read_to_string(&data).unwrap().lines().count() - 1;
    // The highest transform bin of one manoeuvre of n samples at 0.02 s: (⌊n/2⌋ − 1)/(n·0.02).
    let top = (rows / 2 - 1) as f64 / (rows as f64 * 0.02);
    let v = fit(&data, "twin_otter.toml", "fdoe", &["--band-hz", "0.5:100"], "nyquist");
    let f = &v["frequency_domain"];
    assert_eq!(f["band_hz"], serde_json::json!([0.5, 100.0]));
    let (lo, hi) =
        (f["band_fitted_hz"][0].as_f64().unwrap(), f["band_fitted_hz"][1].as_f64().unwrap());
    assert!(lo >= 0.5 && (hi - top).abs() < 1e-9 * top && hi < 25.0, "{lo} {hi} vs {top}");
    let warned = v["warnings"].as_array().unwrap().iter().any(|w| {
        let w = w.as_str().unwrap();
        w.contains("--band-hz 0.5:100") && w.contains("Nyquist frequency 25 Hz")
    });
    assert!(warned, "{}", v["warnings"]);
    let v = fit(&data, "twin_otter.toml", "fdoe", &["--band-hz", "0.2:1.5"], "inside");
    let f = &v["frequency_domain"];
    let (lo, hi) =
        (f["band_fitted_hz"][0].as_f64().unwrap(), f["band_fitted_hz"][1].as_f64().unwrap());
    assert!(0.2 <= lo && lo < hi && hi <= 1.5, "{lo} {hi}");
    assert!(!v["warnings"].to_string().contains("Nyquist"), "{}", v["warnings"]);
}

/// A row missing from a uniform record (a spike the screen removed, a row the reader
/// rejected) no longer stops the fit: the Twin Otter record (018) with its row at t = 4 s
/// deleted is fitted by fdoe with the sample bridged (a warning counts it), and every estimate
/// lies within a quarter of its σ of the whole record's (one interpolated sample of 401 moves
/// little). Five rows missing in a row is a gap: the reader splits the record there into two
/// manoeuvres, and nothing is bridged.
#[test]
fn fdoe_bridges_a_missing_row_and_not_a_gap() {
    let Some(data) = common::shared("sidpac_twin_otter/csv/totter_lon_020213f1_018.csv") else {
        return;
    };
    let text = std::fs::read_to_string(&data).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let without = |drop: std::ops::Range<usize>, name: &str| {
        let kept: Vec<&str> =
            lines.iter().enumerate().filter(|(i, _)| !drop.contains(i)).map(|(_, l)| *l).collect();
        let path =
            std::env::temp_dir().join(format!("aeroident-fdoe-{}-{name}.csv", std::process::id()));
        std::fs::write(&path, kept.join("\n") + "\n").unwrap();
        path
    };
    // Line 201 of the file (after its header) is the sample at t = 4.0 s (0.02 s sampling).
    let one = without(201..202, "one");
    let whole = fit(&data, "twin_otter.toml", "fdoe", &[], "whole");
    let bridged = fit(&one, "twin_otter.toml", "fdoe", &[], "bridged");
    let warned = bridged["warnings"].as_array().unwrap().iter().any(|w| {
        let w = w.as_str().unwrap();
        w.starts_with("fdoe: 1 sample(s) missing") && w.contains("t = 4 s")
    });
    assert!(warned, "{}", bridged["warnings"]);
    assert!(!whole["warnings"].to_string().contains("bridged"), "{}", whole["warnings"]);
    let mut compared = 0;
    let pairs = whole["parameters"].as_array().unwrap().iter();
    for (a, b) in pairs.zip(bridged["parameters"].as_array().unwrap()) {
        assert_eq!(a["name"], b["name"]);
        let (Some(x), Some(y), Some(s)) =
            (a["estimate"].as_f64(), b["estimate"].as_f64(), a["std_error"].as_f64())
        else {
            continue;
        };
        assert!((x - y).abs() <= 0.25 * s, "{}: {x} vs {y} (σ {s})", a["name"]);
        compared += 1;
    }
    assert_eq!(compared, 6, "{}", bridged["parameters"]);
    let gap = without(201..206, "gap");
    let split = fit(&gap, "twin_otter.toml", "fdoe", &[], "gap");
    assert!(!split["warnings"].to_string().contains("bridged"), "{}", split["warnings"]);
    assert_eq!(split["status"], "converged", "{}", split["status_reason"]);
    for p in [one, gap] {
        let _ = std::fs::remove_file(p);
    }
}

/// Three Twin Otter records fitted together (`--and`): fdoe tests whether each derivative
/// repeats across them. Each file's value and σ in the test are that file replayed alone (its
/// estimate and Cramér–Rao σ, to 10⁻⁹ of the σ), and the χ² and the verdict are recomputed
/// here from those values: the weighted mean
/// `θ̄ = Σθᵢ/σᵢ² / Σ1/σᵢ²`, `χ² = Σ(θᵢ − θ̄)²/σᵢ²` on `k − 1` dof, repeating at p ≥ 0.01
/// (`χ²₁` 6.635, `χ²₂` 9.210).
#[test]
fn val_fdoe_tests_whether_each_derivative_repeats_across_records() {
    let recs = ["017", "018", "019"];
    let mut paths = Vec::new();
    for rec in recs {
        let Some(p) =
            common::shared(&format!("sidpac_twin_otter/csv/totter_lon_020213f1_{rec}.csv"))
        else {
            return;
        };
        paths.push(p);
    }
    let mut and = Vec::new();
    for p in &paths[1..] {
        and.extend(["--and".to_string(), p.to_str().unwrap().to_string()]);
    }
    let and: Vec<&str> = and.iter().map(String::as_str).collect();
    let joint = fit(&paths[0], "twin_otter.toml", "fdoe", &and, "repeat-joint");
    let alone: Vec<serde_json::Value> = paths
        .iter()
        .zip(recs)
        .map(|(p, rec)| fit(p, "twin_otter.toml", "fdoe", &[], &format!("repeat-{rec}")))
        .collect();
    let rep = &joint["repeatability"];
    let params = rep["parameters"].as_array().expect("a repeatability test");
    assert_eq!(rep["fits"].as_array().unwrap().len(), 3);
    assert!(params.len() >= 4, "{params:?}");
    for q in params {
        let name = q["parameter"].as_str().unwrap();
        let (mut sw, mut swx, mut vals) = (0.0, 0.0, Vec::new());
        for v in q["values"].as_array().unwrap() {
            let k = v["manoeuvre"].as_u64().unwrap() as usize;
            assert_eq!(alone[k]["manoeuvres"], 1, "{}", recs[k]);
            let solo = alone[k]["parameters"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["name"] == name)
                .unwrap();
            let (x, s) = (v["estimate"].as_f64().unwrap(), v["std_error"].as_f64().unwrap());
            // The fit's own σ (fdoe's Cramér–Rao), before the shares the job adds to every
            // method's (sample timing, the unmodelled σ).
            let (x1, s1) =
                (solo["estimate"].as_f64().unwrap(), solo["crb_std_error"].as_f64().unwrap());
            assert!(
                (x - x1).abs() <= 1e-9 * s1 && (s - s1).abs() <= 1e-9 * s1,
                "{name} #{k}: {x} ± {s} vs {x1} ± {s1}"
            );
            sw += 1.0 / (s * s);
            swx += x / (s * s);
            vals.push((x, s));
        }
        let mean = swx / sw;
        let chi2: f64 = vals.iter().map(|(x, s)| ((x - mean) / s).powi(2)).sum();
        assert!((q["chi2"].as_f64().unwrap() - chi2).abs() < 1e-9 * chi2.max(1.0), "{name}");
        let critical = [6.635, 9.210][vals.len() - 2];
        assert_eq!(q["repeats"].as_bool().unwrap(), chi2 < critical, "{name}: χ² {chi2}");
    }
}
