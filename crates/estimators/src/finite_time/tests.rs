use super::*;
use crate::estimator::Status;
use crate::rls::{Rls, RlsConfig};
use crate::sample::AircraftConstants;
use crate::vocabulary::Term;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

fn constants() -> AircraftConstants {
    AircraftConstants {
        mass_kg: 1000.0,
        S_m2: 10.0,
        cbar_m: Some(1.5),
        b_m: Some(10.0),
        Ixx_kgm2: Some(1000.0),
        Iyy_kgm2: Some(2000.0),
        Izz_kgm2: Some(2800.0),
        Ixz_kgm2: Some(0.0),
        ..Default::default()
    }
}

/// A pitch sample at `t` whose measured Cm is `cm0 + cma α + cmq q̂ + cmde δe + noise`
/// (`q̇` from the moment equation with `r = p = 0`).
fn pitch_sample(t: f64, theta: [f64; 4], noise: f64) -> AirDataSample {
    let (qbar, v) = (3000.0, 60.0);
    let alpha = 0.05 + 0.02 * (1.3 * t).sin() + 0.01 * (3.7 * t).sin();
    let q = 0.1 * (2.1 * t).cos();
    let de = 0.03 * (0.7 * t + 0.4).sin() + 0.01 * (5.3 * t).cos();
    let qhat = q * 1.5 / (2.0 * v);
    let cm = theta[0] + theta[1] * alpha + theta[2] * qhat + theta[3] * de + noise;
    AirDataSample {
        t_s: t,
        vt_mps: v,
        alpha_rad: alpha,
        qbar_pa: qbar,
        q_rad_s: Some(q),
        qdot_rad_s2: Some(cm * qbar * 10.0 * 1.5 / 2000.0),
        de_rad: Some(de),
        constants: constants(),
        ..Default::default()
    }
}

fn pitch() -> ModelStructure {
    ModelStructure::empty().with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De])
}

const TRUTH: [f64; 4] = [0.02, -0.8, -12.0, -1.1];

/// Noise-free samples of a known linear model: the estimate is the exact solution (to
/// rounding), and nothing is identified before the memory is determined.
#[test]
fn analytic_recovers_exact_linear_model() {
    let mut e = FiniteTimeSmpe::new(pitch(), FiniteTimeConfig::default()).unwrap();
    for i in 0..300 {
        let out = e.update(&pitch_sample(i as f64 * 0.02, TRUTH, 0.0)).unwrap();
        if i == 0 {
            assert!(out.value(0).is_none());
            assert_eq!(out.status, Status::Initialising);
        }
    }
    let out = e.estimates();
    assert_eq!(out.status, Status::Running);
    for (k, w) in TRUTH.iter().enumerate() {
        let got = out.value(k).unwrap();
        assert!((got - w).abs() < 1e-8 * (1.0 + w.abs()), "{k}: {got} vs {w}");
    }
}

/// With the memory held fixed, the distance to the surface follows the discrete reaching law
/// `d⁺ = max(0, (1 − qΔt) d − εΔt)` step by step, and reaches 0 within one step of the
/// continuous law's finite time `ln(1 + q d₀/ε)/q`.
#[test]
fn analytic_reaching_law_reaches_the_surface_in_finite_time() {
    let cfg = FiniteTimeConfig {
        sliding_gain_per_s: 40.0,
        reaching_rate_per_s: 2.0,
        ..Default::default()
    };
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let n01 = Normal::new(0.0, 1e-3).unwrap();
    let mut e = FiniteTimeSmpe::new(pitch(), cfg).unwrap();
    for i in 0..500 {
        e.update(&pitch_sample(i as f64 * 0.01, TRUTH, n01.sample(&mut rng))).unwrap();
    }
    let f = e.fits[Coefficient::Cm.index()].as_mut().unwrap();
    let sigma = f.memory.residual_variance().unwrap().sqrt();
    // Push the estimate 30 standard errors off along a fixed direction.
    let dir = [1.0, -2.0, 30.0, 0.5];
    let mut a_norm2 = 0.0;
    for i in 0..4 {
        for j in 0..4 {
            a_norm2 += dir[i] * f.info[i][j] * dir[j];
        }
    }
    let scale = 30.0 * sigma / a_norm2.sqrt();
    for i in 0..4 {
        f.theta[i] = f.memory.theta()[i] + scale * dir[i];
    }
    let (q, eps, dt) = (2.0, 40.0 * sigma, 0.01);
    let d0 = 30.0 * sigma;
    let mut d = d0;
    let mut steps = 0;
    while d > 0.0 {
        f.slide(dt);
        d = ((1.0 - q * dt) * d - eps * dt).max(0.0);
        let mut got = 0.0;
        for i in 0..4 {
            for j in 0..4 {
                got += f.offset[i] * f.info[i][j] * f.offset[j];
            }
        }
        assert!((got.sqrt() - d).abs() < 1e-9 * d0, "step {steps}: {} vs {d}", got.sqrt());
        steps += 1;
        assert!(steps < 10_000);
    }
    let t_finite = (1.0 + q * d0 / eps).ln() / q;
    assert!((steps as f64 * dt - t_finite).abs() <= 2.0 * dt, "{steps} steps vs {t_finite} s");
    // On the surface the estimate is the memory's solution.
    for i in 0..4 {
        assert_eq!(f.theta[i], f.memory.theta()[i]);
    }
}

/// One noisy record with a 30 % step in Cm_alpha at 10 s, through the estimator and RLS with
/// the same forgetting: (time the sliding estimate is back within 10 % of the new value, the
/// same for RLS, whether the final ±2σ interval covers the truth, final distance to the
/// surface in standard errors).
fn step_run(seed: u64, cfg: FiniteTimeConfig) -> (f64, f64, bool, f64) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let n01 = Normal::new(0.0, 2e-3).unwrap();
    let mut e = FiniteTimeSmpe::new(pitch(), cfg).unwrap();
    let mut rls =
        Rls::new(pitch(), RlsConfig { forgetting: cfg.forgetting, init_samples: 0 }).unwrap();
    let after = [TRUTH[0], 0.7 * TRUTH[1], TRUTH[2], TRUTH[3]];
    let (mut back_e, mut back_r) = (f64::NAN, f64::NAN);
    for i in 0..2000 {
        let t = i as f64 * 0.01;
        let th = if t < 10.0 { TRUTH } else { after };
        let s = pitch_sample(t, th, n01.sample(&mut rng));
        let ve = e.update(&s).unwrap().value(1);
        let vr = rls.update(&s).unwrap().value(1);
        let within =
            |v: Option<f64>| v.is_some_and(|v| (v - after[1]).abs() <= 0.1 * after[1].abs());
        if t >= 10.0 {
            if !within(ve) {
                back_e = f64::NAN;
            } else if back_e.is_nan() {
                back_e = t - 10.0;
            }
            if !within(vr) {
                back_r = f64::NAN;
            } else if back_r.is_nan() {
                back_r = t - 10.0;
            }
        }
    }
    let out = e.estimates();
    let (v, s) = (out.value(1).unwrap(), out.sigma(1).unwrap());
    let d = e.distance_to_surface(Coefficient::Cm).unwrap();
    (back_e, back_r, (v - after[1]).abs() <= 2.0 * s, d)
}

/// After a change the estimate follows the memory's solution: back within 10 % no earlier than
/// RLS on the same memory (it tracks that solution, it cannot be more accurate) and at most
/// a second later; its ±2σ covers the truth in ≥ 90 % of 100 runs. In stationary noise the
/// memory's solution jitters by `≈ √(p(1 − λ))` = 0.2 standard errors per sample in a random
/// direction while the law closes `qΔt d + γΔt` = 0.1 d + 0.1 per sample: the estimate stays
/// within about one standard error of the surface (mean distance < 1).
#[test]
fn tracks_a_change_no_faster_than_the_memory_and_covers() {
    let cfg = FiniteTimeConfig { forgetting: 0.99, ..Default::default() };
    let (mut covered, mut dist) = (0, 0.0);
    for seed in 0..100 {
        let (te, tr, cov, eq) = step_run(seed, cfg);
        assert!(te.is_finite() && tr.is_finite(), "seed {seed}: not back ({te}, {tr})");
        assert!(te >= tr - 1e-9, "seed {seed}: sliding {te} s before the memory's {tr} s");
        assert!(te <= tr + 1.0, "seed {seed}: sliding {te} s vs memory {tr} s");
        covered += usize::from(cov);
        dist += eq / 100.0;
    }
    std::println!("coverage {covered} %, mean distance to the surface {dist:.2}");
    assert!(covered >= 90, "coverage {covered} %");
    assert!(dist > 0.0 && dist < 1.0, "mean distance to the surface {dist}");
}

/// A slow law (γ = q = 0.5/s) lags the memory after the change, and σ counts the distance
/// still to slide: the interval stays honest while the estimate is off.
#[test]
fn a_slow_law_lags_and_its_sigma_counts_the_lag() {
    let cfg = FiniteTimeConfig {
        forgetting: 0.99,
        sliding_gain_per_s: 0.5,
        reaching_rate_per_s: 0.5,
        ..Default::default()
    };
    let (te, tr, cov, _) = step_run(7, cfg);
    assert!(te.is_nan() || te > tr + 1.0, "slow law back at {te} s, memory {tr} s");
    assert!(cov, "σ does not count the lag");
}

#[test]
fn refuses_bad_time_config_and_missing_channels_without_changing_state() {
    let mut e = FiniteTimeSmpe::new(pitch(), FiniteTimeConfig::default()).unwrap();
    e.update(&pitch_sample(1.0, TRUTH, 0.0)).unwrap();
    let before = *e.estimates();
    assert!(e.update(&pitch_sample(1.0, TRUTH, 0.0)).is_err());
    let missing = AirDataSample { t_s: 2.0, vt_mps: 50.0, qbar_pa: 1000.0, ..Default::default() };
    assert!(e.update(&missing).is_err());
    assert_eq!(*e.estimates(), before);
    e.update(&pitch_sample(1.01, TRUTH, 0.0)).unwrap();
    let bad = FiniteTimeConfig { sliding_gain_per_s: -1.0, ..Default::default() };
    assert!(FiniteTimeSmpe::new(pitch(), bad).is_err());
    let bad = FiniteTimeConfig { reaching_rate_per_s: f64::NAN, ..Default::default() };
    assert!(FiniteTimeSmpe::new(pitch(), bad).is_err());
    let bad = FiniteTimeConfig { forgetting: 1.5, ..Default::default() };
    assert!(FiniteTimeSmpe::new(pitch(), bad).is_err());
}
