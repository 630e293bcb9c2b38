//! Command-line subcommands. Each submodule owns its `clap` arguments and an `execute` function.

use clap::{Parser, Subcommand};

pub mod bench;
pub mod f16;
pub mod poc;
pub mod replay;
pub mod run;

/// aeroident: real-time aerodynamic parameter identification and an F-16 testbed.
#[derive(Debug, Parser)]
#[command(name = "aeroident", version, about, long_about = None)]
pub struct Cli {
    /// The subcommand to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Proof-of-concept systems of the thesis (first/second order, linear/nonlinear).
    Poc(poc::PocArgs),
    /// The Stevens & Lewis F-16: state derivatives, trim, linearization, open-loop simulation.
    F16(f16::F16Args),
    /// Run an aircraft estimation scenario (no argument: the built-in default).
    Run(run::RunArgs),
    /// Replay a recorded flight through an estimator, sample by sample.
    Replay(replay::ReplayArgs),
    /// Measure simulation speed (one F-16 RK4 step, real-time factor).
    Bench(bench::BenchArgs),
}

impl Cli {
    /// Runs the parsed command.
    ///
    /// # Errors
    /// Any error of the subcommand, with context.
    pub fn execute(self) -> anyhow::Result<()> {
        match self.command {
            Command::Poc(a) => poc::execute(a),
            Command::F16(a) => f16::execute(a),
            Command::Run(a) => run::execute(a),
            Command::Replay(a) => replay::execute(a),
            Command::Bench(a) => bench::execute(a),
        }
    }
}
