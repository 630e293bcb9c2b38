//! The Stevens–Lewis nonlinear F-16 (SLJ 3rd ed. §3.5, subroutine F; data of NASA TP-1538):
//! 13 states, flat earth, the textbook's air-data computer, engine power lag, gyroscopic engine
//! momentum, and table aerodynamics with the textbook's linear extrapolation (README §4 of the
//! data set; [`crate::f16::table::Extrapolation::Linear`]).
//!
//! # States (index, name, unit) — [`crate::f16::STATE_NAMES`]
//! `0 vt_fps, 1 alpha_rad, 2 beta_rad, 3 phi_rad, 4 theta_rad, 5 psi_rad, 6 p_rad_s, 7 q_rad_s,
//! 8 r_rad_s, 9 north_ft, 10 east_ft, 11 alt_ft (up), 12 pow_pct` (engine power, 0 idle, 50 MIL,
//! 100 MAX). `vt, alpha, beta` describe the **inertial** (ground-relative) velocity in body axes.
//!
//! # Controls — [`crate::f16::F16Controls`]
//! Throttle 0–1, elevator/aileron/rudder in **radians** (the tables take degrees internally),
//! textbook signs: positive deflection gives a negative moment (README §3). Plus the wind.
//!
//! # Wind
//! Wind enters only the aerodynamics: the body-axis wind `C_body←NED · w_NED + w_body` is subtracted
//! from the body velocity before air-relative `vt, α, β`, Mach and q̄ are computed; gravity,
//! kinematics and navigation use the inertial velocity. Wind gradients (rotational
//! turbulence) are not modelled. With zero wind the model is the textbook's exactly.
//!
//! # Units and signs
//! ft, s, slug, lbf, rad. Body axes x forward, y right, z down; altitude up (ḣ = −ż_NED).
//!
//! # Example: reference aircraft with "damage" and an estimator's candidate model
//! ```
//! use aeroident_models::Dynamics;
//! use aeroident_models::f16::{AeroIncrements, F16, IncrementReference, IncrementSchedule, ALPHA, Q};
//! use aeroident_models::trim::{trim, TrimCondition};
//! let nominal = F16::new(0.30)?; // xcg 0.30: open-loop stable
//! let t = trim(&nominal, &TrimCondition::level(20_000.0, 675.0))?; // thesis condition
//! let reference = IncrementReference {
//!     alpha_rad: t.state[ALPHA],
//!     q_rad_s: t.state[Q],
//!     elevator_rad: t.controls.elevator_rad,
//!     ..Default::default()
//! };
//! // Truth: ΔCm_α, ΔCm_q, ΔCL_α, ΔCD_α (per rad) switched on at t = 1 s.
//! let truth = AeroIncrements::thesis(reference, 0.0015, 0.01, 0.01, 0.001);
//! let aircraft = nominal.clone().with_increments(truth, IncrementSchedule::StepAt { t0_s: 1.0 });
//! let xdot_true = aircraft.derivatives(2.0, &t.state, &t.controls)?;
//! // Estimator: ẋ for a candidate θ̂ at the same state, without building a new model.
//! let candidate = AeroIncrements::thesis(reference, 0.001, 0.0, 0.0, 0.0);
//! let xdot_hat = nominal.derivatives_with_increments(&t.state, &t.controls, &candidate)?;
//! // At the trim point Δα = Δq = 0, so every increment contributes nothing.
//! assert!((xdot_true - xdot_hat).amax() < 1e-12);
//! # Ok::<(), aeroident_models::ModelError>(())
//! ```

#![allow(clippy::excessive_precision)]

pub mod data;
pub mod increments;
pub mod table;

pub use data::{DataError, F16Data};
pub use increments::{
    AeroCoefficient, AeroIncrements, IncrementInputs, IncrementReference, IncrementRegressor,
    IncrementSchedule,
};

use crate::atmosphere::air_data;
use crate::{Dynamics, ModelError};
use nalgebra::SVector;
use table::Extrapolation;

/// Number of states.
pub const N_STATES: usize = 13;
/// Number of controls in [`F16Controls::to_vector`] order (throttle, elevator, aileron, rudder).
pub const N_CONTROLS: usize = 4;

/// State index: true airspeed, ft/s.
pub const VT: usize = 0;
/// State index: angle of attack, rad.
pub const ALPHA: usize = 1;
/// State index: sideslip, rad.
pub const BETA: usize = 2;
/// State index: roll angle φ, rad.
pub const PHI: usize = 3;
/// State index: pitch angle θ, rad.
pub const THETA: usize = 4;
/// State index: heading ψ, rad.
pub const PSI: usize = 5;
/// State index: body roll rate p, rad/s.
pub const P: usize = 6;
/// State index: body pitch rate q, rad/s.
pub const Q: usize = 7;
/// State index: body yaw rate r, rad/s.
pub const R: usize = 8;
/// State index: north position, ft.
pub const NORTH: usize = 9;
/// State index: east position, ft.
pub const EAST: usize = 10;
/// State index: altitude (up), ft.
pub const ALT: usize = 11;
/// State index: engine power, percent.
pub const POW: usize = 12;

/// State names with units, in state order (also CSV column names).
pub const STATE_NAMES: [&str; N_STATES] = [
    "vt_fps",
    "alpha_rad",
    "beta_rad",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "north_ft",
    "east_ft",
    "alt_ft",
    "pow_pct",
];
/// Control names with units, in [`F16Controls::to_vector`] order.
pub const CONTROL_NAMES: [&str; N_CONTROLS] =
    ["throttle", "elevator_rad", "aileron_rad", "rudder_rad"];

/// The F-16 state vector, in the order of [`STATE_NAMES`].
pub type F16State = SVector<f64, N_STATES>;

/// Pilot controls and the wind, held over an integration step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct F16Controls {
    /// Throttle, 0–1 (0.77 = MIL, 1 = MAX through TGEAR).
    pub throttle: f64,
    /// Elevator δe, rad, positive trailing edge down (nose down).
    pub elevator_rad: f64,
    /// Aileron δa, rad, positive gives a negative rolling moment.
    pub aileron_rad: f64,
    /// Rudder δr, rad, positive trailing edge left (negative yawing moment).
    pub rudder_rad: f64,
    /// Wind velocity in the NED frame, ft/s (air moving towards north/east/down).
    pub wind_ned_fps: [f64; 3],
    /// Wind velocity in body axes, ft/s (x forward: a positive value is a tailwind; z down: a
    /// downdraft), the frame of the thesis's 1-cos gust (2.32) and of MIL-F-8785C Dryden
    /// components (`aeroident_signals::WindField`). Adds to `wind_ned_fps`.
    pub wind_body_fps: [f64; 3],
}

impl F16Controls {
    /// Controls in still air. Surfaces in radians.
    pub fn new(throttle: f64, elevator_rad: f64, aileron_rad: f64, rudder_rad: f64) -> Self {
        Self {
            throttle,
            elevator_rad,
            aileron_rad,
            rudder_rad,
            wind_ned_fps: [0.0; 3],
            wind_body_fps: [0.0; 3],
        }
    }
    /// `[throttle, elevator_rad, aileron_rad, rudder_rad]`.
    pub fn to_vector(&self) -> SVector<f64, N_CONTROLS> {
        SVector::<f64, N_CONTROLS>::new(
            self.throttle,
            self.elevator_rad,
            self.aileron_rad,
            self.rudder_rad,
        )
    }
    /// The inverse of [`Self::to_vector`], keeping the winds of `self`.
    pub fn with_vector(&self, u: &SVector<f64, N_CONTROLS>) -> Self {
        Self {
            throttle: u[0],
            elevator_rad: u[1],
            aileron_rad: u[2],
            rudder_rad: u[3],
            wind_ned_fps: self.wind_ned_fps,
            wind_body_fps: self.wind_body_fps,
        }
    }
}

/// Total aerodynamic coefficients at the actual cg (increments included), dimensionless.
/// CX, CZ exclude thrust. CL, CD are stability-axis: `CL = CX·sinα − CZ·cosα`,
/// `CD = −CX·cosα − CZ·sinα` (α air-relative).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AeroCoefficients {
    /// Body x force coefficient.
    pub CX: f64,
    /// Body y (side) force coefficient.
    pub CY: f64,
    /// Body z force coefficient (negative in lifting flight).
    pub CZ: f64,
    /// Rolling moment coefficient.
    pub Cl: f64,
    /// Pitching moment coefficient.
    pub Cm: f64,
    /// Yawing moment coefficient.
    pub Cn: f64,
    /// Lift coefficient (stability axes).
    pub CL: f64,
    /// Drag coefficient (stability axes).
    pub CD: f64,
}

/// Outputs of one evaluation at the cg.
///
/// Accelerometer convention: `nx_g`, `ny_g` are the specific force (aerodynamic + thrust,
/// no gravity) along body +x and +y in g; `nz_g` is the specific force along body **−z**
/// (positive up, the pilot's "g", SLJ `an` = −q̄S·CZ/(m g)), so steady level flight reads
/// nx ≈ 0, ny = 0, nz = 1 g. g = 32.17 ft/s² (the model's).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct F16Outputs {
    /// Longitudinal load factor, g (positive forward).
    pub nx_g: f64,
    /// Lateral load factor, g (positive right; SLJ `alat`).
    pub ny_g: f64,
    /// Normal load factor, g (positive up; SLJ `an`).
    pub nz_g: f64,
    /// Dynamic pressure from the air-relative speed, lbf/ft².
    pub qbar_psf: f64,
    /// Mach number (air-relative).
    pub mach: f64,
    /// Air-relative true airspeed, ft/s.
    pub vt_air_fps: f64,
    /// Air-relative α, rad.
    pub alpha_air_rad: f64,
    /// Air-relative β, rad.
    pub beta_air_rad: f64,
    /// Thrust, lbf.
    pub thrust_lbf: f64,
    /// Total aerodynamic coefficients.
    pub coefficients: AeroCoefficients,
}

/// Throttle gearing TGEAR (SLJ §3.5): commanded power, percent, for throttle 0–1.
#[inline]
pub fn tgear(e: &data::EngineConstants, throttle: f64) -> f64 {
    if throttle <= e.throttle_break {
        e.tgear_low_slope * throttle
    } else {
        e.tgear_high_slope * throttle + e.tgear_high_offset
    }
}

/// Reciprocal time constant RTAU (SLJ §3.5), 1/s, for a power step `dp` (percent).
#[inline]
pub fn rtau(e: &data::EngineConstants, dp: f64) -> f64 {
    if dp <= e.rtau_dp_low {
        e.rtau_low
    } else if dp >= e.rtau_dp_high {
        e.rtau_high
    } else {
        e.rtau_intercept + e.rtau_slope * dp
    }
}

/// Power rate PDOT (SLJ §3.5), percent/s, for actual power `pow` and commanded `cpow` (percent).
#[inline]
pub fn pdot(e: &data::EngineConstants, pow: f64, cpow: f64) -> f64 {
    let mil = e.mil_power_percent;
    let (target, rate) = if cpow >= mil {
        if pow >= mil {
            (cpow, e.afterburner_rate_per_s)
        } else {
            (e.afterburner_light_target_percent, rtau(e, e.afterburner_light_target_percent - pow))
        }
    } else if pow >= mil {
        (e.afterburner_cut_target_percent, e.afterburner_rate_per_s)
    } else {
        (cpow, rtau(e, cpow - pow))
    };
    rate * (target - pow)
}

/// Thrust THRUST (SLJ §3.5), lbf, at power `pow` (percent), altitude `alt_ft` and `mach`:
/// bilinear in (altitude, Mach), extrapolated linearly, then blended by power.
#[inline]
pub fn thrust_lbf(d: &F16Data, pow: f64, alt_ft: f64, mach: f64) -> f64 {
    let x = Extrapolation::Linear;
    let mil = d.engine.mil_power_percent;
    let (sh, sm) =
        (table::segment(&d.thrust_mil.r, alt_ft, x), table::segment(&d.thrust_mil.c, mach, x));
    let tmil = d.thrust_mil.at(sh, sm);
    if pow < mil {
        let tidl = d.thrust_idle.at(sh, sm);
        tidl + (tmil - tidl) * pow / mil
    } else {
        let tmax = d.thrust_max.at(sh, sm);
        tmil + (tmax - tmil) * (pow - mil) / mil
    }
}

/// The F-16 model: data, cg position and (optionally scheduled) aerodynamic increments.
#[derive(Debug, Clone)]
pub struct F16 {
    data: &'static F16Data,
    /// Centre of gravity, fraction of c̄ (0.35 nominal; use 0.30 for open-loop runs, data
    /// README §7; the check case uses 0.40).
    pub xcg: f64,
    /// Increments added to the textbook coefficients (thesis 3.100–3.101).
    pub increments: AeroIncrements,
    /// When the increments act.
    pub schedule: IncrementSchedule,
}

impl F16 {
    /// The textbook aircraft (embedded data, no increments) with cg `xcg` (fraction of c̄).
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] if `xcg` is not finite.
    pub fn new(xcg: f64) -> Result<Self, ModelError> {
        Self::with_data(F16Data::embedded(), xcg)
    }

    /// The model on other data (e.g. a variant table set parsed with [`F16Data::parse`]).
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] if `xcg` is not finite.
    pub fn with_data(data: &'static F16Data, xcg: f64) -> Result<Self, ModelError> {
        if !xcg.is_finite() {
            return Err(ModelError::InvalidValue {
                field: "xcg",
                value: xcg,
                reason: "not finite",
            });
        }
        Ok(Self {
            data,
            xcg,
            increments: AeroIncrements::zero(),
            schedule: IncrementSchedule::Always,
        })
    }

    /// The same aircraft with `increments` acting per `schedule`.
    pub fn with_increments(
        mut self,
        increments: AeroIncrements,
        schedule: IncrementSchedule,
    ) -> Self {
        self.increments = increments;
        self.schedule = schedule;
        self
    }

    /// The model data.
    pub fn data(&self) -> &'static F16Data {
        self.data
    }

    /// The increments acting at `t_s` (zero before a [`IncrementSchedule::StepAt`] onset).
    pub fn increments_at(&self, t_s: f64) -> AeroIncrements {
        if self.schedule.active(t_s) { self.increments } else { AeroIncrements::zero() }
    }

    /// State derivatives with explicit increments `inc` (ignores `self.increments` and the
    /// schedule). This is the cheap path for an estimator's model: evaluate ẋ(θ̂) for a
    /// candidate increment set at a given state, without cloning the model.
    ///
    /// # Errors
    /// As [`Dynamics::derivatives`].
    pub fn derivatives_with_increments(
        &self,
        x: &F16State,
        u: &F16Controls,
        inc: &AeroIncrements,
    ) -> Result<F16State, ModelError> {
        self.evaluate(x, u, inc).map(|(xd, _)| xd)
    }

    /// Outputs (load factors, air data, coefficients) at time `t_s`.
    ///
    /// # Errors
    /// As [`Dynamics::derivatives`].
    pub fn outputs(
        &self,
        t_s: f64,
        x: &F16State,
        u: &F16Controls,
    ) -> Result<F16Outputs, ModelError> {
        self.evaluate(x, u, &self.increments_at(t_s)).map(|(_, o)| o)
    }

    /// State derivatives and outputs together, with explicit increments.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] when a state or control is not finite, `vt` (inertial or
    /// air-relative) is not positive, |θ| = 90° (Euler singularity), or the altitude is outside
    /// the atmosphere model.
    pub fn evaluate(
        &self,
        x: &F16State,
        u: &F16Controls,
        inc: &AeroIncrements,
    ) -> Result<(F16State, F16Outputs), ModelError> {
        for (k, v) in x.iter().enumerate() {
            if !v.is_finite() {
                return Err(ModelError::InvalidValue {
                    field: STATE_NAMES[k],
                    value: *v,
                    reason: "not finite",
                });
            }
        }
        let ctl = [
            u.throttle,
            u.elevator_rad,
            u.aileron_rad,
            u.rudder_rad,
            u.wind_ned_fps[0],
            u.wind_ned_fps[1],
            u.wind_ned_fps[2],
            u.wind_body_fps[0],
            u.wind_body_fps[1],
            u.wind_body_fps[2],
        ];
        const CTL: [&str; 10] = [
            "throttle",
            "elevator_rad",
            "aileron_rad",
            "rudder_rad",
            "wind_north_fps",
            "wind_east_fps",
            "wind_down_fps",
            "wind_body_x_fps",
            "wind_body_y_fps",
            "wind_body_z_fps",
        ];
        for (k, v) in ctl.iter().enumerate() {
            if !v.is_finite() {
                return Err(ModelError::InvalidValue {
                    field: CTL[k],
                    value: *v,
                    reason: "not finite",
                });
            }
        }
        let d = self.data;
        let vt = x[VT];
        if vt <= 0.0 {
            return Err(ModelError::InvalidValue {
                field: "vt_fps",
                value: vt,
                reason: "must be > 0",
            });
        }
        let (alpha, beta, phi, theta, psi) = (x[ALPHA], x[BETA], x[PHI], x[THETA], x[PSI]);
        let (p, q, r) = (x[P], x[Q], x[R]);
        let alt = x[ALT];
        let pow = x[POW];
        let (sth, cth) = theta.sin_cos();
        if cth == 0.0 {
            return Err(ModelError::InvalidValue {
                field: "theta_rad",
                value: theta,
                reason: "Euler-angle singularity at |theta| = 90 deg",
            });
        }
        let (sph, cph) = phi.sin_cos();
        let (spsi, cpsi) = psi.sin_cos();

        // Inertial body velocity.
        let cbta = beta.cos();
        let (salp, calp) = alpha.sin_cos();
        let u_b = vt * calp * cbta;
        let v_b = vt * beta.sin();
        let w_b = vt * salp * cbta;

        // Direction cosines body←NED (rows: body x, y, z).
        let t1 = sph * cpsi;
        let t2 = cph * sth;
        let t3 = sph * spsi;
        let s1 = cth * cpsi;
        let s2 = cth * spsi;
        let s3 = t1 * sth - cph * spsi;
        let s4 = t3 * sth + cph * cpsi;
        let s5 = sph * cth;
        let s6 = t2 * cpsi + t3;
        let s7 = t2 * spsi - t1;
        let s8 = cph * cth;

        // Air-relative velocity.
        let still_air = u.wind_ned_fps == [0.0; 3] && u.wind_body_fps == [0.0; 3];
        let (vta, alpha_a, beta_a) = if still_air {
            (vt, alpha, beta)
        } else {
            let [wn, we, wd] = u.wind_ned_fps;
            let [wx, wy, wz] = u.wind_body_fps;
            let ua = u_b - (s1 * wn + s2 * we - sth * wd) - wx;
            let va = v_b - (s3 * wn + s4 * we + s5 * wd) - wy;
            let wa = w_b - (s6 * wn + s7 * we + s8 * wd) - wz;
            let vta = (ua * ua + va * va + wa * wa).sqrt();
            if vta <= 0.0 {
                return Err(ModelError::InvalidValue {
                    field: "vt_air_fps",
                    value: vta,
                    reason: "air-relative speed must be > 0",
                });
            }
            (vta, wa.atan2(ua), (va / vta).clamp(-1.0, 1.0).asin())
        };

        let ad = air_data(&d.atmosphere, vta, alt)?;
        let cpow = tgear(&d.engine, u.throttle);
        let pow_dot = pdot(&d.engine, pow, cpow);
        let thrust = thrust_lbf(d, pow, alt, ad.mach);

        // Aerodynamic build-up (SLJ §3.5; README §5). Tables in degrees.
        let lin = Extrapolation::Linear;
        let rtod = d.rad_to_deg;
        let a_deg = alpha_a * rtod;
        let b_deg = beta_a * rtod;
        let el = u.elevator_rad.to_degrees();
        let ail = u.aileron_rad.to_degrees();
        let rdr = u.rudder_rad.to_degrees();
        let dail = ail / d.aileron_scale_deg;
        let drdr = rdr / d.rudder_scale_deg;
        let sign_b = if b_deg < 0.0 { -1.0 } else { 1.0 };
        let abs_b = b_deg.abs();

        // Locate each argument once on its (shared, checked at load) axis.
        let sa_ = table::segment(&d.cx.r, a_deg, lin);
        let se_ = table::segment(&d.cx.c, el, lin);
        let sab_ = table::segment(&d.cl.c, abs_b, lin);
        let sb_ = table::segment(&d.dlda.c, b_deg, lin);
        let mut cxt = d.cx.at(sa_, se_);
        let mut cyt = d.cy.beta_coefficient_per_deg * b_deg
            + d.cy.aileron_coefficient * (ail / d.cy.aileron_scale_deg)
            + d.cy.rudder_coefficient * (rdr / d.cy.rudder_scale_deg);
        let bs = b_deg / d.cz.beta_scale_deg;
        let mut czt = d.cz.table.at(sa_) * (1.0 - bs * bs)
            + d.cz.elevator_coefficient * (el / d.cz.elevator_scale_deg);
        let mut clt =
            sign_b * d.cl.at(sa_, sab_) + d.dlda.at(sa_, sb_) * dail + d.dldr.at(sa_, sb_) * drdr;
        let mut cmt = d.cm.at(sa_, se_);
        let mut cnt =
            sign_b * d.cn.at(sa_, sab_) + d.dnda.at(sa_, sb_) * dail + d.dndr.at(sa_, sb_) * drdr;

        let g = &d.geometry;
        let tvt = 0.5 / vta;
        let b2v = g.span_ft * tvt;
        let cq = g.cbar_ft * q * tvt;
        let mut dmp = [0.0; 9];
        for (k, t) in d.damping.iter().enumerate() {
            dmp[k] = t.at(sa_);
        }
        cxt += cq * dmp[0];
        cyt += b2v * (dmp[1] * r + dmp[2] * p);
        czt += cq * dmp[3];
        clt += b2v * (dmp[4] * r + dmp[5] * p);
        cmt += cq * dmp[6] + czt * (g.xcgr - self.xcg);
        cnt += b2v * (dmp[7] * r + dmp[8] * p) - cyt * (g.xcgr - self.xcg) * g.cbar_ft / g.span_ft;

        let (sa, ca) = if still_air { (salp, calp) } else { alpha_a.sin_cos() };
        if !inc.is_zero() {
            let dc = inc.deltas(
                &IncrementInputs {
                    vt_fps: vta,
                    alpha_rad: alpha_a,
                    beta_rad: beta_a,
                    p_rad_s: p,
                    q_rad_s: q,
                    r_rad_s: r,
                    elevator_rad: u.elevator_rad,
                    aileron_rad: u.aileron_rad,
                    rudder_rad: u.rudder_rad,
                },
                g.span_ft,
                g.cbar_ft,
            );
            let (dcl, dcd) = (dc[AeroCoefficient::CL as usize], dc[AeroCoefficient::CD as usize]);
            cxt += dcl * sa - dcd * ca;
            czt += -dcl * ca - dcd * sa;
            cyt += dc[AeroCoefficient::CY as usize];
            clt += dc[AeroCoefficient::Cl as usize];
            cmt += dc[AeroCoefficient::Cm as usize];
            cnt += dc[AeroCoefficient::Cn as usize];
        }

        // Forces (inertial velocity; aero from air-relative q̄).
        let m = &d.mass;
        let gd = m.g_ft_per_s2;
        let rm = m.inverse_mass_per_slug;
        let qs = ad.qbar_psf * g.wing_area_ft2;
        let qsb = qs * g.span_ft;
        let rmqs = rm * qs;
        let gcth = gd * cth;
        let qsph = q * sph;
        let ax = rm * (qs * cxt + thrust);
        let ay = rmqs * cyt;
        let az = rmqs * czt;
        let udot = r * v_b - q * w_b - gd * sth + ax;
        let vdot = p * w_b - r * u_b + gcth * sph + ay;
        let wdot = q * u_b - p * v_b + gcth * cph + az;
        let dum = u_b * u_b + w_b * w_b;
        if dum <= 0.0 {
            return Err(ModelError::InvalidValue {
                field: "beta_rad",
                value: beta,
                reason: "|beta| = 90 deg: alpha undefined",
            });
        }

        let mut xd = F16State::zeros();
        xd[VT] = (u_b * udot + v_b * vdot + w_b * wdot) / vt;
        xd[ALPHA] = (u_b * wdot - w_b * udot) / dum;
        xd[BETA] = (vt * vdot - v_b * xd[VT]) * cbta / dum;

        // Kinematics.
        xd[PHI] = p + (sth / cth) * (qsph + r * cph);
        xd[THETA] = q * cph - r * sph;
        xd[PSI] = (qsph + r * cph) / cth;

        // Moments.
        let mc = &d.moment;
        let hx = m.hx_slug_ft2_per_s;
        let roll = qsb * clt;
        let pitch = qs * g.cbar_ft * cmt;
        let yaw = qsb * cnt;
        xd[P] = (mc.c2 * p + mc.c1 * r + mc.c4 * hx) * q + mc.c3 * roll + mc.c4 * yaw;
        xd[Q] = (mc.c5 * p - mc.c7 * hx) * r + mc.c6 * (r * r - p * p) + mc.c7 * pitch;
        xd[R] = (mc.c8 * p - mc.c2 * r + mc.c9 * hx) * q + mc.c4 * roll + mc.c9 * yaw;

        // Navigation.
        xd[NORTH] = u_b * s1 + v_b * s3 + w_b * s6;
        xd[EAST] = u_b * s2 + v_b * s4 + w_b * s7;
        xd[ALT] = u_b * sth - v_b * s5 - w_b * s8;
        xd[POW] = pow_dot;

        let out = F16Outputs {
            nx_g: ax / gd,
            ny_g: ay / gd,
            nz_g: -az / gd,
            qbar_psf: ad.qbar_psf,
            mach: ad.mach,
            vt_air_fps: vta,
            alpha_air_rad: alpha_a,
            beta_air_rad: beta_a,
            thrust_lbf: thrust,
            coefficients: AeroCoefficients {
                CX: cxt,
                CY: cyt,
                CZ: czt,
                Cl: clt,
                Cm: cmt,
                Cn: cnt,
                CL: cxt * sa - czt * ca,
                CD: -cxt * ca - czt * sa,
            },
        };
        Ok((xd, out))
    }
}

impl Dynamics<N_STATES> for F16 {
    type Input = F16Controls;
    /// SLJ §3.5 subroutine F with the increments of `self` active per `self.schedule`.
    fn derivatives(&self, t_s: f64, x: &F16State, u: &F16Controls) -> Result<F16State, ModelError> {
        if self.schedule.active(t_s) {
            self.evaluate(x, u, &self.increments).map(|(xd, _)| xd)
        } else {
            self.evaluate(x, u, &AeroIncrements::zero()).map(|(xd, _)| xd)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SLJ 3rd ed. Table 3.5-2 (p. 185): state, controls (surfaces in deg), xcg = 0.40 and the 13
    /// published derivatives, as transcribed in jgoppert/casadi_f16 test_f16.py::test_table_3_5_2
    /// and fsandre/mcflight eqm_f16.tst (identical), see shared/data/f16-stevens-lewis/check_case.toml.
    pub(crate) const CHECK_STATE: [f64; 13] =
        [500.0, 0.5, -0.2, -1.0, 1.0, -1.0, 0.7, -0.8, 0.9, 1000.0, 900.0, 10000.0, 90.0];
    pub(crate) const CHECK_CONTROLS_DEG: [f64; 4] = [0.9, 20.0, -15.0, -20.0];
    pub(crate) const CHECK_XDOT: [f64; 13] = [
        -75.23724, -0.8813491, -0.4759990, 2.505734, 0.3250820, 2.145926, 12.62679, 0.9649671,
        0.5809759, 342.4439, -266.7707, 248.1241, -58.68999,
    ];

    fn check_inputs() -> (F16State, F16Controls) {
        let c = CHECK_CONTROLS_DEG;
        (
            F16State::from_row_slice(&CHECK_STATE),
            F16Controls::new(c[0], c[1].to_radians(), c[2].to_radians(), c[3].to_radians()),
        )
    }

    #[test]
    fn val_slj_table_3_5_2_state_derivatives() {
        let (x, u) = check_inputs();
        let xd = F16::new(0.40).unwrap().derivatives(0.0, &x, &u).unwrap();
        let mut worst = 0.0f64;
        for k in 0..13 {
            let rel = ((xd[k] - CHECK_XDOT[k]) / CHECK_XDOT[k]).abs();
            worst = worst.max(rel);
            assert!(
                rel < 1e-5,
                "{}: got {} published {} (rel {rel:e})",
                STATE_NAMES[k],
                xd[k],
                CHECK_XDOT[k]
            );
        }
        println!("SLJ Table 3.5-2 worst relative error {worst:e}");
    }

    #[test]
    fn val_check_case_intermediates_and_outputs() {
        // Computed intermediates of the data set (check_case.toml [computed_intermediates], marked
        // "computed", from an independent throw-away implementation): totals and load factors.
        let (x, u) = check_inputs();
        let o = F16::new(0.40).unwrap().outputs(0.0, &x, &u).unwrap();
        let c = o.coefficients;
        for (got, want) in [
            (c.CX, 0.042471908),
            (c.CY, 0.18266550),
            (c.CZ, -1.6613130),
            (c.Cl, 0.057958216),
            (c.Cm, 0.026688348),
            (c.Cn, -0.0011420198),
            (o.thrust_lbf, 15912.065),
            (o.nz_g, 5.3444108),
            (o.ny_g, 0.58763126),
            (o.mach, 0.46435945),
            (o.qbar_psf, 219.72452),
        ] {
            assert!(((got - want) / want).abs() < 1e-6, "got {got} want {want}");
        }
    }

    #[test]
    fn analytic_zero_wind_and_constant_wind_equivalence() {
        // A uniform wind w is equivalent to flying with inertial velocity v and air velocity v − w:
        // the aerodynamic forces must equal those of a still-air state with the air-relative velocity.
        let f = F16::new(0.35).unwrap();
        let mut x = F16State::zeros();
        x[VT] = 500.0;
        x[ALPHA] = 0.05;
        x[ALT] = 10_000.0;
        x[POW] = 20.0;
        let mut u = F16Controls::new(0.2, -0.02, 0.0, 0.0);
        // Head wind of 50 ft/s along the body x axis at theta = psi = 0 => wind_ned = (-50 cos a..)
        // Simplest: a pure headwind along north with alpha=0 frame: use vertical wind instead.
        u.wind_ned_fps = [-50.0, 0.0, 0.0];
        let o = f.outputs(0.0, &x, &u).unwrap();
        let ub = 500.0 * 0.05f64.cos();
        let wb = 500.0 * 0.05f64.sin();
        let vta = ((ub + 50.0).powi(2) + wb * wb).sqrt();
        assert!((o.vt_air_fps - vta).abs() < 1e-9);
        assert!((o.alpha_air_rad - wb.atan2(ub + 50.0)).abs() < 1e-12);
    }

    #[test]
    fn analytic_uniform_steady_wind_is_galilean() {
        // Trimmed flight relative to the air, then the same air-relative motion seen from the
        // ground with a uniform steady wind: the inertial velocity is v_air + w. Every derivative
        // except the position rates must vanish (the aircraft flies the same relative to the air),
        // and the position rates must include the wind.
        use crate::trim::{TrimCondition, trim};
        let f = F16::new(0.30).unwrap();
        let t = trim(&f, &TrimCondition::level(10_000.0, 600.0)).unwrap();
        let a = t.state[ALPHA];
        let w_body = [-30.0, 10.0, 5.0]; // body-axis wind (theta = alpha here, psi = phi = 0)
        let (ua, wa) = (600.0 * a.cos(), 600.0 * a.sin());
        let (ui, vi, wi) = (ua + w_body[0], w_body[1], wa + w_body[2]);
        let vt_i = (ui * ui + vi * vi + wi * wi).sqrt();
        let mut x = t.state;
        x[VT] = vt_i;
        x[ALPHA] = wi.atan2(ui);
        x[BETA] = (vi / vt_i).asin();
        let mut u = t.controls;
        u.wind_body_fps = w_body;
        let xd = f.derivatives(0.0, &x, &u).unwrap();
        for k in [VT, ALPHA, BETA, PHI, THETA, PSI, P, Q, R] {
            assert!(xd[k].abs() < 1e-9, "{}: {}", STATE_NAMES[k], xd[k]);
        }
        // The same wind given in NED (theta = alpha, level heading north) gives the same result.
        let (st, ct) = t.state[THETA].sin_cos();
        let mut u2 = t.controls;
        u2.wind_ned_fps =
            [ct * w_body[0] + st * w_body[2], w_body[1], -st * w_body[0] + ct * w_body[2]];
        let xd2 = f.derivatives(0.0, &x, &u2).unwrap();
        assert!((xd - xd2).amax() < 1e-9);
    }

    #[test]
    fn analytic_increments_shift_coefficients_exactly() {
        let (x, u) = check_inputs();
        let f = F16::new(0.40).unwrap();
        let reference = IncrementReference { alpha_rad: 0.4, q_rad_s: -0.5, ..Default::default() };
        let inc = AeroIncrements::thesis(reference, -0.3, -2.0, 0.7, 0.2);
        let (_, o0) = f.evaluate(&x, &u, &AeroIncrements::zero()).unwrap();
        let (_, o1) = f.evaluate(&x, &u, &inc).unwrap();
        let da = 0.5 - 0.4;
        let qhat = 11.32 / (2.0 * 500.0) * (-0.8 + 0.5);
        assert!((o1.coefficients.Cm - o0.coefficients.Cm - (-0.3 * da - 2.0 * qhat)).abs() < 1e-12);
        assert!((o1.coefficients.CL - o0.coefficients.CL - 0.7 * da).abs() < 1e-12);
        assert!((o1.coefficients.CD - o0.coefficients.CD - 0.2 * da).abs() < 1e-12);
        assert!((o1.coefficients.CY - o0.coefficients.CY).abs() < 1e-15);
        // Scheduled step: inactive before t0.
        let g = f.clone().with_increments(inc, IncrementSchedule::StepAt { t0_s: 1.0 });
        assert_eq!(g.derivatives(0.5, &x, &u).unwrap(), f.derivatives(0.5, &x, &u).unwrap());
        assert_eq!(
            g.derivatives(1.0, &x, &u).unwrap(),
            f.derivatives_with_increments(&x, &u, &inc).unwrap()
        );
    }

    #[test]
    fn bad_inputs_are_errors_not_nan() {
        let (mut x, u) = check_inputs();
        let f = F16::new(0.35).unwrap();
        x[VT] = 0.0;
        assert!(f.derivatives(0.0, &x, &u).is_err());
        x[VT] = f64::NAN;
        assert!(matches!(
            f.derivatives(0.0, &x, &u),
            Err(ModelError::InvalidValue { field: "vt_fps", .. })
        ));
        assert!(F16::new(f64::INFINITY).is_err());
    }
}
