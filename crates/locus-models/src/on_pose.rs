//! A measurement of the pose alone on the state of
//! [`CalibratedUnicycle`](crate::calibrated_unicycle::CalibratedUnicycle)
//! (`X = [x, y, theta, s_v, s_omega, b_omega, b_bearing, b_range]`): a
//! model of `[x, y, theta]` whose readings the calibration does not enter,
//! e.g. paper 001's IR pair ([`IrPairObservation`](crate::IrPairObservation))
//! in a log's replay.
//!
//! `h(X) = h_pose(x, y, theta)`, `H = [H_pose, 0]` (the calibration's
//! columns zero), the noise and the residual the pose model's.

use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{MeasurementModel, Scalar};

use crate::calibrated_unicycle::STATE;

/// The pose model `0` on the calibrated state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnPose<P>(pub P);

fn pose<T: Scalar>(x: &SVector<T, STATE>) -> SVector<T, 3> {
    SVector::<T, 3>::new(x[0], x[1], x[2])
}

impl<T: Scalar, P: MeasurementModel<T, 3, M>, const M: usize> MeasurementModel<T, STATE, M>
    for OnPose<P>
{
    /// The pose model's `h`; its `H` in the first three columns, zeros in
    /// the calibration's.
    fn evaluate(
        &self,
        x: &SVector<T, STATE>,
        jacobian: Option<&mut SMatrix<T, M, STATE>>,
    ) -> Option<SVector<T, M>> {
        let Some(j) = jacobian else {
            return self.0.evaluate(&pose(x), None);
        };
        let mut h3 = SMatrix::<T, M, 3>::zeros();
        let z = self.0.evaluate(&pose(x), Some(&mut h3))?;
        *j = SMatrix::<T, M, STATE>::zeros();
        j.fixed_view_mut::<M, 3>(0, 0).copy_from(&h3);
        Some(z)
    }

    fn noise(&self, x: &SVector<T, STATE>) -> SMatrix<T, M, M> {
        self.0.noise(&pose(x))
    }

    fn residual(&self, z: &SVector<T, M>, z_hat: &SVector<T, M>) -> SVector<T, M> {
        self.0.residual(z, z_hat)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AxisWall, IrPair, IrPairObservation};
    use locus_core::jacobian_check::{DEFAULT_STEP, DEFAULT_TOLERANCE, check_measurement_model};

    #[test]
    fn the_ir_pair_on_the_calibrated_state_is_the_pairs_on_the_pose() {
        let obs = IrPairObservation {
            pair: IrPair::centred(0.1),
            wall: AxisWall::x_plus(1.0),
            ds1: 0.11,
            ds2: 0.13,
            r11: 2.5e-5,
            r22: 3e-5,
        };
        let x = SVector::<f64, STATE>::from([0.85, -0.4, 1.5, 1.02, 0.97, 0.01, 0.02, 0.003]);
        let lifted = OnPose(obs);
        let p = pose(&x);
        assert_eq!(lifted.h(&x), obs.h(&p));
        assert_eq!(lifted.noise(&x), obs.noise(&p));
        let (j, j3) = (lifted.jacobian(&x), obs.jacobian(&p));
        assert_eq!(j.fixed_view::<2, 3>(0, 0), j3);
        assert!(j.fixed_view::<2, 5>(0, 3).iter().all(|&v| v == 0.0), "{j}");
        // The heading's residual is wrapped, as the pose model's.
        let r = lifted.residual(&[0.0, 3.1].into(), &[0.0, -3.1].into());
        assert!((r[1] - (6.2 - core::f64::consts::TAU)).abs() < 1e-12, "{r}");
        assert_eq!(
            check_measurement_model(&lifted, &x, DEFAULT_STEP, DEFAULT_TOLERANCE),
            Ok(true)
        );
    }
}
