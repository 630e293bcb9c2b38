//! # aeroident-io
//!
//! Reading and writing: recorded flight data (CSV with a TOML channel mapping, read into the
//! one [`AirDataSample`](aeroident_estimators::AirDataSample)), model files (structure and
//! priors over the one vocabulary), and result writers (CSV time series, JSON summaries).
//! Every reader error names the file, the line or row, and the field.

pub mod align;
mod byte_window;
pub mod dataflash;
pub mod decimal;
pub mod error;
pub mod excitation;
pub mod expression;
pub mod flight_data;
pub mod inspect;
mod line_ends;
pub mod log;
pub mod log_contents;
pub mod mapping;
mod mat5;
pub mod mavlink;
pub mod message;
pub mod model_file;
pub mod multirate;
pub mod parameter;
pub mod reader_report;
pub mod record;
pub mod rejection_log;
pub mod replay_output;
pub mod table;
pub mod thrust_model;
pub mod tlog;
pub mod ulog;
pub mod units;
pub mod warning;

pub use error::{FlightDataError, RowProblem};
pub use flight_data::{FlightDataReader, RecordEvent, Rejection};
pub use log::{LogFormat, LogReader, open_log, open_log_with_notes, open_log_with_report};
pub use mapping::{Channel, Mapping};
pub use model_file::{ModelFileError, ModelSpec, ParamReference, PlausibleRange};
pub use parameter::{Combination, ParameterResult, ReferenceCheck, SCHEMA_VERSION, StdErrorSource};
pub use reader_report::ReaderReport;
pub use record::{Record, RecordSource};
pub use rejection_log::RejectionLog;
