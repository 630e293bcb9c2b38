//! Proof-of-concept experiments of thesis §2.1/§3.3/§4.1: scenario files, the simulation loop,
//! and the run that returns its outcome (the faces write the outputs).

pub mod adapter;
pub mod run;
pub mod scenario;

pub use adapter::ModelAdapter;
pub use run::{EstimatorKind, RunError, RunOutput, SolverReading, run};
pub use scenario::{PocScenario, ScenarioError};
