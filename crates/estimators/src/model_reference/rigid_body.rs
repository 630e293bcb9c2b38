//! The rigid-body rate equation each aerodynamic coefficient drives: its sliding state `z`,
//! the measured `z_m` and `ż_m` at a sample, and the rate per unit coefficient `k = ∂ż/∂C`.
//!
//! Source: Stevens, Lewis & Johnson, *Aircraft Control and Simulation*, 3rd ed., Wiley 2016:
//! §2.5 flat-Earth rigid-body equations in body axes (force equations; moment equations
//! eq. 2.5-24 with `Jxy = Jyz = 0`, the form `sample.rs` uses) and §3.5, subroutine F, for the
//! wind-axis states `V̇, α̇, β̇` formed from the body-axis velocity rates. Thesis §3.4 picks the
//! sliding states: `p, q, r` for the moment estimator, `α, V_T, β` for lift and drag.
//!
//! | coefficient | state `z` | `ż` (measured, this module) | `k = ∂ż/∂C` |
//! |---|---|---|---|
//! | `Cl` | `p` | `ṗ` channel | `q̄ S b c3`, `c3 = Jz / (Jx Jz − Jxz²)` |
//! | `Cm` | `q` | `q̇` channel | `q̄ S c̄ / Jy` |
//! | `Cn` | `r` | `ṙ` channel | `q̄ S b c9`, `c9 = Jx / (Jx Jz − Jxz²)` |
//! | `CL` | `α` | `(u ẇ − w u̇) / (u² + w²)` | `−q̄ S / (m V cos β)` |
//! | `CD` | `V` | `(u u̇ + v v̇ + w ẇ) / V` | `−q̄ S cos β / m` |
//! | `CY` | `β` | `(V v̇ − v V̇) cos β / (u² + w²)` | `q̄ S cos β / (m V)` |
//! | `CX` | `u` | `u̇` | `q̄ S / m` |
//! | `CZ` | `w` | `ẇ` | `q̄ S / m` |
//!
//! with the body velocity `u = V cos α cos β, v = V sin β, w = V sin α cos β` and the body-axis
//! force equations driven by the measured specific force `a` (accelerometers, which include the
//! thrust), all evaluated by the shared kernel ([`aeroident_physics::rigid_body`]: `body_velocity`,
//! `gravity_body`, `body_acceleration`, `wind_axes_rates`; the inertia constants `c3`, `c9`):
//!
//! ```text
//! u̇ = r v − q w − g sin θ + ax
//! v̇ = p w − r u + g sin φ cos θ + ay
//! ẇ = q u − p v + g cos φ cos θ + az
//! ```
//!
//! `Cl` and `Cn` both enter `ṗ` and `ṙ` through `Jxz`: the moment equations are solved for
//! `[ṗ, ṙ]` with the 2×2 inertia block `[[Jx, −Jxz], [−Jxz, Jz]]` (Stevens & Lewis sign, as
//! in `sample.rs`), so `∂ṗ/∂Cl = q̄ S b c3` and `∂ṙ/∂Cn = q̄ S b c9`. Each
//! coefficient is assigned the state whose partial is the direct (diagonal) one; the other
//! coefficient's contribution to that state is a measured term like gravity or thrust.
//!
//! **Measured rates.** `ṗ, q̇, ṙ` are the sample's channels (the same ones that form the measured
//! moment coefficients). `α̇, V̇, β̇, u̇, ẇ` are *not* differences of the measured states and not the
//! `alphadot` channel: they come from the force equations above with the measured specific
//! force, attitude and rates, i.e. from the same accelerometer data that forms the measured force
//! coefficients (no differentiation, no lag). This assumes no wind (air-relative `V, α, β` equal
//! the inertial ones). A record without `β` is taken as symmetric flight (`v = 0`; then `p, r, ay`
//! are not needed), as `sample.rs` does for `Cm`.

use crate::sample::AirDataSample;
use crate::vocabulary::Coefficient;
use aeroident_physics::rigid_body::{self as rb, Inertia, InertiaConstants, SinCos};

/// Standard gravity, m/s² (flat Earth, Stevens & Lewis §2.5; re-exported from
/// [`aeroident_physics::units`]).
pub use aeroident_physics::units::G0_MPS2;

/// The sliding state a coefficient drives (module table).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlidingState {
    /// Body x velocity `u`, m/s (driven by `CX`).
    U,
    /// Sideslip `β`, rad (driven by `CY`).
    Beta,
    /// Body z velocity `w`, m/s (driven by `CZ`).
    W,
    /// Angle of attack `α`, rad (driven by `CL`).
    Alpha,
    /// True airspeed `V`, m/s (driven by `CD`).
    V,
    /// Roll rate `p`, rad/s (driven by `Cl`).
    P,
    /// Pitch rate `q`, rad/s (driven by `Cm`).
    Q,
    /// Yaw rate `r`, rad/s (driven by `Cn`).
    R,
}

impl SlidingState {
    /// The state coefficient `c` drives.
    pub fn of(c: Coefficient) -> Self {
        match c {
            Coefficient::CX => Self::U,
            Coefficient::CY => Self::Beta,
            Coefficient::CZ => Self::W,
            Coefficient::CL => Self::Alpha,
            Coefficient::CD => Self::V,
            Coefficient::Cl => Self::P,
            Coefficient::Cm => Self::Q,
            Coefficient::Cn => Self::R,
        }
    }

    /// Name with unit, e.g. `q_rad_s`, `vt_mps`.
    pub fn name(self) -> &'static str {
        match self {
            Self::U => "u_mps",
            Self::Beta => "beta_rad",
            Self::W => "w_mps",
            Self::Alpha => "alpha_rad",
            Self::V => "vt_mps",
            Self::P => "p_rad_s",
            Self::Q => "q_rad_s",
            Self::R => "r_rad_s",
        }
    }

    /// The largest credible gap `|z_est − z_m|` between an estimated model that still
    /// describes the aircraft and the measured state: 2 rad/s for rates, 0.5 rad for angles,
    /// half the airspeed for velocities. Beyond it the estimator has run away (diverged).
    pub fn runaway_bound(self, vt_mps: f64) -> f64 {
        match self {
            Self::P | Self::Q | Self::R => 2.0,
            Self::Alpha | Self::Beta => 0.5,
            Self::V | Self::U | Self::W => 0.5 * vt_mps,
        }
    }
}

/// One coefficient's sliding state at one sample (module table), units of the state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StateRate {
    /// Measured state `z_m`.
    pub z_m: f64,
    /// Measured state rate `ż_m`, state unit per s.
    pub zdot_m: f64,
    /// Rate per unit coefficient `k = ∂ż/∂C`, state unit per s.
    pub k: f64,
}

/// The sliding state of coefficient `c` at sample `s`, or the name of the first channel or
/// constant it needs that the sample lacks (or that is out of its domain: mass, V, inertia).
///
/// # Errors
/// The field name, e.g. `"qdot_rad_s2"`, `"theta_rad"`, `"Iyy_kgm2"`.
pub fn state_rate(c: Coefficient, s: &AirDataSample) -> Result<StateRate, &'static str> {
    let k = &s.constants;
    let qs = s.qbar_pa * k.S_m2;
    match SlidingState::of(c) {
        SlidingState::Q => {
            let iyy = positive(k.Iyy_kgm2, "Iyy_kgm2")?;
            Ok(StateRate {
                z_m: s.q_rad_s.ok_or("q_rad_s")?,
                zdot_m: s.qdot_rad_s2.ok_or("qdot_rad_s2")?,
                k: qs * k.cbar_m.ok_or("cbar_m")? / iyy,
            })
        }
        SlidingState::P | SlidingState::R => {
            let ixx = positive(k.Ixx_kgm2, "Ixx_kgm2")?;
            let izz = positive(k.Izz_kgm2, "Izz_kgm2")?;
            let ixz = k.Ixz_kgm2.ok_or("Ixz_kgm2")?;
            let inertia = Inertia { jx: ixx, jy: 0.0, jz: izz, jxz: ixz };
            let det = inertia.gamma();
            if det.is_nan() || det <= 0.0 {
                return Err("Ixz_kgm2");
            }
            let qsb = qs * k.b_m.ok_or("b_m")?;
            // ∂ṗ/∂L = c3 and ∂ṙ/∂N = c9 of the moment equations (Jy does not enter them).
            let constants = InertiaConstants::of(&inertia);
            Ok(if c == Coefficient::Cl {
                StateRate {
                    z_m: s.p_rad_s.ok_or("p_rad_s")?,
                    zdot_m: s.pdot_rad_s2.ok_or("pdot_rad_s2")?,
                    k: qsb * constants.c3,
                }
            } else {
                StateRate {
                    z_m: s.r_rad_s.ok_or("r_rad_s")?,
                    zdot_m: s.rdot_rad_s2.ok_or("rdot_rad_s2")?,
                    k: qsb * constants.c9,
                }
            })
        }
        state => force_state(state, s, qs),
    }
}

fn positive(v: Option<f64>, name: &'static str) -> Result<f64, &'static str> {
    v.filter(|x| *x > 0.0).ok_or(name)
}

/// Body velocity and its rate from the force equations (module doc).
struct BodyKinematics {
    u: f64,
    v: f64,
    w: f64,
    udot: f64,
    vdot: f64,
    wdot: f64,
}

fn body_kinematics(s: &AirDataSample) -> Result<BodyKinematics, &'static str> {
    let vt = s.vt_mps;
    if vt.is_nan() || vt <= 0.0 {
        return Err("vt_mps");
    }
    let beta = SinCos::of(s.beta_rad.unwrap_or(0.0));
    let v_body = rb::body_velocity(vt, SinCos::of(s.alpha_rad), beta);
    let [u, v, w] = v_body;
    // Symmetric flight (v = 0): p, r and ay do not enter u̇, ẇ or V̇.
    let lateral = |x: Option<f64>, name: &'static str| match x {
        Some(x) => Ok(x),
        None if v == 0.0 => Ok(0.0),
        None => Err(name),
    };
    let p = lateral(s.p_rad_s, "p_rad_s")?;
    let r = lateral(s.r_rad_s, "r_rad_s")?;
    let ay = lateral(s.ay_mps2, "ay_mps2")?;
    let q = s.q_rad_s.ok_or("q_rad_s")?;
    let ax = s.ax_mps2.ok_or("ax_mps2")?;
    let az = s.az_mps2.ok_or("az_mps2")?;
    let theta = SinCos::of(s.theta_rad.ok_or("theta_rad")?);
    let phi = SinCos::of(s.phi_rad.ok_or("phi_rad")?);
    let gravity = rb::gravity_body(G0_MPS2, phi, theta);
    let [udot, vdot, wdot] = rb::body_acceleration(v_body, [p, q, r], gravity, [ax, ay, az]);
    Ok(BodyKinematics { u, v, w, udot, vdot, wdot })
}

fn force_state(state: SlidingState, s: &AirDataSample, qs: f64) -> Result<StateRate, &'static str> {
    let m = s.constants.mass_kg;
    if m.is_nan() || m <= 0.0 {
        return Err("mass_kg");
    }
    let b = body_kinematics(s)?;
    let vt = s.vt_mps;
    let cb = libm::cos(s.beta_rad.unwrap_or(0.0));
    let (v_body, v_dot) = ([b.u, b.v, b.w], [b.udot, b.vdot, b.wdot]);
    let [vdot_t, alphadot, betadot] = rb::wind_axes_rates(v_body, v_dot, vt, cb);
    Ok(match state {
        SlidingState::U => StateRate { z_m: b.u, zdot_m: b.udot, k: qs / m },
        SlidingState::W => StateRate { z_m: b.w, zdot_m: b.wdot, k: qs / m },
        SlidingState::V => StateRate { z_m: vt, zdot_m: vdot_t, k: -qs * cb / m },
        SlidingState::Alpha => {
            StateRate { z_m: s.alpha_rad, zdot_m: alphadot, k: -qs / (m * vt * cb) }
        }
        SlidingState::Beta => {
            StateRate { z_m: s.beta_rad.ok_or("beta_rad")?, zdot_m: betadot, k: qs * cb / (m * vt) }
        }
        SlidingState::P | SlidingState::Q | SlidingState::R => {
            unreachable!("moment states are handled by state_rate")
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::AircraftConstants;

    fn sample() -> AirDataSample {
        AirDataSample {
            t_s: 0.0,
            vt_mps: 120.0,
            alpha_rad: 0.08,
            qbar_pa: 6000.0,
            beta_rad: Some(0.03),
            p_rad_s: Some(0.2),
            q_rad_s: Some(-0.05),
            r_rad_s: Some(0.07),
            pdot_rad_s2: Some(0.4),
            qdot_rad_s2: Some(-0.3),
            rdot_rad_s2: Some(0.1),
            phi_rad: Some(0.3),
            theta_rad: Some(0.1),
            ax_mps2: Some(1.1),
            ay_mps2: Some(-0.6),
            az_mps2: Some(-11.0),
            constants: AircraftConstants {
                mass_kg: 9000.0,
                S_m2: 27.0,
                cbar_m: Some(3.4),
                b_m: Some(9.1),
                Ixx_kgm2: Some(1.7e4),
                Iyy_kgm2: Some(7.7e4),
                Izz_kgm2: Some(9.1e4),
                Ixz_kgm2: Some(1.4e3),
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// `k = ∂ż/∂C` by an independent route: change the specific force (forces) or the angular
    /// acceleration (moments) the way one unit of extra coefficient would, recompute `ż` and
    /// difference. For the moments the extra roll/yaw moment is pushed through an explicit
    /// Cramer solve of the Euler equations (S&L eq. 2.5-24).
    #[test]
    fn analytic_rate_per_unit_coefficient_matches_a_perturbation() {
        let s = sample();
        let qs = s.qbar_pa * s.constants.S_m2;
        let m = s.constants.mass_kg;
        let (sa, ca) = (s.alpha_rad.sin(), s.alpha_rad.cos());
        let dc = 1e-4;
        // Extra CX, CZ from extra CL, CD: CX = CL sin α − CD cos α, CZ = −CL cos α − CD sin α.
        let forces: [(Coefficient, [f64; 3]); 5] = [
            (Coefficient::CX, [1.0, 0.0, 0.0]),
            (Coefficient::CY, [0.0, 1.0, 0.0]),
            (Coefficient::CZ, [0.0, 0.0, 1.0]),
            (Coefficient::CL, [sa, 0.0, -ca]),
            (Coefficient::CD, [-ca, 0.0, -sa]),
        ];
        for (c, dir) in forces {
            let mut s2 = s;
            s2.ax_mps2 = Some(s.ax_mps2.unwrap() + dir[0] * dc * qs / m);
            s2.ay_mps2 = Some(s.ay_mps2.unwrap() + dir[1] * dc * qs / m);
            s2.az_mps2 = Some(s.az_mps2.unwrap() + dir[2] * dc * qs / m);
            let (a, b) = (state_rate(c, &s).unwrap(), state_rate(c, &s2).unwrap());
            let fd = (b.zdot_m - a.zdot_m) / dc;
            assert!((fd - a.k).abs() < 1e-9 * a.k.abs(), "{}: fd {fd} vs k {}", c.name(), a.k);
        }
        let k = s.constants;
        let (ixx, izz, ixz) = (k.Ixx_kgm2.unwrap(), k.Izz_kgm2.unwrap(), k.Ixz_kgm2.unwrap());
        let qsb = qs * k.b_m.unwrap();
        for (c, dl, dn) in [(Coefficient::Cl, dc * qsb, 0.0), (Coefficient::Cn, 0.0, dc * qsb)] {
            // [Jx −Jxz; −Jxz Jz] [Δṗ, Δṙ] = [ΔL, ΔN] by Cramer's rule.
            let det = ixx * izz - ixz * ixz;
            let dp = (dl * izz + ixz * dn) / det;
            let dr = (ixx * dn + ixz * dl) / det;
            let mut s2 = s;
            s2.pdot_rad_s2 = Some(s.pdot_rad_s2.unwrap() + dp);
            s2.rdot_rad_s2 = Some(s.rdot_rad_s2.unwrap() + dr);
            let (a, b) = (state_rate(c, &s).unwrap(), state_rate(c, &s2).unwrap());
            let fd = (b.zdot_m - a.zdot_m) / dc;
            assert!((fd - a.k).abs() < 1e-6 * a.k.abs(), "{}: fd {fd} vs k {}", c.name(), a.k);
            // The measured coefficient moves by exactly dc as well.
            let i = c.index();
            let dcm = b_coeff(&s2, i) - b_coeff(&s, i);
            assert!((dcm - dc).abs() < 1e-9, "{}: ΔC {dcm}", c.name());
        }
    }

    fn b_coeff(s: &AirDataSample, i: usize) -> f64 {
        s.measured_coefficients()[i].unwrap()
    }

    /// `α̇, V̇, β̇` against the time derivative of `α = atan2(w, u)`, `V = |v|`,
    /// `β = asin(v/V)` along a short step of the body velocity rates (independent kinematics).
    #[test]
    fn analytic_wind_axis_rates_are_derivatives_of_the_body_velocity() {
        let s = sample();
        let b = body_kinematics(&s).unwrap();
        let h = 1e-6;
        let (u, v, w) = (b.u + h * b.udot, b.v + h * b.vdot, b.w + h * b.wdot);
        let vt = (u * u + v * v + w * w).sqrt();
        let alpha = w.atan2(u);
        let beta = (v / vt).asin();
        let rel = |x: f64, y: f64| (x - y).abs() / y.abs().max(1e-12);
        let a = state_rate(Coefficient::CL, &s).unwrap();
        assert!(rel((alpha - s.alpha_rad) / h, a.zdot_m) < 1e-5, "α̇ {}", a.zdot_m);
        let vv = state_rate(Coefficient::CD, &s).unwrap();
        assert!(rel((vt - s.vt_mps) / h, vv.zdot_m) < 1e-5, "V̇ {}", vv.zdot_m);
        let bb = state_rate(Coefficient::CY, &s).unwrap();
        assert!(rel((beta - s.beta_rad.unwrap()) / h, bb.zdot_m) < 1e-5, "β̇ {}", bb.zdot_m);
    }

    /// Level, unaccelerated, wings-level flight (specific force = −g in the vertical): every
    /// force-state rate is zero.
    #[test]
    fn analytic_trim_has_zero_rates() {
        let alpha: f64 = 0.05;
        let mut s = sample();
        s.alpha_rad = alpha;
        s.theta_rad = Some(alpha);
        s.phi_rad = Some(0.0);
        s.beta_rad = None;
        s.p_rad_s = None;
        s.r_rad_s = None;
        s.ay_mps2 = None;
        s.q_rad_s = Some(0.0);
        s.ax_mps2 = Some(G0_MPS2 * alpha.sin());
        s.az_mps2 = Some(-G0_MPS2 * alpha.cos());
        for c in [Coefficient::CX, Coefficient::CZ, Coefficient::CL, Coefficient::CD] {
            let r = state_rate(c, &s).unwrap();
            assert!(r.zdot_m.abs() < 1e-12, "{}: {}", c.name(), r.zdot_m);
        }
        assert_eq!(state_rate(Coefficient::CY, &s), Err("beta_rad"));
        s.theta_rad = None;
        assert_eq!(state_rate(Coefficient::CL, &s), Err("theta_rad"));
    }
}
