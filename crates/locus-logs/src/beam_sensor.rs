//! A range sensor of beams (an IR sensor, a laser rangefinder, a 2-D
//! lidar): where it sits on the robot, where its beams point and the ranges
//! it can report.

use crate::sensor::SensorMount;

/// Most beams a sensor may declare (a 2-D lidar at 0.1 degree over a full
/// turn has 3600; a scan line of this many ranges still fits in
/// [`MAX_LINE`](crate::MAX_LINE) at up to 9 bytes a range).
pub const MAX_BEAMS: u32 = 100_000;

/// Largest mount offset a reader accepts, m, along either robot axis (as
/// the replay's limit on the landmark sensor).
pub const MAX_MOUNT_OFFSET: f64 = 10.0;

/// Largest range limit a reader accepts, m (100 km, the limit on a
/// coordinate).
pub const MAX_RANGE_LIMIT: f64 = 1e5;

/// A beam sensor: `count` beams from one origin at angles
/// `angle_0 + k angle_step` (`k = 0..count`, rad, from the sensor's x axis,
/// counter-clockwise) that report ranges in `[min_range, max_range)`, m.
/// A reading at or beyond `max_range` is no return; one below `min_range`
/// is not a valid reading. An IR sensor or a laser rangefinder is a sensor
/// of one beam (`count` 1, `angle_0` 0), a lidar one of many.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSensor {
    /// The id `scan` records name; unique in a log.
    pub id: u32,
    /// Mount pose in the robot frame (x forward, y left; yaw from the
    /// robot's heading, counter-clockwise), m, m, rad.
    pub mount: SensorMount,
    /// Smallest valid range, m (`>= 0`).
    pub min_range: f64,
    /// Range at and beyond which a reading means no return, m
    /// (`> min_range`).
    pub max_range: f64,
    /// Angle of the first beam from the sensor's x axis, rad.
    pub angle_0: f64,
    /// Angle from one beam to the next, rad (may be negative; unused for
    /// one beam).
    pub angle_step: f64,
    /// Beams of a scan (`1..=MAX_BEAMS`).
    pub count: u32,
}

impl BeamSensor {
    /// The sensor's pose in the world (m, m, rad) on a robot at `pose`
    /// (m, m, rad): its mount turned by the robot's heading.
    #[must_use]
    pub fn mounted(&self, pose: [f64; 3]) -> [f64; 3] {
        let (s, c) = pose[2].sin_cos();
        let m = self.mount;
        [
            pose[0] + c * m.x - s * m.y,
            pose[1] + s * m.x + c * m.y,
            pose[2] + m.yaw,
        ]
    }

    /// Angle of beam `k` from the sensor's x axis, rad (`angle_0 + k
    /// angle_step`; not wrapped; any `k`, even `>= count`).
    #[must_use]
    pub fn angle(&self, k: u32) -> f64 {
        self.angle_0 + f64::from(k) * self.angle_step
    }

    /// A range as this sensor reports it, m, stored as a scan stores it
    /// ([`crate::scans`]): rounded to `f32`, then [`NO_RETURN`] at or
    /// beyond `max_range`, [`MISSING`] below `min_range` (a negative range
    /// and NaN too), else the rounded range.
    ///
    /// [`NO_RETURN`]: crate::scans::NO_RETURN
    /// [`MISSING`]: crate::scans::MISSING
    #[must_use]
    pub fn reading(&self, range: f64) -> f32 {
        // Rounding to f32 is the format's precision (about 1e-7 relative).
        #[expect(clippy::cast_possible_truncation, reason = "ranges are stored as f32")]
        self.classify(range as f32)
    }

    /// A range already rounded to `f32` (m), classified as [`BeamSensor::reading`]
    /// does.
    #[must_use]
    pub fn classify(&self, range: f32) -> f32 {
        let r = f64::from(range);
        if r >= self.max_range {
            crate::scans::NO_RETURN
        } else if r >= self.min_range {
            range
        } else {
            crate::scans::MISSING
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scans::{MISSING, NO_RETURN};

    #[test]
    fn readings_outside_the_limits_are_no_return_or_missing() {
        let s = BeamSensor {
            id: 0,
            mount: SensorMount::default(),
            min_range: 0.1,
            max_range: 4.0,
            angle_0: -1.0,
            angle_step: 0.5,
            count: 5,
        };
        assert_eq!(s.angle(0), -1.0);
        assert_eq!(s.angle(4), 1.0);
        assert_eq!(s.reading(4.0).to_bits(), NO_RETURN.to_bits());
        assert_eq!(s.reading(1e300).to_bits(), NO_RETURN.to_bits());
        assert!(s.reading(0.05).is_nan() && MISSING.is_nan());
        assert!(s.reading(-1.0).is_nan());
        assert!(s.reading(f64::NAN).is_nan());
        assert_eq!(s.reading(0.1), 0.1_f32);
        assert_eq!(s.reading(3.25), 3.25_f32);
    }
}
