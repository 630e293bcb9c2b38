//! Tests of the SMPE engine against hand computations and properties.

use super::*;
use crate::ParametricEstimator;
use nalgebra::SVector;
use proptest::prelude::*;

/// (2.1) as an estimation model: ẋ = −a x + u.
struct FirstOrderModel;
impl ParametricModel<1, 1> for FirstOrderModel {
    type Input = f64;
    fn derivatives(
        &self,
        _t: f64,
        z: &SVector<f64, 1>,
        u: &f64,
        th: &SVector<f64, 1>,
    ) -> Result<SVector<f64, 1>, EstimatorError> {
        Ok(SVector::<f64, 1>::new(-th[0] * z[0] + u))
    }
}

/// (2.3) as an estimation model: ẍ = −a₂ ẋ − a₁ x + u, state [x, ẋ], θ = [a1, a2].
struct SecondOrderModel;
impl ParametricModel<2, 2> for SecondOrderModel {
    type Input = f64;
    fn derivatives(
        &self,
        _t: f64,
        z: &SVector<f64, 2>,
        u: &f64,
        th: &SVector<f64, 2>,
    ) -> Result<SVector<f64, 2>, EstimatorError> {
        Ok(SVector::<f64, 2>::new(z[1], -th[1] * z[1] - th[0] * z[0] + u))
    }
}

fn spec(name: &'static str, lower: f64, upper: f64, lambda: f64, initial: f64) -> ParamSpec {
    ParamSpec { name, lower, upper, lambda, initial }
}

fn first_order(reading: Reading) -> PublishedSmpe<FirstOrderModel, 1, 1> {
    PublishedSmpe::new(
        FirstOrderModel,
        SmpeConfig {
            params: [spec("a", 2.0, 4.5, 10.0, 3.0)],
            eta: 0.01,
            surface: SlidingSurface::first_order(&[0]).unwrap(),
            gain: GainForm::Shared,
            reading,
        },
    )
    .unwrap()
}

/// Hand computation of one sample of (3.22) with K (3.36), done outside the code.
///
/// Bounds [2, 4.5] → α = √(4.5/2) = 1.5, c = |α⁻¹ − 1| = 1/3; λ = 10, η = 0.01.
/// Sample x = 0.5, x_m = 0.45, ẋ_m = 1.1, u = 1, so A = x² = 0.25,
/// E0 = u x − x_m ẋ_m = 0.005, Λ = (λ/2)(x² − x_m²) = 0.2375.
/// Multiplying out F(a) = E0 − A a + Λ − ((c A a − η)(E0 − A a) + η) a gives the cubic
/// c A² a³ − (c A E0 + η A) a² + (η E0 − A − η) a + (E0 + Λ) = 0
/// = 0.0208333 a³ − 0.00291667 a² − 0.25995 a + 0.2425, whose only root in [2, 4.5]
/// (sign change between 3.0 and 3.25; bisection to 1e-16) is a = 3.0038493727998468.
/// Explicit reading from a⁻ = 3: K = 0.24, N = −0.5075, D = K(E0 − 3A) + η = −0.1688,
/// a = N/D = 3.0065165876777256.
#[test]
fn hand_first_order_single_step_implicit_and_explicit() {
    let sample = SmpeSample {
        t_s: 0.001,
        z: SVector::<f64, 1>::new(0.5),
        z_m: SVector::<f64, 1>::new(0.45),
        zdot_m: SVector::<f64, 1>::new(1.1),
        u: 1.0,
    };
    let mut imp = first_order(Reading::Implicit);
    let a = imp.update(&sample).unwrap().theta[0];
    assert!((a - 3.0038493727998468).abs() < 1e-10, "implicit a = {a}");
    assert_eq!(imp.stats().no_root, 0);
    let mut exp = first_order(Reading::Explicit);
    let a = exp.update(&sample).unwrap().theta[0];
    // 1e-9: the default sensitivity is a central difference (rounding ~1e-11 here).
    assert!((a - 3.0065165876777256).abs() < 1e-9, "explicit a = {a}");
}

/// Derivation (3.96) with a shared K and equal λ: F₁ − F₂ = −D (â₁ − â₂), so any root with
/// D ≠ 0 has â₁ = â₂, whatever the truth. The engine must reproduce this structural fact.
#[test]
fn analytic_shared_gain_forces_equal_second_order_estimates() {
    let mut est = PublishedSmpe::new(
        SecondOrderModel,
        SmpeConfig {
            params: [spec("a1", 4.0, 16.0, 5.0, 8.0), spec("a2", 3.0, 12.0, 5.0, 6.0)],
            eta: 0.001,
            surface: SlidingSurface::second_order(0, 1).unwrap(),
            gain: GainForm::Shared,
            reading: Reading::Implicit,
        },
    )
    .unwrap();
    let sample = SmpeSample {
        t_s: 0.1,
        z: SVector::<f64, 2>::new(0.3, 0.8),
        z_m: SVector::<f64, 2>::new(0.31, 0.75),
        zdot_m: SVector::<f64, 2>::new(0.75, 2.0),
        u: 10.0,
    };
    let th = est.update(&sample).unwrap().theta;
    assert_eq!(est.stats().no_root, 0, "a root exists: â1 = â2 = a solves the scalar cubic");
    assert!((th[0] - th[1]).abs() < 1e-6, "â1 = {}, â2 = {}", th[0], th[1]);
}

#[test]
fn invalid_config_is_an_error() {
    let mk = |lower, upper, lambda, eta| {
        PublishedSmpe::new(
            FirstOrderModel,
            SmpeConfig {
                params: [spec("a", lower, upper, lambda, 1.0)],
                eta,
                surface: SlidingSurface::first_order(&[0]).unwrap(),
                gain: GainForm::Shared,
                reading: Reading::Implicit,
            },
        )
    };
    assert!(mk(-1.0, 2.0, 1.0, 0.01).is_err()); // straddles zero: no gain margin
    assert!(mk(0.5, 2.0, 0.0, 0.01).is_err()); // λ = 0
    assert!(mk(0.5, 2.0, 1.0, 0.0).is_err()); // η = 0
    assert!(mk(2.0, 0.5, 1.0, 0.01).is_err()); // unordered
    assert!(mk(0.5, 2.0, 1.0, 0.01).is_ok());
    assert!(SlidingSurface::<1>::first_order(&[1]).is_err());
}

/// The explicit denominator K·B + η crossing zero: with a⁻ = 3, bounds [2, 4.5] (c = 1/3),
/// x = 1 (A = 1) the gain is K = 1 − η; choosing B = u x − a⁻ x² − x_m ẋ_m = −η/K makes
/// D = 0 exactly. η's purpose is to keep |D| ≥ η: the result must be finite, in bounds, and
/// counted as guarded.
#[test]
fn analytic_explicit_zero_denominator_is_guarded() {
    let mut est = first_order(Reading::Explicit);
    let eta = 0.01;
    let k = 1.0 - eta;
    let b = -eta / k;
    // B = u·1 − 3·1 − x_m ẋ_m with x_m = 1 → ẋ_m = u − 3 − B.
    let u = 4.0;
    let sample = SmpeSample {
        t_s: 0.0,
        z: SVector::<f64, 1>::new(1.0),
        z_m: SVector::<f64, 1>::new(1.0),
        zdot_m: SVector::<f64, 1>::new(u - 3.0 - b),
        u,
    };
    let a = est.update(&sample).unwrap().theta[0];
    assert!(a.is_finite() && (2.0..=4.5).contains(&a));
    assert_eq!(est.stats().guarded, 1);
}

/// Corrected estimator on the first-order system with exact measurements: the information
/// update makes the estimate exact once x ≠ 0 (independent truth: a = 3).
#[test]
fn analytic_corrected_first_order_recovers_truth() {
    let mut est = CorrectedSmpe::new(
        FirstOrderModel,
        CorrectedConfig {
            params: [spec("a", 1.0, 6.0, 1.0, 2.0)],
            sliding: [1.0],
            lambda_per_s: 10.0,
            information_per_s: 1e4,
            tracking_weight: 1.0,
            forgetting_per_s: 0.0,
        },
    )
    .unwrap();
    let dt = 1e-3;
    for k in 0..1000 {
        let t = k as f64 * dt;
        let x_m = (1.0 - (-3.0 * t).exp()) / 3.0; // step response of ẋ = −3x + 1
        let xdot_m = (-3.0 * t).exp();
        let s = SmpeSample {
            t_s: t,
            z: SVector::<f64, 1>::new(x_m),
            z_m: SVector::<f64, 1>::new(x_m),
            zdot_m: SVector::<f64, 1>::new(xdot_m),
            u: 1.0,
        };
        est.update(&s).unwrap();
    }
    let a = est.estimate().theta[0];
    assert!((a - 3.0).abs() < 1e-3 * 3.0, "a = {a}");
}

fn same_sign_bounds() -> impl Strategy<Value = (f64, f64)> {
    (0.05f64..50.0, 1.01f64..20.0, any::<bool>())
        .prop_map(|(lo, ratio, neg)| if neg { (-lo * ratio, -lo) } else { (lo, lo * ratio) })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random bounds, states and inputs never produce NaN/±inf or a panic, in either reading,
    /// with either gain form, for the published and the corrected estimator.
    #[test]
    fn prop_estimates_always_finite_and_bounded(
        b1 in same_sign_bounds(),
        b2 in same_sign_bounds(),
        lambda in 0.01f64..100.0,
        eta in 1e-6f64..1.0,
        seed in any::<u64>(),
        explicit in any::<bool>(),
        shared in any::<bool>(),
    ) {
        // Deterministic pseudo-random sample stream from the seed (SplitMix64).
        let mut st = seed;
        let mut rnd = move || {
            st = st.wrapping_add(0x9E3779B97F4A7C15);
            let mut z = st;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let reading = if explicit { Reading::Explicit } else { Reading::Implicit };
        let gain = if shared { GainForm::Shared } else { GainForm::PerParameter };
        let mid = |b: (f64, f64)| ParamSpec::geometric_mean(b.0, b.1).unwrap();
        let mut p2 = PublishedSmpe::new(SecondOrderModel, SmpeConfig {
            params: [spec("a1", b1.0, b1.1, lambda, mid(b1)), spec("a2", b2.0, b2.1, lambda, mid(b2))],
            eta,
            surface: SlidingSurface::second_order(0, 1).unwrap(),
            gain,
            reading,
        }).unwrap();
        let mut p1 = PublishedSmpe::new(FirstOrderModel, SmpeConfig {
            params: [spec("a", b1.0, b1.1, lambda, mid(b1))],
            eta,
            surface: SlidingSurface::first_order(&[0]).unwrap(),
            gain,
            reading,
        }).unwrap();
        let mut c2 = CorrectedSmpe::new(SecondOrderModel, CorrectedConfig {
            params: [spec("a1", b1.0, b1.1, lambda, mid(b1)), spec("a2", b2.0, b2.1, lambda, mid(b2))],
            sliding: [0.0, 1.0],
            lambda_per_s: lambda,
            information_per_s: 1e4,
            tracking_weight: 1.0,
            forgetting_per_s: 0.1,
        }).unwrap();
        for k in 0..40 {
            let scale = 10f64.powf(3.0 * rnd());
            let v2 = |r: &mut dyn FnMut() -> f64| SVector::<f64, 2>::new(r() * scale, r() * scale);
            let s2 = SmpeSample { t_s: k as f64 * 1e-3, z: v2(&mut rnd), z_m: v2(&mut rnd),
                zdot_m: v2(&mut rnd), u: rnd() * scale };
            let s1 = SmpeSample { t_s: s2.t_s, z: SVector::<f64, 1>::new(s2.z[0]),
                z_m: SVector::<f64, 1>::new(s2.z_m[0]), zdot_m: SVector::<f64, 1>::new(s2.zdot_m[0]),
                u: s2.u };
            let t = p2.update(&s2).unwrap().theta;
            prop_assert!(t.iter().all(|x| x.is_finite()));
            prop_assert!(t[0] >= b1.0 && t[0] <= b1.1 && t[1] >= b2.0 && t[1] <= b2.1);
            let t = p1.update(&s1).unwrap().theta;
            prop_assert!(t[0].is_finite() && t[0] >= b1.0 && t[0] <= b1.1);
            let t = c2.update(&s2).unwrap().theta;
            prop_assert!(t.iter().all(|x| x.is_finite()));
            prop_assert!(t[0] >= b1.0 && t[0] <= b1.1 && t[1] >= b2.0 && t[1] <= b2.1);
        }
    }
}
