//! The closed-loop experiment's tests: the two-aircraft experiment, the F-16 adapter of the SMPE
//! engine, the thesis's gains, every scenario file, a never-NaN property, and the
//! sample-driven estimators in the closed loop (RLS against the true derivatives), the summary
//! keys and the scenario syntax.

use crate::common;

use aeroident_estimators::smpe::ParametricModel;
use aeroident_estimators::vocabulary::Param;
use aeroident_models::f16::{self, AeroIncrements, F16, F16Controls, F16State, IncrementReference};
use aeroident_pipelines::aircraft::experiment::{RunOutput, run};
use aeroident_pipelines::aircraft::increments::increment_matrix;
use aeroident_pipelines::aircraft::model::{F16IncrementModel, inverse_inertia};
use aeroident_pipelines::aircraft::scenario::{EstimatorSpec, Scenario};
use nalgebra::SVector;
use proptest::prelude::*;
use std::cell::Cell;
use std::path::PathBuf;
use std::rc::Rc;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scenario(text: &str) -> Scenario {
    Scenario::from_toml(text, "<test>").expect("valid test scenario")
}

fn p(name: &str) -> Param {
    Param::from_name(name).unwrap()
}

/// The thesis's four increments, in the order of the two-aircraft channels.
fn thesis_four() -> [Param; 4] {
    [p("Cm_alpha"), p("Cm_q"), p("CL_alpha"), p("CD_alpha")]
}

fn thesis_matrix(reference: IncrementReference, v: &[f64; 4]) -> AeroIncrements {
    let four = thesis_four();
    increment_matrix(
        reference,
        &[(four[0], v[0]), (four[1], v[1]), (four[2], v[2]), (four[3], v[3])],
    )
}

const FOUR_PARAMS: &str = r#"
[increments.Cm_alpha]
truth = TA
lower = 0.001
upper = 0.002
lambda_per_s = 1e-7
eta = 1e-10
gradient_gain = 1e6
[increments.Cm_q]
truth = TQ
lower = 0.005
upper = 0.05
lambda_per_s = 2e-4
eta = 1e-10
gradient_gain = 1e8
[increments.CL_alpha]
truth = TL
lower = 0.005
upper = 0.05
gradient_gain = 1e3
[increments.CD_alpha]
truth = TD
lower = 0.0005
upper = 0.005
gradient_gain = 1e3
"#;

const ALL_ESTIMATORS: &str = r#"
[[estimator]]
kind = "published"
reading = "implicit"
params = ["Cm_alpha", "Cm_q", "CL_alpha", "CD_alpha"]
[[estimator]]
kind = "published"
reading = "explicit"
params = ["Cm_alpha", "Cm_q", "CL_alpha", "CD_alpha"]
[[estimator]]
kind = "corrected"
information_per_s = 1e12
params = ["Cm_alpha", "Cm_q", "CL_alpha", "CD_alpha"]
[[estimator]]
kind = "mr-gradient"
params = ["Cm_alpha", "Cm_q", "CL_alpha", "CD_alpha"]
"#;

fn four(ta: f64, tq: f64, tl: f64, td: f64) -> String {
    FOUR_PARAMS
        .replace("TA", &ta.to_string())
        .replace("TQ", &tq.to_string())
        .replace("TL", &tl.to_string())
        .replace("TD", &td.to_string())
}

#[test]
fn analytic_zero_truth_no_excitation_estimators_hold_and_aircraft_identical() {
    let text = format!(
        "kind = \"run\"\nname = \"hold\"\nduration_s = 2.0\n{}{}",
        four(0.0, 0.0, 0.0, 0.0),
        ALL_ESTIMATORS
    );
    let out = run(&scenario(&text)).unwrap();
    for ch in &out.channels {
        assert!(ch.failure.is_none(), "{}: {:?}", ch.label, ch.failure);
        // The two aircraft are the same model with Δα = Δq = 0 (trim to round-off), so the
        // increments, whatever their value, do not act: identical to machine precision.
        for (x, xr) in ch.states.iter().zip(&out.reference) {
            for i in 0..f16::N_STATES {
                let tol = 1e-12 * xr[i].abs().max(1.0);
                assert!(
                    (x[i] - xr[i]).abs() <= tol,
                    "{} state {i}: {} vs {}",
                    ch.label,
                    x[i],
                    xr[i]
                );
            }
        }
        for l in &ch.params {
            let v0 = l.estimate[0].unwrap();
            for v in &l.estimate {
                let v = v.unwrap();
                match ch.kind {
                    // Corrected and gradient laws have zero update without excitation (up to the
                    // trim's round-off residual, ~1e-12, times the gains: ~2e-9 relative for the
                    // gradient law's 1e3 gain).
                    "corrected" | "mr-gradient" => {
                        assert!(
                            (v - v0).abs() <= 1e-8 * v0.abs(),
                            "{} {}: {v} vs {v0}",
                            ch.label,
                            l.param.name()
                        )
                    }
                    // Published: with z = z_m the estimator equation reduces to F(θ̂) = −η·θ̂ = 0,
                    // whose root 0 lies outside same-signed bounds. The scalar solver (C_L, C_D
                    // groups) then takes the least-|F| point, the bound nearest zero: the thesis
                    // form does NOT hold its estimate (documented flaw). The two-parameter C_m
                    // group's Newton solve accepts its start point because |F| = η|θ̂| ≈ 1e-13
                    // is below its tolerance, so it holds.
                    _ => {
                        let e = out.scenario.increment(l.param).unwrap();
                        let want =
                            if l.param.coefficient.name() == "Cm" { v0 } else { e.lower.unwrap() };
                        assert_eq!(v, want, "{} {}", ch.label, l.param.name());
                    }
                }
            }
        }
    }
}

/// SLJ §3.5 ADC with the textbook's literal constants (independent of our data file).
fn qbar_slj(vt: f64, alt: f64) -> f64 {
    let rho = 2.377e-3 * (1.0 - 0.703e-5 * alt).powf(4.14);
    0.5 * rho * vt * vt
}

fn logged_sample(out: &RunOutput, ch: usize, k: usize) -> (F16State, F16State, F16State, [f64; 4]) {
    let z = out.channels[ch].states[k];
    let zm = out.reference[k];
    let f = F16::new(out.scenario.trim.xcg).unwrap();
    let reference = IncrementReference {
        alpha_rad: out.trim.state[f16::ALPHA],
        elevator_rad: out.trim.controls.elevator_rad,
        ..Default::default()
    };
    let c = out.controls[k];
    let u = F16Controls::new(c[0], c[1], c[2], c[3]);
    let truth = out.epoch_at(out.t_s[k]).increments;
    assert_eq!(truth, thesis_matrix(reference, &[0.0015, 0.01, 0.01, 0.001]));
    let zdm = f.derivatives_with_increments(&zm, &u, &truth).unwrap();
    let logs = &out.channels[ch].params;
    let th: [f64; 4] = core::array::from_fn(|j| {
        assert_eq!(logs[j].param, thesis_four()[j]);
        logs[j].estimate[k].unwrap()
    });
    (z, zm, zdm, th)
}

#[test]
fn hand_gain_3_128_and_surface_derivative_3_106_at_a_logged_sample() {
    let text = format!(
        "kind = \"run\"\nname = \"k\"\nduration_s = 1.0\n[[input]]\nchannel = \"elevator\"\nkind = \"sine\"\namplitude_deg = 0.05\nfrequency_hz = 1.0\n{}{}",
        four(0.0015, 0.01, 0.01, 0.001),
        "[[estimator]]\nkind = \"published\"\nreading = \"implicit\"\nparams = [\"Cm_alpha\", \"Cm_q\", \"CL_alpha\", \"CD_alpha\"]\n"
    );
    let out = run(&scenario(&text)).unwrap();
    let k = 63;
    let (z, zm, zdm, th) = logged_sample(&out, 0, k);
    let f = F16::new(0.30).unwrap();
    let g = &f.data().geometry;
    let m = 1.0 / f.data().mass.inverse_mass_per_slug;
    let (vt, alpha, beta) = (z[f16::VT], z[f16::ALPHA], z[f16::BETA]);
    let qs = qbar_slj(vt, z[f16::ALT]) * g.wing_area_ft2;
    let da = alpha - out.trim.state[f16::ALPHA];
    let dq = z[f16::Q];
    let mu = |lo: f64, up: f64| (up / lo).sqrt();
    let diag = &out.channels[0].diagnostics[k];
    assert_eq!(diag.len(), 3, "groups C_m, C_L, C_D");

    // (3.117), (3.128): C_p, C_q, C_r = (a12, a22, a32)·q̄Sc̄.
    let a = inverse_inertia(&f);
    let (cp, cq, cr) =
        (a[(0, 1)] * qs * g.cbar_ft, a[(1, 1)] * qs * g.cbar_ft, a[(2, 1)] * qs * g.cbar_ft);
    let prq = z[f16::P] * cp + z[f16::Q] * cq + z[f16::R] * cr;
    let k_cm = (prq
        * (th[0] * (1.0 - 1.0 / mu(0.001, 0.002)) * da
            + th[1] * (1.0 - 1.0 / mu(0.005, 0.05)) * g.cbar_ft / (2.0 * vt) * dq))
        .abs()
        - 1e-10;
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    // The model uses SLJ's rounded moment constant c₇ = 1.792e-5 where a₂₂ = 1/I_yy =
    // 1.791665e-5: the only difference allowed is that ratio (on K + η).
    let c7_ratio = f.data().moment.c7 / a[(1, 1)];
    assert!(
        rel((diag[0].K + 1e-10) / (k_cm + 1e-10), c7_ratio) < 1e-9,
        "K (3.128): logged {} hand {} (c7 ratio {c7_ratio})",
        diag[0].K,
        k_cm
    );

    // (3.106): ṡ = Σ_{p,q,r} (z ż − z_m ż_m) + λ/2 Σ (z² − z_m²), ż from the model at θ̂.
    let reference = IncrementReference {
        alpha_rad: out.trim.state[f16::ALPHA],
        elevator_rad: out.trim.controls.elevator_rad,
        ..Default::default()
    };
    let c = out.controls[k];
    let u = F16Controls::new(c[0], c[1], c[2], c[3]);
    let zd = f.derivatives_with_increments(&z, &u, &thesis_matrix(reference, &th)).unwrap();
    let mut sdot = 0.0;
    for i in [f16::P, f16::Q, f16::R] {
        sdot += z[i] * zd[i] - zm[i] * zdm[i] + 1e-7 / 2.0 * (z[i] * z[i] - zm[i] * zm[i]);
    }
    assert!(
        (diag[0].sdot - sdot).abs() <= 1e-9 * sdot.abs().max(1e-18),
        "ṡ logged {} hand {sdot}",
        diag[0].sdot
    );

    // (3.145)/(3.153): z = Δα q̄S/(m V cos β). The engine's φ = ∂(Σ z ż)/∂θ also carries the
    // sliding state α (from α·α̇): K_engine = |ΔĈL (μ⁻¹ − 1) α z| − η. The printed (3.145)
    // lacks that factor α (see docs/reproduction-f16.md).
    let z_l = da * qs / (m * vt * beta.cos());
    let k_cl = (th[2] * (1.0 / mu(0.005, 0.05) - 1.0) * alpha * z_l).abs() - 1e-9;
    assert!(rel(diag[1].K, k_cl) < 1e-6, "K (3.153)·α: logged {} hand {}", diag[1].K, k_cl);

    // (3.161)/(3.159): z = (q̄S/m) Δα (V cos β − β sin β / V).
    let z_d = qs / m * da * (vt * beta.cos() - beta * beta.sin() / vt);
    let k_cd = (th[3] * (1.0 / mu(0.0005, 0.005) - 1.0) * z_d).abs() - 1e-9;
    assert!(rel(diag[2].K, k_cd) < 1e-6, "K (3.159): logged {} hand {}", diag[2].K, k_cd);
}

#[test]
fn fd_analytic_sensitivity_and_3_161_sign() {
    let f = F16::new(0.30).unwrap();
    let mut x = F16State::zeros();
    x[f16::VT] = 640.0;
    x[f16::ALPHA] = 0.06;
    x[f16::BETA] = 0.03;
    x[f16::PHI] = 0.1;
    x[f16::THETA] = 0.05;
    x[f16::P] = 0.02;
    x[f16::Q] = 0.03;
    x[f16::R] = -0.01;
    x[f16::ALT] = 18_000.0;
    x[f16::POW] = 40.0;
    let reference = IncrementReference { alpha_rad: 0.04, q_rad_s: 0.0, ..Default::default() };
    let theta = SVector::<f64, 4>::new(0.0015, 0.01, 0.01, 0.001);
    for wind in [[0.0; 3], [5.0, -3.0, 8.0]] {
        let mut u = F16Controls::new(0.5, -0.01, 0.0, 0.0);
        u.wind_ned_fps = wind;
        let m = F16IncrementModel::new(
            f.clone(),
            reference,
            thesis_four(),
            Rc::new(Cell::new(AeroIncrements { reference, ..AeroIncrements::zero() })),
        );
        let s = m.sensitivity(0.0, &x, &u, &theta).unwrap();
        for j in 0..4 {
            let h = 1e-4 * theta[j].abs().max(1e-3);
            let (mut tp, mut tm) = (theta, theta);
            tp[j] += h;
            tm[j] -= h;
            let fd = (m.derivatives(0.0, &x, &u, &tp).unwrap()
                - m.derivatives(0.0, &x, &u, &tm).unwrap())
                / (2.0 * h);
            for i in 0..f16::N_STATES {
                let tol = 1e-6 * fd[i].abs() + 1e-9;
                assert!(
                    (s[(i, j)] - fd[i]).abs() <= tol,
                    "wind {wind:?} ∂ẋ{i}/∂θ{j}: {} vs FD {}",
                    s[(i, j)],
                    fd[i]
                );
            }
        }
    }
    // (3.161) up to the sign absorbed by |·| in K: ∂(V V̇ + β β̇)/∂ΔCD_α = −(q̄S/m)Δα(V cosβ − β sinβ/V).
    let u = F16Controls::new(0.5, -0.01, 0.0, 0.0);
    let m = F16IncrementModel::new(
        f.clone(),
        reference,
        [p("CD_alpha")],
        Rc::new(Cell::new(AeroIncrements { reference, ..AeroIncrements::zero() })),
    );
    let th = SVector::<f64, 1>::new(0.001);
    let e = |t: f64| {
        let xd = m.derivatives(0.0, &x, &u, &SVector::<f64, 1>::new(t)).unwrap();
        x[f16::VT] * xd[f16::VT] + x[f16::BETA] * xd[f16::BETA]
    };
    let h = 1e-5;
    let fd = (e(th[0] + h) - e(th[0] - h)) / (2.0 * h);
    let qs = qbar_slj(x[f16::VT], x[f16::ALT]) * f.data().geometry.wing_area_ft2;
    let mass = 1.0 / f.data().mass.inverse_mass_per_slug;
    let (v, b) = (x[f16::VT], x[f16::BETA]);
    let printed = qs / mass * (x[f16::ALPHA] - 0.04) * (v * b.cos() - b * b.sin() / v);
    assert!((fd + printed).abs() < 1e-6 * printed.abs(), "FD {fd} vs −(3.161) {}", -printed);
}

/// The analytic sensitivity of the generalised increments (moments through c₃ c₄ c₇ c₉, the
/// side force through v̇) against central finite differences of the model.
#[test]
fn fd_analytic_sensitivity_of_lateral_and_control_increments() {
    let f = F16::new(0.30).unwrap();
    let mut x = F16State::zeros();
    x[f16::VT] = 640.0;
    x[f16::ALPHA] = 0.06;
    x[f16::BETA] = 0.03;
    x[f16::PHI] = 0.1;
    x[f16::THETA] = 0.05;
    x[f16::P] = 0.2;
    x[f16::Q] = 0.03;
    x[f16::R] = -0.05;
    x[f16::ALT] = 18_000.0;
    x[f16::POW] = 40.0;
    let reference =
        IncrementReference { alpha_rad: 0.04, elevator_rad: -0.03, ..Default::default() };
    let params = [p("Cl_p"), p("Cn_beta"), p("CY_beta"), p("Cm_de")];
    let theta = SVector::<f64, 4>::new(-0.1, 0.05, -0.2, -0.1);
    for wind in [[0.0; 3], [5.0, -3.0, 8.0]] {
        let mut u = F16Controls::new(0.5, -0.01, 0.02, -0.01);
        u.wind_ned_fps = wind;
        let m = F16IncrementModel::new(
            f.clone(),
            reference,
            params,
            Rc::new(Cell::new(AeroIncrements { reference, ..AeroIncrements::zero() })),
        );
        let s = m.sensitivity(0.0, &x, &u, &theta).unwrap();
        for j in 0..4 {
            let h = 1e-4;
            let (mut tp, mut tm) = (theta, theta);
            tp[j] += h;
            tm[j] -= h;
            let fd = (m.derivatives(0.0, &x, &u, &tp).unwrap()
                - m.derivatives(0.0, &x, &u, &tm).unwrap())
                / (2.0 * h);
            assert!(fd.amax() > 1e-6, "{}: no effect", params[j].name());
            for i in 0..f16::N_STATES {
                let tol = 1e-6 * fd[i].abs() + 1e-9;
                assert!(
                    (s[(i, j)] - fd[i]).abs() <= tol,
                    "wind {wind:?} ∂ẋ{i}/∂{}: {} vs FD {}",
                    params[j].name(),
                    s[(i, j)],
                    fd[i]
                );
            }
        }
    }
}

/// Order-of-magnitude and sign cross-check of the truth derivatives against JSBSim's F-16 at
/// the same condition (20,000 ft, 675 ft/s; `../shared/flightdata/jsbsim_samples/
/// f16_ail_rud_doublets_truth.json`, the same NASA TP-1538 data but JSBSim's cg, trim and
/// surface conventions — not an oracle). Terms whose definition is convention-free must agree
/// in sign and within a factor 1.5. Skipped with a message when the data set is absent, a
/// failure under CI.
#[test]
fn val_truth_derivatives_same_sign_and_order_as_jsbsim_f16() {
    // Absent: skipped with a message, a failure under CI (`common::shared`).
    let Some(path) = common::shared("jsbsim_samples/f16_ail_rud_doublets_truth.json") else {
        return;
    };
    let text = std::fs::read_to_string(&path).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let d = &json["derivatives"];
    let f = F16::new(0.30).unwrap();
    let t = aeroident_models::trim::trim(
        &f,
        &aeroident_models::trim::TrimCondition::level(20_000.0, 675.0),
    )
    .unwrap();
    let ld = aeroident_pipelines::aircraft::truth::local_derivatives(
        &f,
        &t.state,
        &t.controls,
        &AeroIncrements::zero(),
    )
    .unwrap();
    // (ours, JSBSim key): hats named phat/qhat/rhat there.
    for (ours, theirs) in [
        ("CL_alpha", "CL_alpha"),
        ("CL_q", "CL_qhat"),
        ("CY_beta", "CY_beta"),
        ("CY_r", "CY_rhat"),
        ("Cl_beta", "Cl_beta"),
        ("Cl_p", "Cl_phat"),
        ("Cl_r", "Cl_rhat"),
        ("Cm_q", "Cm_qhat"),
        ("Cm_de", "Cm_de"),
        ("Cn_beta", "Cn_beta"),
        ("Cn_r", "Cn_rhat"),
    ] {
        let a = ld.derivative(p(ours)).unwrap();
        let b = d[theirs].as_f64().unwrap();
        let ratio = a / b;
        assert!((1.0 / 1.5..=1.5).contains(&ratio), "{ours}: ours {a}, JSBSim {b}");
    }
}

fn scenario_files() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(workspace().join("scenarios/f16"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    v.push(workspace().join("scenarios/default.toml"));
    v
}

fn assert_finite(out: &RunOutput) {
    for ch in &out.channels {
        for l in &ch.params {
            assert!(
                l.estimate.iter().flatten().all(|v| v.is_finite()),
                "{}: non-finite estimate",
                ch.label
            );
        }
        for x in &ch.states {
            assert!(x.iter().all(|v| v.is_finite()), "{}: non-finite state", ch.label);
        }
    }
}

#[test]
fn every_scenario_file_parses_and_runs_shortened() {
    let files = scenario_files();
    assert!(files.len() >= 20, "expected every thesis case and the extra scenarios");
    for f in files {
        let mut sc = Scenario::from_path(&f).unwrap_or_else(|e| panic!("{e}"));
        sc.duration_s = sc.duration_s.min(0.3);
        let out = run(&sc).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_finite(&out);
        let sm = aeroident_pipelines::aircraft::summary::summarize(&out).unwrap();
        for p in &sm.parameters {
            for v in [p.reference, p.estimate, p.std_error, p.rel_error].into_iter().flatten() {
                assert!(v.is_finite(), "{}: {} {}", f.display(), p.estimator, p.name);
            }
        }
    }
}

#[test]
fn val_thesis_table_4_7_case_4_full_run_corrected_converges() {
    // Full 10 s run: the corrected estimator must settle within ±5 % of ΔCm_α = 0.0015 well
    // before the thesis's 0.4 s, the published-implicit one within the run.
    let sc = Scenario::from_path(&workspace().join("scenarios/f16/t4_7_case4.toml")).unwrap();
    let out = run(&sc).unwrap();
    let s = aeroident_pipelines::aircraft::summary::summarize(&out).unwrap();
    let get = |label: &str| s.parameters.iter().find(|p| p.estimator == label).unwrap();
    assert!(get("corrected").convergence_time_s.is_some_and(|t| t < 0.4), "{:?}", get("corrected"));
    assert!(
        get("published-implicit").rel_error.is_some_and(|e| e.abs() < 0.05),
        "{:?}",
        get("published-implicit")
    );
}

/// The exact key sets of `summary.json` and of its parameter entries (the target metrics beside
/// the convergence times), on the shortened default run; the default is six-axis RLS. A key
/// renamed or dropped breaks every reader of the summary, so the set is pinned.
#[test]
fn default_scenario_writes_outputs_with_exact_summary_keys() {
    let sc = Scenario::from_toml(aeroident::cli::run::DEFAULT_SCENARIO, "default").unwrap();
    let dir = std::env::temp_dir().join(format!("aeroident-test-default-{}", std::process::id()));
    let s =
        aeroident::cli::run::run_one(&Scenario { duration_s: 1.0, ..sc }, &dir, &[], true).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let keys = |v: &serde_json::Value| {
        let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    };
    let mut want = vec![
        "schema_version",
        "scenario",
        "estimator",
        "solver",
        "realtime_factor",
        "parameters",
        "reconvergence_time_s",
        "trim",
        "excitation_start_s",
        "damage_at_s",
        "angular_accelerations",
        "sample_lag_s",
        "targets",
        "batch_fits",
        "events",
    ];
    want.sort();
    assert_eq!(keys(&json), want);
    // One events entry per sample-driven estimator, every kind counted.
    for e in json["events"].as_array().unwrap() {
        assert_eq!(keys(e), ["counts", "estimator", "listed", "not_listed"]);
        assert_eq!(keys(&e["counts"]), ["change_detected", "reanchor", "restart"]);
    }
    let mut want_p = common::PARAMETER_KEYS.to_vec();
    want_p.extend([
        "estimator",
        "quantity",
        "primary",
        "truth_before",
        "truth_after",
        "step_at_s",
        "rel_error",
        "covers_truth_2sigma",
        "convergence_time_s",
        "first_within_s",
        "thesis_convergence_time_s",
        "thesis_note",
        "reconvergence_time_s",
        "time_to_10pct_s",
        "reconvergence_10pct_s",
        "meets_targets",
        "failure",
        "estimator_status",
        "batch",
    ]);
    want_p.sort();
    for p in json["parameters"].as_array().unwrap() {
        assert_eq!(keys(p), want_p);
    }
    // Five estimators (rls, ftr, ekf, smpe-corrected, smpe-finite-time), each over the
    // six-axis preset.
    for est in ["rls", "ftr", "ekf", "smpe-corrected", "smpe-finite-time"] {
        let n = s.parameters.iter().filter(|p| p.estimator == est).count();
        assert_eq!(n, 30, "{est}: six-axis preset");
    }
    assert_eq!(s.parameters.len(), 150);
    assert_eq!(json["damage_at_s"], 20.0);
    assert_eq!(json["targets"][0]["total"], 11);
    let cm_a = s.parameters.iter().find(|p| p.name == "Cm_alpha").unwrap();
    assert_eq!(cm_a.quantity, "derivative");
    // 30 % of the pitch stiffness lost: the truth after is 0.7 × the truth before.
    let (b, a) = (cm_a.truth_before.unwrap(), cm_a.truth_after.unwrap());
    assert!(b < 0.0 && (a - 0.7 * b).abs() < 1e-12, "{b} → {a}");
    for f in ["timeseries.csv", "controls.png", "convergence.png", "tracking.png"] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// RLS on the six-axis preset in the closed loop, noise-free, still air, small orthogonal
/// multisines (nonlinearity negligible), no forgetting: every primary derivative within 1 %
/// of the reference F-16's true local derivative (finite differences of its tables at trim).
#[test]
fn val_rls_closed_loop_noise_free_recovers_true_derivatives() {
    let mut text = String::from("kind = \"run\"\nname = \"rls-clean\"\nduration_s = 10.0\n");
    for (k, (ch, a)) in [("elevator", 0.1), ("aileron", 0.15), ("rudder", 0.15)].iter().enumerate()
    {
        text += &format!(
            "[[input]]\nchannel = \"{ch}\"\nkind = \"orthogonal_multisine\"\namplitude_deg = {a}\nbase_period_s = 10.0\nharmonics = [2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]\ninputs = 3\nindex = {k}\n"
        );
    }
    text += "[[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\n";
    let out = run(&scenario(&text)).unwrap();
    let s = aeroident_pipelines::aircraft::summary::summarize(&out).unwrap();
    let primary: Vec<_> = s.parameters.iter().filter(|p| p.primary).collect();
    assert_eq!(primary.len(), 11);
    for p in primary {
        let (f, t) = (p.estimate.unwrap(), p.reference.unwrap());
        assert!(((f - t) / t).abs() < 0.01, "{}: {f} vs truth {t}", p.name);
    }
    assert!(out.channels[0].failure.is_none());
    assert_eq!(out.channels[0].status, Some("running"));
}

/// The headline of docs/reproduction-f16.md: in every thesis table case (4.7–4.10) the
/// corrected estimator settles within ±5 % of the increment in ≤ 0.22 s (noise-free).
#[test]
fn val_corrected_settles_every_thesis_table_case() {
    let mut n = 0;
    for f in scenario_files() {
        let mut sc = Scenario::from_path(&f).unwrap();
        if !sc.thesis_table.as_deref().is_some_and(|t| t.starts_with("4."))
            || sc.name.starts_with("mr")
        {
            continue;
        }
        sc.estimator.retain(|e| matches!(e, EstimatorSpec::Corrected { .. }));
        let s = aeroident_pipelines::aircraft::summary::summarize(&run(&sc).unwrap()).unwrap();
        for p in &s.parameters {
            assert!(
                p.convergence_time_s.is_some_and(|t| t <= 0.22 + 1e-9),
                "{}: {} settles at {:?}",
                sc.name,
                p.name,
                p.convergence_time_s
            );
            n += 1;
        }
    }
    assert_eq!(n, 12, "the twelve table cases");
}

/// The old syntax and impossible increments are refused with a message saying what to write.
#[test]
fn old_syntax_and_inexpressible_increments_are_clear_errors() {
    let old = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[params.dCm_alpha]\ntruth = 0.0015\nlower = 0.001\nupper = 0.002\n[[estimator]]\nkind = \"corrected\"\nparams = [\"dCm_alpha\"]\n";
    let e = Scenario::from_toml(old, "o.toml").unwrap_err().to_string();
    assert!(e.contains("[increments.Cm_alpha]") && e.contains("old syntax"), "{e}");
    let list = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[increments.Cm_alpha]\nlower = 0.001\nupper = 0.002\n[[estimator]]\nkind = \"corrected\"\nparams = [\"dCm_alpha\"]\n";
    let e = Scenario::from_toml(list, "o.toml").unwrap_err().to_string();
    assert!(e.contains("estimator[0].params") && e.contains("write `Cm_alpha`"), "{e}");
    let grad = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[increments.Cm_q]\nlower = 0.005\nupper = 0.05\ngradient_gain = 1e8\n[[estimator]]\nkind = \"gradient\"\nparams = [\"Cm_q\"]\n";
    let e = Scenario::from_toml(grad, "o.toml").unwrap_err().to_string();
    assert!(e.contains("mr-gradient"), "{e}");
    let dot = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[increments.Cm_alphadot]\ntruth = -1.0\n[[estimator]]\nkind = \"rls\"\nmodel = \"longitudinal\"\n";
    let e = Scenario::from_toml(dot, "o.toml").unwrap_err().to_string();
    assert!(e.contains("increments.Cm_alphadot") && e.contains("alphadot"), "{e}");
    // Every factory kind is accepted; an option a kind does not take is named.
    for kind in ["rls", "ftr", "ekf", "smpe", "smpe-corrected", "gradient"] {
        let t = format!(
            "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"{kind}\"\nmodel = \"six-axis\"\n"
        );
        Scenario::from_toml(&t, "o.toml").unwrap();
    }
    let t = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"ekf\"\nmodel = \"six-axis\"\nforgetting = 0.99\n";
    let e = Scenario::from_toml(t, "o.toml").unwrap_err().to_string();
    assert!(e.contains("estimator[0]") && e.contains("unknown option `forgetting`"), "{e}");
    // FTR's grid: three numbers, a valid grid; rls does not take it.
    let ftr = |grid: &str, kind: &str| {
        format!(
            "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"{kind}\"\nmodel = \"six-axis\"\ngrid_hz = {grid}\n"
        )
    };
    Scenario::from_toml(&ftr("[0.1, 1.7, 0.04]", "ftr"), "o.toml").unwrap();
    let e = Scenario::from_toml(&ftr("[0.1, 1.7]", "ftr"), "o.toml").unwrap_err().to_string();
    assert!(e.contains("estimator[0]") && e.contains("`grid_hz` must be"), "{e}");
    let e = Scenario::from_toml(&ftr("[1.7, 0.1, 0.04]", "ftr"), "o.toml").unwrap_err().to_string();
    assert!(e.contains("f_min_hz/f_step_hz/f_max_hz"), "{e}");
    let e = Scenario::from_toml(&ftr("[0.1, 1.7, 0.04]", "rls"), "o.toml").unwrap_err().to_string();
    assert!(e.contains("unknown option `grid_hz`"), "{e}");
    let typo = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\nforgeting = 0.99\n";
    let e = Scenario::from_toml(typo, "o.toml").unwrap_err().to_string();
    assert!(e.contains("forgeting"), "{e}");
    let model = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"rls\"\nmodel = [\"Cm_alpha\", \"Cm_qq\"]\n";
    let e = Scenario::from_toml(model, "o.toml").unwrap_err().to_string();
    assert!(e.contains("estimator[0].model") && e.contains("Cm_qq"), "{e}");
}

/// Any increment over the vocabulary acts on the reference aircraft, including sudden damage
/// on lateral terms, and the sample-driven estimator sees the change in its truth.
#[test]
fn lateral_damage_changes_the_rls_truth_by_the_increment() {
    let text = "kind = \"run\"\nname = \"lat\"\nduration_s = 1.0\n[increments.Cn_beta]\ntruth = -0.05\nstep_to = 0.02\nstep_at_s = 0.5\n[[estimator]]\nkind = \"rls\"\nmodel = \"lateral\"\n";
    let out = run(&scenario(text)).unwrap();
    let l = out.channels[0].param(p("Cn_beta")).unwrap();
    let (before, after) = (l.truth[0].unwrap(), l.truth.last().unwrap().unwrap());
    let nominal = aeroident_pipelines::aircraft::truth::local_derivatives(
        &F16::new(0.30).unwrap(),
        &out.trim.state,
        &out.trim.controls,
        &AeroIncrements::zero(),
    )
    .unwrap()
    .derivative(p("Cn_beta"))
    .unwrap();
    assert!((before - (nominal - 0.05)).abs() < 1e-9, "{before} vs {nominal} − 0.05");
    assert!((after - (nominal + 0.02)).abs() < 1e-9, "{after}");
    assert_eq!(out.epochs.len(), 2);
    assert_eq!(out.epochs[1].from_s, 0.5);
}

#[test]
fn bad_scenario_names_the_field() {
    let text = format!(
        "kind = \"run\"\nname = \"bad\"\nduration_s = 1.0\n{}{}",
        four(0.0, 0.0, 0.0, 0.0),
        ALL_ESTIMATORS
    )
    .replace("lower = 0.001", "lower = 0.003");
    let err = Scenario::from_toml(&text, "x.toml").unwrap_err().to_string();
    assert!(err.contains("x.toml") && err.contains("increments.Cm_alpha.lower"), "{err}");
    let err = Scenario::from_toml(
        "kind = \"run\"\nname = \"x\"\nduration_s = 1.0\nbogus = 1\n",
        "y.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("y.toml") && err.contains("bogus"), "{err}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, .. ProptestConfig::default() })]
    #[test]
    fn prop_estimators_never_output_non_finite(
        ta in 0.001f64..0.002, tq in 0.005f64..0.05, tl in 0.005f64..0.05, td in 0.0005f64..0.005,
        amp_deg in -1.0f64..1.0, freq_hz in 0.1f64..3.0, seed in 0u64..1000, noise in any::<bool>(),
    ) {
        let text = format!(
            "kind = \"run\"\nname = \"p\"\nduration_s = 0.6\n[[input]]\nchannel = \"elevator\"\nkind = \"sine\"\namplitude_deg = {amp_deg}\nfrequency_hz = {freq_hz}\n[sensors]\nnoise = {noise}\nseed = {seed}\n{}{}",
            four(ta, tq, tl, td), ALL_ESTIMATORS
        );
        let out = run(&scenario(&text)).unwrap();
        for ch in &out.channels {
            for l in &ch.params {
                let (lo, up) = out.scenario.increment(l.param).unwrap().bounds().unwrap();
                for v in &l.estimate {
                    let v = v.unwrap();
                    prop_assert!(v.is_finite() && v >= lo && v <= up, "{} {} = {v}", ch.label, l.param.name());
                }
            }
        }
    }
}

/// The reference aircraft flies the pilot's input as the continuous function of time it is
/// (a real surface moves continuously; the recorded surface sample is its position at the
/// sample instant), not a staircase held over each 0.01 s step. Independent check: the F-16
/// integrated from the same trim with 100 RK4 sub-steps per sample, each holding the input of
/// its midpoint (second order in the 0.1 ms sub-step). A staircase at the run's step lags the
/// input by dt/2 = 5 ms on average: at 1.5 Hz with 1° elevator and 2° rudder that is a q, r
/// error of 3 % of the swing (measured with the staircase: q 1.0e-3 rad/s of 3.1e-2), 3000× the
/// tolerance below; the continuous input leaves 1e-8 to 2e-7 of the swing.
#[test]
fn analytic_reference_flies_the_continuous_pilot_input() {
    use aeroident_models::integrate::rk4_step;
    use aeroident_models::trim::{TrimCondition, trim};
    let text = "kind = \"run\"\nname = \"continuous-input\"\nduration_s = 2.0\ndt_s = 0.01\n\
        [[input]]\nchannel = \"elevator\"\nkind = \"sine\"\namplitude_deg = 1.0\nfrequency_hz = 1.5\n\
        [[input]]\nchannel = \"rudder\"\nkind = \"sine\"\namplitude_deg = 2.0\nfrequency_hz = 1.3\n\
        [[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\n";
    let sc = scenario(text);
    let out = run(&sc).unwrap();
    let f = F16::new(sc.trim.xcg).unwrap();
    let t0 = trim(&f, &TrimCondition::level(sc.trim.alt_ft, sc.trim.vt_fps)).unwrap();
    let pilot = |t: f64| {
        let mut u = t0.controls;
        u.elevator_rad += 1.0_f64.to_radians() * (2.0 * std::f64::consts::PI * 1.5 * t).sin();
        u.rudder_rad += 2.0_f64.to_radians() * (2.0 * std::f64::consts::PI * 1.3 * t).sin();
        u
    };
    let (sub, dt) = (100, sc.dt_s);
    let mut x = t0.state;
    let (mut worst, mut swing) = ([0.0_f64; 3], [0.0_f64; 3]);
    for (k, xr) in out.reference.iter().enumerate() {
        // The run logs the controls it flew at the sample instant: the pilot's.
        let u = pilot(out.t_s[k]);
        assert!((out.controls[k][1] - u.elevator_rad).abs() < 1e-12);
        for (j, i) in [f16::Q, f16::R, f16::BETA].into_iter().enumerate() {
            worst[j] = worst[j].max((xr[i] - x[i]).abs());
            swing[j] = swing[j].max((xr[i] - t0.state[i]).abs());
        }
        for s in 0..sub {
            let t = out.t_s[k] + s as f64 * dt / sub as f64;
            let h = dt / sub as f64;
            x = rk4_step(&f, t, &x, &pilot(t + 0.5 * h), h).unwrap();
        }
    }
    for (j, name) in ["q", "r", "beta"].iter().enumerate() {
        assert!(
            worst[j] < 1e-5 * swing[j],
            "{name}: largest difference {:e} against a swing of {:e}",
            worst[j],
            swing[j]
        );
    }
}

/// What each sample-driven estimator is fed unless told: the EKF (a recursive output error with
/// its own flight model) the unsmoothed samples without the differentiated accelerations, the
/// equation-error estimators the matched-smoother samples they regress on
/// (`SampleEstimatorSpec::raw_samples`; docs/uncertainty.md, "EKF: the raw feed by default").
#[test]
fn the_ekf_is_fed_raw_samples_unless_told_smoothed() {
    use aeroident_pipelines::aircraft::scenario::EstimatorSpec;
    let feed = |kind: &str, extra: &str| {
        let t = format!(
            "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"{kind}\"\nmodel = \"six-axis\"\n{extra}"
        );
        match &scenario(&t).estimator[0] {
            EstimatorSpec::Sample(s) => s.raw_samples(),
            other => panic!("{kind}: not sample-driven: {other:?}"),
        }
    };
    assert!(feed("ekf", ""), "ekf defaults to the raw feed");
    assert!(feed("ekf", "samples = \"raw\"\n"));
    assert!(!feed("ekf", "samples = \"smoothed\"\n"), "ekf on request smoothed");
    for kind in ["rls", "ftr", "smpe-corrected", "gradient"] {
        assert!(!feed(kind, ""), "{kind} regresses on the smoothed samples");
    }
    let t = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"ekf\"\nmodel = \"six-axis\"\nsamples = \"filtered\"\n";
    let e = Scenario::from_toml(t, "o.toml").unwrap_err().to_string();
    assert!(e.contains("estimator[0]") && e.contains("`samples` must be"), "{e}");
    let t = "kind = \"run\"\nname = \"o\"\nduration_s = 1.0\n[[estimator]]\nkind = \"rls\"\nmodel = \"six-axis\"\nsamples = \"raw\"\n";
    let e = Scenario::from_toml(t, "o.toml").unwrap_err().to_string();
    assert!(e.contains("unknown option `samples`"), "{e}");
}
