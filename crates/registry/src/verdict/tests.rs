use super::*;
use aeroident_io::parameter::{
    NO_STD_ERROR, STATUS_DIVERGED, STATUS_FLAGGED, STATUS_IDENTIFIED, STATUS_NOT_IDENTIFIED,
};

fn result(name: &str, estimate: f64, sigma: f64, reference: Option<f64>) -> ParameterResult {
    ParameterResult::new(name, Some(estimate), Some(sigma), reference, None)
}

/// The reference is never an input: the same numbers judged with the reference at the
/// estimate and 10σ away get the same status, flags and notes; only `reference_check` differs.
#[test]
fn the_reference_is_compared_beside_the_verdict() {
    let model = ModelSpec::preset("longitudinal").unwrap();
    let evidence = Evidence { plausibility: Some((&model, true)), ..Default::default() };
    let mut near = result("Cm_alpha", -1.0, 0.02, Some(-1.0));
    let mut far = result("Cm_alpha", -1.0, 0.02, Some(-0.8));
    judge(&mut near, &evidence);
    judge(&mut far, &evidence);
    assert_eq!((&near.status, &near.flags, &near.notes), (&far.status, &far.flags, &far.notes));
    assert_eq!(near.status, STATUS_IDENTIFIED);
    let (n, f) = (near.reference_check.unwrap(), far.reference_check.unwrap());
    assert_eq!((n.within_2sigma, f.within_2sigma), (Some(true), Some(false)));
    assert!((f.distance_sigma.unwrap() - 10.0).abs() < 1e-9);
}

/// σ 30 % of the estimate is a note, not a flag; σ 60 % (t-ratio 1.7: ±2σ spans zero) is a
/// flag, and at a t-ratio of exactly 2 a note again; a constant term near 0 is neither; a
/// doubt is a flag; an estimate doubt flags an
/// estimate and leaves a parameter without one alone; a failure replaces the verdict.
#[test]
fn notes_doubts_and_failures() {
    let mut wide = result("Cm_q", -10.0, 3.0, None);
    judge(&mut wide, &Evidence::default());
    assert_eq!((wide.status.as_str(), wide.flags.len()), (STATUS_IDENTIFIED, 0));
    assert_eq!(wide.notes, [precision::flag(0.3)]);
    let mut spans_zero = result("Cm_q", -10.0, 6.0, None);
    judge(&mut spans_zero, &Evidence::default());
    assert_eq!(spans_zero.status, STATUS_FLAGGED);
    assert!(spans_zero.flags[0].starts_with("not told from 0: |estimate|/σ = 1.7 < 2"));
    assert!(spans_zero.notes.is_empty());
    let mut edge = result("Cm_q", -10.0, 5.0, None);
    judge(&mut edge, &Evidence::default());
    assert_eq!((edge.status.as_str(), edge.notes.len()), (STATUS_IDENTIFIED, 1));
    let mut spread = result("Cm_q", -10.0, 0.5, None);
    let note = "does not repeat across manoeuvres to their σ: …".to_string();
    judge(&mut spread, &Evidence { notes: vec![note.clone()], ..Default::default() });
    assert_eq!((spread.status.as_str(), spread.notes.clone()), (STATUS_IDENTIFIED, vec![note]));
    let mut trim = result("Cm_0", 0.001, 0.01, None);
    judge(&mut trim, &Evidence::default());
    assert_eq!(
        (trim.status.as_str(), trim.flags.len(), trim.notes.len()),
        (STATUS_IDENTIFIED, 0, 0)
    );
    let unconverged = unconverged("initialising").unwrap();
    let evidence = Evidence {
        doubts: vec!["sign test: δe reversed".into()],
        estimate_doubts: vec![unconverged.clone()],
        ..Default::default()
    };
    let mut doubted = result("Cm_de", -1.0, 0.01, None);
    judge(&mut doubted, &evidence);
    assert_eq!(doubted.status, STATUS_FLAGGED);
    assert_eq!(doubted.flags, ["sign test: δe reversed".to_string(), unconverged.clone()]);
    let mut none = ParameterResult::new("Cm_q", None, None, None, None);
    judge(&mut none, &Evidence { estimate_doubts: vec![unconverged], ..Default::default() });
    assert_eq!((none.status.as_str(), none.flags.len()), (STATUS_NOT_IDENTIFIED, 0));
    let mut failed = result("Cm_q", -10.0, 0.1, None);
    judge(&mut failed, &Evidence { failure: Some(STATUS_DIVERGED), ..Default::default() });
    assert_eq!(failed.status, STATUS_DIVERGED);
    let mut no_sigma = ParameterResult::new("Cm_q", Some(-10.0), None, None, None);
    judge(&mut no_sigma, &Evidence::default());
    assert_eq!(
        (no_sigma.status.as_str(), no_sigma.flags.as_slice()),
        (STATUS_FLAGGED, &[NO_STD_ERROR.to_string()][..])
    );
    assert!(super::unconverged("running").is_none() && super::unconverged("diverged").is_none());
}

/// A value outside a conventional aircraft's range by more than 2σ is flagged (Cm_q > 0);
/// judged again on the same evidence, nothing is added twice.
#[test]
fn plausibility_is_a_doubt_and_judging_twice_changes_nothing() {
    let model = ModelSpec::preset("longitudinal").unwrap();
    let evidence = Evidence { plausibility: Some((&model, true)), ..Default::default() };
    let mut r = result("Cm_q", 8.0, 0.5, None);
    judge(&mut r, &evidence);
    let once = r.clone();
    judge(&mut r, &evidence);
    assert_eq!(r, once);
    assert_eq!((r.status.as_str(), r.flags.len()), (STATUS_FLAGGED, 1), "{:?}", r.flags);
}

/// A current estimate judged by its own numbers: σ 0.01 on −1 gains 5.5 % of |−1| in
/// quadrature and is identified; at the significance edge the unmodelled share decides: a
/// noise σ of 0.4985 on −1 alone would be t = 2.006, with the share t = 1/0.5015 = 1.994
/// (flagged), and 0.49 stays t = 2.03 (identified); a
/// filter still `initialising` flags every estimate and leaves a parameter without one `not
/// identified`; `diverged` replaces the verdict; without thrust a drag term is withdrawn.
#[test]
fn a_current_estimate_judged_by_its_own_numbers() {
    let model = ModelSpec::preset("longitudinal").unwrap();
    let running = Status::Running.name();
    let r = judge_estimate("Cm_alpha", Some(-1.0), Some(0.01), running, &model, true);
    assert_eq!(r.status, STATUS_IDENTIFIED);
    assert!((r.std_error.unwrap() - 0.01f64.hypot(0.055)).abs() < 1e-15);
    let r = judge_estimate("Cm_q", Some(-1.0), Some(0.4985), running, &model, true);
    assert_eq!(r.status, STATUS_FLAGGED, "t = 1/hypot(0.4985, 0.055) < 2: {:?}", r.flags);
    let r = judge_estimate("Cm_q", Some(-1.0), Some(0.49), running, &model, true);
    assert_eq!(r.status, STATUS_IDENTIFIED, "t = 1/hypot(0.49, 0.055) > 2: {:?}", r.flags);
    let init = Status::Initialising.name();
    let r = judge_estimate("Cm_alpha", Some(-1.0), Some(0.01), init, &model, true);
    assert_eq!(r.status, STATUS_FLAGGED);
    assert!(r.flags[0].contains("initialising"), "{:?}", r.flags);
    let r = judge_estimate("Cm_de", None, None, init, &model, true);
    assert_eq!((r.status.as_str(), r.flags.len()), (STATUS_NOT_IDENTIFIED, 0));
    let diverged = Status::Diverged.name();
    let r = judge_estimate("Cm_alpha", Some(-1.0), Some(0.01), diverged, &model, true);
    assert_eq!(r.status, STATUS_DIVERGED);
    let r = judge_estimate("CD_alpha", Some(0.3), Some(0.01), running, &model, false);
    assert_ne!(r.status, STATUS_IDENTIFIED, "drag without thrust: {:?}", r.flags);
}

/// A strongly correlated pair names each side's partner in a note, with ρ; a parameter in no
/// pair gets none; the `combines` field names the partner with ρ; a note never blocks
/// `identified`.
#[test]
fn a_correlated_pair_is_a_combination_note_on_both() {
    let pairs = [aeroident_io::replay_output::Correlation {
        a: "Cm_q".into(),
        b: "Cm_alphadot".into(),
        rho: -0.97,
    }];
    let q = combination_notes("Cm_q", &pairs);
    let ad = combination_notes("Cm_alphadot", &pairs);
    assert_eq!(q.len(), 1);
    assert!(q[0].starts_with("combines with Cm_alphadot (ρ = -0.97)"), "{q:?}");
    assert!(ad[0].starts_with("combines with Cm_q (ρ = -0.97)"), "{ad:?}");
    assert!(combination_notes("Cm_alpha", &pairs).is_empty());
    let c = combinations("Cm_alphadot", &pairs);
    assert_eq!((c.len(), c[0].with.as_str(), c[0].rho), (1, "Cm_q", -0.97));
    assert!(combinations("Cm_alpha", &pairs).is_empty());
    let mut r = result("Cm_q", -10.0, 0.5, None);
    judge(&mut r, &Evidence { notes: q, ..Default::default() });
    assert_eq!((r.status.as_str(), r.notes.len()), (STATUS_IDENTIFIED, 1));
}
