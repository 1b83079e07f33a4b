//! The error of the simulator's scenarios (closed loop, `wall45`,
//! `tricycle-slip`, `hover`): an invalid configuration, or a failure of the
//! simulated robot, a sensor or the filter.

use crate::robot::RobotError;
use crate::sensors::SensorError;

/// Errors of a closed-loop run.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A configuration value is invalid; the message names it.
    #[error("invalid configuration: {0}")]
    Config(&'static str),
    /// A configuration field is out of its domain.
    #[error("invalid configuration: `{field}` {reason}")]
    Invalid {
        /// The field's name as in a scenario file (`control.v_ref` for a
        /// nested one).
        field: &'static str,
        /// What the field must be.
        reason: &'static str,
    },
    /// A setting is outside its one accepted range
    /// ([`locus_models::settings`], shared with the teaching UI and the
    /// host).
    #[error("invalid configuration: `{field}` must be in {limit}, got {value:e}")]
    OutOfRange {
        /// The field's name as in a scenario file (`control.v_ref`,
        /// `start` for any of its three components).
        field: &'static str,
        /// The setting's range.
        limit: locus_models::settings::Limit,
        /// The value refused.
        value: f64,
    },
    /// The simulated robot rejected a command.
    #[error("robot: {0}")]
    Robot(#[from] RobotError),
    /// A sensor failed.
    #[error("sensor: {0}")]
    Sensor(#[from] SensorError),
    /// The filter failed (non-finite values, S not positive definite, ...).
    #[error("filter: {0}")]
    Filter(#[from] locus_core::Error),
}
