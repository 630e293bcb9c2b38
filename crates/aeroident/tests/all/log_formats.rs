//! The originals of the Jategaonkar records (`../shared/flightdata/jategaonkar_hfb320_attas/`:
//! the HFB-320 `.asc`, the ATTAS `.mat` matrices) replay through the shipped mappings to the
//! same estimates as their CSV copies, sample by sample. The README there says the CSV copies
//! hold "the same numbers" (checked independently: every value of every copy equals the
//! original's `f64`), so the estimates must be equal exactly, not to a tolerance. Skipped with
//! a message when `../shared` is absent; a failure under `CI=true`.

use crate::common;
use common::workspace;

/// `../shared/flightdata/jategaonkar_hfb320_attas/<rel>` as a path string, or `None`
/// ([`common::shared`]: SKIPPED, a failure under `CI=true`).
fn shared(rel: &str) -> Option<String> {
    common::shared(&format!("jategaonkar_hfb320_attas/{rel}")).map(|p| p.display().to_string())
}
use aeroident_io::{LogFormat, Mapping, open_log};
use aeroident_pipelines::estimators::EstimatorKind;
use aeroident_pipelines::replay::{ReplayOptions, ReplayOutcome, replay};

fn run(data: &str, format: Option<LogFormat>, map: &Mapping, est: EstimatorKind) -> ReplayOutcome {
    let reader = open_log(data, format, map).unwrap_or_else(|e| panic!("{e}"));
    let opts = ReplayOptions { estimator: est, ..Default::default() };
    replay(reader, map, &opts, &mut ()).unwrap_or_else(|e| panic!("{data}: {e}"))
}

/// Every estimate and σ at every sample, the rejections and the final summary parameters.
fn assert_same(a: &ReplayOutcome, b: &ReplayOutcome, what: &str) {
    assert!(a.summary.samples_read > 500, "{what}: {} samples", a.summary.samples_read);
    assert_eq!(a.summary.samples_read, b.summary.samples_read, "{what}");
    assert_eq!(a.summary.samples_rejected, b.summary.samples_rejected, "{what}");
    assert_eq!(a.history.stride, 1, "{what}: every sample kept");
    assert_eq!(a.history.t_s, b.history.t_s, "{what}");
    assert_eq!(a.history.values, b.history.values, "{what}: estimates");
    assert_eq!(a.history.sigmas, b.history.sigmas, "{what}: σ");
    let json = |o: &ReplayOutcome| serde_json::to_value(&o.summary.parameters).unwrap();
    assert_eq!(json(a), json(b), "{what}: summary parameters");
    let identified = a.summary.parameters.iter().filter(|p| p.estimate.is_some()).count();
    assert!(identified > 0, "{what}: nothing identified");
}

#[test]
fn val_hfb320_asc_gives_the_csv_copys_estimates_with_every_estimator() {
    let (Some(asc), Some(csv)) = (shared("hfb320_1_10.asc"), shared("csv/hfb320_1_10.csv")) else {
        return;
    };
    let map = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    for est in [EstimatorKind::Rls, EstimatorKind::Ftr, EstimatorKind::Ekf, EstimatorKind::Smpe] {
        let a = run(&asc, None, &map, est);
        let b = run(&csv, None, &map, est);
        assert_same(&a, &b, &format!("hfb320 {}", est.name()));
    }
    // The explicit format gives the same as the extension.
    let a = run(&asc, Some(LogFormat::Asc), &map, EstimatorKind::Rls);
    assert_same(&a, &run(&csv, Some(LogFormat::Csv), &map, EstimatorKind::Rls), "--format");
}

#[test]
fn val_attas_mat_gives_the_csv_copys_estimates() {
    for (rec, map) in [
        ("fAttasElv1", "attas.toml"),
        ("fAttasElv2", "attas.toml"),
        ("fAttasAil1", "attas_lateral.toml"),
        ("fAttasRud1", "attas_lateral.toml"),
        ("fAttasAilRud1", "attas_lateral.toml"),
        ("fAttasAilRud2", "attas_lateral.toml"),
    ] {
        let (Some(mat), Some(csv)) =
            (shared(&format!("{rec}.mat")), shared(&format!("csv/{rec}.csv")))
        else {
            return;
        };
        let map = Mapping::from_path(&workspace().join("mappings").join(map)).unwrap();
        for est in [EstimatorKind::Rls, EstimatorKind::Ekf] {
            let a = run(&mat, None, &map, est);
            assert_same(&a, &run(&csv, None, &map, est), &format!("{rec} {}", est.name()));
        }
    }
}

#[test]
fn errors_an_asc_with_a_text_header_or_the_wrong_mapping_name_the_line_and_count() {
    let Some(with_header) = shared("hfb320_1_10_withHeader.asc") else { return };
    let map = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    let e = open_log(&with_header, None, &map).err().unwrap().to_string();
    assert!(
        e.contains("line 1: 3 fields, but the mapping") && e.contains("names 20 columns"),
        "{e}"
    );
    assert!(e.contains("text"), "says the first line is text: {e}");
    let Some(mat) = shared("fAttasElv1.mat") else { return };
    let e = open_log(&mat, None, &map).err().unwrap().to_string();
    assert!(
        e.contains("variable `fAttasElv1` has 45 columns, but `[columns] names` names 20"),
        "{e}"
    );
}
