//! Where the landmark sensor sits on the robot.

/// The landmark sensor's mount pose in the robot frame: its origin's
/// position and the direction of its x axis. Ranges are measured from the
/// sensor's origin and bearings from its x axis. The default (all zeros)
/// is a sensor at the robot's centre, looking along the robot's heading.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SensorMount {
    /// Forward offset of the sensor's origin from the robot's centre, m.
    pub x: f64,
    /// Leftward offset of the sensor's origin from the robot's centre, m.
    pub y: f64,
    /// Angle from the robot's heading to the sensor's x axis,
    /// counter-clockwise positive, rad.
    pub yaw: f64,
}

impl SensorMount {
    /// Whether the sensor sits at the robot's centre looking along its
    /// heading (every component equal to zero; `-0.0` counts as zero).
    #[must_use]
    pub fn is_centred(&self) -> bool {
        *self == Self::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_zero_mount_is_centred() {
        assert!(SensorMount::default().is_centred());
        assert!(
            SensorMount {
                x: -0.0,
                y: 0.0,
                yaw: -0.0
            }
            .is_centred()
        );
        for m in [
            SensorMount {
                x: 0.1,
                ..SensorMount::default()
            },
            SensorMount {
                y: -0.1,
                ..SensorMount::default()
            },
            SensorMount {
                yaw: 1e-9,
                ..SensorMount::default()
            },
        ] {
            assert!(!m.is_centred(), "{m:?}");
        }
    }
}
