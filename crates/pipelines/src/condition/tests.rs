//! Tests of the conditioning stage.
use super::*;
use aeroident_estimators::AirDataSample;

/// The stage of a log replay: `derivatives` over `window` samples, a pure delay.
fn delayed(derivatives: Vec<Derivative>, window: usize, nominal_dt_s: Option<f64>) -> Conditioning {
    Conditioning { derivatives, window, nominal_dt_s, alignment: Alignment::Delay }
}

/// A wrong nominal interval (2 × the real one) is detected on the first
/// interval; the measured one is used, so the derivative of q = 0.3 t is 0.3 (the nominal
/// would give 0.15), and a warning names both intervals.
#[test]
fn analytic_wrong_nominal_interval_uses_the_measured_one_and_warns() {
    let dt = 0.02;
    let mut st = Conditioner::new(delayed(vec![Derivative::Qdot], 5, Some(2.0 * dt)));
    let (mut ready, mut unused) = (Vec::new(), Vec::new());
    for k in 0..20u64 {
        let t = k as f64 * dt;
        let s = AirDataSample { t_s: t, q_rad_s: Some(0.3 * t), ..Default::default() };
        st.push(k, s, &mut ready, &mut unused).unwrap();
    }
    let w = st.take_warning().expect("warning");
    assert!(w.contains("0.04") && w.contains("0.02"), "{w}");
    assert_eq!(st.dt_s(), Some(dt));
    assert!(ready.len() > 10);
    for (_, s) in &ready {
        assert!((s.qdot_rad_s2.unwrap() - 0.3).abs() < 1e-9, "{:?}", s.qdot_rad_s2);
    }
    // A nominal within 1 % is kept without warning.
    let mut st = Conditioner::new(delayed(vec![Derivative::Qdot], 5, Some(dt * 1.005)));
    for k in 0..3u64 {
        let s = AirDataSample { t_s: k as f64 * dt, ..Default::default() };
        st.push(k, s, &mut ready, &mut unused).unwrap();
    }
    assert!(st.take_warning().is_none());
    assert_eq!(st.dt_s(), Some(dt * 1.005));
}

/// Quadratic rates and α: the least-squares slope is exact for quadratics, so every
/// supplied derivative equals the analytic one at the (delayed) sample's own time, and
/// the other channels come from the same sample (alignment).
#[test]
fn analytic_quadratic_signals_are_differentiated_exactly_and_stay_aligned() {
    let dt = 0.02;
    let mut st = Conditioner::new(delayed(Derivative::ALL.to_vec(), 5, Some(dt)));
    let (mut ready, mut unused) = (Vec::new(), Vec::new());
    for k in 0..40u64 {
        let t = k as f64 * dt;
        let s = AirDataSample {
            t_s: t,
            vt_mps: 100.0 + t,
            alpha_rad: 0.1 + 0.3 * t - 0.2 * t * t,
            qbar_pa: 1.0,
            p_rad_s: Some(0.5 * t * t),
            q_rad_s: Some(-0.4 * t + 0.1),
            r_rad_s: Some(2.0 * t * t - t),
            qdot_rad_s2: Some(99.0),
            ..Default::default()
        };
        st.push(k + 2, s, &mut ready, &mut unused).unwrap();
    }
    st.flush(&mut unused);
    assert_eq!(ready.len(), 36);
    assert_eq!(unused, vec![2, 3, 40, 41]);
    for (row, s) in &ready {
        let t = s.t_s;
        assert_eq!(*row, (t / dt).round() as u64 + 2);
        assert!((s.vt_mps - (100.0 + t)).abs() < 1e-12);
        assert!((s.pdot_rad_s2.unwrap() - t).abs() < 1e-9, "{t}");
        assert!((s.qdot_rad_s2.unwrap() + 0.4).abs() < 1e-9, "overrides the recorded q̇");
        assert!((s.rdot_rad_s2.unwrap() - (4.0 * t - 1.0)).abs() < 1e-9);
        assert!((s.alphadot_rad_s.unwrap() - (0.3 - 0.4 * t)).abs() < 1e-9);
    }
}

#[test]
fn pass_through_when_nothing_is_differentiated() {
    let mut st = Conditioner::new(delayed(Vec::new(), 5, None));
    let (mut ready, mut unused) = (Vec::new(), Vec::new());
    let s = AirDataSample { qdot_rad_s2: Some(1.0), ..Default::default() };
    st.push(2, s, &mut ready, &mut unused).unwrap();
    assert_eq!(ready, vec![(2, s)]);
    assert!(unused.is_empty());
}

/// The identity the matched alignment rests on: for α the trapezoidal integral of q
/// (`α_{j+1} = α_j + (q_j + q_{j+1}) dt/2`), the differentiator's `α̇` equals the matched
/// smoother's `q` exactly (summation by parts: `Σ w_k α_k = Σ (s_k + s_{k+1})/2 · q_k`), for any
/// q. The raw sample keeps the unsmoothed q, a linear channel is unchanged by the symmetric
/// weights, and a channel the window lacks stays missing.
#[test]
fn analytic_matched_smoother_equals_the_derivative_of_the_trapezoidal_integral() {
    let dt = 0.01;
    let cfg = Conditioning {
        derivatives: vec![Derivative::Alphadot],
        window: 11,
        nominal_dt_s: Some(dt),
        alignment: Alignment::Matched,
    };
    let mut st = Conditioner::new(cfg);
    let (mut ready, mut unused) = (Vec::new(), Vec::new());
    let q = |k: u64| (0.7 * k as f64).sin() + 0.3 * (2.3 * k as f64).cos();
    let mut alpha = 0.05;
    let mut raw_q = Vec::new();
    for k in 0..60u64 {
        if k > 0 {
            alpha += 0.5 * (q(k - 1) + q(k)) * dt;
        }
        let t = k as f64 * dt;
        let s = AirDataSample {
            t_s: t,
            vt_mps: 100.0 + 3.0 * t,
            alpha_rad: alpha,
            qbar_pa: 1.0,
            q_rad_s: Some(q(k)),
            p_rad_s: (k != 30).then_some(0.1),
            ..Default::default()
        };
        let before = ready.len();
        st.push(k, s, &mut ready, &mut unused).unwrap();
        if ready.len() > before {
            raw_q.push(st.raw().unwrap().q_rad_s.unwrap());
        }
    }
    assert_eq!(ready.len(), 50);
    assert_eq!(unused, (0..5).collect::<Vec<u64>>());
    for ((row, s), rq) in ready.iter().zip(&raw_q) {
        let ad = s.alphadot_rad_s.unwrap();
        assert!((ad - s.q_rad_s.unwrap()).abs() < 1e-12, "row {row}: {ad} vs {:?}", s.q_rad_s);
        assert_eq!(*rq, q(*row), "raw q of row {row}");
        assert!((s.q_rad_s.unwrap() - q(*row)).abs() > 1e-6, "row {row}: q not smoothed");
        assert!((s.vt_mps - (100.0 + 3.0 * *row as f64 * dt)).abs() < 1e-12);
        // p is missing in row 30: the windows over it keep their centre's p (or its absence).
        let centre_p = (*row != 30).then_some(0.1);
        if (25..=35).contains(row) {
            assert_eq!(s.p_rad_s, centre_p, "row {row}");
        } else {
            assert!((s.p_rad_s.unwrap() - 0.1).abs() < 1e-15, "row {row}");
        }
    }
}

/// One sample missing from a regular grid (row 20 of a linear q = 0.3 t): the stand-in keeps
/// the grid, so every other sample keeps its exact derivative 0.3 and none but the missing one
/// is lost (only the record's own ends are unused); three missing samples are no hole of one:
/// the derivative across them is wrong and nothing is bridged (the reader reports a gap there).
#[test]
fn analytic_one_missing_sample_is_bridged_and_costs_only_itself() {
    let dt = 0.02;
    let run = |missing: &[u64]| {
        let mut st = Conditioner::new(delayed(vec![Derivative::Qdot], 5, Some(dt)));
        let (mut ready, mut unused) = (Vec::new(), Vec::new());
        for k in (0..40u64).filter(|k| !missing.contains(k)) {
            let t = k as f64 * dt;
            let s = AirDataSample { t_s: t, q_rad_s: Some(0.3 * t), ..Default::default() };
            st.push(k, s, &mut ready, &mut unused).unwrap();
        }
        st.flush(&mut unused);
        (ready, unused)
    };
    let (ready, unused) = run(&[20]);
    assert_eq!(unused, vec![0, 1, 38, 39]);
    let rows: Vec<u64> = ready.iter().map(|r| r.0).collect();
    assert_eq!(rows, (2..38).filter(|&k| k != 20).collect::<Vec<_>>());
    for (row, s) in &ready {
        assert!((s.qdot_rad_s2.unwrap() - 0.3).abs() < 1e-9, "row {row}: {:?}", s.qdot_rad_s2);
        assert!((s.t_s - *row as f64 * dt).abs() < 1e-12, "row {row} keeps its own time");
    }
    let (ready, _) = run(&[20, 21, 22]);
    assert!(ready.iter().any(|(_, s)| (s.qdot_rad_s2.unwrap() - 0.3).abs() > 1e-3));
}
