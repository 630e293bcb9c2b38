//! The flat-earth six-degree-of-freedom rigid-body equations, once, as small functions generic
//! over the [`Scalar`] (values with `f64`, exact partials with the estimators' `Dual`).
//!
//! Source: Stevens, Lewis & Johnson, *Aircraft Control and Simulation*, 3rd ed., Wiley 2015
//! (SLJ): the Euler angles and their kinematics (§1.3), the wind-axes angles α, β (§2.3), the
//! flat-earth body-axes equations (§2.5: force, kinematic and moment equations, the moment
//! equations with the inertia constants `c1 … c9`) and their mechanisation in the F-16
//! subroutine `F` (§3.5).
//!
//! # Operation order
//! Each function evaluates its formula in the order its doc writes it, which is the order of
//! subroutine `F`: the F-16 simulator reproduces the textbook's check case (SLJ Table 3.5-2)
//! through these functions, so a rearrangement that is equal in exact arithmetic but rounds
//! differently is a change of behaviour here.
//!
//! # Assumptions
//! Flat, non-rotating earth (NED is inertial), gravity `g` along NED +down, constant mass and
//! inertia, a body x–z plane of symmetry (`Jxy = Jyz = 0`), and an optional rotor (engine)
//! angular momentum `h` along body +x.
//!
//! # Axes, signs, units
//! Body axes x forward, y right, z down; Euler angles 3-2-1 (ψ, θ, φ); `p, q, r` the body rates;
//! moments `L, M, N` right-handed about body x, y, z. `Jxz` as in SLJ: the inertia tensor is
//! `[[Jx, 0, −Jxz], [0, Jy, 0], [−Jxz, 0, Jz]]`. Any consistent units: the simulator works in
//! ft, slug, lbf, the estimators in SI, so `g` is a parameter. Angles in rad; an angle enters as
//! its [`SinCos`], computed once by the caller (the simulator with `std`'s trigonometry, the
//! estimators with `libm`'s, each as before).

use crate::Scalar;

/// Sine and cosine of one angle (the functions below take angles this way, so a caller computes
/// each sine once and chooses its trigonometry).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SinCos<T> {
    /// `sin(angle)`.
    pub sin: T,
    /// `cos(angle)`.
    pub cos: T,
}

impl<T: Scalar> SinCos<T> {
    /// `sin` and `cos` of `angle_rad` through [`Scalar::sin`], [`Scalar::cos`].
    #[inline]
    pub fn of(angle_rad: T) -> Self {
        Self { sin: angle_rad.sin(), cos: angle_rad.cos() }
    }
}

/// Body-axes velocity `[u, v, w]` of speed `vt` at angle of attack α and sideslip β (SLJ
/// §2.3, wind to body axes):
///
/// ```text
/// u = vt cosα cosβ,   v = vt sinβ,   w = vt sinα cosβ
/// ```
///
/// Units of `vt`.
#[inline]
pub fn body_velocity<T: Scalar>(vt: T, alpha: SinCos<T>, beta: SinCos<T>) -> [T; 3] {
    [vt * alpha.cos * beta.cos, vt * beta.sin, vt * alpha.sin * beta.cos]
}

/// Gravity `[0, 0, g]` (NED) in body axes at roll φ and pitch θ: the third column of the
/// direction-cosine matrix `C_body←NED` (SLJ §1.3) times `g` (heading does not enter):
///
/// ```text
/// g_b = [−g sinθ,  g sinφ cosθ,  g cosφ cosθ]
/// ```
///
/// Units of `g` (e.g. ft/s² or m/s²).
#[inline]
pub fn gravity_body<T: Scalar>(g: f64, phi: SinCos<T>, theta: SinCos<T>) -> [T; 3] {
    [-(theta.sin * g), phi.sin * theta.cos * g, phi.cos * theta.cos * g]
}

/// The force equations (SLJ §2.5, flat earth, body axes): the acceleration `[u̇, v̇, ẇ]` of the
/// body velocity `v_body = [u, v, w]` rotating at `omega = [p, q, r]`, under gravity
/// `gravity_body` ([`gravity_body`]) and the specific force `a` = (aerodynamic + thrust
/// force)/mass, i.e. what an accelerometer at the cg reads:
///
/// ```text
/// u̇ = r v − q w + g_b,x + a_x
/// v̇ = p w − r u + g_b,y + a_y
/// ẇ = q u − p v + g_b,z + a_z
/// ```
#[inline]
pub fn body_acceleration<T: Scalar>(
    v_body: [T; 3],
    omega: [T; 3],
    gravity_body: [T; 3],
    specific_force: [T; 3],
) -> [T; 3] {
    let ([u, v, w], [p, q, r]) = (v_body, omega);
    let (g, a) = (gravity_body, specific_force);
    [r * v - q * w + g[0] + a[0], p * w - r * u + g[1] + a[1], q * u - p * v + g[2] + a[2]]
}

/// Rate of the speed `vt = |v_body|` (> 0) for body acceleration `v_dot` (SLJ §3.5,
/// subroutine F): `V̇t = (u u̇ + v v̇ + w ẇ) / vt`.
#[inline]
pub fn airspeed_rate<T: Scalar>(v_body: [T; 3], v_dot: [T; 3], vt: T) -> T {
    let ([u, v, w], [ud, vd, wd]) = (v_body, v_dot);
    (u * ud + v * vd + w * wd) / vt
}

/// Rate of the angle of attack `α = atan2(w, u)` for body acceleration `v_dot` (SLJ §3.5,
/// subroutine F): `α̇ = (u ẇ − w u̇) / (u² + w²)`. Linear in `v_dot` (the estimators use that to
/// solve an α̇-dependent force exactly). Not finite when `u² + w² = 0` (|β| = 90°).
#[inline]
pub fn alpha_rate<T: Scalar>(v_body: [T; 3], v_dot: [T; 3]) -> T {
    let ([u, _, w], [ud, _, wd]) = (v_body, v_dot);
    (u * wd - w * ud) / (u * u + w * w)
}

/// Rate of the sideslip `β = asin(v / vt)` for body acceleration `v_dot`, given `vt`, its rate
/// `vt_dot` ([`airspeed_rate`]) and `cos β` (SLJ §3.5, subroutine F):
/// `β̇ = (vt v̇ − v V̇t) cosβ / (u² + w²)` (equal to `(vt v̇ − v V̇t)/(vt² cosβ)`, since
/// `u² + w² = vt² cos²β`). Not finite when `u² + w² = 0`.
#[inline]
pub fn sideslip_rate<T: Scalar>(v_body: [T; 3], v_dot: [T; 3], vt: T, vt_dot: T, cos_beta: T) -> T {
    let ([u, v, w], vd) = (v_body, v_dot[1]);
    (vt * vd - v * vt_dot) * cos_beta / (u * u + w * w)
}

/// The wind-axes state rates `[V̇t, α̇, β̇]` ([`airspeed_rate`], [`alpha_rate`],
/// [`sideslip_rate`]) of the body velocity `v_body` (speed `vt` > 0, sideslip cosine
/// `cos_beta`) under body acceleration `v_dot` (SLJ §3.5, subroutine F).
#[inline]
pub fn wind_axes_rates<T: Scalar>(v_body: [T; 3], v_dot: [T; 3], vt: T, cos_beta: T) -> [T; 3] {
    let vt_dot = airspeed_rate(v_body, v_dot, vt);
    [vt_dot, alpha_rate(v_body, v_dot), sideslip_rate(v_body, v_dot, vt, vt_dot, cos_beta)]
}

/// The Euler-angle rates `[φ̇, θ̇, ψ̇]` of body rates `omega = [p, q, r]` at roll φ and pitch θ
/// (SLJ §1.3, Euler kinematical equations; §2.5):
///
/// ```text
/// φ̇ = p + (sinθ / cosθ)(q sinφ + r cosφ)
/// θ̇ = q cosφ − r sinφ
/// ψ̇ = (q sinφ + r cosφ) / cosθ
/// ```
///
/// Singular at cosθ = 0 (|θ| = 90°); callers refuse that attitude.
#[inline]
pub fn euler_rates<T: Scalar>(omega: [T; 3], phi: SinCos<T>, theta: SinCos<T>) -> [T; 3] {
    let [p, q, r] = omega;
    let q_sin_phi = q * phi.sin;
    [
        p + theta.sin / theta.cos * (q_sin_phi + r * phi.cos),
        q * phi.cos - r * phi.sin,
        (q_sin_phi + r * phi.cos) / theta.cos,
    ]
}

/// Moments and product of inertia about the cg in body axes, SLJ sign convention (tensor
/// element (1,3) is `−jxz`); units of mass × length² (slug·ft² or kg·m²).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inertia {
    /// `Jx`, about body x.
    pub jx: f64,
    /// `Jy`, about body y.
    pub jy: f64,
    /// `Jz`, about body z.
    pub jz: f64,
    /// `Jxz` (the tensor holds `−Jxz`).
    pub jxz: f64,
}

impl Inertia {
    /// `Γ = Jx Jz − Jxz²` (SLJ §2.5), the determinant of the roll–yaw block; > 0 for a real body.
    #[inline]
    pub fn gamma(&self) -> f64 {
        self.jx * self.jz - self.jxz * self.jxz
    }
}

/// Why an inertia was refused by [`InertiaConstants::from_inertia`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InertiaError {
    /// The offending input: `jx`, `jy`, `jz` or `jxz`.
    pub field: &'static str,
    /// Its value.
    pub value: f64,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl core::fmt::Display for InertiaError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "invalid `{}` = {}: {}",
            self.field,
            crate::text::ExactOrShort(self.value),
            self.reason
        )
    }
}

impl core::error::Error for InertiaError {}

/// The moment-equation inertia constants `c1 … c9` (SLJ §2.5; the F-16 values are printed in
/// §3.5). With `Γ = Jx Jz − Jxz²`:
///
/// ```text
/// Γc1 = (Jy − Jz)Jz − Jxz²   Γc2 = (Jx − Jy + Jz)Jxz   Γc3 = Jz   Γc4 = Jxz
/// c5 = (Jz − Jx)/Jy          c6 = Jxz/Jy                c7 = 1/Jy
/// Γc8 = Jx(Jx − Jy) + Jxz²   Γc9 = Jx
/// ```
///
/// c3, c4, c7, c9 are in 1/(mass × length²), the others dimensionless. c3, c4, c9 and c7 are
/// the entries of the inverse inertia tensor (`[[c3, 0, c4], [0, c7, 0], [c4, 0, c9]]`). A model
/// may also supply published (rounded) values directly, as the F-16 does to reproduce the
/// textbook's check case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InertiaConstants {
    /// c1 = ((Jy − Jz)Jz − Jxz²)/Γ.
    pub c1: f64,
    /// c2 = (Jx − Jy + Jz)Jxz/Γ.
    pub c2: f64,
    /// c3 = Jz/Γ.
    pub c3: f64,
    /// c4 = Jxz/Γ.
    pub c4: f64,
    /// c5 = (Jz − Jx)/Jy.
    pub c5: f64,
    /// c6 = Jxz/Jy.
    pub c6: f64,
    /// c7 = 1/Jy.
    pub c7: f64,
    /// c8 = (Jx(Jx − Jy) + Jxz²)/Γ.
    pub c8: f64,
    /// c9 = Jx/Γ.
    pub c9: f64,
}

impl InertiaConstants {
    /// The constants of moments of inertia `jx`, `jy`, `jz` and product `jxz` (SLJ sign
    /// convention).
    ///
    /// # Errors
    /// [`InertiaError`] if `jx`, `jy` or `jz` is not finite and positive (field = its name), or
    /// `jxz` is not finite or `Γ = Jx Jz − Jxz² ≤ 0` (field `jxz`: the x–z block is not positive
    /// definite).
    pub fn from_inertia(jx: f64, jy: f64, jz: f64, jxz: f64) -> Result<Self, InertiaError> {
        for (field, value) in [("jx", jx), ("jy", jy), ("jz", jz)] {
            if !(value.is_finite() && value > 0.0) {
                let reason = "moment of inertia must be finite and > 0";
                return Err(InertiaError { field, value, reason });
            }
        }
        let inertia = Inertia { jx, jy, jz, jxz };
        if !(jxz.is_finite() && inertia.gamma() > 0.0) {
            let reason = "needs a finite Jxz with Jx*Jz - Jxz^2 > 0";
            return Err(InertiaError { field: "jxz", value: jxz, reason });
        }
        Ok(Self::of(&inertia))
    }

    /// The constants of `i` without checks, for a caller that validated what it uses: with
    /// `Γ = 0` (e.g. only `Jy` known) c1–c4, c8, c9 are not finite while the pitch constants
    /// c5–c7 still are.
    #[inline]
    pub fn of(i: &Inertia) -> Self {
        let Inertia { jx, jy, jz, jxz } = *i;
        let gamma = i.gamma();
        Self {
            c1: ((jy - jz) * jz - jxz * jxz) / gamma,
            c2: (jx - jy + jz) * jxz / gamma,
            c3: jz / gamma,
            c4: jxz / gamma,
            c5: (jz - jx) / jy,
            c6: jxz / jy,
            c7: 1.0 / jy,
            c8: (jx * (jx - jy) + jxz * jxz) / gamma,
            c9: jx / gamma,
        }
    }
}

/// Roll and yaw accelerations `[ṗ, ṙ]` from Euler's equations (SLJ §2.5, solved with the
/// constants `c`) at body rates `omega = [p, q, r]` under rolling moment `roll` (L), yawing
/// moment `yaw` (N) and rotor angular momentum `h_rotor` along body +x (0 without one):
///
/// ```text
/// ṗ = (c2 p + c1 r + c4 h) q + c3 L + c4 N
/// ṙ = (c8 p − c2 r + c9 h) q + c4 L + c9 N
/// ```
#[inline]
pub fn roll_yaw_acceleration<T: Scalar>(
    c: &InertiaConstants,
    omega: [T; 3],
    roll: T,
    yaw: T,
    h_rotor: f64,
) -> [T; 2] {
    let [p, q, r] = omega;
    [
        (p * c.c2 + r * c.c1 + c.c4 * h_rotor) * q + roll * c.c3 + yaw * c.c4,
        (p * c.c8 - r * c.c2 + c.c9 * h_rotor) * q + roll * c.c4 + yaw * c.c9,
    ]
}

/// Pitch acceleration `q̇` from Euler's equations (SLJ §2.5) at roll and yaw rates `p`, `r`
/// under pitching moment `pitch` (M) and rotor angular momentum `h_rotor` along +x:
///
/// ```text
/// q̇ = (c5 p − c7 h) r + c6 (r² − p²) + c7 M
/// ```
#[inline]
pub fn pitch_acceleration<T: Scalar>(
    c: &InertiaConstants,
    p: T,
    r: T,
    pitch: T,
    h_rotor: f64,
) -> T {
    (p * c.c5 - c.c7 * h_rotor) * r + (r * r - p * p) * c.c6 + pitch * c.c7
}

/// The angular acceleration `[ṗ, q̇, ṙ]` ([`roll_yaw_acceleration`], [`pitch_acceleration`]):
/// Euler's equations `J ω̇ = M − ω × (J ω + h e_x)` with the x–z symmetric tensor, at body rates
/// `omega` under `moment = [L, M, N]` (SLJ §2.5).
#[inline]
pub fn angular_acceleration<T: Scalar>(
    c: &InertiaConstants,
    omega: [T; 3],
    moment: [T; 3],
    h_rotor: f64,
) -> [T; 3] {
    let [roll, pitch, yaw] = moment;
    let [pdot, rdot] = roll_yaw_acceleration(c, omega, roll, yaw, h_rotor);
    [pdot, pitch_acceleration(c, omega[0], omega[2], pitch, h_rotor), rdot]
}

/// The inverse of [`roll_yaw_acceleration`]: the rolling and yawing moments `[L, N]` that give
/// roll and yaw accelerations `pdot`, `rdot` at body rates `omega = [p, q, r]` (Euler's
/// equations, SLJ §2.5, `M = J ω̇ + ω × (J ω + h e_x)`), as the measured coefficients need:
///
/// ```text
/// L = Jx ṗ − Jxz (ṙ + p q) + (Jz − Jy) q r
/// N = Jz ṙ − Jxz (ṗ − q r) + (Jy − Jx) p q − h q
/// ```
#[inline]
pub fn roll_yaw_moments<T: Scalar>(
    i: &Inertia,
    omega: [T; 3],
    pdot: T,
    rdot: T,
    h_rotor: f64,
) -> [T; 2] {
    let [p, q, r] = omega;
    [
        pdot * i.jx - (rdot + p * q) * i.jxz + q * (i.jz - i.jy) * r,
        rdot * i.jz - (pdot - q * r) * i.jxz + p * (i.jy - i.jx) * q - q * h_rotor,
    ]
}

/// The inverse of [`pitch_acceleration`]: the pitching moment `M` that gives pitch acceleration
/// `qdot` at roll and yaw rates `p`, `r` (Euler's equations, SLJ §2.5):
///
/// ```text
/// M = Jy q̇ + ((Jx − Jz) p r + Jxz (p² − r²)) + h r
/// ```
///
/// With `p = r = 0` the inertial coupling vanishes exactly (`M = Jy q̇`): the symmetric-flight
/// form a longitudinal record uses.
#[inline]
pub fn pitch_moment<T: Scalar>(i: &Inertia, p: T, r: T, qdot: T, h_rotor: f64) -> T {
    qdot * i.jy + (p * (i.jx - i.jz) * r + (p * p - r * r) * i.jxz) + r * h_rotor
}

#[cfg(test)]
mod tests;
