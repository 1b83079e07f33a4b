//! The replay's errors: what stops a replay before or during its run (a
//! log it cannot start, a configuration out of range, a filter or smoother
//! failure). What the replay refuses and goes on without is not an error
//! but a [`Refusal`](crate::Refusal) in its report.

use crate::initial;

/// Errors of the replay.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The log has no odometry: nothing to replay.
    #[error("the log has no odometry")]
    NoOdometry,
    /// The log gives no initial pose, has no ground truth to start from at
    /// the first odometry time (a pose, or positions whose first motion
    /// gives a heading), or [`Config::start`](crate::Config::start) asks
    /// for the sightings' pose; and its sightings fix none ([`initial`]).
    #[error(
        "no initial pose: {}, and its sightings fix none: {reason}",
        given(*asked, *time)
    )]
    NoStart {
        /// The first odometry time, s.
        time: f64,
        /// Whether the start was asked of the sightings
        /// ([`Start::Sightings`](crate::Start::Sightings)) rather than
        /// missing from the log.
        asked: bool,
        /// Why the sightings fix none.
        reason: initial::NoFix,
    },
    /// The sightings are not in non-decreasing arrival order.
    #[error("sighting {index}: arrival {arrival} s is earlier than the previous one's")]
    ArrivalOrder {
        /// Index of the sighting in [`Log::sightings`](crate::Log::sightings).
        index: usize,
        /// Its arrival time, s.
        arrival: f64,
    },
    /// A sighting arrives before it was taken.
    #[error("sighting {index}: arrival {arrival} s is before its time {time} s")]
    ArrivesBeforeTaken {
        /// Index of the sighting in [`Log::sightings`](crate::Log::sightings).
        index: usize,
        /// Its time, s.
        time: f64,
        /// Its arrival time, s.
        arrival: f64,
    },
    /// The caller asked the replay to stop (a user's interrupt), before
    /// the event of this index.
    #[error("stopped before event {before}, as asked")]
    Stopped {
        /// Index of the first event not replayed.
        before: usize,
    },
    /// A configuration value is out of its valid range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(&'static str),
    /// The smoother's backward pass failed (a prediction that fails or a
    /// predicted covariance that is not positive definite).
    #[error("smoother: prediction failed or not positive definite at {time} s")]
    Smoother {
        /// The event's time, s.
        time: f64,
    },
    /// The log cannot be read (file, line and field named).
    #[error(transparent)]
    Read(#[from] locus_logs::Error),
    /// The bag or its mapping cannot be read (file, record, topic and
    /// field named). Boxed: a bag's error is large.
    #[error(transparent)]
    Bag(Box<locus_bag::BagError>),
    /// A record every sighting or the start depends on is implausible
    /// (`locus_models::plausible`).
    #[error("{file}:{}{what}: {why}", line.map_or_else(String::new, |l| format!("{l}: ")))]
    Implausible {
        /// The log's name (its file's).
        file: String,
        /// The record's line, if known.
        line: Option<usize>,
        /// The record (`sensor`, `landmark`, `start`).
        what: &'static str,
        /// Why.
        why: locus_models::plausible::Implausible,
    },
    /// The log's map (its walls or its map file) cannot be used.
    #[error("{file}:{}map: {reason}", line.map_or_else(String::new, |l| format!("{l}: ")))]
    Map {
        /// The log's name (its file's).
        file: String,
        /// The line of the `wall` or `map` record, if known.
        line: Option<usize>,
        /// Why (the map reader's error).
        reason: String,
    },
    /// The filter failed (non-finite input, ...).
    #[error("filter step at {time} s{}", line.map_or_else(String::new, |l| format!(" (line {l})")))]
    Filter {
        /// The event's time, s.
        time: f64,
        /// The event's line in the log, if known.
        line: Option<usize>,
        /// The filter's error.
        #[source]
        source: locus_core::Error,
    },
}

impl From<locus_bag::BagError> for Error {
    fn from(e: locus_bag::BagError) -> Self {
        Self::Bag(Box::new(e))
    }
}

/// What [`Error::NoStart`] says the start came from: the sightings on
/// request, or nothing else in the log.
fn given(asked: bool, time: f64) -> String {
    if asked {
        "the start was to come from the sightings".to_string()
    } else {
        format!(
            "the log has no start pose and no ground truth to start from at {time} s (a pose, or \
             positions whose first motion gives the heading)"
        )
    }
}
