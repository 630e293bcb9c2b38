//! Small readers of the third-party records in `shared/flightdata` (their READMEs give the
//! columns, units and constants) into [`AirDataSample`]s, SI units, for the tests, examples and
//! benches of this crate: one reader per record family (the JSBSim logger's CSV; the
//! Jategaonkar HFB-320 and ATTAS CSVs; the SIDPAC Twin Otter CSVs), one reader of the JSBSim
//! truth JSON and one printer of a truth-versus-estimate table. Test-only: the product reads
//! records through `aeroident-io` mappings.
#![allow(dead_code)]

use aeroident_estimators::vocabulary::{Coefficient as C, ModelStructure, Param, Term as T};
use aeroident_estimators::{AirDataSample, AircraftConstants, Estimates};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const DEG: f64 = std::f64::consts::PI / 180.0;
const FT: f64 = 0.3048;
const SLUG: f64 = 14.593_902_937_206_364;
const LBF: f64 = 4.448_221_615_260_5;
const PSF: f64 = 47.880_258_980_335_84;
const SLUG_FT2: f64 = SLUG * FT * FT;
const SLUG_FT3: f64 = SLUG / (FT * FT * FT);
const G0: f64 = 9.80665;

/// The shared folder: `$AEROIDENT_SHARED`, else `../shared` next to the repository.
pub fn shared() -> PathBuf {
    std::env::var_os("AEROIDENT_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"))
}

/// `<shared>/flightdata/<rel>`, or `None` with a printed skip message when it is absent
/// ([`present`]: a failure under CI).
pub fn shared_record(rel: &str) -> Option<PathBuf> {
    let p = shared().join("flightdata").join(rel);
    present(&p).then_some(p)
}

/// Whether the shared file `p` exists. When it does not, prints a SKIPPED message, except under
/// CI (`CI=true`), where it panics: CI always has `../shared` beside the repository, so a skip
/// there would hide a broken path and a test that checks nothing.
pub fn present(p: &Path) -> bool {
    if p.exists() {
        return true;
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "{} is absent under CI (CI provides ../shared beside the repository)",
        p.display()
    );
    println!(
        "SKIPPED: {} not found (the shared records are not in the repository; set \
         AEROIDENT_SHARED to the shared folder)",
        p.display()
    );
    false
}

// ---------------------------------------------------------------------------------------------
// JSBSim logger records (`shared/tools/jsbsim_log.py`, READMEs of `jsbsim_samples` and
// `jsbsim_f16_sample`). Conventions: body axes, rad, ft, slug, lbf; `nx, ny, nz` are the body
// specific force in g, i.e. force ÷ `weight_lbs` (accelerometer convention), used only when
// the record has no `ax_fps2 …` columns; JSBSim's `ixz` is the tensor element, `−Jxz` of
// Stevens & Lewis, so `Ixz_kgm2 = −ixz`; `fbx/fbz_prop_lbs` give the thrust and its incidence
// (else `thrust_lbs` along body x); `m_prop_lbsft` is the thrust pitching moment.
// ---------------------------------------------------------------------------------------------

/// Which channels to read from a JSBSim logger record.
#[derive(Debug, Clone, Copy)]
pub struct JsbsimChannels {
    /// Read a channel from its `<col>_noisy` copy where the record has one.
    pub noisy: bool,
    /// Feed the logged angular accelerations `pdot, qdot, rdot` (noise-free in these records;
    /// flight-test records rarely have them). `None` in the samples otherwise.
    pub angular_accelerations: bool,
}

/// One JSBSim record: the samples and, per sample, JSBSim's own aerodynamic coefficients.
pub struct JsbsimRecord {
    /// The samples.
    pub samples: Vec<AirDataSample>,
    /// The logged coefficients `[CX, CY, CZ, CL, CD, Cl, Cm, Cn]` (clean, from JSBSim's forces).
    pub logged: Vec<[f64; 8]>,
}

/// Reads a JSBSim logger CSV.
///
/// # Errors
/// A message naming the missing column or the bad row.
pub fn jsbsim(path: &Path, ch: JsbsimChannels) -> Result<JsbsimRecord, String> {
    let mut rd = csv::Reader::from_path(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let header: Vec<String> =
        rd.headers().map_err(|e| e.to_string())?.iter().map(String::from).collect();
    let col = |name: &str| header.iter().position(|h| h == name);
    let opt = |name: &str| {
        if ch.noisy { col(&format!("{name}_noisy")).or_else(|| col(name)) } else { col(name) }
    };
    let need = |name: &str| opt(name).ok_or(format!("column `{name}` missing"));
    let (t, vt, alpha, beta, qbar) =
        (need("time")?, need("vt_fps")?, need("alpha_rad")?, opt("beta_rad"), need("qbar_psf")?);
    let (p, q, r) = (need("p")?, need("q")?, need("r")?);
    let (pd, qd, rd_) = (need("pdot")?, need("qdot")?, need("rdot")?);
    let (phi, theta) = (need("phi")?, need("theta")?);
    let accel_fps2 = [opt("ax_fps2"), opt("ay_fps2"), opt("az_fps2")];
    let accel_g = [need("nx")?, need("ny")?, need("nz")?];
    let (de, da, dr) = (need("elevator_rad")?, need("aileron_rad")?, need("rudder_rad")?);
    let (thrust, m_prop, rho) = (need("thrust_lbs")?, opt("m_prop_lbsft"), need("rho_slugft3")?);
    let (fbx, fbz) = (opt("fbx_prop_lbs"), opt("fbz_prop_lbs"));
    let (mass, weight) = (need("mass_slug")?, need("weight_lbs")?);
    let (ixx, iyy, izz, ixz) = (need("ixx")?, need("iyy")?, need("izz")?, need("ixz")?);
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
        let mass_slug = f(mass)?;
        let g_fps2 = f(weight)? / mass_slug;
        let accel = |k: usize| -> Result<f64, String> {
            match accel_fps2[k] {
                Some(c) => Ok(f(c)? * FT),
                None => Ok(f(accel_g[k])? * g_fps2 * FT),
            }
        };
        let (fbx_lbs, fbz_lbs) = match (fbx, fbz) {
            (Some(x), Some(z)) => (f(x)?, f(z)?),
            _ => (f(thrust)?, 0.0),
        };
        let incidence = if fbx_lbs != 0.0 { (-fbz_lbs).atan2(fbx_lbs) } else { 0.0 };
        let rates = |c: usize| ch.angular_accelerations.then(|| f(c)).transpose();
        samples.push(AirDataSample {
            t_s: f(t)?,
            vt_mps: f(vt)? * FT,
            alpha_rad: f(alpha)?,
            qbar_pa: f(qbar)? * PSF,
            beta_rad: beta.map(f).transpose()?,
            p_rad_s: Some(f(p)?),
            q_rad_s: Some(f(q)?),
            r_rad_s: Some(f(r)?),
            pdot_rad_s2: rates(pd)?,
            qdot_rad_s2: rates(qd)?,
            rdot_rad_s2: rates(rd_)?,
            phi_rad: Some(f(phi)?),
            theta_rad: Some(f(theta)?),
            ax_mps2: Some(accel(0)?),
            ay_mps2: Some(accel(1)?),
            az_mps2: Some(accel(2)?),
            de_rad: Some(f(de)?),
            // JSBSim's aileron > 0 rolls right; the sample's δa > 0 gives a negative moment.
            da_rad: Some(-f(da)?),
            dr_rad: Some(f(dr)?),
            thrust_n: Some(fbx_lbs.hypot(fbz_lbs) * LBF),
            thrust_moment_nm: m_prop.map(f).transpose()?.map(|m| m * LBF * FT),
            rho_kgpm3: Some(f(rho)? * SLUG_FT3),
            constants: AircraftConstants {
                mass_kg: mass_slug * SLUG,
                S_m2: f(s_ft2)? * FT * FT,
                cbar_m: Some(f(cbar_ft)? * FT),
                b_m: Some(f(b_ft)? * FT),
                Ixx_kgm2: Some(f(ixx)? * SLUG_FT2),
                Iyy_kgm2: Some(f(iyy)? * SLUG_FT2),
                Izz_kgm2: Some(f(izz)? * SLUG_FT2),
                Ixz_kgm2: Some(-f(ixz)? * SLUG_FT2),
                thrust_incidence_rad: incidence,
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
    Ok(JsbsimRecord { samples, logged })
}

/// The truth JSON's `derivatives` under the vocabulary's names (`Cl_p` for `Cl_phat`,
/// `Cm_alphadot` for `Cm_adothat` …) and sign convention (JSBSim's aileron rolls right when
/// positive, the vocabulary's δa left: the `_da` derivatives change sign); keys with no
/// vocabulary parameter are dropped, and bias terms have no truth.
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
            let sign = if name.ends_with("_da") { -1.0 } else { 1.0 };
            out.insert(name, sign * x);
        }
    }
    Ok(out)
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
    /// Whether the accuracy target applies (truth above 5 % of its coefficient's largest term).
    pub targeted: bool,
}

impl Row {
    /// Relative error, %.
    pub fn error_pct(&self) -> Option<f64> {
        let t = self.truth.filter(|t| t.abs() >= 1e-6)?;
        Some(100.0 * (self.value? - t) / t.abs())
    }
}

/// The rows of `structure` given estimates (value, σ per parameter) and the truth of
/// [`read_truth`].
pub fn rows(structure: &ModelStructure, est: &Estimates, truth: &HashMap<String, f64>) -> Vec<Row> {
    let tr = |p: Param| truth.get(p.name()).copied();
    let largest = |c: C| {
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

/// A printed Markdown table of `rows`.
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

// ---------------------------------------------------------------------------------------------
// Jategaonkar (HFB-320, ATTAS) and SIDPAC (Twin Otter) CSVs: one column per channel.
// ---------------------------------------------------------------------------------------------

/// Columns of a CSV file by header name.
pub struct Table {
    cols: HashMap<String, Vec<f64>>,
    pub n: usize,
}

impl Table {
    pub fn read(path: &Path) -> Result<Self, String> {
        let mut rdr =
            csv::Reader::from_path(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let headers: Vec<String> =
            rdr.headers().map_err(|e| e.to_string())?.iter().map(String::from).collect();
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); headers.len()];
        for rec in rdr.records() {
            let rec = rec.map_err(|e| e.to_string())?;
            for (i, f) in rec.iter().enumerate() {
                cols[i].push(f.trim().parse::<f64>().map_err(|e| format!("{f}: {e}"))?);
            }
        }
        let n = cols.first().map_or(0, Vec::len);
        Ok(Self { cols: headers.into_iter().zip(cols).collect(), n })
    }

    pub fn col(&self, name: &str) -> Result<&[f64], String> {
        self.cols.get(name).map(Vec::as_slice).ok_or_else(|| format!("column `{name}` missing"))
    }
}

/// HFB-320 constants of the book's model (`mappings/hfb320.toml`, README of
/// `jategaonkar_hfb320_attas`): S/m = 4.028e-3, S·c̄/Iy = 8.0027e-4, FEIYLT = −7.0153e-6,
/// σT = 0.0524 rad, ρ = 0.792, V0 = 104.67 m/s, c̄/2 = 1.215 m.
pub fn hfb320_constants() -> AircraftConstants {
    AircraftConstants {
        mass_kg: 7472.0,
        S_m2: 4.028e-3 * 7472.0,
        cbar_m: Some(2.43),
        b_m: None,
        Ixx_kgm2: None,
        Iyy_kgm2: Some(4.028e-3 * 7472.0 * 2.43 / 8.0027e-4),
        Izz_kgm2: None,
        Ixz_kgm2: None,
        thrust_arm_m: -7.0153e-6 * (4.028e-3 * 7472.0 * 2.43 / 8.0027e-4),
        thrust_incidence_rad: 0.0524,
        v0_mps: Some(104.67),
    }
}

pub fn hfb320_path() -> PathBuf {
    shared().join("flightdata/jategaonkar_hfb320_attas/csv/hfb320_1_10.csv")
}

/// The HFB-320 record (test case 4) with the channels of the book's model: outputs V, α, θ,
/// q, q̇, ax, az; inputs δe and thrust; no lateral channels (the book's model is purely
/// longitudinal).
pub fn hfb320(path: &Path) -> Result<Vec<AirDataSample>, String> {
    let t = Table::read(path)?;
    let k = hfb320_constants();
    let (tt, de, qbar, thr) =
        (t.col("time_s")?, t.col("elevator_rad")?, t.col("qbar_Pa")?, t.col("thrust_N")?);
    let (v, al, th, q) =
        (t.col("vtas_mps")?, t.col("alpha_rad")?, t.col("theta_rad")?, t.col("q_radps")?);
    let (qd, ax, az) = (t.col("qdot_radps2")?, t.col("ax_mps2")?, t.col("az_mps2")?);
    Ok((0..t.n)
        .map(|i| AirDataSample {
            t_s: tt[i],
            vt_mps: v[i],
            alpha_rad: al[i],
            qbar_pa: qbar[i],
            q_rad_s: Some(q[i]),
            qdot_rad_s2: Some(qd[i]),
            theta_rad: Some(th[i]),
            ax_mps2: Some(ax[i]),
            az_mps2: Some(az[i]),
            de_rad: Some(de[i]),
            thrust_n: Some(thr[i]),
            rho_kgpm3: Some(0.792),
            constants: k,
            ..Default::default()
        })
        .collect())
}

/// The book's HFB-320 model (Jategaonkar 2015 eq. 5.86–5.89, test case 4):
/// `CD = CD0 + CDV V/V0 + CDα α`, `CL = CL0 + CLV V/V0 + CLα α`,
/// `Cm = Cm0 + CmV V/V0 + Cmα α + Cmq q c̄/(2V0) + Cmδe δe`.
pub fn hfb320_structure() -> ModelStructure {
    ModelStructure::empty()
        .with(C::CL, &[T::Bias, T::V, T::Alpha])
        .with(C::CD, &[T::Bias, T::V, T::Alpha])
        .with(C::Cm, &[T::Bias, T::V, T::Alpha, T::Q0, T::De])
}

/// A Twin Otter SIDPAC record (README of `sidpac_twin_otter`): English units and degrees
/// converted to SI; mass properties and geometry from the columns; thrust both engines, on
/// the body x axis through the CG (the README: no thrust line given).
pub fn twin_otter(path: &Path) -> Result<Vec<AirDataSample>, String> {
    let t = Table::read(path)?;
    let c = |n: &str| t.col(n);
    let (tt, v, al, be) = (c("t_s")?, c("airspeed_fps")?, c("alpha_deg")?, c("beta_deg")?);
    let (p, q, r) = (c("p_degps")?, c("q_degps")?, c("r_degps")?);
    let (phi, th) = (c("phi_deg")?, c("theta_deg")?);
    let (ax, ay, az) = (c("ax_g")?, c("ay_g")?, c("az_g")?);
    let (de, qbar, rho) = (c("elevator_deg")?, c("qbar_psf")?, c("rho_slugft3")?);
    let (t1, t2, qd) = (c("thrust_lbf")?, c("thrust2_lbf")?, c("qdot_degps2")?);
    let (m, ixx, iyy, izz, ixz) = (
        c("mass_slug")?,
        c("Ixx_slugft2")?,
        c("Iyy_slugft2")?,
        c("Izz_slugft2")?,
        c("Ixz_slugft2")?,
    );
    let (s, b, cb) = (c("sarea_ft2")?, c("bspan_ft")?, c("cbar_ft")?);
    Ok((0..t.n)
        .map(|i| AirDataSample {
            t_s: tt[i],
            vt_mps: v[i] * FT,
            alpha_rad: al[i] * DEG,
            qbar_pa: qbar[i] * PSF,
            beta_rad: Some(be[i] * DEG),
            p_rad_s: Some(p[i] * DEG),
            q_rad_s: Some(q[i] * DEG),
            r_rad_s: Some(r[i] * DEG),
            qdot_rad_s2: Some(qd[i] * DEG),
            phi_rad: Some(phi[i] * DEG),
            theta_rad: Some(th[i] * DEG),
            ax_mps2: Some(ax[i] * G0),
            ay_mps2: Some(ay[i] * G0),
            az_mps2: Some(az[i] * G0),
            de_rad: Some(de[i] * DEG),
            thrust_n: Some((t1[i] + t2[i]) * LBF),
            rho_kgpm3: Some(rho[i] * SLUG_FT3),
            constants: AircraftConstants {
                mass_kg: m[i] * SLUG,
                S_m2: s[i] * FT * FT,
                cbar_m: Some(cb[i] * FT),
                b_m: Some(b[i] * FT),
                Ixx_kgm2: Some(ixx[i] * SLUG_FT2),
                Iyy_kgm2: Some(iyy[i] * SLUG_FT2),
                Izz_kgm2: Some(izz[i] * SLUG_FT2),
                Ixz_kgm2: Some(ixz[i] * SLUG_FT2),
                thrust_arm_m: 0.0,
                thrust_incidence_rad: 0.0,
                v0_mps: None,
            },
            ..Default::default()
        })
        .collect())
}

/// ATTAS constants (README of `jategaonkar_hfb320_attas`, the book's `umr_reg_attas.m`):
/// m, inertia, S, c̄; span `b = 2 × 10.75 m`; thrust line not given (on body x through the CG).
pub fn attas_constants() -> AircraftConstants {
    AircraftConstants {
        mass_kg: 17631.0,
        S_m2: 64.0,
        cbar_m: Some(3.159),
        b_m: Some(21.5),
        Ixx_kgm2: Some(1.33367e5),
        Iyy_kgm2: Some(2.52687e5),
        Izz_kgm2: Some(3.59593e5),
        Ixz_kgm2: Some(1.1442e4),
        thrust_arm_m: 0.0,
        thrust_incidence_rad: 0.0,
        v0_mps: None,
    }
}

/// An ATTAS record (45 columns) with the book's bias corrections (`b_ax, b_ay, b_az`,
/// `b_p, b_q, b_r` subtracted) and the noseboom flow angles moved to the CG
/// (`α_cg = α_nb + q x/V`, `β_cg = β_nb − r x/V`, `x = 13.080 m`); aileron
/// `(DAIL_R − DAIL_L)/2` as the book; time from the record.
pub fn attas(path: &Path) -> Result<Vec<AirDataSample>, String> {
    let t = Table::read(path)?;
    let c = |n: &str| t.col(n);
    let (tt, v, al, be) = (c("time_s")?, c("vtas_mps")?, c("alpha_deg")?, c("beta_deg")?);
    let (p, q, r) = (c("p_degps")?, c("q_degps")?, c("r_degps")?);
    let (pd, qd, rd) = (c("pdot_degps2")?, c("qdot_degps2")?, c("rdot_degps2")?);
    let (phi, th) = (c("phi_deg")?, c("theta_deg")?);
    let (ax, ay, az) = (c("ax_cg_mps2")?, c("ay_cg_mps2")?, c("az_cg_mps2")?);
    let (de, dal, dar, dr) =
        (c("elevator_deg")?, c("aileron_left_deg")?, c("aileron_right_deg")?, c("rudder_deg")?);
    let (rho, tl, tr) = (c("rho_kgpm3")?, c("thrust_left_N")?, c("thrust_right_N")?);
    let k = attas_constants();
    let x_nb = 13.080;
    Ok((0..t.n)
        .map(|i| {
            let (pi, qi, ri) =
                (p[i] * DEG - 1.02555e-3, q[i] * DEG - 3.40891e-3, r[i] * DEG - 9.96192e-4);
            AirDataSample {
                t_s: tt[i],
                vt_mps: v[i],
                alpha_rad: al[i] * DEG + qi * x_nb / v[i],
                qbar_pa: 0.5 * rho[i] * v[i] * v[i],
                beta_rad: Some(be[i] * DEG - ri * x_nb / v[i]),
                p_rad_s: Some(pi),
                q_rad_s: Some(qi),
                r_rad_s: Some(ri),
                pdot_rad_s2: Some(pd[i] * DEG),
                qdot_rad_s2: Some(qd[i] * DEG),
                rdot_rad_s2: Some(rd[i] * DEG),
                phi_rad: Some(phi[i] * DEG),
                theta_rad: Some(th[i] * DEG),
                ax_mps2: Some(ax[i] - 6.76242e-3),
                ay_mps2: Some(ay[i] + 1.50664e-3),
                az_mps2: Some(az[i] - 8.39892e-2),
                de_rad: Some(de[i] * DEG),
                da_rad: Some(0.5 * (dar[i] - dal[i]) * DEG),
                dr_rad: Some(dr[i] * DEG),
                thrust_n: Some(tl[i] + tr[i]),
                rho_kgpm3: Some(rho[i]),
                constants: k,
                ..Default::default()
            }
        })
        .collect())
}
