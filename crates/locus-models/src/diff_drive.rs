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
use locus_core::{MotionJacobians, MotionModel, Scalar, cast, wrap_angle};

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

    /// Eq. 11-13, with `A = df/dX` and `W = df/dq` beside it (one
    /// `sin_cos`).
    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        u: &WheelTravel<T>,
        q: &SVector<T, 2>,
        jacobians: Option<&mut MotionJacobians<T, 3, 2>>,
    ) -> SVector<T, 3> {
        let (d, dth) = self.increments(u);
        let d = d + q[0];
        let dth = dth + q[1];
        let half = cast::<T>(0.5);
        let (s, c) = (x[2] + dth * half).sin_cos();
        if let Some(j) = jacobians {
            let (o, z) = (T::one(), T::zero());
            j.a = SMatrix::<T, 3, 3>::new(o, z, -d * s, z, o, d * c, z, z, o);
            j.w = SMatrix::<T, 3, 2>::new(c, -d * half * s, s, d * half * c, z, o);
        }
        Vector3::new(x[0] + d * c, x[1] + d * s, wrap_angle(x[2] + dth))
    }

    /// `P- = A P A^T + W Q W^T` in closed form (eq. 11-13): with
    /// `A = I + [a02, a12, 0]^T e_3^T`, the product is the prior plus
    /// rank-one terms in the third column of `P`, and `W Q W^T` is expanded
    /// for the diagonal `Q`. One `sin_cos`; the upper triangle is computed and
    /// mirrored (exactly symmetric).
    #[inline]
    fn propagate(
        &self,
        x: &SVector<T, 3>,
        u: &WheelTravel<T>,
        p: &SMatrix<T, 3, 3>,
    ) -> (SVector<T, 3>, SMatrix<T, 3, 3>) {
        let (d, dth) = self.increments(u);
        let half = cast::<T>(0.5);
        let (s, c) = (x[2] + dth * half).sin_cos();
        let xp = Vector3::new(x[0] + d * c, x[1] + d * s, wrap_angle(x[2] + dth));
        let (a02, a12) = (-d * s, d * c);
        let (p00, p01, p02) = (p[(0, 0)], p[(0, 1)], p[(0, 2)]);
        let (p11, p12, p22) = (p[(1, 1)], p[(1, 2)], p[(2, 2)]);
        // (A P)[i][2] for i = 0, 1.
        let t02 = p02 + a02 * p22;
        let t12 = p12 + a12 * p22;
        // W = [[c, -ws], [s, wc], [0, 1]].
        let (ws, wc) = (d * half * s, d * half * c);
        let (q11, q22) = (self.q11, self.q22);
        let m00 = p00 + a02 * (p02 + t02) + (q11 * c * c + q22 * ws * ws);
        let m01 = p01 + a02 * p12 + a12 * t02 + (q11 * c * s - q22 * ws * wc);
        let m02 = t02 - q22 * ws;
        let m11 = p11 + a12 * (p12 + t12) + (q11 * s * s + q22 * wc * wc);
        let m12 = t12 + q22 * wc;
        let m22 = p22 + q22;
        (
            xp,
            SMatrix::<T, 3, 3>::new(m00, m01, m02, m01, m11, m12, m02, m12, m22),
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
