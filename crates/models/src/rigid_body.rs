//! Flat-earth six-degree-of-freedom rigid-body equations, independent of any aircraft
//! (JSBSim style: aerodynamics, propulsion and atmosphere live in the aircraft model, which hands
//! this module a total force and moment).
//!
//! Source: Stevens, Lewis & Johnson, *Aircraft Control and Simulation*, 3rd ed., Wiley 2015 (SLJ):
//! the Euler-angle direction-cosine matrix of §1.3, the flat-earth body-axes 6-DOF equations of
//! §2.5 (force, kinematic, moment and navigation equations; moment equations with the inertia
//! constants `c1 … c9`), and their mechanisation in the F-16 subroutine `F` of §3.5, which this
//! module follows operation for operation (force equations in wind axes `V̇t, α̇, β̇`).
//! The equations themselves are the shared kernel's ([`aeroident_physics::rigid_body`], the
//! same functions the estimators evaluate); this module adds the 12-state layout, validation,
//! the rotation matrix, the wind and the navigation equations.
//! Validated through the F-16 check case, SLJ Table 3.5-2
//! (`f16::tests::val_slj_table_3_5_2_state_derivatives`), and by this module's tests.
//!
//! # Assumptions
//! Flat, non-rotating earth (NED is inertial), constant gravity along +down, constant mass and
//! inertia, a body x–z plane of symmetry (`Jxy = Jyz = 0`), and an optional rotor (engine)
//! angular momentum `heng` along body +x.
//!
//! # States (index, name, unit) — [`STATE_NAMES`]
//! `0 vt_fps, 1 alpha_rad, 2 beta_rad, 3 phi_rad, 4 theta_rad, 5 psi_rad, 6 p_rad_s, 7 q_rad_s,
//! 8 r_rad_s, 9 north_ft, 10 east_ft, 11 alt_ft (up)`. `vt, alpha, beta` describe the
//! **ground-relative (inertial)** velocity of the cg in body axes (it is the velocity Newton's
//! law acts on); the air-relative velocity the aerodynamics need comes from
//! [`Kinematics::air_relative`]. With zero wind the two coincide.
//!
//! # Axes and signs
//! Body axes x forward, y right, z down; NED north, east, down; altitude up (`ḣ = −ż_NED`).
//! Euler angles 3-2-1 (ψ, θ, φ). Moments L, M, N positive right-handed about body x, y, z.
//! `Jxz` positive as in SLJ: the inertia tensor is `[[Jx, 0, −Jxz], [0, Jy, 0], [−Jxz, 0, Jz]]`.
//! English units (ft, s, slug, lbf, rad) throughout; any consistent units work.
//!
//! # Wind convention (the only one in the crate)
//! The wind is the velocity of the **air mass relative to the ground**, given in NED
//! ([`Wind::ned_fps`]; e.g. `[−20, 0, 0]` is air moving south, a headwind for an aircraft
//! flying north) plus an optional body-axis part ([`Wind::body_fps`], for gusts defined along
//! the body axes). In body axes the wind is `w_b = C·w_NED + w_body` with `C` =
//! [`body_from_ned`], and the **air-relative velocity is ground velocity minus wind**:
//! `v_air = v_ground − w_b`. A headwind therefore raises the airspeed, a tailwind lowers it, an
//! updraft (`w_NED,down < 0`) raises α. Wind enters the aerodynamics only; gravity, kinematics
//! and navigation use the ground velocity. Wind gradients (rotational turbulence) are not
//! modelled.
//!
//! # Use
//! 1. [`Kinematics::new`] once per evaluation (validates the state, builds the rotation matrix
//!    and the body velocity);
//! 2. [`Kinematics::air_relative`] for the aerodynamics;
//! 3. the aircraft's own force and moment build-up into [`BodyLoads`];
//! 4. [`RigidBody::derivatives`] for the 12 state derivatives and the accelerometer outputs.
//!
//! [`STATE_NAMES`]: crate::rigid_body::STATE_NAMES
//! [`Kinematics::air_relative`]: crate::rigid_body::Kinematics::air_relative
//! [`Kinematics::new`]: crate::rigid_body::Kinematics::new
//! [`Wind::ned_fps`]: crate::rigid_body::Wind::ned_fps
//! [`Wind::body_fps`]: crate::rigid_body::Wind::body_fps
//! [`body_from_ned`]: crate::rigid_body::body_from_ned
//! [`BodyLoads`]: crate::rigid_body::BodyLoads
//! [`RigidBody::derivatives`]: crate::rigid_body::RigidBody::derivatives

use crate::ModelError;
use aeroident_physics::rigid_body::{self as kernel, SinCos};
use nalgebra::{Matrix3, SVector, Vector3};

pub use aeroident_physics::rigid_body::{InertiaConstants, InertiaError};

/// Number of rigid-body states.
pub const N_STATES: usize = 12;

/// State index: ground-relative speed Vt, ft/s.
pub const VT: usize = 0;
/// State index: angle of attack of the ground-relative velocity, rad.
pub const ALPHA: usize = 1;
/// State index: sideslip of the ground-relative velocity, rad.
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

/// State names with units, in state order (the F-16's first 12 are these).
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
];

/// The rigid-body state vector, in the order of [`STATE_NAMES`] (also used for its derivative).
pub type RigidBodyState = SVector<f64, N_STATES>;

/// The direction-cosine matrix `C_body←NED` of the 3-2-1 Euler angles φ, θ, ψ (rad), SLJ 3rd ed.
/// §1.3: `v_body = C · v_NED`, `v_NED = Cᵀ · v_body`. Rows are the body x, y, z axes in NED:
///
/// ```text
/// [ cθcψ            cθsψ            −sθ  ]
/// [ sφsθcψ − cφsψ   sφsθsψ + cφcψ   sφcθ ]
/// [ cφsθcψ + sφsψ   cφsθsψ − sφcψ   cφcθ ]
/// ```
///
/// The crate's only rotation matrix: gravity (`C·[0, 0, g]`), navigation (`Cᵀ·v_body`) and the
/// NED wind (`C·w_NED`) all use it.
#[inline]
pub fn body_from_ned(phi_rad: f64, theta_rad: f64, psi_rad: f64) -> Matrix3<f64> {
    dcm_from_sin_cos(phi_rad.sin_cos(), theta_rad.sin_cos(), psi_rad.sin_cos())
}

/// [`body_from_ned`] from the `(sin, cos)` pairs of φ, θ, ψ (lets [`Kinematics::new`] reuse its
/// sines and cosines; the formula exists only here).
#[inline]
fn dcm_from_sin_cos(
    (sph, cph): (f64, f64),
    (sth, cth): (f64, f64),
    (spsi, cpsi): (f64, f64),
) -> Matrix3<f64> {
    // Products grouped as in SLJ's subroutine F (§3.5), so the F-16 reproduces it bit for bit.
    let (t1, t2, t3) = (sph * cpsi, cph * sth, sph * spsi);
    Matrix3::new(
        cth * cpsi,
        cth * spsi,
        -sth,
        t1 * sth - cph * spsi,
        t3 * sth + cph * cpsi,
        sph * cth,
        t2 * cpsi + t3,
        t2 * spsi - t1,
        cph * cth,
    )
}

/// `C · v` for `C` = [`body_from_ned`] (NED vector `v` into body axes), summed left to right.
#[inline]
fn rotate_to_body(c: &Matrix3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::from_fn(|i, _| c[(i, 0)] * v[0] + c[(i, 1)] * v[1] + c[(i, 2)] * v[2])
}

/// `Cᵀ · v` for `C` = [`body_from_ned`] (body vector `v` into NED), summed left to right.
#[inline]
fn rotate_to_ned(c: &Matrix3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::from_fn(|i, _| v[0] * c[(0, i)] + v[1] * c[(1, i)] + v[2] * c[(2, i)])
}

/// A velocity as speed and aerodynamic angles: `Vt` (ft/s), α (rad) and β (rad) (SLJ 3rd ed.
/// §2.3, wind-axes definition of α and β; §3.5 subroutine F).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VelocityAngles {
    /// Speed `Vt = |v|`, ft/s.
    pub vt_fps: f64,
    /// Angle of attack `α = atan2(w, u)`, rad.
    pub alpha_rad: f64,
    /// Sideslip `β = asin(v / Vt)`, rad.
    pub beta_rad: f64,
}

impl VelocityAngles {
    /// Body-axis components `(u, v, w)`, ft/s: `u = Vt cosα cosβ`, `v = Vt sinβ`,
    /// `w = Vt sinα cosβ` (SLJ 3rd ed. §2.3).
    #[inline]
    pub fn to_body(self) -> Vector3<f64> {
        self.to_body_and_cos_beta().0
    }

    /// [`Self::to_body`] and `cos β` (reused by the β̇ equation).
    #[inline]
    fn to_body_and_cos_beta(self) -> (Vector3<f64>, f64) {
        let beta = sin_cos(self.beta_rad);
        let v = kernel::body_velocity(self.vt_fps, sin_cos(self.alpha_rad), beta);
        (v.into(), beta.cos)
    }

    /// The inverse of [`Self::to_body`] for body components `(u, v, w)` (ft/s): `Vt = |v|`,
    /// `α = atan2(w, u)` ∈ (−π, π], `β = asin(v / Vt)` ∈ [−π/2, π/2]. For a zero vector `Vt = 0`
    /// and β is NaN: callers that need angles check `Vt > 0`.
    #[inline]
    pub fn from_body(v: &Vector3<f64>) -> Self {
        let vt = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        Self {
            vt_fps: vt,
            alpha_rad: v[2].atan2(v[0]),
            beta_rad: (v[1] / vt).clamp(-1.0, 1.0).asin(),
        }
    }
}

/// The wind: velocity of the air mass relative to the ground, ft/s (module doc, "Wind
/// convention"). The body-axis wind is `C·ned_fps + body_fps`; the air-relative velocity is the
/// ground velocity minus it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wind {
    /// Wind in NED, ft/s (air moving towards north / east / down; `[−20, 0, 0]` is a 20 ft/s
    /// wind from the north, `down < 0` an updraft).
    pub ned_fps: Vector3<f64>,
    /// Additional wind along the body axes, ft/s (x forward: a positive value is a tailwind;
    /// z down: a downdraft).
    pub body_fps: Vector3<f64>,
}

impl Wind {
    /// Still air.
    pub fn still() -> Self {
        Self::default()
    }

    /// True when both parts are exactly zero.
    pub fn is_still(&self) -> bool {
        self.ned_fps == Vector3::zeros() && self.body_fps == Vector3::zeros()
    }
}

/// `(sin, cos)` of an angle as the kernel takes it, through `std` (the simulator's trigonometry,
/// which the F-16's check case was reproduced with).
#[inline]
fn sin_cos(angle_rad: f64) -> SinCos<f64> {
    let (sin, cos) = angle_rad.sin_cos();
    SinCos { sin, cos }
}

/// Mass properties and gravity of a rigid body on a flat earth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBody {
    /// Mass, slug (> 0).
    pub mass_slug: f64,
    /// Inertia constants of the moment equations.
    pub inertia: InertiaConstants,
    /// Gravitational acceleration, ft/s², along NED +down.
    pub g_fps2: f64,
}

/// External loads at the cg in body axes, all except gravity (which [`RigidBody`] adds).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyLoads {
    /// Total force (aerodynamic + thrust) along body x, y, z, lbf.
    pub force_lbf: Vector3<f64>,
    /// Total moment about the cg: rolling L, pitching M, yawing N, ft·lbf.
    pub moment_ft_lbf: Vector3<f64>,
    /// Angular momentum of spinning rotors (engine) along body +x, slug·ft²/s (SLJ `heng`; its
    /// gyroscopic moment `−ω × h` is added by [`RigidBody::derivatives`]).
    pub heng_slug_ft2_per_s: f64,
}

/// What [`RigidBody::derivatives`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBodyRates {
    /// Time derivative of each state of [`STATE_NAMES`] (units of the state per second).
    pub xdot: RigidBodyState,
    /// Accelerometer at the cg, body +x: `F_x/(m g)`, g (specific force without gravity).
    pub nx_g: f64,
    /// Accelerometer at the cg, body +y: `F_y/(m g)`, g.
    pub ny_g: f64,
    /// Accelerometer at the cg, body **−z** (positive up, the pilot's "g"): `−F_z/(m g)`, g;
    /// 1 in steady level flight, 0 in free fall.
    pub nz_g: f64,
}

/// One rigid-body state, validated, with its rotation matrix and ground velocity in body axes:
/// computed once per evaluation and shared by the wind, the aircraft's loads and
/// [`RigidBody::derivatives`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    x: RigidBodyState,
    dcm: Matrix3<f64>,
    v_body: Vector3<f64>,
    cos_beta: f64,
    phi: SinCos<f64>,
    theta: SinCos<f64>,
}

impl Kinematics {
    /// Validates `x` and evaluates the quantities every equation shares.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (field = the state's name) when a state is not finite,
    /// `vt_fps` ≤ 0, or cos θ = 0 (Euler-angle singularity at |θ| = 90°).
    #[inline]
    pub fn new(x: &RigidBodyState) -> Result<Self, ModelError> {
        for (k, v) in x.as_slice().iter().enumerate() {
            if !v.is_finite() {
                return Err(ModelError::InvalidValue {
                    field: STATE_NAMES[k],
                    value: *v,
                    reason: "not finite",
                });
            }
        }
        if x[VT] <= 0.0 {
            return Err(ModelError::InvalidValue {
                field: STATE_NAMES[VT],
                value: x[VT],
                reason: "must be > 0",
            });
        }
        let theta = sin_cos(x[THETA]);
        if theta.cos == 0.0 {
            return Err(ModelError::InvalidValue {
                field: STATE_NAMES[THETA],
                value: x[THETA],
                reason: "Euler-angle singularity at |theta| = 90 deg",
            });
        }
        let phi = sin_cos(x[PHI]);
        let dcm = dcm_from_sin_cos((phi.sin, phi.cos), (theta.sin, theta.cos), x[PSI].sin_cos());
        let (v_body, cos_beta) =
            VelocityAngles { vt_fps: x[VT], alpha_rad: x[ALPHA], beta_rad: x[BETA] }
                .to_body_and_cos_beta();
        Ok(Self { x: *x, dcm, v_body, cos_beta, phi, theta })
    }

    /// The state.
    pub fn state(&self) -> &RigidBodyState {
        &self.x
    }

    /// `C_body←NED` at the state's attitude ([`body_from_ned`]).
    pub fn body_from_ned(&self) -> &Matrix3<f64> {
        &self.dcm
    }

    /// Ground-relative velocity of the cg in body axes `(u, v, w)`, ft/s.
    pub fn velocity_body_fps(&self) -> &Vector3<f64> {
        &self.v_body
    }

    /// The air-relative speed and angles for `wind` (module doc, "Wind convention"):
    /// `v_air = v_ground − (C·w_NED + w_body)`. In still air the state's own `vt, α, β` are
    /// returned unchanged.
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (`vt_air_fps`) when the air-relative speed is not finite
    /// (e.g. a wind component is not) or not positive (α, β undefined).
    #[inline]
    pub fn air_relative(&self, wind: &Wind) -> Result<VelocityAngles, ModelError> {
        if wind.is_still() {
            return Ok(VelocityAngles {
                vt_fps: self.x[VT],
                alpha_rad: self.x[ALPHA],
                beta_rad: self.x[BETA],
            });
        }
        let air = VelocityAngles::from_body(
            &(self.v_body - rotate_to_body(&self.dcm, &wind.ned_fps) - wind.body_fps),
        );
        if !(air.vt_fps > 0.0 && air.vt_fps.is_finite()) {
            return Err(ModelError::InvalidValue {
                field: "vt_air_fps",
                value: air.vt_fps,
                reason: "air-relative speed must be > 0",
            });
        }
        Ok(air)
    }
}

impl RigidBody {
    /// A rigid body of mass `mass_slug` (slug), inertia `jx, jy, jz, jxz` (slug·ft², SLJ sign
    /// convention) under gravity `g_fps2` (ft/s²); constants by [`InertiaConstants::from_inertia`].
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] for a mass or g that is not finite and positive, or inertia
    /// rejected by [`InertiaConstants::from_inertia`].
    pub fn new(
        mass_slug: f64,
        jx: f64,
        jy: f64,
        jz: f64,
        jxz: f64,
        g_fps2: f64,
    ) -> Result<Self, ModelError> {
        for (field, value) in [("mass_slug", mass_slug), ("g_fps2", g_fps2)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ModelError::InvalidValue {
                    field,
                    value,
                    reason: "must be finite and > 0",
                });
            }
        }
        Ok(Self { mass_slug, inertia: InertiaConstants::from_inertia(jx, jy, jz, jxz)?, g_fps2 })
    }

    /// The flat-earth 6-DOF state derivatives at `k` under `loads` (SLJ 3rd ed. §2.5; the
    /// mechanisation of subroutine `F`, §3.5), with `a = F/m`, `g_b = C·[0, 0, g]`; every group
    /// but the navigation is a function of the shared kernel ([`aeroident_physics::rigid_body`]:
    /// `gravity_body`, `body_acceleration`, `wind_axes_rates`, `euler_rates`,
    /// `angular_acceleration`), which keeps subroutine F's operation order:
    ///
    /// ```text
    /// force:      u̇ = rv − qw + g_b,x + a_x
    ///             v̇ = pw − ru + g_b,y + a_y
    ///             ẇ = qu − pv + g_b,z + a_z
    /// wind axes:  V̇t = (u u̇ + v v̇ + w ẇ)/Vt
    ///             α̇ = (u ẇ − w u̇)/(u² + w²)
    ///             β̇ = (Vt v̇ − v V̇t) cosβ/(u² + w²)
    /// kinematic:  φ̇ = p + tanθ (q sinφ + r cosφ)
    ///             θ̇ = q cosφ − r sinφ
    ///             ψ̇ = (q sinφ + r cosφ)/cosθ
    /// moment:     ṗ = (c2 p + c1 r + c4 heng) q + c3 L + c4 N
    ///             q̇ = (c5 p − c7 heng) r + c6 (r² − p²) + c7 M
    ///             ṙ = (c8 p − c2 r + c9 heng) q + c4 L + c9 N
    /// navigation: [ṅ, ė, −ḣ] = Cᵀ·[u, v, w]
    /// ```
    ///
    /// # Errors
    /// [`ModelError::InvalidValue`] (`beta_rad`) when `u² + w² = 0` (|β| = 90°: α undefined).
    #[inline]
    pub fn derivatives(
        &self,
        k: &Kinematics,
        loads: &BodyLoads,
    ) -> Result<RigidBodyRates, ModelError> {
        let x = &k.x;
        let (vt, beta) = (x[VT], x[BETA]);
        let omega = [x[P], x[Q], x[R]];
        let v_body: [f64; 3] = k.v_body.into();
        let [u, _, w] = v_body;

        // Force equations: specific force a = F/m and gravity in body axes.
        let a = loads.force_lbf * (1.0 / self.mass_slug);
        let gb = kernel::gravity_body(self.g_fps2, k.phi, k.theta);
        let v_dot = kernel::body_acceleration(v_body, omega, gb, a.into());
        if u * u + w * w <= 0.0 {
            return Err(ModelError::InvalidValue {
                field: STATE_NAMES[BETA],
                value: beta,
                reason: "|beta| = 90 deg: alpha undefined",
            });
        }

        let mut xd = RigidBodyState::zeros();
        [xd[VT], xd[ALPHA], xd[BETA]] = kernel::wind_axes_rates(v_body, v_dot, vt, k.cos_beta);
        [xd[PHI], xd[THETA], xd[PSI]] = kernel::euler_rates(omega, k.phi, k.theta);
        let moment = loads.moment_ft_lbf.into();
        let h = loads.heng_slug_ft2_per_s;
        [xd[P], xd[Q], xd[R]] = kernel::angular_acceleration(&self.inertia, omega, moment, h);

        // Navigation equations.
        let ned = rotate_to_ned(&k.dcm, &k.v_body);
        xd[NORTH] = ned[0];
        xd[EAST] = ned[1];
        xd[ALT] = -ned[2];

        let g = self.g_fps2;
        Ok(RigidBodyRates { xdot: xd, nx_g: a[0] / g, ny_g: a[1] / g, nz_g: -a[2] / g })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_6};

    fn state(vt: f64, alpha: f64, beta: f64, att: [f64; 3], pqr: [f64; 3]) -> RigidBodyState {
        let mut x = RigidBodyState::zeros();
        x[VT] = vt;
        x[ALPHA] = alpha;
        x[BETA] = beta;
        x[PHI] = att[0];
        x[THETA] = att[1];
        x[PSI] = att[2];
        x[P] = pqr[0];
        x[Q] = pqr[1];
        x[R] = pqr[2];
        x[ALT] = 1000.0;
        x
    }

    fn body(jxz: f64) -> RigidBody {
        RigidBody::new(500.0, 10_000.0, 50_000.0, 60_000.0, jxz, 32.17).unwrap()
    }

    fn rates(b: &RigidBody, x: &RigidBodyState, loads: &BodyLoads) -> RigidBodyRates {
        b.derivatives(&Kinematics::new(x).unwrap(), loads).unwrap()
    }

    /// Body-axis acceleration (u̇, v̇, ẇ) from (Vt, α, β) and their rates, by differentiating
    /// u = Vt cosα cosβ, v = Vt sinβ, w = Vt sinα cosβ (independent of the wind-axes inversion).
    fn body_acceleration(x: &RigidBodyState, xd: &RigidBodyState) -> Vector3<f64> {
        let (vt, a, b) = (x[VT], x[ALPHA], x[BETA]);
        let (vtd, ad, bd) = (xd[VT], xd[ALPHA], xd[BETA]);
        let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
        Vector3::new(
            vtd * ca * cb - vt * sa * cb * ad - vt * ca * sb * bd,
            vtd * sb + vt * cb * bd,
            vtd * sa * cb + vt * ca * cb * ad - vt * sa * sb * bd,
        )
    }

    #[test]
    fn analytic_free_fall_accelerates_down_at_g_without_rotation() {
        let b = body(1500.0);
        for (alpha, beta, att) in [
            (0.0, 0.0, [0.0, 0.0, 0.0]),
            (0.1, 0.05, [0.3, 0.2, 1.0]),
            (-0.4, -0.3, [-2.0, -1.1, 2.5]),
        ] {
            let x = state(300.0, alpha, beta, att, [0.0; 3]);
            let out = rates(&b, &x, &BodyLoads::default());
            // No moment, no rates: no angular acceleration and constant attitude.
            for i in [PHI, THETA, PSI, P, Q, R] {
                assert_eq!(out.xdot[i], 0.0, "{}", STATE_NAMES[i]);
            }
            // Accelerometers read zero in free fall.
            assert_eq!([out.nx_g, out.ny_g, out.nz_g], [0.0; 3]);
            // With ω = 0 the NED acceleration is Cᵀ·(u̇, v̇, ẇ): (0, 0, g), i.e. ḧ = −g.
            let a_ned = body_from_ned(att[0], att[1], att[2]).transpose()
                * body_acceleration(&x, &out.xdot);
            assert!((a_ned - Vector3::new(0.0, 0.0, 32.17)).amax() < 1e-12, "{a_ned}");
        }
        // Level, α = β = 0: the velocity turns down at α̇ = g/Vt, speed unchanged.
        let out = rates(&b, &state(300.0, 0.0, 0.0, [0.0; 3], [0.0; 3]), &BodyLoads::default());
        assert_eq!(out.xdot[VT], 0.0);
        assert!((out.xdot[ALPHA] - 32.17 / 300.0).abs() < 1e-15);
        // A lift force equal to the weight cancels gravity; nz reads 1 g.
        let lift =
            BodyLoads { force_lbf: Vector3::new(0.0, 0.0, -500.0 * 32.17), ..Default::default() };
        let out = rates(&b, &state(300.0, 0.0, 0.0, [0.0; 3], [0.0; 3]), &lift);
        assert!(out.xdot.fixed_rows::<9>(0).amax() < 1e-12);
        assert!((out.nz_g - 1.0).abs() < 1e-15);
    }

    #[test]
    fn analytic_pure_roll_moment() {
        let (jx, jz, l) = (10_000.0, 60_000.0, 2_000.0);
        let loads = BodyLoads { moment_ft_lbf: Vector3::new(l, 0.0, 0.0), ..Default::default() };
        let x = state(300.0, 0.05, 0.0, [0.0; 3], [0.0; 3]);
        // Jxz = 0: ṗ = L/Jx, no yaw coupling.
        let out = rates(&body(0.0), &x, &loads);
        assert!((out.xdot[P] - l / jx).abs() < 1e-15);
        assert_eq!((out.xdot[Q], out.xdot[R]), (0.0, 0.0));
        // Jxz ≠ 0: [Jx −Jxz; −Jxz Jz]·[ṗ; ṙ] = [L; 0], inverted by hand.
        let jxz = 1_500.0;
        let det = jx * jz - jxz * jxz;
        let (pdot, rdot) = (jz * l / det, jxz * l / det);
        let out = rates(&body(jxz), &x, &loads);
        assert!((out.xdot[P] - pdot).abs() < 1e-15 * pdot.abs().max(1.0), "{}", out.xdot[P]);
        assert!((out.xdot[R] - rdot).abs() < 1e-15, "{} vs {rdot}", out.xdot[R]);
        assert_eq!(out.xdot[Q], 0.0);
        // And the cross-coupled rate differs from the uncoupled one.
        assert!(rdot > 1e-3 && (pdot - l / jx).abs() > 1e-4);
    }

    #[test]
    fn analytic_moment_equations_are_eulers_equations() {
        // I·ω̇ = M − ω × (I·ω + h e_x) with the full tensor, solved by nalgebra.
        let (jx, jy, jz, jxz) = (9_496.0, 55_814.0, 63_100.0, 982.0);
        let b = RigidBody::new(636.94, jx, jy, jz, jxz, 32.17).unwrap();
        let tensor = Matrix3::new(jx, 0.0, -jxz, 0.0, jy, 0.0, -jxz, 0.0, jz);
        let inv = tensor.try_inverse().unwrap();
        let omega = Vector3::new(0.7, -0.8, 0.9);
        let moment = Vector3::new(12_000.0, -30_000.0, 5_000.0);
        let h = 160.0;
        let want = inv * (moment - omega.cross(&(tensor * omega + Vector3::new(h, 0.0, 0.0))));
        let x = state(500.0, 0.1, 0.05, [0.1, 0.2, 0.3], [omega[0], omega[1], omega[2]]);
        let loads =
            BodyLoads { moment_ft_lbf: moment, heng_slug_ft2_per_s: h, ..Default::default() };
        let xd = rates(&b, &x, &loads).xdot;
        let got = Vector3::new(xd[P], xd[Q], xd[R]);
        assert!((got - want).amax() < 1e-12 * want.amax(), "{got} vs {want}");
    }

    #[test]
    fn val_inertia_constants_match_slj_f16_values() {
        // SLJ §3.5 prints the F-16's c1..c9 rounded; they must follow from its Jx, Jy, Jz, Jxz.
        let c = InertiaConstants::from_inertia(9_496.0, 55_814.0, 63_100.0, 982.0).unwrap();
        let printed = crate::f16::F16Data::embedded().moment;
        for (exact, rounded) in [
            (c.c1, printed.c1),
            (c.c2, printed.c2),
            (c.c3, printed.c3),
            (c.c4, printed.c4),
            (c.c5, printed.c5),
            (c.c6, printed.c6),
            (c.c7, printed.c7),
            (c.c8, printed.c8),
            (c.c9, printed.c9),
        ] {
            assert!(((exact - rounded) / rounded).abs() < 2e-3, "{exact} vs {rounded}");
        }
        // The exact values listed in the data file (data/f16_stevens_lewis.toml, 7 digits).
        for (got, want) in [
            (c.c1, -0.7701192),
            (c.c2, 0.02754766),
            (c.c3, 1.054772e-4),
            (c.c4, 1.641500e-6),
            (c.c5, 0.9604042),
            (c.c6, 0.01759415),
            (c.c7, 1.791665e-5),
            (c.c8, -0.7336125),
            (c.c9, 1.587341e-5),
        ] {
            assert!(((got - want) / want).abs() < 1e-6, "{got} vs {want}");
        }
        assert!(InertiaConstants::from_inertia(1.0, 1.0, 1.0, 1.0).is_err());
        assert!(InertiaConstants::from_inertia(0.0, 1.0, 1.0, 0.0).is_err());
        assert!(RigidBody::new(-1.0, 1.0, 1.0, 1.0, 0.0, 32.17).is_err());
    }

    #[test]
    fn analytic_rotation_matrix_orthonormal_and_hand_values() {
        for (phi, theta, psi) in [(0.0, 0.0, 0.0), (0.3, -0.7, 2.9), (-2.5, 1.2, -1.0)] {
            let c = body_from_ned(phi, theta, psi);
            assert!((c * c.transpose() - Matrix3::identity()).amax() < 1e-15);
            assert!((c.determinant() - 1.0).abs() < 1e-15);
        }
        // ψ = 90°, θ = 30°, φ = 0: nose east and 30° up; right wing south; belly down-east.
        let s3 = 3f64.sqrt() / 2.0;
        let c = body_from_ned(0.0, FRAC_PI_6, FRAC_PI_2);
        let want = Matrix3::new(0.0, s3, -0.5, -1.0, 0.0, 0.0, 0.0, 0.5, s3);
        assert!((c - want).amax() < 1e-15, "{c}");
        // φ = 90° (right wing down) heading north: body y points down, body z points west.
        let c = body_from_ned(FRAC_PI_2, 0.0, 0.0);
        let want = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0);
        assert!((c - want).amax() < 1e-15, "{c}");
    }

    #[test]
    fn analytic_navigation_and_gravity_use_the_same_matrix() {
        let b = body(0.0);
        let (att, alpha, beta) = ([0.4, -0.3, 2.0], 0.2, -0.1);
        let x = state(400.0, alpha, beta, att, [0.0; 3]);
        let k = Kinematics::new(&x).unwrap();
        let c = body_from_ned(att[0], att[1], att[2]);
        assert_eq!(k.body_from_ned(), &c);
        let v_ned = c.transpose() * k.velocity_body_fps();
        let xd = b.derivatives(&k, &BodyLoads::default()).unwrap().xdot;
        assert!((Vector3::new(xd[NORTH], xd[EAST], -xd[ALT]) - v_ned).amax() < 1e-12);
        assert!((v_ned.norm() - 400.0).abs() < 1e-12);
    }

    #[test]
    fn analytic_velocity_angles_round_trip() {
        for vt in [1.0, 250.0, 900.0] {
            for alpha in [-3.0, -1.2, -0.1, 0.0, 0.35, 1.5, 3.1] {
                for beta in [-1.5, -0.4, 0.0, 0.2, 1.4] {
                    let va = VelocityAngles { vt_fps: vt, alpha_rad: alpha, beta_rad: beta };
                    let v = va.to_body();
                    assert!((v.norm() - vt).abs() < 1e-12 * vt);
                    let back = VelocityAngles::from_body(&v);
                    assert!((back.vt_fps - vt).abs() < 1e-12 * vt);
                    assert!((back.alpha_rad - alpha).abs() < 1e-12, "{back:?} vs {va:?}");
                    assert!((back.beta_rad - beta).abs() < 1e-9, "{back:?} vs {va:?}");
                }
            }
        }
        let v = Vector3::new(100.0, -20.0, 30.0);
        let back = VelocityAngles::from_body(&v).to_body();
        assert!((back - v).amax() < 1e-12);
    }

    #[test]
    fn analytic_wind_sign_convention() {
        // Level, heading north at 300 ft/s ground speed, α = β = 0.
        let k = Kinematics::new(&state(300.0, 0.0, 0.0, [0.0; 3], [0.0; 3])).unwrap();
        let air = |ned: [f64; 3], body: [f64; 3]| {
            k.air_relative(&Wind { ned_fps: ned.into(), body_fps: body.into() }).unwrap()
        };
        // Still air: the state itself.
        assert_eq!(air([0.0; 3], [0.0; 3]), VelocityAngles { vt_fps: 300.0, ..Default::default() });
        // Air moving south at 20 ft/s: a headwind, airspeed 320.
        assert!((air([-20.0, 0.0, 0.0], [0.0; 3]).vt_fps - 320.0).abs() < 1e-12);
        // Tailwind in body axes: airspeed 280.
        assert!((air([0.0; 3], [20.0, 0.0, 0.0]).vt_fps - 280.0).abs() < 1e-12);
        // Updraft (air moving up): α > 0; air moving west, i.e. from the right: β > 0.
        assert!((air([0.0, 0.0, -30.0], [0.0; 3]).alpha_rad - 0.1f64.atan()).abs() < 1e-12);
        assert!(air([0.0, -30.0, 0.0], [0.0; 3]).beta_rad > 0.09);
        // Air moving west seen heading east (ψ = 90°) is a headwind.
        let k90 =
            Kinematics::new(&state(300.0, 0.0, 0.0, [0.0, 0.0, FRAC_PI_2], [0.0; 3])).unwrap();
        let w = Wind { ned_fps: Vector3::new(0.0, -20.0, 0.0), body_fps: Vector3::zeros() };
        assert!((k90.air_relative(&w).unwrap().vt_fps - 320.0).abs() < 1e-12);
        // Flying with the air: undefined air-relative angles are an error, not NaN.
        assert!(
            k.air_relative(&Wind { ned_fps: Vector3::new(300.0, 0.0, 0.0), ..Wind::still() })
                .is_err()
        );
    }

    #[test]
    fn bad_states_are_errors() {
        let mut x = state(300.0, 0.0, 0.0, [0.0; 3], [0.0; 3]);
        x[VT] = 0.0;
        assert!(matches!(
            Kinematics::new(&x),
            Err(ModelError::InvalidValue { field: "vt_fps", .. })
        ));
        x[VT] = 300.0;
        x[EAST] = f64::NAN;
        assert!(matches!(
            Kinematics::new(&x),
            Err(ModelError::InvalidValue { field: "east_ft", .. })
        ));
    }
}
