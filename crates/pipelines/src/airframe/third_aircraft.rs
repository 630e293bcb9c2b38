//! A third aircraft type added as one `impl Aircraft` and one `impl FlyableAircraft`: a
//! linear state-space aircraft `ẋ = f0 + A (x − x0) + B (u − u0)` (SI states of
//! [`STATE_NAMES`], commanded thrust, standard atmosphere), here the linearization of the F-16's
//! local derivatives flown as a model-file aircraft. With nothing else written for it, it is
//! trimmed and linearized ([`linearize_level`]), flown into a record ([`crate::sim::aircraft::run`]),
//! identified by the replay's estimators in one run and in a Monte Carlo campaign
//! ([`crate::montecarlo::aircraft::AircraftExperiment`]), and given a designed input
//! ([`crate::export::design::design_for_aircraft`]). Each result is checked against the
//! nonlinear aircraft it was linearized from, an independent computation: they agree to the
//! order of the perturbations the flights make.

use super::flyable::isa_outputs;
use super::tests::{ALT_FT, VT_FPS, as_model_file, f16_trim};
use super::*;
use aeroident_models::aircraft::{AircraftMass, ReferenceGeometry, linearize_level};
use aeroident_physics::units::M_PER_FT;
use nalgebra::SMatrix;

/// A linear state-space aircraft (module doc).
#[derive(Debug, Clone)]
struct LinearAircraft {
    x0: AirframeState,
    u0: ControlVector,
    f0: AirframeState,
    a: SMatrix<f64, N_STATES, N_STATES>,
    b: SMatrix<f64, N_STATES, 4>,
    mass: AircraftMass,
    geometry: ReferenceGeometry,
    constants: aeroident_estimators::AircraftConstants,
    structure: ModelStructure,
    theta: Vec<f64>,
}

impl Dynamics<N_STATES> for LinearAircraft {
    type Input = ControlVector;

    fn derivatives(
        &self,
        _t_s: f64,
        x: &AirframeState,
        u: &ControlVector,
    ) -> Result<AirframeState, ModelError> {
        Ok(self.f0 + self.a * (x - self.x0) + self.b * (u - self.u0))
    }
}

impl Aircraft<N_STATES> for LinearAircraft {
    fn name(&self) -> String {
        "linear state-space aircraft".into()
    }

    fn mass(&self) -> AircraftMass {
        self.mass
    }

    fn geometry(&self) -> ReferenceGeometry {
        self.geometry
    }

    fn engine_command(&self) -> &'static str {
        "thrust_n"
    }

    fn length_unit_m(&self) -> f64 {
        1.0
    }

    fn state_names(&self) -> &'static [&'static str; N_STATES] {
        &STATE_NAMES
    }

    fn input(&self, u: &ControlVector) -> ControlVector {
        *u
    }

    /// Only its own trim: a linear model holds about the point it was taken at.
    fn trim_level(&self, vt_mps: f64, alt_m: f64) -> Result<AircraftTrim<N_STATES>, ModelError> {
        if (vt_mps - self.x0[rb::VT]).abs() > 1e-6 || (alt_m - self.x0[rb::ALT]).abs() > 1e-3 {
            return Err(ModelError::InvalidValue {
                field: "vt_mps",
                value: vt_mps,
                reason: "a linear aircraft trims only at the point it was linearized about",
            });
        }
        let r = self.f0;
        let residual = [rb::VT, rb::ALPHA, rb::BETA, rb::P, rb::Q, rb::R].map(|k| r[k].abs());
        Ok(AircraftTrim {
            state: self.x0,
            controls: self.u0,
            max_abs_residual: residual.into_iter().fold(0.0, f64::max),
        })
    }
}

impl FlyableAircraft<N_STATES> for LinearAircraft {
    fn rigid_body_si(&self, x: &AirframeState) -> AirframeState {
        *x
    }

    fn outputs(
        &self,
        t_s: f64,
        x: &AirframeState,
        u: &ControlVector,
    ) -> Result<AirframeOutputs, ModelError> {
        isa_outputs(x, self.derivatives(t_s, x, u)?, u[0])
    }

    fn constants(&self) -> aeroident_estimators::AircraftConstants {
        self.constants
    }

    fn flown_structure(&self) -> ModelStructure {
        self.structure
    }

    fn flown_values(&self, _trim: &AircraftTrim<N_STATES>) -> Result<Vec<f64>, ModelError> {
        Ok(self.theta.clone())
    }
}

/// The F-16's local derivatives as a model-file aircraft in the standard atmosphere, and the
/// linear aircraft of its linearization at the thesis condition.
fn aircraft_pair() -> (ModelFileAircraft, LinearAircraft) {
    let (f, t) = f16_trim();
    let source = as_model_file(&f, &t).with_atmosphere(Atmosphere::Isa);
    let l = linearize_level(&source, VT_FPS * M_PER_FT, ALT_FT * M_PER_FT).unwrap();
    let (x0, u0) = (l.trim.state, l.trim.controls);
    let linear = LinearAircraft {
        x0,
        u0,
        f0: source.derivatives(0.0, &x0, &u0).unwrap(),
        a: l.linear.a,
        b: l.linear.b,
        mass: source.mass(),
        geometry: source.geometry(),
        constants: source.constants(),
        structure: source.structure(),
        theta: source.theta().to_vec(),
    };
    (source, linear)
}

/// The kinematic specific force equals the nonlinear aircraft's own force sum over its mass
/// away from trim (pitching, rolling, sideslipping, banked): two computations that share only
/// the states.
#[test]
fn the_kinematic_specific_force_is_the_force_sum_over_the_mass() {
    let (source, linear) = aircraft_pair();
    let mut x = linear.x0;
    super::tests::off_trim(&mut x);
    let u = linear.u0 + ControlVector::new(500.0, 0.01, -0.02, 0.01);
    let own = source.outputs(0.0, &x, &u).unwrap();
    let kinematic = flyable::specific_force(&x, &own.xdot);
    for (k, (a, b)) in own.accel_mps2.iter().zip(kinematic).enumerate() {
        assert!((a - b).abs() < 1e-9 * (1.0 + a.abs()), "axis {k}: force sum {a}, kinematic {b}");
    }
}

/// Linearized again, the linear aircraft gives its own matrices and the source's modes.
#[test]
fn the_third_aircraft_linearizes_to_its_matrices_and_the_sources_modes() {
    let (source, linear) = aircraft_pair();
    let (vt, alt) = (VT_FPS * M_PER_FT, ALT_FT * M_PER_FT);
    let own = linearize_level(&linear, vt, alt).unwrap();
    let src = linearize_level(&source, vt, alt).unwrap();
    let scale = linear.a.amax();
    assert!(
        (own.linear.a - linear.a).amax() < 1e-6 * scale,
        "{}",
        (own.linear.a - linear.a).amax()
    );
    assert!((own.linear.b - linear.b).amax() < 1e-6 * linear.b.amax());
    assert_eq!(own.modes.len(), src.modes.len());
    for (m, n) in own.modes.iter().zip(&src.modes) {
        assert_eq!(m.name, n.name);
        let rel = (m.eigenvalue - n.eigenvalue).norm() / n.eigenvalue.norm().max(1e-3);
        assert!(rel < 1e-6, "{:?}: {} against {}", m.name, m.eigenvalue, n.eigenvalue);
    }
}

/// `sim` flies the linear aircraft through 1° and 2° doublets on each surface: its states
/// follow the nonlinear source's within 10 % of each one's excursion, and so does its specific
/// force while the aircraft flies wings level (the elevator doublet, the first 4 s). The
/// neglected terms are products of perturbations, the largest being the bank angle (0.16 rad
/// at most): relative differences of that order are the linearization's, while a wrong
/// column of `A` or `B` would be of order one (measured: 0.5–5.5 %). Rolling and
/// sideslipping, the kinematic `az` holds products the linear α̇ row has no term for
/// (`p β V`: 0.4 rad/s × 0.02 rad × 208 m/s ≈ 1.6 m/s²; gravity's `g (1 − cos φ)`), and the two
/// part by more. Both records carry the same columns.
#[test]
fn the_third_aircraft_flies_the_sources_record_to_first_order() {
    let (source, linear) = aircraft_pair();
    let x = crate::montecarlo::aircraft::tests::experiment_with(linear, &["oe"]);
    let mut clean = x.scenario.clone();
    clean.sensor.clear();
    let base = std::path::Path::new(".");
    let lin = crate::sim::aircraft::run(&x.aircraft, &clean, base).unwrap();
    let src = crate::sim::aircraft::run(&source, &clean, base).unwrap();
    assert_eq!(lin.table.columns, src.table.columns);
    let level = (4.0 / clean.run.dt_s) as usize;
    let channels =
        ["alpha_rad", "beta_rad", "p_rad_s", "q_rad_s", "r_rad_s", "phi_rad", "theta_rad"];
    let spans = channels.map(|c| (c, usize::MAX)).into_iter().chain([("az_mps2", level)]);
    for (name, end) in spans {
        let a = lin.table.column(name).unwrap();
        let b = src.table.column(name).unwrap();
        let (a, b) = (&a[..end.min(a.len())], &b[..end.min(b.len())]);
        let excursion = b.iter().fold(0f64, |m, v| m.max((v - b[0]).abs()));
        let worst = a.iter().zip(b).fold(0f64, |m, (p, q)| m.max((p - q).abs()));
        eprintln!("{name:>10}: excursion {excursion:.3e}, largest difference {worst:.3e}");
        assert!(worst <= 0.10 * excursion, "{name}: {worst} against excursion {excursion}");
    }
}

/// `run` and `montecarlo` on the linear aircraft: output error fits the records the
/// replay reads, as for any aircraft; over 8 noisy flights every primary derivative's mean is
/// within 3 standard errors of the scatter plus 3 % of the source's value (the first-order
/// model's own departure) of the value flown.
#[test]
fn the_third_aircraft_runs_the_monte_carlo_of_any_aircraft() {
    let (_, linear) = aircraft_pair();
    let x = crate::montecarlo::aircraft::tests::experiment_with(linear, &["oe"]);
    let runs = 8;
    let c = x.campaign_watched(runs, 11, None, &|| {}).unwrap();
    assert_eq!(c.status, crate::montecarlo::STATUS_COMPLETE, "{:?}", c.status_reason);
    let oe = &c.estimators[0];
    assert_eq!(oe.runs_ok as u64, runs, "{:?}", oe.failed_runs);
    let primaries = oe
        .parameters
        .iter()
        .filter(|p| crate::aircraft::summary::PRIMARY_DERIVATIVES.contains(&p.name.as_str()));
    for p in primaries {
        let truth = x.truth(&p.name).unwrap();
        let (bias, scatter) = (p.bias.unwrap(), p.scatter.unwrap());
        let allowed = 3.0 * scatter / (runs as f64).sqrt() + 0.03 * truth.abs();
        eprintln!("{:>9} truth {truth:10.4} bias {bias:+.3e} scatter {scatter:.2e}", p.name);
        assert!(bias.abs() <= allowed, "{}: bias {bias}, allowed {allowed}", p.name);
    }
}

/// `design` for the linear aircraft predicts the Cramér–Rao σ it predicts for the source at
/// the same condition: a design reads the aircraft only through its trim, derivatives,
/// constants and flight condition, which the two share.
#[test]
fn the_third_aircraft_gets_the_sources_design() {
    use crate::export::design::{Surface, design_for_aircraft};
    let (source, linear) = aircraft_pair();
    let spec = super::tests::design_spec(vec![Surface::De, Surface::Da]);
    let (vt, alt) = (VT_FPS * M_PER_FT, ALT_FT * M_PER_FT);
    let own = design_for_aircraft(&spec, &linear, vt, alt).unwrap();
    let src = design_for_aircraft(&spec, &source, vt, alt).unwrap();
    assert_eq!(own.crb.names, src.crb.names);
    let pairs = own.crb.names.iter().zip(own.crb.sigma.iter().zip(&src.crb.sigma));
    for (n, (a, b)) in pairs {
        match (a, b) {
            (Some(a), Some(b)) => assert!((a / b - 1.0).abs() < 1e-6, "{n}: {a} against {b}"),
            _ => assert_eq!(a, b, "{n}: a bound for one aircraft and not the other"),
        }
    }
    assert!(own.crb.sigma.iter().flatten().count() >= 10, "{:?}", own.crb.sigma);
}
