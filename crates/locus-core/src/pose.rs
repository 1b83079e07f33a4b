//! A planar pose: position `(x, y)` (m, world frame) and heading `theta`
//! (rad, counter-clockwise from the world x axis).

use nalgebra::Vector3;

use crate::{Scalar, wrap_angle};

/// A planar pose `(x, y, theta)`: metres, metres, radians.
///
/// The state of every planar model of Locus is this pose as a vector
/// ([`Pose::to_vector`]); [`Pose::new`] wraps the heading to (-pi, pi].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose<T> {
    /// Position along the world x axis, m.
    pub x: T,
    /// Position along the world y axis, m.
    pub y: T,
    /// Heading, rad, counter-clockwise from the world x axis.
    pub theta: T,
}

impl<T: Scalar> Pose<T> {
    /// A pose `(x, y, theta)` (m, m, rad), the heading wrapped to (-pi, pi].
    #[inline]
    pub fn new(x: T, y: T, theta: T) -> Self {
        Self {
            x,
            y,
            theta: wrap_angle(theta),
        }
    }

    /// The pose from a state vector `[x, y, theta]`, as it is (no wrapping).
    #[inline]
    pub fn from_vector(v: &Vector3<T>) -> Self {
        Self {
            x: v[0],
            y: v[1],
            theta: v[2],
        }
    }

    /// The state vector `[x, y, theta]`.
    #[inline]
    pub fn to_vector(&self) -> Vector3<T> {
        Vector3::new(self.x, self.y, self.theta)
    }

    /// The error `truth - estimate` of the estimate `self` against `truth`:
    /// `[dx, dy, wrap(dtheta)]` (m, m, rad).
    #[inline]
    pub fn error_to(&self, truth: &Self) -> Vector3<T> {
        Vector3::new(
            truth.x - self.x,
            truth.y - self.y,
            wrap_angle(truth.theta - self.theta),
        )
    }
}
