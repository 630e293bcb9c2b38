//! The default scenario's excitation is free of second-order intermodulation on its own lines
//! (docs/uncertainty.md, "Odd-harmonic inputs").
//!
//! The F-16's lateral tables depend on α, which the elevator swings over 0–5°, so the yaw and
//! roll moments carry products such as `Δα·β` and `Δα·δr`. A product of two sinusoids at
//! harmonics `k` and `l` of the base frequency has power at `k ± l`. With the harmonics
//! 2–16 dealt out in turn (elevator 2, 5, 8 …; aileron 3, 6, 9 …; rudder 4, 7, 10 …), `2 + 4`
//! lands on the aileron's 6 and `5 − 2` on its 3: the nonlinearity puts power exactly where the
//! linear model's regressors have theirs, and equation error and output error read it as a
//! bias of the lateral derivatives (FTR Cn_δr +2.3 %, Cl_β −2.7 %, RLS Cn_β −1.2 % of truth in
//! 200 runs). With odd harmonics only, `odd ± odd` is even: every second-order product
//! (squares, cross products of any two inputs, and of the responses, which share the inputs'
//! lines) lies on lines no input excites (the odd multisines of Pintelon & Schoukens,
//! *System Identification: A Frequency Domain Approach*, 2nd ed., Wiley–IEEE 2012).
//!
//! The check is an independent DFT over one base period of the inputs the scenario flies.

use crate::common;

use aeroident_pipelines::aircraft::scenario::Scenario;
use aeroident_signals::InputSignal;
use aeroident_signals::config::InputConfig;

/// |DFT| at harmonic `k` of `x` sampled at `n` points over one base period.
fn dft_abs(x: &[f64], k: usize) -> f64 {
    let n = x.len() as f64;
    let (mut re, mut im) = (0.0, 0.0);
    for (i, v) in x.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * (k * i) as f64 / n;
        re += v * w.cos();
        im -= v * w.sin();
    }
    (re * re + im * im).sqrt() / n
}

/// The base period and the harmonics of every orthogonal multisine input of `sc`.
fn design(sc: &Scenario) -> (f64, Vec<Vec<u32>>) {
    let mut period = None;
    let mut sets = Vec::new();
    for spec in &sc.input {
        let InputConfig::OrthogonalMultisine { base_period_s, harmonics, inputs, index, .. } =
            &spec.signal
        else {
            panic!("the default scenario flies orthogonal multisines only");
        };
        assert!(period.is_none_or(|p| p == *base_period_s), "one base period");
        period = Some(*base_period_s);
        sets.push(aeroident_signals::orthogonal_harmonics(harmonics, *inputs, *index).unwrap());
    }
    (period.unwrap(), sets)
}

/// Largest |DFT| of every product `u_i u_j` (`i ≤ j`) on any excited harmonic, relative to the
/// product's largest |DFT| over all harmonics up to twice the highest excited one.
fn worst_intermodulation(sc: &Scenario) -> f64 {
    let (period, sets) = design(sc);
    let n = 4000;
    let signals: Vec<Vec<f64>> = sc
        .input
        .iter()
        .map(|spec| {
            let u = spec.signal.build().unwrap();
            (0..n).map(|i| u.value(period * i as f64 / n as f64)).collect()
        })
        .collect();
    let excited: Vec<usize> = sets.iter().flatten().map(|&k| k as usize).collect();
    let k_max = 2 * excited.iter().max().unwrap();
    let mut worst: f64 = 0.0;
    for i in 0..signals.len() {
        for j in i..signals.len() {
            let prod: Vec<f64> = signals[i].iter().zip(&signals[j]).map(|(a, b)| a * b).collect();
            let all = (1..=k_max).map(|k| dft_abs(&prod, k)).fold(0.0, f64::max);
            let on = excited.iter().map(|&k| dft_abs(&prod, k)).fold(0.0, f64::max);
            worst = worst.max(on / all);
        }
    }
    worst
}

#[test]
fn default_inputs_put_no_second_order_product_on_an_excited_line() {
    let sc = Scenario::from_toml(aeroident::cli::run::DEFAULT_SCENARIO, "default").unwrap();
    let (_, sets) = design(&sc);
    assert_eq!(sets.len(), 3, "elevator, aileron, rudder");
    for s in &sets {
        assert!(s.iter().all(|k| k % 2 == 1), "odd harmonics only: {s:?}");
    }
    let w = worst_intermodulation(&sc);
    assert!(w < 1e-9, "second-order products on excited lines: {w:e} of their peak");
}

/// The former design (harmonics 2–16 in turn over 10 s) fails the same check: the test can
/// tell the two apart.
#[test]
fn consecutive_harmonics_put_products_on_excited_lines() {
    let old = common::with_former_default_inputs(aeroident::cli::run::DEFAULT_SCENARIO);
    let sc = Scenario::from_toml(&old, "default, harmonics 2-16").unwrap();
    let w = worst_intermodulation(&sc);
    assert!(w > 0.1, "{w}");
}
