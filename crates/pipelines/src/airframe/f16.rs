//! The Stevens–Lewis F-16 as a [`FlyableAircraft`]: flown by the same `sim`, experiment and
//! design as a model-file aircraft, its record in SI, identified through the replay's
//! estimators as a flight log is.
//!
//! - States: its own 13 (ft, ft/s; the engine's power last), the rigid body's 12 converted to
//!   SI for the record.
//! - Channels: its own evaluation (SLJ 3rd ed. §3.5): thrust, dynamic pressure and Mach of its
//!   textbook air-data computer, density `2 q̄ / V²` from them, and the specific force of its
//!   load factors at its own gravity (32.17 ft/s²).
//! - Engine command: the throttle (0–1), through its power lag.
//! - Derivatives flown: the local derivatives at the trim ([`local_derivatives`]) in the
//!   decoupled linear structure [`f16_local_structure`]: for `CX`, `CZ` and `Cm` a bias, α, q̂
//!   and δe; for `CY`, `Cl` and `Cn` a bias, β, p̂, r̂, δa and δr. At a wings-level trim those
//!   are the terms whose local derivative is not zero (`CZ`'s β and `Cl`'s α enter as
//!   products with β, zero at β = 0).
//! - Constants: its mass, inertia and geometry; thrust along body x through the CG (no arm,
//!   no incidence). The engine's angular momentum (SLJ `heng`) stays in its equations and
//!   out of the identification model.
//! - No actuators: the surfaces are the commands (the `f16 sim` command flies its actuators).

use super::flyable::airframe_constants;
use super::{AirframeOutputs, AirframeState, Atmosphere, FlyableAircraft};
use crate::aircraft::truth::local_derivatives;
use aeroident_estimators::AircraftConstants;
use aeroident_estimators::vocabulary::{Coefficient, ModelStructure, Term};
use aeroident_models::ModelError;
use aeroident_models::aircraft::{Aircraft, AircraftTrim, ControlVector};
use aeroident_models::f16::{self, AeroIncrements, F16, F16State};
use aeroident_models::rigid_body as rb;
use aeroident_physics::units::{M_PER_FT, N_PER_LBF, PA_PER_PSF};

/// The structure of the F-16's local derivatives (module doc).
pub fn f16_local_structure() -> ModelStructure {
    use Coefficient::*;
    let lon = [Term::Bias, Term::Alpha, Term::Q, Term::De];
    let lat = [Term::Bias, Term::Beta, Term::P, Term::R, Term::Da, Term::Dr];
    let mut s = ModelStructure::empty();
    for (c, terms) in [(CX, &lon[..]), (CY, &lat), (CZ, &lon), (Cl, &lat), (Cm, &lon), (Cn, &lat)] {
        s = s.with(c, terms);
    }
    s
}

impl FlyableAircraft<{ f16::N_STATES }> for F16 {
    fn rigid_body_si(&self, x: &F16State) -> AirframeState {
        let mut s = AirframeState::from_fn(|i, _| x[i]);
        for k in [rb::VT, rb::NORTH, rb::EAST, rb::ALT] {
            s[k] *= M_PER_FT;
        }
        s
    }

    fn outputs(
        &self,
        t_s: f64,
        x: &F16State,
        u: &ControlVector,
    ) -> Result<AirframeOutputs, ModelError> {
        // One evaluation gives the derivative and the channels (the same increments as
        // `derivatives` at `t_s`).
        let (xd, o) = self.evaluate(x, &self.input(u), &self.increments_at(t_s))?;
        let xdot = self.rigid_body_si(&xd);
        let g = self.data().mass.g_ft_per_s2 * M_PER_FT;
        let vt = x[rb::VT] * M_PER_FT;
        let qbar_pa = o.qbar_psf * PA_PER_PSF;
        Ok(AirframeOutputs {
            xdot,
            accel_mps2: [o.nx_g * g, o.ny_g * g, -o.nz_g * g],
            thrust_n: o.thrust_lbf * N_PER_LBF,
            qbar_pa,
            rho_kgpm3: 2.0 * qbar_pa / (vt * vt),
            mach: o.mach,
        })
    }

    fn constants(&self) -> AircraftConstants {
        airframe_constants(&self.mass(), &self.geometry(), (0.0, 0.0), None)
    }

    fn flown_structure(&self) -> ModelStructure {
        f16_local_structure()
    }

    fn flown_values(&self, trim: &AircraftTrim<{ f16::N_STATES }>) -> Result<Vec<f64>, ModelError> {
        let u = self.input(&trim.controls);
        let ld = local_derivatives(self, &trim.state, &u, &AeroIncrements::zero())?;
        let s = f16_local_structure();
        s.params()
            .map(|p| {
                ld.truth(&s, p).ok_or(ModelError::InvalidValue {
                    field: "trim",
                    value: f64::NAN,
                    reason: "a local derivative of the structure has no single value there",
                })
            })
            .collect()
    }

    fn engine_column(&self) -> &'static str {
        "throttle"
    }

    fn density_kgpm3(&self, alt_m: f64) -> Result<f64, ModelError> {
        Ok(Atmosphere::Textbook(self.data().atmosphere.clone()).air(alt_m)?.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airframe::flyable::specific_force;
    use crate::airframe::tests::{as_model_file, f16_trim};

    /// The F-16's load factors (its force sum over its mass) are the kinematic specific force
    /// of its own state derivative, away from trim, to the difference of its gravity (32.17
    /// ft/s²) from standard gravity (1.3e-3 m/s²).
    #[test]
    fn the_f16_load_factors_are_its_kinematic_specific_force() {
        let (f, t) = f16_trim();
        let mut x = t.state;
        crate::airframe::tests::off_trim(&mut x);
        let u = t.controls.to_vector() + ControlVector::new(0.1, 0.01, -0.02, 0.01);
        let o = FlyableAircraft::outputs(&f, 0.0, &x, &u).unwrap();
        let kinematic = specific_force(&f.rigid_body_si(&x), &o.xdot);
        for (k, (a, b)) in o.accel_mps2.iter().zip(kinematic).enumerate() {
            assert!((a - b).abs() < 2e-3, "axis {k}: load factors {a}, kinematic {b}");
        }
    }

    /// The F-16 and the model-file aircraft of its local derivatives (the same trim, the same
    /// doublets, the same sensors and seeds) go through one experiment: output error on each
    /// record scores each against the values it flies, and the F-16's primary derivatives come
    /// within 10 % of its local derivatives and within 2 % of the twin's fit (the tables'
    /// curvature over the flown α and β ranges, the engine lag and the engine's angular
    /// momentum are what the derivative model leaves out; measured 2.6 % and 0.9 % at most).
    #[test]
    fn the_f16_runs_the_experiment_of_any_aircraft() {
        use crate::montecarlo::aircraft::tests::experiment_with;
        let (f, t) = f16_trim();
        let f16 = experiment_with(f.clone(), &["oe"]);
        let twin = experiment_with(as_model_file(&f, &t), &["oe"]);
        let (a, b) = (f16.fly(&f16.scenario).unwrap(), twin.fly(&twin.scenario).unwrap());
        assert_eq!(
            a.sim.table.columns,
            b.sim
                .table
                .columns
                .iter()
                .map(|c| { if c == "thrust_cmd_n" { "throttle".to_string() } else { c.clone() } })
                .collect::<Vec<_>>()
        );
        let (ea, eb) = (&a.estimators[0], &b.estimators[0]);
        assert_eq!((ea.failure.as_ref(), eb.failure.as_ref()), (None, None));
        for (p, q) in ea.params.iter().zip(&eb.params) {
            let (truth, twin_truth) = (p.result.reference.unwrap(), q.result.reference.unwrap());
            let (e, et) = (p.result.estimate.unwrap(), q.result.estimate.unwrap());
            eprintln!(
                "{:>9} local {truth:10.4} (twin {twin_truth:10.4}) F-16 oe {e:10.4} twin oe {et:10.4}",
                p.result.name
            );
            assert_eq!(p.result.name, q.result.name);
            assert!((truth - twin_truth).abs() <= 1e-9 * (1.0 + truth.abs()), "{}", p.result.name);
            if p.primary {
                let rel = (e - truth).abs() / truth.abs();
                assert!(rel < 0.10, "{}: {e} against {truth} ({rel})", p.result.name);
                let apart = (e - et).abs() / et.abs();
                assert!(apart < 0.02, "{}: F-16 {e}, twin {et}", p.result.name);
            }
        }
    }
}
