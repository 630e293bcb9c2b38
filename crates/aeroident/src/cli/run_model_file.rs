//! `aeroident run SCENARIO --aircraft MODEL.toml --map M [--summary S] [--estimator rls,oe]`:
//! one flight of a model-file aircraft with the scenario's sensor noise, every estimator run on
//! its record and scored against the values flown
//! ([`aeroident_pipelines::montecarlo::aircraft`]).
//!
//! Writes into `--out` (default `./aeroident-out/<model file's stem>`): the record and its mapping, the
//! states and controls figures and `report.html` (as `aeroident sim`), and `summary.json`
//! ([`aeroident_pipelines::montecarlo::aircraft::FlownRun::document`]); prints one table per
//! estimator: estimate ± σ, the value flown, the error %, the status and the time to ±10 %.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::aircraft_args::AircraftArgs;
use aeroident_pipelines::montecarlo::EstimatorRun;
use aeroident_pipelines::montecarlo::aircraft::FlownRun;

/// Runs one model-file flight (module doc): `scenario` flown by `aircraft`, `estimators`
/// (default `oe`) on its record, outputs into `out`.
///
/// # Errors
/// Files that do not describe a flyable aircraft or scenario, an unknown estimator, a flight
/// that fails, unwritable outputs.
pub fn execute(
    aircraft: &AircraftArgs,
    scenario: &Path,
    estimators: Option<&[String]>,
    out: Option<PathBuf>,
) -> anyhow::Result<()> {
    let x = super::aircraft_args::experiment(aircraft, scenario, estimators)?;
    let name = {
        use aeroident_models::aircraft::Aircraft as _;
        x.aircraft.name()
    };
    let stem = Path::new(&aircraft.aircraft).file_stem().and_then(|s| s.to_str());
    let dir = out.unwrap_or_else(|| {
        let safe = stem.and_then(|s| crate::outdir::safe_component(s).ok()).unwrap_or("run");
        PathBuf::from("aeroident-out").join(safe)
    });
    let mut inputs = aircraft.files()?;
    inputs.push(scenario);
    // Lock and clear the directory first, so a failing run leaves no old outputs.
    let mut od = crate::outdir::OutputDir::open(&dir, "run", &inputs)?;
    let spin = crate::progress::spinner(&format!("run `{name}`"));
    let flown = x.fly(&x.scenario);
    spin.finish_and_clear();
    let flown = flown.with_context(|| format!("{name} flying `{}`", scenario.display()))?;
    crate::sim::write_aircraft_outputs(&flown.sim, &flown.mapping, &mut od)?;
    let summary = flown.document(x.scenario.run.seed);
    od.write_bytes("summary.json", serde_json::to_string_pretty(&summary)?.as_bytes())?;
    od.finish();
    super::print_stdout(&format!("{}wrote {}", results_text(&flown), dir.display()))?;
    all_failed(&flown)
}

/// A run whose every estimator failed has no result, whatever it wrote (the record, and the
/// summary saying why): an error, as `montecarlo` gives for the same flight.
fn all_failed(flown: &FlownRun) -> anyhow::Result<()> {
    let failures: Vec<String> = flown
        .estimators
        .iter()
        .filter_map(|e| e.failure.as_ref().map(|why| format!("{}: {why}", e.name)))
        .collect();
    if !failures.is_empty() && failures.len() == flown.estimators.len() {
        anyhow::bail!("every estimator failed on the flight ({})", failures.join("; "));
    }
    Ok(())
}

/// One table per estimator (module doc), or the estimator's failure.
fn results_text(flown: &FlownRun) -> String {
    let mut s =
        format!("{}: one flight, {} rows\n", flown.sim.aircraft, flown.sim.table.data[0].len());
    for e in &flown.estimators {
        match &e.failure {
            Some(why) => {
                let _ = writeln!(s, "{}: failed: {why}", e.name);
            }
            None => {
                let _ = writeln!(s, "{}\n{}", e.name, estimator_table(e));
            }
        }
    }
    s.push_str("error % = (estimate − flown) / |flown|; t10 = time from the start until the estimate stays within ±10 % (batch: a post-flight fit)\n");
    s
}

/// The table of one estimator's parameters.
fn estimator_table(e: &EstimatorRun) -> comfy_table::Table {
    use aeroident_report::table::fmt_sig;
    let mut t = comfy_table::Table::new();
    t.load_preset(comfy_table::presets::UTF8_FULL_CONDENSED)
        .set_header(vec!["param", "estimate", "σ", "flown", "error %", "status", "t10"]);
    for p in &e.params {
        let error = match (p.estimate, p.reference) {
            (Some(v), Some(r)) if r != 0.0 => format!("{:+.1}", 100.0 * (v - r) / r.abs()),
            _ => "—".into(),
        };
        let t10 = match (e.iterations, p.time_to_10pct_s) {
            (Some(_), _) => "batch".into(),
            (None, Some(t)) => format!("{t:.2} s"),
            (None, None) => "never".into(),
        };
        t.add_row(vec![
            p.name.clone(),
            fmt_sig(p.estimate, 4),
            fmt_sig(p.std_error, 2),
            fmt_sig(p.reference, 4),
            error,
            p.status.clone(),
            t10,
        ]);
    }
    t
}
