//! The `aeroident` command-line program. It only parses arguments; see [`aeroident::cli`].

use clap::Parser;

fn main() -> anyhow::Result<()> {
    aeroident::cli::Cli::parse().execute()
}
