//! Recursive least squares against independent truths: a batch QR solve of the same regression
//! (nalgebra, dynamic matrices), known coefficients under white noise, and Monte Carlo scatter.

use aeroident_estimators::ParametricEstimator;
use aeroident_estimators::legacy_rls::{Rls, RlsConfig};
use aeroident_estimators::regressors::{CoefficientSample, LinearCoefficient};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64Mcg;

/// HFB-320-like regressor ranges: α ≈ 0.1 rad, q̂ ≈ 1e-3, δe ≈ 0.01 rad, V/V0 ≈ 1.03.
fn synthetic(n: usize, theta: &[f64; 5], sigma: f64, rng: &mut Pcg64Mcg) -> Vec<CoefficientSample> {
    let noise = Normal::new(0.0, sigma).unwrap();
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.02;
            let alpha = 0.1 + 0.01 * (1.3 * t).sin() + 0.002 * rng.random::<f64>();
            let qhat = 1e-3 * (2.1 * t).cos() + 2e-4 * rng.random::<f64>();
            let de = -0.01 + 0.01 * (0.7 * t + 0.3).sin().signum() * rng.random::<f64>();
            let v_ratio = 1.03 + 0.03 * (0.2 * t).sin();
            let cm = theta[0]
                + theta[1] * alpha
                + theta[2] * qhat
                + theta[3] * de
                + theta[4] * v_ratio
                + noise.sample(rng);
            CoefficientSample {
                t_s: t,
                alpha_rad: alpha,
                qhat,
                de_rad: de,
                v_ratio,
                Cm: cm,
                CL: 0.0,
                CD: 0.0,
            }
        })
        .collect()
}

const THETA: [f64; 5] = [0.13, -1.0, -27.0, -1.44, -0.014];

fn batch(samples: &[CoefficientSample]) -> (DVector<f64>, DMatrix<f64>) {
    let n = samples.len();
    let x = DMatrix::from_fn(n, 5, |i, j| {
        let s = &samples[i];
        [1.0, s.alpha_rad, s.qhat, s.de_rad, s.v_ratio][j]
    });
    let y = DVector::from_fn(n, |i, _| samples[i].Cm);
    let qr = x.clone().qr();
    let theta = qr.r().solve_upper_triangular(&(qr.q().transpose() * &y)).unwrap();
    let res = &y - &x * &theta;
    let s2 = res.dot(&res) / (n as f64 - 5.0);
    let svd = (x.transpose() * &x).svd(true, true);
    let cov = svd.pseudo_inverse(0.0).unwrap() * s2;
    (theta, cov)
}

#[test]
fn val_batch_qr_rls_without_forgetting_equals_batch_least_squares() {
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    let data = synthetic(2000, &THETA, 0.004, &mut rng);
    let mut rls = Rls::new(LinearCoefficient::PITCH_MOMENT_V, RlsConfig::default()).unwrap();
    for s in &data {
        rls.update(s).unwrap();
    }
    let (theta_b, cov_b) = batch(&data);
    let est = rls.estimate();
    let cov = est.covariance.unwrap();
    for i in 0..5 {
        let rel = (est.theta[i] - theta_b[i]).abs() / theta_b[i].abs();
        assert!(rel < 1e-6, "param {i}: rls {} batch {} rel {rel:e}", est.theta[i], theta_b[i]);
        let rel_s = (cov[(i, i)].sqrt() - cov_b[(i, i)].sqrt()).abs() / cov_b[(i, i)].sqrt();
        assert!(rel_s < 1e-6, "sigma {i}: rel {rel_s:e}");
    }
    assert_eq!(est.t_s, data.last().unwrap().t_s);
}

#[test]
fn analytic_noise_free_rls_recovers_coefficients_exactly() {
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let data = synthetic(300, &THETA, 1e-300, &mut rng);
    let mut rls = Rls::new(LinearCoefficient::PITCH_MOMENT_V, RlsConfig::default()).unwrap();
    for s in &data {
        rls.update(s).unwrap();
    }
    for (i, t) in THETA.iter().enumerate() {
        assert!((rls.estimate().theta[i] - t).abs() < 1e-8 * t.abs().max(1.0), "param {i}");
    }
}

/// Known coefficients + white noise, 400 Monte Carlo runs: the mean estimate is unbiased and the
/// reported standard errors match the scatter of the estimates within 20 %.
#[test]
fn prop_monte_carlo_standard_errors_match_scatter() {
    let runs = 400;
    let mut est = Vec::with_capacity(runs);
    let mut sig = Vec::with_capacity(runs);
    for seed in 0..runs as u64 {
        let mut rng = Pcg64Mcg::seed_from_u64(1000 + seed);
        let data = synthetic(400, &THETA, 0.005, &mut rng);
        let mut rls = Rls::new(LinearCoefficient::PITCH_MOMENT_V, RlsConfig::default()).unwrap();
        for s in &data {
            rls.update(s).unwrap();
        }
        let e = rls.estimate();
        est.push(e.theta);
        sig.push((0..5).map(|i| e.std_error(i).unwrap()).collect::<Vec<_>>());
    }
    for i in 0..5 {
        let mean = est.iter().map(|t| t[i]).sum::<f64>() / runs as f64;
        let sd =
            (est.iter().map(|t| (t[i] - mean).powi(2)).sum::<f64>() / (runs as f64 - 1.0)).sqrt();
        let mean_sigma = sig.iter().map(|s| s[i]).sum::<f64>() / runs as f64;
        let ratio = mean_sigma / sd;
        assert!(
            (0.8..1.2).contains(&ratio),
            "param {i}: reported σ {mean_sigma:e} vs scatter {sd:e}"
        );
        // Unbiased: the mean lies within 4 standard errors of the mean of the truth.
        assert!(
            (mean - THETA[i]).abs() < 4.0 * sd / (runs as f64).sqrt(),
            "param {i} biased: {mean}"
        );
    }
}

#[test]
fn analytic_forgetting_tracks_a_step_change() {
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let mut data = synthetic(3000, &THETA, 1e-4, &mut rng);
    // After sample 1500 Cm_alpha changes from −1.0 to −0.5.
    for s in data.iter_mut().skip(1500) {
        s.Cm += 0.5 * s.alpha_rad;
    }
    let mut forget = Rls::new(
        LinearCoefficient::PITCH_MOMENT_V,
        RlsConfig { forgetting: 0.99, init_samples: 0 },
    )
    .unwrap();
    let mut plain = Rls::new(LinearCoefficient::PITCH_MOMENT_V, RlsConfig::default()).unwrap();
    for s in &data {
        forget.update(s).unwrap();
        plain.update(s).unwrap();
    }
    assert!(
        (forget.estimate().theta[1] + 0.5).abs() < 0.05,
        "forgetting: {}",
        forget.estimate().theta[1]
    );
    assert!((plain.estimate().theta[1] + 0.5).abs() > 0.1, "no forgetting should average");
}

#[test]
fn errors_invalid_forgetting_and_nonfinite_sample_leave_state_unchanged() {
    assert!(
        Rls::new(LinearCoefficient::PITCH_MOMENT, RlsConfig { forgetting: 1.5, init_samples: 0 })
            .is_err()
    );
    assert!(
        Rls::new(LinearCoefficient::PITCH_MOMENT, RlsConfig { forgetting: 0.0, init_samples: 0 })
            .is_err()
    );
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    let data = synthetic(50, &THETA, 0.01, &mut rng);
    let mut rls = Rls::new(LinearCoefficient::PITCH_MOMENT_V, RlsConfig::default()).unwrap();
    for s in &data {
        rls.update(s).unwrap();
    }
    let before = *rls.estimate();
    let mut bad = data[0];
    bad.qhat = f64::NAN;
    assert!(rls.update(&bad).is_err());
    assert_eq!(*rls.estimate(), before);
}
