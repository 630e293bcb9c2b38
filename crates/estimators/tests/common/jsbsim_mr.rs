//! A small reader of the JSBSim logger's CSV (`../shared/tools/jsbsim_log.py`, README in
//! `../shared/flightdata/jsbsim_samples/`) into `AirDataSample`s, SI units, and of its truth
//! JSON. Test and example support only; the application crate has the real mappings.
//!
//! Conventions (README of the records): body axes, rad, ft, slug, lbf; `nx, ny, nz` in g of
//! 32.174 ft/s² (accelerometer convention); JSBSim's `ixz` is the tensor element, i.e. `−Jxz`
//! of Stevens & Lewis; the thrust acts along body x (`fbz_prop_lbs = 0`); `m_prop_lbsft` is the
//! thrust pitching moment. A channel with a `_noisy` copy is read from the copy.

#![allow(dead_code)]

use aeroident_estimators::{AirDataSample, AircraftConstants, Param};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const FT: f64 = 0.3048;
const SLUG: f64 = 14.593_902_937_206_364;
const LBF: f64 = 4.448_221_615_260_5;
const PSF: f64 = 47.880_258_980_335_84;
const SLUG_FT2: f64 = SLUG * FT * FT;
const SLUG_FT3: f64 = SLUG / (FT * FT * FT);
const G_FTPS2: f64 = 32.174;

/// `../shared/flightdata/<rel>` beside the workspace, or `None` with a printed skip message.
pub fn shared_record(rel: &str) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/flightdata");
    let p = root.join(rel);
    if p.exists() {
        Some(p)
    } else {
        println!(
            "SKIPPED: {} not found (the shared records are not in the repository)",
            p.display()
        );
        None
    }
}

/// One record: the samples and, per sample, the logged "true" aerodynamic coefficients
/// (`CL CD CY Cl Cm Cn` columns) for cross-checks.
pub struct Record {
    /// The samples.
    pub samples: Vec<AirDataSample>,
    /// The logged coefficients `[CX, CY, CZ, CL, CD, Cl, Cm, Cn]` (clean, from JSBSim's forces).
    pub logged: Vec<[f64; 8]>,
}

/// Reads a JSBSim CSV, from the `_noisy` copies of the channels that have one when `noisy`.
///
/// # Errors
/// A message naming the missing column or the bad row.
pub fn read_csv(path: &Path, noisy: bool) -> Result<Record, String> {
    let mut rd = csv::Reader::from_path(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let header: Vec<String> =
        rd.headers().map_err(|e| e.to_string())?.iter().map(String::from).collect();
    let col = |name: &str| header.iter().position(|h| h == name);
    let pick = |name: &str| {
        if noisy { col(&format!("{name}_noisy")).or_else(|| col(name)) } else { col(name) }
    };
    let need = |name: &str| pick(name).ok_or(format!("column `{name}` missing"));
    let opt = |name: &str| pick(name);
    let (t, vt, alpha, beta, qbar) =
        (need("time")?, need("vt_fps")?, need("alpha_rad")?, opt("beta_rad"), need("qbar_psf")?);
    let (p, q, r) = (need("p")?, need("q")?, need("r")?);
    let (pd, qd, rd_) = (need("pdot")?, need("qdot")?, need("rdot")?);
    let (phi, theta) = (need("phi")?, need("theta")?);
    let accel_fps2 = [opt("ax_fps2"), opt("ay_fps2"), opt("az_fps2")];
    let accel_g = [need("nx")?, need("ny")?, need("nz")?];
    let (de, da, dr) = (need("elevator_rad")?, need("aileron_rad")?, need("rudder_rad")?);
    let (thrust, m_prop, rho) = (need("thrust_lbs")?, need("m_prop_lbsft")?, need("rho_slugft3")?);
    let (mass, ixx, iyy, izz, ixz) =
        (need("mass_slug")?, need("ixx")?, need("iyy")?, need("izz")?, need("ixz")?);
    let (s_ft2, b_ft, cbar_ft) = (need("S_ft2")?, need("b_ft")?, need("cbar_ft")?);
    let logged_cols: Vec<usize> = ["CX", "CY", "CZ", "CL", "CD", "Cl", "Cm", "Cn"]
        .iter()
        .map(|n| col(n).ok_or(format!("column `{n}` missing")))
        .collect::<Result<_, _>>()?;
    let mut samples = Vec::new();
    let mut logged = Vec::new();
    for (i, row) in rd.records().enumerate() {
        let row = row.map_err(|e| format!("row {}: {e}", i + 2))?;
        let f = |c: usize| -> Result<f64, String> {
            row[c]
                .trim()
                .parse::<f64>()
                .map_err(|e| format!("row {} column {}: {e}", i + 2, header[c]))
        };
        let accel = |k: usize| -> Result<f64, String> {
            match accel_fps2[k] {
                Some(c) => Ok(f(c)? * FT),
                None => Ok(f(accel_g[k])? * G_FTPS2 * FT),
            }
        };
        samples.push(AirDataSample {
            t_s: f(t)?,
            vt_mps: f(vt)? * FT,
            alpha_rad: f(alpha)?,
            qbar_pa: f(qbar)? * PSF,
            beta_rad: beta.map(f).transpose()?,
            p_rad_s: Some(f(p)?),
            q_rad_s: Some(f(q)?),
            r_rad_s: Some(f(r)?),
            pdot_rad_s2: Some(f(pd)?),
            qdot_rad_s2: Some(f(qd)?),
            rdot_rad_s2: Some(f(rd_)?),
            phi_rad: Some(f(phi)?),
            theta_rad: Some(f(theta)?),
            ax_mps2: Some(accel(0)?),
            ay_mps2: Some(accel(1)?),
            az_mps2: Some(accel(2)?),
            de_rad: Some(f(de)?),
            da_rad: Some(f(da)?),
            dr_rad: Some(f(dr)?),
            thrust_n: Some(f(thrust)? * LBF),
            thrust_moment_nm: Some(f(m_prop)? * LBF * FT),
            rho_kgpm3: Some(f(rho)? * SLUG_FT3),
            constants: AircraftConstants {
                mass_kg: f(mass)? * SLUG,
                S_m2: f(s_ft2)? * FT * FT,
                cbar_m: Some(f(cbar_ft)? * FT),
                b_m: Some(f(b_ft)? * FT),
                Ixx_kgm2: Some(f(ixx)? * SLUG_FT2),
                Iyy_kgm2: Some(f(iyy)? * SLUG_FT2),
                Izz_kgm2: Some(f(izz)? * SLUG_FT2),
                Ixz_kgm2: Some(-f(ixz)? * SLUG_FT2),
                ..Default::default()
            },
            ..Default::default()
        });
        let mut l = [0.0; 8];
        for (k, c) in logged_cols.iter().enumerate() {
            l[k] = f(*c)?;
        }
        logged.push(l);
    }
    Ok(Record { samples, logged })
}

/// The truth JSON's derivatives under the vocabulary's names (`Cl_p` for `Cl_phat` …); bias
/// terms have no truth.
///
/// # Errors
/// A message when the file cannot be read or has no `derivatives`.
pub fn read_truth(path: &Path) -> Result<HashMap<String, f64>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let d = v.get("derivatives").and_then(|d| d.as_object()).ok_or("no `derivatives`")?;
    let mut out = HashMap::new();
    for (k, val) in d {
        let name = k
            .replace("_phat", "_p")
            .replace("_qhat", "_q")
            .replace("_rhat", "_r")
            .replace("_adothat", "_alphadot");
        if let (Some(x), Some(_)) = (val.as_f64(), Param::from_name(&name)) {
            out.insert(name, x);
        }
    }
    Ok(out)
}
