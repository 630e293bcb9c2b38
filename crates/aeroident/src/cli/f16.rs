//! `aeroident f16`: placeholder until its issue lands.

/// Arguments of `aeroident f16`.
#[derive(Debug, clap::Args)]
pub struct F16Args {}

/// Runs `aeroident f16`.
///
/// # Errors
/// Always, until the command is built.
pub fn execute(_args: F16Args) -> anyhow::Result<()> {
    anyhow::bail!("`aeroident f16` is not built yet")
}
