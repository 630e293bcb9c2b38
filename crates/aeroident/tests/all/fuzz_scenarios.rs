//! Fuzzing of the scenario parsers (a scenario is text a user wrote, so no input may panic): the
//! aircraft scenario (`Scenario::from_toml`), the proof-of-concept scenario
//! (`PocScenario::from_str_at`) and the F-16 simulation scenario (`sim::parse_scenario`), on
//! arbitrary text and on mutated shipped files: never a panic, and every error names the file.
//! Bounded for CI by `PROPTEST_CASES` (default 64).

use aeroident_pipelines::aircraft::scenario::Scenario;
use aeroident_pipelines::poc::PocScenario;
use aeroident_pipelines::sim::parse_scenario;
use proptest::prelude::*;
use std::path::Path;

#[path = "../../../io/tests/all/common/mutate.rs"]
mod mutate;
use mutate::mutate;

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

const FILE: &str = "fuzz-target.input";

const SEEDS: [&str; 5] = [
    include_str!("../../../../scenarios/default.toml"),
    include_str!("../../../../scenarios/f16/combined.toml"),
    include_str!("../../../../scenarios/f16/x_damage_step.toml"),
    include_str!("../../../../scenarios/poc/t4_1_case1.toml"),
    include_str!("../../../../scenarios/sim/gust_and_turbulence.toml"),
];

/// Parses `text` with all three parsers; fails the case if an error does not name the file.
fn check(text: &str) -> Result<(), TestCaseError> {
    if let Err(e) = Scenario::from_toml(text, FILE) {
        prop_assert!(e.to_string().contains(FILE), "aircraft: {}", e);
    }
    if let Err(e) = PocScenario::from_str_at(text, Path::new(FILE)) {
        prop_assert!(e.to_string().contains(FILE), "poc: {}", e);
    }
    if let Err(e) = parse_scenario(text, Path::new(FILE)) {
        prop_assert!(format!("{e:#}").contains(FILE), "sim: {:#}", e);
    }
    Ok(())
}

fn edits() -> impl Strategy<Value = Vec<(usize, u8, String)>> {
    let text = prop_oneof![
        r#"[\[\]{}="',.#\n a-z0-9_-]{0,6}"#,
        prop::sample::select(vec![
            "nan",
            "inf",
            "-inf",
            "1e308",
            "-1",
            "0",
            "\"\"",
            "[[",
            "]]",
            "\"../../x\"",
            "true",
            "{}",
            "[]",
            "1e-320",
            "18446744073709551615",
        ])
        .prop_map(str::to_string),
        any::<String>(),
    ];
    prop::collection::vec((any::<usize>(), any::<u8>(), text), 1..6)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn fuzz_scenarios_arbitrary(text in any::<String>()) {
        check(&text)?;
    }

    #[test]
    fn fuzz_scenarios_mutated(seed in 0..SEEDS.len(), e in edits()) {
        check(&mutate(SEEDS[seed], &e))?;
    }
}

/// Each seed parses with its own parser (else the mutations would only fuzz error paths).
#[test]
fn seeds_parse() {
    for s in &SEEDS[..3] {
        Scenario::from_toml(s, "seed").unwrap();
    }
    PocScenario::from_str_at(SEEDS[3], Path::new("seed")).unwrap();
    parse_scenario(SEEDS[4], Path::new("seed")).unwrap();
}
