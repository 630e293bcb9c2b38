//! The thesis's aircraft experiments (issue 4; thesis §3.4, §4.2, Figure 3.2;
//! `spec/thesis-method.md` §3–§5): a reference F-16 flying with the true increments, an
//! estimated F-16 per estimator flying with the current estimates, a sensor model between them,
//! and the estimators as instances of the generic engine of `aeroident_estimators::smpe`
//! (published and corrected) and of the gradient law of `aeroident_estimators::mrac`.
//!
//! Increments are **per radian** (ΔCm_q per unit `(c̄/2V_T)Δq`), taken about the trim point.

pub mod experiment;
pub mod model;
pub mod report;
pub mod scenario;
pub mod sensors;

pub use experiment::{ChannelLog, ExperimentError, RunOutput, run};
pub use model::{F16IncrementModel, Increment};
pub use scenario::{Scenario, ScenarioError};
