//! Time windows of a record (`replay --window START:END`) on ATTAS AilRud1, which is fAttasAil1
//! (50.08–80.08 s) and fAttasRud1 (110.16–140.16 s) joined (../shared/flightdata; skipped with a
//! message when absent, a failure under CI): a window is exactly the record it cuts out,
//! windows covering both manoeuvres are exactly the whole record, and the two records fitted
//! together (`--and`) are exactly the joined one.

mod common;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::replay::batch::{BatchSummary, FitOptions, fit_record, fit_records};
use aeroident_pipelines::window::TimeWindow;
use common::{shared, workspace};
use std::path::Path;

fn fit(data: &Path, windows: &[&str]) -> BatchSummary {
    let m = Mapping::from_path(&workspace().join("mappings/attas_lateral.toml")).unwrap();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let windows = windows.iter().map(|w| TimeWindow::parse(w).unwrap()).collect();
    fit_record(reader, &m, None, FitOptions { windows, ..Default::default() }).unwrap().summary
}

fn values(s: &BatchSummary) -> Vec<(String, f64, f64)> {
    s.parameters.iter().map(|p| (p.name.clone(), p.estimate, p.std_error)).collect()
}

#[test]
fn val_a_window_is_the_record_it_cuts_out() {
    let (Some(joined), Some(ail)) = (
        shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv"),
        shared("jategaonkar_hfb320_attas/csv/fAttasAil1.csv"),
    ) else {
        return;
    };
    let cut = fit(&joined, &["50:81"]);
    let alone = fit(&ail, &[]);
    assert_eq!(cut.manoeuvres, 1);
    assert_eq!(values(&cut), values(&alone));
    let note = cut.warnings.iter().find(|w| w.starts_with("time windows")).expect("a window note");
    assert!(note.contains("751 samples used, 751 outside"), "{note}");
    let both = fit(&joined, &["50:81", "110:141"]);
    let whole = fit(&joined, &[]);
    assert_eq!(both.manoeuvres, 2);
    assert_eq!(values(&both), values(&whole));
}

#[test]
fn val_two_records_fitted_together_are_the_joined_record() {
    let rel = |n: &str| shared(&format!("jategaonkar_hfb320_attas/csv/{n}.csv"));
    let (Some(joined), Some(ail), Some(rud)) =
        (rel("fAttasAilRud1"), rel("fAttasAil1"), rel("fAttasRud1"))
    else {
        return;
    };
    let m = Mapping::from_path(&workspace().join("mappings/attas_lateral.toml")).unwrap();
    let open = |p: &Path| open_log(&p.display().to_string(), None, &m).unwrap();
    let together =
        fit_records(vec![open(&ail), open(&rud)], &m, None, FitOptions::default()).unwrap().summary;
    let whole = fit(&joined, &[]);
    assert_eq!((together.manoeuvres, together.samples_read), (2, 1502));
    assert_eq!(values(&together), values(&whole));
}
