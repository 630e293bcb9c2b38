//! The augmented-state EKF against a known truth: data simulated in this test (its own RK4 of
//! the Jategaonkar 2015 eq. 5.86–5.89 model, finer step than the filter) with known parameters
//! and white measurement noise.

use aeroident_estimators::ParametricEstimator;
use aeroident_estimators::legacy_kalman::{
    EkfConfig, G0_MPS2, LongitudinalConstants, LongitudinalEkf, LongitudinalSample, N_PARAMS,
    PARAM_NAMES, SigmaCorrection,
};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64Mcg;

/// HFB-320 constants of `xdot_TC04_hfb_lon.m` (README of the record).
fn hfb_constants() -> LongitudinalConstants {
    let mass = 7472.0;
    let s = 4.028e-3 * mass;
    let cbar = 2.0 * 1.215;
    let iyy = s * cbar / 8.0027e-4;
    LongitudinalConstants {
        mass_kg: mass,
        S_m2: s,
        cbar_m: cbar,
        Iyy_kgm2: iyy,
        thrust_arm_m: -7.0153e-6 * iyy,
        thrust_incidence_rad: 0.0524,
        v0_mps: 104.67,
    }
}

/// "Truth": the published-reproduction OEM values of the HFB-320 README.
const TRUTH: [f64; N_PARAMS] =
    [0.1178, -0.0518, 0.2349, -0.2045, 0.3634, 3.212, 0.1344, -0.0139, -1.002, -27.06, -1.437];
/// Book starting values (`mDefCase04.m`), deliberately poor.
#[allow(clippy::approx_constant)] // CL_0 = −0.318 is the book's number, not 1/π.
const START: [f64; N_PARAMS] =
    [0.00568, 0.00773, 0.674, -0.318, 0.260, 5.376, 0.0498, 0.0189, -0.499, -25.84, -0.991];

fn deriv(c: &LongitudinalConstants, x: [f64; 4], de: f64, t: f64, rho: f64) -> [f64; 4] {
    let [v, al, th, q] = x;
    let p = &TRUTH;
    let qbar = 0.5 * rho * v * v;
    let vr = v / c.v0_mps;
    let cd = p[0] + p[1] * vr + p[2] * al;
    let cl = p[3] + p[4] * vr + p[5] * al;
    let cm = p[6] + p[7] * vr + p[8] * al + p[9] * q * c.cbar_m / (2.0 * v) + p[10] * de;
    let m = c.mass_kg;
    [
        -qbar * c.S_m2 * cd / m
            + t * (al + c.thrust_incidence_rad).cos() / m
            + G0_MPS2 * (al - th).sin(),
        -qbar * c.S_m2 * cl / (m * v) - t * (al + c.thrust_incidence_rad).sin() / (m * v)
            + q
            + G0_MPS2 * (al - th).cos() / v,
        q,
        qbar * c.S_m2 * c.cbar_m * cm / c.Iyy_kgm2 + c.thrust_arm_m * t / c.Iyy_kgm2,
    ]
}

fn elevator(t: f64) -> f64 {
    // 3-2-1-1 of ±0.01 rad around −0.008 rad starting at 2 s (unit 1 s), then a pulse at 30 s.
    let base = -0.008;
    let a = 0.01;
    match t {
        t if (2.0..5.0).contains(&t) => base + a,
        t if (5.0..7.0).contains(&t) => base - a,
        t if (7.0..8.0).contains(&t) => base + a,
        t if (8.0..9.0).contains(&t) => base - a,
        t if (30.0..32.0).contains(&t) => base - a,
        _ => base,
    }
}

#[test]
fn val_known_truth_ekf_recovers_parameters_within_3_sigma() {
    let c = hfb_constants();
    let rho = 0.792;
    let thrust = 11600.0;
    let mut rng = Pcg64Mcg::seed_from_u64(42);
    let sig = [0.1, 1e-3, 1e-3, 1e-3, 5e-3, 0.02, 0.1];
    let noise: Vec<Normal<f64>> = sig.iter().map(|s| Normal::new(0.0, *s).unwrap()).collect();
    let cfg = EkfConfig {
        constants: c,
        theta0: START,
        p0_states: [1.0, 1e-4, 1e-4, 1e-4],
        p0_params: [10.0; N_PARAMS],
        q_states: [0.0; 4],
        q_params: 0.0,
        r: sig.map(|s| s * s),
        sigma: SigmaCorrection::Filter,
    };
    let mut ekf = LongitudinalEkf::new(cfg).unwrap();
    // Trim-like initial state.
    let mut x = [106.0, 0.1117, 0.1049, 0.0];
    let h = 0.01;
    for k in 0..=600 {
        let t = k as f64 * 0.1;
        let de = elevator(t);
        let xd = deriv(&c, x, de, thrust, rho);
        let clean = [x[0], x[1], x[2], x[3], xd[3], 0.0, 0.0];
        let mut y = [None; 7];
        for i in 0..5 {
            y[i] = Some(clean[i] + noise[i].sample(&mut rng));
        }
        let s = LongitudinalSample { t_s: t, de_rad: de, thrust_n: thrust, rho_kgpm3: rho, y };
        ekf.update(&s).unwrap();
        // Propagate the truth to the next sample. The sampled elevator is a ramp between
        // samples (a rate-limited actuator), which the filter's linear input interpolation
        // (Jategaonkar's `ruku4_aug.m`) represents exactly.
        let de_next = elevator(t + 0.1);
        let de_at = |tau: f64| de + (de_next - de) * tau / 0.1;
        for j in 0..10 {
            let tau = j as f64 * h;
            let add = |x: [f64; 4], k: [f64; 4], f: f64| {
                [x[0] + f * k[0], x[1] + f * k[1], x[2] + f * k[2], x[3] + f * k[3]]
            };
            let k1 = deriv(&c, x, de_at(tau), thrust, rho);
            let k2 = deriv(&c, add(x, k1, h / 2.0), de_at(tau + h / 2.0), thrust, rho);
            let k3 = deriv(&c, add(x, k2, h / 2.0), de_at(tau + h / 2.0), thrust, rho);
            let k4 = deriv(&c, add(x, k3, h), de_at(tau + h), thrust, rho);
            for i in 0..4 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
    }
    let e = ekf.estimate();
    for (i, name) in PARAM_NAMES.iter().enumerate() {
        let s = e.std_error(i).unwrap();
        let err = e.theta[i] - TRUTH[i];
        // The well-determined short-period derivatives must be within 3σ and 10 %.
        if ["Cm_alpha", "Cm_q", "Cm_de", "CL_alpha"].contains(name) {
            assert!(err.abs() < 3.0 * s, "{name}: {} ± {s} vs truth {}", e.theta[i], TRUTH[i]);
            assert!(
                err.abs() < 0.1 * TRUTH[i].abs(),
                "{name}: {} vs truth {}",
                e.theta[i],
                TRUTH[i]
            );
        }
        // Every parameter: not wildly overconfident (within 5σ).
        assert!(err.abs() < 5.0 * s, "{name}: {} ± {s} vs truth {}", e.theta[i], TRUTH[i]);
    }
    let p = e.covariance.unwrap();
    assert!((p - p.transpose()).abs().max() < 1e-12 * p.abs().max());
}

#[test]
fn errors_bad_config_and_input() {
    let mut cfg = EkfConfig {
        constants: hfb_constants(),
        theta0: START,
        p0_states: [1.0; 4],
        p0_params: [1.0; N_PARAMS],
        q_states: [0.0; 4],
        q_params: 0.0,
        r: [1.0; 7],
        sigma: SigmaCorrection::Filter,
    };
    cfg.constants.mass_kg = -1.0;
    assert!(LongitudinalEkf::new(cfg).is_err());
    cfg.constants = hfb_constants();
    cfg.r[3] = 0.0;
    assert!(LongitudinalEkf::new(cfg).is_err());
    cfg.r[3] = 1.0;
    let mut ekf = LongitudinalEkf::new(cfg).unwrap();
    let mut s = LongitudinalSample {
        t_s: 0.0,
        de_rad: 0.0,
        thrust_n: 0.0,
        rho_kgpm3: 1.0,
        y: [Some(100.0), Some(0.1), Some(0.1), Some(0.0), None, None, None],
    };
    ekf.update(&s).unwrap();
    s.t_s = 0.0;
    assert!(ekf.update(&s).is_err(), "repeated time must be an error");
    s.t_s = 0.1;
    s.y[1] = Some(f64::NAN);
    assert!(ekf.update(&s).is_err());
}
