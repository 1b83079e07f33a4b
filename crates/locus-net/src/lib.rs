//! The robot link of paper 001 over UDP (protocol: `docs/protocol.md`,
//! codec: [`locus_link`]).
//!
//! - [`host`]: the localisation and control loop for any robot that speaks
//!   the protocol: decode, classify, predict (through gaps), correct with
//!   the IR pair, run the path controller, send commands; it reports the
//!   receiver's counters and the clock estimate.
//! - [`plausible`]: the limits a telemetry packet's content must respect
//!   before it touches the filter.
//! - The UDP plumbing every endpoint shares: the [`Error`] type,
//!   [`at_least_1us`] and [`is_timeout`]. The simulated robot endpoint
//!   (`locus_simlink`) builds on them.
//!
//! An endpoint takes an already bound [`std::net::UdpSocket`], so a caller
//! chooses the address (the CLI binds `127.0.0.1` by default) and tests can
//! put a proxy between the endpoints.

pub mod host;
pub mod plausible;
pub mod transport;

use core::time::Duration;

/// Errors of a link endpoint.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A socket operation failed.
    #[error("socket: {0}")]
    Io(#[from] std::io::Error),
    /// A packet could not be encoded (a non-finite value).
    #[error("encode: {0}")]
    Encode(locus_link::Error),
    /// The filter failed.
    #[error("filter: {0}")]
    Filter(#[from] locus_core::Error),
    /// The peer did not answer in time; the text says which step.
    #[error("timed out: {0}")]
    Timeout(&'static str),
    /// A serial device could not be opened.
    #[error("serial device {device}: {source}")]
    Serial {
        /// The device path.
        device: String,
        /// What went wrong.
        source: serialport::Error,
    },
    /// A configuration value is invalid; the text names it.
    #[error("invalid configuration: {0}")]
    Config(&'static str),
    /// A setting is outside its one accepted range
    /// ([`locus_models::settings`], shared with the simulator and the
    /// teaching UI).
    #[error("invalid configuration: `{}` must be in {limit}, got {value:e}", limit.field)]
    OutOfRange {
        /// The setting's range (and name).
        limit: locus_models::settings::Limit,
        /// The value refused.
        value: f64,
    },
}

/// `d` clamped to at least 1 us (a zero read timeout is an error for
/// [`std::net::UdpSocket::set_read_timeout`]).
pub fn at_least_1us(d: Duration) -> Duration {
    d.max(Duration::from_micros(1))
}

/// `true` for the error kinds a read timeout (or a non-blocking read with
/// nothing to read) produces.
pub fn is_timeout(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
    )
}
