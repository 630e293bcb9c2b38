//! Per-call cost of the signal tools inside a simulation step (budget: the whole closed
//! loop at ≥ 500× real time at 100 Hz, i.e. ≤ 20 µs per 10 ms step for everything). Criterion
//! reports the time per call; each should be tens of nanoseconds.
#![allow(missing_docs)] // criterion_group! generates an undocumented `pub fn`.

use aeroident_signals::{
    BandLimitedWhiteNoise, Doublet, DrydenParameters, DrydenTurbulence, Input, InputSignal,
    Multisine, SensorModel, SensorParameters, Sine, Sum, TurbulenceSeverity, WindField,
};
use criterion::{Criterion, black_box, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let sum: Input = Sum::new(vec![
        Sine::new(0.05f64.to_radians(), std::f64::consts::TAU, 0.0, 0.0, None).unwrap().into(),
        Doublet::new(-0.05f64.to_radians(), 1.0, 0.5).unwrap().into(),
    ])
    .into();
    let mut t = 0.0;
    c.bench_function("input_sum_sine_doublet_value", |b| {
        b.iter(|| {
            t += 1e-3;
            black_box(sum.value(black_box(t)))
        })
    });
    let ms = Multisine::schroeder(0.01, 10.0, &(1..=12).collect::<Vec<_>>(), 0.0, None).unwrap();
    c.bench_function("multisine_12_value", |b| {
        b.iter(|| {
            t += 1e-3;
            black_box(ms.value(black_box(t)))
        })
    });
    let noise = BandLimitedWhiteNoise::new(1e-4, 0.01, 7).unwrap();
    c.bench_function("band_limited_white_noise_value", |b| {
        b.iter(|| {
            t += 1e-3;
            black_box(noise.value(black_box(t)))
        })
    });
    let p = DrydenParameters::mil_f_8785c(20000.0, TurbulenceSeverity::Moderate).unwrap();
    let dryden = DrydenTurbulence::generate(&p, 675.0, 0.01, 1000.0, 1).unwrap();
    c.bench_function("dryden_wind_body_lookup", |b| {
        b.iter(|| {
            t = (t + 1e-3) % 1000.0;
            black_box(dryden.wind_body_fps(black_box(t)))
        })
    });
    let mut sensor = SensorModel::new(
        SensorParameters {
            white_sigma: 1e-3,
            gauss_markov: Some((5e-4, 30.0)),
            delay_samples: 2,
            quantum: Some(1e-4),
            ..SensorParameters::ideal(1000.0)
        },
        3,
    )
    .unwrap();
    let mut ts = 0.0;
    c.bench_function("sensor_measure_every_sample", |b| {
        b.iter(|| {
            ts += 1e-3;
            black_box(sensor.measure(black_box(ts), 0.1))
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_secs(1));
    targets = bench
}
criterion_main!(benches);
