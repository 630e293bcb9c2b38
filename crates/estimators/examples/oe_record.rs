//! Runs batch output error on a third-party flight-test record in `shared/flightdata` and
//! prints the iteration log, estimates with Cramér–Rao and coloured-residual σ, residuals and
//! the wall time (the measurements reported in the output-error closing note).
//!
//! `cargo run --release -p aeroident-estimators --example oe_record -- CASE [--x0] [--biases]`
//! with CASE one of `hfb320` (book model, test case 4), `hfb320-q` (the same with `Cm_q` on
//! `q c̄/2V`), `twin-otter` (017+018+019 as three manoeuvres, longitudinal), `attas-lon`
//! (fAttasElv1 + fAttasElv2), `attas-lat` (fAttasAilRud1), `attas-lat2` (fAttasAilRud1 +
//! fAttasAilRud2); every record is split into manoeuvres at its time gaps (each AilRud
//! record holds an aileron and a rudder manoeuvre). `--x0` estimates the initial states; `--book-start` (hfb320) starts from the book's
//! starting values; `--start-priors` from the generic priors; `--relaxation` uses Jategaonkar's
//! relaxation step; `--t1 S` keeps the first S seconds of each record; `--max-lag K` caps the
//! coloured-residual lag; `--biases` estimates output biases on
//! the rates, angular accelerations and specific forces.
#![allow(missing_docs)]

#[path = "../tests/all/common/records.rs"]
mod records;

use aeroident_estimators::AirDataSample;
use aeroident_estimators::flight_model::Output;
use aeroident_estimators::output_error::{InitialStates, OeConfig, OeError, fit, split_at_gaps};
use aeroident_estimators::vocabulary::{Coefficient as C, ModelStructure, Term as T};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = args.first().ok_or("usage: oe_record CASE [--x0] [--biases]")?;
    let flag = |f: &str| args.iter().any(|a| a == f);
    let dir = records::shared().join("flightdata");
    let jat = dir.join("jategaonkar_hfb320_attas/csv");
    let (mut manoeuvres, structure): (Vec<Vec<AirDataSample>>, ModelStructure) = match case.as_str()
    {
        "hfb320" => (vec![records::hfb320(&records::hfb320_path())?], records::hfb320_structure()),
        "hfb320-q" => (
            vec![records::hfb320(&records::hfb320_path())?],
            ModelStructure::empty()
                .with(C::CL, &[T::Bias, T::V, T::Alpha])
                .with(C::CD, &[T::Bias, T::V, T::Alpha])
                .with(C::Cm, &[T::Bias, T::V, T::Alpha, T::Q, T::De]),
        ),
        "twin-otter" => (
            ["017", "018", "019"]
                .iter()
                .map(|k| {
                    records::twin_otter(
                        &dir.join(format!("sidpac_twin_otter/csv/totter_lon_020213f1_{k}.csv")),
                    )
                })
                .collect::<Result<_, _>>()?,
            ModelStructure::empty()
                .with(C::CL, &[T::Bias, T::Alpha, T::De])
                .with(C::CD, &[T::Bias, T::Alpha])
                .with(C::Cm, &[T::Bias, T::Alpha, T::Q, T::De]),
        ),
        "attas-lon" => (
            vec![
                records::attas(&jat.join("fAttasElv1.csv"))?,
                records::attas(&jat.join("fAttasElv2.csv"))?,
            ],
            ModelStructure::empty()
                .with(C::CL, &[T::Bias, T::Alpha, T::De])
                .with(C::CD, &[T::Bias, T::Alpha])
                .with(C::Cm, &[T::Bias, T::Alpha, T::Q, T::De]),
        ),
        "attas-lat" => {
            (vec![records::attas(&jat.join("fAttasAilRud1.csv"))?], ModelStructure::lateral())
        }
        "attas-lat2" => (
            vec![
                records::attas(&jat.join("fAttasAilRud1.csv"))?,
                records::attas(&jat.join("fAttasAilRud2.csv"))?,
            ],
            ModelStructure::lateral(),
        ),
        other => return Err(format!("unknown case `{other}`")),
    };
    let mut cfg = OeConfig::new(structure);
    if flag("--x0") {
        cfg.initial_states = InitialStates::Estimate([true; 8]);
    }
    if flag("--biases") {
        let lon = [Output::Q, Output::Qdot, Output::Ax, Output::Az];
        let lat = [Output::P, Output::R, Output::Pdot, Output::Rdot, Output::Ay];
        cfg.output_biases = if case.starts_with("attas-lat") { lat.to_vec() } else { lon.to_vec() };
    }
    if flag("--relaxation") {
        cfg.step = aeroident_estimators::output_error::StepKind::Relaxation;
    }
    if flag("--book-start") {
        // The book's starting values (mDefCase04.m), structure order CL(0, α, V), CD(0, α, V),
        // Cm(0, α, δe, V, q0): they fit the data badly (README).
        cfg.start = aeroident_estimators::output_error::Start::Given(vec![
            -0.318267, 5.37576, 0.260317, 0.00567516, 0.674256, 0.00772612, 0.0498218, -0.498586,
            -0.990687, 0.0189182, -25.8439,
        ]);
    }
    if flag("--start-priors") {
        cfg.start = aeroident_estimators::output_error::Start::Priors;
    }
    if let Some(i) = args.iter().position(|a| a == "--t1") {
        let t1: f64 = args[i + 1].parse().map_err(|e| format!("--t1: {e}"))?;
        for m in manoeuvres.iter_mut() {
            let t0 = m[0].t_s;
            m.retain(|s| s.t_s - t0 <= t1);
        }
    }
    if let Some(i) = args.iter().position(|a| a == "--max-lag") {
        cfg.coloured_max_lag = Some(args[i + 1].parse().map_err(|e| format!("--max-lag: {e}"))?);
    }
    let slices: Vec<&[AirDataSample]> = manoeuvres.iter().flat_map(|m| split_at_gaps(m)).collect();
    let start = std::time::Instant::now();
    let res = fit(&slices, &cfg);
    let el = start.elapsed();
    match res {
        Ok(r) => print!("{r}"),
        Err(OeError::NotConverged { reason, result }) => {
            print!("{result}");
            println!("NOT CONVERGED: {reason:?}");
        }
        Err(e) => return Err(e.to_string()),
    }
    println!("wall time {:.1} ms", el.as_secs_f64() * 1e3);
    Ok(())
}
