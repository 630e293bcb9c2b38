use super::*;
use crate::rls::{CoefficientFit, Fit};
use crate::vocabulary::{Coefficient, ModelStructure, N_TERMS, Term};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// A two-term fit `y = θ₁ x₁ + θ₂ x₂ + σ v` at 100 Hz (`x` and `v` white unit Gaussian),
/// forgetting `λ`, with `θ₁` stepping from `a` to `b` at `t_step_s`; optionally with the change
/// test of `config`. Returns, per sample, `θ̂₁` (NaN before the initialisation) and the alarm
/// times.
#[allow(clippy::too_many_arguments)]
fn step_run(
    seed: u64,
    seconds: f64,
    sigma: f64,
    (a, b, t_step_s): (f64, f64, f64),
    lambda: f64,
    config: Option<ChangeConfig>,
) -> (std::vec::Vec<f64>, std::vec::Vec<f64>) {
    let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Alpha, Term::Q]);
    let mut fit = Fit::new(&st, Coefficient::Cm);
    if let Some(c) = config {
        fit.enable_change_test(c, c.threshold(1, 2));
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let n01 = Normal::new(0.0, 1.0).unwrap();
    let (mut est, mut alarms) = (std::vec::Vec::new(), std::vec::Vec::new());
    let n = (seconds * 100.0) as usize;
    for i in 0..n {
        let t = i as f64 * 0.01;
        let mut phi = [0.0; N_TERMS];
        phi[0] = n01.sample(&mut rng);
        phi[1] = n01.sample(&mut rng);
        let th1 = if t < t_step_s { a } else { b };
        let y = th1 * phi[0] - 1.3 * phi[1] + sigma * n01.sample(&mut rng);
        fit.update(&phi, y, lambda, 0, t).unwrap();
        if fit.take_change().is_some() {
            alarms.push(t);
        }
        est.push(if fit.initialised() { fit.theta()[0] } else { f64::NAN });
    }
    (est, alarms)
}

/// Time after `t_step_s` from which `est` (one per 0.01 s) stays within ±10 % of `b`.
fn back_within_10pct(est: &[f64], b: f64, t_step_s: f64) -> Option<f64> {
    let k0 = (t_step_s * 100.0).round() as usize;
    // NaN (not identified) counts as outside the band.
    let inside = |v: f64| (v - b).abs() <= 0.1 * b.abs();
    let last_out = (k0..est.len()).rev().find(|&k| !inside(est[k]))?;
    Some((last_out + 1 - k0) as f64 * 0.01)
}

/// A step of `θ₁` from 1 to 3 in unit residual noise (`x` unit white): each post-step sample
/// adds `E[(2x)²] = 4` to the window's non-centrality, against the threshold
/// `χ²₂(1 − α) = 2 ln(1/α) = 19.1` (`α = 0.25/3600`): about 5 post-step samples cross it, so
/// the alarm comes at the end of the window holding the step or of the next (≤ 0.5 s). The
/// memory re-opened on the window then holds the post-step samples at full weight and the old
/// memory at 2 %: `θ̂₁` has σ ≈ 1/√n after `n` post-step samples and is back within ±10 %
/// (±0.3, 2σ at n = 44) in well under a second. Without the test the 2-s memory needs
/// `2 e^{−t/τ} < 0.3`, `t > τ ln(6.7) = 3.8 s` (analytic).
#[test]
fn step_is_detected_within_two_windows_and_the_estimate_returns_within_a_second() {
    let lambda = 0.995;
    let step = (1.0, 3.0, 20.0);
    for seed in 0..10 {
        let (est, alarms) = step_run(seed, 30.0, 1.0, step, lambda, Some(ChangeConfig::default()));
        assert!(alarms.iter().all(|&t| t >= 20.0), "seed {seed}: false alarm {alarms:?}");
        let first = *alarms.first().expect("the step raises an alarm");
        let back = back_within_10pct(&est, 3.0, 20.0).unwrap();
        std::println!(
            "seed {seed}: alarm {:.2} s after the step, back within 10 % after {back:.2} s",
            first - 20.0
        );
        assert!(first - 20.0 <= 0.5 + 1e-9, "seed {seed}: alarm at {first}");
        assert!(back < 1.0, "seed {seed}: back within 10 % after {back} s");
        let (plain, none) = step_run(seed, 30.0, 1.0, step, lambda, None);
        assert!(none.is_empty());
        let slow = back_within_10pct(&plain, 3.0, 20.0).unwrap();
        let tau = 0.01 / (1.0 - lambda);
        let analytic = tau * (2.0f64 / 0.3).ln();
        // Noise can only delay the last exit from the band beyond the memory's decay, much.
        assert!(slow > analytic - 0.5, "seed {seed}: without the test {slow} s vs {analytic}");
    }
}

/// Stationary white residuals through the RLS recursion (σ̂² from its own 2-s memory, the
/// a-priori residuals): no change, so every alarm is false. Designed for one false alarm per
/// 25 s (`α = 0.25/25 = 0.01` per window, the 99 % point of χ²₂), the count over the tested
/// windows must not exceed `α` per window by more than 3 binomial σ (the design's promise),
/// and must reach half of it (a test that never fires would pass the first check). Measured:
/// 0.66 of the design (180 of 273.5), conservative; the cause is not established (within-window
/// adaptation of θ̂ lowers the score's variance by only ≈ W/(2N) = 6 %).
#[test]
fn white_residuals_false_alarm_rate_matches_the_design() {
    let config = ChangeConfig { false_alarm_interval_s: 25.0, ..ChangeConfig::default() };
    let alpha = config.alpha(1);
    assert!((alpha - 0.01).abs() < 1e-15);
    let seconds = 7200.0;
    let (_, alarms) = step_run(3, seconds, 1.0, (0.7, 0.7, f64::INFINITY), 0.995, Some(config));
    // Tested time: the flight less the rest after the initialisation and after each alarm.
    let tested = seconds - config.holdoff_s * (alarms.len() + 1) as f64;
    let windows = tested / config.block_s;
    let expected = windows * alpha;
    let count = alarms.len() as f64;
    std::println!("{count} false alarms in {windows:.0} windows, expected {expected:.1}");
    let sd = (expected * (1.0 - alpha)).sqrt();
    assert!(count <= expected + 3.0 * sd, "{count} false alarms, design {expected:.1}");
    assert!(count >= 0.5 * expected, "{count} false alarms: deaf (design {expected:.1})");
}

/// The χ² tail against printed tables (Abramowitz & Stegun table 26.8: the 95 % points
/// 3.841, 5.991, 11.070, 15.507 of 1, 2, 5, 8 degrees of freedom; the 99.9 % point 20.515 of
/// 5), and the quantile inverting it.
#[test]
fn chi2_tail_matches_tables() {
    for (k, x, p) in [
        (1, 3.841, 0.05),
        (2, 5.991, 0.05),
        (5, 11.070, 0.05),
        (8, 15.507, 0.05),
        (5, 20.515, 0.001),
    ] {
        let q = chi2_upper_tail(k, x);
        assert!((q / p - 1.0).abs() < 2e-3, "χ²_{k} > {x}: {q} vs {p}");
        let xq = chi2_upper_quantile(k, p);
        assert!((xq - x).abs() < 2e-3 * x, "quantile {k} {p}: {xq} vs {x}");
    }
}

#[test]
fn threshold_and_config_checks() {
    let c = ChangeConfig::default();
    // α = W_s / (T E): one hour, six equations, 0.25-s windows.
    assert!((c.alpha(6) - 0.25 / (3600.0 * 6.0)).abs() < 1e-18);
    assert!((chi2_upper_tail(8, c.threshold(6, 8)) / c.alpha(6) - 1.0).abs() < 1e-6);
    assert!(c.validated().is_ok());
    let bad = ChangeConfig { memory_kept: 0.0, ..c }.validated().unwrap_err();
    assert!(matches!(bad, EstimatorError::InvalidConfig { field: "change_memory_kept", .. }));
    let bad = ChangeConfig { block_s: -1.0, ..c }.validated().unwrap_err();
    assert!(matches!(bad, EstimatorError::InvalidConfig { field: "change_block_s", .. }));
}
