//! Proof-of-concept experiments of thesis §2.1/§3.3/§4.1: scenario files, the simulation loop,
//! outputs (CSV, JSON, figures) and the thesis-versus-ours report.

pub mod adapter;
pub mod output;
pub mod report;
pub mod run;
pub mod scenario;

pub use adapter::ModelAdapter;
pub use run::{EstimatorKind, RunError, RunOutput, SolverReading, run};
pub use scenario::{PocScenario, ScenarioError};
