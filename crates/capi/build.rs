//! Generates the C header from the crate's extern functions and `#[repr(C)]` types into
//! `$OUT_DIR/aeroident.h`; the test `header` checks that the committed `include/aeroident.h`
//! equals it.

fn main() {
    let dir = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    let config = cbindgen::Config::from_file(format!("{dir}/cbindgen.toml"))
        .expect("crates/capi/cbindgen.toml is valid");
    cbindgen::Builder::new()
        .with_crate(&dir)
        .with_config(config)
        .generate()
        .expect("cbindgen parses crates/capi/src")
        .write_to_file(format!("{out}/aeroident.h"));
}
