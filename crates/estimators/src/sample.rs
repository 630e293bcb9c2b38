//! The one air-data sample every aircraft estimator, log reader and the simulator share, the
//! aircraft constants it carries, and the measured non-dimensional coefficients it implies.
//!
//! Axes and signs (Stevens & Lewis, *Aircraft Control and Simulation*, 3rd ed., §1.4, §2.5):
//! body axes x forward, y right, z down; `p, q, r` body rates; `α`, `β` air-relative flow angles
//! at the CG; accelerometers give the **specific force** at the CG (non-gravitational force ÷
//! mass, so `az ≈ −g` in level flight); elevator, aileron and rudder in the convention of
//! Stevens & Lewis and Jategaonkar, a positive deflection giving a negative moment on a
//! conventional aircraft: δe > 0 trailing edge down (nose-down, Cm_de < 0), δa > 0 right aileron
//! trailing edge down (negative rolling moment, Cl_da < 0), δr > 0 trailing edge left
//! (nose-left, Cn_dr < 0). Products of inertia in the Stevens & Lewis convention: the inertia tensor is
//! `[[Jx, 0, −Jxz], [0, Jy, 0], [−Jxz, 0, Jz]]`, so `Ixz` here is `Jxz` (≈ +1060 slug·ft² for the
//! F-16; JSBSim logs the tensor element, i.e. `−Jxz`).
//!
//! Measured coefficients (Klein & Morelli, *Aircraft System Identification*, AIAA 2006, eqs.
//! 3.1–3.6 and §5.1, "equation-error data preparation"; Jategaonkar 2015 eq. 5.86–5.89 for the
//! thrust terms, thrust inclined by `σT` to body x):
//!
//! ```text
//! CX = (m ax − T cos σT) / (q̄ S)          CY = m ay / (q̄ S)          CZ = (m az + T sin σT) / (q̄ S)
//! CL = −CZ cos α + CX sin α               CD = −CX cos α − CZ sin α   (stability axes)
//! L  = Ixx ṗ − Ixz (ṙ + p q) + (Izz − Iyy) q r
//! M  = Iyy q̇ + (Ixx − Izz) p r + Ixz (p² − r²) − M_T,    M_T = measured, else l_T · T
//! N  = Izz ṙ − Ixz (ṗ − q r) + (Iyy − Ixx) p q
//! Cl = L / (q̄ S b)        Cm = M / (q̄ S c̄)        Cn = N / (q̄ S b)
//! ```
//!
//! (the moment equations are Stevens & Lewis eq. 2.5-24 solved for the applied moment, with
//! `Jxy = Jyz = 0`: the shared kernel's `roll_yaw_moments` and `pitch_moment`,
//! [`aeroident_physics::rigid_body`], without rotor momentum). A coefficient whose channels the sample lacks is `None`, never 0; the one
//! exception is the pitch coupling term `(Ixx − Izz) p r + Ixz (p² − r²)`, neglected when p, r
//! or the roll/yaw inertias are absent (a longitudinal record; symmetric flight assumed).

use aeroident_physics::rigid_body::{self as rb, Inertia};

/// Aircraft constants of one sample, SI. Optional values are `None` when the record does not
/// give them; anything that needs them is then unavailable (never computed with a made-up 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AircraftConstants {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Wing reference area, m².
    pub S_m2: f64,
    /// Mean aerodynamic chord, m (needed by `Cm` and by `q̂`, `α̇`-hat).
    pub cbar_m: Option<f64>,
    /// Wing span, m (needed by `Cl`, `Cn` and by `p̂`, `r̂`).
    pub b_m: Option<f64>,
    /// Roll moment of inertia `Jx`, kg·m².
    pub Ixx_kgm2: Option<f64>,
    /// Pitch moment of inertia `Jy`, kg·m².
    pub Iyy_kgm2: Option<f64>,
    /// Yaw moment of inertia `Jz`, kg·m².
    pub Izz_kgm2: Option<f64>,
    /// Product of inertia `Jxz` (Stevens & Lewis sign, see the module doc), kg·m².
    pub Ixz_kgm2: Option<f64>,
    /// Thrust pitching-moment arm, m: `M_T = arm · T`, positive nose-up (0 = thrust line
    /// through the CG).
    pub thrust_arm_m: f64,
    /// Thrust inclination to body x, rad, positive nose-up (0 = along body x).
    pub thrust_incidence_rad: f64,
    /// Reference speed of the `V/V0` terms, m/s.
    pub v0_mps: Option<f64>,
}

/// One air-data sample: every channel a six-axis identification uses, SI units, at the CG.
/// Channels a record lacks are `None`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AirDataSample {
    /// Time, s.
    pub t_s: f64,
    /// True airspeed `V`, m/s (> 0).
    pub vt_mps: f64,
    /// Angle of attack at the CG, rad.
    pub alpha_rad: f64,
    /// Dynamic pressure `q̄`, Pa (> 0): measured, or `½ρV²` formed by the reader.
    pub qbar_pa: f64,
    /// Sideslip at the CG, rad.
    pub beta_rad: Option<f64>,
    /// Body roll rate, rad/s.
    pub p_rad_s: Option<f64>,
    /// Body pitch rate, rad/s.
    pub q_rad_s: Option<f64>,
    /// Body yaw rate, rad/s.
    pub r_rad_s: Option<f64>,
    /// Roll acceleration, rad/s² (recorded or from a causal differentiator).
    pub pdot_rad_s2: Option<f64>,
    /// Pitch acceleration, rad/s².
    pub qdot_rad_s2: Option<f64>,
    /// Yaw acceleration, rad/s².
    pub rdot_rad_s2: Option<f64>,
    /// Angle-of-attack rate `α̇`, rad/s.
    pub alphadot_rad_s: Option<f64>,
    /// Bank angle, rad.
    pub phi_rad: Option<f64>,
    /// Pitch attitude, rad.
    pub theta_rad: Option<f64>,
    /// Heading, rad.
    pub psi_rad: Option<f64>,
    /// Body x specific force at the CG, m/s².
    pub ax_mps2: Option<f64>,
    /// Body y specific force at the CG, m/s².
    pub ay_mps2: Option<f64>,
    /// Body z specific force at the CG, m/s² (≈ −g level).
    pub az_mps2: Option<f64>,
    /// Elevator, rad (trailing edge down positive).
    pub de_rad: Option<f64>,
    /// Aileron, rad (positive: right aileron trailing edge down, a negative rolling moment).
    pub da_rad: Option<f64>,
    /// Rudder, rad (trailing edge left positive).
    pub dr_rad: Option<f64>,
    /// Total thrust, N.
    pub thrust_n: Option<f64>,
    /// Throttle, – (0–1), when logged.
    pub throttle: Option<f64>,
    /// Thrust pitching moment about the CG, N·m (positive nose-up), when logged.
    pub thrust_moment_nm: Option<f64>,
    /// Air density, kg/m³.
    pub rho_kgpm3: Option<f64>,
    /// Aircraft constants at this sample.
    pub constants: AircraftConstants,
}

/// Limits no aircraft sample can exceed (SI). They are sanity limits against corrupt records,
/// not tuning: anything beyond them is refused as implausible by every estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plausibility {
    /// Largest true airspeed, m/s (Mach ≈ 15 at sea level).
    pub vt_mps: f64,
    /// Smallest dynamic pressure, Pa (≈ 1.3 m/s at sea level: below it no coefficient is
    /// measurable).
    pub qbar_min_pa: f64,
    /// Largest dynamic pressure, Pa.
    pub qbar_max_pa: f64,
    /// Largest |α|, |β|, |φ|, |θ|, rad.
    pub angle_rad: f64,
    /// Largest |p|, |q|, |r|, |α̇|, rad/s.
    pub rate_rad_s: f64,
    /// Largest angular acceleration, rad/s².
    pub accel_rad_s2: f64,
    /// Largest |specific force|, m/s² (≈ 100 g).
    pub specific_force_mps2: f64,
    /// Largest |surface deflection|, rad (90°).
    pub surface_rad: f64,
    /// Largest |thrust|, N.
    pub thrust_n: f64,
    /// Largest air density, kg/m³.
    pub rho_kgpm3: f64,
    /// Largest mass, kg.
    pub mass_kg: f64,
    /// Largest reference length, m.
    pub length_m: f64,
    /// Largest moment of inertia, kg·m².
    pub inertia_kgm2: f64,
    /// Largest |measured coefficient| (aerodynamic coefficients are O(1)).
    pub coefficient: f64,
}

/// Expands macro `$callback` with the identifiers of [`AirDataSample`]'s optional channels
/// (`beta_rad` … `rho_kgpm3`, every `Option<f64>` field but the constants), in the struct's
/// order: the one list the code that must name each field (the C ABI's sample, Python's
/// keywords, [`AirDataSample::between`]) expands, so that a channel added to the sample is added
/// to each of them or fails to compile there.
#[macro_export]
macro_rules! optional_sample_fields {
    ($callback:ident) => {
        $callback! {
            beta_rad,
            p_rad_s,
            q_rad_s,
            r_rad_s,
            pdot_rad_s2,
            qdot_rad_s2,
            rdot_rad_s2,
            alphadot_rad_s,
            phi_rad,
            theta_rad,
            psi_rad,
            ax_mps2,
            ay_mps2,
            az_mps2,
            de_rad,
            da_rad,
            dr_rad,
            thrust_n,
            throttle,
            thrust_moment_nm,
            rho_kgpm3
        }
    };
}

/// The names of the per-sample measured fields [`AirDataSample::field`] reads, in the
/// sample's order.
pub const MEASURED_FIELDS: [&str; 24] = [
    "vt_mps",
    "alpha_rad",
    "qbar_pa",
    "beta_rad",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "pdot_rad_s2",
    "qdot_rad_s2",
    "rdot_rad_s2",
    "alphadot_rad_s",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "ax_mps2",
    "ay_mps2",
    "az_mps2",
    "de_rad",
    "da_rad",
    "dr_rad",
    "thrust_n",
    "throttle",
    "thrust_moment_nm",
    "rho_kgpm3",
];

/// The limits every estimator applies ([`AirDataSample::first_implausible`]).
pub const PLAUSIBILITY: Plausibility = Plausibility {
    vt_mps: 5000.0,
    qbar_min_pa: 1.0,
    qbar_max_pa: 1e7,
    angle_rad: 10.0,
    rate_rad_s: 50.0,
    accel_rad_s2: 1000.0,
    specific_force_mps2: 1000.0,
    surface_rad: core::f64::consts::FRAC_PI_2,
    thrust_n: 1e8,
    rho_kgpm3: 10.0,
    mass_kg: 1e7,
    length_m: 1000.0,
    inertia_kgm2: 1e12,
    coefficient: 1000.0,
};

/// The eight non-dimensional aerodynamic coefficients, in the order of
/// [`Coefficient::ALL`](crate::vocabulary::Coefficient::ALL): `CX CY CZ CL CD Cl Cm Cn`.
pub type CoefficientValues = [Option<f64>; 8];

impl AirDataSample {
    /// Thrust, N: the recorded one, else 0 (a record without a thrust channel is taken as a
    /// glider or as thrust-in-trim; the mappings state which).
    pub fn thrust_or_zero(&self) -> f64 {
        self.thrust_n.unwrap_or(0.0)
    }

    /// Air density, kg/m³: the recorded one, else `2 q̄ / V²`.
    pub fn rho(&self) -> f64 {
        self.rho_kgpm3.unwrap_or(2.0 * self.qbar_pa / (self.vt_mps * self.vt_mps))
    }

    /// The speed of sound, m/s, at the standard temperature of the density altitude of
    /// [`AirDataSample::rho`] ([`aeroident_physics::isa::temperature_of_density_k`]); `None`
    /// when that density is outside the standard atmosphere's −1 … 20 km.
    ///
    /// The sample has no static temperature: this is the standard day's. On a day `ΔT` off
    /// standard the speed of sound is off by about `−0.62 ΔT/T` (−3.2 % at ISA + 15 K), and a
    /// Mach number formed from it by `+0.62 ΔT/T`.
    pub fn speed_of_sound_mps(&self) -> Option<f64> {
        use aeroident_physics::isa;
        isa::temperature_of_density_k(self.rho()).map(isa::speed_of_sound_mps)
    }

    /// Mach number `V / a` with [`AirDataSample::speed_of_sound_mps`].
    pub fn mach(&self) -> Option<f64> {
        Some(self.vt_mps / self.speed_of_sound_mps()?)
    }

    /// The sample a fraction `w` (0–1) of the way from `a` to `b`, every channel linearly
    /// interpolated (a channel either lacks is absent; the heading the short way round, by its
    /// wrapped difference, and wrapped back into the neighbours' range: (−π, π], or [0, 2π)
    /// where both lie there), the constants `a`'s. For a transform that needs uniform sampling, a
    /// sample the record lacks or a screen removed is bridged so instead of leaving a gap:
    /// interpolation reconstructs missing or bad points (Klein & Morelli 2006, §11.3).
    pub fn between(a: &Self, b: &Self, w: f64) -> Self {
        let mix = |x: f64, y: f64| x + w * (y - x);
        let opt = |x: Option<f64>, y: Option<f64>| Some(mix(x?, y?));
        let heading = |x: Option<f64>, y: Option<f64>| {
            use core::f64::consts::{PI, TAU};
            let (x, y) = (x?, y?);
            let h = libm::remainder(x + w * libm::remainder(y - x, TAU), TAU);
            let from_zero = x > PI || y > PI;
            let below = if from_zero { h < 0.0 } else { h <= -PI };
            Some(if below { h + TAU } else { h })
        };
        macro_rules! interpolated {
            ($($f:ident),*) => {
                Self {
                    t_s: mix(a.t_s, b.t_s),
                    vt_mps: mix(a.vt_mps, b.vt_mps),
                    alpha_rad: mix(a.alpha_rad, b.alpha_rad),
                    qbar_pa: mix(a.qbar_pa, b.qbar_pa),
                    constants: a.constants,
                    $($f: opt(a.$f, b.$f),)*
                }
            };
        }
        let mut s = crate::optional_sample_fields!(interpolated);
        s.psi_rad = heading(a.psi_rad, b.psi_rad);
        s
    }

    /// The measured field named `field` (one of [`MEASURED_FIELDS`], the SI names the
    /// estimators use in their errors), `None` when the sample lacks it or the name is not one
    /// of them.
    pub fn field(&self, field: &str) -> Option<f64> {
        match field {
            "vt_mps" => Some(self.vt_mps),
            "alpha_rad" => Some(self.alpha_rad),
            "qbar_pa" => Some(self.qbar_pa),
            "beta_rad" => self.beta_rad,
            "p_rad_s" => self.p_rad_s,
            "q_rad_s" => self.q_rad_s,
            "r_rad_s" => self.r_rad_s,
            "pdot_rad_s2" => self.pdot_rad_s2,
            "qdot_rad_s2" => self.qdot_rad_s2,
            "rdot_rad_s2" => self.rdot_rad_s2,
            "alphadot_rad_s" => self.alphadot_rad_s,
            "phi_rad" => self.phi_rad,
            "theta_rad" => self.theta_rad,
            "psi_rad" => self.psi_rad,
            "ax_mps2" => self.ax_mps2,
            "ay_mps2" => self.ay_mps2,
            "az_mps2" => self.az_mps2,
            "de_rad" => self.de_rad,
            "da_rad" => self.da_rad,
            "dr_rad" => self.dr_rad,
            "thrust_n" => self.thrust_n,
            "throttle" => self.throttle,
            "thrust_moment_nm" => self.thrust_moment_nm,
            "rho_kgpm3" => self.rho_kgpm3,
            _ => None,
        }
    }

    /// Names of the fields that are not finite (`None` fields are not checked), for a clear
    /// refusal. Returns the first offending field and its value.
    pub fn first_non_finite(&self) -> Option<(&'static str, f64)> {
        let c = &self.constants;
        // Each estimator update runs this: a chain of tests, not a table built per sample
        // (the table of tuples was a tenth of an RLS update).
        macro_rules! first_non_finite {
            ($($name:literal: $v:expr),* $(,)?) => {$(
                if let Some(v) = $v {
                    if !f64::is_finite(v) {
                        return Some(($name, v));
                    }
                }
            )*};
        }
        first_non_finite!(
            "t_s": Some(self.t_s),
            "vt_mps": Some(self.vt_mps),
            "alpha_rad": Some(self.alpha_rad),
            "qbar_pa": Some(self.qbar_pa),
            "mass_kg": Some(c.mass_kg),
            "S_m2": Some(c.S_m2),
            "thrust_arm_m": Some(c.thrust_arm_m),
            "thrust_incidence_rad": Some(c.thrust_incidence_rad),
            "beta_rad": self.beta_rad,
            "p_rad_s": self.p_rad_s,
            "q_rad_s": self.q_rad_s,
            "r_rad_s": self.r_rad_s,
            "pdot_rad_s2": self.pdot_rad_s2,
            "qdot_rad_s2": self.qdot_rad_s2,
            "rdot_rad_s2": self.rdot_rad_s2,
            "alphadot_rad_s": self.alphadot_rad_s,
            "phi_rad": self.phi_rad,
            "theta_rad": self.theta_rad,
            "psi_rad": self.psi_rad,
            "ax_mps2": self.ax_mps2,
            "ay_mps2": self.ay_mps2,
            "az_mps2": self.az_mps2,
            "de_rad": self.de_rad,
            "da_rad": self.da_rad,
            "dr_rad": self.dr_rad,
            "thrust_n": self.thrust_n,
            "throttle": self.throttle,
            "thrust_moment_nm": self.thrust_moment_nm,
            "rho_kgpm3": self.rho_kgpm3,
            "cbar_m": c.cbar_m,
            "b_m": c.b_m,
            "Ixx_kgm2": c.Ixx_kgm2,
            "Iyy_kgm2": c.Iyy_kgm2,
            "Izz_kgm2": c.Izz_kgm2,
            "Ixz_kgm2": c.Ixz_kgm2,
            "v0_mps": c.v0_mps,
        );
        None
    }

    /// The first field outside the limits of [`PLAUSIBILITY`] (`None` fields are not
    /// checked): `(field, value, limit)`. Finite but impossible values come from corrupt
    /// records (a 1e308 in a column) and would otherwise overflow the estimators.
    pub fn first_implausible(&self) -> Option<(&'static str, f64, f64)> {
        let c = &self.constants;
        let l = &PLAUSIBILITY;
        // A chain of tests, as in `first_non_finite`.
        macro_rules! first_outside {
            ($($name:literal: $v:expr, $lo:expr, $hi:expr);* $(;)?) => {$(
                if let Some(v) = $v {
                    let (lo, hi): (f64, f64) = ($lo, $hi);
                    if !(v >= lo && v <= hi) {
                        return Some(($name, v, if v < lo { lo } else { hi }));
                    }
                }
            )*};
        }
        first_outside!(
            "vt_mps": Some(self.vt_mps), f64::MIN_POSITIVE, l.vt_mps;
            "qbar_pa": Some(self.qbar_pa), l.qbar_min_pa, l.qbar_max_pa;
            "alpha_rad": Some(self.alpha_rad), -l.angle_rad, l.angle_rad;
            "beta_rad": self.beta_rad, -l.angle_rad, l.angle_rad;
            "phi_rad": self.phi_rad, -l.angle_rad, l.angle_rad;
            "theta_rad": self.theta_rad, -l.angle_rad, l.angle_rad;
            "p_rad_s": self.p_rad_s, -l.rate_rad_s, l.rate_rad_s;
            "q_rad_s": self.q_rad_s, -l.rate_rad_s, l.rate_rad_s;
            "r_rad_s": self.r_rad_s, -l.rate_rad_s, l.rate_rad_s;
            "pdot_rad_s2": self.pdot_rad_s2, -l.accel_rad_s2, l.accel_rad_s2;
            "qdot_rad_s2": self.qdot_rad_s2, -l.accel_rad_s2, l.accel_rad_s2;
            "rdot_rad_s2": self.rdot_rad_s2, -l.accel_rad_s2, l.accel_rad_s2;
            "alphadot_rad_s": self.alphadot_rad_s, -l.rate_rad_s, l.rate_rad_s;
            "ax_mps2": self.ax_mps2, -l.specific_force_mps2, l.specific_force_mps2;
            "ay_mps2": self.ay_mps2, -l.specific_force_mps2, l.specific_force_mps2;
            "az_mps2": self.az_mps2, -l.specific_force_mps2, l.specific_force_mps2;
            "de_rad": self.de_rad, -l.surface_rad, l.surface_rad;
            "da_rad": self.da_rad, -l.surface_rad, l.surface_rad;
            "dr_rad": self.dr_rad, -l.surface_rad, l.surface_rad;
            "thrust_n": self.thrust_n, -l.thrust_n, l.thrust_n;
            "thrust_moment_nm": self.thrust_moment_nm, -l.thrust_n * 100.0, l.thrust_n * 100.0;
            "rho_kgpm3": self.rho_kgpm3, f64::MIN_POSITIVE, l.rho_kgpm3;
            "mass_kg": Some(c.mass_kg), f64::MIN_POSITIVE, l.mass_kg;
            "S_m2": Some(c.S_m2), f64::MIN_POSITIVE, l.length_m * l.length_m;
            "cbar_m": c.cbar_m, f64::MIN_POSITIVE, l.length_m;
            "b_m": c.b_m, f64::MIN_POSITIVE, l.length_m;
            "Ixx_kgm2": c.Ixx_kgm2, f64::MIN_POSITIVE, l.inertia_kgm2;
            "Iyy_kgm2": c.Iyy_kgm2, f64::MIN_POSITIVE, l.inertia_kgm2;
            "Izz_kgm2": c.Izz_kgm2, f64::MIN_POSITIVE, l.inertia_kgm2;
            "Ixz_kgm2": c.Ixz_kgm2, -l.inertia_kgm2, l.inertia_kgm2;
        );
        None
    }

    /// The measured coefficients `CX CY CZ CL CD Cl Cm Cn` of this sample (module doc), each
    /// `None` when a channel or constant it needs is absent or `q̄ S ≤ 0`.
    pub fn measured_coefficients(&self) -> CoefficientValues {
        let c = &self.constants;
        let qs = self.qbar_pa * c.S_m2;
        if !(qs > 0.0 && qs.is_finite()) {
            return [None; 8];
        }
        let t = self.thrust_or_zero();
        let (ss, cs) = (libm::sin(c.thrust_incidence_rad), libm::cos(c.thrust_incidence_rad));
        let m = c.mass_kg;
        let cx = self.ax_mps2.map(|ax| (m * ax - t * cs) / qs);
        let cy = self.ay_mps2.map(|ay| m * ay / qs);
        let cz = self.az_mps2.map(|az| (m * az + t * ss) / qs);
        let (sa, ca) = (libm::sin(self.alpha_rad), libm::cos(self.alpha_rad));
        let (cl, cd) = match (cx, cz) {
            (Some(x), Some(z)) => (Some(-z * ca + x * sa), Some(-x * ca - z * sa)),
            _ => (None, None),
        };
        let p = self.p_rad_s;
        let q = self.q_rad_s;
        let r = self.r_rad_s;
        // Pitch: the inertial coupling term needs p, r, Ixx, Izz and Ixz. A record without
        // any of them is a longitudinal record (e.g. the HFB-320, whose roll and yaw inertias
        // are not published): the term is neglected, symmetric flight assumed (Klein & Morelli
        // §5.1) — it is second order in the lateral rates.
        let cm = (|| {
            let qd = self.qdot_rad_s2?;
            let jy = c.Iyy_kgm2?;
            let cbar = c.cbar_m?;
            // Without the coupling, p = r = 0 makes the kernel's coupling term exactly 0.
            let (i, pv, rv) = match (p, r, c.Ixx_kgm2, c.Izz_kgm2, c.Ixz_kgm2) {
                (Some(pv), Some(rv), Some(jx), Some(jz), Some(jxz)) => {
                    (Inertia { jx, jy, jz, jxz }, pv, rv)
                }
                _ => (Inertia { jy, ..Inertia::default() }, 0.0, 0.0),
            };
            let m_t = self.thrust_moment_nm.unwrap_or(c.thrust_arm_m * t);
            Some((rb::pitch_moment(&i, pv, rv, qd, 0.0) - m_t) / (qs * cbar))
        })();
        let (cl_roll, cn) = (|| {
            let (jx, jy, jz, jxz) = (c.Ixx_kgm2?, c.Iyy_kgm2?, c.Izz_kgm2?, c.Ixz_kgm2?);
            let b = c.b_m?;
            let omega = [p?, q?, r?];
            let (pd, rd) = (self.pdot_rad_s2?, self.rdot_rad_s2?);
            let i = Inertia { jx, jy, jz, jxz };
            let [l, n] = rb::roll_yaw_moments(&i, omega, pd, rd, 0.0);
            Some((Some(l / (qs * b)), Some(n / (qs * b))))
        })()
        .unwrap_or((None, None));
        [cx, cy, cz, cl, cd, cl_roll, cm, cn]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level() -> AirDataSample {
        let g = 9.80665;
        let alpha: f64 = 0.05;
        AirDataSample {
            t_s: 0.0,
            vt_mps: 100.0,
            alpha_rad: alpha,
            qbar_pa: 4000.0,
            beta_rad: Some(0.0),
            p_rad_s: Some(0.0),
            q_rad_s: Some(0.0),
            r_rad_s: Some(0.0),
            pdot_rad_s2: Some(0.0),
            qdot_rad_s2: Some(0.0),
            rdot_rad_s2: Some(0.0),
            ax_mps2: Some(g * alpha.sin()),
            ay_mps2: Some(0.0),
            az_mps2: Some(-g * alpha.cos()),
            constants: AircraftConstants {
                mass_kg: 7000.0,
                S_m2: 30.0,
                cbar_m: Some(2.0),
                b_m: Some(15.0),
                Ixx_kgm2: Some(3e4),
                Iyy_kgm2: Some(1e5),
                Izz_kgm2: Some(1.2e5),
                Ixz_kgm2: Some(2e3),
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// A sample between two: each channel at the fraction asked (a quarter of the way from
    /// 100 to 104 m/s is 101), a channel one of them lacks absent, the heading across ±π by
    /// the short way round (from 3.1 to −3.1 rad is 0.083 rad through π, not 6.2 back
    /// through 0), the constants the first's.
    #[test]
    fn a_sample_between_two_interpolates_every_channel() {
        let a = AirDataSample { t_s: 1.0, psi_rad: Some(3.1), de_rad: Some(-0.02), ..level() };
        let b = AirDataSample {
            t_s: 1.04,
            vt_mps: 104.0,
            q_rad_s: Some(0.08),
            psi_rad: Some(-3.1),
            de_rad: None,
            constants: AircraftConstants { mass_kg: 1.0, ..level().constants },
            ..level()
        };
        let m = AirDataSample::between(&a, &b, 0.25);
        assert!((m.t_s - 1.01).abs() < 1e-12 && (m.vt_mps - 101.0).abs() < 1e-12);
        assert_eq!(m.q_rad_s, Some(0.02));
        assert_eq!(m.de_rad, None);
        let short_way = 2.0 * core::f64::consts::PI - 6.2;
        assert!((m.psi_rad.unwrap() - (3.1 + 0.25 * short_way)).abs() < 1e-12, "{m:?}");
        assert_eq!(m.constants, a.constants);
        assert_eq!(AirDataSample::between(&a, &b, 0.0).vt_mps, a.vt_mps);
        // Past π the heading comes back round: three quarters of the way is
        // 3.1 + 0.75 × 0.083 = 3.162 > π, which is 3.162 − 2π = −3.121 in (−π, π].
        let late = AirDataSample::between(&a, &b, 0.75).psi_rad.unwrap();
        assert!((late - (3.1 + 0.75 * short_way - 2.0 * core::f64::consts::PI)).abs() < 1e-12);
        // A log in [0, 2π) (6.2 to 0.1 rad) stays there: halfway is 6.2 + 0.0916 − 2π = 0.008.
        let (c, d) = (
            AirDataSample { psi_rad: Some(6.2), ..level() },
            AirDataSample { psi_rad: Some(0.1), ..level() },
        );
        let h = AirDataSample::between(&c, &d, 0.5).psi_rad.unwrap();
        let half = 0.5 * (0.1 + 2.0 * core::f64::consts::PI - 6.2);
        assert!((h - (6.2 + half - 2.0 * core::f64::consts::PI)).abs() < 1e-12 && h >= 0.0, "{h}");
    }

    /// Every name of `MEASURED_FIELDS` reads its own field: a sample whose measured fields hold
    /// 1, 2, … 24 in the struct's order gives them back in the list's order; unknown names
    /// and constants read nothing.
    #[test]
    fn measured_fields_read_by_name() {
        let s = AirDataSample {
            vt_mps: 1.0,
            alpha_rad: 2.0,
            qbar_pa: 3.0,
            beta_rad: Some(4.0),
            p_rad_s: Some(5.0),
            q_rad_s: Some(6.0),
            r_rad_s: Some(7.0),
            pdot_rad_s2: Some(8.0),
            qdot_rad_s2: Some(9.0),
            rdot_rad_s2: Some(10.0),
            alphadot_rad_s: Some(11.0),
            phi_rad: Some(12.0),
            theta_rad: Some(13.0),
            psi_rad: Some(14.0),
            ax_mps2: Some(15.0),
            ay_mps2: Some(16.0),
            az_mps2: Some(17.0),
            de_rad: Some(18.0),
            da_rad: Some(19.0),
            dr_rad: Some(20.0),
            thrust_n: Some(21.0),
            throttle: Some(22.0),
            thrust_moment_nm: Some(23.0),
            rho_kgpm3: Some(24.0),
            ..level()
        };
        for (i, name) in MEASURED_FIELDS.iter().enumerate() {
            assert_eq!(s.field(name), Some(i as f64 + 1.0), "{name}");
        }
        assert_eq!(s.field("mass_kg"), None);
        assert_eq!(s.field("t_s"), None);
        assert_eq!(level().field("psi_rad"), None);
    }

    /// Level, unaccelerated flight: lift balances weight, no drag without thrust, no moments.
    #[test]
    fn analytic_level_flight_balances() {
        let s = level();
        let c = s.measured_coefficients();
        let w_over_qs = 7000.0 * 9.80665 / (4000.0 * 30.0);
        assert!((c[3].unwrap() - w_over_qs).abs() < 1e-12, "CL");
        assert!(c[4].unwrap().abs() < 1e-12, "CD");
        for (i, v) in c.iter().enumerate().skip(5) {
            assert!(v.unwrap().abs() < 1e-15, "moment {i}");
        }
        assert!(c[1].unwrap().abs() < 1e-15);
    }

    /// Roll and yaw moments against an independent solve of S&L eq. 2.5-24: pick the applied
    /// moments, solve the 2×2 inertia block for ṗ, ṙ by Cramer's rule, and recover them.
    #[test]
    fn analytic_lateral_moments_invert_the_euler_equations() {
        let mut s = level();
        let (p, q, r) = (0.3, -0.1, 0.2);
        let (ixx, iyy, izz, ixz) = (3e4, 1e5, 1.2e5, 2e3);
        let (l_app, n_app) = (5.0e4, -2.0e4);
        // Jx ṗ − Jxz ṙ = L + Jxz p q − (Jz − Jy) q r;  Jz ṙ − Jxz ṗ = N − (Jy − Jx) p q − Jxz q r
        let rhs1 = l_app + ixz * p * q - (izz - iyy) * q * r;
        let rhs2 = n_app - (iyy - ixx) * p * q - ixz * q * r;
        let det = ixx * izz - ixz * ixz;
        let pd = (rhs1 * izz + ixz * rhs2) / det;
        let rd = (ixx * rhs2 + ixz * rhs1) / det;
        s.p_rad_s = Some(p);
        s.q_rad_s = Some(q);
        s.r_rad_s = Some(r);
        s.pdot_rad_s2 = Some(pd);
        s.rdot_rad_s2 = Some(rd);
        let c = s.measured_coefficients();
        let qsb = 4000.0 * 30.0 * 15.0;
        assert!((c[5].unwrap() - l_app / qsb).abs() < 1e-12, "Cl {}", c[5].unwrap());
        assert!((c[7].unwrap() - n_app / qsb).abs() < 1e-12, "Cn {}", c[7].unwrap());
        // Pitch: Jy q̇ = M + (Jz − Jx) p r − Jxz (p² − r²) with M = 0 → Cm = 0.
        s.qdot_rad_s2 = Some(((izz - ixx) * p * r - ixz * (p * p - r * r)) / iyy);
        assert!(s.measured_coefficients()[6].unwrap().abs() < 1e-15);
    }

    #[test]
    fn absent_channels_give_absent_coefficients() {
        let mut s = level();
        s.ay_mps2 = None;
        s.constants.b_m = None;
        let c = s.measured_coefficients();
        assert!(c[1].is_none() && c[5].is_none() && c[7].is_none());
        assert!(c[0].is_some() && c[6].is_some());
        // Rates without the roll/yaw inertias (a longitudinal record): coupling neglected.
        s.p_rad_s = Some(0.3);
        s.r_rad_s = Some(0.2);
        s.qdot_rad_s2 = Some(0.1);
        s.constants.Ixx_kgm2 = None;
        let cm = s.measured_coefficients()[6].unwrap();
        assert!((cm - 1e5 * 0.1 / (4000.0 * 30.0 * 2.0)).abs() < 1e-15, "{cm}");
        s.qbar_pa = 0.0;
        assert!(s.measured_coefficients().iter().all(Option::is_none));
    }
}
