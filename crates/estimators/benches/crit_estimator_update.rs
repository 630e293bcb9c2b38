//! Per-sample update cost of the recorded-data estimators (issue 5 targets on one core:
//! RLS ≥ 1,000,000 samples/s, i.e. ≤ 1 µs per update; EKF ≥ 100,000 samples/s, ≤ 10 µs).
//! Criterion reports the time per update and, via `Throughput::Elements`, samples per second.
#![allow(missing_docs)] // criterion_group! generates an undocumented `pub fn`.

use aeroident_estimators::ParametricEstimator;
use aeroident_estimators::legacy_kalman::{
    EkfConfig, LongitudinalConstants, LongitudinalEkf, LongitudinalSample, N_PARAMS,
    SigmaCorrection,
};
use aeroident_estimators::legacy_rls::{Rls, RlsConfig};
use aeroident_estimators::regressors::{CoefficientSample, LinearCoefficient};
use criterion::{Criterion, Throughput, black_box, criterion_group, criterion_main};

const N: usize = 1000;

fn coefficient_samples() -> Vec<CoefficientSample> {
    (0..N)
        .map(|k| {
            let t = k as f64 * 0.01;
            let alpha = 0.1 + 0.01 * (1.3 * t).sin();
            let qhat = 1e-3 * (2.1 * t).cos();
            let de = -0.01 + 0.005 * (0.7 * t).sin();
            let v_ratio = 1.0 + 0.03 * (0.2 * t).sin();
            let cm = 0.1 - alpha - 27.0 * qhat - 1.4 * de + 1e-3 * (37.0 * t).sin();
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

fn bench_rls(c: &mut Criterion) {
    let data = coefficient_samples();
    let mut g = c.benchmark_group("rls_update");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("pitch_moment_5_params_1000_samples", |b| {
        b.iter(|| {
            let mut rls = Rls::new(
                LinearCoefficient::PITCH_MOMENT_V,
                RlsConfig { forgetting: 0.999, init_samples: 0 },
            )
            .unwrap();
            for s in &data {
                black_box(rls.update(black_box(s)).unwrap());
            }
        })
    });
    g.finish();
}

fn bench_ekf(c: &mut Criterion) {
    let mass = 7472.0;
    let s = 4.028e-3 * mass;
    let iyy = s * 2.43 / 8.0027e-4;
    let cfg = EkfConfig {
        constants: LongitudinalConstants {
            mass_kg: mass,
            S_m2: s,
            cbar_m: 2.43,
            Iyy_kgm2: iyy,
            thrust_arm_m: -7.0153e-6 * iyy,
            thrust_incidence_rad: 0.0524,
            v0_mps: 104.67,
        },
        theta0: [0.1, -0.05, 0.23, -0.2, 0.36, 3.2, 0.13, -0.01, -1.0, -27.0, -1.4],
        p0_states: [1.0, 1e-4, 1e-4, 1e-4],
        p0_params: [10.0; N_PARAMS],
        q_states: [0.0; 4],
        q_params: 0.0,
        r: [0.01, 1e-6, 1e-6, 1e-6, 3e-5, 4e-4, 0.02],
        sigma: SigmaCorrection::ColouredResiduals,
    };
    let data: Vec<LongitudinalSample> = (0..N)
        .map(|k| {
            let t = k as f64 * 0.1;
            LongitudinalSample {
                t_s: t,
                de_rad: -0.008 + 0.01 * (0.5 * t).sin(),
                thrust_n: 11600.0,
                rho_kgpm3: 0.792,
                y: [
                    Some(106.0 + 0.5 * (0.05 * t).sin()),
                    Some(0.11 + 0.005 * (0.9 * t).sin()),
                    Some(0.105 + 0.01 * (0.3 * t).sin()),
                    Some(0.01 * (0.9 * t).cos()),
                    Some(0.01 * (0.9 * t).sin()),
                    Some(0.9),
                    Some(-9.8),
                ],
            }
        })
        .collect();
    let mut g = c.benchmark_group("ekf_update");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("longitudinal_15_states_7_outputs_1000_samples", |b| {
        b.iter(|| {
            let mut ekf = LongitudinalEkf::new(cfg).unwrap();
            for s in &data {
                // Synthetic data need not fit the model; keep going past numerical refusals.
                let _ = black_box(ekf.update(black_box(s)));
            }
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench_rls, bench_ekf
}
criterion_main!(benches);
