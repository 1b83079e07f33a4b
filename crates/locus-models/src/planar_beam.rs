//! One beam of a range sensor (an IR sensor, a laser rangefinder, one beam
//! of a lidar) against a locally planar surface, on the state of
//! [`CalibratedUnicycle`](crate::calibrated_unicycle::CalibratedUnicycle)
//! (`X = [x, y, theta, s_v, s_omega, b_omega, b_bearing, b_range]`); papers 000 and
//! 003 correct each such range as one scalar update.
//!
//! The surface is the one the beam hit when it was cast in the map from the
//! prior: the point `p` it hit and the surface's unit normal `n` (world,
//! pointing back towards the sensor). The beam leaves the sensor's origin
//! `o(X) = (x, y) + R(theta) m` (`m` the mount position in the robot
//! frame, m) along `d(X) = (cos phi, sin phi)`, `phi = theta + yaw + a`
//! (`yaw` the sensor's mount yaw, `a` the beam's angle on the sensor, rad).
//! Its range to the plane through `p` with normal `n` is
//!
//! `h(X) = n.(p - o) / (n.d) + b_range` (m)
//!
//! (paper 000's eq. 9 for a wall line, with the wall moved to the hit's
//! plane, plus the range bias that persists from reading to reading), and
//! its Jacobian, with `o_t = dR/dtheta m` and `d_t = (-sin phi, cos phi)`,
//!
//! ```text
//! H = [ -n_x/(n.d), -n_y/(n.d), -(n.o_t + h n.d_t)/(n.d), 0, 0, 0, 0, 1 ].
//! ```
//!
//! The odometry and bearing calibration states do not enter a beam. Noise
//! `R = sigma^2` (m^2), the reading's own (white) part.
//! Valid domain: the beam meets the plane from its front at an incidence
//! (the angle between `-d` and `n`) of at most `max_incidence`, at a range
//! of at least `min_range`; else `h` is `None` (a grazing beam's range is
//! too sensitive to the heading to linearise, and a beam from behind the
//! plane does not see it).

use locus_core::nalgebra::{SMatrix, SVector, Vector2};
use locus_core::{MeasurementModel, Scalar};

use crate::calibrated_unicycle::{RANGE_BIAS, STATE};

/// A beam's mount on the robot: position (robot frame, m) and direction
/// (the sensor's yaw plus the beam's angle on it, rad, counter-clockwise
/// from the robot's heading).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamMount<T: Scalar> {
    /// The sensor's origin in the robot frame (x forward, y left), m.
    pub position: Vector2<T>,
    /// The beam's direction from the robot's heading, rad.
    pub angle: T,
}

/// One beam against the plane its cast hit: the model of the module doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarBeam<T: Scalar> {
    /// Where the beam leaves the robot and in which direction.
    pub mount: BeamMount<T>,
    /// The point the cast hit (world, m).
    pub point: Vector2<T>,
    /// The surface's unit normal at it (world), towards the sensor.
    pub normal: Vector2<T>,
    /// Range noise variance, m^2.
    pub var_range: T,
    /// Shortest valid range, m (>= 0).
    pub min_range: T,
    /// Largest incidence angle at which the beam is used, rad in
    /// `[0, pi/2)`.
    pub max_incidence: T,
}

impl<T: Scalar> PlanarBeam<T> {
    /// The beam's origin and direction in the world at the pose
    /// `(x, y, theta)`, and their derivatives by `theta`.
    fn ray(&self, x: &SVector<T, STATE>) -> [Vector2<T>; 4] {
        let (s, c) = x[2].sin_cos();
        let m = self.mount.position;
        let o = Vector2::new(x[0] + c * m.x - s * m.y, x[1] + s * m.x + c * m.y);
        let o_t = Vector2::new(-s * m.x - c * m.y, c * m.x - s * m.y);
        let (sp, cp) = (x[2] + self.mount.angle).sin_cos();
        [o, o_t, Vector2::new(cp, sp), Vector2::new(-sp, cp)]
    }
}

impl<T: Scalar> MeasurementModel<T, STATE, 1> for PlanarBeam<T> {
    fn evaluate(
        &self,
        x: &SVector<T, STATE>,
        jacobian: Option<&mut SMatrix<T, 1, STATE>>,
    ) -> Option<SVector<T, 1>> {
        let [o, o_t, d, d_t] = self.ray(x);
        let n = self.normal;
        let nd = n.dot(&d);
        // Facing the plane from its front, no more than `max_incidence`
        // off its normal (false for NaN too).
        let facing = -nd >= self.max_incidence.cos();
        let h = n.dot(&(self.point - o)) / nd;
        if !(facing && h >= self.min_range) {
            return None;
        }
        let bias = x[RANGE_BIAS];
        if let Some(j) = jacobian {
            *j = SMatrix::<T, 1, STATE>::zeros();
            j[(0, 0)] = -n.x / nd;
            j[(0, 1)] = -n.y / nd;
            j[(0, 2)] = -(n.dot(&o_t) + h * n.dot(&d_t)) / nd;
            j[(0, RANGE_BIAS)] = T::one();
        }
        Some(SVector::<T, 1>::new(h + bias))
    }

    fn noise(&self, _x: &SVector<T, STATE>) -> SMatrix<T, 1, 1> {
        SMatrix::<T, 1, 1>::new(self.var_range)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall at x = 3 (normal -x), a beam mounted 0.1 m ahead and 0.05 m
    /// left, looking 0.2 rad left of the heading.
    fn beam() -> PlanarBeam<f64> {
        PlanarBeam {
            mount: BeamMount {
                position: Vector2::new(0.1, 0.05),
                angle: 0.2,
            },
            point: Vector2::new(3.0, 0.7),
            normal: Vector2::new(-1.0, 0.0),
            var_range: 0.01,
            min_range: 0.02,
            max_incidence: 1.2,
        }
    }

    #[test]
    fn the_range_is_the_distance_along_the_beam_to_the_plane() {
        let x = SVector::<f64, STATE>::from([0.5, -0.2, 0.1, 1.0, 1.0, 0.0, 0.0, 0.0]);
        let b = beam();
        let r = b.h(&x).unwrap()[0];
        let [o, _, d, _] = b.ray(&x);
        let hit = o + d * r;
        assert!((hit.x - 3.0).abs() < 1e-12, "{hit}");
        // Straight on, from the origin: the distance to the wall.
        let straight = PlanarBeam {
            mount: BeamMount {
                position: Vector2::zeros(),
                angle: 0.0,
            },
            ..b
        };
        let at = SVector::<f64, STATE>::from([1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!((straight.h(&at).unwrap()[0] - 2.0).abs() < 1e-12);
        // A range bias adds to the reading as it is.
        let mut biased = at;
        biased[RANGE_BIAS] = 0.03;
        assert!((straight.h(&biased).unwrap()[0] - 2.03).abs() < 1e-12);
        assert_eq!(b.noise(&x)[(0, 0)], 0.01);
    }

    #[test]
    fn the_jacobian_matches_central_differences() {
        let b = beam();
        for x in [
            [0.5, -0.2, 0.1, 1.0, 1.0, 0.0, 0.0, 0.0],
            [1.5, 0.4, -0.6, 1.1, 0.9, 0.01, 0.02, 0.03],
            [-1.0, 2.0, 0.7, 1.0, 1.0, 0.0, 0.0, -0.05],
        ] {
            let x = SVector::<f64, STATE>::from(x);
            let mut j = SMatrix::<f64, 1, STATE>::zeros();
            b.evaluate(&x, Some(&mut j)).unwrap();
            for k in 0..STATE {
                let e = 1e-6;
                let mut hi = x;
                let mut lo = x;
                hi[k] += e;
                lo[k] -= e;
                let fd = (b.h(&hi).unwrap()[0] - b.h(&lo).unwrap()[0]) / (2.0 * e);
                assert!(
                    (fd - j[(0, k)]).abs() < 1e-7,
                    "d/dx{k}: {fd} vs {}",
                    j[(0, k)]
                );
            }
        }
    }

    #[test]
    fn grazing_backward_and_too_short_beams_have_no_range() {
        let b = beam();
        // Heading 1.3 rad + 0.2: the beam runs almost along the wall.
        let grazing = SVector::<f64, STATE>::from([0.5, 0.0, 1.3, 1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!(b.h(&grazing).is_none());
        // Looking away from the wall.
        let away = SVector::<f64, STATE>::from([0.5, 0.0, 3.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!(b.h(&away).is_none());
        // Behind the plane (x = 4 > 3), looking at it from its back.
        let behind = SVector::<f64, STATE>::from([4.0, 0.0, 3.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!(b.h(&behind).is_none());
        // 0.01 m from the wall, below min_range.
        let close = SVector::<f64, STATE>::from([2.89, -0.05, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!(b.h(&close).is_none(), "{:?}", b.h(&close));
    }
}
