//! Experiment design before flight: predicted Cramér–Rao σ of the longitudinal derivatives of
//! the F-16-like aircraft of the EKF and output-error tests (V = 180 m/s, α = θ = 0.06 rad,
//! ρ = 0.75 kg/m³, T = 18 kN, biases trimmed there) for an elevator 3-2-1-1 (unit 0.4 s, from
//! t = 1 s) at 1°, 2° and 4°, in a 10 s and a 20 s record, and for two 3-2-1-1 (at 1 s and
//! 11 s) in 20 s. Outputs V, α, θ, q, ax, az, q̇ with white sensor noise σ 0.3 m/s,
//! 0.002 rad, 0.003 rad, 0.003 rad/s, 0.08 m/s², 0.08 m/s², 0.05 rad/s²; initial states
//! estimated with the parameters, as a fit would.
//!
//! `cargo run --release -p aeroident-estimators --example design_plan`
//!
//! The aircraft and the 3-2-1-1 are the unit tests' (`src/test_aircraft.rs`); an application
//! would take the 3-2-1-1 from `aeroident_signals`.
#![allow(missing_docs)]

#[path = "../src/test_aircraft.rs"]
mod test_aircraft;

use aeroident_estimators::EstimatorError;
use aeroident_estimators::flight_model::{N_STATES, Output};
use aeroident_estimators::output_error::InitialStates;
use aeroident_estimators::output_error::design::{
    DesignPlan, DesignResult, FlightCondition, PlannedInputs, Sensor, predict_crb, trim_biases,
};
use aeroident_estimators::vocabulary::ModelStructure;
use test_aircraft::{ALPHA0, RHO, THRUST, V0, three_two_one_one};

const DT: f64 = 0.02;
const DEG: f64 = std::f64::consts::PI / 180.0;

fn main() -> Result<(), EstimatorError> {
    let constants = test_aircraft::constants();
    let condition = FlightCondition::level(V0, ALPHA0, RHO, THRUST);
    let st = ModelStructure::longitudinal();
    let theta = test_aircraft::derivatives(&st);
    let theta = trim_biases(&st, &theta, &constants, &condition)?;
    let sensors = [
        (Output::Vt, 0.3),
        (Output::Alpha, 0.002),
        (Output::Theta, 0.003),
        (Output::Q, 0.003),
        (Output::Ax, 0.08),
        (Output::Az, 0.08),
        (Output::Qdot, 0.05),
    ]
    .map(|(output, sigma)| Sensor { output, sigma })
    .to_vec();
    let cases: [(&str, f64, f64, &[f64]); 6] = [
        ("1° 10 s", 1.0, 10.0, &[1.0]),
        ("2° 10 s", 2.0, 10.0, &[1.0]),
        ("4° 10 s", 4.0, 10.0, &[1.0]),
        ("1° 20 s", 1.0, 20.0, &[1.0]),
        ("2° 20 s", 2.0, 20.0, &[1.0]),
        ("2° 2×3211 20 s", 2.0, 20.0, &[1.0, 11.0]),
    ];
    let mut results: Vec<(&str, DesignResult)> = Vec::new();
    for (label, amp_deg, duration_s, starts) in cases {
        let mut plan = DesignPlan::new(
            st,
            theta.clone(),
            constants,
            condition,
            vec![PlannedInputs {
                dt_s: DT,
                de_rad: three_two_one_one(starts, 0.4, amp_deg * DEG, duration_s, DT),
                ..Default::default()
            }],
            sensors.clone(),
        );
        plan.initial_states = InitialStates::Estimate([true; N_STATES]);
        results.push((label, predict_crb(&plan)?));
    }
    println!("Predicted σ_CRB (σ/|θ| in %), elevator 3-2-1-1, unit 0.4 s, 50 Hz");
    print!("{:<10} {:>9}", "parameter", "θ");
    for (label, _) in &results {
        print!(" {label:>20}");
    }
    println!();
    for (i, value) in theta.iter().enumerate() {
        let name = &results[0].1.names[i];
        print!("{name:<10} {value:>9.4}");
        for (_, r) in &results {
            let cell = match (r.sigma[i], r.relative_sigma[i]) {
                (Some(s), Some(rel)) => format!("{s:.5} ({:.2}%)", 100.0 * rel),
                (Some(s), None) => format!("{s:.5}"),
                (None, _) => "not identifiable".to_string(),
            };
            print!(" {cell:>20}");
        }
        println!();
    }
    print!("{:<20}", "peak |Δα| deg");
    for (_, r) in &results {
        let j = r.outputs.iter().position(|o| *o == Output::Alpha).unwrap_or(0);
        print!(" {:>20.2}", r.output_excursion[j] / DEG);
    }
    println!();
    print!("{:<20}", "peak |q| deg/s");
    for (_, r) in &results {
        let j = r.outputs.iter().position(|o| *o == Output::Q).unwrap_or(0);
        print!(" {:>20.2}", r.output_excursion[j] / DEG);
    }
    println!();
    print!("{:<20}", "condition number");
    for (_, r) in &results {
        print!(" {:>20.3e}", r.condition_number);
    }
    println!();
    Ok(())
}
