//! `aeroident montecarlo` end to end through the binary on the short noisy scenario.

use crate::common;
use common::{NORMAL_1SIGMA, NORMAL_2SIGMA, binomial_range};
use std::process::Command;

fn scenario() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/montecarlo/short.toml").into()
}

/// `--json` prints exactly the document its readers rely on (Python's
/// `montecarlo` returns it): 4 runs, both estimators, every six-axis
/// parameter, a finite positive Cramér–Rao σ for the primary derivatives; the default mode
/// writes `montecarlo.json`, `runs.json` and PNG figures. Each primary derivative's
/// `coverage_2sigma` is the fraction of the runs in `runs.json` whose ±2σ interval covers the
/// truth ([`check_coverage`]).
#[test]
fn montecarlo_four_runs_end_to_end() {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["montecarlo", &scenario(), "--runs", "4", "--json", "--seed", "3"])
        .output()
        .unwrap();
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["runs"], 4);
    assert_eq!((v["status"].as_str(), v["runs_requested"].as_u64()), (Some("complete"), Some(4)));
    let ests = v["estimators"].as_array().unwrap();
    assert_eq!(
        ests.iter().map(|e| e["name"].as_str().unwrap()).collect::<Vec<_>>(),
        ["rls", "ekf"]
    );
    for e in ests {
        let ps = e["parameters"].as_array().unwrap();
        assert_eq!(ps.len(), 30, "six-axis parameters of {}", e["name"]);
        let cm = ps.iter().find(|p| p["name"] == "Cm_alpha").unwrap();
        let crb = cm["crb_std_error"].as_f64().unwrap();
        assert!(crb.is_finite() && crb > 0.0);
        assert!(cm["scatter"].as_f64().unwrap() > 0.0);
    }
    let dir = std::env::temp_dir().join(format!("aeroident_mc_{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["montecarlo", &scenario(), "--runs", "4", "--seed", "3", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("montecarlo.json")).unwrap())
            .unwrap();
    assert_eq!(file["estimators"][0]["runs_ok"], 4);
    assert_eq!(
        file["estimators"][0]["parameters"][0]["bias"], v["estimators"][0]["parameters"][0]["bias"],
        "the same seed gives the same statistics"
    );
    for f in ["runs.json", "coverage.png", "histograms_0_rls.png", "histograms_1_ekf.png"] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("runs.json")).unwrap()).unwrap();
    check_coverage(&v, &runs);
    std::fs::remove_dir_all(&dir).ok();
}

/// `(estimate − truth)/σ` of `estimator`'s parameter `param` in every run of `runs`
/// (`runs.json`); empty unless it is a primary derivative.
fn z_scores(runs: &serde_json::Value, estimator: &str, param: &serde_json::Value) -> Vec<f64> {
    let ok = runs.as_array().unwrap().iter().flat_map(|r| r["outcome"]["Ok"].as_array().unwrap());
    ok.filter(|x| x["name"] == estimator)
        .flat_map(|x| x["params"].as_array().unwrap())
        .filter(|q| q["name"] == *param && q["primary"] == true)
        .map(|q| {
            let f = |k: &str| q[k].as_f64().unwrap();
            (f("estimate") - f("reference")) / f("std_error")
        })
        .collect()
}

/// Per estimator of `doc` (the `--json` document), against the runs of `runs` (`runs.json`,
/// the same seed): each primary derivative's `coverage_2sigma` is the fraction of runs with
/// `|estimate − truth| ≤ 2σ`, and over the 11 primaries × 4 runs the counts within ±1σ and ±2σ
/// lie in the 99.9 % range of Binomial(44, 0.683) and Binomial(44, 0.954): 19–39 and 36–44 (the
/// primaries taken as independent). That is what 4 runs support: a σ doubled (≈ 42 within
/// ±1σ) or halved (≈ 30 within ±2σ) fails. Over 40 runs of this scenario RLS and the EKF cover
/// 92 % at ±2σ.
fn check_coverage(doc: &serde_json::Value, runs: &serde_json::Value) {
    for e in doc["estimators"].as_array().unwrap() {
        let name = e["name"].as_str().unwrap();
        let (mut in1, mut in2, mut n) = (0, 0, 0);
        for p in e["parameters"].as_array().unwrap() {
            let z = z_scores(runs, name, &p["name"]);
            if z.is_empty() {
                continue;
            }
            let covered = z.iter().filter(|z| z.abs() <= 2.0).count();
            let fraction = covered as f64 / z.len() as f64;
            assert_eq!(
                p["coverage_2sigma"].as_f64(),
                Some(fraction),
                "{name} {}: {z:?}",
                p["name"]
            );
            in1 += z.iter().filter(|z| z.abs() <= 1.0).count();
            (in2, n) = (in2 + covered, n + z.len());
        }
        assert_eq!(n, 44, "{name}: 11 primaries × 4 runs");
        for (count, p) in [(in1, NORMAL_1SIGMA), (in2, NORMAL_2SIGMA)] {
            let (lo, hi) = binomial_range(n, p);
            assert!((lo..=hi).contains(&count), "{name}: {count} of {n} covered, nominal {p}");
        }
    }
}

/// `--runs 0` is refused with a message naming the option.
#[test]
fn montecarlo_zero_runs_is_an_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["montecarlo", &scenario(), "--runs", "0", "--json"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--runs"));
}

/// SIGINT during `--runs 10000` (the documented maximum, tens of minutes): no further run
/// starts, the runs under way finish, and `montecarlo.json`, `runs.json` and the report are
/// written over the runs done, status `interrupted` with their count; exit 130.
#[cfg(unix)]
#[test]
fn montecarlo_sigint_writes_the_runs_done_marked_interrupted() {
    let dir = std::env::temp_dir().join(format!("aeroident_mc_int_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let child = Command::new(env!("CARGO_BIN_EXE_aeroident"))
        .args(["montecarlo", &scenario(), "--runs", "10000", "--no-figures", "--out"])
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(4));
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let sent = std::time::Instant::now();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(sent.elapsed() < std::time::Duration::from_secs(30), "{:?}", sent.elapsed());
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("montecarlo.json")).unwrap())
            .unwrap();
    assert_eq!(file["status"], "interrupted", "{file}");
    assert_eq!(file["runs_requested"], 10_000);
    let done = file["runs"].as_u64().unwrap();
    assert!((1..10_000).contains(&done), "{done} runs done");
    let reason = format!("stopped on request after {done} of 10000 runs");
    assert!(file["status_reason"].as_str().unwrap().contains(&reason), "{file}");
    assert!(String::from_utf8_lossy(&out.stdout).contains(&reason));
    let ok = file["estimators"][0]["runs_ok"].as_u64().unwrap();
    assert!(ok >= 1 && ok <= done, "statistics over {ok} of the {done} runs done");
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("runs.json")).unwrap()).unwrap();
    assert_eq!(runs.as_array().unwrap().len() as u64, done);
    assert!(dir.join("report.html").is_file());
    std::fs::remove_dir_all(&dir).ok();
}

/// A campaign whose every run fails at trim (60 ft/s, far below any trim), or whose runs give no
/// estimate (a run of one step), writes its empty statistics with a
/// status saying so and exits 1; once both exited 0 with status `complete`.
#[test]
fn montecarlo_without_any_estimate_is_not_complete() {
    let text = std::fs::read_to_string(scenario()).unwrap();
    let dir = std::env::temp_dir().join(format!("aeroident_mc_fail_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (tag, from, to, status, says) in [
        (
            "trim",
            "vt_fps = 675.0",
            "vt_fps = 60.0",
            "failed",
            "every one of the 2 runs failed (run 0",
        ),
        (
            "dt",
            "duration_s = 10.0",
            "duration_s = 0.01",
            "no_estimates",
            "none of the 2 runs gave an estimate",
        ),
    ] {
        assert!(text.contains(from), "short.toml changed: no `{from}`");
        let path = dir.join(format!("{tag}.toml"));
        std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_aeroident"))
            .args(["montecarlo"])
            .arg(&path)
            .args(["--runs", "2", "--json"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{tag}: {stderr}");
        assert!(stderr.contains(&format!("{status}: {says}")), "{tag}: {stderr}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["status"], status, "{tag}: {v}");
        assert!(v["status_reason"].as_str().unwrap().contains(says), "{tag}: {v}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
