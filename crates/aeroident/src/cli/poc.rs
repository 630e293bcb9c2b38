//! `aeroident poc`: placeholder until its issue lands.

/// Arguments of `aeroident poc`.
#[derive(Debug, clap::Args)]
pub struct PocArgs {}

/// Runs `aeroident poc`.
///
/// # Errors
/// Always, until the command is built.
pub fn execute(_args: PocArgs) -> anyhow::Result<()> {
    anyhow::bail!("`aeroident poc` is not built yet")
}
