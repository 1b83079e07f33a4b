//! Typed errors of the filter core.
//!
//! Every fallible operation of the core returns [`Error`]. The contract that
//! makes the errors safe to handle: **on any error the caller's belief is
//! unchanged** (the filter functions take the belief by reference and return a
//! new one only on success).

use core::fmt;

/// Which input of an operation carried a non-finite (NaN or infinite) value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Input {
    /// The belief's state vector `x`.
    State,
    /// The belief's covariance `P`.
    Covariance,
    /// The control input `u` of a motion model.
    Control,
    /// The process noise covariance `Q` (or the mapped `W Q W^T`).
    ProcessNoise,
    /// The measurement vector `z`.
    Measurement,
    /// The measurement noise covariance `R` (or the mapped `V R V^T`).
    MeasurementNoise,
    /// The motion model's output `f(x, u)` or its Jacobians.
    MotionModel,
    /// The measurement model's output `h(x)` or its Jacobian.
    MeasurementModel,
    /// A configuration value (confidence level, step size, ...).
    Parameter,
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Input::State => "state x",
            Input::Covariance => "covariance P",
            Input::Control => "control input u",
            Input::ProcessNoise => "process noise Q",
            Input::Measurement => "measurement z",
            Input::MeasurementNoise => "measurement noise R",
            Input::MotionModel => "motion model output",
            Input::MeasurementModel => "measurement model output",
            Input::Parameter => "parameter",
        })
    }
}

/// Errors of the filter core. Small, `no_std`, and `#[non_exhaustive]` so new
/// failure modes can be added without breaking callers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// An input (or a model's output) held NaN or an infinity.
    NonFinite(Input),
    /// The innovation covariance `S = H P H^T + V R V^T` is not positive
    /// definite (singular or indefinite): the correction cannot be computed.
    InnovationNotPositiveDefinite,
    /// A noise covariance handed to the sequential correction could not be
    /// decorrelated (its Cholesky factorisation failed: not positive definite).
    NoiseNotPositiveDefinite,
    /// The measurement model predicts no measurement at this state (a beam
    /// parallel to the wall, a wall behind the sensor, out of range, ...).
    NoMeasurement,
    /// Every component of the measurement was marked missing.
    NothingToCorrect,
    /// A parameter is out of its valid range (e.g. a confidence outside (0, 1)).
    InvalidParameter(&'static str),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NonFinite(what) => write!(f, "non-finite value (NaN or infinity) in the {what}"),
            Error::InnovationNotPositiveDefinite => {
                f.write_str("innovation covariance S is not positive definite")
            }
            Error::NoiseNotPositiveDefinite => {
                f.write_str("measurement noise covariance is not positive definite")
            }
            Error::NoMeasurement => f.write_str("the model predicts no measurement at this state"),
            Error::NothingToCorrect => f.write_str("every measurement component is marked missing"),
            Error::InvalidParameter(what) => write!(f, "invalid parameter: {what}"),
        }
    }
}

impl core::error::Error for Error {}
