//! Range alone to a known beacon or landmark from a sensor mounted on the
//! robot, on the state of
//! [`CalibratedUnicycle`](crate::calibrated_unicycle::CalibratedUnicycle)
//! (`X = [x, y, theta, s_v, s_omega, b_omega, b_bearing, b_range]`):
//!
//! `h(X) = |l - s(X)|` (m),
//!
//! `s(X)` the sensor's position in the world, `(x, y)` plus the mount
//! `(sx, sy)` (robot frame, m) turned by `theta` ([`RangeBearing`]'s
//! `sensor_world`). The sensor's yaw does not enter a range. Its Jacobian
//! is the range row of [`RangeBearing`]'s:
//!
//! ```text
//! H = [ -dx/r, -dy/r, -(dx px_t + dy py_t)/r, 0, 0, 0, 0, 0 ]
//! ```
//!
//! with `(dx, dy)` the landmark's offset from the sensor, `r` its length and
//! `(px_t, py_t)` the sensor position's derivative by theta. Noise
//! `R = sigma_r^2` (m^2). Valid domain: the landmark farther than
//! `min_range` from the sensor (else `h` is `None`: the range's gradient
//! is undefined at the sensor). A log's `range` records (UWB beacons,
//! docs/log-format.md) are corrected with it.

use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{MeasurementModel, Scalar};

use crate::calibrated_unicycle::STATE;
use crate::range_bearing::RangeBearing;

/// Range alone from a mounted sensor: the landmark, the sensor's position
/// on the robot and the range noise of `inner` (its bearing noise unused).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibratedRange<T: Scalar> {
    /// The landmark (world, m), the sensor's position on the robot (robot
    /// frame, m), `var_range` (m^2) and `min_range` (m).
    pub inner: RangeBearing<T>,
}

fn pose<T: Scalar>(x: &SVector<T, STATE>) -> SVector<T, 3> {
    SVector::<T, 3>::new(x[0], x[1], x[2])
}

impl<T: Scalar> MeasurementModel<T, STATE, 1> for CalibratedRange<T> {
    /// The range of [`RangeBearing`], `H` its first row on the pose.
    fn evaluate(
        &self,
        x: &SVector<T, STATE>,
        jacobian: Option<&mut SMatrix<T, 1, STATE>>,
    ) -> Option<SVector<T, 1>> {
        let mut h3 = SMatrix::<T, 2, 3>::zeros();
        let want = jacobian.is_some();
        let z = self.inner.evaluate(&pose(x), want.then_some(&mut h3))?;
        if let Some(j) = jacobian {
            *j = SMatrix::<T, 1, STATE>::zeros();
            for c in 0..3 {
                j[(0, c)] = h3[(0, c)];
            }
        }
        Some(SVector::<T, 1>::new(z[0]))
    }

    fn noise(&self, _x: &SVector<T, STATE>) -> SMatrix<T, 1, 1> {
        SMatrix::<T, 1, 1>::new(self.inner.var_range)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_core::nalgebra::Vector2;

    #[test]
    fn a_sensor_ahead_of_the_centre_sees_the_beacon_closer() {
        let at = |sensor: Vector2<f64>| CalibratedRange {
            inner: RangeBearing::new(Vector2::new(2.0, 0.0), sensor, 0.1, 1.0),
        };
        let x = SVector::<f64, STATE>::from([0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.3, 0.0]);
        assert!((at(Vector2::zeros()).h(&x).unwrap()[0] - 2.0).abs() < 1e-12);
        assert!((at(Vector2::new(0.2, 0.0)).h(&x).unwrap()[0] - 1.8).abs() < 1e-12);
        // Turned by pi/2, the mount 0.2 m ahead is 0.2 m to the left:
        // sqrt(2^2 + 0.2^2) from the beacon.
        let turned = SVector::<f64, STATE>::from([
            0.0,
            0.0,
            core::f64::consts::FRAC_PI_2,
            1.0,
            1.0,
            0.0,
            0.0,
            0.0,
        ]);
        let r = at(Vector2::new(0.2, 0.0)).h(&turned).unwrap()[0];
        assert!((r - (4.0f64 + 0.04).sqrt()).abs() < 1e-12, "{r}");
        assert_eq!(at(Vector2::zeros()).noise(&x)[(0, 0)], 0.1 * 0.1);
    }

    #[test]
    fn no_range_at_the_sensor() {
        let m = CalibratedRange {
            inner: RangeBearing::new(Vector2::new(0.1, 0.0), Vector2::new(0.1, 0.0), 0.1, 1.0),
        };
        assert!(m.h(&SVector::<f64, STATE>::zeros()).is_none());
    }
}
