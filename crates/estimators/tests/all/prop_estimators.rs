//! Property tests of every aircraft estimator under arbitrary sample streams: a
//! flight computer feeds them whatever its sensors give.
//!
//! Relations checked, not only "no panic":
//! - an estimator never panics and never publishes a non-finite value or σ;
//! - a refused sample (an `Err` from `update` while not diverged) leaves the estimates exactly as
//!   they were;
//! - a value is published only when identified (`value(i)` is `None` otherwise) and σ only with
//!   a value;
//! - once diverged, every later sample is refused and the status stays `Diverged`.
//!
//! The case count is bounded for CI (`PROPTEST_CASES`, default 64 here); the long run is
//! documented in `docs/reliability.md`.

use aeroident_estimators::ekf::{Ekf, EkfConfig};
use aeroident_estimators::ftr::{Ftr, FtrConfig};
use aeroident_estimators::model_reference::{
    CorrectedSmpeEstimator, GradientEstimator, ModelReferenceConfig, PublishedSmpeEstimator,
};
use aeroident_estimators::rls::{Rls, RlsConfig};
use aeroident_estimators::{
    AirDataSample, AircraftConstants, Estimator, ModelStructure, Priors, Status,
};
use proptest::prelude::*;

fn estimators(st: ModelStructure) -> Vec<Box<dyn Estimator>> {
    let pr = Priors::generic(&st);
    let mut v: Vec<Box<dyn Estimator>> = vec![
        Box::new(Rls::new(st, RlsConfig { forgetting: 0.99, init_samples: 0 }).unwrap()),
        Box::new(Ftr::new(st, FtrConfig { solve_interval_s: 0.05, ..Default::default() }).unwrap()),
        Box::new(CorrectedSmpeEstimator::new(st, &pr, ModelReferenceConfig::default()).unwrap()),
        Box::new(GradientEstimator::new(st, &pr, ModelReferenceConfig::default()).unwrap()),
        Box::new(PublishedSmpeEstimator::new(st, &pr, ModelReferenceConfig::default()).unwrap()),
    ];
    if let Ok(e) = Ekf::new(EkfConfig::new(st)) {
        v.push(Box::new(e));
    }
    v
}

/// A value that is usually plausible, sometimes extreme or non-finite.
fn wild(scale: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (-1.0..1.0f64).prop_map(move |x| x * scale),
        1 => prop_oneof![
            Just(0.0),
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(-f64::INFINITY),
            Just(1e308),
            Just(-1e308),
            Just(1e-308)
        ],
    ]
}

fn opt(scale: f64) -> impl Strategy<Value = Option<f64>> {
    prop_oneof![6 => wild(scale).prop_map(Some), 1 => Just(None)]
}

prop_compose! {
    fn sample()(
        dt in prop_oneof![8 => 0.001..0.05f64, 1 => Just(0.0), 1 => -0.1..0.0f64],
        v in prop_oneof![8 => 20.0..300.0f64, 1 => wild(1e3)],
        alpha in wild(0.3), qbar in prop_oneof![8 => 500.0..30000.0f64, 1 => wild(1e5)],
        beta in opt(0.2), p in opt(1.0), q in opt(1.0), r in opt(1.0),
        pdot in opt(3.0), qdot in opt(3.0), rdot in opt(3.0), alphadot in opt(1.0),
        phi in opt(1.0), theta in opt(0.5),
        ax in opt(5.0), ay in opt(5.0), az in opt(20.0),
        de in opt(0.3), da in opt(0.3), dr in opt(0.3), thrust in opt(5e4),
    ) -> (f64, AirDataSample) {
        (dt, AirDataSample {
            t_s: 0.0, vt_mps: v, alpha_rad: alpha, qbar_pa: qbar, beta_rad: beta,
            p_rad_s: p, q_rad_s: q, r_rad_s: r, pdot_rad_s2: pdot, qdot_rad_s2: qdot,
            rdot_rad_s2: rdot, alphadot_rad_s: alphadot, phi_rad: phi, theta_rad: theta,
            ax_mps2: ax, ay_mps2: ay, az_mps2: az, de_rad: de, da_rad: da, dr_rad: dr,
            thrust_n: thrust,
            constants: AircraftConstants {
                mass_kg: 9000.0, S_m2: 28.0, cbar_m: Some(3.4), b_m: Some(9.1),
                Ixx_kgm2: Some(1.3e4), Iyy_kgm2: Some(7.5e4), Izz_kgm2: Some(8.5e4),
                Ixz_kgm2: Some(1.3e3), thrust_arm_m: 0.0, thrust_incidence_rad: 0.0,
                v0_mps: Some(200.0),
            },
            ..Default::default()
        })
    }
}

fn check_stream(st: ModelStructure, stream: &[(f64, AirDataSample)]) -> Result<(), TestCaseError> {
    for mut est in estimators(st) {
        let name = est.method();
        let mut t = 0.0;
        for (dt, s) in stream {
            t += dt;
            let s = AirDataSample { t_s: t, ..*s };
            let before = *est.estimates();
            let was_diverged = before.status == Status::Diverged;
            let result = est.update(&s).copied();
            let after = *est.estimates();
            if was_diverged {
                prop_assert!(result.is_err(), "{name}: accepted a sample after diverging");
            }
            if result.is_err() && after.status != Status::Diverged {
                prop_assert_eq!(before, after, "{}: refused sample changed the state", name);
            }
            for i in 0..after.n {
                match after.value(i) {
                    Some(v) => prop_assert!(v.is_finite(), "{name}: param {i} = {v}"),
                    None => prop_assert!(after.sigma(i).is_none(), "{name}: σ without value"),
                }
                if let Some(sg) = after.sigma(i) {
                    prop_assert!(sg.is_finite() && sg >= 0.0, "{name}: σ {i} = {sg}");
                }
            }
        }
    }
    Ok(())
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(64)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn prop_longitudinal_streams(stream in prop::collection::vec(sample(), 1..120)) {
        check_stream(ModelStructure::longitudinal(), &stream)?;
    }

    #[test]
    fn prop_lateral_streams(stream in prop::collection::vec(sample(), 1..120)) {
        check_stream(ModelStructure::lateral(), &stream)?;
    }

    #[test]
    fn prop_six_axis_streams(stream in prop::collection::vec(sample(), 1..80)) {
        check_stream(ModelStructure::six_axis(), &stream)?;
    }
}
