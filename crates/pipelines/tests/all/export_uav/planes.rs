//! The aircraft the export tests fly (the `export_uav` oracles and the real JSBSim of
//! `aeroident`'s `export_jsbsim`), and the files `sim` flies them from: one table, included by
//! both test crates (`#[path]`).

/// An aircraft flown: its model's values, its constants (mass kg; Ixx, Iyy, Izz, Ixz kg·m²;
/// S m², b m, c̄ m) and its trim (m/s, m).
pub struct Plane {
    pub values: &'static [(&'static str, f64)],
    pub constants: [f64; 8],
    pub trim: (f64, f64),
}

/// A 3.3-kg UAV's six-axis model (uav_oat's mass, inertia and geometry), the drag an exact
/// polar.
pub const UAV: Plane = Plane {
    values: &[
        ("CL_0", 0.3),
        ("CL_alpha", 4.8),
        ("CL_q", 6.0),
        ("CL_de", 0.35),
        ("CD_0", 0.03),
        ("CD_alpha", 2.0 * 0.3 * 0.9 / 4.8),
        ("CD_alpha2", 0.9),
        ("CY_beta", -0.3),
        ("CY_p", -0.05),
        ("CY_r", 0.2),
        ("CY_dr", 0.15),
        ("Cl_beta", -0.08),
        ("Cl_p", -0.45),
        ("Cl_r", 0.1),
        ("Cl_da", -0.25),
        ("Cl_dr", 0.005),
        ("Cm_0", 0.02),
        ("Cm_alpha", -0.6),
        ("Cm_q", -9.0),
        ("Cm_de", -1.0),
        ("Cn_beta", 0.06),
        ("Cn_p", -0.03),
        ("Cn_r", -0.08),
        ("Cn_da", 0.004),
        ("Cn_dr", -0.05),
    ],
    constants: [3.3, 0.17, 0.289, 0.443, 0.019, 0.384, 1.6, 0.24],
    trim: (18.0, 100.0),
};

/// The JSBSim c172x's XML coefficients (aeroident's aileron sign), mass and inertia
/// (77.08 slug; ixx 2095.7, iyy 1505.0, izz 3150.4, ixz 13.55 slug·ft², JSBSim's element),
/// geometry (174 ft², 36 ft, 4.9 ft), CL_alpha the wing-body slope, a drag polar; 55 m/s,
/// 1524 m.
pub const C172X: Plane = Plane {
    values: &[
        ("CL_0", 0.25),
        ("CL_alpha", 5.33),
        ("CL_q", 3.9),
        ("CL_de", 0.347),
        ("CD_0", 0.027),
        ("CD_alpha", 2.0 * 0.25 * 0.3 / 5.33),
        ("CD_alpha2", 0.3),
        ("CY_beta", -0.309),
        ("CY_p", -0.037),
        ("CY_r", 0.21),
        ("CY_da", 0.05),
        ("CY_dr", 0.098),
        ("Cl_beta", -0.0891),
        ("Cl_p", -0.47),
        ("Cl_r", 0.0972),
        ("Cl_da", -0.23),
        ("Cl_dr", 0.0147),
        ("Cm_0", 0.06),
        ("Cm_alpha", -1.8),
        ("Cm_q", -12.4),
        ("Cm_de", -1.28),
        ("Cn_beta", 0.065),
        ("Cn_p", -0.03),
        ("Cn_r", -0.099),
        ("Cn_da", -0.0053),
        ("Cn_dr", -0.043),
    ],
    constants: [1124.9, 2841.4, 2040.5, 4271.4, -18.4, 16.165, 10.973, 1.4935],
    trim: (55.0, 1524.0),
};

/// A model file whose terms are `values`' names (per coefficient) with `values` as its
/// references.
pub fn model_toml(values: &[(&str, f64)]) -> String {
    let mut model = String::from("description = \"test aircraft\"\n[coefficients]\n");
    for c in ["CL", "CD", "CY", "Cl", "Cm", "Cn"] {
        let terms: Vec<String> = values
            .iter()
            .filter_map(|(n, _)| n.strip_prefix(&format!("{c}_")).map(|t| format!("\"{t}\"")))
            .collect();
        model.push_str(&format!("{c} = [{}]\n", terms.join(", ")));
    }
    for (n, v) in values {
        model.push_str(&format!("[reference.{n}]\nvalue = {v}\nsource = \"test\"\n"));
    }
    model
}

/// A mapping of `plane`'s constants (its channels name some record's columns), with an
/// extra channel line `de_line` (e.g. an elevator with an actuator).
pub fn mapping_toml(plane: &Plane, de_line: &str) -> String {
    let [m, ixx, iyy, izz, ixz, area, span, chord] = plane.constants;
    format!(
        "description = \"test\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = {{ column = \"v\", unit = \"m/s\" }}\nalpha = {{ column = \"a\", unit = \"rad\" }}\nqbar = {{ column = \"qbar\", unit = \"Pa\" }}\n{de_line}mass = {{ value = {m}, unit = \"kg\" }}\nIxx = {{ value = {ixx}, unit = \"kg*m2\" }}\nIyy = {{ value = {iyy}, unit = \"kg*m2\" }}\nIzz = {{ value = {izz}, unit = \"kg*m2\" }}\nIxz = {{ value = {ixz}, unit = \"kg*m2\" }}\nS = {{ value = {area}, unit = \"m2\" }}\nb = {{ value = {span}, unit = \"m\" }}\ncbar = {{ value = {chord}, unit = \"m\" }}\n"
    )
}

/// The `sim` scenario: trimmed at `plane`'s condition, 9 s at 200 Hz, a 2° elevator doublet
/// at 0.5 s, a 3° aileron doublet at 3.5 s, a 4° rudder doublet at 6.5 s (0.4-s pulses).
pub fn scenario_toml(plane: &Plane) -> String {
    let doublet = |ch: &str, deg: f64, t0: f64| {
        format!(
            "[[input]]\nchannel = \"{ch}\"\nkind = \"doublet\"\namplitude_deg = {deg}\nstart_s = {t0}\npulse_width_s = 0.4\n"
        )
    };
    format!(
        "kind = \"sim\"\n[trim]\nvt_mps = {}\nalt_m = {}\n[run]\nduration_s = 9.0\ndt_s = 0.005\n{}{}{}",
        plane.trim.0,
        plane.trim.1,
        doublet("elevator", 2.0, 0.5),
        doublet("aileron", 3.0, 3.5),
        doublet("rudder", 4.0, 6.5)
    )
}

/// The uav_oat records (`../shared/flightdata/uav_oat/csv`) the identified UAV is fitted from
/// with `mappings/uav_oat.toml`, six-axis output error: the 2023 flight's elevator and aileron
/// multisteps jointly (that flight's pair converges; its rudder was not excited).
pub const UAV_OAT_RECORDS: [&str; 2] =
    ["uavoat_2023_02_01_14_21_28_el_1.csv", "uavoat_2023_02_01_14_21_28_ail_1.csv"];

/// The uav_oat records' directory, `None` with a message when `../shared` is absent (a
/// failure under `CI=true`, where the data must be there).
pub fn uav_oat_dir() -> Option<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/flightdata/uav_oat/csv");
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "{} is absent under CI",
        dir.display()
    );
    eprintln!("SKIPPED: {} is absent (CI provides ../shared beside the repository)", dir.display());
    None
}

/// uav_oat's identified values completed for flight: each parameter the fit left `null` (the
/// drag, as thrust is not mapped; the rudder terms, not excited) takes the textbook UAV's value
/// of [`UAV`] (0 for a term it lacks), the stated prior a partial test card flies with — except
/// the drag's α terms, 0: [`UAV`]'s belong to a polar of its own lift, not the identified one,
/// so the filled drag is its parasitic `CD_0` alone.
/// Returns the values and the names filled.
pub fn completed(identified: &[(String, Option<f64>)]) -> (Vec<(String, f64)>, Vec<String>) {
    let prior = |n: &str| {
        let own = UAV.values.iter().find(|(p, _)| *p == n && !p.starts_with("CD_alpha"));
        own.map_or(0.0, |(_, v)| *v)
    };
    let filled = identified.iter().filter(|(_, v)| v.is_none()).map(|(n, _)| n.clone()).collect();
    let values =
        identified.iter().map(|(n, v)| (n.clone(), v.unwrap_or_else(|| prior(n)))).collect();
    (values, filled)
}
