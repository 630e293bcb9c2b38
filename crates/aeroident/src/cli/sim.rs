//! `aeroident sim`: open-loop simulation of any aircraft from trim: the F-16
//! ([`aeroident_pipelines::sim`], as `aeroident f16 sim`) or an aircraft flying identified
//! derivatives ([`aeroident_pipelines::sim::aircraft`]: a model file with a summary's
//! estimates or its reference values, and a mapping's constants). The work is the library's;
//! this module translates arguments and renders.
//!
//! ```text
//! aeroident sim scenarios/sim/elevator_doublet.toml --out out/sim
//! aeroident sim scenarios/sim/aircraft_doublets.toml --aircraft models/my_uav.toml \
//!               --summary out/replay/summary.json --map mappings/my_uav.toml --out out/sim_uav
//! aeroident replay out/sim_uav/timeseries.csv --map out/sim_uav/mapping.toml --out out/re
//! ```

use anyhow::Context;
use std::path::PathBuf;

/// Arguments of `aeroident sim`.
#[derive(Debug, clap::Args)]
pub struct SimArgs {
    /// Scenario TOML file (format: `aeroident_pipelines::sim::scenario`; without `[aircraft]`
    /// for a model file).
    pub scenario: PathBuf,
    /// The aircraft.
    #[command(flatten)]
    pub aircraft: super::aircraft_args::AircraftArgs,
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `aeroident sim`.
///
/// # Errors
/// Files that cannot be read or do not describe a flyable aircraft or scenario, no trim, a
/// model error during the run, or an output that cannot be written.
pub fn execute(a: SimArgs) -> anyhow::Result<()> {
    if a.aircraft.is_f16()? {
        return super::f16::execute_sim(super::f16::SimArgs { scenario: a.scenario, out: a.out });
    }
    let mut inputs = a.aircraft.files()?;
    inputs.push(&a.scenario);
    // Lock and clear the directory first, so a failing run leaves no old outputs.
    let mut od = crate::outdir::OutputDir::open(&a.out, "sim", &inputs)?;
    let aircraft = a.aircraft.model_file()?;
    let sc = aeroident_pipelines::sim::load_scenario(&a.scenario)?;
    let base = a.scenario.parent().unwrap_or(std::path::Path::new("."));
    let r = aeroident_pipelines::sim::aircraft::run(&aircraft, &sc, base)
        .with_context(|| format!("{} flying `{}`", a.aircraft.aircraft, a.scenario.display()))?;
    let mapping = aeroident_pipelines::sim::aircraft::replay_mapping(&aircraft, &r);
    crate::sim::write_aircraft_outputs(&r, &mapping, &mut od)?;
    od.finish();
    let (x, u) = (&r.trim.state, &r.trim.controls);
    super::print_stdout(&format!(
        "{}: simulated {:.2} s ({} rows, {} columns) from trim at {:.3} m/s, {:.1} m: alpha {:.4} deg, elevator {:.4} deg, {} {:.6}\nwrote {}/timeseries.csv, mapping.toml (replays it), report.html, states and controls (.png, .svg)",
        r.aircraft,
        r.table.data[0].last().copied().unwrap_or(0.0),
        r.table.data[0].len(),
        r.table.columns.len(),
        x[0],
        x[11],
        x[1].to_degrees(),
        u[1].to_degrees(),
        r.engine_column,
        u[0],
        a.out.display()
    ))?;
    Ok(())
}
