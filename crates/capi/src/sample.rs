//! The sample a C caller feeds: [`AeroidentSample`], the estimators' `AirDataSample` as one flat
//! `#[repr(C)]` struct (SI units, radians), with a bit mask saying which optional channels and
//! constants are present, so that "not recorded" is never confused with a value.

use aeroident_estimators::{AirDataSample, AircraftConstants};

/// [`AeroidentSample::present`] bit: `beta_rad` is given.
pub const AEROIDENT_HAS_BETA: u32 = 1 << 0;
/// `p_rad_s` is given.
pub const AEROIDENT_HAS_P: u32 = 1 << 1;
/// `q_rad_s` is given.
pub const AEROIDENT_HAS_Q: u32 = 1 << 2;
/// `r_rad_s` is given.
pub const AEROIDENT_HAS_R: u32 = 1 << 3;
/// `pdot_rad_s2` is given.
pub const AEROIDENT_HAS_PDOT: u32 = 1 << 4;
/// `qdot_rad_s2` is given.
pub const AEROIDENT_HAS_QDOT: u32 = 1 << 5;
/// `rdot_rad_s2` is given.
pub const AEROIDENT_HAS_RDOT: u32 = 1 << 6;
/// `alphadot_rad_s` is given.
pub const AEROIDENT_HAS_ALPHADOT: u32 = 1 << 7;
/// `phi_rad` is given.
pub const AEROIDENT_HAS_PHI: u32 = 1 << 8;
/// `theta_rad` is given.
pub const AEROIDENT_HAS_THETA: u32 = 1 << 9;
/// `psi_rad` is given.
pub const AEROIDENT_HAS_PSI: u32 = 1 << 10;
/// `ax_mps2` is given.
pub const AEROIDENT_HAS_AX: u32 = 1 << 11;
/// `ay_mps2` is given.
pub const AEROIDENT_HAS_AY: u32 = 1 << 12;
/// `az_mps2` is given.
pub const AEROIDENT_HAS_AZ: u32 = 1 << 13;
/// `de_rad` is given.
pub const AEROIDENT_HAS_DE: u32 = 1 << 14;
/// `da_rad` is given.
pub const AEROIDENT_HAS_DA: u32 = 1 << 15;
/// `dr_rad` is given.
pub const AEROIDENT_HAS_DR: u32 = 1 << 16;
/// `thrust_n` is given.
pub const AEROIDENT_HAS_THRUST: u32 = 1 << 17;
/// `throttle` is given.
pub const AEROIDENT_HAS_THROTTLE: u32 = 1 << 18;
/// `thrust_moment_nm` is given.
pub const AEROIDENT_HAS_THRUST_MOMENT: u32 = 1 << 19;
/// `rho_kgpm3` is given.
pub const AEROIDENT_HAS_RHO: u32 = 1 << 20;
/// `cbar_m` is given.
pub const AEROIDENT_HAS_CBAR: u32 = 1 << 21;
/// `b_m` is given.
pub const AEROIDENT_HAS_B: u32 = 1 << 22;
/// `Ixx_kgm2` is given.
pub const AEROIDENT_HAS_IXX: u32 = 1 << 23;
/// `Iyy_kgm2` is given.
pub const AEROIDENT_HAS_IYY: u32 = 1 << 24;
/// `Izz_kgm2` is given.
pub const AEROIDENT_HAS_IZZ: u32 = 1 << 25;
/// `Ixz_kgm2` is given.
pub const AEROIDENT_HAS_IXZ: u32 = 1 << 26;
/// `v0_mps` is given.
pub const AEROIDENT_HAS_V0: u32 = 1 << 27;
/// Every defined [`AeroidentSample::present`] bit; a bit outside it is refused.
pub const AEROIDENT_HAS_ALL: u32 = (1 << 28) - 1;

/// One air-data sample, SI units and radians, at the CG, in the axes and sign conventions of
/// Stevens & Lewis and Jategaonkar (body x forward, z down; δe > 0 trailing edge down, δa > 0
/// right aileron trailing edge down, δr > 0 trailing edge left; accelerometers give the specific
/// force, `az ≈ −g` level). The fields are those of the estimators' `AirDataSample` with its
/// aircraft constants, flattened.
///
/// `t_s`, `vt_mps`, `alpha_rad`, `qbar_pa`, `mass_kg`, `S_m2`, `thrust_arm_m` and
/// `thrust_incidence_rad` are always read. Every other field is read only when its
/// `AEROIDENT_HAS_*` bit is set in `present`; an unset field is "not recorded" (an estimator
/// that needs it refuses the sample, naming it). A field whose bit is set must be finite: a
/// non-finite value is refused, never taken as absent. Zero-initialise the struct
/// (`AeroidentSample s = {0};`) and set the bits of the fields you fill.
///
/// This is the sample the estimator consumes, conditioned: the angular accelerations `ṗ q̇ ṙ`
/// the equation-error estimators (`rls`, `rls-iv`, `ftr`, the sliding-mode estimators) need
/// for the moment coefficients, and `α̇` where the model has an `alphadot` term, are the
/// caller's to supply (recorded, or from its own differentiator); so are `v0_mps` when the
/// model has `V` terms, and any screening of the raw channels. docs/c-abi.md says what
/// `aeroident replay` does there.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AeroidentSample {
    /// Time, s (strictly increasing from sample to sample).
    pub t_s: f64,
    /// True airspeed `V`, m/s (> 0).
    pub vt_mps: f64,
    /// Angle of attack at the CG, rad.
    pub alpha_rad: f64,
    /// Dynamic pressure `q̄`, Pa (> 0).
    pub qbar_pa: f64,
    /// Sideslip at the CG, rad ([`AEROIDENT_HAS_BETA`]).
    pub beta_rad: f64,
    /// Body roll rate, rad/s ([`AEROIDENT_HAS_P`]).
    pub p_rad_s: f64,
    /// Body pitch rate, rad/s ([`AEROIDENT_HAS_Q`]).
    pub q_rad_s: f64,
    /// Body yaw rate, rad/s ([`AEROIDENT_HAS_R`]).
    pub r_rad_s: f64,
    /// Roll acceleration, rad/s² ([`AEROIDENT_HAS_PDOT`]).
    pub pdot_rad_s2: f64,
    /// Pitch acceleration, rad/s² ([`AEROIDENT_HAS_QDOT`]).
    pub qdot_rad_s2: f64,
    /// Yaw acceleration, rad/s² ([`AEROIDENT_HAS_RDOT`]).
    pub rdot_rad_s2: f64,
    /// Angle-of-attack rate, rad/s ([`AEROIDENT_HAS_ALPHADOT`]).
    pub alphadot_rad_s: f64,
    /// Bank angle, rad ([`AEROIDENT_HAS_PHI`]).
    pub phi_rad: f64,
    /// Pitch attitude, rad ([`AEROIDENT_HAS_THETA`]).
    pub theta_rad: f64,
    /// Heading, rad ([`AEROIDENT_HAS_PSI`]).
    pub psi_rad: f64,
    /// Body x specific force at the CG, m/s² ([`AEROIDENT_HAS_AX`]).
    pub ax_mps2: f64,
    /// Body y specific force at the CG, m/s² ([`AEROIDENT_HAS_AY`]).
    pub ay_mps2: f64,
    /// Body z specific force at the CG, m/s², ≈ −g level ([`AEROIDENT_HAS_AZ`]).
    pub az_mps2: f64,
    /// Elevator, rad, trailing edge down positive ([`AEROIDENT_HAS_DE`]).
    pub de_rad: f64,
    /// Aileron, rad, right trailing edge down positive ([`AEROIDENT_HAS_DA`]).
    pub da_rad: f64,
    /// Rudder, rad, trailing edge left positive ([`AEROIDENT_HAS_DR`]).
    pub dr_rad: f64,
    /// Total thrust, N ([`AEROIDENT_HAS_THRUST`]); absent: taken as 0 (a glider, or thrust
    /// in trim).
    pub thrust_n: f64,
    /// Throttle, 0–1 ([`AEROIDENT_HAS_THROTTLE`]).
    pub throttle: f64,
    /// Thrust pitching moment about the CG, N·m, nose-up positive
    /// ([`AEROIDENT_HAS_THRUST_MOMENT`]).
    pub thrust_moment_nm: f64,
    /// Air density, kg/m³ ([`AEROIDENT_HAS_RHO`]); absent: `2 q̄ / V²`.
    pub rho_kgpm3: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Wing reference area, m².
    pub S_m2: f64,
    /// Mean aerodynamic chord, m ([`AEROIDENT_HAS_CBAR`]).
    pub cbar_m: f64,
    /// Wing span, m ([`AEROIDENT_HAS_B`]).
    pub b_m: f64,
    /// Roll moment of inertia `Jx`, kg·m² ([`AEROIDENT_HAS_IXX`]).
    pub Ixx_kgm2: f64,
    /// Pitch moment of inertia `Jy`, kg·m² ([`AEROIDENT_HAS_IYY`]).
    pub Iyy_kgm2: f64,
    /// Yaw moment of inertia `Jz`, kg·m² ([`AEROIDENT_HAS_IZZ`]).
    pub Izz_kgm2: f64,
    /// Product of inertia `Jxz`, Stevens & Lewis sign (tensor `[[Jx,0,−Jxz],[0,Jy,0],[−Jxz,0,Jz]]`),
    /// kg·m² ([`AEROIDENT_HAS_IXZ`]).
    pub Ixz_kgm2: f64,
    /// Thrust pitching-moment arm, m: `M_T = arm · T`, nose-up positive (0: through the CG).
    pub thrust_arm_m: f64,
    /// Thrust inclination to body x, rad, nose-up positive.
    pub thrust_incidence_rad: f64,
    /// Reference speed of the `V/V0` terms, m/s ([`AEROIDENT_HAS_V0`]).
    pub v0_mps: f64,
    /// Which optional fields are given: `AEROIDENT_HAS_*` bits, or-ed.
    pub present: u32,
}

/// `value` when `bit` is set in `present`.
fn opt(present: u32, bit: u32, value: f64) -> Option<f64> {
    (present & bit != 0).then_some(value)
}

/// `value`'s content and its bit in a mask (0 when absent).
fn put(value: Option<f64>, bit: u32) -> (f64, u32) {
    value.map_or((0.0, 0), |v| (v, bit))
}

impl AeroidentSample {
    /// The estimators' sample: each optional field `Some` exactly when its bit is set.
    ///
    /// # Errors
    /// The bits of `present` that are not defined ([`AEROIDENT_HAS_ALL`]).
    pub fn to_air_data(&self) -> Result<AirDataSample, u32> {
        let m = self.present;
        if m & !AEROIDENT_HAS_ALL != 0 {
            return Err(m & !AEROIDENT_HAS_ALL);
        }
        let constants = AircraftConstants {
            mass_kg: self.mass_kg,
            S_m2: self.S_m2,
            cbar_m: opt(m, AEROIDENT_HAS_CBAR, self.cbar_m),
            b_m: opt(m, AEROIDENT_HAS_B, self.b_m),
            Ixx_kgm2: opt(m, AEROIDENT_HAS_IXX, self.Ixx_kgm2),
            Iyy_kgm2: opt(m, AEROIDENT_HAS_IYY, self.Iyy_kgm2),
            Izz_kgm2: opt(m, AEROIDENT_HAS_IZZ, self.Izz_kgm2),
            Ixz_kgm2: opt(m, AEROIDENT_HAS_IXZ, self.Ixz_kgm2),
            thrust_arm_m: self.thrust_arm_m,
            thrust_incidence_rad: self.thrust_incidence_rad,
            v0_mps: opt(m, AEROIDENT_HAS_V0, self.v0_mps),
        };
        Ok(AirDataSample {
            t_s: self.t_s,
            vt_mps: self.vt_mps,
            alpha_rad: self.alpha_rad,
            qbar_pa: self.qbar_pa,
            beta_rad: opt(m, AEROIDENT_HAS_BETA, self.beta_rad),
            p_rad_s: opt(m, AEROIDENT_HAS_P, self.p_rad_s),
            q_rad_s: opt(m, AEROIDENT_HAS_Q, self.q_rad_s),
            r_rad_s: opt(m, AEROIDENT_HAS_R, self.r_rad_s),
            pdot_rad_s2: opt(m, AEROIDENT_HAS_PDOT, self.pdot_rad_s2),
            qdot_rad_s2: opt(m, AEROIDENT_HAS_QDOT, self.qdot_rad_s2),
            rdot_rad_s2: opt(m, AEROIDENT_HAS_RDOT, self.rdot_rad_s2),
            alphadot_rad_s: opt(m, AEROIDENT_HAS_ALPHADOT, self.alphadot_rad_s),
            phi_rad: opt(m, AEROIDENT_HAS_PHI, self.phi_rad),
            theta_rad: opt(m, AEROIDENT_HAS_THETA, self.theta_rad),
            psi_rad: opt(m, AEROIDENT_HAS_PSI, self.psi_rad),
            ax_mps2: opt(m, AEROIDENT_HAS_AX, self.ax_mps2),
            ay_mps2: opt(m, AEROIDENT_HAS_AY, self.ay_mps2),
            az_mps2: opt(m, AEROIDENT_HAS_AZ, self.az_mps2),
            de_rad: opt(m, AEROIDENT_HAS_DE, self.de_rad),
            da_rad: opt(m, AEROIDENT_HAS_DA, self.da_rad),
            dr_rad: opt(m, AEROIDENT_HAS_DR, self.dr_rad),
            thrust_n: opt(m, AEROIDENT_HAS_THRUST, self.thrust_n),
            throttle: opt(m, AEROIDENT_HAS_THROTTLE, self.throttle),
            thrust_moment_nm: opt(m, AEROIDENT_HAS_THRUST_MOMENT, self.thrust_moment_nm),
            rho_kgpm3: opt(m, AEROIDENT_HAS_RHO, self.rho_kgpm3),
            constants,
        })
    }

    /// The C sample of `s`: each `Some` field given with its bit set, each `None` zero with
    /// its bit clear ([`AeroidentSample::to_air_data`] gives `s` back exactly).
    pub fn from_air_data(s: &AirDataSample) -> Self {
        let c = &s.constants;
        let mut present = 0;
        let mut field = |v: Option<f64>, bit: u32| {
            let (v, b) = put(v, bit);
            present |= b;
            v
        };
        let mut out = Self {
            t_s: s.t_s,
            vt_mps: s.vt_mps,
            alpha_rad: s.alpha_rad,
            qbar_pa: s.qbar_pa,
            beta_rad: field(s.beta_rad, AEROIDENT_HAS_BETA),
            p_rad_s: field(s.p_rad_s, AEROIDENT_HAS_P),
            q_rad_s: field(s.q_rad_s, AEROIDENT_HAS_Q),
            r_rad_s: field(s.r_rad_s, AEROIDENT_HAS_R),
            pdot_rad_s2: field(s.pdot_rad_s2, AEROIDENT_HAS_PDOT),
            qdot_rad_s2: field(s.qdot_rad_s2, AEROIDENT_HAS_QDOT),
            rdot_rad_s2: field(s.rdot_rad_s2, AEROIDENT_HAS_RDOT),
            alphadot_rad_s: field(s.alphadot_rad_s, AEROIDENT_HAS_ALPHADOT),
            phi_rad: field(s.phi_rad, AEROIDENT_HAS_PHI),
            theta_rad: field(s.theta_rad, AEROIDENT_HAS_THETA),
            psi_rad: field(s.psi_rad, AEROIDENT_HAS_PSI),
            ax_mps2: field(s.ax_mps2, AEROIDENT_HAS_AX),
            ay_mps2: field(s.ay_mps2, AEROIDENT_HAS_AY),
            az_mps2: field(s.az_mps2, AEROIDENT_HAS_AZ),
            de_rad: field(s.de_rad, AEROIDENT_HAS_DE),
            da_rad: field(s.da_rad, AEROIDENT_HAS_DA),
            dr_rad: field(s.dr_rad, AEROIDENT_HAS_DR),
            thrust_n: field(s.thrust_n, AEROIDENT_HAS_THRUST),
            throttle: field(s.throttle, AEROIDENT_HAS_THROTTLE),
            thrust_moment_nm: field(s.thrust_moment_nm, AEROIDENT_HAS_THRUST_MOMENT),
            rho_kgpm3: field(s.rho_kgpm3, AEROIDENT_HAS_RHO),
            mass_kg: c.mass_kg,
            S_m2: c.S_m2,
            cbar_m: field(c.cbar_m, AEROIDENT_HAS_CBAR),
            b_m: field(c.b_m, AEROIDENT_HAS_B),
            Ixx_kgm2: field(c.Ixx_kgm2, AEROIDENT_HAS_IXX),
            Iyy_kgm2: field(c.Iyy_kgm2, AEROIDENT_HAS_IYY),
            Izz_kgm2: field(c.Izz_kgm2, AEROIDENT_HAS_IZZ),
            Ixz_kgm2: field(c.Ixz_kgm2, AEROIDENT_HAS_IXZ),
            thrust_arm_m: c.thrust_arm_m,
            thrust_incidence_rad: c.thrust_incidence_rad,
            v0_mps: field(c.v0_mps, AEROIDENT_HAS_V0),
            present: 0,
        };
        out.present = present;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every optional field has its own bit: setting one field of an all-`None` sample sets
    /// exactly one new bit, and the round trip gives the sample back.
    #[test]
    fn each_optional_field_round_trips_through_its_own_bit() {
        let base = AirDataSample {
            t_s: 1.5,
            vt_mps: 100.0,
            alpha_rad: 0.05,
            qbar_pa: 5000.0,
            constants: AircraftConstants { mass_kg: 1000.0, S_m2: 10.0, ..Default::default() },
            ..Default::default()
        };
        assert_eq!(AeroidentSample::from_air_data(&base).present, 0);
        let mut seen = 0u32;
        let mut check = |s: AirDataSample| {
            let c = AeroidentSample::from_air_data(&s);
            assert_eq!(c.present.count_ones(), 1, "{c:?}");
            assert_eq!(seen & c.present, 0, "bit {:#x} used twice", c.present);
            seen |= c.present;
            assert_eq!(c.to_air_data().unwrap(), s);
        };
        macro_rules! each {
            ($($f:ident),*) => {$( check(AirDataSample { $f: Some(0.25), ..base }); )*};
        }
        aeroident_estimators::optional_sample_fields!(each);
        macro_rules! each_constant {
            ($($f:ident),*) => {$(
                check(AirDataSample {
                    constants: AircraftConstants { $f: Some(0.25), ..base.constants },
                    ..base
                });
            )*};
        }
        each_constant!(cbar_m, b_m, Ixx_kgm2, Iyy_kgm2, Izz_kgm2, Ixz_kgm2, v0_mps);
        assert_eq!(seen, AEROIDENT_HAS_ALL);
        let bad = AeroidentSample { present: 1 << 30, ..Default::default() };
        assert_eq!(bad.to_air_data(), Err(1 << 30));
    }
}
