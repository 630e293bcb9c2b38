//! Proof-of-concept outputs (thesis §4.1): CSV, JSON and figures of one case ([`output`](crate::poc::output)) and
//! the thesis-versus-ours report ([`report`](crate::poc::report)) of an [`aeroident_pipelines::poc`] run.

pub mod output;
pub mod report;
