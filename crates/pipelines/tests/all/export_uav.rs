//! `export ardupilot` and `export gazebo` checked against the targets' formulas: each test
//! writes a small summary with known coefficients, exports it, reads the file back and
//! evaluates the forces and moments the target would compute from it — its formula written
//! out here from its source (ArduPilot `libraries/SITL/SIM_Plane.cpp` `getForce`/`getTorque`;
//! gz-sim `AdvancedLiftDrag.cc` `Update`, docs/export.md), not through the exporter — at random
//! states, and compares them with aeroident's own model (the summary's values times
//! `Term::value`, dimensional with q̄S, b, c̄) to 1e-9 of the largest component. Each test
//! also mutates one exported value and checks the comparison then fails.

use aeroident_estimators::sample::{AirDataSample, AircraftConstants};
use aeroident_estimators::vocabulary::Term;
use aeroident_estimators::vocabulary::{AlphaKnots, Coefficient, Param};
use aeroident_models::aircraft::AircraftMass;
use aeroident_pipelines::export::ardupilot::{ArdupilotOptions, Throws, ardupilot_json};
use aeroident_pipelines::export::gazebo::{ControlJoint, GazeboOptions, gazebo_plugin_sdf};
use aeroident_pipelines::export::uav::Geometry;
use aeroident_pipelines::summary_file::{SummaryParameters, read_summary};

mod flight;
mod planes;

const GEOMETRY: Geometry = Geometry { area_m2: 0.9, span_m: 1.95, chord_m: 0.47 };

/// One flight state: the flow angles as the target defines them, body rates (FRD), the speed
/// the target normalises with, and aeroident's surface deflections, rad.
#[derive(Debug, Clone, Copy)]
struct State {
    alpha: f64,
    beta: f64,
    p: f64,
    q: f64,
    r: f64,
    v: f64,
    de: f64,
    da: f64,
    dr: f64,
}

/// Deterministic uniform samples (xorshift64*), so a failure reproduces.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let u = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }

    fn state(&mut self) -> State {
        State {
            alpha: self.uniform(-0.12, 0.12),
            beta: self.uniform(-0.15, 0.15),
            p: self.uniform(-1.0, 1.0),
            q: self.uniform(-1.0, 1.0),
            r: self.uniform(-1.0, 1.0),
            v: self.uniform(12.0, 35.0),
            de: self.uniform(-0.2, 0.2),
            da: self.uniform(-0.2, 0.2),
            dr: self.uniform(-0.2, 0.2),
        }
    }
}

/// Writes `params` as a replay summary and reads it back.
fn summary(tag: &str, params: &[(&str, Option<f64>)]) -> SummaryParameters {
    let dir = std::env::temp_dir().join(format!("aeroident-export-uav-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{tag}.json"));
    let json = serde_json::json!({"estimator": "oe", "model": "test", "parameters":
        params.iter().map(|(n, v)| serde_json::json!({"name": n, "estimate": v, "std_error": 0.01}))
            .collect::<Vec<_>>()});
    std::fs::write(&path, json.to_string()).unwrap();
    read_summary(&path).unwrap()
}

/// aeroident's model at `s`: body forces (FRD, N) and moments (N·m) from the coefficients
/// `Σ value · Term::value`, CL and CD rotated from the stability axes by α.
fn aeroident_model(params: &[(&str, Option<f64>)], s: &State, rho: f64) -> [f64; 6] {
    let sample = AirDataSample {
        vt_mps: s.v,
        alpha_rad: s.alpha,
        qbar_pa: 0.5 * rho * s.v * s.v,
        beta_rad: Some(s.beta),
        p_rad_s: Some(s.p),
        q_rad_s: Some(s.q),
        r_rad_s: Some(s.r),
        de_rad: Some(s.de),
        da_rad: Some(s.da),
        dr_rad: Some(s.dr),
        constants: AircraftConstants {
            mass_kg: 5.0,
            S_m2: GEOMETRY.area_m2,
            cbar_m: Some(GEOMETRY.chord_m),
            b_m: Some(GEOMETRY.span_m),
            ..AircraftConstants::default()
        },
        ..AirDataSample::default()
    };
    let mut c = [0.0; 8];
    // A parameter not identified contributes nothing (its target value is 0).
    for (name, v) in params.iter().filter_map(|(n, v)| v.map(|v| (n, v))) {
        let p = Param::from_name(name).unwrap();
        let xi = p.term.value(&sample, &AlphaKnots::NONE).unwrap();
        c[p.coefficient.index()] += v * xi;
    }
    let at = |k: Coefficient| c[k.index()];
    let (sa, ca) = s.alpha.sin_cos();
    let (cl, cd) = (at(Coefficient::CL), at(Coefficient::CD));
    let qs = sample.qbar_pa * GEOMETRY.area_m2;
    [
        qs * (-cd * ca + cl * sa),
        qs * at(Coefficient::CY),
        qs * (-cd * sa - cl * ca),
        qs * GEOMETRY.span_m * at(Coefficient::Cl),
        qs * GEOMETRY.chord_m * at(Coefficient::Cm),
        qs * GEOMETRY.span_m * at(Coefficient::Cn),
    ]
}

/// Largest difference of forces (relative to the largest force) and of moments (to the
/// largest moment).
fn relative_error(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    let part = |r: std::ops::Range<usize>| {
        let scale = r.clone().map(|i| b[i].abs()).fold(0.0, f64::max);
        r.map(|i| (a[i] - b[i]).abs() / scale).fold(0.0, f64::max)
    };
    part(0..3).max(part(3..6))
}

/// ArduPilot SITL's plane (`SIM_Plane.cpp`, docs/export.md) from the file's keys: body forces
/// and moments at `s` with density `rho`.
fn ardupilot_plane(k: &serde_json::Value, s: &State, rho: f64) -> [f64; 6] {
    let g = |n: &str| k[n].as_f64().unwrap_or_else(|| panic!("no key {n}"));
    let (area, b, c) = (g("s"), g("b"), g("c"));
    // Servo commands ±1, positive for a positive body moment: the opposite of aeroident's δ.
    let (ua, ue, ur) = (-s.da / g("deltaa_max"), -s.de / g("deltae_max"), -s.dr / g("deltar_max"));
    let (ph, qh, rh) = (s.p * b / (2.0 * s.v), s.q * c / (2.0 * s.v), s.r * b / (2.0 * s.v));
    let (m, a0) = (g("mcoeff"), g("alpha_stall"));
    let a = s.alpha.clamp(a0 - 0.8, a0 + 0.8);
    let sigma = (1.0 + (-m * (a - a0)).exp() + (m * (a + a0)).exp())
        / (1.0 + (-m * (a - a0)).exp())
        / (1.0 + (m * (a + a0)).exp());
    let al = s.alpha;
    let lin = g("c_lift_0") + g("c_lift_a") * al;
    let cl_a = (1.0 - sigma) * lin + sigma * 2.0 * al.signum() * al.sin().powi(2) * al.cos();
    let cd_a = g("c_drag_p") + lin * lin / (std::f64::consts::PI * g("oswald") * b * b / area);
    let (sa, ca) = al.sin_cos();
    let cx_q = -g("c_drag_q") * ca + g("c_lift_q") * sa;
    let cz_q = -g("c_drag_q") * sa - g("c_lift_q") * ca;
    let qbar = 0.5 * rho * s.v * s.v * area;
    let fx = qbar
        * (-cd_a * ca + cl_a * sa + cx_q * qh - g("c_drag_deltae") * ca * ue.abs()
            + g("c_lift_deltae") * sa * ue);
    let fz = qbar
        * (-cd_a * sa - cl_a * ca + cz_q * qh
            - g("c_drag_deltae") * sa * ue.abs()
            - g("c_lift_deltae") * ca * ue);
    let lat = |pre: &str| {
        g(&format!("{pre}_0"))
            + g(&format!("{pre}_b")) * s.beta
            + g(&format!("{pre}_p")) * ph
            + g(&format!("{pre}_r")) * rh
            + g(&format!("{pre}_deltaa")) * ua
            + g(&format!("{pre}_deltar")) * ur
    };
    let fy = qbar * lat("c_y");
    let cm = g("c_m_0") + g("c_m_a") * al + g("c_m_q") * qh + g("c_m_deltae") * ue;
    let (l, mm, n) = (qbar * b * lat("c_l"), qbar * c * cm, qbar * b * lat("c_n"));
    let cg: Vec<f64> =
        k["CGOffset"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    [
        fx,
        fy,
        fz,
        l + cg[1] * fz - cg[2] * fy,
        mm - cg[0] * fz + cg[2] * fx,
        n - cg[1] * fx + cg[0] * fy,
    ]
}

/// A six-axis model SITL's plane holds: the drag a polar on CL_0 + CL_alpha α (CD_alpha =
/// 2 CL_0 CD_alpha2 / CL_alpha); Cm_alphadot not identified.
fn ardupilot_params() -> Vec<(&'static str, Option<f64>)> {
    vec![
        ("CL_0", Some(0.31)),
        ("CL_alpha", Some(5.1)),
        ("CL_q", Some(3.9)),
        ("CL_de", Some(0.43)),
        ("CD_0", Some(0.031)),
        ("CD_alpha", Some(2.0 * 0.31 * 0.8 / 5.1)),
        ("CD_alpha2", Some(0.8)),
        ("CD_q", Some(0.05)),
        ("CY_0", Some(0.01)),
        ("CY_beta", Some(-0.31)),
        ("CY_p", Some(-0.04)),
        ("CY_r", Some(0.2)),
        ("CY_da", Some(0.02)),
        ("CY_dr", Some(0.187)),
        ("Cl_0", Some(0.001)),
        ("Cl_beta", Some(-0.089)),
        ("Cl_p", Some(-0.47)),
        ("Cl_r", Some(0.096)),
        ("Cl_da", Some(-0.178)),
        ("Cl_dr", Some(0.0147)),
        ("Cm_0", Some(-0.015)),
        ("Cm_alpha", Some(-0.89)),
        ("Cm_q", Some(-12.4)),
        ("Cm_alphadot", None),
        ("Cm_de", Some(-1.28)),
        ("Cn_0", Some(0.002)),
        ("Cn_beta", Some(0.065)),
        ("Cn_p", Some(-0.03)),
        ("Cn_r", Some(-0.099)),
        ("Cn_da", Some(-0.053)),
        ("Cn_dr", Some(-0.0657)),
    ]
}

/// A 5-kg UAV's mass and inertia (kg, kg·m²), with a product of inertia.
const UAV_MASS: AircraftMass =
    AircraftMass { mass_kg: 5.0, jx_kgm2: 0.8, jy_kgm2: 1.1, jz_kgm2: 1.7, jxz_kgm2: 0.09 };

fn ardupilot_options(drop: bool) -> ArdupilotOptions {
    ArdupilotOptions {
        geometry: GEOMETRY,
        throws: Throws { aileron_rad: 0.35, elevator_rad: 0.4, rudder_rad: 0.3 },
        alpha_stall_rad: 0.6,
        mcoeff: 50.0,
        drop_unrepresentable: drop,
        mass: UAV_MASS,
        sitl_mass_kg: 2.0,
        notes: vec![],
    }
}

/// The rigid body's accelerations from body forces and moments `fm`: `F/m` and `J⁻¹ M`
/// without the rate products (Stevens & Lewis tensor `[[Jx,0,−Jxz],[0,Jy,0],[−Jxz,0,Jz]]`,
/// its roll–yaw block solved by Cramer's rule).
fn rigid_body_accelerations(fm: &[f64; 6], m: &AircraftMass) -> [f64; 6] {
    let det = m.jx_kgm2 * m.jz_kgm2 - m.jxz_kgm2 * m.jxz_kgm2;
    [
        fm[0] / m.mass_kg,
        fm[1] / m.mass_kg,
        fm[2] / m.mass_kg,
        (m.jz_kgm2 * fm[3] + m.jxz_kgm2 * fm[5]) / det,
        fm[4] / m.jy_kgm2,
        (m.jxz_kgm2 * fm[3] + m.jx_kgm2 * fm[5]) / det,
    ]
}

/// SITL's accelerations from its force and moment (`Plane::calculate_forces`,
/// `Aircraft::update_dynamics`): the force over its own mass, the moment as ω̇.
fn sitl_accelerations(fm: &[f64; 6], sitl_mass_kg: f64) -> [f64; 6] {
    [fm[0] / sitl_mass_kg, fm[1] / sitl_mass_kg, fm[2] / sitl_mass_kg, fm[3], fm[4], fm[5]]
}

/// The largest relative difference over 500 random states.
fn worst(model: impl Fn(&State) -> [f64; 6], target: impl Fn(&State) -> [f64; 6]) -> f64 {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    (0..500)
        .map(|_| rng.state())
        .map(|s| relative_error(&target(&s), &model(&s)))
        .fold(0.0, f64::max)
}

#[test]
fn ardupilot_file_gives_the_aircrafts_accelerations_in_sitls_equations() {
    let params = ardupilot_params();
    let out =
        ardupilot_json(&summary("ap", &params), "ap.json", &ardupilot_options(false)).unwrap();
    let k: serde_json::Value = serde_json::from_str(&out.text).unwrap();
    let rho = 1.225;
    let model = |s: &State| rigid_body_accelerations(&aeroident_model(&params, s, rho), &UAV_MASS);
    let sitl =
        |k: &serde_json::Value, s: &State| sitl_accelerations(&ardupilot_plane(k, s, rho), 2.0);
    let e = worst(model, |s| sitl(&k, s));
    assert!(e < 1e-9, "SITL's plane differs from the model by {e:e}\n{}", out.text);
    // Unscaled (the aircraft's own coefficients), SITL's accelerations would be wrong.
    let mut unit = k.clone();
    unit["c_m_a"] = serde_json::json!(k["c_m_a"].as_f64().unwrap() * UAV_MASS.jy_kgm2);
    assert!(worst(model, |s| sitl(&unit, s)) > 1e-3, "an unscaled c_m_a went unseen");
    assert!(k["aeroident_notes"].to_string().contains("SITL mass"), "the scaling is not noted");
    // The unidentified derivative is named, in the warnings and in the file's notes.
    assert!(out.warnings.iter().any(|w| w.contains("Cm_alphadot")), "{:?}", out.warnings);
    assert!(k["aeroident_notes"].to_string().contains("Cm_alphadot"));
    // The comparison can fail: the aileron sign flipped is seen.
    let mut wrong = k.clone();
    wrong["c_l_deltaa"] = serde_json::json!(-k["c_l_deltaa"].as_f64().unwrap());
    let e = worst(model, |s| sitl(&wrong, s));
    assert!(e > 1e-3, "a flipped c_l_deltaa went unseen ({e:e})");
}

#[test]
fn ardupilot_refuses_what_sitl_cannot_hold_unless_dropping_is_asked() {
    let mut params = ardupilot_params();
    params.push(("Cm_alpha2", Some(-0.7)));
    params.push(("CD_de", Some(0.02)));
    params[5].1 = Some(0.05); // CD_alpha off the polar
    let s = summary("ap-bad", &params);
    let e = ardupilot_json(&s, "ap-bad.json", &ardupilot_options(false)).unwrap_err().to_string();
    for name in ["Cm_alpha2", "CD_de", "CD_alpha", "--drop-unrepresentable", "ap-bad.json"] {
        assert!(e.contains(name), "{name} not named:\n{e}");
    }
    let out = ardupilot_json(&s, "ap-bad.json", &ardupilot_options(true)).unwrap();
    for name in ["Cm_alpha2", "CD_de", "CD_alpha"] {
        assert!(out.warnings.iter().any(|w| w.contains(name)), "{name}: {:?}", out.warnings);
        assert!(out.text.contains(name), "{name} not noted in the file");
    }
    // The same terms at exactly 0 need nothing of SITL's formula.
    let mut zero = ardupilot_params();
    zero.extend([("Cm_alpha2", Some(0.0)), ("CD_de", Some(0.0))]);
    let s = summary("ap-zero", &zero);
    assert!(ardupilot_json(&s, "ap-zero.json", &ardupilot_options(false)).is_ok());
    // Body-axis coefficients are not SITL's.
    let s = summary("ap-body", &[("CX_alpha", Some(0.1)), ("CZ_alpha", Some(-4.0))]);
    let e = ardupilot_json(&s, "b.json", &ardupilot_options(false)).unwrap_err().to_string();
    assert!(e.contains("CX_alpha") && e.contains("CZ_alpha"), "{e}");
}

/// `a × b`.
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// The elements of the plugin: scalars by name, control surfaces as (direction, derivatives
/// by name), and the vectors.
struct Sdf {
    scalars: std::collections::BTreeMap<String, String>,
    surfaces: Vec<(String, std::collections::BTreeMap<String, f64>)>,
}

impl Sdf {
    fn parse(text: &str) -> Sdf {
        let mut r = quick_xml::Reader::from_str(text);
        r.config_mut().check_comments = true;
        let (mut path, scalars, mut surfaces) =
            (Vec::<String>::new(), Default::default(), Vec::new());
        let mut scalars: std::collections::BTreeMap<String, String> = scalars;
        loop {
            match r.read_event().unwrap() {
                quick_xml::events::Event::Start(e) => {
                    let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                    if name == "control_surface" {
                        surfaces.push((String::new(), Default::default()));
                    }
                    path.push(name);
                }
                quick_xml::events::Event::End(_) => {
                    path.pop();
                }
                quick_xml::events::Event::Text(t) => {
                    let text = std::str::from_utf8(&t).unwrap().trim().to_string();
                    match path.as_slice() {
                        [_, s, el] if s == "control_surface" => {
                            let (name, values): &mut (
                                String,
                                std::collections::BTreeMap<String, f64>,
                            ) = surfaces.last_mut().unwrap();
                            if el == "name" {
                                *name = text;
                            } else {
                                values.insert(el.clone(), text.parse().unwrap());
                            }
                        }
                        [_, el] => {
                            scalars.insert(el.clone(), text);
                        }
                        _ => {}
                    }
                }
                quick_xml::events::Event::Eof => break,
                _ => {}
            }
        }
        scalars = std::mem::take(&mut scalars);
        Sdf { scalars, surfaces }
    }

    fn f(&self, name: &str) -> f64 {
        self.scalars.get(name).unwrap_or_else(|| panic!("no <{name}>")).parse().unwrap()
    }

    fn v(&self, name: &str) -> [f64; 3] {
        let x: Vec<f64> =
            self.scalars[name].split_whitespace().map(|t| t.parse().unwrap()).collect();
        [x[0], x[1], x[2]]
    }
}

/// The plugin's `Update` (docs/export.md) on a link at the identity pose with the file's
/// forward/upward: the state's air velocity at the link origin (the CG) and rates given in
/// the link's FLU frame, the air velocity taken at `cp` as the source does, the resulting
/// force and torque about the origin returned in FRD body axes. `V` of the state is the
/// speed in the body x–z plane at the CG; the joints are at `θ = direction · δ` with `δ`
/// given per joint. `fixed`: `Cem = Cem0 + Cema α + Cemb β` (a corrected plugin) instead of
/// the source's overwrite `Cem = Cemb β`.
fn gazebo_plugin(sdf: &Sdf, s: &State, joints: &[(&str, f64)], fixed: bool) -> [f64; 6] {
    let (u, w) = (s.v * s.alpha.cos(), s.v * s.alpha.sin());
    let omega = [s.p, -s.q, -s.r];
    let vel = add([u, -u * s.beta.tan(), -w], cross(omega, sdf.v("cp")));
    let bx = sdf.v("forward");
    let bz = scale(sdf.v("upward"), -1.0);
    let by = cross(bz, bx);
    let vld = add(vel, scale(by, -dot(vel, by)));
    let speed = dot(vld, vld).sqrt();
    let sx = scale(vld, 1.0 / speed);
    let sz = cross(sx, by);
    let alpha = dot(sx, bz).atan2(dot(sx, bx));
    let beta = dot(vel, by).atan2(dot(vel, bx));
    let (rr, pr, yr) = (omega[0], -omega[1], -omega[2]);
    let (area, ar, mac, rho) = (sdf.f("area"), sdf.f("AR"), sdf.f("mac"), sdf.f("air_density"));
    let span = (area * ar).sqrt();
    let (dyn_pres, half_rho_vel) = (0.5 * rho * speed * speed, 0.5 * rho * speed);
    let (m, a0) = (15.0, sdf.f("alpha_stall"));
    let sigma = (1.0 + (-m * (alpha - a0)).exp() + (m * (alpha + a0)).exp())
        / ((1.0 + (-m * (alpha - a0)).exp()) * (1.0 + (m * (alpha + a0)).exp()));
    let mut ctrl = std::collections::BTreeMap::<String, f64>::new();
    for (name, values) in &sdf.surfaces {
        let delta = joints.iter().find(|(j, _)| j == name).unwrap().1;
        let d = values["direction"];
        let theta_deg = (d * delta).to_degrees();
        for (k, v) in values.iter().filter(|(k, _)| k.ends_with("_ctrl")) {
            *ctrl.entry(k.clone()).or_default() += theta_deg * v * d;
        }
    }
    let c = |k: &str| ctrl.get(k).copied().unwrap_or(0.0);
    let (sa, ca) = alpha.sin_cos();
    let rates = |pre: &str| {
        sdf.f(&format!("{pre}p")) * (rr * span / 2.0) * half_rho_vel
            + sdf.f(&format!("{pre}q")) * (pr * mac / 2.0) * half_rho_vel
            + sdf.f(&format!("{pre}r")) * (yr * span / 2.0) * half_rho_vel
    };
    let mut cl = (1.0 - sigma) * (sdf.f("CL0") + sdf.f("CLa") * alpha)
        + sigma * 2.0 * alpha.signum() * sa * sa * ca;
    cl += sdf.f("CLb") * beta + c("CL_ctrl");
    let lift = scale(sz, -(cl * dyn_pres + rates("CL")) * area);
    let cd_fp = 2.0 / (1.0 + (-0.224 - 0.115 * ar.max(1.0 / ar)).exp());
    let cd = (1.0 - sigma) * (sdf.f("CD0") + cl * cl / (std::f64::consts::PI * ar * sdf.f("eff")))
        + sigma * (cd_fp * (0.5 - 0.5 * (2.0 * alpha).cos())).abs()
        + c("CD_ctrl");
    let drag = scale(sx, -(cd * dyn_pres + rates("CD")) * area);
    let cy = sdf.f("CYa") * alpha + sdf.f("CYb") * beta + c("CY_ctrl");
    let side = scale(by, (cy * dyn_pres + rates("CY")) * area);
    // As in the source: Cem0 + Cema α is computed, then replaced by Cemb β.
    let static_pitch = if fixed { sdf.f("Cem0") + sdf.f("Cema") * alpha } else { 0.0 };
    let cem = static_pitch + sdf.f("Cemb") * beta + c("Cem_ctrl");
    let pm = scale(by, (cem * dyn_pres + rates("Cem")) * area * mac);
    let cell = sdf.f("Cella") * alpha + sdf.f("Cellb") * beta + c("Cell_ctrl");
    let rm = scale(bx, (cell * dyn_pres + rates("Cell")) * area * span);
    let cen = sdf.f("Cena") * alpha + sdf.f("Cenb") * beta + c("Cen_ctrl");
    let ym = scale(bz, (cen * dyn_pres + rates("Cen")) * area * span);
    let force = add(add(lift, drag), side);
    let torque = add(add(add(pm, rm), ym), cross(sdf.v("cp"), force));
    [force[0], -force[1], -force[2], torque[0], -torque[1], -torque[2]]
}

/// A model the plugin holds (Cm_alpha through the centre of pressure): no induced drag, since
/// its lift has surface terms.
fn gazebo_params() -> Vec<(&'static str, Option<f64>)> {
    vec![
        ("CL_0", Some(0.31)),
        ("CL_alpha", Some(5.1)),
        ("CL_beta", Some(0.02)),
        ("CL_q", Some(3.9)),
        ("CL_de", Some(0.43)),
        ("CD_0", Some(0.031)),
        ("CD_q", Some(0.05)),
        ("CD_de", Some(0.012)),
        ("CY_alpha", Some(0.03)),
        ("CY_beta", Some(-0.31)),
        ("CY_p", Some(-0.04)),
        ("CY_r", Some(0.2)),
        ("CY_da", Some(0.02)),
        ("CY_dr", Some(0.187)),
        ("Cl_alpha", Some(0.004)),
        ("Cl_beta", Some(-0.089)),
        ("Cl_p", Some(-0.47)),
        ("Cl_r", Some(0.096)),
        ("Cl_da", Some(-0.178)),
        ("Cl_dr", Some(0.0147)),
        ("Cm_0", Some(-0.015)),
        ("Cm_alpha", Some(-0.89)),
        ("Cm_beta", Some(0.01)),
        ("Cm_q", Some(-12.4)),
        ("Cm_de", Some(-1.28)),
        ("Cn_alpha", Some(-0.003)),
        ("Cn_beta", Some(0.065)),
        ("Cn_p", Some(-0.03)),
        ("Cn_q", None),
        ("Cn_r", Some(-0.099)),
        ("Cn_da", Some(-0.053)),
        ("Cn_dr", Some(-0.0657)),
    ]
}

fn gazebo_options(drop: bool) -> GazeboOptions {
    let joint = |surface, joint: &str, direction, share| ControlJoint {
        surface,
        joint: joint.into(),
        direction,
        share,
    };
    GazeboOptions {
        geometry: GEOMETRY,
        joints: vec![
            joint(Term::De, "servo_2", -1.0, 1.0),
            joint(Term::Da, "servo_0", 1.0, 0.5),
            joint(Term::Da, "servo_1", 1.0, -0.5),
            joint(Term::Dr, "servo_3", -1.0, 1.0),
        ],
        link_name: "base_link".into(),
        air_density_kgpm3: 1.2041,
        alpha_stall_rad: 1.8,
        drop_unrepresentable: drop,
        notes: vec![],
    }
}

/// The joints' deflections for state `st`: the elevator and rudder as the state's, the
/// aileron pair as `δa` left and `−δa` right (`δa = (θ_L − θ_R)/2` with direction 1).
fn gazebo_joints(st: &State) -> [(&'static str, f64); 4] {
    [("servo_2", st.de), ("servo_0", st.da), ("servo_1", -st.da), ("servo_3", st.dr)]
}

/// With the force at the centre of pressure the plugin holds the model to first order in the
/// flow angles: what is left (the lift's `1 − cos α`, the drag's `sin α`, the cp's own flow
/// angles beyond first order, at |α| ≤ 0.12 rad, |q| ≤ 1 rad/s) stays within 2 % of the
/// largest force or moment.
const CP_SECOND_ORDER: f64 = 0.02;

#[test]
fn gazebo_plugin_flies_aeroidents_forces_and_moments_with_static_stability_at_the_cp() {
    let params = gazebo_params();
    let out =
        gazebo_plugin_sdf(&summary("gz", &params), "gz.json", &gazebo_options(false)).unwrap();
    let sdf = Sdf::parse(&out.text);
    let x = -0.89 * GEOMETRY.chord_m / 5.1;
    assert!((sdf.v("cp")[0] - x).abs() < 1e-15 && sdf.f("Cema") == 0.0, "{}", out.text);
    let rho = 1.2041;
    let model = |st: &State| aeroident_model(&params, st, rho);
    let fixed = worst(model, |st| gazebo_plugin(&sdf, st, &gazebo_joints(st), true));
    assert!(fixed < CP_SECOND_ORDER, "a corrected plugin differs by {fixed:e}\n{}", out.text);
    // The plugin as read drops Cem0, the residual Cm_0 − (x/c̄) CL_0: it flies that Cm_0.
    let held = x / GEOMETRY.chord_m * 0.31;
    let flown: Vec<_> =
        params.iter().map(|&(n, v)| if n == "Cm_0" { (n, Some(held)) } else { (n, v) }).collect();
    let as_read = worst(
        |st| aeroident_model(&flown, st, rho),
        |st| gazebo_plugin(&sdf, st, &gazebo_joints(st), false),
    );
    assert!(as_read < CP_SECOND_ORDER, "the plugin as read differs by {as_read:e}");
    assert!(
        out.warnings.iter().any(|w| w.contains("Cem0") && w.contains("trim")),
        "{:?}",
        out.warnings
    );
    assert!(out.warnings.iter().any(|w| w.contains("Cn_q")), "{:?}", out.warnings);
    // The comparison can fail: the roll damping changed, or the cp left at the CG, is seen.
    let mut wrong = Sdf::parse(&out.text);
    wrong.scalars.insert("Cellp".into(), "-0.3".into());
    let e = worst(model, |st| gazebo_plugin(&wrong, st, &gazebo_joints(st), true));
    assert!(e > 5.0 * CP_SECOND_ORDER, "a changed Cellp went unseen ({e:e})");
    let mut at_cg = Sdf::parse(&out.text);
    at_cg.scalars.insert("cp".into(), "0 0 0".into());
    let e = worst(model, |st| gazebo_plugin(&at_cg, st, &gazebo_joints(st), true));
    assert!(e > 5.0 * CP_SECOND_ORDER, "the cp at the CG went unseen ({e:e})");
}

#[test]
fn gazebo_refuses_squared_lift_terms_with_induced_drag() {
    let mut params = gazebo_params();
    params.push(("CD_alpha2", Some(0.8)));
    params.push(("CD_alpha", Some(2.0 * 0.31 * 0.8 / 5.1)));
    let s = summary("gz-polar", &params);
    let e = gazebo_plugin_sdf(&s, "p.json", &gazebo_options(false)).unwrap_err().to_string();
    assert!(e.contains("CL_beta") && e.contains("CL_de") && !e.contains("CD_alpha ="), "{e}");
    // Without a lift slope, no centre of pressure holds Cm_alpha.
    let s = summary("gz-nolift", &[("CL_0", Some(0.3)), ("Cm_alpha", Some(-0.5))]);
    let e = gazebo_plugin_sdf(&s, "l.json", &gazebo_options(false)).unwrap_err().to_string();
    assert!(e.contains("Cm_alpha") && e.contains("centre of pressure"), "{e}");
    // A surface derivative needs its joint.
    let mut o = gazebo_options(false);
    o.joints.retain(|j| j.surface != Term::Dr);
    let s = summary("gz-nojoint", &[("Cn_dr", Some(-0.06))]);
    let e = gazebo_plugin_sdf(&s, "j.json", &o).unwrap_err().to_string();
    assert!(e.contains("dr") && e.contains("joint"), "{e}");
}
