//! Loading the F-16 numbers (SLJ §3.5 and Appendix A; NASA TP-1538) from the shipped TOML file
//! `crates/models/data/f16_stevens_lewis.toml` into fixed-size arrays.
//!
//! The file is embedded with `include_str!` and parsed once ([`F16Data::embedded`]); the project
//! never reads `../shared` at run time. [`F16Data::parse`] returns an error naming the table and
//! field for malformed data (wrong shape, wrong axis names, non-monotonic breakpoints, non-finite
//! numbers, TOML syntax errors with their line).

use super::table::{Table1, Table2, check_breakpoints};
use crate::rigid_body::InertiaConstants;
use aeroident_physics::rigid_body::Inertia;
use serde::Deserialize;
use std::sync::OnceLock;

/// The shipped data file's text (provenance in its header comment).
pub const EMBEDDED_TOML: &str = include_str!("../../data/f16_stevens_lewis.toml");

/// Why the F-16 data could not be loaded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DataError {
    /// TOML syntax error or a missing/mistyped key (the message carries the line and column).
    #[error("F-16 data: TOML error: {0}")]
    Toml(String),
    /// A table has the wrong shape, axes or values.
    #[error("F-16 data: table `{table}`, field `{field}`: {reason}")]
    Invalid {
        /// Table (TOML section) name.
        table: &'static str,
        /// Field inside the table.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
}

// ---------------------------------------------------------------------------------------------
// Raw serde mirror of the file.
#[derive(Deserialize)]
struct RawFile {
    constants: RawConstants,
    cx: RawTable2,
    cz: RawCz,
    cm: RawTable2,
    cy: RawCy,
    cl: RawTable2,
    cn: RawTable2,
    dlda: RawTable2,
    dldr: RawTable2,
    dnda: RawTable2,
    dndr: RawTable2,
    damping: RawDamping,
    thrust_idle: RawTable2,
    thrust_mil: RawTable2,
    thrust_max: RawTable2,
    buildup: RawBuildup,
    engine: EngineConstants,
    atmosphere: AtmosphereConstants,
    mass: MassProperties,
    geometry: Geometry,
    #[serde(with = "MomentConstantsFile")]
    moment_constants: MomentConstants,
    ranges: DataRanges,
}

/// The `[moment_constants]` table, read into the kernel's [`InertiaConstants`] (a type of
/// `aeroident-physics`, which is `no_std` without serde).
#[derive(Deserialize)]
#[serde(remote = "InertiaConstants", deny_unknown_fields)]
struct MomentConstantsFile {
    c1: f64,
    c2: f64,
    c3: f64,
    c4: f64,
    c5: f64,
    c6: f64,
    c7: f64,
    c8: f64,
    c9: f64,
}

#[derive(Deserialize)]
struct RawConstants {
    rad_to_deg: f64,
}

#[derive(Deserialize)]
struct RawTable2 {
    axes: Vec<String>,
    #[serde(flatten)]
    rest: toml::Table,
}

#[derive(Deserialize)]
struct RawCz {
    axes: Vec<String>,
    alpha_deg: Vec<f64>,
    values: Vec<f64>,
    beta_scale_deg: f64,
    elevator_coefficient: f64,
    elevator_scale_deg: f64,
}

#[derive(Deserialize)]
struct RawCy {
    beta_coefficient_per_deg: f64,
    aileron_coefficient: f64,
    aileron_scale_deg: f64,
    rudder_coefficient: f64,
    rudder_scale_deg: f64,
}

#[derive(Deserialize)]
struct RawDamping {
    axes: Vec<String>,
    coefficient: Vec<String>,
    alpha_deg: Vec<f64>,
    values: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct RawBuildup {
    aileron_scale_deg: f64,
    rudder_scale_deg: f64,
}

// ---------------------------------------------------------------------------------------------
// Public, loaded data.

/// Engine constants (SLJ §3.5, functions TGEAR, PDOT, RTAU). Power in percent (0 idle, 50 MIL,
/// 100 MAX), throttle 0–1.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EngineConstants {
    /// Throttle at which the gearing slope changes (0.77).
    pub throttle_break: f64,
    /// Gearing slope below the break, percent per unit throttle (64.94).
    pub tgear_low_slope: f64,
    /// Gearing slope above the break (217.38).
    pub tgear_high_slope: f64,
    /// Gearing offset above the break, percent (−117.38).
    pub tgear_high_offset: f64,
    /// MIL power, percent (50).
    pub mil_power_percent: f64,
    /// Afterburner power-lag rate, 1/s (5).
    pub afterburner_rate_per_s: f64,
    /// Target when lighting the afterburner from below MIL, percent (60).
    pub afterburner_light_target_percent: f64,
    /// Target when cutting the afterburner, percent (40).
    pub afterburner_cut_target_percent: f64,
    /// rtau: power step below which the rate is `rtau_low` (25).
    pub rtau_dp_low: f64,
    /// rtau rate for small steps, 1/s (1).
    pub rtau_low: f64,
    /// rtau: power step above which the rate is `rtau_high` (50).
    pub rtau_dp_high: f64,
    /// rtau rate for large steps, 1/s (0.1).
    pub rtau_high: f64,
    /// rtau intercept in between, 1/s (1.9).
    pub rtau_intercept: f64,
    /// rtau slope in between, 1/(s·percent) (−0.036).
    pub rtau_slope: f64,
}

/// Air-data constants of the textbook ADC subroutine (SLJ §3.5).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtmosphereConstants {
    /// Sea-level density, slug/ft³ (2.377e-3).
    pub rho0_slug_per_ft3: f64,
    /// Temperature lapse factor per ft (0.703e-5).
    pub temperature_factor_per_ft: f64,
    /// Sea-level temperature, °R (519).
    pub t0_rankine: f64,
    /// Altitude above which temperature is constant, ft (35 000).
    pub tropopause_altitude_ft: f64,
    /// Temperature above the tropopause, °R (390).
    pub t_above_tropopause_rankine: f64,
    /// Density exponent (4.14).
    pub density_exponent: f64,
    /// Ratio of specific heats (1.4).
    pub gamma: f64,
    /// Gas constant for the speed of sound, ft²/(s²·°R) (1716.3).
    pub gas_constant_speed_of_sound: f64,
    /// Gas constant for static pressure (1715).
    pub gas_constant_static_pressure: f64,
}

/// Mass properties (SLJ §3.5; `[mass]` of the data file).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MassProperties {
    /// 1/m, 1/slug (1.57e-3, the textbook code's RM).
    pub inverse_mass_per_slug: f64,
    /// Weight g/RM, lbf (20 490.446).
    pub weight_lbf: f64,
    /// Gravity, ft/s² (32.17, the model's value, not standard gravity).
    pub g_ft_per_s2: f64,
    /// Ixx, slug·ft².
    pub ixx_slug_ft2: f64,
    /// Iyy, slug·ft².
    pub iyy_slug_ft2: f64,
    /// Izz, slug·ft².
    pub izz_slug_ft2: f64,
    /// Jxz (positive as in the textbook; tensor element (1,3) is −Jxz), slug·ft².
    pub ixz_slug_ft2: f64,
    /// Engine angular momentum along +x body, slug·ft²/s (160).
    pub hx_slug_ft2_per_s: f64,
}

impl MassProperties {
    /// Mass, slug (1 / `inverse_mass_per_slug`).
    pub fn mass_slug(&self) -> f64 {
        1.0 / self.inverse_mass_per_slug
    }

    /// The body-axis inertia tensor `I = [[Ixx, 0, −Jxz], [0, Iyy, 0], [−Jxz, 0, Izz]]`,
    /// slug·ft² (SLJ §1.3 / §3.5 sign convention: Jxz enters with a minus sign).
    pub fn inertia_slug_ft2(&self) -> nalgebra::Matrix3<f64> {
        nalgebra::Matrix3::new(
            self.ixx_slug_ft2,
            0.0,
            -self.ixz_slug_ft2,
            0.0,
            self.iyy_slug_ft2,
            0.0,
            -self.ixz_slug_ft2,
            0.0,
            self.izz_slug_ft2,
        )
    }

    /// `I⁻¹ = [a_ij]`, 1/(slug·ft²), the matrix of the thesis's moment equations (2.15) and of
    /// its pitch-rate sensitivities C_p, C_q, C_r = (a₁₂, a₂₂, a₃₂)·q̄Sc̄ (3.117). Closed form
    /// with Γ = Ixx·Izz − Jxz²: `a11 = Izz/Γ, a13 = a31 = Jxz/Γ, a22 = 1/Iyy, a33 = Ixx/Γ`
    /// (the exact values of SLJ's c3, c4, c7, c9).
    pub fn inverse_inertia(&self) -> nalgebra::Matrix3<f64> {
        let c = InertiaConstants::of(&Inertia {
            jx: self.ixx_slug_ft2,
            jy: self.iyy_slug_ft2,
            jz: self.izz_slug_ft2,
            jxz: self.ixz_slug_ft2,
        });
        nalgebra::Matrix3::new(c.c3, 0.0, c.c4, 0.0, c.c7, 0.0, c.c4, 0.0, c.c9)
    }
}

/// Geometry (SLJ §3.5).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Wing area S, ft² (300).
    pub wing_area_ft2: f64,
    /// Span b, ft (30).
    pub span_ft: f64,
    /// Mean aerodynamic chord c̄, ft (11.32).
    pub cbar_ft: f64,
    /// Reference cg of the Cm and Cn tables, fraction of c̄ (0.35).
    pub xcgr: f64,
    /// The textbook's nominal cg, fraction of c̄ (0.35).
    pub xcg_nominal: f64,
}

/// Moment-equation constants c1..c9 (SLJ §3.5, rounded textbook values; see the data file):
/// the rigid body's [`InertiaConstants`], read as printed rather than computed from the
/// inertias (so the textbook's check case is reproduced).
pub type MomentConstants = InertiaConstants;

/// The ranges the data are meant for (SLJ subroutine headers; `[ranges]` of the data file),
/// each `[min, max]`. Outside them the lookups extrapolate (README §4): results are flagged,
/// not physics. Angles in degrees as in the file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataRanges {
    /// α, deg.
    pub alpha_deg: [f64; 2],
    /// β, deg.
    pub beta_deg: [f64; 2],
    /// Elevator, deg.
    pub elevator_deg: [f64; 2],
    /// Aileron, deg.
    pub aileron_deg: [f64; 2],
    /// Rudder, deg.
    pub rudder_deg: [f64; 2],
    /// Throttle, 0–1.
    pub throttle: [f64; 2],
    /// Engine power, percent.
    pub power_percent: [f64; 2],
    /// Altitude, ft.
    pub altitude_ft: [f64; 2],
    /// Mach.
    pub mach: [f64; 2],
}

/// CY linear formula constants (SLJ App. A, FUNCTION CY): CY = kβ·β° + ka·(δa°/sa) + kr·(δr°/sr).
#[derive(Debug, Clone, PartialEq)]
pub struct CyFormula {
    /// Per degree of β (−0.02).
    pub beta_coefficient_per_deg: f64,
    /// Per unit normalized aileron (0.021).
    pub aileron_coefficient: f64,
    /// Aileron normalization, deg (20).
    pub aileron_scale_deg: f64,
    /// Per unit normalized rudder (0.086).
    pub rudder_coefficient: f64,
    /// Rudder normalization, deg (30).
    pub rudder_scale_deg: f64,
}

/// CZ constants (SLJ App. A, FUNCTION CZ): CZ = table(α°)·(1 − (β°/βs)²) + ke·(δe°/es).
#[derive(Debug, Clone, PartialEq)]
pub struct CzModel {
    /// CZ(α°), 12 breakpoints −10…45°.
    pub table: Table1<12>,
    /// βs, deg (57.3).
    pub beta_scale_deg: f64,
    /// ke (−0.19).
    pub elevator_coefficient: f64,
    /// es, deg (25).
    pub elevator_scale_deg: f64,
}

/// All numbers of the Stevens–Lewis F-16 model, as fixed arrays. Angles in the tables are in
/// degrees (private breakpoints, SLJ App. A); the model converts.
#[derive(Debug, Clone, PartialEq)]
pub struct F16Data {
    /// Degrees per radian used for α and β (57.29578, the textbook constant).
    pub rad_to_deg: f64,
    /// CX(α°, δe°) (SLJ App. A, CX).
    pub cx: Table2<12, 5>,
    /// CZ model.
    pub cz: CzModel,
    /// Cm(α°, δe°) about xcgr (SLJ App. A, CM).
    pub cm: Table2<12, 5>,
    /// CY formula.
    pub cy: CyFormula,
    /// Cl(α°, |β|°), odd in β (SLJ App. A, CL).
    pub cl: Table2<12, 7>,
    /// Cn(α°, |β|°), odd in β (SLJ App. A, CN).
    pub cn: Table2<12, 7>,
    /// dCl per normalized aileron (α°, β°).
    pub dlda: Table2<12, 7>,
    /// dCl per normalized rudder (α°, β°).
    pub dldr: Table2<12, 7>,
    /// dCn per normalized aileron (α°, β°).
    pub dnda: Table2<12, 7>,
    /// dCn per normalized rudder (α°, β°).
    pub dndr: Table2<12, 7>,
    /// Damping rows vs α° in textbook order CXq, CYr, CYp, CZq, Clr, Clp, Cmq, Cnr, Cnp.
    pub damping: [Table1<12>; 9],
    /// Idle thrust (altitude ft, Mach), lbf.
    pub thrust_idle: Table2<6, 6>,
    /// MIL thrust, lbf.
    pub thrust_mil: Table2<6, 6>,
    /// MAX thrust, lbf.
    pub thrust_max: Table2<6, 6>,
    /// Aileron normalization of dlda/dnda, deg (20).
    pub aileron_scale_deg: f64,
    /// Rudder normalization of dldr/dndr, deg (30).
    pub rudder_scale_deg: f64,
    /// Engine constants.
    pub engine: EngineConstants,
    /// Atmosphere constants.
    pub atmosphere: AtmosphereConstants,
    /// Mass properties.
    pub mass: MassProperties,
    /// Geometry.
    pub geometry: Geometry,
    /// Moment constants c1..c9.
    pub moment: MomentConstants,
    /// Intended ranges of the data.
    pub ranges: DataRanges,
}

fn invalid(table: &'static str, field: &'static str, reason: impl Into<String>) -> DataError {
    DataError::Invalid { table, field, reason: reason.into() }
}

fn finite(table: &'static str, field: &'static str, v: f64) -> Result<f64, DataError> {
    if v.is_finite() { Ok(v) } else { Err(invalid(table, field, format!("not finite: {v}"))) }
}

fn array<const N: usize>(
    table: &'static str,
    field: &'static str,
    v: &[f64],
) -> Result<[f64; N], DataError> {
    let a: [f64; N] = v
        .try_into()
        .map_err(|_| invalid(table, field, format!("expected {N} values, found {}", v.len())))?;
    for &x in &a {
        finite(table, field, x)?;
    }
    Ok(a)
}

fn axis<const N: usize>(
    table: &'static str,
    field: &'static str,
    v: &[f64],
) -> Result<[f64; N], DataError> {
    let a = array::<N>(table, field, v)?;
    check_breakpoints(&a).map_err(|r| invalid(table, field, r))?;
    Ok(a)
}

fn check_axes(table: &'static str, found: &[String], expected: [&str; 2]) -> Result<(), DataError> {
    if found.len() != 2 || found[0] != expected[0] || found[1] != expected[1] {
        return Err(invalid(table, "axes", format!("expected {expected:?}, found {found:?}")));
    }
    Ok(())
}

fn float_list(
    table: &'static str,
    field: &'static str,
    rest: &toml::Table,
) -> Result<Vec<f64>, DataError> {
    let v = rest.get(field).ok_or_else(|| invalid(table, field, "missing"))?;
    let arr = v.as_array().ok_or_else(|| invalid(table, field, "not an array"))?;
    arr.iter()
        .enumerate()
        .map(|(k, x)| {
            x.as_float()
                .or_else(|| x.as_integer().map(|i| i as f64))
                .ok_or_else(|| invalid(table, field, format!("element {k} is not a number")))
        })
        .collect()
}

fn table2<const R: usize, const C: usize>(
    table: &'static str,
    raw: &RawTable2,
    row: &'static str,
    col: &'static str,
) -> Result<Table2<R, C>, DataError> {
    check_axes(table, &raw.axes, [row, col])?;
    let r = axis::<R>(table, row, &float_list(table, row, &raw.rest)?)?;
    let c = axis::<C>(table, col, &float_list(table, col, &raw.rest)?)?;
    let rows = raw
        .rest
        .get("values")
        .and_then(|v| v.as_array())
        .ok_or_else(|| invalid(table, "values", "missing"))?;
    if rows.len() != R {
        return Err(invalid(table, "values", format!("expected {R} rows, found {}", rows.len())));
    }
    let mut z = [[0.0; C]; R];
    for (i, row_v) in rows.iter().enumerate() {
        let cells = row_v
            .as_array()
            .ok_or_else(|| invalid(table, "values", format!("row {i} is not an array")))?;
        let nums: Vec<f64> = cells
            .iter()
            .map(|x| x.as_float().or_else(|| x.as_integer().map(|k| k as f64)))
            .collect::<Option<_>>()
            .ok_or_else(|| invalid(table, "values", format!("row {i} has a non-number")))?;
        z[i] = array::<C>(table, "values", &nums).map_err(|e| match e {
            DataError::Invalid { reason, .. } => {
                invalid(table, "values", format!("row {i}: {reason}"))
            }
            other => other,
        })?;
    }
    Ok(Table2 { r, c, z })
}

const DAMPING_ORDER: [&str; 9] = ["CXq", "CYr", "CYp", "CZq", "Clr", "Clp", "Cmq", "Cnr", "Cnp"];

/// The `[cz]` section: its 1-D α table and the β/elevator build-up constants (SLJ App. A,
/// FUNCTION CZ).
fn cz_model(raw: &RawCz) -> Result<CzModel, DataError> {
    if raw.axes != ["alpha_deg"] {
        return Err(invalid(
            "cz",
            "axes",
            format!("expected [\"alpha_deg\"], found {:?}", raw.axes),
        ));
    }
    Ok(CzModel {
        table: Table1 {
            x: axis::<12>("cz", "alpha_deg", &raw.alpha_deg)?,
            y: array::<12>("cz", "values", &raw.values)?,
        },
        beta_scale_deg: finite("cz", "beta_scale_deg", raw.beta_scale_deg)?,
        elevator_coefficient: finite("cz", "elevator_coefficient", raw.elevator_coefficient)?,
        elevator_scale_deg: finite("cz", "elevator_scale_deg", raw.elevator_scale_deg)?,
    })
}

/// The `[cy]` section: the linear CY formula's constants (SLJ App. A, FUNCTION CY), each
/// required finite.
fn cy_formula(raw: &RawCy) -> Result<CyFormula, DataError> {
    Ok(CyFormula {
        beta_coefficient_per_deg: finite(
            "cy",
            "beta_coefficient_per_deg",
            raw.beta_coefficient_per_deg,
        )?,
        aileron_coefficient: finite("cy", "aileron_coefficient", raw.aileron_coefficient)?,
        aileron_scale_deg: finite("cy", "aileron_scale_deg", raw.aileron_scale_deg)?,
        rudder_coefficient: finite("cy", "rudder_coefficient", raw.rudder_coefficient)?,
        rudder_scale_deg: finite("cy", "rudder_scale_deg", raw.rudder_scale_deg)?,
    })
}

/// The `[damping]` section: nine rows vs α° in the textbook order [`DAMPING_ORDER`] (the model
/// indexes them by position, so the order is checked, not just the count), all on one α axis.
fn damping_tables(d: &RawDamping) -> Result<[Table1<12>; 9], DataError> {
    if d.axes != ["coefficient", "alpha_deg"] {
        return Err(invalid(
            "damping",
            "axes",
            format!("expected [\"coefficient\", \"alpha_deg\"], found {:?}", d.axes),
        ));
    }
    if d.coefficient != DAMPING_ORDER {
        return Err(invalid(
            "damping",
            "coefficient",
            format!("expected {DAMPING_ORDER:?}, found {:?}", d.coefficient),
        ));
    }
    let alpha = axis::<12>("damping", "alpha_deg", &d.alpha_deg)?;
    if d.values.len() != 9 {
        return Err(invalid(
            "damping",
            "values",
            format!("expected 9 rows, found {}", d.values.len()),
        ));
    }
    let mut rows = Vec::with_capacity(9);
    for (i, row) in d.values.iter().enumerate() {
        let y = array::<12>("damping", "values", row).map_err(|e| match e {
            DataError::Invalid { reason, .. } => {
                invalid("damping", "values", format!("row {i} ({}): {reason}", DAMPING_ORDER[i]))
            }
            other => other,
        })?;
        rows.push(Table1 { x: alpha, y });
    }
    rows.try_into().map_err(|_| invalid("damping", "values", "expected 9 rows"))
}

impl F16Data {
    /// Parses the data file's text.
    ///
    /// # Errors
    /// [`DataError::Toml`] for syntax or missing keys (message with line/column);
    /// [`DataError::Invalid`] naming table and field for a wrong shape, axis name, non-increasing
    /// breakpoints or non-finite number.
    pub fn parse(text: &str) -> Result<Self, DataError> {
        let raw: RawFile = toml::from_str(text).map_err(|e| DataError::Toml(e.to_string()))?;
        let rad_to_deg = finite("constants", "rad_to_deg", raw.constants.rad_to_deg)?;
        let cx = table2::<12, 5>("cx", &raw.cx, "alpha_deg", "elevator_deg")?;
        let cm = table2::<12, 5>("cm", &raw.cm, "alpha_deg", "elevator_deg")?;
        let cl = table2::<12, 7>("cl", &raw.cl, "alpha_deg", "abs_beta_deg")?;
        let cn = table2::<12, 7>("cn", &raw.cn, "alpha_deg", "abs_beta_deg")?;
        let dlda = table2::<12, 7>("dlda", &raw.dlda, "alpha_deg", "beta_deg")?;
        let dldr = table2::<12, 7>("dldr", &raw.dldr, "alpha_deg", "beta_deg")?;
        let dnda = table2::<12, 7>("dnda", &raw.dnda, "alpha_deg", "beta_deg")?;
        let dndr = table2::<12, 7>("dndr", &raw.dndr, "alpha_deg", "beta_deg")?;
        let thrust_idle = table2::<6, 6>("thrust_idle", &raw.thrust_idle, "altitude_ft", "mach")?;
        let thrust_mil = table2::<6, 6>("thrust_mil", &raw.thrust_mil, "altitude_ft", "mach")?;
        let thrust_max = table2::<6, 6>("thrust_max", &raw.thrust_max, "altitude_ft", "mach")?;
        let cz = cz_model(&raw.cz)?;
        let cy = cy_formula(&raw.cy)?;
        let damping = damping_tables(&raw.damping)?;

        let data = Self {
            rad_to_deg,
            cx,
            cz,
            cm,
            cy,
            cl,
            cn,
            dlda,
            dldr,
            dnda,
            dndr,
            damping,
            thrust_idle,
            thrust_mil,
            thrust_max,
            aileron_scale_deg: raw.buildup.aileron_scale_deg,
            rudder_scale_deg: raw.buildup.rudder_scale_deg,
            engine: raw.engine,
            atmosphere: raw.atmosphere,
            mass: raw.mass,
            geometry: raw.geometry,
            moment: raw.moment_constants,
            ranges: raw.ranges,
        };
        data.check_shared_axes()?;
        data.check_physical()?;
        Ok(data)
    }

    /// Rejects tables whose breakpoints differ where the model assumes one shared axis.
    ///
    /// All aerodynamic tables share one alpha axis (SLJ App. A: −10…45° by 5°); the model
    /// locates alpha once per evaluation, so insist on it here. Likewise for the elevator axis
    /// of cx/cm, the |β| axis of cl/cn, the β axis of the four control-derivative tables and
    /// the (altitude, Mach) grid of the three thrust tables.
    fn check_shared_axes(&self) -> Result<(), DataError> {
        let alpha_axis = self.cx.r;
        for (name, ax) in [
            ("cm", &self.cm.r),
            ("cl", &self.cl.r),
            ("cn", &self.cn.r),
            ("dlda", &self.dlda.r),
            ("dldr", &self.dldr.r),
            ("dnda", &self.dnda.r),
            ("dndr", &self.dndr.r),
            ("cz", &self.cz.table.x),
            ("damping", &self.damping[0].x),
        ] {
            if *ax != alpha_axis {
                return Err(invalid(
                    name,
                    "alpha_deg",
                    "must equal the alpha axis of cx (shared axis)",
                ));
            }
        }
        if self.cm.c != self.cx.c {
            return Err(invalid(
                "cm",
                "elevator_deg",
                "must equal the elevator axis of cx (shared axis)",
            ));
        }
        if self.cn.c != self.cl.c {
            return Err(invalid(
                "cn",
                "abs_beta_deg",
                "must equal the |beta| axis of cl (shared axis)",
            ));
        }
        for (name, ax) in [("dldr", &self.dldr.c), ("dnda", &self.dnda.c), ("dndr", &self.dndr.c)] {
            if *ax != self.dlda.c {
                return Err(invalid(
                    name,
                    "beta_deg",
                    "must equal the beta axis of dlda (shared axis)",
                ));
            }
        }
        let (idle, mil, max) = (&self.thrust_idle, &self.thrust_mil, &self.thrust_max);
        if mil.r != idle.r || max.r != idle.r || mil.c != idle.c || max.c != idle.c {
            return Err(invalid(
                "thrust_mil",
                "altitude_ft",
                "thrust tables must share the altitude and Mach axes of thrust_idle",
            ));
        }
        Ok(())
    }

    /// Rejects physically meaningless constants: masses, inertias, lengths, densities,
    /// temperatures and control normalizations must be finite and positive (they divide or
    /// scale the dynamics), and every intended range must be a finite `[min, max]` with
    /// `min < max`.
    fn check_physical(&self) -> Result<(), DataError> {
        let positive = |table: &'static str, field: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(invalid(table, field, format!("must be finite and > 0, got {v}")))
            }
        };
        let m = &self.mass;
        positive("mass", "inverse_mass_per_slug", m.inverse_mass_per_slug)?;
        positive("mass", "g_ft_per_s2", m.g_ft_per_s2)?;
        positive("mass", "ixx_slug_ft2", m.ixx_slug_ft2)?;
        positive("mass", "iyy_slug_ft2", m.iyy_slug_ft2)?;
        positive("mass", "izz_slug_ft2", m.izz_slug_ft2)?;
        let g = &self.geometry;
        positive("geometry", "wing_area_ft2", g.wing_area_ft2)?;
        positive("geometry", "span_ft", g.span_ft)?;
        positive("geometry", "cbar_ft", g.cbar_ft)?;
        let a = &self.atmosphere;
        positive("atmosphere", "rho0_slug_per_ft3", a.rho0_slug_per_ft3)?;
        positive("atmosphere", "t0_rankine", a.t0_rankine)?;
        positive("atmosphere", "t_above_tropopause_rankine", a.t_above_tropopause_rankine)?;
        positive("buildup", "aileron_scale_deg", self.aileron_scale_deg)?;
        positive("buildup", "rudder_scale_deg", self.rudder_scale_deg)?;
        let rg = &self.ranges;
        for (field, r) in [
            ("alpha_deg", rg.alpha_deg),
            ("beta_deg", rg.beta_deg),
            ("elevator_deg", rg.elevator_deg),
            ("aileron_deg", rg.aileron_deg),
            ("rudder_deg", rg.rudder_deg),
            ("throttle", rg.throttle),
            ("power_percent", rg.power_percent),
            ("altitude_ft", rg.altitude_ft),
            ("mach", rg.mach),
        ] {
            if !(r[0].is_finite() && r[1].is_finite() && r[0] < r[1]) {
                return Err(invalid(
                    "ranges",
                    field,
                    format!("must be [min, max] with min < max, got {r:?}"),
                ));
            }
        }
        Ok(())
    }

    /// The shipped data ([`EMBEDDED_TOML`]), parsed once on first use.
    ///
    /// # Panics
    /// Never in practice: the embedded text is a compile-time constant and the test
    /// `embedded_data_parses` guarantees it parses; the `expect` only documents that invariant.
    pub fn embedded() -> &'static F16Data {
        static DATA: OnceLock<F16Data> = OnceLock::new();
        DATA.get_or_init(|| {
            F16Data::parse(EMBEDDED_TOML)
                .expect("embedded F-16 data parses (tested by embedded_data_parses)")
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_data_parses() {
        let d = F16Data::parse(EMBEDDED_TOML).unwrap();
        // Spot values straight from SLJ App. A as printed in the data file.
        assert_eq!(d.cx.z[0][0], -0.099);
        assert_eq!(d.damping[6].y[1], -0.540);
        assert_eq!(d.thrust_idle.z[1][3], -710.0);
        assert_eq!(d.moment.c1, -0.770);
    }

    #[test]
    fn analytic_inverse_inertia_matches_slj_moment_constants() {
        let d = F16Data::parse(EMBEDDED_TOML).unwrap();
        let m = &d.mass;
        let inv = m.inverse_inertia();
        assert!((m.inertia_slug_ft2() * inv - nalgebra::Matrix3::identity()).amax() < 1e-15);
        // SLJ's rounded c3, c4, c7, c9 (data file) agree with the exact a_ij to their rounding.
        for (exact, rounded) in [
            (inv[(0, 0)], d.moment.c3),
            (inv[(0, 2)], d.moment.c4),
            (inv[(1, 1)], d.moment.c7),
            (inv[(2, 2)], d.moment.c9),
        ] {
            assert!(((exact - rounded) / exact).abs() < 2e-3, "{exact} vs {rounded}");
        }
        assert!((m.mass_slug() * m.g_ft_per_s2 - m.weight_lbf).abs() < 1e-3);
    }

    fn expect_invalid(text: &str, table: &str, field: &str) {
        match F16Data::parse(text) {
            Err(DataError::Invalid { table: t, field: f, .. }) => {
                assert_eq!((t, f), (table, field));
            }
            other => panic!("expected Invalid {table}.{field}, got {other:?}"),
        }
    }

    #[test]
    fn malformed_data_is_rejected_with_table_and_field() {
        // A short row.
        let bad = EMBEDDED_TOML.replacen(
            "[ -0.099,  -0.048,  -0.022,  -0.040,  -0.083]",
            "[ -0.099,  -0.048,  -0.022,  -0.040]",
            1,
        );
        expect_invalid(&bad, "cx", "values");
        // Swapped axes (the orientation trap of README §4).
        let bad = EMBEDDED_TOML.replacen(
            "axes = [\"altitude_ft\", \"mach\"]",
            "axes = [\"mach\", \"altitude_ft\"]",
            1,
        );
        expect_invalid(&bad, "thrust_idle", "axes");
        // Non-increasing breakpoints.
        let bad = EMBEDDED_TOML.replacen(
            "elevator_deg = [-24.0, -12.0, 0.0, 12.0, 24.0]",
            "elevator_deg = [-24.0, 12.0, 0.0, 12.0, 24.0]",
            1,
        );
        expect_invalid(&bad, "cx", "elevator_deg");
        // Wrong damping order.
        let bad = EMBEDDED_TOML.replacen(
            "coefficient = [\"CXq\", \"CYr\"",
            "coefficient = [\"CYr\", \"CXq\"",
            1,
        );
        expect_invalid(&bad, "damping", "coefficient");
        // Syntax error names the line.
        let bad = EMBEDDED_TOML.replacen("rad_to_deg = 57.29578", "rad_to_deg = = 57.29578", 1);
        match F16Data::parse(&bad) {
            Err(DataError::Toml(msg)) => assert!(msg.contains("line"), "{msg}"),
            other => panic!("expected Toml error, got {other:?}"),
        }
        // Missing section.
        let bad = EMBEDDED_TOML.replacen("[moment_constants]", "[moment_constants_x]", 1);
        assert!(matches!(F16Data::parse(&bad), Err(DataError::Toml(_))));
    }
}
