//! The closed-loop experiment's outputs: the files, console table and `run --all` report
//! ([`outputs`](crate::aircraft::outputs)) and the figures ([`figures`](crate::aircraft::figures)) of an [`aeroident_pipelines::aircraft`] run.

pub mod figures;
pub mod outputs;
