//! Wall time of one complete batch output-error fit (target: the HFB-320 book case,
//! 11 parameters, 7 outputs, 601 samples, ≤ 1 s on one core including the noise-covariance
//! relaxation and the coloured-residual σ). Uses the record in `shared/flightdata` when
//! present, else a synthetic problem of the same size (the book's model simulated with a
//! 3-2-1-1 elevator input and deterministic pseudo-noise).
#![allow(missing_docs)] // criterion_group! generates an undocumented `pub fn`.

#[path = "../tests/all/common/records.rs"]
mod records;

use aeroident_estimators::AirDataSample;
use aeroident_estimators::flight_model::{FlightModel, ModelInputs};
use aeroident_estimators::output_error::{OeConfig, fit};
use criterion::{Criterion, black_box, criterion_group, criterion_main};

/// The book's model with parameters near its published fit, 601 samples at 10 Hz.
fn synthetic() -> Vec<AirDataSample> {
    let st = records::hfb320_structure();
    let model = FlightModel::new(st).unwrap();
    // Structure order: CL (0, alpha, V), CD (0, alpha, V), Cm (0, alpha, de, V, q0).
    let th =
        [-0.2045, 3.212, 0.3634, 0.1178, 0.2349, -0.0518, 0.1344, -1.002, -1.437, -0.0139, -27.06];
    let k = records::hfb320_constants();
    let de = |t: f64| {
        let steps = [(2.0, 3.0, -0.01), (5.0, 2.0, 0.01), (7.0, 1.0, -0.01), (8.0, 1.0, 0.01)];
        -0.008 + steps.iter().find(|(t0, w, _)| t >= *t0 && t < t0 + w).map_or(0.0, |s| s.2)
    };
    let sample = |t: f64, x: &[f64; 4]| AirDataSample {
        t_s: t,
        vt_mps: x[0],
        alpha_rad: x[1],
        qbar_pa: 0.5 * 0.792 * x[0] * x[0],
        theta_rad: Some(x[2]),
        q_rad_s: Some(x[3]),
        qdot_rad_s2: Some(0.0),
        ax_mps2: Some(0.0),
        az_mps2: Some(0.0),
        de_rad: Some(de(t)),
        thrust_n: Some(11_600.0),
        rho_kgpm3: Some(0.792),
        constants: k,
        ..Default::default()
    };
    let mut x = [106.0, 0.112, 0.105, 0.0];
    let mut out = Vec::new();
    let z8 = [0.0; 8];
    let noise = |i: usize, j: usize| ((i * 7 + j * 13) as f64 * 1.618).sin();
    for i in 0..601 {
        let t = i as f64 * 0.1;
        let u0 = model.inputs(&sample(t, &x)).unwrap();
        let d = model.eval(&th, &u0, &model.full_state(&x, &u0), &z8, &z8, None).unwrap();
        let mut s = sample(t, &x);
        s.vt_mps += 0.5 * noise(i, 0);
        s.alpha_rad += 0.002 * noise(i, 1);
        s.theta_rad = Some(x[2] + 0.01 * noise(i, 2));
        s.q_rad_s = Some(x[3] + 0.0025 * noise(i, 3));
        s.qdot_rad_s2 = Some(d.xdot[4] + 0.008 * noise(i, 4));
        s.ax_mps2 = Some(d.accel[0] + 0.025 * noise(i, 5));
        s.az_mps2 = Some(d.accel[2] + 0.2 * noise(i, 6));
        out.push(s);
        let u1 = model.inputs(&sample((i + 1) as f64 * 0.1, &x)).unwrap();
        let um = ModelInputs::lerp(&u0, &u1, 0.5);
        let f = |u: &ModelInputs, x: &[f64; 4]| model.derivatives(&th, u, x).unwrap();
        let k1 = f(&u0, &x);
        let x2 = std::array::from_fn(|j| x[j] + 0.05 * k1[j]);
        let k2 = f(&um, &x2);
        let x3 = std::array::from_fn(|j| x[j] + 0.05 * k2[j]);
        let k3 = f(&um, &x3);
        let x4 = std::array::from_fn(|j| x[j] + 0.1 * k3[j]);
        let k4 = f(&u1, &x4);
        for j in 0..4 {
            x[j] += 0.1 / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        }
    }
    out
}

fn bench_output_error(c: &mut Criterion) {
    let path = records::hfb320_path();
    let (label, samples) = if path.exists() {
        ("hfb320_record_11_params_601_samples", records::hfb320(&path).unwrap())
    } else {
        eprintln!("{} absent: benchmarking a synthetic problem of the same size", path.display());
        ("hfb320_synthetic_11_params_601_samples", synthetic())
    };
    let cfg = OeConfig::new(records::hfb320_structure());
    let mut g = c.benchmark_group("output_error_fit");
    g.sample_size(20);
    g.bench_function(label, |b| b.iter(|| black_box(fit(&[&samples], black_box(&cfg)).unwrap())));
    g.finish();
}

criterion_group!(benches, bench_output_error);
criterion_main!(benches);
