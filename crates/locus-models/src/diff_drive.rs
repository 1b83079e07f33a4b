//! Differential-drive motion with centred differences (paper 001, eq. 7-13).
//!
//! State `X = [x, y, theta]` (m, m, rad) in the world frame; `f` returns theta
//! wrapped to (-pi, pi] (a correction may leave it slightly outside; the next
//! prediction wraps it again, and every angle difference is wrapped). Input: the distances travelled by each wheel in the step,
//! `d1` (right wheel, wheel 1) and `d2` (left wheel, wheel 2), in metres
//! (eq. 9: `d_i = Odo_i / Codo_i`, pulses over pulses per metre).
//!
//! ```text
//! d = (d1 + d2)/2 + e_d             dtheta = (d1 - d2)/b + e_dtheta      (eq. 8, 10)
//! x' = x + d cos(theta + dtheta/2)
//! y' = y + d sin(theta + dtheta/2)
//! theta' = theta + dtheta                                                (eq. 7, 10; [fix] no "omega +")
//! ```
//!
//! Process noise `q = [e_d, e_dtheta]` (m, rad), `Q = diag(Q11, Q22)`.
//! Jacobians (eq. 13, with `c = cos(theta + dtheta/2)`, `s = sin(...)`):
//! `A = [[1, 0, -d s], [0, 1, d c], [0, 0, 1]]`,
//! `W = [[c, -d/2 s], [s, d/2 c], [0, 1]]`.
//! Valid everywhere.

use locus_core::nalgebra::{Matrix2, SMatrix, SVector, Vector3};
use locus_core::{MotionModel, Scalar, cast, wrap_angle};

/// Distances travelled by the two wheels in one step (m). Wheel 1 is the
/// right wheel: a positive turn rate makes it travel further.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelTravel<T> {
    /// Right wheel (wheel 1), m.
    pub d1: T,
    /// Left wheel (wheel 2), m.
    pub d2: T,
}

impl<T: Scalar> WheelTravel<T> {
    /// From encoder pulse counts in the step and the odometry constants
    /// (pulses per metre) of each wheel (eq. 9).
    pub fn from_counts(odo1: T, odo2: T, codo1: T, codo2: T) -> Self {
        Self {
            d1: odo1 / codo1,
            d2: odo2 / codo2,
        }
    }
}

/// The differential-drive motion model of paper 001.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffDrive<T: Scalar> {
    /// Distance between the wheels `b`, m (> 0).
    pub wheelbase: T,
    /// Variance of the travelled-distance noise `Q11 = var(e_d)`, m^2.
    pub q11: T,
    /// Variance of the heading-change noise `Q22 = var(e_dtheta)`, rad^2.
    pub q22: T,
}

impl<T: Scalar> DiffDrive<T> {
    /// A model with wheelbase `b` (m) and noise variances `Q11` (m^2), `Q22` (rad^2).
    pub fn new(wheelbase: T, q11: T, q22: T) -> Self {
        Self {
            wheelbase,
            q11,
            q22,
        }
    }

    /// `(d, dtheta)` of an input (eq. 8).
    #[inline]
    pub fn increments(&self, u: &WheelTravel<T>) -> (T, T) {
        let half = cast::<T>(0.5);
        ((u.d1 + u.d2) * half, (u.d1 - u.d2) / self.wheelbase)
    }
}

impl<T: Scalar> MotionModel<T, 3, 2> for DiffDrive<T> {
    type Input = WheelTravel<T>;

    fn f(&self, x: &SVector<T, 3>, u: &WheelTravel<T>, q: &SVector<T, 2>) -> SVector<T, 3> {
        let (d, dth) = self.increments(u);
        let d = d + q[0];
        let dth = dth + q[1];
        let mid = x[2] + dth * cast::<T>(0.5);
        let (s, c) = mid.sin_cos();
        Vector3::new(x[0] + d * c, x[1] + d * s, wrap_angle(x[2] + dth))
    }

    fn jacobian_state(&self, x: &SVector<T, 3>, u: &WheelTravel<T>) -> SMatrix<T, 3, 3> {
        let (d, dth) = self.increments(u);
        let (s, c) = (x[2] + dth * cast::<T>(0.5)).sin_cos();
        let (o, z) = (T::one(), T::zero());
        SMatrix::<T, 3, 3>::new(o, z, -d * s, z, o, d * c, z, z, o)
    }

    fn jacobian_noise(&self, x: &SVector<T, 3>, u: &WheelTravel<T>) -> SMatrix<T, 3, 2> {
        let (d, dth) = self.increments(u);
        let half = cast::<T>(0.5);
        let (s, c) = (x[2] + dth * half).sin_cos();
        SMatrix::<T, 3, 2>::new(c, -d * half * s, s, d * half * c, T::zero(), T::one())
    }

    /// One `sin_cos` for `f`, `A` and `W`.
    #[inline]
    fn linearize(
        &self,
        x: &SVector<T, 3>,
        u: &WheelTravel<T>,
    ) -> (SVector<T, 3>, SMatrix<T, 3, 3>, SMatrix<T, 3, 2>) {
        let (d, dth) = self.increments(u);
        let half = cast::<T>(0.5);
        let (s, c) = (x[2] + dth * half).sin_cos();
        let (o, z) = (T::one(), T::zero());
        (
            Vector3::new(x[0] + d * c, x[1] + d * s, wrap_angle(x[2] + dth)),
            SMatrix::<T, 3, 3>::new(o, z, -d * s, z, o, d * c, z, z, o),
            SMatrix::<T, 3, 2>::new(c, -d * half * s, s, d * half * c, z, o),
        )
    }

    fn noise_cov(&self, _u: &WheelTravel<T>) -> SMatrix<T, 2, 2> {
        Matrix2::new(self.q11, T::zero(), T::zero(), self.q22)
    }

    fn input_is_finite(&self, u: &WheelTravel<T>) -> bool {
        u.d1.is_finite() && u.d2.is_finite() && self.wheelbase.is_finite()
    }

    fn state_residual(&self, a: &SVector<T, 3>, b: &SVector<T, 3>) -> SVector<T, 3> {
        Vector3::new(a[0] - b[0], a[1] - b[1], wrap_angle(a[2] - b[2]))
    }
}
