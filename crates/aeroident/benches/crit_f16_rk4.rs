//! Criterion benchmark: one RK4 step of the 13-state F-16 at the thesis trim (20 000 ft,
//! 675 ft/s, xcg 0.30), and one derivative evaluation. Target: RK4 step ≤ 2 µs (≥ 5000× real
//! time at 100 Hz).

#![allow(missing_docs)] // criterion_group! generates an undocumented pub fn.

use aeroident_models::Dynamics;
use aeroident_models::f16::F16;
use aeroident_models::integrate::rk4_step;
use aeroident_models::trim::{TrimCondition, trim};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let f16 = F16::new(0.30).expect("xcg is finite");
    let t = trim(&f16, &TrimCondition::level(20_000.0, 675.0)).expect("thesis trim converges");
    c.bench_function("f16_rk4_step_100hz", |b| {
        b.iter(|| {
            rk4_step(black_box(&f16), 0.0, black_box(&t.state), black_box(&t.controls), 0.01)
                .expect("in domain")
        })
    });
    c.bench_function("f16_derivatives", |b| {
        b.iter(|| {
            f16.derivatives(0.0, black_box(&t.state), black_box(&t.controls)).expect("in domain")
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
