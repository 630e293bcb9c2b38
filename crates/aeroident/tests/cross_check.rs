//! `replay --cross-check` on the HFB-320 record (../shared/flightdata; skipped with a message
//! when absent, a failure under CI): equation error's Cm_q (−42.6, the α channel lagging the
//! kinematics by ~0.2 s) is flagged against output error's (−27.9) with a time skew as the
//! likely cause, and every flag is more than 2 combined σ by the summaries' own numbers.

mod common;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_pipelines::replay::{ReplayOptions, cross_check_record, replay};
use common::{shared, workspace};

#[test]
fn val_hfb320_equation_error_pitch_damping_is_flagged_against_output_error() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let m = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    let model = ModelSpec::from_path(&workspace().join("models/hfb320_jategaonkar.toml")).unwrap();
    let opts = ReplayOptions { model: Some(model), ..Default::default() };
    let open = || open_log(&data.display().to_string(), None, &m).unwrap();
    let mut o = replay(open(), &m, &opts, &mut ()).unwrap();
    assert!(o.cross_check.is_none());
    cross_check_record(&mut o, open(), &m, &opts);
    let c = o.cross_check.as_ref().expect("the output-error fit converges on this record");
    assert_eq!((c.batch_estimator.as_str(), c.compared), ("oe", 11));
    let q = c.flagged.iter().find(|d| d.parameter == "Cm_q").expect("Cm_q is flagged");
    assert!(q.estimate < -40.0 && q.batch_estimate > -32.0, "{q:?}");
    assert!(q.likely_cause.contains("time skew"), "{}", q.likely_cause);
    for d in &c.flagged {
        let z = (d.estimate - d.batch_estimate).abs() / d.std_error.hypot(d.batch_std_error);
        assert!(z > 2.0 && (z - d.combined_sigmas).abs() < 1e-12, "{d:?}");
        let online = o.summary.parameters.iter().find(|p| p.name == d.parameter).unwrap();
        assert_eq!((online.estimate, online.std_error), (Some(d.estimate), Some(d.std_error)));
    }
    let warned = o.summary.warnings.iter().filter(|w| w.starts_with("cross-check:")).count();
    assert_eq!(warned, c.flagged.len());
}
