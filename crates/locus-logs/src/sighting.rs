//! The landmark map and the landmark sightings of a recorded log, whatever
//! its format: what the replay consumes.

/// A landmark of the map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landmark {
    /// The id sightings refer to (MRCLAM: the subject number).
    pub id: u32,
    /// x in the world frame, m.
    pub x: f64,
    /// y in the world frame, m.
    pub y: f64,
}

/// A sighting of a landmark: its range, and its bearing if the sensor
/// gives one (a camera's range-bearing sighting; a UWB radio's range-only
/// sighting of a beacon has none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// Time the sighting was taken, s: the filter applies it at this time.
    pub time: f64,
    /// Time the filter receives it, s (`>= time`; equal for a log recorded
    /// in time order). Odometry up to this time is processed first.
    pub arrival: f64,
    /// The landmark's id.
    pub landmark: u32,
    /// Range from the landmark sensor's origin, m (the robot's centre
    /// unless the log places the sensor elsewhere, see [`crate::SensorMount`]).
    pub range: f64,
    /// Bearing from the landmark sensor's x axis (the robot's heading unless
    /// the log places the sensor elsewhere), counter-clockwise positive, rad;
    /// `None` for a range-only sighting.
    pub bearing: Option<f64>,
}

impl Sighting {
    /// Components the sighting measures: 2 (range and bearing) or 1 (range
    /// alone): the degrees of freedom of its NIS.
    #[must_use]
    pub fn dof(&self) -> u32 {
        if self.bearing.is_some() { 2 } else { 1 }
    }
}
