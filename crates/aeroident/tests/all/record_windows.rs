//! Time windows of a record (`replay --window START:END`) on ATTAS AilRud1, which is fAttasAil1
//! (50.08–80.08 s) and fAttasRud1 (110.16–140.16 s) joined (../shared/flightdata; skipped with a
//! message when absent, a failure under CI): a window is exactly the record it cuts out,
//! windows covering both manoeuvres are exactly the whole record, and the two records fitted
//! together (`--and`) are exactly the joined one.

use crate::common;
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::replay::batch::{BatchSummary, FitOptions};
use aeroident_pipelines::replay::fit::{fit_record, fit_records};
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
    s.parameters
        .iter()
        .map(|p| (p.name.clone(), p.estimate.unwrap(), p.std_error.unwrap()))
        .collect()
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

/// A window holding one sample (ATTAS at 25 Hz: 110.16–110.17 s holds the sample at 110.16 s)
/// is a manoeuvre output error cannot simulate: it is rejected by its row, named, and the fit is
/// exactly the one without it; windows that each hold at most one sample are an error that names
/// the file and the first rows.
#[test]
fn val_a_one_sample_window_is_rejected_by_row_not_an_anonymous_error() {
    let Some(joined) = shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv") else {
        return;
    };
    let with_lone = fit(&joined, &["50:81", "110.16:110.17"]);
    let without = fit(&joined, &["50:81"]);
    assert_eq!(values(&with_lone), values(&without));
    assert_eq!(with_lone.manoeuvres, 1);
    assert_eq!(with_lone.samples_rejected, without.samples_rejected + 1);
    let lone: Vec<_> = with_lone
        .rejections
        .iter()
        .filter(|r| r.reason.contains("manoeuvre of one sample"))
        .collect();
    assert_eq!(lone.len(), 1, "{:?}", with_lone.rejections);

    let m = Mapping::from_path(&workspace().join("mappings/attas_lateral.toml")).unwrap();
    let reader = open_log(&joined.display().to_string(), None, &m).unwrap();
    let tiny: Vec<TimeWindow> = (0..590)
        .map(|k| {
            TimeWindow::parse(&format!("{}:{}", 50.0 + 0.1 * k as f64, 50.03 + 0.1 * k as f64))
                .unwrap()
        })
        .collect();
    let err = match fit_record(reader, &m, None, FitOptions { windows: tiny, ..Default::default() })
    {
        Ok(_) => panic!("windows of at most one sample each cannot be fitted"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("fAttasAilRud1.csv"), "{err}");
    assert!(err.contains("manoeuvre of one sample"), "{err}");
    assert!(err.contains("row"), "{err}");
}

/// Windows beyond the record's end (AilRud1 spans 50.08–140.16 s) are an error naming the
/// `--window` option, the windows and the record's time span, for the batch fit and the
/// real-time estimators alike, not "no usable samples (0 rows rejected)".
#[test]
fn errors_windows_outside_the_record_name_the_windows_and_its_span() {
    let Some(joined) = shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv") else {
        return;
    };
    let m = Mapping::from_path(&workspace().join("mappings/attas_lateral.toml")).unwrap();
    let windows: Vec<TimeWindow> =
        ["200:300", "400:500"].iter().map(|w| TimeWindow::parse(w).unwrap()).collect();
    let file = joined.display().to_string();
    let check = |e: String| {
        assert!(e.contains("option `--window`") && e.contains(&file), "{e}");
        assert!(e.contains("windows 200:300, 400:500 lie outside"), "{e}");
        assert!(e.contains("50.08 to 140.16 s"), "{e}");
        assert!(!e.contains("no usable samples"), "{e}");
    };
    let reader = open_log(&file, None, &m).unwrap();
    let options = FitOptions { windows: windows.clone(), ..Default::default() };
    check(fit_record(reader, &m, None, options).unwrap_err().to_string());
    let reader = open_log(&file, None, &m).unwrap();
    let opts = aeroident_pipelines::replay::ReplayOptions { windows, ..Default::default() };
    check(aeroident_pipelines::replay::replay(reader, &m, &opts, &mut ()).unwrap_err().to_string());
}

/// A record whose every row is rejected (the elevator NaN throughout), fitted or replayed in a
/// window, is refused with the rejections counted and named, as without the window: the
/// window stage dropped them unplaced and the error read "no usable samples (0 rows
/// rejected)", hiding the column.
#[test]
fn errors_every_row_rejected_in_a_window_names_the_rejections() {
    let map = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\nthrust = { value = 0.0, unit = \"N\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";
    let m = Mapping::from_toml_str(map, "m.toml").unwrap();
    let mut csv = String::from("t,V,a,q,ax,az,de\n");
    for k in 0..100 {
        csv.push_str(&format!("{:.1},50,0.05,0.01,0.1,-9.8,NaN\n", f64::from(k) * 0.1));
    }
    let windows = vec![TimeWindow::parse("1:5").unwrap()];
    let check = |e: String| {
        assert!(e.contains("no usable samples (100 rows rejected"), "{e}");
        assert!(e.contains("column `de`"), "{e}");
    };
    let reader = aeroident_io::FlightDataReader::new(csv.as_bytes(), "nan_de.csv", &m).unwrap();
    let options = FitOptions { windows: windows.clone(), ..Default::default() };
    check(fit_record(reader, &m, None, options).unwrap_err().to_string());
    let reader = aeroident_io::FlightDataReader::new(csv.as_bytes(), "nan_de.csv", &m).unwrap();
    let opts = aeroident_pipelines::replay::ReplayOptions { windows, ..Default::default() };
    check(aeroident_pipelines::replay::replay(reader, &m, &opts, &mut ()).unwrap_err().to_string());
}
