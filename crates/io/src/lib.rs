//! # aeroident-io
//!
//! Reading and writing: scenario files (TOML), recorded flight data (CSV with a TOML channel
//! mapping), and result writers (CSV time series, JSON summaries). Every reader error names the
//! file, the line or row, and the field.

pub mod error;
pub mod flight_data;
pub mod mapping;
pub mod replay_output;
pub mod units;

pub use error::{FlightDataError, RowProblem};
pub use flight_data::{FlightDataReader, FlightSample, RecordEvent, Rejection};
pub use mapping::{Channel, Mapping};
