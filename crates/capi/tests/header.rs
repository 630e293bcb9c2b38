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
