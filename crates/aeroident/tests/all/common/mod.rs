//! Helpers shared by the integration tests (the test binary's module `common`; not every test
//! module uses every helper).
#![allow(dead_code)]

pub mod browser;
pub mod live;

use std::path::PathBuf;

/// The keys every per-parameter entry of a `summary.json` has (schema version 3,
/// docs/output-schema.md), written out here as the schema states them.
pub const PARAMETER_KEYS: [&str; 13] = [
    "name",
    "estimate",
    "std_error",
    "std_error_source",
    "crb_std_error",
    "timing_std_error",
    "unmodelled_std_error",
    "reference",
    "reference_check",
    "status",
    "flags",
    "notes",
    "combines",
];

/// The workspace root.
pub fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The record at `../shared/flightdata/<rel>` beside the workspace root, or `None` with a
/// SKIPPED message when the shared data are absent. Under CI (`CI=true`) a missing record is a
/// failure: CI always has `../shared`, so a skip there would hide a broken path.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = workspace().join("../shared/flightdata").join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "{} is absent under CI",
        p.display()
    );
    eprintln!("SKIPPED: {} is absent (CI provides ../shared beside the repository)", p.display());
    None
}

/// Two-sided 99.9 % range of a Binomial(n, p) count: the largest `lo` with P(X < lo) ≤ 0.0005
/// and the smallest `hi` with P(X > hi) ≤ 0.0005, by summing the exact probabilities
/// (Binomial(44, 0.9545): 36–44; Binomial(44, 0.6827): 19–39).
pub fn binomial_range(n: usize, p: f64) -> (usize, usize) {
    let mut pmf = vec![(1.0 - p).powi(n as i32)];
    for k in 1..=n {
        let prev = pmf[k - 1];
        pmf.push(prev * (n - k + 1) as f64 / k as f64 * p / (1.0 - p));
    }
    let (mut lo, mut below) = (0, 0.0);
    while below + pmf[lo] <= 0.0005 {
        below += pmf[lo];
        lo += 1;
    }
    let (mut hi, mut above) = (n, 0.0);
    while above + pmf[hi] <= 0.0005 {
        above += pmf[hi];
        hi -= 1;
    }
    (lo, hi)
}

/// The normal mass within ±1 and ±2 standard deviations: the nominal coverage of honest ±1σ
/// and ±2σ intervals.
pub const NORMAL_1SIGMA: f64 = 0.682_689;
pub const NORMAL_2SIGMA: f64 = 0.954_500;

/// `text` (a scenario) with the default scenario's orthogonal multisines put back to the
/// former design: base period 10 s, harmonics 2–16 dealt out in turn, instead of the odd
/// harmonics 5–31 over 20 s (docs/uncertainty.md, "Odd-harmonic inputs"). The campaign runs
/// that the regression tests re-create were found on the former design.
///
/// # Panics
/// When `text` does not hold the current design's three inputs.
pub fn with_former_default_inputs(text: &str) -> String {
    let now =
        "base_period_s = 20.0\nharmonics = [5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31]";
    let former =
        "base_period_s = 10.0\nharmonics = [2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]";
    assert_eq!(text.matches(now).count(), 3, "the default's three odd-harmonic inputs");
    text.replace(now, former)
}

/// `mappings/aeroident-sim.toml` pointed at the simulated sensors' columns (`meas_…`) of α, the
/// accelerometers, q, p, θ and φ, without the sideslip vane: the degraded records of the
/// compatibility tests (`scenarios/sim/degraded_compat.toml`).
pub fn sim_measured_without_beta() -> String {
    let shipped = std::fs::read_to_string(workspace().join("mappings/aeroident-sim.toml")).unwrap();
    let mut text: String =
        shipped.lines().filter(|l| !l.starts_with("beta =")).collect::<Vec<_>>().join("\n");
    for c in ["alpha_air_rad", "ax_fps2", "az_fps2", "q_rad_s", "p_rad_s", "theta_rad", "phi_rad"] {
        text = text.replace(&format!("column = \"{c}\""), &format!("column = \"meas_{c}\""));
    }
    text
}
