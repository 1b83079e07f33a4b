//! Range and bearing to a known point landmark, from a sensor mounted off the
//! robot's centre.
//!
//! Not from a seed paper: this is the measurement of recorded logs such as the
//! UTIAS MRCLAM dataset (a camera reading the range and bearing of barcoded
//! landmarks). Same frame conventions as the laser of paper 000 (spec
//! section 2): the sensor sits at `(sx, sy)` in the robot frame (x forward,
//! y left), its axes parallel to the robot's.
//!
//! State `X = [x, y, theta]` (m, m, rad), world frame. The sensor's world
//! position and the landmark's offset from it:
//!
//! ```text
//! px = x + sx cos(theta) - sy sin(theta)        py = y + sx sin(theta) + sy cos(theta)
//! dx = lx - px                                  dy = ly - py
//! h(X) = [ r, b ] = [ sqrt(dx^2 + dy^2),  wrap(atan2(dy, dx) - theta) ]
//! ```
//!
//! Range `r` in m; bearing `b` in rad, from the robot's heading to the
//! landmark, counter-clockwise positive, in (-pi, pi]. The residual wraps the
//! bearing component. Noise `R = diag(sigma_r^2, sigma_b^2)`, `V = I`.
//!
//! Jacobian, with `px_t = dpx/dtheta = -sx sin(theta) - sy cos(theta)` and
//! `py_t = dpy/dtheta = sx cos(theta) - sy sin(theta)`:
//!
//! ```text
//! H = [[-dx/r,    -dy/r,   -(dx px_t + dy py_t)/r        ],
//!      [ dy/r^2,  -dx/r^2,  (dy px_t - dx py_t)/r^2 - 1  ]]
//! ```
//!
//! Valid domain: the landmark farther than [`RangeBearing::min_range`] from
//! the sensor; closer (the bearing is undefined at the sensor itself and `H`
//! grows like `1/r^2`), `h` returns `None`.

use locus_core::nalgebra::{Matrix2, SMatrix, SVector, Vector2};
use locus_core::{MeasurementModel, Scalar, cast, wrap_angle};

/// One range-bearing observation's model: which landmark, where the sensor
/// is mounted, and the noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeBearing<T: Scalar> {
    /// The landmark's position `(lx, ly)` in the world frame, m.
    pub landmark: Vector2<T>,
    /// The sensor's position `(sx, sy)` in the robot frame (x forward, y
    /// left), m. Zero for a sensor at the robot's centre.
    pub sensor: Vector2<T>,
    /// Range noise variance `sigma_r^2`, m^2 (> 0).
    pub var_range: T,
    /// Bearing noise variance `sigma_b^2`, rad^2 (> 0).
    pub var_bearing: T,
    /// Smallest landmark-to-sensor distance with a measurement, m (>= 0).
    /// Default 1e-3 m.
    pub min_range: T,
}

impl<T: Scalar> RangeBearing<T> {
    /// A model for a landmark at `landmark` (world, m), a sensor at `sensor`
    /// (robot frame, m), range standard deviation `sigma_r` (m) and bearing
    /// standard deviation `sigma_b` (rad); `min_range` 1e-3 m.
    pub fn new(landmark: Vector2<T>, sensor: Vector2<T>, sigma_r: T, sigma_b: T) -> Self {
        Self {
            landmark,
            sensor,
            var_range: sigma_r * sigma_r,
            var_bearing: sigma_b * sigma_b,
            min_range: cast::<T>(1e-3),
        }
    }

    /// The same sensor and noise, observing another landmark (world, m):
    /// the usual way to build one model per sighting.
    pub fn with_landmark(mut self, landmark: Vector2<T>) -> Self {
        self.landmark = landmark;
        self
    }

    /// The same model with another minimum range (m).
    pub fn with_min_range(mut self, min_range: T) -> Self {
        self.min_range = min_range;
        self
    }

    /// The sensor's world position `(px, py)` (m) and its derivative with
    /// respect to theta `(px_t, py_t)` (m/rad) at state `x`.
    #[inline]
    pub fn sensor_world(&self, x: &SVector<T, 3>) -> (Vector2<T>, Vector2<T>) {
        let (s, c) = x[2].sin_cos();
        let (sx, sy) = (self.sensor[0], self.sensor[1]);
        (
            Vector2::new(x[0] + sx * c - sy * s, x[1] + sx * s + sy * c),
            Vector2::new(-sx * s - sy * c, sx * c - sy * s),
        )
    }
}

impl<T: Scalar> MeasurementModel<T, 3, 2> for RangeBearing<T> {
    /// Range and bearing from the mounted sensor, `H` beside them (one
    /// `sin_cos`, one `atan2`, one `sqrt`).
    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        jacobian: Option<&mut SMatrix<T, 2, 3>>,
    ) -> Option<SVector<T, 2>> {
        let (p, pt) = self.sensor_world(x);
        let dx = self.landmark[0] - p[0];
        let dy = self.landmark[1] - p[1];
        let r = (dx * dx + dy * dy).sqrt();
        // Positive test so that NaN gives None.
        if !(r > self.min_range && r.is_finite()) {
            return None;
        }
        if let Some(j) = jacobian {
            let r2 = r * r;
            *j = SMatrix::<T, 2, 3>::new(
                -dx / r,
                -dy / r,
                -(dx * pt[0] + dy * pt[1]) / r,
                dy / r2,
                -dx / r2,
                (dy * pt[0] - dx * pt[1]) / r2 - T::one(),
            );
        }
        Some(Vector2::new(r, wrap_angle(dy.atan2(dx) - x[2])))
    }

    fn noise(&self, _x: &SVector<T, 3>) -> SMatrix<T, 2, 2> {
        Matrix2::new(self.var_range, T::zero(), T::zero(), self.var_bearing)
    }

    fn residual(&self, z: &SVector<T, 2>, z_hat: &SVector<T, 2>) -> SVector<T, 2> {
        Vector2::new(z[0] - z_hat[0], wrap_angle(z[1] - z_hat[1]))
    }
}
