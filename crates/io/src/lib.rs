//! # aeroident-io
//!
//! Reading and writing: scenario files (TOML), recorded flight data (CSV with a TOML channel
//! mapping), and result writers (CSV time series, JSON summaries). Every reader error names the
//! file, the line or row, and the field.
