//! Typed errors of the odometry subsystem.
//!
//! One small `#[non_exhaustive]` enum for the whole crate, usable without
//! `std` (`Display` and [`core::error::Error`]). Errors of a firmware-supplied
//! [`EncoderSource`](crate::source::EncoderSource) are not wrapped here: the
//! functions that poll a source return the source's own error type.

use core::fmt;

/// Errors of the odometry subsystem. New variants may be added without a
/// breaking change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// Both quadrature channels changed between two samples, so neither the
    /// direction nor the number of edges is known (spec section 5: "an error
    /// to count, not a count"). Returned by
    /// [`decode`](crate::quadrature::decode); the stateful
    /// [`QuadratureDecoder`](crate::quadrature::QuadratureDecoder) counts these
    /// instead of failing.
    InvalidTransition,
    /// A configuration value or an argument is outside its valid range; the
    /// text names it (e.g. `"wheel_radius must be finite and > 0"`).
    InvalidParameter(&'static str),
    /// A steering angle outside the mechanical limit (spec section 5:
    /// +-40 deg by default).
    SteeringOutOfRange,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidTransition => {
                f.write_str("invalid quadrature transition: both channels changed at once")
            }
            Error::InvalidParameter(what) => write!(f, "invalid parameter: {what}"),
            Error::SteeringOutOfRange => f.write_str("steering angle outside its limit"),
        }
    }
}

impl core::error::Error for Error {}
