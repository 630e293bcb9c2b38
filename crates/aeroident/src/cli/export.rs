//! `aeroident export`: results for other tools (docs/export.md).
//!
//! ```text
//! aeroident export jsbsim --summary DIR/summary.json [--out FILE] [--v0-mps V0]
//!                  [--elevator-property P] [--aileron-property P] [--rudder-property P]
//! ```
//! Writes the identified derivatives of a `replay` summary as a JSBSim `<aerodynamics>`
//! fragment to FILE (atomically: a temporary file beside it, renamed) or to stdout.

use aeroident_pipelines::export::jsbsim::{SurfaceProperties, aerodynamics_xml, read_summary};
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `aeroident export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// What to export.
    #[command(subcommand)]
    pub what: ExportWhat,
}

/// The export formats.
#[derive(Debug, clap::Subcommand)]
pub enum ExportWhat {
    /// Identified derivatives as a JSBSim `<aerodynamics>` fragment.
    Jsbsim(JsbsimArgs),
}

/// Arguments of `aeroident export jsbsim`.
#[derive(Debug, clap::Args)]
pub struct JsbsimArgs {
    /// The `summary.json` of a replay (online estimator or `--estimator oe`).
    #[arg(long)]
    pub summary: PathBuf,
    /// Output file (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Reference speed V0, m/s, for the `V` (V/V0) and `q0` (q c̄/2V0) terms; without it they
    /// are omitted with a comment.
    #[arg(long)]
    pub v0_mps: Option<f64>,
    /// JSBSim property of the elevator deflection, rad, > 0 trailing edge down.
    #[arg(long, default_value = "fcs/elevator-pos-rad")]
    pub elevator_property: String,
    /// JSBSim property of the aileron deflection, rad, > 0 rolls right wing down (the
    /// fragment multiplies it by −1: aeroident's δa > 0 rolls left).
    #[arg(long, default_value = "fcs/left-aileron-pos-rad")]
    pub aileron_property: String,
    /// JSBSim property of the rudder deflection, rad, > 0 trailing edge left.
    #[arg(long, default_value = "fcs/rudder-pos-rad")]
    pub rudder_property: String,
}

/// Runs `aeroident export`.
///
/// # Errors
/// An unreadable or malformed summary (naming the file and parameter), nothing identified,
/// mixed axis systems, a non-positive V0, or an output I/O error naming the file.
pub fn execute(args: ExportArgs) -> anyhow::Result<()> {
    match args.what {
        ExportWhat::Jsbsim(a) => jsbsim(a),
    }
}

fn jsbsim(a: JsbsimArgs) -> anyhow::Result<()> {
    if let Some(v) = a.v0_mps
        && !(v.is_finite() && v > 0.0)
    {
        anyhow::bail!("--v0-mps must be a positive speed in m/s, got {v}");
    }
    let summary = read_summary(&a.summary)?;
    let surfaces = SurfaceProperties {
        elevator: a.elevator_property,
        aileron: a.aileron_property,
        rudder: a.rudder_property,
    };
    let xml = aerodynamics_xml(&summary, &a.summary.display().to_string(), &surfaces, a.v0_mps)?;
    let exported = xml.matches("<function ").count();
    let omitted = xml.matches("omitted").count();
    match &a.out {
        Some(path) => {
            write_atomically(path, xml.as_bytes())?;
            aeroident_report::note!(
                "{}: {exported} derivatives exported, {omitted} omitted (see the comments); wrote {}",
                a.summary.display(),
                path.display()
            );
        }
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(xml.as_bytes())?;
            out.flush()?;
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` through a temporary file beside it and a rename, so a failure
/// leaves no partial file. (A single named file, not an output directory: the directory may
/// hold another run's files, which `OutputDir` would clear.)
fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let name =
        path.file_name().with_context(|| format!("--out `{}` names no file", path.display()))?;
    let tmp = path.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        anyhow::anyhow!("writing {}: {e}", path.display())
    })
}
