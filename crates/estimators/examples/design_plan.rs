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
//! The 3-2-1-1 is built here; an application would take it from `aeroident_signals`.
#![allow(missing_docs)]

use aeroident_estimators::flight_model::{N_STATES, Output};
use aeroident_estimators::output_error::InitialStates;
use aeroident_estimators::output_error::design::{
    DesignPlan, DesignResult, FlightCondition, PlannedInputs, Sensor, predict_crb, trim_biases,
};
use aeroident_estimators::vocabulary::{Coefficient as C, ModelStructure, Param, Term as T};
use aeroident_estimators::{AircraftConstants, EstimatorError};

const DT: f64 = 0.02;
const DEG: f64 = std::f64::consts::PI / 180.0;

fn three_two_one_one(starts_s: &[f64], unit_s: f64, amp: f64, duration_s: f64) -> Vec<f64> {
    let n = (duration_s / DT).round() as usize + 1;
    (0..n)
        .map(|i| {
            starts_s
                .iter()
                .map(|t0| match (i as f64 * DT - t0) / unit_s {
                    u if (0.0..3.0).contains(&u) => amp,
                    u if (3.0..5.0).contains(&u) => -amp,
                    u if (5.0..6.0).contains(&u) => amp,
                    u if (6.0..7.0).contains(&u) => -amp,
                    _ => 0.0,
                })
                .sum()
        })
        .collect()
}

fn main() -> Result<(), EstimatorError> {
    let constants = AircraftConstants {
        mass_kg: 9300.0,
        S_m2: 27.87,
        cbar_m: Some(3.45),
        b_m: Some(9.14),
        Ixx_kgm2: Some(16_660.0),
        Iyy_kgm2: Some(77_430.0),
        Izz_kgm2: Some(90_940.0),
        Ixz_kgm2: Some(1_437.0),
        thrust_arm_m: 0.0,
        thrust_incidence_rad: 0.0,
        v0_mps: Some(180.0),
    };
    let condition = FlightCondition::level(180.0, 0.06, 0.75, 18_000.0);
    let st = ModelStructure::longitudinal();
    let mut theta = vec![0.0; st.n_params()];
    for (c, t, v) in [
        (C::CL, T::Alpha, 4.2),
        (C::CL, T::Q, 6.0),
        (C::CL, T::De, 0.45),
        (C::CD, T::Alpha, 0.35),
        (C::CD, T::De, 0.06),
        (C::Cm, T::Alpha, -0.7),
        (C::Cm, T::Q, -14.0),
        (C::Cm, T::De, -0.9),
    ] {
        if let Some(i) = st.index_of(Param::new(c, t)) {
            theta[i] = v;
        }
    }
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
                de_rad: three_two_one_one(starts, 0.4, amp_deg * DEG, duration_s),
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
