//! Command-line subcommands. Each submodule owns its `clap` arguments and an `execute` function.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

pub mod aircraft_args;
pub mod auto_window;
pub mod bench;
pub mod compat;
pub mod design;
pub mod export;
pub mod f16;
pub mod freqresp;
pub mod inspect;
pub mod linearize;
pub mod live;
pub mod montecarlo;
pub mod poc;
pub mod replay;
pub mod run;
pub mod run_model_file;
pub mod sim;
pub mod whole_record;

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
    /// Open-loop simulation of any aircraft from trim (the F-16, or a model file flying
    /// identified derivatives): a record and the mapping that replays it.
    Sim(sim::SimArgs),
    /// Monte Carlo campaign: N seeded noisy flights of a scenario, statistics per estimator.
    Montecarlo(montecarlo::MonteCarloArgs),
    /// Replay a recorded flight through an estimator, sample by sample.
    Replay(Box<replay::ReplayArgs>),
    /// The replay with a live control-room view in the browser (a loopback address).
    Live(Box<live::LiveArgs>),
    /// Check a record's data compatibility: the biases, scale factors and time shifts that
    /// make its accelerations, rates, attitudes and air data consistent.
    Compat(compat::CompatArgs),
    /// Write results for other tools (a JSBSim aerodynamics fragment).
    Export(export::ExportArgs),
    /// Frequency responses of a sweep or chirp record (composite windows, coherence, random
    /// error) and low-order transfer-function fits.
    Freqresp(freqresp::FreqRespArgs),
    /// Look at a log before mapping it: topics, fields, units, rates, gaps, parameters and
    /// candidate manoeuvres as `--window` arguments; `--plot` draws raw channels.
    Inspect(inspect::InspectArgs),
    /// Design an orthogonal multisine input and predict its Cramér–Rao σ before flight.
    Design(design::DesignArgs),
    /// Trim any aircraft wings-level (the F-16, or a model file flying identified
    /// derivatives) and linearize it: A, B, eigenvalues and modes.
    Linearize(linearize::LinearizeArgs),
    /// Measure simulation speed (one F-16 RK4 step, real-time factor).
    Bench(bench::BenchArgs),
}

impl Cli {
    /// The command line's definition: every (sub)command takes negative numbers as option
    /// values (`--xcg -0.5`, `--band-hz -1 5`), which clap otherwise reads as unknown flags.
    pub fn definition() -> clap::Command {
        fn negatives(cmd: clap::Command) -> clap::Command {
            cmd.allow_negative_numbers(true).mut_subcommands(negatives)
        }
        negatives(Self::command())
    }

    /// Parses `args` (the program name first) by [`Cli::definition`].
    ///
    /// # Errors
    /// clap's error for a bad command line (print it with `Error::exit`).
    pub fn try_parse_args<I, T>(args: I) -> Result<Self, clap::Error>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        Self::from_arg_matches(&Self::definition().try_get_matches_from(args)?)
    }

    /// Runs the parsed command.
    ///
    /// # Errors
    /// Any error of the subcommand, with context.
    pub fn execute(self) -> anyhow::Result<()> {
        match self.command {
            Command::Poc(a) => poc::execute(a),
            Command::F16(a) => f16::execute(a),
            Command::Run(a) => run::execute(a),
            Command::Sim(a) => sim::execute(a),
            Command::Montecarlo(a) => montecarlo::execute(a),
            Command::Replay(a) => replay::execute(*a),
            Command::Live(a) => live::execute(*a),
            Command::Compat(a) => compat::execute(a),
            Command::Bench(a) => bench::execute(a),
            Command::Export(a) => export::execute(a),
            Command::Design(a) => design::execute(a),
            Command::Linearize(a) => linearize::execute(a),
            Command::Freqresp(a) => freqresp::execute(a),
            Command::Inspect(a) => inspect::execute(a),
        }
    }
}

/// A value parser over a [`Named`](aeroident_pipelines::Named) set of choices: the names the
/// pipelines define are the ones the command line accepts and lists in `--help`.
pub fn named<T>() -> impl clap::builder::TypedValueParser<Value = T>
where
    T: aeroident_pipelines::Named + Clone + Send + Sync,
{
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(T::names())
        .map(|s| T::from_name(&s).expect("the parser accepts only the listed names"))
}

/// [`crate::console::print_stdout`], where every command prints from.
pub use crate::console::print_stdout;

/// The error and its causes on one line ("file:line: field: reason"), as the CLI prints it
/// after `error: ` and the Python bindings raise it, with no backtrace whatever RUST_BACKTRACE
/// says: errors here are problems with the user's input. Some error types print their source in
/// their own message and some do not, so a cause is appended only when the text so far does not
/// already contain it.
pub fn error_chain(e: &anyhow::Error) -> String {
    aeroident_pipelines::error::chain_message(e.chain())
}

/// Whether an error (or any of its causes) is a closed output pipe: the reader went away, which
/// is not a failure of the run (`aeroident … | head`).
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
