//! Trim of the F-16 (SLJ 3rd ed. §3.6): steady wings-level flight (optionally climbing), a steady
//! coordinated turn and a steady pull-up.
//!
//! Unknowns `z = [throttle, δe_rad, α_rad, δa_rad, δr_rad, β_rad]`. The remaining state follows
//! from the constraints of SLJ §3.6:
//! * rate-of-climb constraint (SLJ eq. 3.6-3) gives θ from α, β, φ and the flight-path angle γ;
//! * coordinated-turn constraint (SLJ eq. 3.6-5) gives φ from the turn rate ψ̇, V, α, β, γ, and
//!   the body rates are `p = −ψ̇ sinθ, q = ψ̇ sinφ cosθ, r = ψ̇ cosφ cosθ`;
//! * pull-up: φ = 0, θ = α + γ, q = the given pitch rate, p = r = 0;
//! * engine in equilibrium: power = TGEAR(throttle).
//!
//! The cost is the thesis's trim index (2.31) `J = V̇² + α̇² + β̇² + ṗ² + q̇² + ṙ²`
//! (SI-free: ft/s², rad/s, rad/s²). It is minimised with argmin's Nelder–Mead simplex (a
//! derivative-free, well-kept optimiser that tolerates the tables' kinks), then polished with
//! damped Newton steps on the 6 residuals (central-difference Jacobian; the system is square),
//! which drives the residual to round-off. The reported [`crate::trim::F16Trim::cost`] is `J` at the
//! returned point.

use crate::ModelError;
use crate::f16::{
    ALPHA, ALT, BETA, F16, F16Controls, F16State, P, PHI, POW, Q, R, THETA, VT, tgear,
};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use nalgebra::{SMatrix, SVector};

/// The steady manoeuvre to trim for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrimManeuver {
    /// Wings-level, steady flight (climbing when γ ≠ 0).
    WingsLevel,
    /// Steady coordinated turn at a turn rate ψ̇ (rad/s, positive to the right).
    CoordinatedTurn {
        /// Turn rate ψ̇, rad/s.
        turn_rate_rad_s: f64,
    },
    /// Steady pull-up at the bottom of the manoeuvre, pitch rate q (rad/s).
    PullUp {
        /// Pitch rate q, rad/s.
        pitch_rate_rad_s: f64,
    },
}

/// A trim request.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrimCondition {
    /// Altitude, ft.
    pub alt_ft: f64,
    /// True airspeed, ft/s.
    pub vt_fps: f64,
    /// Flight-path angle γ, rad (0 = level).
    pub gamma_rad: f64,
    /// Manoeuvre.
    pub maneuver: TrimManeuver,
}

impl TrimCondition {
    /// Wings-level, level flight at `alt_ft`, `vt_fps`.
    pub fn level(alt_ft: f64, vt_fps: f64) -> Self {
        Self { alt_ft, vt_fps, gamma_rad: 0.0, maneuver: TrimManeuver::WingsLevel }
    }
}

/// A trimmed flight condition.
#[derive(Debug, Clone, PartialEq)]
pub struct F16Trim {
    /// Trimmed state (north = east = ψ = 0), order of [`crate::f16::STATE_NAMES`].
    pub state: F16State,
    /// Trimmed controls (still air).
    pub controls: F16Controls,
    /// Trim index (2.31) at the solution.
    pub cost: f64,
    /// `[V̇, α̇, β̇, ṗ, q̇, ṙ]` at the solution (ft/s², rad/s, rad/s, rad/s² ×3).
    pub residual: [f64; 6],
    /// Nelder–Mead iterations used.
    pub nelder_mead_iterations: u64,
    /// Newton polishing iterations used.
    pub newton_iterations: usize,
    /// Trim quantities outside the ranges the data are meant for (data `[ranges]`; the tables
    /// extrapolate there), e.g. `"alpha_deg = 45.6 outside [-10, 45]"`. Empty when all inside.
    pub out_of_range: Vec<String>,
}

impl F16Trim {
    /// Largest absolute residual.
    pub fn max_abs_residual(&self) -> f64 {
        self.residual.iter().fold(0.0f64, |m, r| m.max(r.abs()))
    }
}

/// θ from the rate-of-climb constraint, SLJ eq. (3.6-3).
pub fn theta_from_climb_constraint(
    alpha_rad: f64,
    beta_rad: f64,
    phi_rad: f64,
    gamma_rad: f64,
) -> f64 {
    let a = alpha_rad.cos() * beta_rad.cos();
    let b = phi_rad.sin() * beta_rad.sin() + phi_rad.cos() * alpha_rad.sin() * beta_rad.cos();
    let sg = gamma_rad.sin();
    ((a * b + sg * (a * a - sg * sg + b * b).max(0.0).sqrt()) / (a * a - sg * sg)).atan()
}

/// φ from the coordinated-turn constraint, SLJ eq. (3.6-5), for turn rate ψ̇ (rad/s), airspeed
/// (ft/s) and gravity `g_fps2`.
pub fn phi_from_turn_constraint(
    turn_rate_rad_s: f64,
    vt_fps: f64,
    g_fps2: f64,
    alpha_rad: f64,
    beta_rad: f64,
    gamma_rad: f64,
) -> f64 {
    let g = turn_rate_rad_s * vt_fps / g_fps2;
    let (ta, sb, cb) = (alpha_rad.tan(), beta_rad.sin(), beta_rad.cos());
    let a = 1.0 - g * ta * sb;
    let b = gamma_rad.sin() / cb;
    let c = 1.0 + g * g * cb * cb;
    let num = (a - b * b) + b * ta * (c * (1.0 - b * b) + g * g * sb * sb).max(0.0).sqrt();
    let den = a * a - b * b * (1.0 + c * ta * ta);
    (g * cb / alpha_rad.cos() * num / den).atan()
}

struct Problem<'a> {
    model: &'a F16,
    cond: TrimCondition,
}

impl Problem<'_> {
    fn state_controls(&self, z: &[f64; 6]) -> (F16State, F16Controls) {
        let [thtl, el, alpha, ail, rdr, beta] = *z;
        let c = &self.cond;
        let mut x = F16State::zeros();
        x[VT] = c.vt_fps;
        x[ALPHA] = alpha;
        x[BETA] = beta;
        x[ALT] = c.alt_ft;
        x[POW] = tgear(&self.model.data().engine, thtl);
        match c.maneuver {
            TrimManeuver::WingsLevel => {
                x[THETA] = theta_from_climb_constraint(alpha, beta, 0.0, c.gamma_rad);
            }
            TrimManeuver::CoordinatedTurn { turn_rate_rad_s: w } => {
                let phi = phi_from_turn_constraint(
                    w,
                    c.vt_fps,
                    self.model.data().mass.g_ft_per_s2,
                    alpha,
                    beta,
                    c.gamma_rad,
                );
                let theta = theta_from_climb_constraint(alpha, beta, phi, c.gamma_rad);
                x[PHI] = phi;
                x[THETA] = theta;
                x[P] = -w * theta.sin();
                x[Q] = w * phi.sin() * theta.cos();
                x[R] = w * phi.cos() * theta.cos();
            }
            TrimManeuver::PullUp { pitch_rate_rad_s } => {
                x[THETA] = alpha + c.gamma_rad;
                x[Q] = pitch_rate_rad_s;
            }
        }
        (x, F16Controls::new(thtl, el, ail, rdr))
    }

    fn residual(&self, z: &[f64; 6]) -> Result<SVector<f64, 6>, ModelError> {
        let (x, u) = self.state_controls(z);
        let xd = self.model.derivatives_with_increments(&x, &u, &self.model.increments)?;
        Ok(SVector::<f64, 6>::new(xd[VT], xd[ALPHA], xd[BETA], xd[P], xd[Q], xd[R]))
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let z: [f64; 6] = p.as_slice().try_into()?;
        // Outside the model's domain the cost is +inf: the simplex moves away from there.
        Ok(self.residual(&z).map(|r| r.norm_squared()).unwrap_or(f64::INFINITY))
    }
}

fn newton_polish(pb: &Problem<'_>, z0: [f64; 6]) -> Result<([f64; 6], usize), ModelError> {
    let mut z = z0;
    let mut r = pb.residual(&z)?;
    let mut it = 0;
    while it < 40 && r.amax() > 1e-13 {
        it += 1;
        let mut j = SMatrix::<f64, 6, 6>::zeros();
        for k in 0..6 {
            let h = 1e-7 * z[k].abs().max(1e-2);
            let mut zp = z;
            let mut zm = z;
            zp[k] += h;
            zm[k] -= h;
            let col = (pb.residual(&zp)? - pb.residual(&zm)?) / (2.0 * h);
            j.set_column(k, &col);
        }
        let Some(step) = j.lu().solve(&(-r)) else { break };
        // Backtracking on |r|².
        let mut lambda = 1.0;
        let mut improved = false;
        for _ in 0..30 {
            let mut zn = z;
            for k in 0..6 {
                zn[k] += lambda * step[k];
            }
            if let Ok(rn) = pb.residual(&zn)
                && rn.norm_squared() < r.norm_squared()
            {
                z = zn;
                r = rn;
                improved = true;
                break;
            }
            lambda *= 0.5;
        }
        if !improved {
            break;
        }
    }
    Ok((z, it))
}

/// The lowest altitude a trim is computed at, ft: below the lowest ground on Earth (the Dead
/// Sea shore, about −1,400 ft) with a margin. Between it and 0 ft the atmosphere extrapolates
/// and [`F16Trim::out_of_range`] says so; further down no aircraft flies.
pub const LOWEST_TRIM_ALT_FT: f64 = -2_000.0;

/// Trims `model` (its increments included) for `cond`.
///
/// A trim is **feasible** when the throttle is within 0–1 and each surface within its
/// position range (data `[ranges]`: ±25°, ±21.5°, ±30°); the search prefers feasible
/// solutions and an infeasible best one is an error. Other quantities outside the data's
/// ranges (α beyond −10…45°, Mach > 1, altitude > 50 000 ft) are listed in
/// [`F16Trim::out_of_range`] (the published 130 ft/s trim has α = 45.6°).
///
/// # Errors
/// [`ModelError::InvalidValue`] for a non-finite or non-positive airspeed, a non-finite
/// altitude / γ or an altitude below [`LOWEST_TRIM_ALT_FT`]; [`ModelError::NoConvergence`] when no start reaches a residual below 1e-8, or
/// the only trims found need throttle or surfaces beyond their ranges (the detail says which).
pub fn trim(model: &F16, cond: &TrimCondition) -> Result<F16Trim, ModelError> {
    if !(cond.vt_fps.is_finite() && cond.vt_fps > 0.0) {
        return Err(ModelError::InvalidValue {
            field: "vt_fps",
            value: cond.vt_fps,
            reason: "must be finite and > 0",
        });
    }
    for (f, v) in [("alt_ft", cond.alt_ft), ("gamma_rad", cond.gamma_rad)] {
        if !v.is_finite() {
            return Err(ModelError::InvalidValue { field: f, value: v, reason: "not finite" });
        }
    }
    if cond.alt_ft < LOWEST_TRIM_ALT_FT {
        return Err(ModelError::InvalidValue {
            field: "alt_ft",
            value: cond.alt_ft,
            reason: "below the lowest ground on Earth (the Dead Sea shore, about -1,400 ft; trims go down to -2,000 ft)",
        });
    }
    let pb = Problem { model, cond: *cond };
    let mut best: Option<(F16Trim, Vec<String>)> = None;
    // Starts: low, medium and high angle of attack (the textbook's range is −10…45°).
    for &(alpha0, thtl0) in &[(0.05, 0.2), (0.25, 0.4), (0.6, 0.8)] {
        let x0 = vec![thtl0, -0.02, alpha0, 0.0, 0.0, 0.0];
        let steps = [0.1, 0.05, 0.05, 0.02, 0.02, 0.02];
        let mut simplex = vec![x0.clone()];
        for k in 0..6 {
            let mut v = x0.clone();
            v[k] += steps[k];
            simplex.push(v);
        }
        let solver = NelderMead::new(simplex).with_sd_tolerance(1e-14).map_err(|e| {
            ModelError::NoConvergence { what: "trim (Nelder-Mead setup)", detail: e.to_string() }
        })?;
        let res = Executor::new(Problem { model, cond: *cond }, solver)
            .configure(|s| s.max_iters(4000))
            .run();
        let Ok(res) = res else { continue };
        let st = res.state();
        let Some(p) = st.get_best_param() else { continue };
        let nm_iters = st.get_iter();
        let Ok(z_nm): Result<[f64; 6], _> = p.as_slice().try_into() else { continue };
        let Ok((z, newton_it)) = newton_polish(&pb, z_nm) else { continue };
        let Ok(r) = pb.residual(&z) else { continue };
        let (state, controls) = pb.state_controls(&z);
        let (infeasible, out_of_range) = range_check(model, &state, &controls);
        let cand = F16Trim {
            state,
            controls,
            cost: r.norm_squared(),
            residual: [r[0], r[1], r[2], r[3], r[4], r[5]],
            nelder_mead_iterations: nm_iters,
            newton_iterations: newton_it,
            out_of_range,
        };
        // Prefer: converged, then feasible, then lower cost.
        let rank =
            |c: &F16Trim, inf: &[String]| (c.max_abs_residual() >= 1e-8, !inf.is_empty(), c.cost);
        let better = match &best {
            None => true,
            Some((b, binf)) => {
                rank(&cand, &infeasible).partial_cmp(&rank(b, binf))
                    == Some(std::cmp::Ordering::Less)
            }
        };
        let done = cand.max_abs_residual() < 1e-10 && infeasible.is_empty();
        if better {
            best = Some((cand, infeasible));
        }
        if done {
            break;
        }
    }
    match best {
        Some((b, inf)) if b.max_abs_residual() < 1e-8 && inf.is_empty() => Ok(b),
        Some((b, inf)) if b.max_abs_residual() < 1e-8 => Err(ModelError::NoConvergence {
            what: "trim",
            detail: format!("infeasible: {}", inf.join("; ")),
        }),
        Some((b, _)) => Err(ModelError::NoConvergence {
            what: "trim",
            detail: format!("best residual {:e} (cost {:e})", b.max_abs_residual(), b.cost),
        }),
        None => {
            Err(ModelError::NoConvergence { what: "trim", detail: "no start evaluated".into() })
        }
    }
}

/// (infeasible controls, other out-of-range quantities) of a candidate trim.
fn range_check(model: &F16, x: &F16State, u: &F16Controls) -> (Vec<String>, Vec<String>) {
    let rg = &model.data().ranges;
    let fmt =
        |name: &str, v: f64, r: [f64; 2]| format!("{name} = {v:.4} outside [{}, {}]", r[0], r[1]);
    let outside = |v: f64, r: [f64; 2]| !(r[0]..=r[1]).contains(&v);
    let mut infeasible = vec![];
    for (name, v, r) in [
        ("throttle", u.throttle, rg.throttle),
        ("elevator_deg", u.elevator_rad.to_degrees(), rg.elevator_deg),
        ("aileron_deg", u.aileron_rad.to_degrees(), rg.aileron_deg),
        ("rudder_deg", u.rudder_rad.to_degrees(), rg.rudder_deg),
    ] {
        if outside(v, r) {
            infeasible.push(fmt(name, v, r));
        }
    }
    let mut flagged = vec![];
    let mach = crate::atmosphere::air_data(&model.data().atmosphere, x[VT], x[ALT])
        .map(|a| a.mach)
        .unwrap_or(f64::NAN);
    for (name, v, r) in [
        ("alpha_deg", x[ALPHA].to_degrees(), rg.alpha_deg),
        ("beta_deg", x[BETA].to_degrees(), rg.beta_deg),
        ("altitude_ft", x[ALT], rg.altitude_ft),
        ("mach", mach, rg.mach),
    ] {
        if outside(v, r) {
            flagged.push(fmt(name, v, r));
        }
    }
    (infeasible, flagged)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_altitude_below_any_ground_is_refused_naming_it() {
        let f16 = F16::new(0.35).unwrap();
        let cond = |alt_ft| TrimCondition {
            alt_ft,
            vt_fps: 500.0,
            gamma_rad: 0.0,
            maneuver: TrimManeuver::WingsLevel,
        };
        let e = trim(&f16, &cond(-5e4)).unwrap_err().to_string();
        assert!(e.contains("alt_ft") && e.contains("-50000"), "{e}");
        // Just above the bound: trimmed, the altitude flagged as outside the data's range.
        let t = trim(&f16, &cond(-1_000.0)).unwrap();
        assert!(
            t.out_of_range.iter().any(|s| s.starts_with("altitude_ft")),
            "{:?}",
            t.out_of_range
        );
    }

    #[test]
    fn infeasible_trims_are_errors_naming_the_control() {
        let f16 = F16::new(0.35).unwrap();
        // 60 000 ft at 600 ft/s needs negative throttle in this model; 100 ft/s needs > 25° elevator.
        for (alt, vt, what) in [(60_000.0, 600.0, "throttle"), (0.0, 100.0, "elevator_deg")] {
            match trim(&f16, &TrimCondition::level(alt, vt)) {
                Err(ModelError::NoConvergence { detail, .. }) => {
                    assert!(detail.contains(what), "{detail}")
                }
                other => panic!("expected infeasible trim at {alt} ft {vt} ft/s, got {other:?}"),
            }
        }
        // The published 130 ft/s trim (SLJ Table 3.6-2) is feasible but has alpha > 45 deg: flagged.
        let t = trim(&f16, &TrimCondition::level(0.0, 130.0)).unwrap();
        assert!(t.out_of_range.iter().any(|s| s.starts_with("alpha_deg")), "{:?}", t.out_of_range);
    }

    #[test]
    fn analytic_constraints_reduce_to_simple_cases() {
        // Level, wings level, no sideslip: θ = α. Climb with β = φ = 0: θ = α + γ.
        assert!((theta_from_climb_constraint(0.1, 0.0, 0.0, 0.0) - 0.1).abs() < 1e-15);
        assert!((theta_from_climb_constraint(0.1, 0.0, 0.0, 0.2) - 0.3).abs() < 1e-12);
        // Coordinated turn at α = β = γ = 0: tanφ = ψ̇V/g.
        let phi = phi_from_turn_constraint(0.1, 500.0, 32.17, 0.0, 0.0, 0.0);
        assert!((phi.tan() - 0.1 * 500.0 / 32.17).abs() < 1e-12);
    }
}
