//! What can go wrong writing Foxglove output.

use std::path::PathBuf;

/// Errors of this crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A time that an MCAP or Foxglove time cannot carry.
    #[error("time {time} s of {what} cannot be a Foxglove time (0 to 4.29e9 s, finite)")]
    Time {
        /// The time (s).
        time: f64,
        /// Whose time it is.
        what: &'static str,
    },
    /// A value JSON cannot carry (NaN or infinite) where a number is required.
    #[error("{what} at {time} s is {value}: a Foxglove message needs a finite number")]
    NotFinite {
        /// The field.
        what: &'static str,
        /// The value.
        value: f64,
        /// The step's time (s).
        time: f64,
    },
    /// The MCAP file could not be created or written.
    #[error("{what} {}: {source}", path.display())]
    Io {
        /// `creating`, `writing` or `renaming`.
        what: &'static str,
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The MCAP writer refused a record.
    #[error("writing {}: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: mcap::McapError,
    },
}
