//! Every shipped mapping (`mappings/*.toml`) and model file (`models/*.toml`) parses and has
//! the channels its records need.

use aeroident_io::{Channel, Mapping, ModelSpec};
use std::path::PathBuf;

fn dir(name: &str) -> Vec<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").join(name);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

#[test]
fn shipped_mappings_parse_and_map_what_their_records_are_for() {
    let maps = dir("mappings");
    for want in [
        "aeroident-sim.toml",
        "aeroident-sim-measured.toml",
        "attas.toml",
        "attas_lateral.toml",
        "hfb320.toml",
        "jsbsim.toml",
        "jsbsim_clean.toml",
        "mavlink-aeroident.toml",
        "twin_otter.toml",
        "px4-fixedwing.toml",
        "arduplane.toml",
        "arduplane-minimal.toml",
        "uav_oat.toml",
    ] {
        assert!(maps.iter().any(|p| p.ends_with(want)), "{want} missing: {maps:?}");
    }
    for p in &maps {
        let m = Mapping::from_path(p).unwrap_or_else(|e| panic!("{e}"));
        let name = p.file_name().unwrap().to_str().unwrap();
        let lateral = [Channel::Beta, Channel::Ay, Channel::Da, Channel::Dr, Channel::B];
        let has_lateral = lateral.iter().all(|c| m.has(*c));
        match name {
            // The MAVLink feed carries every channel (six-axis aircraft).
            "aeroident-sim.toml"
            | "aeroident-sim-measured.toml"
            | "attas_lateral.toml"
            | "jsbsim.toml"
            | "jsbsim_clean.toml"
            | "mavlink-aeroident.toml"
            | "px4-fixedwing.toml"
            | "arduplane.toml"
            | "uav_oat.toml" => {
                assert!(has_lateral, "{name}")
            }
            // Longitudinal records (and arduplane-minimal.toml, which has no surfaces): the
            // lateral preset must not be the default there.
            _ => assert!(!has_lateral, "{name}"),
        }
        // JSBSim logs the tensor element ixz = −Jxz: the mappings must flip it.
        if name.starts_with("jsbsim") {
            assert_eq!(m.channels[&Channel::Ixz].scale, -1.0, "{name}");
        }
    }
}

#[test]
fn shipped_model_files_parse() {
    let models = dir("models");
    assert!(!models.is_empty());
    for p in &models {
        let m = ModelSpec::from_path(p).unwrap_or_else(|e| panic!("{e}"));
        assert!(m.structure.n_params() > 0 && !m.description.is_empty(), "{}", p.display());
    }
}
