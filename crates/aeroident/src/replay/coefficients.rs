//! Non-dimensional force and moment coefficients from measured flight data.
//!
//! Sources: Klein & Morelli, *Aircraft System Identification*, AIAA 2006, ch. 3 (body-axis
//! equations of motion) and ch. 5 (equation-error data preparation: "measured" coefficients from
//! accelerometers and angular accelerations); Jategaonkar 2015 eq. (5.86)–(5.89) for the thrust
//! terms (thrust inclined by σT to body x, moment `M_T`). All quantities SI, body axes, x
//! forward, z down; accelerometers measure specific force at the CG (`az ≈ −g` level):
//!
//! ```text
//! q̄    = measured q̄, else ½ ρ V²
//! α_cg = α_vane + x_vane q / V                                      (vane x_vane ahead of CG)
//! CX   = (m ax − T cos σT) / (q̄ S)
//! CZ   = (m az + T sin σT) / (q̄ S)
//! CL   = −CZ cos α + CX sin α,    CD = −CX cos α − CZ sin α        (stability axes)
//! Cm   = (Iyy q̇ − (Izz − Ixx) p r − Ixz (r² − p²) − M_T) / (q̄ S c̄),  M_T = measured or l_T·T
//! q̂    = q c̄ / (2V),   V/V0
//! ```
//!
//! Checked against the Twin Otter record's stored SIDPAC `Cm`, `CL`, `CD` and the JSBSim log's
//! own `Cm`, `CL` (tests in `crates/aeroident/tests/replay_records.rs`).

use aeroident_estimators::regressors::CoefficientSample;
use aeroident_io::FlightSample;

/// Dynamic pressure, Pa: the measured one if mapped, else `½ρV²`; `None` if neither is known.
pub fn qbar_pa(s: &FlightSample) -> Option<f64> {
    s.qbar_pa.or_else(|| s.rho_kgpm3.map(|rho| 0.5 * rho * s.vt_mps * s.vt_mps))
}

/// Air density, kg/m³: the mapped one, else `2 q̄ / V²`.
pub fn rho_kgpm3(s: &FlightSample) -> Option<f64> {
    s.rho_kgpm3.or_else(|| s.qbar_pa.map(|q| 2.0 * q / (s.vt_mps * s.vt_mps)))
}

/// Angle of attack at the CG, rad: `α_vane + x_vane q / V` (Klein & Morelli 2006, ch. 10,
/// data compatibility: kinematic position correction, first order, no α̇ term).
pub fn alpha_cg_rad(s: &FlightSample) -> f64 {
    s.alpha_rad + s.alpha_vane_x_m * s.q_rad_s / s.vt_mps
}

/// The measured coefficients and regressors of one sample, with pitch acceleration
/// `qdot_rad_s2` (from the record or the causal differentiator) and reference speed `v0_mps`.
/// `None` if the dynamic pressure is unknown.
pub fn coefficient_sample(
    s: &FlightSample,
    qdot_rad_s2: f64,
    v0_mps: f64,
) -> Option<CoefficientSample> {
    let qbar = qbar_pa(s)?;
    let qs = qbar * s.S_m2;
    let alpha = alpha_cg_rad(s);
    let cx = (s.mass_kg * s.ax_mps2 - s.thrust_n * s.thrust_incidence_rad.cos()) / qs;
    let cz = (s.mass_kg * s.az_mps2 + s.thrust_n * s.thrust_incidence_rad.sin()) / qs;
    let (sa, ca) = alpha.sin_cos();
    let cl = -cz * ca + cx * sa;
    let cd = -cx * ca - cz * sa;
    let m_t = s.thrust_moment_nm.unwrap_or(s.thrust_arm_m * s.thrust_n);
    let (p, r) = (s.p_rad_s, s.r_rad_s);
    let m_aero = s.Iyy_kgm2 * qdot_rad_s2
        - (s.Izz_kgm2 - s.Ixx_kgm2) * p * r
        - s.Ixz_kgm2 * (r * r - p * p)
        - m_t;
    Some(CoefficientSample {
        t_s: s.t_s,
        alpha_rad: alpha,
        qhat: s.q_rad_s * s.cbar_m / (2.0 * s.vt_mps),
        de_rad: s.de_rad,
        v_ratio: s.vt_mps / v0_mps,
        Cm: m_aero / (qs * s.cbar_m),
        CL: cl,
        CD: cd,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Level, unaccelerated flight: lift balances weight, drag balances thrust, Cm = 0.
    #[test]
    fn analytic_steady_level_flight_balances() {
        let m = 7000.0;
        let g = 9.80665;
        let qbar = 4000.0;
        let s_ref = 30.0;
        let alpha: f64 = 0.05;
        // Specific force of a level, steady aircraft at pitch = α: gravity only, body axes.
        let s = FlightSample {
            t_s: 0.0,
            vt_mps: 100.0,
            alpha_rad: alpha,
            ax_mps2: g * alpha.sin(),
            az_mps2: -g * alpha.cos(),
            qbar_pa: Some(qbar),
            mass_kg: m,
            Iyy_kgm2: 1e5,
            S_m2: s_ref,
            cbar_m: 2.0,
            ..Default::default()
        };
        let c = coefficient_sample(&s, 0.0, 100.0).unwrap();
        assert!((c.CL - m * g / (qbar * s_ref)).abs() < 1e-12);
        assert!(c.CD.abs() < 1e-12);
        assert!(c.Cm.abs() < 1e-15);
        // Thrust along body x adds to ax; the aerodynamic coefficients must not change.
        let t = 5000.0;
        let s2 = FlightSample { ax_mps2: s.ax_mps2 + t / m, thrust_n: t, ..s };
        let c2 = coefficient_sample(&s2, 0.0, 100.0).unwrap();
        assert!((c2.CL - c.CL).abs() < 1e-12 && (c2.CD - c.CD).abs() < 1e-12);
        // Thrust moment: q̇ = M_T / Iyy with zero aerodynamic moment gives Cm = 0.
        let s3 = FlightSample { thrust_arm_m: -0.5, ..s2 };
        let c3 = coefficient_sample(&s3, -0.5 * t / 1e5, 100.0).unwrap();
        assert!(c3.Cm.abs() < 1e-15);
        assert!((c3.qhat - 0.0).abs() < 1e-15 && (c3.v_ratio - 1.0).abs() < 1e-15);
    }

    #[test]
    fn analytic_vane_position_correction() {
        let s = FlightSample {
            vt_mps: 130.0,
            alpha_rad: 0.05,
            q_rad_s: 0.1,
            alpha_vane_x_m: 13.0,
            ..Default::default()
        };
        assert!((alpha_cg_rad(&s) - (0.05 + 13.0 * 0.1 / 130.0)).abs() < 1e-15);
    }
}
