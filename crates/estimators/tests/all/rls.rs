//! Recursive least squares against independent truths: a batch QR solve of the same regression
//! (nalgebra, dynamic matrices), known coefficients under white noise, and Monte Carlo scatter.

use aeroident_estimators::rls::{Rls, RlsConfig};
use aeroident_estimators::{
    AirDataSample, AircraftConstants, Coefficient, Estimator, ModelStructure, Term,
};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64Mcg;

/// One regression row as the air-data sample that produces it: V/V0 from V with V0 = 100 m/s,
/// q from q̂, and q̇ such that the measured Cm = Iyy q̇ / (q̄ S c̄) equals `cm` (no p, r: no
/// inertial coupling).
#[derive(Debug, Clone, Copy)]
struct Row {
    alpha: f64,
    qhat: f64,
    de: f64,
    v_ratio: f64,
    cm: f64,
    t: f64,
}

const QBAR: f64 = 5000.0;
const S: f64 = 30.0;
const CBAR: f64 = 2.0;
const IYY: f64 = 1e5;

fn sample(r: &Row) -> AirDataSample {
    let vt = 100.0 * r.v_ratio;
    AirDataSample {
        t_s: r.t,
        vt_mps: vt,
        alpha_rad: r.alpha,
        qbar_pa: QBAR,
        q_rad_s: Some(r.qhat * 2.0 * vt / CBAR),
        qdot_rad_s2: Some(r.cm * QBAR * S * CBAR / IYY),
        de_rad: Some(r.de),
        constants: AircraftConstants {
            mass_kg: 7000.0,
            S_m2: S,
            cbar_m: Some(CBAR),
            Iyy_kgm2: Some(IYY),
            v0_mps: Some(100.0),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// `Cm = Cm_0 + Cm_alpha α + Cm_q q̂ + Cm_de δe + Cm_V V/V0` (Jategaonkar's HFB-320 form).
fn structure() -> ModelStructure {
    ModelStructure::empty()
        .with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q, Term::De, Term::V])
}

fn value(rls: &Rls, i: usize) -> f64 {
    rls.estimates().value(i).unwrap()
}

/// HFB-320-like regressor ranges: α ≈ 0.1 rad, q̂ ≈ 1e-3, δe ≈ 0.01 rad, V/V0 ≈ 1.03.
fn synthetic(n: usize, theta: &[f64; 5], sigma: f64, rng: &mut Pcg64Mcg) -> Vec<Row> {
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
            Row { alpha, qhat, de, v_ratio, cm, t }
        })
        .collect()
}

const THETA: [f64; 5] = [0.13, -1.0, -27.0, -1.44, -0.014];

fn batch(samples: &[Row]) -> (DVector<f64>, DMatrix<f64>) {
    let n = samples.len();
    let x = DMatrix::from_fn(n, 5, |i, j| {
        let s = &samples[i];
        [1.0, s.alpha, s.qhat, s.de, s.v_ratio][j]
    });
    let y = DVector::from_fn(n, |i, _| samples[i].cm);
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
    let mut rls = Rls::new(structure(), RlsConfig::default()).unwrap();
    for s in &data {
        rls.update(&sample(s)).unwrap();
    }
    let (theta_b, cov_b) = batch(&data);
    for i in 0..5 {
        let v = value(&rls, i);
        let rel = (v - theta_b[i]).abs() / theta_b[i].abs();
        assert!(rel < 1e-6, "param {i}: rls {v} batch {} rel {rel:e}", theta_b[i]);
        let sig = rls.covariance(i, i).unwrap().sqrt();
        assert!((sig - rls.estimates().sigma(i).unwrap()).abs() < 1e-15 * sig.max(1.0));
        let rel_s = (sig - cov_b[(i, i)].sqrt()).abs() / cov_b[(i, i)].sqrt();
        assert!(rel_s < 1e-6, "sigma {i}: rel {rel_s:e}");
    }
    assert_eq!(rls.estimates().t_s, data.last().unwrap().t);
}

#[test]
fn analytic_noise_free_rls_recovers_coefficients_exactly() {
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let data = synthetic(300, &THETA, 1e-300, &mut rng);
    let mut rls = Rls::new(structure(), RlsConfig::default()).unwrap();
    for s in &data {
        rls.update(&sample(s)).unwrap();
    }
    for (i, t) in THETA.iter().enumerate() {
        assert!((value(&rls, i) - t).abs() < 1e-8 * t.abs().max(1.0), "param {i}");
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
        let mut rls = Rls::new(structure(), RlsConfig::default()).unwrap();
        for s in &data {
            rls.update(&sample(s)).unwrap();
        }
        est.push((0..5).map(|i| value(&rls, i)).collect::<Vec<_>>());
        sig.push((0..5).map(|i| rls.estimates().sigma(i).unwrap()).collect::<Vec<_>>());
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
        s.cm += 0.5 * s.alpha;
    }
    let mut forget =
        Rls::new(structure(), RlsConfig { forgetting: 0.99, init_samples: 0 }).unwrap();
    let mut plain = Rls::new(structure(), RlsConfig::default()).unwrap();
    for s in &data {
        forget.update(&sample(s)).unwrap();
        plain.update(&sample(s)).unwrap();
    }
    assert!((value(&forget, 1) + 0.5).abs() < 0.05, "forgetting: {}", value(&forget, 1));
    assert!((value(&plain, 1) + 0.5).abs() > 0.1, "no forgetting should average");
}

#[test]
fn errors_invalid_forgetting_and_nonfinite_sample_leave_state_unchanged() {
    assert!(Rls::new(structure(), RlsConfig { forgetting: 1.5, init_samples: 0 }).is_err());
    assert!(Rls::new(structure(), RlsConfig { forgetting: 0.0, init_samples: 0 }).is_err());
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    let data = synthetic(50, &THETA, 0.01, &mut rng);
    let mut rls = Rls::new(structure(), RlsConfig::default()).unwrap();
    for s in &data {
        rls.update(&sample(s)).unwrap();
    }
    let before = *rls.estimates();
    let mut bad = sample(&data[0]);
    bad.t_s += 10.0;
    bad.q_rad_s = Some(f64::NAN);
    assert!(rls.update(&bad).is_err());
    assert_eq!(*rls.estimates(), before);
}

/// Every estimator keeps the structure it was built for, whatever its size, and has
/// identified nothing before data. Compiled as a dependency at the release profile's
/// opt-level 3, rustc 1.95 once returned a corrupted structure (31–50 parameters for the
/// 12-parameter longitudinal preset) from `Rls::new` when the fits array was built on the
/// stack and moved into the estimator; the unit tests, compiled inside the crate, did not
/// see it. The construction is now in place; this test guards it for RLS, FTR and the EKF.
#[test]
fn every_estimator_keeps_its_structure_after_construction() {
    use aeroident_estimators::{Ekf, EkfConfig, Ftr, FtrConfig};
    for st in
        [ModelStructure::longitudinal(), ModelStructure::lateral(), ModelStructure::six_axis()]
    {
        let n = st.n_params();
        let rls = Rls::new(st, RlsConfig { forgetting: 0.995, init_samples: 0 }).unwrap();
        assert_eq!(*rls.structure(), st, "rls");
        let ftr = Ftr::new(st, FtrConfig::default()).unwrap();
        assert_eq!(*ftr.structure(), st, "ftr");
        let ekf = Ekf::new(EkfConfig::new(st)).unwrap();
        assert_eq!(*ekf.structure(), st, "ekf");
        for e in [&rls as &dyn Estimator, &ftr, &ekf] {
            assert_eq!(e.structure().n_params(), n, "{}", e.method());
            assert!((0..n).all(|i| e.estimates().value(i).is_none()), "{}", e.method());
        }
    }
}
