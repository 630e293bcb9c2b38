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
//! # Structure
//! [`F16::evaluate`](crate::f16::F16::evaluate) is the F-16's own part of subroutine F (air
//! data, engine, table aerodynamics, increments, loads) on top of the aircraft-independent
//! flat-earth rigid body of [`crate::rigid_body`] (force, kinematic, moment and navigation
//! equations; states 0–11).
//!
//! # Wind
//! The convention of [`crate::rigid_body`]: wind is the air's velocity over the ground, and
//! the air-relative velocity is the inertial velocity minus the body-axis wind
//! `C_body←NED · w_NED + w_body`. Wind enters only the aerodynamics (air-relative `vt, α, β`,
//! Mach, q̄); gravity, kinematics and navigation use the inertial velocity. Wind gradients
//! (rotational turbulence) are not modelled. With zero wind the model is the textbook's exactly.
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
use crate::rigid_body::{self, BodyLoads, Kinematics, RigidBody, VelocityAngles, Wind};
use crate::{Dynamics, ModelError};
use nalgebra::{SVector, Vector3};
use table::Extrapolation;

/// Number of states.
pub const N_STATES: usize = 13;
/// Number of controls in [`F16Controls::to_vector`] order (throttle, elevator, aileron, rudder).
pub const N_CONTROLS: usize = 4;

/// State index: true airspeed, ft/s.
pub const VT: usize = rigid_body::VT;
/// State index: angle of attack, rad.
pub const ALPHA: usize = rigid_body::ALPHA;
/// State index: sideslip, rad.
pub const BETA: usize = rigid_body::BETA;
/// State index: roll angle φ, rad.
pub const PHI: usize = rigid_body::PHI;
/// State index: pitch angle θ, rad.
pub const THETA: usize = rigid_body::THETA;
/// State index: heading ψ, rad.
pub const PSI: usize = rigid_body::PSI;
/// State index: body roll rate p, rad/s.
pub const P: usize = rigid_body::P;
/// State index: body pitch rate q, rad/s.
pub const Q: usize = rigid_body::Q;
/// State index: body yaw rate r, rad/s.
pub const R: usize = rigid_body::R;
/// State index: north position, ft.
pub const NORTH: usize = rigid_body::NORTH;
/// State index: east position, ft.
pub const EAST: usize = rigid_body::EAST;
/// State index: altitude (up), ft.
pub const ALT: usize = rigid_body::ALT;
/// State index: engine power, percent.
pub const POW: usize = rigid_body::N_STATES;

/// State names with units, in state order (also CSV column names): the rigid body's
/// ([`rigid_body::STATE_NAMES`], taken from it so the two cannot differ), then `pow_pct`.
pub const STATE_NAMES: [&str; N_STATES] = {
    let mut names = [""; N_STATES];
    let mut i = 0;
    while i < rigid_body::N_STATES {
        names[i] = rigid_body::STATE_NAMES[i];
        i += 1;
    }
    names[POW] = "pow_pct";
    names
};
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
    /// The aerodynamic model the increments are added to: the textbook tables (default) or
    /// a linear model ([`F16::with_linear_aero`]).
    pub aerodynamics: Aerodynamics,
}

/// The aerodynamic model of an [`F16`] (increments are added to either).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Aerodynamics {
    /// The Stevens–Lewis tables, rate damping and cg transfer (SLJ App. A).
    #[default]
    Tables,
    /// Linear aerodynamics about a reference point, written as an increment matrix
    /// ([`AeroIncrements`]) added to zero: its bias column holds the coefficients `CL CD CY Cl
    /// Cm Cn` at the reference, its other columns their first-order derivatives (Klein &
    /// Morelli 2006 eq. 5.1–5.6). Body-axis moments about the actual cg; `CL`, `CD`
    /// stability-axis, rotated through the air-relative α as every increment is.
    Linear(Box<AeroIncrements>),
}

/// The cg range the model accepts, fraction of c̄: `[XCG_MIN, XCG_MAX]`. The Stevens & Lewis
/// data (and this repo's data file) state no cg range; they are used at 0.30–0.40 (trim tables
/// 0.30/0.35/0.38, check case 0.40) about the reference cg 0.35. The moment transfer
/// `CZ·(xcgr − xcg)` is exact for any cg, but far outside these values the aircraft is no
/// longer the F-16 the tables describe (e.g. trims at −0.5), so 0.1–0.5 is accepted.
pub const XCG_MIN: f64 = 0.1;
/// Upper end of the accepted cg range, fraction of c̄ (see [`XCG_MIN`]).
pub const XCG_MAX: f64 = 0.5;

impl F16 {
    /// The textbook aircraft (embedded data, no increments) with cg `xcg` (fraction of c̄).
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] if `xcg` is not finite or outside
    /// [`XCG_MIN`]–[`XCG_MAX`].
    pub fn new(xcg: f64) -> Result<Self, ModelError> {
        Self::with_data(F16Data::embedded(), xcg)
    }

    /// The model on other data (e.g. a variant table set parsed with [`F16Data::parse`]).
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] if `xcg` is not finite or outside
    /// [`XCG_MIN`]–[`XCG_MAX`].
    pub fn with_data(data: &'static F16Data, xcg: f64) -> Result<Self, ModelError> {
        if !xcg.is_finite() {
            return Err(ModelError::InvalidValue {
                field: "xcg",
                value: xcg,
                reason: "not finite",
            });
        }
        if !(XCG_MIN..=XCG_MAX).contains(&xcg) {
            return Err(ModelError::InvalidValue {
                field: "xcg",
                value: xcg,
                reason: "outside the accepted cg range 0.1–0.5 (fraction of cbar; the data are used at 0.30–0.40)",
            });
        }
        Ok(Self {
            data,
            xcg,
            increments: AeroIncrements::zero(),
            schedule: IncrementSchedule::Always,
            aerodynamics: Aerodynamics::Tables,
        })
    }

    /// The same aircraft with the linear aerodynamics `aero` in place of the tables (mass,
    /// engine, geometry and the scheduled increments unchanged; [`Aerodynamics::Linear`]).
    /// Built from the tables' values and local derivatives at a trim, the trim holds (the
    /// coefficients at the reference point are the tables' there).
    pub fn with_linear_aero(mut self, aero: AeroIncrements) -> Self {
        self.aerodynamics = Aerodynamics::Linear(Box::new(aero));
        self
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

    /// State derivatives and outputs together, with explicit increments: SLJ §3.5 subroutine F,
    /// split into the F-16's own parts (air data, engine, aerodynamic build-up, loads) and the
    /// shared flat-earth rigid body ([`crate::rigid_body`]).
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
        check_finite(x, u)?;
        let kin = Kinematics::new(&x.fixed_rows::<{ rigid_body::N_STATES }>(0).into_owned())?;
        let air = kin.air_relative(&Wind {
            ned_fps: u.wind_ned_fps.into(),
            body_fps: u.wind_body_fps.into(),
        })?;
        let ad = air_data(&self.data.atmosphere, air.vt_fps, x[ALT])?;
        let (thrust, pow_dot) = self.engine(x[POW], u.throttle, x[ALT], ad.mach);
        let coefficients = self.aero_coefficients(&air, [x[P], x[Q], x[R]], u, inc);
        let loads = self.forces_and_moments(&coefficients, ad.qbar_psf, thrust);
        let rb = self.rigid_body().derivatives(&kin, &loads)?;

        let mut xd = F16State::zeros();
        xd.fixed_rows_mut::<{ rigid_body::N_STATES }>(0).copy_from(&rb.xdot);
        xd[POW] = pow_dot;
        let out = F16Outputs {
            nx_g: rb.nx_g,
            ny_g: rb.ny_g,
            nz_g: rb.nz_g,
            qbar_psf: ad.qbar_psf,
            mach: ad.mach,
            vt_air_fps: air.vt_fps,
            alpha_air_rad: air.alpha_rad,
            beta_air_rad: air.beta_rad,
            thrust_lbf: thrust,
            coefficients,
        };
        Ok((xd, out))
    }

    /// The F-16 as a rigid body (SLJ §3.5): mass `1/RM`, the textbook's rounded moment
    /// constants c1…c9 (not recomputed from the inertias, so the check case of Table 3.5-2 is
    /// reproduced) and the model's g = 32.17 ft/s².
    pub fn rigid_body(&self) -> RigidBody {
        let m = &self.data.mass;
        RigidBody { mass_slug: m.mass_slug(), inertia: self.data.moment, g_fps2: m.g_ft_per_s2 }
    }

    /// Engine (SLJ §3.5 TGEAR, PDOT, THRUST): thrust (lbf) and power rate (percent/s) at power
    /// `pow` (percent), `throttle` (0–1), altitude `alt_ft` and `mach`.
    fn engine(&self, pow: f64, throttle: f64, alt_ft: f64, mach: f64) -> (f64, f64) {
        let d = self.data;
        let cpow = tgear(&d.engine, throttle);
        (thrust_lbf(d, pow, alt_ft, mach), pdot(&d.engine, pow, cpow))
    }

    /// Total coefficients at the cg (SLJ §3.5; data README §5): table build-up, rate damping and
    /// cg shift (or the linear model of [`Aerodynamics::Linear`]), then the increments `inc`, at the air-relative `air` and body rates
    /// `[p, q, r]` (rad/s).
    fn aero_coefficients(
        &self,
        air: &VelocityAngles,
        pqr: [f64; 3],
        u: &F16Controls,
        inc: &AeroIncrements,
    ) -> AeroCoefficients {
        let d = self.data;
        let x = IncrementInputs {
            vt_fps: air.vt_fps,
            alpha_rad: air.alpha_rad,
            beta_rad: air.beta_rad,
            p_rad_s: pqr[0],
            q_rad_s: pqr[1],
            r_rad_s: pqr[2],
            elevator_rad: u.elevator_rad,
            aileron_rad: u.aileron_rad,
            rudder_rad: u.rudder_rad,
        };
        let sc_alpha = air.alpha_rad.sin_cos();
        let mut c = match &self.aerodynamics {
            Aerodynamics::Tables => {
                // α is located once on the shared α axis of every table (checked at load).
                let a_deg = air.alpha_rad * d.rad_to_deg;
                let sa = table::segment(&d.cx.r, a_deg, Extrapolation::Linear);
                let mut c = self.static_coefficients(sa, air.beta_rad * d.rad_to_deg, u);
                self.add_damping_and_cg(&mut c, sa, air.vt_fps, pqr);
                c
            }
            Aerodynamics::Linear(lin) => {
                let mut c = AeroCoefficients::default();
                self.add_increments(&mut c, lin, &x, sc_alpha);
                c
            }
        };
        if !inc.is_zero() {
            self.add_increments(&mut c, inc, &x, sc_alpha);
        }
        let (s_alpha, c_alpha) = sc_alpha;
        c.CL = c.CX * s_alpha - c.CZ * c_alpha;
        c.CD = -c.CX * c_alpha - c.CZ * s_alpha;
        c
    }

    /// Adds the increments `inc` at the air-relative condition `x` to `c`; `(sin α, cos α)` of
    /// the air-relative α rotates ΔCL, ΔCD (stability axes) into body x, z.
    fn add_increments(
        &self,
        c: &mut AeroCoefficients,
        inc: &AeroIncrements,
        x: &IncrementInputs,
        (s_alpha, c_alpha): (f64, f64),
    ) {
        let g = &self.data.geometry;
        let dc = inc.deltas(x, g.span_ft, g.cbar_ft);
        let (dcl, dcd) = (dc[AeroCoefficient::CL as usize], dc[AeroCoefficient::CD as usize]);
        c.CX += dcl * s_alpha - dcd * c_alpha;
        c.CZ += -dcl * c_alpha - dcd * s_alpha;
        c.CY += dc[AeroCoefficient::CY as usize];
        c.Cl += dc[AeroCoefficient::Cl as usize];
        c.Cm += dc[AeroCoefficient::Cm as usize];
        c.Cn += dc[AeroCoefficient::Cn as usize];
    }

    /// Static and control coefficients from the tables (SLJ App. A: CX, CY, CZ, CL, DLDA, DLDR,
    /// CM, CN, DNDA, DNDR; degrees) at the located α segment `sa`, sideslip `b_deg` and the
    /// surfaces of `u`. CL and CD are left zero.
    fn static_coefficients(
        &self,
        sa: table::Segment,
        b_deg: f64,
        u: &F16Controls,
    ) -> AeroCoefficients {
        let d = self.data;
        let lin = Extrapolation::Linear;
        let el = u.elevator_rad.to_degrees();
        let ail = u.aileron_rad.to_degrees();
        let rdr = u.rudder_rad.to_degrees();
        let dail = ail / d.aileron_scale_deg;
        let drdr = rdr / d.rudder_scale_deg;
        let sign_b = if b_deg < 0.0 { -1.0 } else { 1.0 };
        let se = table::segment(&d.cx.c, el, lin);
        let sab = table::segment(&d.cl.c, b_deg.abs(), lin);
        let sb = table::segment(&d.dlda.c, b_deg, lin);
        let bs = b_deg / d.cz.beta_scale_deg;
        AeroCoefficients {
            CX: d.cx.at(sa, se),
            CY: d.cy.beta_coefficient_per_deg * b_deg
                + d.cy.aileron_coefficient * (ail / d.cy.aileron_scale_deg)
                + d.cy.rudder_coefficient * (rdr / d.cy.rudder_scale_deg),
            CZ: d.cz.table.at(sa) * (1.0 - bs * bs)
                + d.cz.elevator_coefficient * (el / d.cz.elevator_scale_deg),
            Cl: sign_b * d.cl.at(sa, sab) + d.dlda.at(sa, sb) * dail + d.dldr.at(sa, sb) * drdr,
            Cm: d.cm.at(sa, se),
            Cn: sign_b * d.cn.at(sa, sab) + d.dnda.at(sa, sb) * dail + d.dndr.at(sa, sb) * drdr,
            CL: 0.0,
            CD: 0.0,
        }
    }

    /// Adds the rate damping (SLJ App. A DAMP, at the located α segment `sa`; rates made
    /// dimensionless with the air-relative `vt_fps`) and the moment transfer from the tables'
    /// reference cg `xcgr` to `self.xcg`.
    fn add_damping_and_cg(
        &self,
        c: &mut AeroCoefficients,
        sa: table::Segment,
        vt_fps: f64,
        [p, q, r]: [f64; 3],
    ) {
        let d = self.data;
        let g = &d.geometry;
        let tvt = 0.5 / vt_fps;
        let b2v = g.span_ft * tvt;
        let cq = g.cbar_ft * q * tvt;
        let mut dmp = [0.0; 9];
        for (k, t) in d.damping.iter().enumerate() {
            dmp[k] = t.at(sa);
        }
        c.CX += cq * dmp[0];
        c.CY += b2v * (dmp[1] * r + dmp[2] * p);
        c.CZ += cq * dmp[3];
        c.Cl += b2v * (dmp[4] * r + dmp[5] * p);
        c.Cm += cq * dmp[6] + c.CZ * (g.xcgr - self.xcg);
        c.Cn +=
            b2v * (dmp[7] * r + dmp[8] * p) - c.CY * (g.xcgr - self.xcg) * g.cbar_ft / g.span_ft;
    }

    /// Body-axis loads at the cg from the coefficients `c`, dynamic pressure `qbar_psf` and
    /// `thrust_lbf` (SLJ §3.5: thrust along body +x through the cg; engine angular momentum
    /// `heng` along +x).
    fn forces_and_moments(
        &self,
        c: &AeroCoefficients,
        qbar_psf: f64,
        thrust_lbf: f64,
    ) -> BodyLoads {
        let g = &self.data.geometry;
        let qs = qbar_psf * g.wing_area_ft2;
        let qsb = qs * g.span_ft;
        BodyLoads {
            force_lbf: Vector3::new(qs * c.CX + thrust_lbf, qs * c.CY, qs * c.CZ),
            moment_ft_lbf: Vector3::new(qsb * c.Cl, qs * g.cbar_ft * c.Cm, qsb * c.Cn),
            heng_slug_ft2_per_s: self.data.mass.hx_slug_ft2_per_s,
        }
    }
}

/// Checks that every state and control (winds included) is finite; the error names the first
/// offending one.
fn check_finite(x: &F16State, u: &F16Controls) -> Result<(), ModelError> {
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
    for (k, v) in x.as_slice().iter().enumerate() {
        if !v.is_finite() {
            return Err(ModelError::InvalidValue {
                field: STATE_NAMES[k],
                value: *v,
                reason: "not finite",
            });
        }
    }
    for (k, v) in ctl.iter().enumerate() {
        if !v.is_finite() {
            return Err(ModelError::InvalidValue {
                field: CTL[k],
                value: *v,
                reason: "not finite",
            });
        }
    }
    Ok(())
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

    /// A cg outside 0.1–0.5 c̄ (e.g. −0.5, which trims, though the aircraft is then no longer
    /// the F-16 the tables describe) is an error naming xcg and the range; the ends and the
    /// textbook values are accepted.
    #[test]
    fn errors_xcg_outside_range_is_refused() {
        for bad in [-0.5, 0.0, 0.099, 0.501, 2.0, f64::NAN] {
            let e = F16::new(bad).unwrap_err().to_string();
            assert!(e.contains("xcg"), "{e}");
            if bad.is_finite() {
                assert!(e.contains("0.1–0.5"), "{e}");
            }
        }
        for ok in [XCG_MIN, 0.30, 0.35, 0.40, XCG_MAX] {
            assert_eq!(F16::new(ok).unwrap().xcg, ok);
        }
    }

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
    fn rigid_body_states_are_the_first_twelve() {
        assert_eq!(STATE_NAMES[..rigid_body::N_STATES], rigid_body::STATE_NAMES);
        assert_eq!((POW, N_STATES), (rigid_body::N_STATES, rigid_body::N_STATES + 1));
        let rb = F16::new(0.35).unwrap().rigid_body();
        assert_eq!(rb.mass_slug, 1.0 / 1.57e-3);
        assert_eq!((rb.inertia.c1, rb.inertia.c9, rb.g_fps2), (-0.770, 1.587e-5, 32.17));
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
