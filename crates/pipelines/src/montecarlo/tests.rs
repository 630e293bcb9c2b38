use super::*;
use aeroident_io::ParameterResult;

fn prun(
    name: &str,
    truth: f64,
    fin: Option<f64>,
    sigma: Option<f64>,
    t10: Option<f64>,
) -> ParamRun {
    ParamRun {
        result: ParameterResult::new(name, fin, sigma, Some(truth), None),
        primary: true,
        truth_before: Some(truth),
        truth_after: Some(truth),
        time_to_10pct_s: t10,
        reconvergence_10pct_s: None,
    }
}

fn result(
    index: u64,
    fin: Option<f64>,
    sigma: Option<f64>,
    t10: Option<f64>,
    fail: Option<&str>,
) -> RunResult {
    RunResult {
        index,
        sensor_seed: index,
        outcome: Ok(vec![EstimatorRun {
            failure: fail.map(Into::into),
            params: vec![prun("Cm_alpha", -1.0, fin, sigma, t10)],
            ..EstimatorRun::named("rls")
        }]),
    }
}

/// Bias, scatter, mean σ, coverage and median worked by hand: finals −0.9, −1.1, −1.3, −0.5
/// (truth −1), σ 0.1, 0.1, 0.1, 0.2 → mean −0.95, bias 0.05; deviations 0.05, −0.15, −0.35,
/// 0.45 → Σd² = 0.0025 + 0.0225 + 0.1225 + 0.2025 = 0.35, scatter √(0.35/3); |err| ≤ 2σ for
/// 0.1 ≤ 0.2 yes, 0.1 yes, 0.3 no, 0.5 no (0.4) → 2/4. One diverged run (value 100) and one
/// failed experiment are listed and not averaged in. Times 1, 2, never, 3 → median of
/// {1, 2, 3, ∞} = 2.5.
#[test]
fn statistics_by_hand() {
    let runs = vec![
        result(0, Some(-0.9), Some(0.1), Some(1.0), None),
        result(1, Some(-1.1), Some(0.1), Some(2.0), None),
        result(2, Some(100.0), Some(0.1), None, Some("t = 3 s: estimator diverged")),
        result(3, Some(-1.3), Some(0.1), None, None),
        RunResult { index: 4, sensor_seed: 4, outcome: Err("trim failed".into()) },
        result(5, Some(-0.5), Some(0.2), Some(3.0), None),
    ];
    let mut crb = CrbTable::default();
    crb.sigma.entry("rls".into()).or_default().insert("Cm_alpha".into(), 0.07);
    crb.calm.entry("rls".into()).or_default().insert("Cm_alpha".into(), 0.03);
    let st = statistics(&runs, &["rls".into()], &crb);
    let e = &st[0];
    assert_eq!(e.runs_ok, 4);
    assert_eq!(e.failed_runs.iter().map(|f| f.run).collect::<Vec<_>>(), vec![2, 4]);
    let p = &e.parameters[0];
    assert!((p.bias.unwrap() - 0.05).abs() < 1e-12);
    assert!((p.scatter.unwrap() - (0.35f64 / 3.0).sqrt()).abs() < 1e-12);
    assert!((p.mean_std_error.unwrap() - 0.125).abs() < 1e-12);
    assert_eq!(p.coverage_2sigma, Some(0.5));
    assert_eq!(p.crb_std_error, Some(0.07));
    assert_eq!(p.crb_std_error_calm, Some(0.03));
    assert_eq!(p.median_time_to_10pct_s, Some(2.5));
    assert_eq!(p.n_estimates, 4);
    assert!(e.restarted_runs.is_empty());
}

/// A run whose estimator restarted from its priors and ran to the end is listed in
/// `restarted_runs` and kept in the statistics; a restarted run that then diverged is a
/// failure only.
#[test]
fn restarted_runs_are_counted_apart_and_used() {
    let restarted = |mut r: RunResult| {
        if let Ok(e) = &mut r.outcome {
            e[0].restarts = 1;
        }
        r
    };
    let runs = vec![
        result(0, Some(-0.9), Some(0.1), Some(1.0), None),
        restarted(result(1, Some(-1.1), Some(0.1), Some(2.0), None)),
        restarted(result(2, Some(100.0), Some(0.1), None, Some("t = 3 s: diverged"))),
    ];
    let st = statistics(&runs, &["rls".into()], &CrbTable::default());
    assert_eq!(st[0].restarted_runs, vec![1]);
    assert_eq!(st[0].runs_ok, 2);
    assert_eq!(st[0].failed_runs.iter().map(|f| f.run).collect::<Vec<_>>(), vec![2]);
    assert!((st[0].parameters[0].bias.unwrap() - 0.0).abs() < 1e-12);
}

/// Without σ the coverage is null; a run without an estimate does not cover; a median that
/// falls on "never" is null.
#[test]
fn statistics_nulls() {
    let runs =
        vec![result(0, Some(-1.0), None, None, None), result(1, Some(-1.2), None, Some(1.0), None)];
    let st = statistics(&runs, &["rls".into()], &CrbTable::default());
    let p = &st[0].parameters[0];
    assert_eq!(p.coverage_2sigma, None);
    assert_eq!(p.mean_std_error, None);
    assert_eq!(p.crb_std_error, None);
    assert_eq!(p.median_time_to_10pct_s, None);
    let runs =
        vec![result(0, Some(-1.0), Some(0.1), None, None), result(1, None, None, None, None)];
    let st = statistics(&runs, &["rls".into()], &CrbTable::default());
    assert_eq!(st[0].parameters[0].coverage_2sigma, Some(0.5));
    assert_eq!(st[0].parameters[0].n_estimates, 1);
    // All runs failed: no parameters, every run listed.
    let runs = vec![RunResult { index: 0, sensor_seed: 0, outcome: Err("x".into()) }];
    let st = statistics(&runs, &["rls".into()], &CrbTable::default());
    assert!(st[0].parameters.is_empty());
    assert_eq!(st[0].failed_runs.len(), 1);
}

/// SplitMix64's published first outputs for state 0 (the generator adds the golden ratio before
/// mixing): 0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4 (reference C implementation, Vigna).
#[test]
fn splitmix_reference_values() {
    assert_eq!(splitmix64(GOLDEN), 0xE220_A839_7B1D_CDAF);
    assert_eq!(splitmix64(GOLDEN.wrapping_mul(2)), 0x6E78_9E6A_A1B9_65F4);
}

/// Seeds differ between runs, streams and campaigns, and follow the stated rule.
#[test]
fn seed_rule() {
    let mut seen = std::collections::BTreeSet::new();
    for s in [0u64, 1, 42] {
        for i in 0..50 {
            for stream in 0..3 {
                assert!(seen.insert(run_seed(s, i, stream)));
            }
        }
    }
    assert_eq!(
        run_seed(7, 3, 2),
        splitmix64(7u64.wrapping_add(GOLDEN.wrapping_mul(1 + 64 * 3 + 2)))
    );
}

fn short_scenario() -> Scenario {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/montecarlo/short.toml");
    Scenario::from_path(std::path::Path::new(path)).unwrap()
}

/// The seeded scenario sets the sensor and the turbulence seeds of the rule and nothing else.
#[test]
fn seeded_scenario_sets_seeds() {
    let sc = short_scenario();
    let s = seeded_scenario(&sc, 9, 4);
    assert_eq!(s.sensors.seed, run_seed(9, 4, 0));
    match &s.wind[0] {
        WindConfig::Dryden { seed, .. } => assert_eq!(*seed, run_seed(9, 4, 1)),
        other => panic!("expected Dryden, got {other:?}"),
    }
    let mut back = s.clone();
    back.sensors.seed = sc.sensors.seed;
    back.wind = sc.wind.clone();
    assert_eq!(back, sc);
}

/// Per-run results are bit-identical on 1 and 2 threads, and differ between runs (the noise
/// is really reseeded).
#[test]
fn runs_identical_across_thread_counts() {
    let sc = short_scenario();
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let a = pool(1).install(|| run_range(&sc, 11, 0..3)).unwrap();
    let b = pool(2).install(|| run_range(&sc, 11, 0..3)).unwrap();
    assert_eq!(a, b);
    let fin = |r: &RunResult| -> Vec<Option<u64>> {
        r.outcome.as_ref().unwrap()[0].params.iter().map(|p| p.estimate.map(f64::to_bits)).collect()
    };
    assert!(fin(&a[0]).iter().any(Option::is_some));
    assert_ne!(fin(&a[0]), fin(&a[1]));
}

/// The scenario's Dryden entry becomes shaping filters in SI whose variance is the MIL-F-8785C
/// intensity (`∫₀^∞ |H|²/π dω = σ²`: for the first-order u filter `c² b² / (2a)`), converted
/// from ft/s; the bound of the flown experiment differs from the calm one with turbulence and
/// is the calm one without.
#[test]
fn turbulent_and_calm_bounds() {
    use aeroident_signals::turbulence::DrydenParameters;
    let sc = short_scenario();
    let g = gust_model(&sc).unwrap().expect("short.toml has Dryden turbulence");
    let WindConfig::Dryden { severity: Some(sev), altitude_ft: Some(h), .. } = sc.wind[0] else {
        panic!("expected a Dryden preset");
    };
    let p = DrydenParameters::mil_f_8785c(h, sev).unwrap();
    let f = &g.filters[0];
    let var = (f.c[0] * f.b[0]).powi(2) / (2.0 * -f.a[(0, 0)]);
    assert!((var.sqrt() / (p.sigma_u_fps * M_PER_FT) - 1.0).abs() < 1e-12);
    let crb = crb_sigmas(&sc).unwrap();
    let (label, flown) = crb.sigma.iter().next().expect("a bound");
    let calm = &crb.calm[label];
    let differ = flown.iter().filter(|(k, v)| (*v / calm[*k] - 1.0).abs() > 0.01).count();
    assert!(differ > flown.len() / 2, "turbulence must change most bounds: {flown:?} {calm:?}");
    assert!(crb.notes.iter().any(|n| n.contains("Dryden turbulence as process noise")));
    let mut still = sc.clone();
    still.wind.clear();
    let crb = crb_sigmas(&still).unwrap();
    assert_eq!(crb.sigma, crb.calm);
    assert!(crb.notes.iter().any(|n| n.contains("no Dryden turbulence")));
}

/// The `--json` document has exactly its keys (plus `crb_std_error_calm` and
/// `schema_version`): Python's `montecarlo` and every other reader of it rely on them.
#[test]
fn json_keys_exact() {
    let runs = vec![result(0, Some(-0.9), Some(0.1), Some(1.0), None)];
    let c = Campaign {
        schema_version: aeroident_io::SCHEMA_VERSION,
        scenario: "x".into(),
        runs: 1,
        runs_requested: 1,
        status: "complete",
        status_reason: None,
        seed: 1,
        seed_rule: SEED_RULE,
        failed_runs: vec![],
        estimators: statistics(&runs, &["rls".into()], &CrbTable::default()),
        crb_notes: vec![],
        wall_s: 0.0,
        threads: 1,
        results: runs,
    };
    let v = json_summary(&c);
    let keys = |v: &serde_json::Value| {
        let mut k = v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
        k.sort_unstable();
        k
    };
    assert_eq!(
        keys(&v),
        ["estimators", "runs", "runs_requested", "schema_version", "status", "status_reason"]
    );
    assert_eq!(v["schema_version"], 3);
    assert_eq!((v["status"].as_str(), v["runs_requested"].as_u64()), (Some("complete"), Some(1)));
    let e = &v["estimators"][0];
    assert_eq!(keys(e), ["name", "parameters"]);
    let mut want = vec![
        "name",
        "reference",
        "bias",
        "scatter",
        "mean_std_error",
        "coverage_2sigma",
        "crb_std_error",
        "crb_std_error_calm",
        "median_time_to_10pct_s",
    ];
    want.sort_unstable();
    assert_eq!(keys(&e["parameters"][0]), want);
    assert_eq!(v["runs"], 1);
    assert!(e["parameters"][0]["crb_std_error"].is_null());
}

/// A campaign's run count is checked before any run or allocation: 0 and more than
/// [`MAX_RUNS`] are refused with the option named (`u64::MAX` once overflowed the results'
/// capacity), [`MAX_RUNS`] itself is accepted; a chunk of a distributed campaign is held to the
/// same limit wherever it starts, and an empty (or reversed) chunk is no error.
#[test]
fn run_counts_are_limited_before_allocating() {
    let sc = short_scenario();
    for runs in [MAX_RUNS + 1, 1_000_000_000_000, u64::MAX] {
        let Err(e) = campaign(&sc, runs, 1) else { panic!("{runs} runs accepted") };
        assert!(e.starts_with(&format!("runs = {runs} is more than the {MAX_RUNS}")), "{e}");
        let e = check_runs(runs, "--runs").unwrap_err();
        assert!(e.starts_with("--runs = "), "{e}");
    }
    assert_eq!(campaign(&sc, 0, 1).err().as_deref(), Some("runs must be at least 1"));
    assert_eq!(check_runs(MAX_RUNS, "runs"), Ok(()));
    assert_eq!(check_runs(1, "runs"), Ok(()));
    let e = run_range(&sc, 1, 5..5 + MAX_RUNS + 1).unwrap_err();
    assert!(e.contains(&format!("{}", MAX_RUNS + 1)), "{e}");
    let (start, stop) = (7, 3);
    assert_eq!(run_range(&sc, 1, start..stop), Ok(Vec::new()));
}

/// `run_result_from_json` inverts the serialisation exactly (the distributed reduce), accepts
/// the keys older versions lack, and names a bad or missing key by its path.
#[test]
fn run_results_round_trip_through_json() {
    let mut ok = result(3, Some(-0.9), Some(0.1), Some(1.0), None);
    if let Ok(e) = &mut ok.outcome {
        e[0].restarts = 2;
        e[0].iterations = Some(7);
        e[0].fit_wall_s = Some(0.25);
        e[0].sigma_candidates = vec![("crb".into(), vec![0.1])];
        e[0].bootstrap_failed = Some(1);
        e[0].bootstrap_bias = Some(vec![1e-3]);
    }
    let failed = RunResult { index: 4, sensor_seed: 9, outcome: Err("trim failed".into()) };
    for r in [ok, failed, result(5, None, None, None, Some("diverged"))] {
        let v = serde_json::to_value(&r).unwrap();
        assert_eq!(run_result_from_json(&v).unwrap(), r);
    }
    let mut v = serde_json::to_value(result(0, Some(-1.0), None, None, None)).unwrap();
    let e = &mut v["outcome"]["Ok"][0];
    for k in ["restarts", "sigma_candidates", "bootstrap_failed", "bootstrap_bias"] {
        e.as_object_mut().unwrap().remove(k);
    }
    assert_eq!(run_result_from_json(&v).unwrap(), result(0, Some(-1.0), None, None, None));
    v["outcome"]["Ok"][0]["params"][0]["estimate"] = "x".into();
    assert_eq!(
        run_result_from_json(&v).unwrap_err(),
        "per-run result: `outcome.Ok[0].params[0]`: `estimate`: invalid type: string \"x\", expected f64"
    );
    v["outcome"]["Ok"][0]["params"][0]["estimate"] = (-1.0).into();
    v["outcome"]["Ok"][0].as_object_mut().unwrap().remove("name");
    let e = run_result_from_json(&v).unwrap_err();
    assert!(e.contains("`outcome.Ok[0]`") && e.contains("missing field `name`"), "{e}");
    // A nullable key left out is refused too (serde alone would read it as null): a result
    // of schema 1, whose parameters had `final` for `estimate`, is not a run with nothing.
    let mut old = serde_json::to_value(result(0, Some(-1.0), None, None, None)).unwrap();
    let p = old["outcome"]["Ok"][0]["params"][0].as_object_mut().unwrap();
    let estimate = p.remove("estimate").unwrap();
    p.insert("final".into(), estimate);
    let e = run_result_from_json(&old).unwrap_err();
    assert_eq!(e, "per-run result: `outcome.Ok[0].params[0]`: missing field `estimate`");
    old["outcome"]["Ok"][0].as_object_mut().unwrap().remove("failure");
    let e = run_result_from_json(&old).unwrap_err();
    assert_eq!(e, "per-run result: `outcome.Ok[0]`: missing field `failure`");
}

/// The campaign's derived views: error % of |truth|, scatter over the CRB, the final estimates
/// of the good runs, the primary derivatives and the coverage series.
#[test]
fn campaign_views() {
    let runs = vec![
        result(0, Some(-0.9), Some(0.1), Some(1.0), None),
        result(1, Some(100.0), Some(0.1), None, Some("diverged")),
        RunResult { index: 2, sensor_seed: 2, outcome: Err("trim failed".into()) },
        result(3, Some(-1.3), Some(0.1), None, None),
    ];
    let mut crb = CrbTable::default();
    crb.sigma.entry("rls".into()).or_default().insert("Cm_alpha".into(), 0.1);
    let estimators = statistics(&runs, &["rls".into()], &crb);
    let p = estimators[0].parameters[0].clone();
    assert!((p.bias_percent_of_truth().unwrap() - 100.0 * -0.1).abs() < 1e-9);
    assert!((p.scatter_over_crb().unwrap() - p.scatter.unwrap() / 0.1).abs() < 1e-12);
    assert_eq!(p.truth_or_zero(), Some(-1.0));
    let zero = ParamStats { reference: Some(1e-15), ..p.clone() };
    assert_eq!((zero.truth_or_zero(), zero.bias_percent_of_truth()), (Some(0.0), None));
    assert!(!estimators[0].is_batch());
    let c = Campaign {
        schema_version: aeroident_io::SCHEMA_VERSION,
        scenario: "s".into(),
        runs: 4,
        runs_requested: 4,
        status: "complete",
        status_reason: None,
        seed: 1,
        seed_rule: SEED_RULE,
        failed_runs: Vec::new(),
        estimators,
        crb_notes: Vec::new(),
        wall_s: 0.0,
        threads: 1,
        results: runs,
    };
    assert_eq!(c.final_estimates("rls", "Cm_alpha"), vec![-0.9, -1.3]);
    assert!(c.final_estimates("ekf", "Cm_alpha").is_empty());
    assert!(
        c.final_estimates("rls", "Cm_nope").is_empty(),
        "an unknown parameter is not the first one"
    );
    assert_eq!(c.primary_parameters(), vec!["Cm_alpha".to_string()]);
    assert_eq!(
        c.coverage_by_estimator(&["Cm_alpha".into(), "Cm_q".into()]),
        vec![("rls".to_string(), vec![p.coverage_2sigma, None])]
    );
}

/// `campaign_watched` tells its watcher once per run ended, from whichever worker ran it, and a
/// campaign stopped before its start runs nothing and tells nothing.
#[test]
fn the_watcher_hears_each_run_once() {
    use std::sync::atomic::{AtomicBool, AtomicU64};
    let sc = short_scenario();
    let done = AtomicU64::new(0);
    let c = campaign_watched(&sc, 3, 5, None, &|| {
        done.fetch_add(1, Ordering::SeqCst);
    })
    .unwrap();
    assert_eq!((done.load(Ordering::SeqCst), c.runs), (3, 3));
    let stop = AtomicBool::new(true);
    let done = AtomicU64::new(0);
    let c = campaign_watched(&sc, 3, 5, Some(&stop), &|| {
        done.fetch_add(1, Ordering::SeqCst);
    })
    .unwrap();
    assert_eq!((done.load(Ordering::SeqCst), c.runs), (0, 0));
}
