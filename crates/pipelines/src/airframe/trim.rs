//! Steady wings-level, level trim of a [`ModelFileAircraft`] (SLJ 3rd ed. §3.6: the six
//! accelerations `V̇, α̇, β̇, ṗ, q̇, ṙ` zeroed with φ = 0 and θ from the rate-of-climb
//! constraint, eq. 3.6-3, at γ = 0).
//!
//! Unknowns `z = (α, β, engine command, δe, δa, δr)`; residual
//! `r = (V̇/V, α̇, β̇, ṗ, q̇, ṙ)` (all 1/s or 1/s²). Newton's method with a central-difference
//! Jacobian and a halving line search on `|r|`: the aircraft's coefficients are linear in α, β
//! and the deflections (polynomial with the α products), so it converges in a few steps from
//! `α = 0.05`, the rest zero (throttle 0.5, a propeller at 300 rad/s).

use super::{AirframeState, ModelFileAircraft, Propulsion};
use aeroident_io::thrust_model::LawInput;
use aeroident_models::aircraft::{AircraftTrim, ControlVector};
use aeroident_models::rigid_body as rb;
use aeroident_models::trim::theta_from_climb_constraint;
use aeroident_models::{Dynamics, ModelError};
use nalgebra::{SMatrix, SVector};

/// The largest |α|, |β| and deflection a trim may return, rad (30°): beyond it the linear
/// derivatives of an identification are far outside the data they were fitted on.
pub const MAX_TRIM_ANGLE_RAD: f64 = 0.523_598_775_598_298_8;

/// Converged when every residual is below this, 1/s or 1/s².
const TOLERANCE: f64 = 1e-11;

/// Newton iterations at most.
const MAX_ITERATIONS: usize = 60;

type Z = SVector<f64, 6>;

/// The state and controls of unknowns `z` at `vt_mps`, `alt_m` (module doc).
fn point(z: &Z, vt_mps: f64, alt_m: f64) -> (AirframeState, ControlVector) {
    let mut x = AirframeState::zeros();
    x[rb::VT] = vt_mps;
    x[rb::ALPHA] = z[0];
    x[rb::BETA] = z[1];
    x[rb::THETA] = theta_from_climb_constraint(z[0], z[1], 0.0, 0.0);
    x[rb::ALT] = alt_m;
    (x, ControlVector::new(z[2], z[3], z[4], z[5]))
}

/// The residual `r(z)` (module doc).
fn residual(a: &ModelFileAircraft, z: &Z, vt: f64, alt: f64) -> Result<Z, ModelError> {
    let (x, u) = point(z, vt, alt);
    let xd = a.derivatives(0.0, &x, &u)?;
    Ok(Z::new(xd[rb::VT] / vt, xd[rb::ALPHA], xd[rb::BETA], xd[rb::P], xd[rb::Q], xd[rb::R]))
}

/// Which unknowns are held at 0: the surfaces the model has no derivative of (a partial test
/// card: an elevator-and-aileron UAV has no rudder to trim with).
pub fn held_surfaces(a: &ModelFileAircraft) -> [bool; 6] {
    let held = super::flyable::held_surfaces(&a.structure());
    let h = |s: &str| held.contains(&s);
    [false, false, false, h("de"), h("da"), h("dr")]
}

/// `Jz` solved for the step on the unknowns not `held` (those stay): a square system when
/// nothing is held, else least squares (a symmetric aircraft without a rudder balances
/// β̇, ṗ, ṙ with β and δa alone); `None` when the free columns are rank deficient.
fn solve_free(j: &SMatrix<f64, 6, 6>, r: &Z, held: &[bool; 6]) -> Option<Z> {
    let mut jf = *j;
    for (k, h) in held.iter().enumerate() {
        if *h {
            jf.column_mut(k).fill(0.0);
        }
    }
    let svd = jf.svd(true, true);
    let largest = svd.singular_values.max();
    let rank = svd.singular_values.iter().filter(|s| **s > 1e-10 * largest).count();
    if rank < held.iter().filter(|h| !**h).count() {
        return None;
    }
    svd.solve(&(-r), 1e-10 * largest).ok()
}

/// One Newton step from `z` with residual `r`: the new point and its residual.
fn newton_step(
    a: &ModelFileAircraft,
    z: &Z,
    r: &Z,
    (vt, alt): (f64, f64),
    held: &[bool; 6],
) -> Result<(Z, Z), ModelError> {
    let mut j = SMatrix::<f64, 6, 6>::zeros();
    for k in 0..6 {
        let h = 1e-6 * z[k].abs().max(1.0);
        let (mut zp, mut zm) = (*z, *z);
        zp[k] += h;
        zm[k] -= h;
        let col = (residual(a, &zp, vt, alt)? - residual(a, &zm, vt, alt)?) / (2.0 * h);
        j.set_column(k, &col);
    }
    let dz = solve_free(&j, r, held).ok_or_else(|| ModelError::NoConvergence {
        what: "wings-level trim",
        detail: "singular Jacobian: a control or state has no effect on the accelerations (missing derivative?)".into(),
    })?;
    let mut step = 1.0;
    for _ in 0..30 {
        let zn = z + dz * step;
        if let Ok(rn) = residual(a, &zn, vt, alt)
            && rn.norm() < r.norm()
        {
            return Ok((zn, rn));
        }
        step *= 0.5;
    }
    Err(ModelError::NoConvergence {
        what: "wings-level trim",
        detail: format!("no step lowers the residual {:.3e}", r.norm()),
    })
}

/// Steady wings-level, level flight of `aircraft` at true airspeed `vt_mps` (m/s) and
/// altitude `alt_m` (m) (module doc).
///
/// # Errors
/// [`ModelError::InvalidValue`] for a speed or altitude that is not finite and positive /
/// inside the atmosphere; [`ModelError::NoConvergence`] when Newton's method stalls, or the
/// solution needs an angle beyond [`MAX_TRIM_ANGLE_RAD`], a throttle outside 0–1 or a negative
/// thrust or propeller speed (no trim at that condition), naming the quantity.
pub fn trim_wings_level(
    aircraft: &ModelFileAircraft,
    vt_mps: f64,
    alt_m: f64,
) -> Result<AircraftTrim<{ super::N_STATES }>, ModelError> {
    if !(vt_mps.is_finite() && vt_mps > 0.0) {
        return Err(ModelError::InvalidValue {
            field: "vt_mps",
            value: vt_mps,
            reason: "must be finite and > 0",
        });
    }
    aircraft.air(alt_m)?;
    let command0 = match aircraft.airframe().propulsion {
        Propulsion::Commanded => 0.0,
        Propulsion::Law(law) if law.input() == LawInput::Throttle => 0.5,
        Propulsion::Law(_) => 300.0,
    };
    let held = held_surfaces(aircraft);
    let mut z = Z::new(0.05, 0.0, command0, 0.0, 0.0, 0.0);
    let mut r = residual(aircraft, &z, vt_mps, alt_m)?;
    let mut it = 0;
    while r.amax() > TOLERANCE {
        if it == MAX_ITERATIONS {
            return Err(ModelError::NoConvergence {
                what: "wings-level trim",
                detail: format!("residual {:.3e} after {it} Newton steps", r.amax()),
            });
        }
        (z, r) = newton_step(aircraft, &z, &r, (vt_mps, alt_m), &held)?;
        it += 1;
    }
    check_solution(aircraft, &z)?;
    let (state, controls) = point(&z, vt_mps, alt_m);
    Ok(AircraftTrim { state, controls, max_abs_residual: r.amax() })
}

/// Refuses a solution no aircraft can fly (see [`trim_wings_level`]).
fn check_solution(aircraft: &ModelFileAircraft, z: &Z) -> Result<(), ModelError> {
    let names = ["alpha_rad", "beta_rad", "", "elevator_rad", "aileron_rad", "rudder_rad"];
    let refuse = |what: &str, v: f64| ModelError::NoConvergence {
        what: "wings-level trim",
        detail: format!("no trim at this condition: it needs {what} = {v:.4}"),
    };
    for k in [0, 1, 3, 4, 5] {
        if z[k].abs() > MAX_TRIM_ANGLE_RAD {
            return Err(refuse(names[k], z[k]));
        }
    }
    let c = z[2];
    let ok = match aircraft.airframe().propulsion {
        Propulsion::Law(law) if law.input() == LawInput::Throttle => (0.0..=1.0).contains(&c),
        _ => c >= 0.0,
    };
    if ok { Ok(()) } else { Err(refuse(aircraft.airframe().propulsion.command(), c)) }
}
