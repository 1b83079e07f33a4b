//! Paper 001's IR pair as a log declares it (`ir_pair` record, version 5):
//! two one-beam sensors read together as one measurement of the wall they
//! face, its distance and angle (paper 001, eq. 3-5), rather than as two
//! beams one after the other.

use crate::beam_sensor::BeamSensor;

/// Largest gap from the right-angle (rad) and between the two sensors'
/// lateral offsets (m) a pair's sensors may show: their mounts are written
/// as decimal text, so they agree to rounding, not bit for bit.
pub const MOUNT_TOLERANCE: f64 = 1e-9;

/// Two one-beam sensors of a log read as paper 001's IR pair: both look to
/// the robot's right (mount yaw `-pi/2`), side by side along the heading,
/// `front` ahead of `rear`. A filter associates their readings of one
/// instant with the wall the pair's centre ray meets within
/// `association_range` (m), and corrects only when both read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IrPairRecord {
    /// The front sensor's id (`s1` of paper 001).
    pub front: u32,
    /// The rear sensor's id (`s2`).
    pub rear: u32,
    /// Largest distance from the pair's centre to the wall, along its
    /// sensing ray, at which a reading is associated with the wall, m
    /// (paper 001: the sensors' 0.30 m range plus 0.10 m for the estimate's
    /// error).
    pub association_range: f64,
}

/// Why two beam sensors cannot form an IR pair
/// ([`IrPairRecord::sensor_problem`], [`IrPairRecord::pair_problem`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairProblem {
    /// A sensor has more than one beam.
    NotOneBeam,
    /// A sensor does not look to the robot's right (yaw `-pi/2`, beam
    /// angle 0).
    NotLookingRight,
    /// The same sensor twice.
    SameSensor,
    /// The two sensors are not side by side along the heading (different
    /// lateral offsets).
    NotSideBySide,
    /// The rear sensor is not behind the front one.
    RearNotBehind,
}

impl PairProblem {
    /// What a pair's sensor must be, for an error message.
    #[must_use]
    pub const fn expected(self) -> &'static str {
        match self {
            Self::NotOneBeam => "a one-beam sensor (count 1)",
            Self::NotLookingRight => {
                "a sensor looking to the robot's right (yaw -pi/2, angle_0 0), as paper 001's pair"
            }
            Self::SameSensor => "a sensor other than the front one",
            Self::NotSideBySide => "a sensor at the front one's lateral offset y",
            Self::RearNotBehind => "a sensor behind the front one (smaller x)",
        }
    }
}

impl IrPairRecord {
    /// Why `s` cannot be a sensor of paper 001's pair, if it cannot: it
    /// must have one beam looking to the robot's right.
    #[must_use]
    pub fn sensor_problem(s: &BeamSensor) -> Option<PairProblem> {
        let yaw = s.mount.yaw + s.angle_0;
        if s.count != 1 {
            Some(PairProblem::NotOneBeam)
        } else if (yaw + core::f64::consts::FRAC_PI_2).abs() > MOUNT_TOLERANCE {
            Some(PairProblem::NotLookingRight)
        } else {
            None
        }
    }

    /// Why `front` and `rear`, each a possible pair sensor
    /// ([`IrPairRecord::sensor_problem`]), cannot form the pair, if they
    /// cannot: they must be two sensors at one lateral offset, `rear`
    /// behind `front`.
    #[must_use]
    pub fn pair_problem(front: &BeamSensor, rear: &BeamSensor) -> Option<PairProblem> {
        if rear.id == front.id {
            Some(PairProblem::SameSensor)
        } else if (front.mount.y - rear.mount.y).abs() > MOUNT_TOLERANCE {
            Some(PairProblem::NotSideBySide)
        } else if rear.mount.x >= front.mount.x {
            Some(PairProblem::RearNotBehind)
        } else {
            None
        }
    }

    /// The pair's geometry `(L, e, c)` from its sensors' mounts (m): the
    /// spacing along the heading, the centre's offset to the robot's right
    /// and ahead of its centre (paper 001's `L`; `e`, `c` of
    /// `locus_models::IrPair`).
    #[must_use]
    pub fn geometry(front: &BeamSensor, rear: &BeamSensor) -> (f64, f64, f64) {
        (
            front.mount.x - rear.mount.x,
            -0.5 * (front.mount.y + rear.mount.y),
            0.5 * (front.mount.x + rear.mount.x),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::SensorMount;
    use core::f64::consts::FRAC_PI_2;

    fn ir(x: f64, y: f64, yaw: f64) -> BeamSensor {
        BeamSensor {
            id: 0,
            mount: SensorMount { x, y, yaw },
            min_range: 0.04,
            max_range: 0.3,
            angle_0: 0.0,
            angle_step: 0.0,
            count: 1,
        }
    }

    #[test]
    fn paper_001s_mounting_is_a_pair_and_others_are_named() {
        let (s1, s2) = (ir(0.05, 0.0, -FRAC_PI_2), ir(-0.05, 0.0, -FRAC_PI_2));
        let s2 = BeamSensor { id: 1, ..s2 };
        assert_eq!(IrPairRecord::sensor_problem(&s1), None);
        assert_eq!(IrPairRecord::pair_problem(&s1, &s2), None);
        assert_eq!(IrPairRecord::geometry(&s1, &s2), (0.1, 0.0, 0.0));
        assert_eq!(
            IrPairRecord::pair_problem(&s2, &s1),
            Some(PairProblem::RearNotBehind)
        );
        assert_eq!(
            IrPairRecord::pair_problem(&s1, &s1),
            Some(PairProblem::SameSensor)
        );
        assert_eq!(
            IrPairRecord::sensor_problem(&ir(-0.05, 0.0, FRAC_PI_2)),
            Some(PairProblem::NotLookingRight)
        );
        let offset = BeamSensor {
            id: 1,
            ..ir(-0.05, 0.01, -FRAC_PI_2)
        };
        assert_eq!(
            IrPairRecord::pair_problem(&s1, &offset),
            Some(PairProblem::NotSideBySide)
        );
        let lidar = BeamSensor { count: 2, ..s1 };
        assert_eq!(
            IrPairRecord::sensor_problem(&lidar),
            Some(PairProblem::NotOneBeam)
        );
        // Offset to the right and ahead: e = 0.02, c = 0.03.
        let g = IrPairRecord::geometry(&ir(0.08, -0.02, -FRAC_PI_2), &ir(-0.02, -0.02, -FRAC_PI_2));
        assert!(
            (g.0 - 0.1).abs() < 1e-15 && g.1 == 0.02 && (g.2 - 0.03).abs() < 1e-15,
            "{g:?}"
        );
    }
}
