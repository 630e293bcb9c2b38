//! `aeroident replay`: placeholder until its issue lands.

/// Arguments of `aeroident replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {}

/// Runs `aeroident replay`.
///
/// # Errors
/// Always, until the command is built.
pub fn execute(_args: ReplayArgs) -> anyhow::Result<()> {
    anyhow::bail!("`aeroident replay` is not built yet")
}
