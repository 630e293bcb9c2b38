//! The committed header `include/aeroident.h` is the one cbindgen generates from the crate
//! (build.rs writes it to `$OUT_DIR`): C users take the header from the tree, so it must not
//! drift from the ABI.

#[test]
fn committed_header_is_cbindgens_output() {
    let generated = include_str!(concat!(env!("OUT_DIR"), "/aeroident.h"));
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/include/aeroident.h");
    let committed = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        committed == generated,
        "{path} is not cbindgen's output for the current sources; update it with\n  cp {}/aeroident.h {path}",
        env!("OUT_DIR")
    );
    // Every extern function of the crate is declared.
    for f in [
        "aeroident_estimator_new(",
        "aeroident_estimator_update(",
        "aeroident_estimator_estimates(",
        "aeroident_estimator_state(",
        "aeroident_estimator_verdicts(",
        "aeroident_estimator_flags(",
        "aeroident_estimator_reset(",
        "aeroident_estimator_free(",
        "aeroident_last_error_message(",
    ] {
        assert!(generated.contains(f), "{f} is not in the header");
    }
}

/// The C sample's fields are the CSV columns of the replayed samples after `manoeuvre` (`t_s`,
/// the estimators' `MEASURED_FIELDS`, the constants), then `present`: the struct is written
/// out by hand in `src/sample.rs`, and this holds it, through the header cbindgen makes of
/// it, to the one list of sample fields.
#[test]
fn the_c_samples_fields_are_the_sample_columns() {
    let generated = include_str!(concat!(env!("OUT_DIR"), "/aeroident.h"));
    let body = generated
        .split_once("typedef struct AeroidentSample {")
        .and_then(|(_, rest)| rest.split_once("} AeroidentSample;"))
        .expect("the header defines AeroidentSample")
        .0;
    let fields: Vec<&str> = body
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("//"))
        .filter_map(|l| l.strip_suffix(';')?.split_whitespace().last())
        .collect();
    let mut expected: Vec<&str> = aeroident_capi::replayed::SAMPLE_COLUMNS[1..].to_vec();
    expected.push("present");
    assert_eq!(fields, expected);
    let measured = &aeroident_estimators::sample::MEASURED_FIELDS;
    assert_eq!(fields[1..1 + measured.len()], measured[..]);
}
