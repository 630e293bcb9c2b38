//! Small readers of the third-party flight-test records in `shared/flightdata` (their READMEs
//! give the columns, units and constants) into [`AirDataSample`]s, SI units, for the
//! output-error test, example and bench. Test-only: the product reads records through
//! `aeroident-io` mappings.
#![allow(dead_code)]

use aeroident_estimators::vocabulary::{Coefficient as C, ModelStructure, Term as T};
use aeroident_estimators::{AirDataSample, AircraftConstants};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const DEG: f64 = std::f64::consts::PI / 180.0;
const FT: f64 = 0.3048;
const SLUG: f64 = 14.593_902_94;
const SLUGFT2: f64 = 1.355_817_95;
const LBF: f64 = 4.448_221_62;
const PSF: f64 = 47.880_258_9;
const SLUGFT3: f64 = 515.378_818;
const G0: f64 = 9.80665;

/// The shared folder: `$AEROIDENT_SHARED`, else `../shared` next to the repository.
pub fn shared() -> PathBuf {
    std::env::var_os("AEROIDENT_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"))
}

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
            rho_kgpm3: Some(rho[i] * SLUGFT3),
            constants: AircraftConstants {
                mass_kg: m[i] * SLUG,
                S_m2: s[i] * FT * FT,
                cbar_m: Some(cb[i] * FT),
                b_m: Some(b[i] * FT),
                Ixx_kgm2: Some(ixx[i] * SLUGFT2),
                Iyy_kgm2: Some(iyy[i] * SLUGFT2),
                Izz_kgm2: Some(izz[i] * SLUGFT2),
                Ixz_kgm2: Some(ixz[i] * SLUGFT2),
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
