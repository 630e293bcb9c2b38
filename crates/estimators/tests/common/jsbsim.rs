//! Reads a JSBSim logger record (`shared/tools/jsbsim_log.py` columns, README of
//! `shared/flightdata/jsbsim_samples`) into [`AirDataSample`]s, SI units, and its truth JSON.
//! Noisy columns (`<col>_noisy`) are used where present. JSBSim's `ixz` is the tensor element,
//! `−Jxz`, so `Ixz_kgm2 = −ixz`.
#![allow(dead_code)]

use aeroident_estimators::vocabulary::{Coefficient, ModelStructure, Param, Term};
use aeroident_estimators::{AirDataSample, AircraftConstants};
use std::collections::HashMap;
use std::path::Path;

const FT: f64 = 0.3048;
const SLUG: f64 = 14.593_902_94;
const SLUGFT2: f64 = 1.355_817_95;
const LBF: f64 = 4.448_221_62;
const LBFFT: f64 = 1.355_817_95;
const PSF: f64 = 47.880_258_9;
const SLUGFT3: f64 = 515.378_818;

/// What to read from a record.
#[derive(Debug, Clone, Copy, Default)]
pub struct ReadOptions {
    /// Feed the logged angular accelerations `pdot, qdot, rdot` (noise-free in these records;
    /// flight-test records rarely have them).
    pub angular_accelerations: bool,
}

/// The record's samples.
pub fn read_samples(csv_path: &Path, opt: ReadOptions) -> Result<Vec<AirDataSample>, String> {
    let mut rdr = csv::Reader::from_path(csv_path).map_err(|e| e.to_string())?;
    let headers = rdr.headers().map_err(|e| e.to_string())?.clone();
    let idx: HashMap<String, usize> =
        headers.iter().enumerate().map(|(i, h)| (h.to_string(), i)).collect();
    let col = |name: &str| -> Option<usize> {
        idx.get(&format!("{name}_noisy")).or_else(|| idx.get(name)).copied()
    };
    let need = |name: &str| col(name).ok_or_else(|| format!("column `{name}` missing"));
    let (c_t, c_v, c_a, c_q) = (need("time")?, need("vt_fps")?, need("alpha_rad")?, need("q")?);
    let (c_b, c_p, c_r) = (need("beta_rad")?, need("p")?, need("r")?);
    let (c_phi, c_th) = (need("phi")?, need("theta")?);
    let (c_de, c_da, c_dr) = (need("elevator_rad")?, need("aileron_rad")?, need("rudder_rad")?);
    let (c_qbar, c_rho) = (need("qbar_psf")?, need("rho_slugft3")?);
    let (c_m, c_w) = (need("mass_slug")?, need("weight_lbs")?);
    let (c_ixx, c_iyy, c_izz, c_ixz) = (need("ixx")?, need("iyy")?, need("izz")?, need("ixz")?);
    let (c_s, c_b_ft, c_c) = (need("S_ft2")?, need("b_ft")?, need("cbar_ft")?);
    let c_thrust = need("thrust_lbs")?;
    let c_mprop = col("m_prop_lbsft");
    let (c_fbx, c_fbz) = (col("fbx_prop_lbs"), col("fbz_prop_lbs"));
    let acc = [col("ax_fps2"), col("ay_fps2"), col("az_fps2")];
    let nacc = [need("nx")?, need("ny")?, need("nz")?];
    let (c_pd, c_qd, c_rd) = (need("pdot")?, need("qdot")?, need("rdot")?);
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| e.to_string())?;
        let g = |c: usize| -> Result<f64, String> {
            rec[c].trim().parse::<f64>().map_err(|e| format!("{}: {e}", &headers[c]))
        };
        let mass_slug = g(c_m)?;
        let g_fps2 = g(c_w)? / mass_slug;
        let mut a = [0.0; 3];
        for i in 0..3 {
            a[i] = match acc[i] {
                Some(c) => g(c)? * FT,
                None => g(nacc[i])? * g_fps2 * FT,
            };
        }
        let (fbx, fbz) = match (c_fbx, c_fbz) {
            (Some(x), Some(z)) => (g(x)?, g(z)?),
            _ => (g(c_thrust)?, 0.0),
        };
        let thrust = (fbx * fbx + fbz * fbz).sqrt() * LBF;
        let incidence = if fbx != 0.0 { (-fbz).atan2(fbx) } else { 0.0 };
        let vt = g(c_v)? * FT;
        out.push(AirDataSample {
            t_s: g(c_t)?,
            vt_mps: vt,
            alpha_rad: g(c_a)?,
            qbar_pa: g(c_qbar)? * PSF,
            beta_rad: Some(g(c_b)?),
            p_rad_s: Some(g(c_p)?),
            q_rad_s: Some(g(c_q)?),
            r_rad_s: Some(g(c_r)?),
            pdot_rad_s2: opt.angular_accelerations.then(|| g(c_pd)).transpose()?,
            qdot_rad_s2: opt.angular_accelerations.then(|| g(c_qd)).transpose()?,
            rdot_rad_s2: opt.angular_accelerations.then(|| g(c_rd)).transpose()?,
            phi_rad: Some(g(c_phi)?),
            theta_rad: Some(g(c_th)?),
            ax_mps2: Some(a[0]),
            ay_mps2: Some(a[1]),
            az_mps2: Some(a[2]),
            de_rad: Some(g(c_de)?),
            da_rad: Some(g(c_da)?),
            dr_rad: Some(g(c_dr)?),
            thrust_n: Some(thrust),
            thrust_moment_nm: c_mprop.map(&g).transpose()?.map(|m| m * LBFFT),
            rho_kgpm3: Some(g(c_rho)? * SLUGFT3),
            constants: AircraftConstants {
                mass_kg: mass_slug * SLUG,
                S_m2: g(c_s)? * FT * FT,
                cbar_m: Some(g(c_c)? * FT),
                b_m: Some(g(c_b_ft)? * FT),
                Ixx_kgm2: Some(g(c_ixx)? * SLUGFT2),
                Iyy_kgm2: Some(g(c_iyy)? * SLUGFT2),
                Izz_kgm2: Some(g(c_izz)? * SLUGFT2),
                Ixz_kgm2: Some(-g(c_ixz)? * SLUGFT2),
                thrust_arm_m: 0.0,
                thrust_incidence_rad: incidence,
                v0_mps: None,
            },
            ..Default::default()
        });
    }
    Ok(out)
}

/// The truth JSON's `derivatives` map.
pub fn read_truth(path: &Path) -> Result<HashMap<String, f64>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let d = v.get("derivatives").and_then(|d| d.as_object()).ok_or("no `derivatives`")?;
    Ok(d.iter().filter_map(|(k, v)| v.as_f64().map(|x| (k.clone(), x))).collect())
}

/// The truth key of a parameter (`Cm_q` → `Cm_qhat`), `None` for bias and nonlinear terms.
pub fn truth_key(p: Param) -> Option<String> {
    let t = match p.term {
        Term::Alpha => "alpha",
        Term::Beta => "beta",
        Term::P => "phat",
        Term::Q => "qhat",
        Term::R => "rhat",
        Term::Alphadot => "adothat",
        Term::De => "de",
        Term::Da => "da",
        Term::Dr => "dr",
        _ => return None,
    };
    Some(format!("{}_{t}", p.coefficient.name()))
}

/// One row of the accuracy table.
#[derive(Debug, Clone)]
pub struct Row {
    /// Parameter name.
    pub name: &'static str,
    /// Truth, if the JSON has it.
    pub truth: Option<f64>,
    /// Estimate, if identified.
    pub value: Option<f64>,
    /// Its σ.
    pub sigma: Option<f64>,
    /// Whether the issue's target applies (truth above 5 % of its coefficient's largest term).
    pub targeted: bool,
}

impl Row {
    /// Relative error, %.
    pub fn error_pct(&self) -> Option<f64> {
        let t = self.truth.filter(|t| t.abs() >= 1e-6)?;
        Some(100.0 * (self.value? - t) / t.abs())
    }
}

/// The rows of `structure` given estimates (value, σ per parameter) and the truth.
pub fn rows(
    structure: &ModelStructure,
    est: &aeroident_estimators::Estimates,
    truth: &HashMap<String, f64>,
) -> Vec<Row> {
    let tr = |p: Param| truth_key(p).and_then(|k| truth.get(&k).copied());
    let largest = |c: Coefficient| {
        structure
            .terms_of(c)
            .filter_map(|t| tr(Param::new(c, t)))
            .fold(0.0f64, |m, v| m.max(v.abs()))
    };
    structure
        .params()
        .enumerate()
        .map(|(i, p)| {
            let truth = tr(p);
            Row {
                name: p.name(),
                truth,
                value: est.value(i),
                sigma: est.sigma(i),
                targeted: truth.is_some_and(|t| t.abs() > 0.05 * largest(p.coefficient)),
            }
        })
        .collect()
}

/// A printed table.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| parameter | truth | estimate ± σ | error % | target |\n|---|---|---|---|---|\n",
    );
    for r in rows {
        let f = |v: Option<f64>| v.map_or("–".into(), |x| format!("{x:.4}"));
        let est = match (r.value, r.sigma) {
            (Some(v), Some(sg)) => format!("{v:.4} ± {sg:.4}"),
            _ => "not identified".into(),
        };
        let err = r.error_pct().map_or("–".into(), |e| format!("{e:+.1}"));
        let tgt = if r.targeted {
            if r.error_pct().is_some_and(|e| e.abs() <= 10.0) { "met" } else { "MISSED" }
        } else {
            ""
        };
        s += &format!("| {} | {} | {est} | {err} | {tgt} |\n", r.name, f(r.truth));
    }
    s
}
