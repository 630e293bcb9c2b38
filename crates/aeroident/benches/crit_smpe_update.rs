//! Cost of one SMPE update (ns per sample) on the thesis's second-order nonlinear system (2.4):
//! published estimator in both readings and the corrected estimator. At a 1 kHz sample rate
//! the real-time budget is 1 ms per sample.
#![allow(missing_docs)] // criterion_group! generates an undocumented pub fn.

use aeroident_estimators::ParametricEstimator;
use aeroident_estimators::smpe::{
    CorrectedConfig, CorrectedSmpe, GainForm, ParamSpec, PublishedSmpe, Reading, SlidingSurface,
    SmpeConfig, SmpeSample,
};
use aeroident_models::small::SecondOrderNonlinear;
use aeroident_pipelines::poc::ModelAdapter;
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::SVector;
use std::hint::black_box;

fn params() -> [ParamSpec; 2] {
    [
        ParamSpec { name: "a1", lower: 6.0, upper: 24.0, lambda: 2.0, initial: 8.0 },
        ParamSpec { name: "a2", lower: 4.0, upper: 16.0, lambda: 2.0, initial: 5.0 },
    ]
}

fn sample(k: usize) -> SmpeSample<2, f64> {
    let t = k as f64 * 1e-3;
    SmpeSample {
        t_s: t,
        z: SVector::<f64, 2>::new(0.3 + 0.01 * t.sin(), 0.5),
        z_m: SVector::<f64, 2>::new(0.31, 0.52 + 0.01 * t.cos()),
        zdot_m: SVector::<f64, 2>::new(0.52, 1.1),
        u: 5.0,
    }
}

fn bench(c: &mut Criterion) {
    let model = ModelAdapter(SecondOrderNonlinear { a1: 12.0, a2: 8.0 });
    for (name, reading) in [("implicit", Reading::Implicit), ("explicit", Reading::Explicit)] {
        let cfg = SmpeConfig {
            params: params(),
            eta: 0.01,
            surface: SlidingSurface::second_order(0, 1).unwrap(),
            gain: GainForm::Shared,
            reading,
        };
        let mut est = PublishedSmpe::new(model.clone(), cfg).unwrap();
        let mut k = 0;
        c.bench_function(&format!("smpe_published_{name}_update"), |b| {
            b.iter(|| {
                k += 1;
                black_box(est.update(black_box(&sample(k))).unwrap().theta)
            })
        });
    }
    let cfg = CorrectedConfig {
        params: params(),
        sliding: [0.0, 1.0],
        lambda_per_s: 2.0,
        information_per_s: 1e4,
        tracking_weight: 1.0,
        forgetting_per_s: 0.0,
    };
    let mut est = CorrectedSmpe::new(model, cfg).unwrap();
    let mut k = 0;
    c.bench_function("smpe_corrected_update", |b| {
        b.iter(|| {
            k += 1;
            black_box(est.update(black_box(&sample(k))).unwrap().theta)
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
