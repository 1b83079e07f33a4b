//! Range and bearing to a known landmark from a sensor mounted on the robot
//! (position and yaw in the robot frame), with the bearing bias of
//! [`CalibratedUnicycle`](crate::calibrated_unicycle::CalibratedUnicycle)'s
//! state:
//!
//! `h(X) = [ |l - s(X)|, atan2(l - s(X)) - theta - yaw + b_bearing ]`,
//!
//! `s(X)` the sensor's position in the world (see [`RangeBearing`]). A log's
//! `sensor` record gives the mount; a bearing bias the mount's yaw does not
//! explain (a camera turned a little in its holder) is estimated.

use locus_core::nalgebra::{SMatrix, SVector, Vector2};
use locus_core::{MeasurementModel, Scalar, wrap_angle};

use crate::calibrated_unicycle::{BEARING_BIAS, STATE};
use crate::range_bearing::RangeBearing;

/// Range and bearing from a mounted sensor, with a bearing bias state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibratedRangeBearing<T: Scalar> {
    /// The landmark, the sensor's position on the robot and the noise.
    pub inner: RangeBearing<T>,
    /// The sensor's yaw on the robot, rad (bearings are taken from its x
    /// axis).
    pub yaw: T,
}

fn pose<T: Scalar>(x: &SVector<T, STATE>) -> SVector<T, 3> {
    SVector::<T, 3>::new(x[0], x[1], x[2])
}

impl<T: Scalar> MeasurementModel<T, STATE, 2> for CalibratedRangeBearing<T> {
    /// [`RangeBearing`] on the pose, the bearing less the sensor's yaw
    /// plus the bearing bias; `H` its Jacobian on the pose and 1 on the
    /// bias.
    fn evaluate(
        &self,
        x: &SVector<T, STATE>,
        jacobian: Option<&mut SMatrix<T, 2, STATE>>,
    ) -> Option<SVector<T, 2>> {
        let mut h3 = SMatrix::<T, 2, 3>::zeros();
        let want = jacobian.is_some();
        let z = self.inner.evaluate(&pose(x), want.then_some(&mut h3))?;
        if let Some(j) = jacobian {
            *j = SMatrix::<T, 2, STATE>::zeros();
            for r in 0..2 {
                for c in 0..3 {
                    j[(r, c)] = h3[(r, c)];
                }
            }
            j[(1, BEARING_BIAS)] = T::one();
        }
        Some(Vector2::new(
            z[0],
            wrap_angle(z[1] - self.yaw + x[BEARING_BIAS]),
        ))
    }

    fn noise(&self, x: &SVector<T, STATE>) -> SMatrix<T, 2, 2> {
        self.inner.noise(&pose(x))
    }

    fn residual(&self, z: &SVector<T, 2>, z_hat: &SVector<T, 2>) -> SVector<T, 2> {
        self.inner.residual(z, z_hat)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_core::jacobian_check::check_measurement_model;

    #[test]
    fn jacobian_matches_finite_differences() {
        let m = CalibratedRangeBearing {
            inner: RangeBearing::new(Vector2::new(3.0, -1.0), Vector2::new(0.2, 0.05), 0.1, 0.01),
            yaw: 0.1,
        };
        for x in [
            SVector::<f64, STATE>::from([0.0, 0.0, 0.3, 1.0, 1.0, 0.0, 0.02, 0.0]),
            SVector::<f64, STATE>::from([5.0, 2.0, -2.5, 1.1, 0.9, 0.01, -0.03, 0.0]),
        ] {
            assert!(check_measurement_model(&m, &x, 1e-6, 1e-6).unwrap());
        }
    }

    #[test]
    fn a_sensor_ahead_of_the_centre_sees_the_landmark_closer() {
        let at = |sensor: Vector2<f64>, yaw: f64| CalibratedRangeBearing {
            inner: RangeBearing::new(Vector2::new(2.0, 0.0), sensor, 0.1, 0.01),
            yaw,
        };
        let x = SVector::<f64, STATE>::from([0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        let centred = at(Vector2::zeros(), 0.0).h(&x).unwrap();
        let ahead = at(Vector2::new(0.2, 0.0), 0.0).h(&x).unwrap();
        assert!((centred[0] - 2.0).abs() < 1e-12);
        assert!((ahead[0] - 1.8).abs() < 1e-12);
        // A sensor turned left by 0.1 rad sees the landmark 0.1 rad right.
        let turned = at(Vector2::zeros(), 0.1).h(&x).unwrap();
        assert!((turned[1] + 0.1).abs() < 1e-12);
    }
}
