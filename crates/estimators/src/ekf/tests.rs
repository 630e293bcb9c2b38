use super::*;
use crate::flight_model::{STATE_NAMES, state};
use crate::sample::AircraftConstants;
use crate::test_aircraft::{self, ALPHA0, V0, doublet};
use crate::vocabulary::{Coefficient as C, Param, Term as T};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::vec::Vec;

/// The F-16-like test aircraft ([`crate::test_aircraft`]) without a reference airspeed.
fn constants() -> AircraftConstants {
    AircraftConstants { v0_mps: None, ..test_aircraft::constants() }
}

/// True six-axis derivatives of the synthetic aircraft (biases set by the level trim).
fn truth() -> (ModelStructure, [f64; MAX_PARAMS]) {
    let st = ModelStructure::six_axis();
    let mut th = [0.0; MAX_PARAMS];
    th[..st.n_params()].copy_from_slice(&test_aircraft::trimmed_truth(&st));
    (st, th)
}

/// Known white sensor noise σ of the synthetic record (per output index).
const NOISE: [f64; N_OUTPUTS] = [
    0.15, 0.0017, 0.0017, 0.0017, 0.0017, 0.0017, 0.0017, 0.0017, 0.05, 0.05, 0.05, 0.05, 0.05,
    0.05,
];

/// Simulates the coupled six-axis model with the true parameters from trim, with doublets on
/// δe (1 s), δa (7 s) and δr (12 s), at `rate` Hz for `duration` s (RK4, 4 substeps, inputs
/// linear between samples as the filter assumes), and returns noisy samples (no angular
/// accelerations, clean controls).
fn simulate(rate: f64, duration: f64, seed: u64) -> Vec<AirDataSample> {
    simulate_with_step(rate, duration, seed, None)
}

/// [`simulate`] with an optional step of one six-axis parameter `(param, at_s, new value)`.
fn simulate_with_step(
    rate: f64,
    duration: f64,
    seed: u64,
    step_change: Option<(Param, f64, f64)>,
) -> Vec<AirDataSample> {
    simulate_full(rate, duration, seed, step_change, [0.0; 8], 0.0)
}

/// [`simulate_with_step`] with white process noise of intensity `process[i]` (units per √s,
/// full-state order) on each true state: an increment `process[i] √dt N(0, 1)` after each
/// sample interval, the discrete form of `ẋ = f + w`, `E[w wᵀ] = diag(process²) δ(t)`; the
/// inputs start `lead_s` later (steady flight before the manoeuvre).
fn simulate_full(
    rate: f64,
    duration: f64,
    seed: u64,
    step_change: Option<(Param, f64, f64)>,
    process: [f64; 8],
    lead_s: f64,
) -> Vec<AirDataSample> {
    let (st, th0) = truth();
    let mut th = th0;
    let model = FlightModel::new(st).unwrap();
    let np = st.n_params();
    let k = constants();
    let controls = |t: f64| {
        let t = t - lead_s;
        (
            doublet(t, 1.0, 0.6, 0.035) + doublet(t, 16.0, 0.4, -0.03),
            -doublet(t, 7.0, 0.5, 0.05) - doublet(t, 18.0, 0.5, -0.05),
            doublet(t, 11.0, 1.0, 0.08) + doublet(t, 21.0, 0.8, -0.08),
        )
    };
    let base = |t: f64, x: &[f64; 8]| test_aircraft::sample(t, x, controls(t), k);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let n01 = Normal::new(0.0, 1.0).unwrap();
    let mut x = [V0, ALPHA0, 0.0, 0.0, 0.0, 0.0, 0.0, ALPHA0];
    let dt = 1.0 / rate;
    let n = (duration * rate) as usize;
    let mut out = Vec::with_capacity(n);
    let z8 = [0.0; 8];
    for step in 0..n {
        let t = step as f64 * dt;
        if let Some((p, at_s, value)) = step_change
            && t >= at_s
        {
            th[st.index_of(p).unwrap()] = value;
        }
        let u0 = model.inputs(&base(t, &x)).unwrap();
        let d = model.eval(&th[..np], &u0, &x, &z8, &z8, None).unwrap();
        let mut s = base(t, &x);
        let mut noisy = |v: f64, o: Output| v + NOISE[o.index()] * n01.sample(&mut rng);
        s.vt_mps = noisy(s.vt_mps, Output::Vt);
        s.alpha_rad = noisy(s.alpha_rad, Output::Alpha);
        for (o, i) in [
            (Output::Beta, 2),
            (Output::P, 3),
            (Output::Q, 4),
            (Output::R, 5),
            (Output::Phi, 6),
            (Output::Theta, 7),
        ] {
            let v = noisy(x[i], o);
            test_aircraft::set_output(&mut s, o, v);
        }
        s.ax_mps2 = Some(noisy(d.accel[0], Output::Ax));
        s.ay_mps2 = Some(noisy(d.accel[1], Output::Ay));
        s.az_mps2 = Some(noisy(d.accel[2], Output::Az));
        out.push(s);
        // Integrate to the next sample with inputs linear between the two samples.
        let u1 = model.inputs(&base((step + 1) as f64 * dt, &x)).unwrap();
        let sub = 4;
        let h = dt / sub as f64;
        for j in 0..sub {
            let ua = ModelInputs::lerp(&u0, &u1, j as f64 / sub as f64);
            let um = ModelInputs::lerp(&u0, &u1, (j as f64 + 0.5) / sub as f64);
            let ub = ModelInputs::lerp(&u0, &u1, (j as f64 + 1.0) / sub as f64);
            let f = |u: &ModelInputs, x: &[f64; 8]| {
                model.eval(&th[..np], u, x, &z8, &z8, None).unwrap().xdot
            };
            let k1 = f(&ua, &x);
            let x2: [f64; 8] = core::array::from_fn(|i| x[i] + 0.5 * h * k1[i]);
            let k2 = f(&um, &x2);
            let x3: [f64; 8] = core::array::from_fn(|i| x[i] + 0.5 * h * k2[i]);
            let k3 = f(&um, &x3);
            let x4: [f64; 8] = core::array::from_fn(|i| x[i] + h * k3[i]);
            let k4 = f(&ub, &x4);
            for i in 0..8 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        for (xi, q) in x.iter_mut().zip(process) {
            if q > 0.0 {
                *xi += q * dt.sqrt() * n01.sample(&mut rng);
            }
        }
    }
    out
}

fn config(st: ModelStructure) -> EkfConfig {
    let mut cfg = EkfConfig::new(st);
    cfg.measurement_sigma = NOISE;
    cfg
}

/// Runs `st` on the synthetic record and checks every parameter against the stated
/// tolerance: the primary derivatives ([`PRIMARY`]) within 10 % of the truth; every other
/// parameter within 10 % of its truth where the truth is above 5 % of the coefficient's largest
/// derivative (the accuracy target), else within 5 % of that largest derivative, **or** within
/// 3 σ (secondary derivatives such as `CY_r`, `Cn_p` move the outputs by less than the sensor
/// noise with doublets; the filter must then say so by its σ); and ±3σ covers the truth for at
/// least 80 % of all parameters.
/// Primary derivatives: held to 10 % without a σ allowance.
const PRIMARY: [&str; 15] = [
    "CL_alpha", "CL_de", "CD_alpha", "Cm_alpha", "Cm_q", "Cm_de", "CY_beta", "CY_dr", "Cl_beta",
    "Cl_p", "Cl_da", "Cl_dr", "Cn_beta", "Cn_r", "Cn_dr",
];

fn recover(st: ModelStructure) {
    let (st6, th6) = truth();
    let data = simulate(50.0, 25.0, 7);
    let mut ekf = Ekf::new(config(st)).unwrap();
    for s in &data {
        ekf.update(s).unwrap();
    }
    let e = *ekf.estimates();
    let mut covered = 0;
    let mut failures = Vec::new();
    for (i, p) in st.params().enumerate() {
        let truth = th6[st6.index_of(p).unwrap()];
        let largest = st6
            .terms_of(p.coefficient)
            .filter(|t| *t != T::Bias)
            .map(|t| th6[st6.index_of(Param::new(p.coefficient, t)).unwrap()].abs())
            .fold(0.0, f64::max);
        let got = e.value(i).unwrap_or_else(|| panic!("{} not identified", p.name()));
        let sigma = e.sigma(i).unwrap();
        let err = (got - truth).abs();
        let primary = PRIMARY.contains(&p.name());
        let tol = if primary || truth.abs() > 0.05 * largest {
            0.1 * truth.abs()
        } else {
            0.05 * largest
        };
        let tol = if primary { tol } else { tol.max(3.0 * sigma) };
        std::println!("{:>10} truth {truth:9.4} est {got:9.4} ± {sigma:.4}", p.name());
        if err > tol {
            failures.push(std::format!("{}: {got} vs truth {truth} (tolerance {tol})", p.name()));
        }
        if err <= 3.0 * sigma {
            covered += 1;
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
    let n = st.n_params();
    assert!(covered * 5 >= n * 4, "±3σ covers the truth for {covered} of {n}");
    assert_eq!(e.status, Status::Running);
}

#[test]
fn synthetic_recovery_longitudinal() {
    recover(ModelStructure::longitudinal());
}

#[test]
fn synthetic_recovery_lateral() {
    recover(ModelStructure::lateral());
}

#[test]
fn synthetic_recovery_coupled_six_axis() {
    recover(ModelStructure::six_axis());
}

/// A record without a sideslip channel: the filter starts β at 0 and carries it as a state,
/// seen through `ay`, `p`, `r`; the primary lateral derivatives are recovered within 10 % and
/// the sideslip it ends with is the record's (removed) one within 4 sensor σ. `CY_0` is left
/// out: without β its level and a constant sideslip are the same unknown. (With β's process
/// noise estimated from the record, as for a measured β, `CY_β` ended at −0.50, `Cn_r` −0.92.)
#[test]
fn an_unmeasured_sideslip_is_carried_as_a_state() {
    let (st6, th6) = truth();
    let mut st = ModelStructure::lateral();
    st.remove(Param::new(C::CY, T::Bias));
    let data = simulate(50.0, 25.0, 7);
    let mut ekf = Ekf::new(config(st)).unwrap();
    for s in &data {
        let mut s = *s;
        s.beta_rad = None;
        ekf.update(&s).unwrap();
    }
    let e = *ekf.estimates();
    assert_eq!(e.status, Status::Running);
    for name in ["CY_beta", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr"] {
        let p = Param::from_name(name).unwrap();
        let truth = th6[st6.index_of(p).unwrap()];
        let got = e.value(st.index_of(p).unwrap()).unwrap();
        assert!((got - truth).abs() < 0.1 * truth.abs(), "{name}: {got} vs truth {truth}");
    }
    let last = data.last().unwrap().beta_rad.unwrap();
    let beta = ekf.state(state::BETA).unwrap();
    assert!((beta - last).abs() < 4.0 * NOISE[Output::Beta.index()], "β {beta} vs {last}");
}

/// The book's pitch-damping normalisation with the reference speed, term `q0` = q c̄/(2 V0)
/// (Jategaonkar 2015 eq. 5.86), on records as thin as the HFB-320's (10 Hz, one elevator
/// doublet in 10 s): the synthetic record, generated with `Cm_q` on q c̄/(2V) and given `V0`
/// = the trim speed, is the same moment with `Cm_q0` = `Cm_q` · V0/V. The filter identifies
/// `Cm_q0` and ends within 10 % of the regression of the true damping moment `Cm_q q c̄/(2V)`
/// on `q c̄/(2 V0)` over the record's own samples (about `Cm_q`: V stays within a few % of
/// V0) on each of 3 seeds. With the catch-all prior `q0` had before (0 ± 1, a fifteenth of a
/// typical `Cm_q`) it ended 20–30 % short on each (measured −9.8 to −11.1 against −14), and
/// on the HFB-320 record it was never identified.
#[test]
fn pitch_damping_normalised_by_the_reference_speed_is_identified() {
    let (st6, th6) = truth();
    let mut st = ModelStructure::longitudinal();
    st.remove(Param::new(C::Cm, T::Q));
    st.insert(Param::new(C::Cm, T::Q0));
    let cm_q = th6[st6.index_of(Param::new(C::Cm, T::Q)).unwrap()];
    let i = st.index_of(Param::new(C::Cm, T::Q0)).unwrap();
    for seed in 0..3 {
        let mut data = simulate(10.0, 10.0, 7 + seed);
        let (mut num, mut den) = (0.0, 0.0);
        for s in &mut data {
            s.constants.v0_mps = Some(V0);
            let q = s.q_rad_s.unwrap();
            num += cm_q * (q / s.vt_mps) * (q / V0);
            den += (q / V0) * (q / V0);
        }
        let truth = num / den;
        let ekf = run(config(st), &data);
        let e = ekf.estimates();
        let got = e.value(i).expect("Cm_q0 not identified");
        std::println!(
            "seed {seed}: Cm_q0 {got:.3} ± {:.3} (truth {truth:.3})",
            e.sigma(i).unwrap()
        );
        assert!((got - truth).abs() < 0.1 * truth.abs(), "Cm_q0 {got} vs {truth}");
    }
}

fn running_filter(st: ModelStructure) -> (Ekf, Vec<AirDataSample>) {
    let data = simulate(50.0, 4.0, 3);
    let mut ekf = Ekf::new(config(st)).unwrap();
    for s in &data[..100] {
        ekf.update(s).unwrap();
    }
    (ekf, data)
}

fn snapshot(ekf: &Ekf) -> (Estimates, [Option<f64>; 8], Vec<f64>) {
    let cov = (0..ekf.np).map(|i| ekf.filter_sigma(i).unwrap()).collect();
    (*ekf.estimates(), core::array::from_fn(|i| ekf.state(i)), cov)
}

#[test]
fn refusing_a_bad_sample_leaves_the_state_unchanged() {
    let (mut ekf, data) = running_filter(ModelStructure::longitudinal());
    let before = snapshot(&ekf);
    let mut bad = data[100];
    bad.q_rad_s = Some(f64::NAN);
    assert!(matches!(
        ekf.update(&bad),
        Err(EstimatorError::NonFiniteInput { field: "q_rad_s", .. })
    ));
    assert_eq!(snapshot(&ekf), before);
    let mut bad = data[100];
    bad.t_s = data[99].t_s;
    assert!(matches!(ekf.update(&bad), Err(EstimatorError::NonFiniteInput { field: "dt_s", .. })));
    assert_eq!(snapshot(&ekf), before);
    let mut bad = data[100];
    bad.de_rad = None;
    assert!(matches!(
        ekf.update(&bad),
        Err(EstimatorError::NonFiniteInput { field: "de_rad", .. })
    ));
    assert_eq!(snapshot(&ekf), before);
    // The next good sample is accepted.
    assert!(ekf.update(&data[100]).is_ok());
    assert_ne!(snapshot(&ekf), before);
}

#[test]
fn new_manoeuvre_reinitialises_states_and_keeps_parameters() {
    let (mut ekf, data) = running_filter(ModelStructure::six_axis());
    let theta: Vec<f64> = (0..ekf.np).map(|i| ekf.estimates().raw_value(i)).collect();
    let sig: Vec<f64> = (0..ekf.np).map(|i| ekf.filter_sigma(i).unwrap()).collect();
    ekf.new_manoeuvre();
    // The next sample comes after a 30 s gap, at another condition.
    let mut s = data[150];
    s.t_s += 30.0;
    s.vt_mps = 170.0;
    s.alpha_rad = 0.08;
    s.beta_rad = Some(0.01);
    s.p_rad_s = Some(0.05);
    s.phi_rad = Some(0.2);
    s.theta_rad = Some(0.1);
    ekf.update(&s).unwrap();
    let want = [170.0, 0.08, 0.01, 0.05, s.q_rad_s.unwrap(), s.r_rad_s.unwrap(), 0.2, 0.1];
    for (i, w) in want.iter().enumerate() {
        assert_eq!(ekf.state(i), Some(*w), "state {}", STATE_NAMES[i]);
    }
    for i in 0..ekf.np {
        assert_eq!(ekf.estimates().raw_value(i), theta[i]);
        assert_eq!(ekf.filter_sigma(i).unwrap(), sig[i]);
        // State–parameter cross covariance restarts at 0.
        for k in 0..ekf.nx {
            assert_eq!(ekf.p()[k][ekf.nx + i], 0.0);
        }
    }
    // And it runs on from there (no dt across the gap is integrated).
    let mut s2 = data[151];
    s2.t_s += 30.0;
    assert!(ekf.update(&s2).is_ok());
}

/// The 50-Hz longitudinal record (seed 3) and a filter with `max_consecutive_rejections` 3 and
/// `max_restarts` restarts, run through its first 100 samples (the stuck-vane tests below).
fn filter_at_sample_100(max_restarts: u32) -> (Ekf, EkfConfig, Vec<AirDataSample>) {
    let data = simulate(50.0, 4.0, 3);
    let mut cfg = config(ModelStructure::longitudinal());
    cfg.max_consecutive_rejections = 3;
    cfg.max_restarts = max_restarts;
    let mut ekf = Ekf::new(cfg).unwrap();
    for s in &data[..100] {
        ekf.update(s).unwrap();
    }
    (ekf, cfg, data)
}

#[test]
fn divergence_is_reported_and_estimates_keep_last_good_values() {
    let (mut gated, mut cfg, data) = filter_at_sample_100(0);
    // An α sensor stuck at 1 rad: rejected by the gate, then declared divergence.
    for k in 0..3 {
        let mut s = data[100 + k];
        s.alpha_rad = 1.0;
        let r = gated.update(&s);
        assert_eq!(r.is_err(), k == 2, "sample {k}");
    }
    assert_eq!(gated.rejections(Output::Alpha), 3);
    assert_eq!(gated.estimates().status, Status::Diverged);
    assert!(gated.update(&data[103]).is_err(), "a diverged filter refuses further samples");
    // Without a gate the α state runs away past 1.5 rad: divergence, last good estimates.
    cfg.gate_sigmas = f64::INFINITY;
    // Fixed R: an R estimated from the wild innovations would grow and keep α from running
    // away, which is what the adaptive estimate is for, but not what this checks.
    cfg.adaptive_r_window = 0;
    // No change test either: inflating the parameters on the wild α would let them absorb it.
    cfg.change_false_alarm_interval_s = 0.0;
    let mut ekf = Ekf::new(cfg).unwrap();
    for s in &data[..100] {
        ekf.update(s).unwrap();
    }
    // Feed an α sensor gone wild (5 rad: plausible enough to pass the input check, far past
    // the filter's 1.5 rad runaway limit) until the filter gives up.
    let mut failed = None;
    for k in 0..50 {
        let before = *ekf.estimates();
        let mut s = data[100 + k];
        s.alpha_rad = 5.0;
        if let Err(e) = ekf.update(&s) {
            failed = Some((e, before));
            break;
        }
    }
    let (err, before) = failed.expect("a runaway α must be reported as divergence");
    assert!(matches!(err, EstimatorError::Numerical { .. }), "{err:?}");
    let after = *ekf.estimates();
    assert_eq!(after.status, Status::Diverged);
    for i in 0..ekf.np {
        assert_eq!(after.raw_value(i), before.raw_value(i));
        assert_eq!(after.sigma(i), before.sigma(i));
    }
}

/// A lock-out with a restart left (module doc, "Restart"): the filter starts again from its
/// priors with its states from the sample at which the rule fired, the restart is an event
/// naming the output, the rejection counts run on; at the next lock-out, with no restart
/// left, it diverges. An α vane stuck at 1 rad for three samples (`max_consecutive_rejections`
/// 3): the restart takes α = 1 rad from the third, so the good samples after it fail the gate
/// (a 0.95-rad innovation against the initial state σ of 0.007 rad) and the filter diverges at
/// the third of them.
#[test]
fn a_lock_out_restarts_the_filter_once_and_reports_it() {
    assert_eq!(EkfConfig::new(ModelStructure::longitudinal()).max_restarts, DEFAULT_MAX_RESTARTS);
    let (mut ekf, cfg, data) = filter_at_sample_100(DEFAULT_MAX_RESTARTS);
    assert!(ekf.estimates().all_identified());
    for k in 0..3 {
        let mut s = data[100 + k];
        s.alpha_rad = 1.0;
        let est = ekf.update(&s).expect("a lock-out with a restart left is not an error");
        assert_eq!(est.status == Status::Initialising, k == 2, "sample {k}");
    }
    assert_eq!(ekf.restarts(), 1);
    assert_eq!(ekf.rejections(Output::Alpha), 3, "counts run on through the restart");
    let ev = ekf.events().listed();
    assert_eq!(ev.len(), 1, "{ev:?}");
    assert_eq!(
        (ev[0].kind, ev[0].subject, ev[0].t_s),
        (EventKind::Restart, Output::Alpha.name(), data[102].t_s)
    );
    assert_eq!(ekf.events().count(EventKind::Restart), 1);
    assert_eq!(ekf.state(state::ALPHA), Some(1.0), "states from the sample it fired at");
    for i in 0..ekf.np {
        assert_eq!(ekf.estimates().raw_value(i), cfg.priors.prior[i].value, "parameter {i}");
        assert!(!ekf.estimates().is_identified(i));
        assert_eq!(ekf.filter_sigma(i), Some(cfg.priors.prior[i].sigma));
    }
    assert_eq!(ekf.nis(), None, "a restarted filter's NIS starts empty");
    // No restart left: the next lock-out is a divergence.
    let mut err = None;
    for s in &data[103..110] {
        if let Err(e) = ekf.update(s) {
            err = Some(e);
            break;
        }
    }
    assert!(matches!(err, Some(EstimatorError::Numerical { .. })), "{err:?}");
    assert_eq!(ekf.estimates().status, Status::Diverged);
    assert_eq!(ekf.events().count(EventKind::Restart), 1);
}

/// A lock-out at a sample that lacks a state channel (pitch attitude): the restart is made and
/// reported, and the restarted filter waits for a sample with every state channel to start its
/// states, as a new filter does, instead of failing.
#[test]
fn a_restart_at_an_incomplete_sample_waits_for_a_complete_one() {
    let (mut ekf, _, data) = filter_at_sample_100(1);
    for k in 0..3 {
        let mut s = data[100 + k];
        s.alpha_rad = 1.0;
        if k == 2 {
            s.theta_rad = None;
        }
        ekf.update(&s).expect("a restart is not an error");
    }
    assert_eq!(ekf.events().count(EventKind::Restart), 1);
    assert_eq!(ekf.state(state::ALPHA), None, "states not started from an incomplete sample");
    ekf.update(&data[103]).unwrap();
    assert_eq!(ekf.state(state::ALPHA), Some(data[103].alpha_rad));
    for s in &data[104..150] {
        ekf.update(s).unwrap();
    }
    assert_ne!(ekf.estimates().status, Status::Diverged);
}

#[test]
fn configuration_errors_are_named() {
    let mut cfg = EkfConfig::new(ModelStructure::lateral());
    cfg.measurement_sigma[Output::Ay.index()] = 0.0;
    assert!(matches!(
        Ekf::new(cfg),
        Err(EstimatorError::InvalidConfig { field: "measurement_sigma", .. })
    ));
    let cm = ModelStructure::empty().with(C::Cm, &[T::Alpha]);
    assert!(matches!(
        Ekf::new(EkfConfig::new(cm)),
        Err(EstimatorError::IncompleteAxis { lateral: false, .. })
    ));
    let ekf = Ekf::new(EkfConfig::new(ModelStructure::lateral())).unwrap();
    assert_eq!(ekf.method(), "ekf");
    assert!(ekf.estimates().value(0).is_none(), "nothing identified before data");
}

/// Runs a fresh filter of `st` with `cfg` over `data`.
fn run(cfg: EkfConfig, data: &[AirDataSample]) -> Ekf {
    let mut ekf = Ekf::new(cfg).unwrap();
    for s in data {
        ekf.update(s).unwrap();
    }
    ekf
}

/// Constant parameters: the change test raises at most about one alarm per record, and the
/// reported σ of the roll and yaw derivatives describe the scatter of the estimates over
/// independent noise records (mean σ / scatter within 0.6–1.7 for each, a band that a σ 2×
/// off fails), with ±2σ coverage ≥ 80 % overall.
#[test]
fn constant_parameters_few_alarms_and_sigma_matches_scatter() {
    let st = ModelStructure::lateral();
    let (st6, th6) = truth();
    let names = ["Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr"];
    let idx: Vec<usize> =
        names.iter().map(|n| st.params().position(|p| p.name() == *n).unwrap()).collect();
    let truth: Vec<f64> =
        idx.iter().map(|&i| th6[st6.index_of(st.params().nth(i).unwrap()).unwrap()]).collect();
    let seeds = 16;
    let mut finals = std::vec![Vec::new(); names.len()];
    let mut sigmas = std::vec![0.0; names.len()];
    let (mut alarms, mut covered) = (0, 0);
    for seed in 0..seeds {
        let data = simulate(50.0, 25.0, 100 + seed);
        let ekf = run(config(st), &data);
        alarms += (0..ekf.np).map(|i| ekf.change_alarms(i)).sum::<u32>();
        let e = ekf.estimates();
        for (k, &i) in idx.iter().enumerate() {
            let (v, s) = (e.value(i).unwrap(), e.sigma(i).unwrap());
            finals[k].push(v);
            sigmas[k] += s / seeds as f64;
            covered += usize::from((v - truth[k]).abs() <= 2.0 * s);
        }
    }
    // Measured: 17 alarms on 16 records, all on the roll derivatives at the second aileron
    // doublet (18 s): after one doublet the constant-parameter filter is overconfident (its
    // estimate is not yet a martingale, Ljung 1979), and the test sees that. The bound keeps
    // the rate at about one per record, far from an alarm every window.
    assert!(alarms <= 24, "{alarms} change alarms on {seeds} constant-parameter records");
    for k in 0..names.len() {
        let m = finals[k].iter().sum::<f64>() / seeds as f64;
        let scatter =
            (finals[k].iter().map(|v| (v - m).powi(2)).sum::<f64>() / (seeds - 1) as f64).sqrt();
        let ratio = sigmas[k] / scatter;
        std::println!(
            "{:>8} truth {:9.4} mean {m:9.4} scatter {scatter:.2e} σ {:.2e} ratio {ratio:.2}",
            names[k],
            truth[k],
            sigmas[k]
        );
        assert!((0.6..1.7).contains(&ratio), "{}: mean σ / scatter = {ratio}", names[k]);
    }
    let n = seeds as usize * names.len();
    assert!(covered * 10 >= n * 8, "±2σ covers {covered} of {n}");
}

/// A 30 % loss of roll damping at 12 s: the change test raises an alarm on Cl_p, and the
/// filter follows the step to within 10 % by the end of the record; without the test the
/// constant-parameter filter stays closer to the old value than to the new one.
#[test]
fn step_change_is_detected_and_followed() {
    let st = ModelStructure::lateral();
    let (st6, th6) = truth();
    let cl_p = Param::new(C::Cl, T::P);
    let old = th6[st6.index_of(cl_p).unwrap()];
    let new = 0.7 * old;
    let data = simulate_with_step(50.0, 30.0, 11, Some((cl_p, 12.0, new)));
    let i = st.index_of(cl_p).unwrap();
    let ekf = run(config(st), &data);
    let got = ekf.estimates().value(i).unwrap();
    std::println!("Cl_p old {old:.4} new {new:.4} got {got:.4} alarms {}", ekf.change_alarms(i));
    assert!(ekf.change_alarms(i) >= 1, "no alarm on Cl_p");
    assert!((got - new).abs() < 0.1 * new.abs(), "Cl_p {got} vs new truth {new}");
    // Each alarm is an event naming the parameter; the Cl_p alarms come after the step.
    let events = ekf.events();
    let on_cl_p: Vec<f64> = events
        .listed()
        .iter()
        .filter(|e| e.kind == EventKind::ChangeDetected && e.subject == "Cl_p")
        .map(|e| e.t_s)
        .collect();
    assert!(on_cl_p.iter().all(|&t| t > 12.0) && !on_cl_p.is_empty(), "{on_cl_p:?}");
    let alarms: u32 = (0..ekf.np).map(|k| ekf.change_alarms(k)).sum();
    assert_eq!(events.count(EventKind::ChangeDetected), alarms);
    let mut off = config(st);
    off.change_false_alarm_interval_s = 0.0;
    let fixed = run(off, &data);
    let stuck = fixed.estimates().value(i).unwrap();
    assert_eq!(fixed.change_alarms(i), 0);
    assert!((stuck - old).abs() < (stuck - new).abs(), "constant filter at {stuck}");
}

/// The lateral filter on the 50-Hz synthetic record (seed 5), clean and with `n` consecutive
/// roll-rate samples from sample 800 made wild (+50 noise σ): `(clean, hit)`.
fn roll_rate_glitch(n: usize) -> (Ekf, Ekf) {
    let st = ModelStructure::lateral();
    let data = simulate(50.0, 25.0, 5);
    let clean = run(config(st), &data);
    let mut bad = data.clone();
    for s in &mut bad[800..800 + n] {
        s.p_rad_s = Some(s.p_rad_s.unwrap() + 50.0 * NOISE[Output::P.index()]);
    }
    (clean, run(config(st), &bad))
}

/// No estimate of `hit` differs from `clean`'s by 0.2 of `clean`'s σ.
fn assert_estimates_unmoved(clean: &Ekf, hit: &Ekf) {
    for i in 0..clean.np {
        let (a, b) = (clean.estimates().raw_value(i), hit.estimates().raw_value(i));
        let s = clean.estimates().sigma(i).unwrap();
        assert!((a - b).abs() < 0.2 * s, "parameter {i}: {a} vs {b} (σ {s})");
    }
}

/// One wild roll-rate sample (50 noise σ) is rejected by the gate, raises no change alarm and
/// moves no estimate by more than 0.2 σ.
#[test]
fn one_outlier_is_gated_and_raises_no_alarm() {
    let (clean, hit) = roll_rate_glitch(1);
    assert_eq!(hit.rejections(Output::P), clean.rejections(Output::P) + 1);
    let alarms = |e: &Ekf| (0..e.np).map(|i| e.change_alarms(i)).sum::<u32>();
    assert_eq!(alarms(&hit), alarms(&clean));
    assert_estimates_unmoved(&clean, &hit);
}

/// White process noise of 0.005 rad/√s on the true `α` and `β` (about light turbulence at the
/// test aircraft's speed: σ_w √(3V/L) / V), [`NOISE`] on the sensors.
fn turbulent_process() -> [f64; 8] {
    let mut process = [0.0; 8];
    process[state::ALPHA] = 0.005;
    process[state::BETA] = 0.005;
    process
}

/// Steady flight before the first input in the process-noise records, s: the `Q` estimate
/// forms from the record, and information gathered before it has (the first second or two)
/// is counted with the configured `Q` (module doc).
const LEAD_S: f64 = 3.0;

fn fixed_q(st: ModelStructure) -> EkfConfig {
    let mut cfg = config(st);
    cfg.adaptive_q_window = 0;
    cfg
}

fn adaptive_q(st: ModelStructure) -> EkfConfig {
    let mut cfg = config(st);
    cfg.adaptive_q_window = 500;
    cfg
}

/// Bound on the estimated airspeed process-noise σ, m/s/√s, on records without any: a sixth of
/// the 0.3 m/s/√s of [`airspeed_process_noise_converges_to_the_truth`], 2.7× the floor
/// [`DEFAULT_STATE_PROCESS_NOISE`] (0.015).
const V_CALM_BOUND: f64 = 0.04;

/// (d) Process noise of known intensity on `V` (0.3 m/s/√s, with the α, β turbulence of
/// [`turbulent_process`]): the airspeed's statistic takes its own lag products (module doc), and
/// the estimated σ is within a factor 0.6–1.6 of the truth on every seed and within ±30 % on the
/// mean of 6 seeds (a `Q` at its floor would be 0.05 of the truth). The records of (a) and (b),
/// without airspeed noise, hold it below [`V_CALM_BOUND`].
#[test]
fn airspeed_process_noise_converges_to_the_truth() {
    let st = ModelStructure::six_axis();
    let mut process = turbulent_process();
    process[state::V] = 0.3;
    let seeds = 6;
    let mut mean = 0.0;
    for seed in 0..seeds {
        let data = simulate_full(50.0, 28.0, 200 + seed, None, process, LEAD_S);
        let ekf = run(adaptive_q(st), &data);
        let q = ekf.state_process_noise(state::V).unwrap();
        let ratio = q / process[state::V];
        std::println!("seed {seed}: V σ_Q {q:.4} ({ratio:.2} of the truth)");
        assert!((0.6..1.6).contains(&ratio), "V: σ_Q {q} vs {}", process[state::V]);
        mean += ratio / seeds as f64;
    }
    std::println!("mean V σ_Q / truth {mean:.3}");
    assert!((0.7..1.3).contains(&mean), "mean V σ_Q / truth {mean}");
}

/// (a) Process noise of known intensity on `α` and `β`: the estimated process-noise σ of both
/// is within a factor 0.6–1.6 of the truth on every seed (25 s of data after 3 s of steady
/// flight) and within ±30 % on the mean of 6 seeds (measured: α 0.67–0.95 of the truth, mean
/// 0.80, β 0.85–1.18; a `Q` stuck at its floor would be 0.06); the states not adapted keep their
/// configured σ, and `V`, adapted but without process noise, stays below [`V_CALM_BOUND`].
#[test]
fn adapted_process_noise_converges_to_the_truth() {
    let st = ModelStructure::six_axis();
    let process = turbulent_process();
    let seeds = 6;
    let mut mean = [0.0; 2];
    for seed in 0..seeds {
        let data = simulate_full(50.0, 28.0, 200 + seed, None, process, LEAD_S);
        let ekf = run(adaptive_q(st), &data);
        let q: Vec<f64> = (0..8).map(|i| ekf.state_process_noise(i).unwrap()).collect();
        std::println!("seed {seed}: Q σ {q:.5?} NIS {:.3}", ekf.nis().unwrap());
        for (m, i) in mean.iter_mut().zip([state::ALPHA, state::BETA]) {
            let ratio = q[i] / process[i];
            assert!(
                (0.6..1.6).contains(&ratio),
                "{}: σ_Q {} vs {}",
                STATE_NAMES[i],
                q[i],
                process[i]
            );
            *m += ratio / seeds as f64;
        }
        for i in [state::P, state::Q, state::R, state::PHI, state::THETA] {
            assert_eq!(q[i], DEFAULT_STATE_PROCESS_NOISE[i], "{}", STATE_NAMES[i]);
        }
        // No process noise on V: its estimate does not pick up α's.
        assert!(q[state::V] < V_CALM_BOUND, "V: σ_Q {}", q[state::V]);
    }
    std::println!("mean σ_Q / truth: α {:.3}, β {:.3}", mean[0], mean[1]);
    for m in mean {
        assert!((0.7..1.3).contains(&m), "mean σ_Q / truth {m}");
    }
}

/// (b) No process noise: the estimated `Q` of `α` and `β` stays below 0.001 rad/√s (its floor
/// is 0.0003, the process noise of the other tests 0.005; `V` below [`V_CALM_BOUND`];
/// measured ≤ 0.00062: the early
/// transient and the clipping at the floor lift it a little); over the primary derivatives of 4
/// records the RMS of the standardised error `(θ̂ − θ)/σ` is not larger than the fixed-`Q`
/// filter's (+10 %; measured 7.71 vs 7.73), each σ is within 0.8–3× the fixed-`Q` filter's
/// and their mean below 1.25× (measured 1.18, the largest 2.6× on `CL_de` and 2.0× on `Cm_q`
/// in one record each): the `Q` of the early transient, before the parameters are near the
/// truth, costs information. That is the price of adapting from the start, which the turbulent
/// records need (module doc).
#[test]
fn adapted_process_noise_stays_at_the_floor_in_calm_air() {
    let st = ModelStructure::six_axis();
    let (_, th6) = truth();
    let (mut err_fixed, mut err_adapted) = (0.0, 0.0);
    let (mut ratio_sum, mut ratio_n) = (0.0, 0.0);
    for seed in 0..4 {
        let data = simulate(50.0, 25.0, 300 + seed);
        let fixed = run(fixed_q(st), &data);
        let adapted = run(adaptive_q(st), &data);
        let q: Vec<f64> = (0..8).map(|i| adapted.state_process_noise(i).unwrap()).collect();
        std::println!("calm seed {seed}: Q σ {q:.5?}");
        for i in [state::ALPHA, state::BETA] {
            assert!(q[i] <= 0.001, "{}: {}", STATE_NAMES[i], q[i]);
        }
        assert!(q[state::V] < V_CALM_BOUND, "V: σ_Q {}", q[state::V]);
        let (a, f) = (adapted.estimates(), fixed.estimates());
        for (i, p) in st.params().enumerate() {
            if !PRIMARY.contains(&p.name()) {
                continue;
            }
            let (sa, sf) = (a.sigma(i).unwrap(), f.sigma(i).unwrap());
            err_fixed += ((f.value(i).unwrap() - th6[i]) / sf).powi(2);
            err_adapted += ((a.value(i).unwrap() - th6[i]) / sa).powi(2);
            assert!((0.8..3.0).contains(&(sa / sf)), "{}: σ {sa} vs {sf}", p.name());
            ratio_sum += sa / sf;
            ratio_n += 1.0;
        }
    }
    let mean_ratio = ratio_sum / ratio_n;
    std::println!("mean σ adapted / fixed {mean_ratio:.3}");
    assert!(mean_ratio < 1.25, "mean σ adapted / fixed {mean_ratio}");
    let (ef, ea) = (err_fixed.sqrt(), err_adapted.sqrt());
    std::println!("Σ standardised error²: fixed {ef:.3}, adapted {ea:.3}");
    assert!(ea <= 1.1 * ef, "adapted {ea} vs fixed {ef}");
}

/// (c) Consistency under process noise: over 24 records with process noise on `α` and `β`,
/// the filter with `Q` from the record has a mean NIS within 0.9–1.1 and a mean σ / scatter
/// within 0.7–1.4 for the lateral-directional primary derivatives and `CL_alpha` (measured
/// 0.74–1.37). The pitch derivatives are still optimistic and held to 0.35–1.4 (measured
/// `Cm_alpha` 1.04, `Cm_q` 0.76, `Cm_de` 0.54 with `V` adapted, 0.56, 0.84, 0.39 without; the
/// fixed-`Q` filter 0.75, 0.90, 0.65 with
/// 2.5–7× their scatter): the `α` `Q` comes out ~20 % low in (a), the information of the first
/// seconds is counted with the floor `Q`, and the estimate pauses while an output is being
/// rejected. The fixed-`Q` filter, which takes the turbulent motion for model error, is printed
/// for comparison (its scatter is 2.5–50× larger).
#[test]
fn adapted_process_noise_is_consistent_over_a_small_monte_carlo() {
    let st = ModelStructure::six_axis();
    let (_, th6) = truth();
    let names = [
        "CL_alpha", "Cm_alpha", "Cm_q", "Cm_de", "CY_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r",
        "Cn_dr",
    ];
    let idx: Vec<usize> =
        names.iter().map(|n| st.params().position(|p| p.name() == *n).unwrap()).collect();
    let seeds = 24;
    for adapt in [false, true] {
        let mut finals = std::vec![Vec::new(); names.len()];
        let mut sigmas = std::vec![0.0; names.len()];
        let mut nis = 0.0;
        for seed in 0..seeds {
            let data = simulate_full(50.0, 28.0, 400 + seed, None, turbulent_process(), LEAD_S);
            let ekf = run(if adapt { adaptive_q(st) } else { fixed_q(st) }, &data);
            nis += ekf.nis().unwrap() / seeds as f64;
            for (k, &i) in idx.iter().enumerate() {
                finals[k].push(ekf.estimates().value(i).unwrap());
                sigmas[k] += ekf.estimates().sigma(i).unwrap() / seeds as f64;
            }
        }
        std::println!("adaptive Q {adapt}: mean NIS {nis:.3}");
        let mut ratios = Vec::new();
        for k in 0..names.len() {
            let m = finals[k].iter().sum::<f64>() / seeds as f64;
            let scatter = (finals[k].iter().map(|v| (v - m).powi(2)).sum::<f64>()
                / (seeds - 1) as f64)
                .sqrt();
            let ratio = sigmas[k] / scatter;
            std::println!(
                "{:>8} truth {:9.4} mean {m:9.4} scatter {scatter:.2e} σ {:.2e} ratio {ratio:.2}",
                names[k],
                th6[idx[k]],
                sigmas[k]
            );
            ratios.push(ratio);
        }
        if adapt {
            assert!((0.9..1.1).contains(&nis), "mean NIS {nis}");
            for (n, r) in names.iter().zip(&ratios) {
                let low = if n.starts_with("Cm_") { 0.35 } else { 0.7 };
                assert!((low..1.4).contains(r), "{n}: mean σ / scatter = {r}");
            }
        }
    }
}

/// A 70 % loss of the dihedral effect (`Cl_beta` × 0.3) at 12 s on the 100-Hz synthetic
/// lateral record, constant-parameter filter: the roll-rate gyro leaves the gate at once. With
/// re-anchoring (module doc) the filter runs to the end and follows the step to within 10 %;
/// without it the gyro is rejected 50 times in a row and the filter reports divergence
/// (measured: on all three seeds, as a `Cl_p` × 0.3 or a `Cl_da` × 0.5 step does).
#[test]
fn sudden_moment_change_is_reanchored_and_followed_not_locked_out() {
    let st = ModelStructure::lateral();
    let (st6, th6) = truth();
    let cl_beta = Param::new(C::Cl, T::Beta);
    let i = st.index_of(cl_beta).unwrap();
    let new = 0.3 * th6[st6.index_of(cl_beta).unwrap()];
    for seed in [11, 12, 13] {
        let data = simulate_with_step(100.0, 30.0, seed, Some((cl_beta, 12.0, new)));
        let ekf = run(config(st), &data);
        let got = ekf.estimates().value(i).unwrap();
        std::println!(
            "seed {seed}: Cl_beta {got:.4} (new {new:.4}), re-anchored p {}",
            ekf.reanchors(Output::P)
        );
        assert!(ekf.reanchors(Output::P) >= 1, "seed {seed}: the roll gyro was never re-anchored");
        assert!((got - new).abs() < 0.1 * new.abs(), "seed {seed}: Cl_beta {got} vs {new}");
        // The run of re-anchorings is one event, after the step.
        let reanchored: Vec<_> = ekf
            .events()
            .listed()
            .iter()
            .filter(|e| e.kind == EventKind::Reanchor && e.subject == Output::P.name())
            .collect();
        assert!(!reanchored.is_empty() && reanchored[0].t_s > 12.0, "{reanchored:?}");
        assert_eq!(ekf.events().count(EventKind::Restart), 0, "seed {seed}");
        let mut off = config(st);
        off.reanchor_after = 0;
        off.max_restarts = 0;
        let mut locked = Ekf::new(off).unwrap();
        let failed = data.iter().any(|s| locked.update(s).is_err());
        assert!(failed, "seed {seed}: without re-anchoring the filter should lock out the gyro");
        assert_eq!(locked.estimates().status, Status::Diverged);
    }
}

/// A glitch of `reanchor_after − 1` consecutive wild roll-rate samples (50 noise σ) is
/// rejected sample by sample: nothing is re-anchored and no estimate moves by 0.2 σ.
#[test]
fn a_short_glitch_is_rejected_not_reanchored() {
    let n = DEFAULT_REANCHOR_AFTER - 1;
    let (clean, hit) = roll_rate_glitch(n as usize);
    assert_eq!(hit.rejections(Output::P), clean.rejections(Output::P) + n);
    assert_eq!(hit.reanchors(Output::P), 0);
    assert_estimates_unmoved(&clean, &hit);
}

/// The parameter-block re-anchoring reaches its target exactly (`h P hᵀ` = target, solved from
/// the quadratic in the scale), keeps `P` symmetric and positive definite (Cholesky) and keeps
/// every correlation coefficient, and leaves the states' block and the parameters the output
/// does not see untouched.
#[test]
fn parameter_reanchoring_reaches_the_bound_and_keeps_correlations() {
    let (nx, n) = (3, 6);
    // A positive definite P with every pair correlated: B Bᵀ + I.
    let mut p: Square = [[0.0; MAX_AUG]; MAX_AUG];
    let b = [
        [1.0, 0.3, -0.2, 0.5, 0.1, 0.0],
        [0.2, 0.8, 0.4, -0.3, 0.2, 0.1],
        [-0.1, 0.5, 1.2, 0.2, -0.4, 0.3],
        [0.4, -0.2, 0.1, 0.9, 0.3, -0.2],
        [0.0, 0.3, -0.3, 0.2, 0.7, 0.4],
        [0.2, 0.1, 0.2, -0.1, 0.3, 0.6],
    ];
    for i in 0..n {
        for j in 0..n {
            p[i][j] =
                (0..n).map(|k| b[i][k] * b[j][k]).sum::<f64>() + if i == j { 1.0 } else { 0.0 };
        }
    }
    let before = p;
    // The output sees states 0 and 2 and parameters 3 and 4, not parameter 5.
    let mut h = [0.0; MAX_AUG];
    h[0] = 0.7;
    h[2] = -0.4;
    h[3] = 1.5;
    h[4] = -0.8;
    let hph = |p: &Square| {
        (0..n).map(|i| (0..n).map(|j| h[i] * p[i][j] * h[j]).sum::<f64>()).sum::<f64>()
    };
    let target = 10.0 * hph(&p);
    assert!(reanchor_parameters(&mut p, &h, nx, n, target));
    assert!((hph(&p) / target - 1.0).abs() < 1e-8, "{} vs {target}", hph(&p));
    let corr = |p: &Square, i: usize, j: usize| p[i][j] / (p[i][i] * p[j][j]).sqrt();
    for i in 0..n {
        for j in 0..n {
            assert_eq!(p[i][j], p[j][i]);
            assert!((corr(&p, i, j) - corr(&before, i, j)).abs() < 1e-12, "ρ({i},{j})");
            if !(i == 3 || i == 4 || j == 3 || j == 4) {
                assert_eq!(p[i][j], before[i][j], "({i},{j}) should be untouched");
            }
        }
    }
    let m = nalgebra::DMatrix::from_fn(n, n, |i, j| p[i][j]);
    assert!(m.cholesky().is_some(), "P is no longer positive definite");
    // Nothing to do when the bound is already met, or when the output sees no parameter.
    let mut q = before;
    assert!(!reanchor_parameters(&mut q, &h, nx, n, 0.5 * hph(&before)));
    let mut states_only = [0.0; MAX_AUG];
    states_only[1] = 1.0;
    assert!(!reanchor_parameters(&mut q, &states_only, nx, n, 100.0));
    assert_eq!(q, before);
}

/// The six-axis structure's coefficients that `keep` selects, terms as in it.
fn axis_part(keep: fn(C) -> bool) -> ModelStructure {
    let six = ModelStructure::six_axis();
    let mut st = ModelStructure::empty().with_knots(*six.knots());
    for p in six.params().filter(|p| keep(p.coefficient)) {
        st.insert(p);
    }
    st
}

fn is_lateral(c: C) -> bool {
    matches!(c, C::CY | C::Cl | C::Cn)
}

/// The blocks of the six-axis filter are a longitudinal and a lateral filter run on their
/// own over the same record: every estimate, σ and identification equal to the bit at every
/// sample, and the primary derivatives recovered within 10 % of the truth.
#[test]
fn the_blocks_are_the_two_axis_filters() {
    let data = simulate(50.0, 25.0, 7);
    let mut blocks = EkfBlocks::new(config(ModelStructure::six_axis())).unwrap();
    let mut lon = Ekf::new(config(axis_part(|c| !is_lateral(c)))).unwrap();
    let mut lat = Ekf::new(config(axis_part(is_lateral))).unwrap();
    let six = ModelStructure::six_axis();
    for s in &data {
        let e = *blocks.update(s).unwrap();
        for axis in [&mut lon, &mut lat] {
            let a = *axis.update(s).unwrap();
            for (k, p) in axis.structure().params().enumerate() {
                let i = six.index_of(p).unwrap();
                let same = a.raw_value(k).to_bits() == e.raw_value(i).to_bits()
                    && a.sigma(k).map(f64::to_bits) == e.sigma(i).map(f64::to_bits)
                    && a.is_identified(k) == e.is_identified(i);
                assert!(same, "{} at {} s", p.name(), s.t_s);
            }
        }
    }
    let (st6, th6) = truth();
    let e = *blocks.estimates();
    assert_eq!(e.status, Status::Running);
    for name in PRIMARY {
        let i = st6.params().position(|p| p.name() == name).unwrap();
        let got = e.value(i).unwrap();
        assert!((got - th6[i]).abs() <= 0.1 * th6[i].abs(), "{name}: {got} vs {}", th6[i]);
    }
    assert!(blocks.covariance(0, 1).is_some() && blocks.nis().is_some());
    let (cl, cy) =
        (six.index_of(Param::new(C::CL, T::Alpha)), six.index_of(Param::new(C::CY, T::Beta)));
    assert_eq!(blocks.covariance(cl.unwrap(), cy.unwrap()), None, "no covariance across the axes");
}

/// A sample one block cannot read (θ, an input of the lateral block) is refused before either
/// block moves; a one-axis structure is refused.
#[test]
fn the_blocks_refuse_a_sample_either_cannot_read() {
    let data = simulate(50.0, 4.0, 3);
    let (mut clean, mut hit) = (
        EkfBlocks::new(config(ModelStructure::six_axis())).unwrap(),
        EkfBlocks::new(config(ModelStructure::six_axis())).unwrap(),
    );
    for s in &data[..100] {
        clean.update(s).unwrap();
        hit.update(s).unwrap();
    }
    let mut bad = data[100];
    bad.theta_rad = None;
    assert!(matches!(
        hit.update(&bad),
        Err(EstimatorError::NonFiniteInput { field: "theta_rad", .. })
    ));
    for s in &data[100..] {
        assert_eq!(*clean.update(s).unwrap(), *hit.update(s).unwrap(), "at {} s", s.t_s);
    }
    let lon = EkfBlocks::new(config(ModelStructure::longitudinal()));
    assert!(matches!(lon, Err(EstimatorError::InvalidConfig { field: "blocks", .. })));
}

/// A filter that steps on every second sample is the filter fed every second sample: the
/// same estimates, σ and identification to the bit after each sample it reads, unchanged
/// over each sample it passes over, and its new manoeuvre starts with its first sample.
/// The primary derivatives are still recovered within 10 % of the truth from half the data.
#[test]
fn a_filter_stepping_on_every_second_sample_is_the_filter_fed_those_samples() {
    let data = simulate(50.0, 25.0, 11);
    let six = ModelStructure::six_axis();
    let every = |n| EkfConfig { update_every: n, ..config(six) };
    let (mut half, mut fed) = (Ekf::new(every(2)).unwrap(), Ekf::new(every(1)).unwrap());
    let same = |a: &Estimates, b: &Estimates| {
        (0..six.n_params()).all(|i| {
            a.raw_value(i).to_bits() == b.raw_value(i).to_bits()
                && a.sigma(i).map(f64::to_bits) == b.sigma(i).map(f64::to_bits)
                && a.is_identified(i) == b.is_identified(i)
        })
    };
    let mut previous = *half.estimates();
    for (k, s) in data.iter().enumerate() {
        if k == data.len() / 2 {
            half.new_manoeuvre();
            fed.new_manoeuvre();
        }
        let h = *half.update(s).unwrap();
        let read = (k - if k >= data.len() / 2 { data.len() / 2 } else { 0 }) % 2 == 0;
        if read {
            let f = *fed.update(s).unwrap();
            assert!(same(&h, &f), "at {} s", s.t_s);
        } else {
            assert!(same(&h, &previous), "passed over at {} s", s.t_s);
        }
        previous = h;
    }
    let (st6, th6) = truth();
    let e = *half.estimates();
    for name in PRIMARY {
        let i = st6.params().position(|p| p.name() == name).unwrap();
        let got = e.value(i).unwrap();
        assert!((got - th6[i]).abs() <= 0.1 * th6[i].abs(), "{name}: {got} vs {}", th6[i]);
    }
}
