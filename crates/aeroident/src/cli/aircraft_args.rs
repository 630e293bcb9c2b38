//! `--aircraft f16|MODEL.toml [--summary S] [--map M]`: the aircraft a command flies, shared by
//! the commands that take either (`sim`, `linearize`, `run`, `montecarlo`).

use anyhow::Context;
use std::path::{Path, PathBuf};

/// The aircraft options (flattened into a command's arguments).
#[derive(Debug, Clone, clap::Args)]
pub struct AircraftArgs {
    /// `f16`, or a model file (`models/*.toml`) whose derivatives the aircraft flies, or a
    /// model preset's name (`six-axis`, as `replay --model`) with `--summary` giving the
    /// values (docs/aircraft.md).
    #[arg(long, default_value = "f16")]
    pub aircraft: String,
    /// Model file: a replay's `summary.json` giving the parameter values (default: the model
    /// file's `[reference.<param>]` values).
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// Model file: the mapping whose constants give mass, inertia, S, b, c̄, thrust line and
    /// thrust law (required with a model file).
    #[arg(long)]
    pub map: Option<PathBuf>,
}

impl AircraftArgs {
    /// Whether the F-16 is asked for.
    ///
    /// # Errors
    /// `--summary` or `--map` given with the F-16.
    pub fn is_f16(&self) -> anyhow::Result<bool> {
        if self.aircraft != "f16" {
            return Ok(false);
        }
        anyhow::ensure!(
            self.summary.is_none() && self.map.is_none(),
            "--summary and --map describe a model-file aircraft, not the F-16"
        );
        Ok(true)
    }

    /// The mapping of a model-file aircraft.
    ///
    /// # Errors
    /// No `--map`.
    pub fn map(&self) -> anyhow::Result<&Path> {
        self.map
            .as_deref()
            .context("--map is required with a model file (mass, inertia, S, b, cbar)")
    }

    /// The model-file aircraft these options name ([`aeroident_pipelines::airframe::load`]).
    ///
    /// # Errors
    /// No `--map`, or files that do not describe a flyable aircraft (naming file and field).
    pub fn model_file(&self) -> anyhow::Result<aeroident_pipelines::airframe::ModelFileAircraft> {
        let map = self.map()?;
        let aircraft = aeroident_pipelines::airframe::load(
            self.aircraft.as_ref(),
            self.summary.as_deref(),
            map,
        )?;
        warn_unfinished(self.summary.as_deref())?;
        note_held_surfaces(&aircraft);
        Ok(aircraft)
    }

    /// The files a model-file aircraft is read from (model, mapping, summary when given).
    ///
    /// # Errors
    /// No `--map`.
    pub fn files(&self) -> anyhow::Result<Vec<&Path>> {
        let mut v = vec![Path::new(&self.aircraft), self.map()?];
        v.extend(self.summary.as_deref());
        Ok(v)
    }
}

/// Warns when `summary` is of a run that did not finish (an interrupted replay, a fit that did
/// not converge): the aircraft flies where that run stopped
/// ([`aeroident_pipelines::summary_file::SummaryParameters::unfinished`]).
///
/// # Errors
/// The summary cannot be read (naming the file).
pub fn warn_unfinished(summary: Option<&Path>) -> anyhow::Result<()> {
    let Some(path) = summary else { return Ok(()) };
    if let Some(note) = aeroident_pipelines::summary_file::read_summary(path)?.unfinished() {
        aeroident_report::note!("warning: {}: {note}", path.display());
    }
    Ok(())
}

/// Says which surfaces a model-file aircraft holds at 0 (its model has no derivative of
/// them) and which values it flies at the model's prior, if any.
pub fn note_held_surfaces(aircraft: &aeroident_pipelines::airframe::ModelFileAircraft) {
    for note in aircraft.notes().iter().cloned().chain(aircraft.held_surfaces_note()) {
        aeroident_report::note!("note: {note}");
    }
}

/// The model-file experiment of `a` flying `scenario` with `estimators` (default `oe`; `run`
/// and `montecarlo` with `--aircraft MODEL.toml`;
/// [`aeroident_pipelines::montecarlo::aircraft::ModelFileExperiment::load`]).
///
/// # Errors
/// No `--map`; files that do not describe a flyable aircraft or scenario; an unknown
/// estimator.
pub fn experiment(
    a: &AircraftArgs,
    scenario: &Path,
    estimators: Option<&[String]>,
) -> anyhow::Result<aeroident_pipelines::montecarlo::aircraft::ModelFileExperiment> {
    use aeroident_pipelines::montecarlo::aircraft::{ExperimentFiles, ModelFileExperiment};
    let files = ExperimentFiles {
        model: Path::new(&a.aircraft),
        summary: a.summary.as_deref(),
        map: a.map()?,
        scenario,
    };
    let default = ["oe".to_string()];
    let x = ModelFileExperiment::load(files, estimators.unwrap_or(&default))?;
    note_held_surfaces(&x.aircraft);
    Ok(x)
}
