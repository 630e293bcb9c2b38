//! `replay --cross-check` on the HFB-320 record (../shared/flightdata; skipped with a message
//! when absent, a failure under CI): equation error's Cm_q (−42.6, the α channel lagging the
//! kinematics by ~0.2 s) is flagged against output error's (−27.9) with a time skew as the
//! likely cause, and every flag is more than 2 combined σ by the summaries' own numbers. The
//! verdicts in the summary follow: the flagged parameter's status names the disagreement and
//! its flags carry the warning; a batch fit's references are the model file's, judged ±2σ.

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
    for p in &o.summary.parameters {
        let flagged = c.flagged.iter().find(|d| d.parameter == p.name);
        match flagged {
            Some(d) => {
                assert_eq!(p.status, "flagged", "{p:?}");
                let want = format!("by {:.1} combined σ", d.combined_sigmas);
                assert!(
                    p.flags.iter().any(|f| f.starts_with("cross-check: ") && f.contains(&want))
                );
            }
            None => assert!(!p.flags.iter().any(|f| f.starts_with("cross-check")), "{p:?}"),
        }
    }
}

/// The batch fit's verdicts: each reference is the model file's `[reference.X]` value (read
/// here from the TOML itself), flagged as outside ±2σ exactly when that value lies more than 2
/// reported σ from the estimate, and σ's source and the Cramér–Rao σ are named.
#[test]
fn val_hfb320_output_error_verdicts_against_the_model_files_references() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let m = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    let path = workspace().join("models/hfb320_book_q0.toml");
    let model = ModelSpec::from_path(&path).unwrap();
    let text: toml::Value = toml::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let published = text["reference"].as_table().unwrap();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let options = aeroident_pipelines::replay::batch::FitOptions::default();
    let fit =
        aeroident_pipelines::replay::fit::fit_record(reader, &m, Some(model), options).unwrap();
    let mut judged = 0;
    for p in &fit.summary.parameters {
        let want = published.get(&p.name).map(|r| r["value"].as_float().unwrap());
        assert_eq!(p.reference, want, "{}", p.name);
        let (e, s) = (p.estimate.unwrap(), p.std_error.unwrap());
        assert!(p.crb_std_error.is_some_and(|c| c > 0.0), "{p:?}");
        assert!(p.std_error_source.is_some(), "{p:?}");
        let outside = want.is_some_and(|r| (e - r).abs() > 2.0 * s);
        let flagged_outside = p.flags.iter().any(|f| f.contains("(outside ±2σ)"));
        assert_eq!(flagged_outside, outside, "{p:?}");
        let want_status = if p.flags.is_empty() { "identified" } else { "flagged" };
        assert_eq!(p.status, want_status, "{p:?}");
        judged += usize::from(want.is_some());
    }
    assert_eq!(judged, published.len(), "every published value is set beside its estimate");
}

/// A filter-error fit whose measurement-noise variance collapsed is flagged: the HFB-320 `fem`
/// fit is healthy (every noise variance 0.2–0.9 of its innovation variance, measured), so
/// nothing is said; with one variance set to a millionth of its innovation variance, as a
/// degenerate filter ends, every estimate is flagged and a consistency warning names the output.
#[test]
fn val_hfb320_filter_error_with_a_collapsed_noise_variance_is_flagged() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let m = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    let model = ModelSpec::from_path(&workspace().join("models/hfb320_book_q0.toml")).unwrap();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let options = aeroident_pipelines::replay::batch::FitOptions {
        method: aeroident_pipelines::replay::batch::BatchMethod::Fem,
        ..Default::default()
    };
    let mut fit =
        aeroident_pipelines::replay::fit::fit_record(reader, &m, Some(model.clone()), options)
            .unwrap();
    let s = &mut fit.summary;
    assert_eq!(s.collapsed_noise(), None, "{:?}", s.measurement_noise_var);
    assert!(s.parameters.iter().all(|p| !p.flags.iter().any(|f| f.contains("degenerate"))));
    let (name, rms) = s.residual_rms[1].clone();
    let k = s.measurement_noise_var.iter().position(|(n, _)| *n == name).unwrap();
    s.measurement_noise_var[k].1 = 1e-6 * rms * rms;
    s.judge(&model, true);
    for p in &s.parameters {
        assert_eq!(p.status, "flagged", "{p:?}");
        assert!(p.flags.iter().any(|f| f.starts_with("degenerate filter") && f.contains(&name)));
    }
    assert!(s.warnings.iter().any(|w| w.starts_with("degenerate filter")));
}
