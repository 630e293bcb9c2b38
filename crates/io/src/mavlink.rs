//! Live MAVLink feeds: messages received over UDP turned into the rows of a CSV record, so
//! they go through exactly the same mapping and row checks as a file ([`crate::FlightDataReader`]).
//!
//! ```text
//! aeroident replay mavlink:udp:127.0.0.1:14550[?timeout_s=10] --map mappings/mavlink-aeroident.toml
//! ```
//!
//! # Naming
//!
//! A mapping refers to a message field as `<MESSAGE>.<field>` (the MAVLink XML names, as
//! every multi-rate log in [`crate::table`]): `ATTITUDE.pitchspeed`, `HIGHRES_IMU.zacc`,
//! `AOA_SSA.AOA`. An array element is `<field>[<i>]` (`SERVO_OUTPUT_RAW.servo3_raw` is a
//! scalar, `ACTUATOR_OUTPUT_STATUS.actuator[2]` an element). A message with a string field
//! `name` (`NAMED_VALUE_FLOAT`, `NAMED_VALUE_INT`, `DEBUG_FLOAT_ARRAY`) is one topic per name,
//! written as the instance: `NAMED_VALUE_FLOAT[de].value`. Message and field names are checked
//! against the dialect (ardupilotmega, which includes common) when the feed is opened: an
//! unknown message, field or index, or a non-numeric field, is an error naming the mapping file,
//! the channel and the column.
//!
//! # Rows: zero-order hold on a clock message
//!
//! The message of the mapping's `[time] column` is the clock (e.g. `ATTITUDE.time_boot_ms`,
//! unit `ms`). Every other mapped field holds its latest value; each clock message emits one
//! row holding the latest value of every mapped column (zero-order hold, what an on-board
//! consumer sees, [`crate::table::Interpolation::ZeroOrderHold`]). A sender should therefore send
//! the clock message last in each frame (aeroident's own feed, [`feed`], does). Clock messages
//! before every mapped column has been received produce no row (counted in
//! [`LinkStats::clock_without_row`], with the columns still missing); rows are never filled
//! with 0. Values are written with Rust's `{}` formatting of `f64`, which round-trips exactly,
//! so a row read back by the CSV parser holds bit-identical values (MAVLink floats are `f32`,
//! converted exactly to `f64`). A NaN (MAVLink's "unknown") is written as an empty field, which
//! the reader rejects with the column named if the channel is mapped.
//!
//! # End of the stream and problems
//!
//! The feed ends cleanly after `timeout_s` seconds (default [`DEFAULT_TIMEOUT_S`]) without a
//! datagram once messages have arrived, or on the sentinel message `NAMED_VALUE_FLOAT` named
//! [`END_OF_STREAM_NAME`]; if nothing arrives within the timeout at all, reading fails with
//! [`MavlinkError::NothingReceived`]. Datagrams with no valid MAVLink frame are counted and
//! the first few are reported on stderr with their first bytes ([`LinkStats::unparseable`]).
//! Sequence numbers are per sender (system, component), mod 256: a gap counts its missing
//! messages as lost ([`LinkStats::lost`]); a gap of at least as many messages as the mapping
//! reads topics (every column may have missed an update) makes the builder forget its held
//! values, as a queue drop does, so no row mixes values from both sides of the hole, while a
//! shorter loss is held over as a lower send rate would be; a repeat of the last number with
//! the same bytes
//! (message id and payload) is a duplicate, the same datagram received twice
//! ([`LinkStats::duplicates`]). A repeat with other bytes is a new message from a sender that
//! does not number its messages (one that always sends 0, say): it is used, and counted per sender
//! ([`LinkStats::stuck_sequence`], named in the link line). A number behind the last is a
//! late message ([`LinkStats::out_of_order`]). Neither duplicates nor late messages are used
//! (the held values stay the newest; three in a row behind mean the sender restarted its
//! count, and are used, after forgetting the held values as after a gap). A late message a gap
//! had skipped (two neighbours swapped on the link) was not lost: it is taken off the lost
//! count and counted late only. The receive queue is
//! bounded and drops the oldest datagrams when full ([`LinkStats::dropped`]; see
//! `mavlink/udp.rs`). A feed that ends without producing a row fails with
//! [`MavlinkError::NoRows`], naming the columns (and channels) never received and giving the
//! link statistics. Messages from every system and component are merged.

pub mod feed;
mod rows;
mod udp;

pub use rows::RowBuilder;
pub use udp::{LinkStats, MavlinkRows, NOTED_SENDERS, QUEUE_BYTES, QUEUE_DATAGRAMS, StuckSender};

/// Name of the `NAMED_VALUE_FLOAT` that ends a feed cleanly (≤ 10 characters, the field size).
pub const END_OF_STREAM_NAME: &str = "aid_end";

/// Default idle time that ends a feed, s.
pub const DEFAULT_TIMEOUT_S: f64 = 10.0;

/// A parsed `mavlink:` source: `mavlink:udp:<host>:<port>[?timeout_s=<s>]`.
#[derive(Debug, Clone, PartialEq)]
pub struct MavlinkUrl {
    /// The local address to listen on (`udp:` = listen, as a ground station does).
    pub addr: std::net::SocketAddr,
    /// Idle time that ends the feed, s (> 0).
    pub timeout_s: f64,
    /// The source as written (for messages and the summary).
    pub text: String,
}

impl MavlinkUrl {
    /// Parses `mavlink:udp:<host>:<port>[?timeout_s=<s>]` (the `mavlink:` prefix is required).
    ///
    /// # Errors
    /// [`MavlinkError::Url`] naming what is wrong.
    pub fn parse(text: &str) -> Result<Self, MavlinkError> {
        let bad = |reason: String| MavlinkError::Url { url: text.to_string(), reason };
        let rest = text
            .strip_prefix("mavlink:")
            .ok_or_else(|| bad("does not start with `mavlink:`".into()))?;
        let rest = rest.strip_prefix("udp:").ok_or_else(|| {
            bad("only UDP is supported: `mavlink:udp:<host>:<port>` (e.g. mavlink:udp:127.0.0.1:14550)".into())
        })?;
        let (addr_text, query) = match rest.split_once('?') {
            Some((a, q)) => (a, Some(q)),
            None => (rest, None),
        };
        use std::net::ToSocketAddrs;
        let addr = addr_text
            .to_socket_addrs()
            .map_err(|e| bad(format!("address `{addr_text}`: {e}")))?
            .next()
            .ok_or_else(|| bad(format!("address `{addr_text}` resolves to nothing")))?;
        let mut timeout_s = DEFAULT_TIMEOUT_S;
        for kv in query.into_iter().flat_map(|q| q.split('&')) {
            match kv.split_once('=') {
                Some(("timeout_s", v)) => {
                    timeout_s = v
                        .parse::<f64>()
                        .ok()
                        .filter(|t| t.is_finite() && *t > 0.0 && *t < 1e6)
                        .ok_or_else(|| {
                            bad(format!("timeout_s `{v}` is not a positive number of seconds"))
                        })?;
                }
                _ => return Err(bad(format!("unknown option `{kv}` (known: timeout_s=<s>)"))),
            }
        }
        Ok(Self { addr, timeout_s, text: text.to_string() })
    }
}

/// Errors of a MAVLink feed.
#[derive(Debug, thiserror::Error)]
pub enum MavlinkError {
    /// The `mavlink:` source did not parse.
    #[error("`{url}`: {reason}")]
    Url {
        /// The source as written.
        url: String,
        /// What is wrong.
        reason: String,
    },
    /// A mapped column does not name a numeric field of a known message.
    #[error("{file}: channel `{channel}`: column `{column}`: {reason}")]
    Column {
        /// Mapping file.
        file: String,
        /// Channel key (`time` for the clock).
        channel: String,
        /// The column as written.
        column: String,
        /// What is wrong.
        reason: String,
    },
    /// The socket could not be opened.
    #[error("{url}: {source}")]
    Io {
        /// The source.
        url: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Nothing arrived within the timeout. (The message leaves out the source: the reader's
    /// error names it.)
    #[error("no MAVLink datagram received within {timeout_s} s")]
    NothingReceived {
        /// The source.
        url: String,
        /// The timeout, s.
        timeout_s: f64,
    },
    /// The feed ended without producing a row: which mapped columns (and so channels) never
    /// arrived, and the link statistics. (The message leaves out the source: the reader's error
    /// names it.)
    #[error(
        "the feed ended without a row (one is made on each clock message `{clock}` once every mapped column has arrived); never received: {}; {link}",
        never_received_list(.never_received)
    )]
    NoRows {
        /// The clock topic.
        clock: String,
        /// The columns never received, with their channels.
        never_received: Vec<String>,
        /// The link statistics ([`LinkStats::line`]).
        link: String,
    },
}

fn never_received_list(columns: &[String]) -> String {
    if columns.is_empty() { "nothing".into() } else { columns.join(", ") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn url_parses_host_port_and_timeout() {
        let u = MavlinkUrl::parse("mavlink:udp:127.0.0.1:14550?timeout_s=2.5").unwrap();
        assert_eq!(u.addr, "127.0.0.1:14550".parse().unwrap());
        assert_eq!(u.timeout_s, 2.5);
        let u = MavlinkUrl::parse("mavlink:udp:127.0.0.1:14551").unwrap();
        assert_eq!(u.timeout_s, DEFAULT_TIMEOUT_S);
    }

    #[test]
    fn url_errors_name_the_problem() {
        for (url, needle) in [
            ("mavlink:tcp:127.0.0.1:5760", "only UDP"),
            ("mavlink:udp:127.0.0.1", "address"),
            ("mavlink:udp:127.0.0.1:14550?timeout_s=-1", "timeout_s `-1`"),
            ("mavlink:udp:127.0.0.1:14550?rate=5", "unknown option `rate=5`"),
        ] {
            let e = MavlinkUrl::parse(url).unwrap_err().to_string();
            assert!(e.contains(needle), "{url}: {e}");
        }
    }
}
