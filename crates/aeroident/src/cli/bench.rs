//! `aeroident bench`: placeholder until its issue lands.

/// Arguments of `aeroident bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {}

/// Runs `aeroident bench`.
///
/// # Errors
/// Always, until the command is built.
pub fn execute(_args: BenchArgs) -> anyhow::Result<()> {
    anyhow::bail!("`aeroident bench` is not built yet")
}
