//! Speed target of the frequency responses (docs/frequency-response.md): a 255 s, 400 Hz chirp
//! log (102 000 samples) processed in ≤ 2 s. The record here is what ArduPilot's SYSID mode
//! flies (a logarithmic chirp with fades) through a lightly damped second-order system with
//! output noise; the benchmark is the composite-window estimate with the default options
//! (five windows, 80 % overlap, 40 points per decade up to a fifth of the sample rate) and one
//! transfer-function fit.
#![allow(missing_docs)] // criterion_group! generates an undocumented `pub fn`.

use aeroident_signals::spectral::{SpectralOptions, frequency_responses};
use aeroident_signals::tf_fit::{FitOptions, TfSpec, fit_transfer_function};
use aeroident_signals::{InputSignal, Sweep, SweepLaw};
use criterion::{Criterion, black_box, criterion_group, criterion_main};

fn record() -> Vec<Vec<f64>> {
    let dt = 1.0 / 400.0;
    let n = 102_000;
    let sweep = Sweep::new(1.0, 0.2, 60.0, 2.5, 250.0, SweepLaw::Logarithmic, 5.0).unwrap();
    let x: Vec<f64> = (0..n).map(|k| sweep.value(k as f64 * dt)).collect();
    // ωn = 3 rad/s, ζ = 0.3 by Euler steps at 400 Hz (fine enough for a timing record).
    let (wn, zeta) = (3.0f64, 0.3);
    let (mut y1, mut y2) = (0.0, 0.0);
    let mut seed = 1u64;
    let y: Vec<f64> = x
        .iter()
        .map(|u| {
            let acc = wn * wn * (u - y1) - 2.0 * zeta * wn * y2;
            y1 += dt * y2;
            y2 += dt * acc;
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            y1 + 0.01 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        })
        .collect();
    vec![x, y]
}

fn bench(c: &mut Criterion) {
    let data = vec![record()];
    let (i, o) = (vec!["u".to_string()], vec!["y".to_string()]);
    let spec = TfSpec::parse("y/u:0/2+delay").unwrap();
    c.bench_function("freqresp_255s_400hz_chirp_with_fit", |b| {
        b.iter(|| {
            let r = frequency_responses(
                black_box(&data),
                &i,
                &o,
                1.0 / 400.0,
                &SpectralOptions::default(),
            )
            .unwrap();
            black_box(fit_transfer_function(&r.pairs[0], &spec, &FitOptions::default()).unwrap())
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
