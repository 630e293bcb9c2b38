//! Per-sample update cost of the recorded-data estimators (targets on one core:
//! RLS ≥ 1,000,000 samples/s, i.e. ≤ 1 µs per update, for the six-axis preset; EKF ≥ 100,000
//! samples/s, ≤ 10 µs, for the longitudinal and the lateral preset).
//! Criterion reports the time per update and, via `Throughput::Elements`, samples per second.
#![allow(missing_docs)] // criterion_group! generates an undocumented `pub fn`.

#[path = "../src/test_aircraft.rs"]
mod test_aircraft;

use aeroident_estimators::ekf::EkfBlocks;
use aeroident_estimators::finite_time::{FiniteTimeConfig, FiniteTimeSmpe};
use aeroident_estimators::ftr::{Ftr, FtrConfig};
use aeroident_estimators::model_reference::{CorrectedSmpeEstimator, ModelReferenceConfig};
use aeroident_estimators::prior::Priors;
use aeroident_estimators::rls::{Rls as StructureRls, RlsConfig as StructureRlsConfig};
use aeroident_estimators::vocabulary::ModelStructure;
use aeroident_estimators::{Ekf, Estimator};
use criterion::{Criterion, Throughput, black_box, criterion_group, criterion_main};

const N: usize = 1000;

/// The new EKF over the longitudinal (4 states + 12 parameters), lateral (4 + 18) and six-axis
/// (the default job's filter) presets, the new RLS over the six-axis preset (30 parameters in
/// six fits), and the corrected sliding-mode estimator over the six-axis preset.
fn bench_structure_estimators(c: &mut Criterion) {
    // 1000 samples at 50 Hz; the doublets (1, 6, 12 s) fall inside the 20 s record.
    let data = test_aircraft::six_axis_stream(N, 0.02, 20.0);
    let mut g = c.benchmark_group("structure_estimators");
    g.throughput(Throughput::Elements(N as u64));
    for (name, st) in [
        ("ekf_longitudinal", ModelStructure::longitudinal()),
        ("ekf_lateral", ModelStructure::lateral()),
        ("ekf_six_axis", ModelStructure::six_axis()),
    ] {
        let cfg = aeroident_estimators::EkfConfig::new(st);
        g.bench_function(format!("{name}_1000_samples"), |b| {
            b.iter(|| {
                let mut ekf = Box::new(Ekf::new(cfg).unwrap());
                for s in &data {
                    black_box(ekf.update(black_box(s)).unwrap());
                }
            })
        });
    }
    // The six-axis preset by blocks: a longitudinal and a lateral filter (`ekf` option
    // `blocks = true`).
    let cfg = aeroident_estimators::EkfConfig::new(ModelStructure::six_axis());
    g.bench_function("ekf_six_axis_blocks_1000_samples", |b| {
        b.iter(|| {
            let mut ekf = Box::new(EkfBlocks::new(cfg).unwrap());
            for s in &data {
                black_box(ekf.update(black_box(s)).unwrap());
            }
        })
    });
    // FTR: the target is ≥ 10⁶ samples/s for a 20-frequency grid and the longitudinal
    // signals (0.1–0.86 Hz in 0.04 Hz steps = 20 frequencies).
    let ftr_cfg = FtrConfig { f_max_hz: 0.86, ..FtrConfig::default() };
    g.bench_function("ftr_longitudinal_20_frequencies_1000_samples", |b| {
        b.iter(|| {
            let mut ftr = Box::new(Ftr::new(ModelStructure::longitudinal(), ftr_cfg).unwrap());
            for s in &data {
                black_box(ftr.update(black_box(s)).unwrap());
            }
        })
    });
    g.bench_function("rls_six_axis_1000_samples", |b| {
        b.iter(|| {
            let mut rls =
                StructureRls::new(ModelStructure::six_axis(), StructureRlsConfig::default())
                    .unwrap();
            for s in &data {
                black_box(rls.update(black_box(s)).unwrap());
            }
        })
    });
    // The corrected sliding-mode estimator as the default job runs it (generic priors here):
    // one adaptation law per coefficient, all stepped or none per sample.
    let priors = Priors::generic(&ModelStructure::six_axis());
    g.bench_function("smpe_corrected_six_axis_1000_samples", |b| {
        b.iter(|| {
            let mut e = Box::new(
                CorrectedSmpeEstimator::new(
                    ModelStructure::six_axis(),
                    &priors,
                    ModelReferenceConfig::default(),
                )
                .unwrap(),
            );
            for s in &data {
                black_box(e.update(black_box(s)).unwrap());
            }
        })
    });
    g.finish();
}

/// The sliding-mode memory estimator against RLS on the same structure and memory (the
/// default job's λ = 0.995): its update is RLS's plus the information matrix and the law, and
/// must cost at most 2× RLS's (docs/smpe-finite-time.md).
fn bench_sliding_memory_against_rls(c: &mut Criterion) {
    let data = test_aircraft::six_axis_stream(N, 0.02, 20.0);
    let mut g = c.benchmark_group("sliding_memory_vs_rls");
    g.throughput(Throughput::Elements(N as u64));
    for (name, st) in
        [("six_axis", ModelStructure::six_axis()), ("longitudinal", ModelStructure::longitudinal())]
    {
        g.bench_function(format!("rls_{name}_1000_samples"), |b| {
            let cfg = StructureRlsConfig { forgetting: 0.995, init_samples: 0 };
            b.iter(|| {
                let mut e = StructureRls::new(st, cfg).unwrap();
                for s in &data {
                    black_box(e.update(black_box(s)).unwrap());
                }
            })
        });
        g.bench_function(format!("smpe_finite_time_{name}_1000_samples"), |b| {
            let cfg = FiniteTimeConfig { forgetting: 0.995, ..FiniteTimeConfig::default() };
            b.iter(|| {
                let mut e = FiniteTimeSmpe::new(st, cfg).unwrap();
                for s in &data {
                    black_box(e.update(black_box(s)).unwrap());
                }
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default();
    targets = bench_structure_estimators, bench_sliding_memory_against_rls
}
criterion_main!(benches);
