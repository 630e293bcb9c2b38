use super::*;
use crate::output_error::{OeConfig, Start, fit};
use crate::test_aircraft::{
    ALPHA0, RHO, THRUST, V0, constants, derivatives, set_output, three_two_one_one,
};
use crate::vocabulary::{Coefficient as C, Term as T};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::println;

const DT: f64 = 0.02;

fn condition() -> FlightCondition {
    FlightCondition::level(V0, ALPHA0, RHO, THRUST)
}

fn trimmed(st: &ModelStructure) -> Vec<f64> {
    trim_biases(st, &derivatives(st), &constants(), &condition()).unwrap()
}

fn doublet(t0_s: f64, half_s: f64, amp: f64, duration_s: f64) -> Vec<f64> {
    let n = (duration_s / DT).round() as usize + 1;
    (0..n)
        .map(|i| {
            let u = (i as f64 * DT - t0_s) / half_s;
            if (0.0..1.0).contains(&u) {
                amp
            } else if (1.0..2.0).contains(&u) {
                -amp
            } else {
                0.0
            }
        })
        .collect()
}

fn sensors(outputs: &[Output], scale: f64) -> Vec<Sensor> {
    let sigma = |o: Output| match o {
        Output::Vt => 0.3,
        Output::Alpha | Output::Beta => 0.002,
        Output::P | Output::Q | Output::R | Output::Phi | Output::Theta => 0.003,
        Output::Ax | Output::Ay | Output::Az => 0.08,
        Output::Pdot | Output::Qdot | Output::Rdot => 0.05,
    };
    outputs.iter().map(|&o| Sensor { output: o, sigma: scale * sigma(o) }).collect()
}

fn lon_plan(de: Vec<f64>) -> DesignPlan {
    let st = ModelStructure::longitudinal();
    let outputs = StateSet::Longitudinal.outputs();
    DesignPlan::new(
        st,
        trimmed(&st),
        constants(),
        condition(),
        vec![PlannedInputs { dt_s: DT, de_rad: de, ..Default::default() }],
        sensors(outputs, 1.0),
    )
}

fn lat_plan(duration_s: f64, amp: f64) -> DesignPlan {
    let st = ModelStructure::lateral();
    let outputs = StateSet::Lateral.outputs();
    DesignPlan::new(
        st,
        trimmed(&st),
        constants(),
        condition(),
        vec![PlannedInputs {
            dt_s: DT,
            da_rad: doublet(1.0, 0.5, -amp, duration_s),
            dr_rad: doublet(4.0, 0.8, amp, duration_s),
            ..Default::default()
        }],
        sensors(outputs, 1.0),
    )
}

const DEG: f64 = core::f64::consts::PI / 180.0;

/// The roll-acceleration model `CY = CY_0, Cl = Cl_0 + Cl_da δa, Cn = Cn_0`, only `ṗ`
/// measured: with `q = 0`, `ṗ = (Jz L + Jxz N) / (Jx Jz − Jxz²)` (Stevens & Lewis eq.
/// 2.5-24), so `∂ṗ/∂Cl_0 = k_l`, `∂ṗ/∂Cl_da = k_l δa_i`, `∂ṗ/∂Cn_0 = k_n`, `∂ṗ/∂CY_0 = 0`
/// with `k_l = q̄ S b Jz / (Jx Jz − Jxz²)`, `k_n = q̄ S b Jxz / (Jx Jz − Jxz²)`: a linear
/// regression whose Cramér–Rao bound is closed form.
fn roll_plan(ixz: f64, scale: f64) -> (DesignPlan, Vec<f64>) {
    let st = ModelStructure::empty()
        .with(C::CY, &[T::Bias])
        .with(C::Cl, &[T::Bias, T::Da])
        .with(C::Cn, &[T::Bias]);
    let mut th = vec![0.0; st.n_params()];
    th[st.index_of(Param::new(C::Cl, T::Da)).unwrap()] = 0.07;
    let mut k = constants();
    k.Ixz_kgm2 = Some(ixz);
    // A non-zero-mean input so that Cl_0 and Cl_da are correlated.
    let da: Vec<f64> = (0..101)
        .map(|i| scale * 0.004 * (1.0 + (2.0 * core::f64::consts::PI * 0.7 * i as f64 * DT).sin()))
        .collect();
    let plan = DesignPlan::new(
        st,
        th,
        k,
        condition(),
        vec![PlannedInputs { dt_s: DT, da_rad: da.clone(), ..Default::default() }],
        vec![Sensor { output: Output::Pdot, sigma: 0.05 }],
    );
    (plan, da)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn analytic_roll_acceleration_bound_matches_the_closed_form() {
    let sigma_n = 0.05;
    let k = constants();
    let qsb = condition().qbar_pa() * k.S_m2 * k.b_m.unwrap();
    let (jx, jz) = (k.Ixx_kgm2.unwrap(), k.Izz_kgm2.unwrap());

    // Jxz = 0: Cl_0 and Cl_da identifiable, 2 × 2 regression on [1, δa]; CY_0 and Cn_0
    // do not affect ṗ.
    let (plan, da) = roll_plan(0.0, 1.0);
    let r = predict_crb(&plan).unwrap();
    let n = da.len() as f64;
    let s1: f64 = da.iter().sum();
    let s2: f64 = da.iter().map(|v| v * v).sum();
    let det = n * s2 - s1 * s1;
    let kl = qsb / jx;
    let want_da = sigma_n / kl * (n / det).sqrt();
    let want_0 = sigma_n / kl * (s2 / det).sqrt();
    let want_corr = -s1 / (n * s2).sqrt();
    println!(
        "Jxz = 0: σ(Cl_da) {:.6e} closed form {want_da:.6e}; σ(Cl_0) {:.6e} closed form {want_0:.6e}; ρ {:.6} closed form {want_corr:.6}",
        r.sigma_of("Cl_da").unwrap(),
        r.sigma_of("Cl_0").unwrap(),
        r.correlation(r.index_of("Cl_0").unwrap(), r.index_of("Cl_da").unwrap()).unwrap()
    );
    assert!(close(r.sigma_of("Cl_da").unwrap(), want_da, 1e-9));
    assert!(close(r.sigma_of("Cl_0").unwrap(), want_0, 1e-9));
    let corr = r.correlation(r.index_of("Cl_0").unwrap(), r.index_of("Cl_da").unwrap()).unwrap();
    assert!((corr - want_corr).abs() < 1e-9, "correlation {corr} vs {want_corr}");
    assert_eq!(r.not_identifiable, ["CY_0", "Cn_0"]);
    assert!(r.sigma_of("CY_0").is_none() && r.sigma_of("Cn_0").is_none());
    assert!(r.condition_number.is_infinite());
    let rel = r.relative_sigma[r.index_of("Cl_da").unwrap()].unwrap();
    assert!(close(rel, want_da / 0.07, 1e-9));
    assert!(r.relative_sigma[r.index_of("Cl_0").unwrap()].is_none(), "θ = 0: no relative σ");

    // Jxz ≠ 0: Cl_0 and Cn_0 both give constant columns (k_l, k_n): collinear, neither is
    // identifiable; Cl_da still is, with the bound of the regression on [1, δa].
    let jxz = k.Ixz_kgm2.unwrap();
    let (plan, _) = roll_plan(jxz, 1.0);
    let r = predict_crb(&plan).unwrap();
    let kl = qsb * jz / (jx * jz - jxz * jxz);
    let want_da = sigma_n / kl * (n / det).sqrt();
    assert!(close(r.sigma_of("Cl_da").unwrap(), want_da, 1e-9));
    assert_eq!(r.not_identifiable, ["CY_0", "Cl_0", "Cn_0"]);

    // Doubling the amplitude of this linear regression halves σ(Cl_da) exactly.
    let (plan2, _) = roll_plan(0.0, 2.0);
    let (plan1, _) = roll_plan(0.0, 1.0);
    let ratio = predict_crb(&plan2).unwrap().sigma_of("Cl_da").unwrap()
        / predict_crb(&plan1).unwrap().sigma_of("Cl_da").unwrap();
    assert!((ratio - 0.5).abs() < 1e-9, "amplitude ×2: σ ratio {ratio}");
}

/// The derivative (non-bias) parameters of a structure.
fn derivative_names(st: &ModelStructure) -> Vec<&'static str> {
    st.params().filter(|p| p.term != T::Bias).map(Param::name).collect()
}

#[test]
fn scaling_laws_amplitude_noise_repeats_duration() {
    let st = ModelStructure::longitudinal();
    // Amplitude: the sensitivity of a derivative is proportional to the excursion of its
    // regressor, so σ ∝ 1/amplitude for the linearised model (the biases' sensitivities do
    // not scale; their σ are not checked). Small amplitudes keep the nonlinearity small.
    let a1 = predict_crb(&lon_plan(three_two_one_one(&[1.0], 0.4, 0.5 * DEG, 10.0, DT))).unwrap();
    let a2 = predict_crb(&lon_plan(three_two_one_one(&[1.0], 0.4, 1.0 * DEG, 10.0, DT))).unwrap();
    for name in derivative_names(&st) {
        let r = a2.sigma_of(name).unwrap() / a1.sigma_of(name).unwrap();
        println!("amplitude ×2: {name:>9} σ ratio {r:.4}");
        assert!((r - 0.5).abs() < 0.005, "{name}: amplitude ×2 gives σ ratio {r}");
    }
    // Sensor noise halved: every σ halves exactly (M scales by 4).
    let mut plan = lon_plan(three_two_one_one(&[1.0], 0.4, 1.0 * DEG, 10.0, DT));
    plan.sensors.iter_mut().for_each(|s| s.sigma *= 0.5);
    let h = predict_crb(&plan).unwrap();
    for i in 0..a2.n() {
        let r = h.sigma[i].unwrap() / a2.sigma[i].unwrap();
        assert!((r - 0.5).abs() < 1e-9, "{}: noise ×½ gives σ ratio {r}", a2.names[i]);
    }
    // Two identical repeats: every σ × 1/√2 exactly.
    let mut plan = lon_plan(three_two_one_one(&[1.0], 0.4, 1.0 * DEG, 10.0, DT));
    plan.repeats = 2;
    let rep = predict_crb(&plan).unwrap();
    for i in 0..a2.n() {
        let r = rep.sigma[i].unwrap() / a2.sigma[i].unwrap();
        assert!((r - core::f64::consts::FRAC_1_SQRT_2).abs() < 1e-9);
    }
    // Duration: a stationary (periodic) input over 2 and 4 periods; the information of the
    // short-period derivatives grows ∝ duration, σ × ≈ 1/√2 (the transient from trim and the
    // slow phugoid make it approximate).
    let multisine = |duration_s: f64| -> Vec<f64> {
        let n = (duration_s / DT).round() as usize + 1;
        let period = 5.0;
        (0..n)
            .map(|i| {
                let t = i as f64 * DT;
                (1..=5)
                    .map(|k| {
                        let kf = k as f64;
                        // Schroeder phases for a low peak factor.
                        let phase = -core::f64::consts::PI * kf * (kf - 1.0) / 5.0;
                        0.4 * DEG * (2.0 * core::f64::consts::PI * kf * t / period + phase).sin()
                    })
                    .sum()
            })
            .collect()
    };
    let d1 = predict_crb(&lon_plan(multisine(20.0))).unwrap();
    let d2 = predict_crb(&lon_plan(multisine(40.0))).unwrap();
    for name in ["CL_alpha", "CL_de", "Cm_alpha", "Cm_q", "Cm_de"] {
        let r = d2.sigma_of(name).unwrap() / d1.sigma_of(name).unwrap();
        println!("duration ×2: {name:>9} σ ratio {r:.4} (1/√2 = 0.7071)");
        assert!(
            (r - core::f64::consts::FRAC_1_SQRT_2).abs() < 0.02,
            "{name}: duration ×2 gives σ ratio {r}"
        );
    }
}

#[test]
fn trim_biases_balance_level_flight_and_the_plan_starts_in_trim() {
    let st = ModelStructure::longitudinal();
    let th = trimmed(&st);
    // Level flight, thrust along body x: L + T sin α = W, D = T cos α, Cm = 0.
    let k = constants();
    let qs = condition().qbar_pa() * k.S_m2;
    let get = |c, t| th[st.index_of(Param::new(c, t)).unwrap()];
    let cl = (k.mass_kg * G0_MPS2 - THRUST * ALPHA0.sin()) / qs;
    let cd = THRUST * ALPHA0.cos() / qs;
    assert!((get(C::CL, T::Bias) - (cl - 4.2 * ALPHA0)).abs() < 1e-10);
    assert!((get(C::CD, T::Bias) - (cd - 0.35 * ALPHA0)).abs() < 1e-10);
    assert!((get(C::Cm, T::Bias) - 0.7 * ALPHA0).abs() < 1e-12);
    let r = predict_crb(&lon_plan(three_two_one_one(&[1.0], 0.4, DEG, 10.0, DT))).unwrap();
    for (name, rate) in &r.trim_rates {
        assert!(rate.abs() < 1e-9, "{name} rate {rate} at trim");
    }
    // Untrimmed θ (biases 0) is visible in the rates.
    let mut plan = lon_plan(three_two_one_one(&[1.0], 0.4, DEG, 10.0, DT));
    plan.theta = derivatives(&st);
    let r = predict_crb(&plan).unwrap();
    assert!(r.trim_rates.iter().any(|(_, v)| v.abs() > 0.1));
    // Lateral: the trimmed biases of a symmetric aircraft are 0; the coupled model trims too.
    let lat = trimmed(&ModelStructure::lateral());
    assert!(lat.iter().zip(derivatives(&ModelStructure::lateral())).all(|(a, b)| a == &b));
    let six = ModelStructure::six_axis();
    let th6 = trimmed(&six);
    let model = FlightModel::new(six).unwrap();
    let c = condition();
    let u = model.inputs(&condition_sample(&k, &c, StateSet::Coupled, 0.0, [0.0; 3])).unwrap();
    let f = model.derivatives(&th6, &u, &condition_states(&c, StateSet::Coupled)).unwrap();
    assert!(f.iter().all(|v| v.abs() < 1e-9), "coupled trim rates {f:?}");
    // A structure without the bias to trim with is named.
    let no_cm0 = ModelStructure::empty()
        .with(C::CL, &[T::Bias, T::Alpha])
        .with(C::CD, &[T::Bias])
        .with(C::Cm, &[T::Alpha]);
    let err = trim_biases(&no_cm0, &[0.0; 4], &k, &c).unwrap_err();
    assert!(matches!(err, EstimatorError::InvalidConfig { field: "Cm_0", .. }), "{err:?}");
}

/// Monte Carlo check of the prediction: the plan simulated with the assumed θ (the same
/// model), white noise of the planned σ on every planned output, `seeds` fits by
/// [`fit`] (ML output error, R estimated, the plan's initial states estimated), and the
/// scatter of the estimates compared with the predicted σ.
///
/// With `seeds` draws the sample standard deviation has a relative standard error of about
/// `1/√(2(seeds − 1))` (7 % for 100), so ±30 % is a 4.2-standard-error band.
fn monte_carlo(plan: &DesignPlan, seeds: u64, check: &[&str]) {
    let pred = predict_crb(plan).unwrap();
    let Prepared { problem: p, beta, .. } = prepare(plan).unwrap();
    let mut y = Vec::new();
    p.simulate(&beta, &mut y, None).unwrap();
    let set = p.model.state_set();
    let clean = planned_samples(plan, set, &plan.manoeuvres[0]).unwrap();
    let ny = p.ny();
    let np = plan.structure.n_params();
    let mut config = OeConfig::new(plan.structure);
    config.outputs = Some(p.outputs.clone());
    config.initial_states = plan.initial_states;
    config.start = Start::Given(plan.theta.clone());
    let n01 = Normal::new(0.0, 1.0).unwrap();
    let mut est: Vec<Vec<f64>> = Vec::new();
    for seed in 0..seeds {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1000 + seed);
        let mut data = clean.clone();
        for (i, s) in data.iter_mut().enumerate() {
            for (j, sensor) in plan.sensors.iter().enumerate() {
                set_output(s, sensor.output, y[i * ny + j] + sensor.sigma * n01.sample(&mut rng));
            }
        }
        let res = fit(&[&data], &config).unwrap();
        est.push(res.values[..np].to_vec());
    }
    let k = seeds as f64;
    for (i, name) in plan.structure.names().enumerate() {
        let mean = est.iter().map(|e| e[i]).sum::<f64>() / k;
        let scatter = (est.iter().map(|e| (e[i] - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
        let crb = pred.sigma[i].unwrap();
        let ratio = scatter / crb;
        println!(
            "{name:>9} θ {:9.4} mean {mean:9.4} σ_CRB {crb:.5} scatter {scatter:.5} ratio {ratio:.3}",
            plan.theta[i]
        );
        if check.contains(&name) {
            assert!((0.7..=1.3).contains(&ratio), "{name}: Monte Carlo scatter / σ_CRB = {ratio}");
            let z = (mean - plan.theta[i]) / (crb / k.sqrt());
            assert!(z.abs() < 4.0, "{name}: mean of the estimates {z:.1} standard errors off");
        }
    }
}

#[test]
fn monte_carlo_scatter_matches_prediction_longitudinal_3211() {
    let mut plan = lon_plan(three_two_one_one(&[1.0], 0.4, 2.0 * DEG, 8.0, DT));
    plan.initial_states = InitialStates::Estimate([true; N_STATES]);
    let st = plan.structure;
    monte_carlo(&plan, 100, &derivative_names(&st));
}

#[test]
fn monte_carlo_scatter_matches_prediction_lateral_doublets() {
    let mut plan = lat_plan(8.0, 2.0 * DEG);
    plan.initial_states = InitialStates::Estimate([true; N_STATES]);
    let st = plan.structure;
    monte_carlo(&plan, 100, &derivative_names(&st));
}

#[test]
fn bad_plans_are_named() {
    let field = |plan: &DesignPlan| match predict_crb(plan) {
        Err(EstimatorError::InvalidConfig { field, .. }) => field,
        other => panic!("expected InvalidConfig, got {other:?}"),
    };
    let good = lon_plan(three_two_one_one(&[1.0], 0.4, DEG, 4.0, DT));
    assert!(predict_crb(&good).is_ok());
    let mut p = good.clone();
    p.theta.pop();
    assert_eq!(field(&p), "theta");
    let mut p = good.clone();
    p.theta[3] = f64::NAN;
    assert_eq!(field(&p), "theta");
    let mut p = good.clone();
    p.sensors[1].sigma = 0.0;
    assert_eq!(field(&p), "alpha_rad");
    let mut p = good.clone();
    p.sensors.push(Sensor { output: Output::P, sigma: 0.01 });
    assert_eq!(field(&p), "p_rad_s");
    let mut p = good.clone();
    p.sensors.clear();
    assert_eq!(field(&p), "sensors");
    let mut p = good.clone();
    p.manoeuvres.clear();
    assert_eq!(field(&p), "manoeuvres");
    let mut p = good.clone();
    p.manoeuvres[0].dt_s = -0.1;
    assert_eq!(field(&p), "dt_s");
    let mut p = good.clone();
    p.manoeuvres[0].da_rad = vec![0.0; 3];
    assert_eq!(field(&p), "da_rad");
    let mut p = good.clone();
    p.manoeuvres[0].de_rad.clear();
    assert_eq!(field(&p), "de_rad");
    let mut p = good.clone();
    p.repeats = 0;
    assert_eq!(field(&p), "repeats");
    let mut p = good.clone();
    p.singular_tolerance = 0.0;
    assert_eq!(field(&p), "singular_tolerance");
    let mut p = good.clone();
    p.constants.Iyy_kgm2 = None;
    assert_eq!(field(&p), "Iyy_kgm2");
    let mut p = good.clone();
    p.manoeuvres[0].de_rad[10] = f64::INFINITY;
    assert!(matches!(predict_crb(&p), Err(EstimatorError::NonFiniteInput { field: "de_rad", .. })));
    // An input far too large for the model: the simulated response leaves the domain.
    let big = lon_plan(three_two_one_one(&[1.0], 2.0, 60.0 * DEG, 20.0, DT));
    assert!(matches!(predict_crb(&big), Err(EstimatorError::Numerical { .. })));
}
