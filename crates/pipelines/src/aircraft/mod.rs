//! The aircraft estimation experiments (thesis §3.4, §4.2, Figure 3.2;
//! `spec/thesis-method.md` §3–§5): a reference F-16 flying with true increments named with the
//! vocabulary, a sensor model, and any estimator:
//! - the thesis's **two-aircraft** estimators ([`two_aircraft`](crate::aircraft::two_aircraft): published and corrected SMPE,
//!   model-reference gradient law), each with its own estimated F-16, estimating increments;
//! - **sample-driven** estimators (`Box<dyn aeroident_estimators::Estimator>`, e.g. RLS over a
//!   model structure), fed one air-data sample per step ([`air_data`](crate::aircraft::air_data)) and scored against the
//!   reference's true local derivatives ([`truth`](crate::aircraft::truth)).
//!
//! - the **batch** output-error estimator ([`batch`](crate::aircraft::batch)), fitted after the
//!   flight to the same recorded samples.
//!
//! Increments are **per radian** (per unit hat-rate for p̂, q̂, r̂), about the trim point.

pub mod air_data;
pub mod batch;
pub mod evidence;
pub mod experiment;
pub mod increments;
pub mod model;
pub mod scenario;
pub mod sensors;
pub mod summary;
pub mod truth;
pub mod two_aircraft;

pub use experiment::{ChannelLog, ExperimentError, Quantity, RunOutput, run};
pub use model::F16IncrementModel;
pub use scenario::{Scenario, ScenarioError};
