//! Where each record of a log sits in its file, for the messages that name
//! a record a reader or the replay refuses.

/// The line (1-based) of each record of a log, in the order the log holds
/// the records; empty (or `None`) where not known (a log built in memory).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Lines {
    /// Each measurement's (`measurement` and `range` lines, libRSF's
    /// `range2`).
    pub measurements: Vec<usize>,
    /// Each odometry record's.
    pub odometry: Vec<usize>,
    /// Each landmark's (its first line, for a libRSF beacon).
    pub landmarks: Vec<usize>,
    /// The `sensor` line's.
    pub sensor: Option<usize>,
    /// The `start` line's.
    pub start: Option<usize>,
    /// Each `noise` record's, in the order of
    /// [`NoiseRecords::ALL_NAMES`](crate::NoiseRecords::ALL_NAMES).
    pub noise: [Option<usize>; 5],
    /// Each wall's (version 4).
    pub walls: Vec<usize>,
    /// The `map` line's (version 4).
    pub map: Option<usize>,
    /// Each beam sensor's (version 4).
    pub beam_sensors: Vec<usize>,
    /// Each scan's (version 4).
    pub scans: Vec<usize>,
    /// Each IR pair's (version 5).
    pub ir_pairs: Vec<usize>,
}
