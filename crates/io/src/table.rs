//! The in-memory form every non-CSV log reader produces before the channel mapping is applied.
//!
//! Two shapes, one per kind of log:
//!
//! - [`Table`]: one time base, one value per column per row (a FVSysID `.asc` file, a MATLAB
//!   `.mat` record, or a multi-rate log after alignment). Column names are what a mapping's
//!   `column = "…"` refers to.
//! - [`Topic`]: one message stream of a multi-rate log (a PX4 ULog topic, an ArduPilot
//!   DataFlash message type, a MAVLink message), each with its own timestamps. Its fields are
//!   named `<topic>.<field>` in the aligned [`Table`] (e.g. `vehicle_attitude.rollspeed`,
//!   `ATT.Roll`, `ATTITUDE.rollspeed`); a multi-instance topic adds `[<instance>]` after the
//!   topic name (`vehicle_imu[1].accel_x`).
//!
//! Aligning topics to one time base is [`Interpolation`]: zero-order hold (the latest value
//! at or before each output time, what an on-board consumer sees) or linear interpolation
//! between the two neighbouring samples (the better estimate of a smooth signal after the
//! fact). Output times before a topic's first sample have no value (the row is not produced
//! rather than filled with 0).

/// Columns sharing one time base. Invariant: `names.len() == columns.len()` and every column
/// has the same length (the number of rows); the time column is one of them, named by the
/// mapping's `[time] column`.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// The file the table was read from, for messages.
    pub file: String,
    /// Column names, unique.
    pub names: Vec<String>,
    /// Column values in the record's own units (the mapping converts them), one `Vec` per
    /// column, all of the same length.
    pub columns: Vec<Vec<f64>>,
}

/// One message stream of a multi-rate log.
#[derive(Debug, Clone, PartialEq)]
pub struct Topic {
    /// Topic or message name, with `[instance]` for multi-instance topics.
    pub name: String,
    /// Timestamps of the messages, seconds, strictly increasing after reading.
    pub t_s: Vec<f64>,
    /// Fields: name (without the topic prefix) and one value per timestamp.
    pub fields: Vec<(String, Vec<f64>)>,
}

/// How topics with their own timestamps are brought onto one time base.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// The latest sample at or before each output time.
    ZeroOrderHold,
    /// Linear between the samples either side of each output time.
    Linear,
}
