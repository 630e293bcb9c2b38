//! `aeroident run`: placeholder until its issue lands.

/// Arguments of `aeroident run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {}

/// Runs `aeroident run`.
///
/// # Errors
/// Always, until the command is built.
pub fn execute(_args: RunArgs) -> anyhow::Result<()> {
    anyhow::bail!("`aeroident run` is not built yet")
}
